"""Metaheuristic tuners: plain minimisers of a batch objective on the box [-1, 1]^d.

Every method has one interface (``minimize`` dispatches by name through :data:`TUNERS`)::

    result = minimize(objective_batch, n_dims, method="ssa", budget=300, random_state=0)

``objective_batch(X)`` takes a whole population ``X`` of shape (m, d) with every row in
[-1, 1]^d and returns the m objective values (lower is better) as an array of shape (m,).
Passing a population at once lets the caller spread one batch over cores (see
:class:`nfs.compensate.search.MetaheuristicSearchCV`, which evaluates candidates x folds with
joblib).  The caller maps the normalised box to real parameters (e.g. log10 C in [-2, 3]).

Budget
------
``budget`` is the maximum number of objective evaluations (rows passed to
``objective_batch``), the initial population included.  All methods share one evaluator
(:class:`_Evaluator`): when a method asks for a batch larger than what is left, **only the
first ``remaining`` rows of that batch (in the method's own order: rank order for SSA,
particle order for PSO, ...) are evaluated, the other rows are discarded unevaluated, and the
run ends**.  So ``n_evaluations == budget`` whenever the method runs to its end (grid and
TPE stop at exactly ``budget`` as well) and methods are compared at equal budget.  The
schedules that the papers write in iterations (PSO's inertia weight, GWO's ``a``, SSA's
``iter_max``) use the number of generations the budget allows; HHO, whose cost per generation
varies with its rapid dives, runs its escape-energy schedule on the spent fraction of the
budget instead (see :func:`hho`).

Conventions
-----------
* Every random draw comes from one ``numpy.random.Generator`` made from ``random_state``
  (int, Generator, legacy RandomState or None); the same seed gives the same history.
* ``population`` (swarm, pack, flock size) defaults to :func:`default_population`.
* Initial populations are uniform in the box; every candidate position is clipped to the box
  before it is evaluated (positions outside are never passed to the objective).
* A NaN objective value (a failed fit) is treated as +inf.

Known bias toward the origin
----------------------------
Several published update rules multiply positions by factors that pull toward the origin of
the search space: SSA's producer rule ``X * exp(-i / (alpha iter_max))`` and the "fly
elsewhere" scrounger rule ``Q exp(...)`` (Xue & Shen 2020 eqs. (3), (4)), GWO's
``|C X_p - X|`` with ``C`` in [0, 2] (Mirjalili et al. 2014 eq. (3.1)), and HHO's soft
besiege ``X_rabbit - X - E|J X_rabbit - X|`` (a difference of positions, not a position;
Heidari et al. 2019 eq. (4)) and perch rule ``(X_rabbit - X_m) - r3 (LB + r4 (UB - LB))``
(eq. (1)).  On benchmark functions whose optimum is the origin these rules look better than
they are.  The functions below keep the papers' forms; the tests check every method on
optima away from the origin (``tests/compensate/test_tuners.py``) and print the difference.
The normalised box puts the middle of each real range at 0, so a tuner biased to the origin
is biased to the middle of the user's ranges.
"""

from __future__ import annotations

import inspect
import math
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from nfs.docfields import document_fields
from nfs.errors import NfsError

__all__ = [
    "TuneResult",
    "TuningError",
    "TUNERS",
    "minimize",
    "grid",
    "random_search",
    "pso",
    "gwo",
    "hho",
    "ssa",
    "tpe",
    "default_population",
]

ObjectiveBatch = Callable[[np.ndarray], np.ndarray]

LOW, HIGH = -1.0, 1.0  # the normalised search box


class TuningError(NfsError):
    """A bad tuner name, option, budget or objective."""


@document_fields
@dataclass(frozen=True)
class TuneResult:
    """What a tuner found and how it got there (all positions in [-1, 1]^d)."""

    x_best: np.ndarray
    """Best position found, shape (d,)."""
    f_best: float
    """Objective value at ``x_best``."""
    n_evaluations: int
    """Number of objective evaluations made (<= budget)."""
    history: np.ndarray
    """Best-so-far objective value after each evaluation, shape (n_evaluations,)."""
    all_x: np.ndarray
    """Every evaluated position in evaluation order, shape (n_evaluations, d)."""
    all_f: np.ndarray
    """Objective value of every evaluated position, shape (n_evaluations,)."""
    method: str
    """Name of the tuner in :data:`TUNERS`."""


# --------------------------------------------------------------------------------------
# shared machinery


class _BudgetExhausted(Exception):
    """Raised inside a method when the budget is spent (internal control flow)."""


class _Evaluator:
    """Counts evaluations against the budget and records every one of them."""

    def __init__(self, objective_batch: ObjectiveBatch, n_dims: int, budget: int) -> None:
        self.objective_batch = objective_batch
        self.n_dims = n_dims
        self.budget = budget
        self.xs: list[np.ndarray] = []
        self.fs: list[np.ndarray] = []
        self.n = 0

    @property
    def remaining(self) -> int:
        return self.budget - self.n

    @property
    def spent_fraction(self) -> float:
        return self.n / self.budget

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """Evaluate the rows of ``X`` (clipped to the box) that the budget allows.

        Returns the values of the rows.  When the batch is cut by the budget, or spends its
        last evaluation, the evaluated rows are recorded and :class:`_BudgetExhausted` is
        raised instead (the methods catch it and return their result).
        """
        X = np.clip(np.atleast_2d(np.asarray(X, dtype=float)), LOW, HIGH)
        m = X.shape[0]
        k = min(m, self.remaining)
        f = np.full(m, np.inf)
        if k > 0:
            Xk = X[:k].copy()
            fk = np.asarray(self.objective_batch(Xk), dtype=float).reshape(-1)
            if fk.shape != (k,):
                raise TuningError(f"objective_batch returned {fk.size} values for a batch of "
                                  f"{k} positions; it must return one value per row")
            fk = np.where(np.isnan(fk), np.inf, fk)
            self.xs.append(Xk)
            self.fs.append(fk)
            self.n += k
            f[:k] = fk
        if k < m or self.remaining == 0:
            raise _BudgetExhausted
        return f

    def result(self, method: str) -> TuneResult:
        if self.n == 0:
            raise TuningError(f"tuner '{method}' made no evaluation")
        all_x = np.concatenate(self.xs)
        all_f = np.concatenate(self.fs)
        i = int(np.argmin(all_f))
        return TuneResult(x_best=all_x[i].copy(), f_best=float(all_f[i]), n_evaluations=self.n,
                          history=np.minimum.accumulate(all_f), all_x=all_x, all_f=all_f,
                          method=method)


def _rng(random_state: int | np.random.Generator | None) -> np.random.Generator:
    if isinstance(random_state, np.random.Generator):
        return random_state
    if isinstance(random_state, np.random.RandomState):
        return np.random.default_rng(random_state.randint(0, 2**31 - 1))
    return np.random.default_rng(random_state)


def _check(n_dims: int, budget: int, population: int | None, min_pop: int = 1) -> None:
    if int(n_dims) != n_dims or n_dims < 1:
        raise TuningError(f"n_dims must be a positive integer, got {n_dims!r}")
    if int(budget) != budget or budget < 1:
        raise TuningError(f"budget must be a positive integer, got {budget!r}")
    if population is not None and (int(population) != population or population < min_pop):
        raise TuningError(f"population must be an integer >= {min_pop}, got {population!r}")


def default_population(budget: int) -> int:
    """Population used when none is given: ``min(30, max(6, budget // 10))``.

    About ten generations at small budgets, 30 individuals from a budget of 300 up.
    """
    return int(min(30, max(6, budget // 10)))


def _uniform(rng: np.random.Generator, n: int, d: int) -> np.ndarray:
    return rng.uniform(LOW, HIGH, size=(n, d))


def _generations(budget: int, population: int, per_generation: int) -> int:
    """Number of (possibly partial) generations after the initial population."""
    return max(1, math.ceil((budget - population) / per_generation))


def _evaluate_fixed(objective_batch: ObjectiveBatch, n_dims: int, budget: int,
                    points: np.ndarray, population: int | None, method: str) -> TuneResult:
    """Evaluate a set of positions fixed in advance (grid, random search) in batches of
    ``population`` (default: one batch), up to the budget."""
    ev = _Evaluator(objective_batch, n_dims, budget)
    step = population or len(points)
    try:
        for start in range(0, len(points), step):
            ev(points[start:start + step])
    except _BudgetExhausted:
        pass
    return ev.result(method)


# --------------------------------------------------------------------------------------
# grid


def grid(objective_batch: ObjectiveBatch, n_dims: int, *, budget: int,
         random_state: int | np.random.Generator | None = None,
         population: int | None = None, kind: str = "auto") -> TuneResult:
    """Grid search: a full-factorial grid, or a scrambled Sobol set.

    ``kind="factorial"``: ``k = floor(budget ** (1/d))`` equally spaced points per axis
    including both ends of the box (``linspace(-1, 1, k)``), ``k**d <= budget`` points.
    ``kind="sobol"``: the first ``budget`` points of a scrambled Sobol sequence (scipy.stats.qmc,
    seeded from ``random_state``) mapped to the box.  ``kind="auto"`` (default) takes the
    factorial grid when ``budget`` is an exact d-th power (``k**d == budget``) and the Sobol
    set otherwise, so that the grid always spends the whole budget.

    ``population`` (optional) splits the points into batches of that size; by default all
    points form one batch.  The factorial grid is deterministic (``random_state`` unused).
    """
    _check(n_dims, budget, population)
    if kind not in ("auto", "factorial", "sobol"):
        raise TuningError(f"grid kind must be 'auto', 'factorial' or 'sobol', got {kind!r}")
    rng = _rng(random_state)
    k = int(math.floor(budget ** (1.0 / n_dims) + 1e-9))
    if kind == "auto":
        kind = "factorial" if k ** n_dims == budget else "sobol"
    if kind == "factorial":
        if k < 1:
            raise TuningError("budget too small for a factorial grid")
        axes = [np.linspace(LOW, HIGH, k) if k > 1 else np.zeros(1)] * n_dims
        points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, n_dims)
    else:
        from scipy.stats import qmc
        seed = int(rng.integers(0, 2**31 - 1))
        try:
            sampler = qmc.Sobol(n_dims, scramble=True, rng=seed)
        except TypeError:  # scipy < 1.15
            sampler = qmc.Sobol(n_dims, scramble=True, seed=seed)
        with warnings.catch_warnings():  # a count that is not a power of 2 is fine here
            warnings.simplefilter("ignore", UserWarning)
            points = LOW + (HIGH - LOW) * sampler.random(budget)
    return _evaluate_fixed(objective_batch, n_dims, budget, points, population, "grid")


# --------------------------------------------------------------------------------------
# random search


def random_search(objective_batch: ObjectiveBatch, n_dims: int, *, budget: int,
                  random_state: int | np.random.Generator | None = None,
                  population: int | None = None) -> TuneResult:
    """Random search: ``budget`` positions drawn uniformly in the box (Bergstra & Bengio 2012).

    The baseline every tuner must beat: no model, no memory.  ``population`` positions are
    evaluated per batch (default: all at once).  Uniform in the normalised box is
    log-uniform on a log-scaled real range.
    """
    _check(n_dims, budget, population)
    rng = _rng(random_state)
    points = _uniform(rng, budget, n_dims)
    return _evaluate_fixed(objective_batch, n_dims, budget, points, population, "random")


# --------------------------------------------------------------------------------------
# PSO


def pso(objective_batch: ObjectiveBatch, n_dims: int, *, budget: int,
        random_state: int | np.random.Generator | None = None,
        population: int | None = None, w: float | tuple[float, float] = (0.9, 0.4),
        c1: float = 2.0, c2: float = 2.0, v_max: float = 0.2) -> TuneResult:
    """Particle swarm optimisation with inertia weight.

    Kennedy & Eberhart (1995), Proc. ICNN'95, 1942-1948, with the inertia weight of
    Shi & Eberhart (1998), Proc. IEEE ICEC, 69-73::

        v <- w v + c1 r1 (p_i - x) + c2 r2 (g - x)          r1, r2 ~ U(0,1) per dimension
        x <- x + v

    ``p_i`` is particle i's best position, ``g`` the swarm's best (global topology).

    Parameters
    ----------
    w : float or (w_start, w_end)
        Inertia weight [-]; a pair decreases it linearly over the generations the budget
        allows (Shi & Eberhart's 0.9 -> 0.4 by default).
    c1, c2 : float
        Cognitive and social acceleration coefficients [-] (2.0, 2.0 as in Kennedy &
        Eberhart).
    v_max : float
        Velocity clamp as a fraction of the box width [-]: ``|v_j| <= v_max * 2``.
    population : int
        Swarm size (default :func:`default_population`).

    Boundary handling: a particle leaving the box is put back on the wall (clipped) and the
    velocity components that crossed it are set to zero ("absorbing" walls).
    """
    population = population or default_population(budget)
    _check(n_dims, budget, population)
    rng = _rng(random_state)
    vclamp = v_max * (HIGH - LOW)
    ev = _Evaluator(objective_batch, n_dims, budget)
    n_gen = _generations(budget, population, population)
    w0, w1 = (w, w) if np.isscalar(w) else w
    x = _uniform(rng, population, n_dims)
    v = rng.uniform(-vclamp, vclamp, size=x.shape)
    try:
        f = ev(x)
        p, fp = x.copy(), f.copy()
        for t in range(n_gen):
            wt = w0 + (w1 - w0) * t / max(1, n_gen - 1)
            g = p[np.argmin(fp)]
            r1 = rng.random(x.shape)
            r2 = rng.random(x.shape)
            v = wt * v + c1 * r1 * (p - x) + c2 * r2 * (g - x)
            v = np.clip(v, -vclamp, vclamp)
            x = x + v
            out = (x < LOW) | (x > HIGH)
            x = np.clip(x, LOW, HIGH)
            v[out] = 0.0
            f = ev(x)
            better = f < fp
            p[better], fp[better] = x[better], f[better]
    except _BudgetExhausted:
        pass
    return ev.result("pso")


# --------------------------------------------------------------------------------------
# GWO


def gwo(objective_batch: ObjectiveBatch, n_dims: int, *, budget: int,
        random_state: int | np.random.Generator | None = None,
        population: int | None = None, a_start: float = 2.0) -> TuneResult:
    """Grey wolf optimiser, Mirjalili, Mirjalili & Lewis (2014), Adv. Eng. Softw. 69, 46-61.

    Encircling, eqs. (3.1)-(3.4), for each leader p in {alpha, beta, delta} (the three best
    positions found so far)::

        D_p = |C . X_p - X|                      (3.1), (3.5)
        X_k = X_p - A . D_p                      (3.2), (3.6)
        A = 2 a r1 - a,   C = 2 r2               (3.3), (3.4)   r1, r2 ~ U(0,1) per dimension
        X(t+1) = (X_1 + X_2 + X_3) / 3           (3.7)

    with ``a`` decreasing linearly from ``a_start`` (2) to 0 over the generations the budget
    allows.  Wolves always move (no greedy selection), as in the paper.

    Bias: ``C . X_p`` scales the leader's position by a factor in [0, 2], which pulls the
    pack toward the origin of the box (Niu, Niu, Liu & Chang 2019, Knowl.-Based Syst. 171,
    37-43, showed GWO's scores on origin-centred benchmarks depend on it); kept as published.
    """
    population = population or default_population(budget)
    _check(n_dims, budget, population, min_pop=3)
    rng = _rng(random_state)
    ev = _Evaluator(objective_batch, n_dims, budget)
    n_gen = _generations(budget, population, population)
    x = _uniform(rng, population, n_dims)
    leaders_x = np.zeros((0, n_dims))
    leaders_f = np.zeros(0)
    try:
        f = ev(x)
        for t in range(n_gen):
            # alpha, beta, delta: the three best positions seen so far
            pool_x = np.vstack([leaders_x, x])
            pool_f = np.concatenate([leaders_f, f])
            best = np.argsort(pool_f, kind="stable")[:3]
            leaders_x, leaders_f = pool_x[best], pool_f[best]
            a = a_start * (1.0 - t / n_gen)
            x_new = np.zeros_like(x)
            for xp in leaders_x:
                r1 = rng.random(x.shape)
                r2 = rng.random(x.shape)
                A = 2.0 * a * r1 - a
                C = 2.0 * r2
                D = np.abs(C * xp - x)
                x_new += xp - A * D
            x = np.clip(x_new / 3.0, LOW, HIGH)
            f = ev(x)
    except _BudgetExhausted:
        pass
    return ev.result("gwo")


# --------------------------------------------------------------------------------------
# HHO


def _levy(rng: np.random.Generator, shape: tuple[int, ...], beta: float) -> np.ndarray:
    """Levy flight step, Heidari et al. (2019) eq. (9) (Mantegna's algorithm)."""
    sigma = (math.gamma(1 + beta) * math.sin(math.pi * beta / 2)
             / (math.gamma((1 + beta) / 2) * beta * 2 ** ((beta - 1) / 2))) ** (1 / beta)
    u = rng.standard_normal(shape) * sigma
    v = rng.standard_normal(shape)
    return 0.01 * u / np.abs(v) ** (1 / beta)


def hho(objective_batch: ObjectiveBatch, n_dims: int, *, budget: int,
        random_state: int | np.random.Generator | None = None,
        population: int | None = None, beta: float = 1.5) -> TuneResult:
    """Harris hawks optimisation, Heidari et al. (2019), Future Gener. Comput. Syst. 97, 849-872.

    Escaping energy of the prey (eq. (3)): ``E = 2 E0 (1 - t/T)``, ``E0 ~ U(-1, 1)`` per hawk
    and generation.  Here ``t/T`` is the spent fraction of the budget (evaluations made /
    ``budget``), because the rapid dives make the cost of a generation vary.

    Exploration, ``|E| >= 1`` (eq. (1)), ``q, r1..r4 ~ U(0,1)``::

        q >= 0.5:  X <- X_rand - r1 |X_rand - 2 r2 X|
        q <  0.5:  X <- (X_rabbit - X_m) - r3 (LB + r4 (UB - LB))

    Exploitation, ``|E| < 1``, ``r ~ U(0,1)`` the chance of escape, ``J = 2 (1 - r5)``:

    * soft besiege, ``r >= 0.5, |E| >= 0.5`` (eq. (4)): ``X <- (X_rabbit - X) - E |J X_rabbit - X|``
    * hard besiege, ``r >= 0.5, |E| < 0.5`` (eq. (6)): ``X <- X_rabbit - E |X_rabbit - X|``
    * soft besiege with progressive rapid dives, ``r < 0.5, |E| >= 0.5`` (eqs. (7)-(10)):
      ``Y = X_rabbit - E |J X_rabbit - X|``, ``Z = Y + S * LF(d)``
    * hard besiege with progressive rapid dives, ``r < 0.5, |E| < 0.5`` (eqs. (11)-(13)):
      ``Y = X_rabbit - E |J X_rabbit - X_m|``, ``Z = Y + S * LF(d)``

    with ``S ~ U(0,1)^d`` and the Levy flight ``LF`` of eq. (9) (``beta`` = 1.5).  A diving
    hawk moves to Y if ``F(Y) < F(X)``, else to Z if ``F(Z) < F(X)``, else stays.  Both dives
    are evaluations and count against the budget: a generation evaluates the non-diving hawks'
    moves and every Y in one batch, then the Z of the hawks whose Y failed in a second batch.
    ``X_rabbit`` is the best position so far, ``X_m`` the mean of the current hawks.

    Bias: eq. (4) returns a difference of positions (near the origin when the hawk is near
    the rabbit) and eq. (1)'s second branch subtracts a random point of the box from
    ``X_rabbit - X_m``; both pull toward the origin of the box.  Kept as published; the dives
    (greedy) and hard besiege carry the search to optima away from the origin.
    """
    population = population or default_population(budget)
    _check(n_dims, budget, population, min_pop=2)
    rng = _rng(random_state)
    ev = _Evaluator(objective_batch, n_dims, budget)
    n, d = population, n_dims
    x = _uniform(rng, n, d)
    try:
        f = ev(x)
        i0 = int(np.argmin(f))
        rabbit, f_rabbit = x[i0].copy(), f[i0]
        while True:
            frac = ev.spent_fraction
            x_m = x.mean(axis=0)
            E0 = rng.uniform(-1.0, 1.0, size=n)
            E = 2.0 * E0 * (1.0 - frac)
            new = np.empty_like(x)
            dive = np.zeros(n, dtype=bool)
            for i in range(n):
                q, r = rng.random(), rng.random()
                if abs(E[i]) >= 1.0:  # exploration
                    if q >= 0.5:
                        xr = x[rng.integers(n)]
                        r1, r2 = rng.random(), rng.random()
                        new[i] = xr - r1 * np.abs(xr - 2.0 * r2 * x[i])
                    else:
                        r3, r4 = rng.random(), rng.random()
                        new[i] = (rabbit - x_m) - r3 * (LOW + r4 * (HIGH - LOW))
                    continue
                J = 2.0 * (1.0 - rng.random())
                if r >= 0.5 and abs(E[i]) >= 0.5:  # soft besiege
                    new[i] = (rabbit - x[i]) - E[i] * np.abs(J * rabbit - x[i])
                elif r >= 0.5:  # hard besiege
                    new[i] = rabbit - E[i] * np.abs(rabbit - x[i])
                else:  # progressive rapid dives: Y here, Z below
                    ref = x[i] if abs(E[i]) >= 0.5 else x_m
                    new[i] = rabbit - E[i] * np.abs(J * rabbit - ref)
                    dive[i] = True
            new = np.clip(new, LOW, HIGH)
            # Z candidates drawn now (before any evaluation) so the draws do not depend on
            # how the budget cuts a batch
            z = np.clip(new + rng.random((n, d)) * _levy(rng, (n, d), beta), LOW, HIGH)
            f_new = ev(new)
            moved = ~dive | (f_new < f)
            x_prev_f = f.copy()
            x[moved], f[moved] = new[moved], f_new[moved]
            retry = np.flatnonzero(dive & ~(f_new < x_prev_f))
            if retry.size:
                f_z = ev(z[retry])
                ok = f_z < x_prev_f[retry]
                x[retry[ok]], f[retry[ok]] = z[retry[ok]], f_z[ok]
            i0 = int(np.argmin(f))
            if f[i0] < f_rabbit:
                rabbit, f_rabbit = x[i0].copy(), f[i0]
    except _BudgetExhausted:
        pass
    return ev.result("hho")


# --------------------------------------------------------------------------------------
# SSA


def ssa(objective_batch: ObjectiveBatch, n_dims: int, *, budget: int,
        random_state: int | np.random.Generator | None = None,
        population: int | None = None, PD: float = 0.2, SD: float = 0.2,
        ST: float = 0.8) -> TuneResult:
    """Sparrow search algorithm, Xue & Shen (2020), Syst. Sci. Control Eng. 8(1), 22-34.

    The population is kept sorted by fitness (rank i = 1 is the best).  Each generation:

    Producers, the best ``n_P = max(1, round(PD n))`` sparrows, eq. (3), with one alarm value
    ``R2 ~ U(0,1)`` per generation::

        R2 <  ST:  X_i <- X_i . exp(-i / (alpha iter_max))      alpha ~ U(0,1] per sparrow
        R2 >= ST:  X_i <- X_i + Q L                             Q ~ N(0,1), L = ones(1, d)

    Scroungers, ranks i = n_P + 1 .. n, eq. (4)::

        i >  n/2:  X_i <- Q exp((X_worst - X_i) / i^2)          (hungry: fly elsewhere)
        i <= n/2:  X_i <- X_P + |X_i - X_P| A+ L                (follow the best producer)

    with ``A`` a 1 x d row of random +-1, ``A+ = A^T (A A^T)^-1 = A^T / d``: every dimension
    moves by the same scalar ``sum_j |X_ij - X_Pj| A_j / d``.  ``X_P`` is the best producer
    position after the producer step.

    Scouts, ``n_S = max(1, round(SD n))`` sparrows drawn at random, aware of danger, eq. (5)::

        f_i >  f_g:  X_i <- X_best + beta |X_i - X_best|        beta ~ N(0,1) per dimension
        f_i == f_g:  X_i <- X_i + K |X_i - X_worst| / ((f_i - f_w) + eps)     K ~ U(-1,1)

    Greedy update (as in the authors' code): a sparrow keeps its old position unless the new
    one is better; a sparrow that is both a scrounger and a scout keeps the best of the three.
    ``iter_max`` is the number of generations the budget allows; a generation costs
    ``n + n_S`` evaluations in two batches (producers, then scroungers and scouts together:
    the scouts use the positions after the producer step).  Options ``PD`` (0.2), ``SD``
    and ``ST`` (0.8) follow the paper's notation.  ``SD`` defaults to 0.2, the top of the
    paper's 0.1-0.2: the scouts' rule is the only one not biased to the origin, and on a
    shifted 3-D sphere at 600 evaluations SD = 0.2 brings the median error from 3e-2 (0.1)
    to 4e-3 (30 seeds).

    Bias: eq. (3)'s first branch shrinks producers toward the origin and eq. (4)'s first
    branch throws hungry scroungers to ``Q (~1, ..., ~1)``, a point on the diagonal near the
    origin.  Kept as published; with the greedy update they cost evaluations but never lose
    the best position, and the scouts (eq. (5)) and followers find optima away from the origin.
    """
    population = population or default_population(budget)
    _check(n_dims, budget, population, min_pop=2)
    for name, val in (("PD", PD), ("SD", SD), ("ST", ST)):
        if not 0.0 < val <= 1.0:
            raise TuningError(f"ssa option {name} must be in (0, 1], got {val!r}")
    rng = _rng(random_state)
    ev = _Evaluator(objective_batch, n_dims, budget)
    n, d = population, n_dims
    n_p = max(1, min(n, int(round(PD * n))))
    n_s = max(1, min(n, int(round(SD * n))))
    iter_max = _generations(budget, n, n + n_s)
    eps = np.finfo(float).eps
    x = _uniform(rng, n, d)
    try:
        f = ev(x)
        while True:
            order = np.argsort(f, kind="stable")
            x, f = x[order], f[order]  # rank i = index + 1
            x_worst, f_w = x[-1].copy(), f[-1]
            # -- producers, eq. (3)
            r2 = rng.random()
            ranks = np.arange(1, n_p + 1)
            if r2 < ST:
                alpha = 1.0 - rng.random(n_p)  # (0, 1]
                xp_new = x[:n_p] * np.exp(-ranks / (alpha * iter_max))[:, None]
            else:
                xp_new = x[:n_p] + rng.standard_normal(n_p)[:, None] * np.ones(d)
            xp_new = np.clip(xp_new, LOW, HIGH)
            fp_new = ev(xp_new)
            better = fp_new < f[:n_p]
            x[:n_p][better], f[:n_p][better] = xp_new[better], fp_new[better]
            x_P = x[int(np.argmin(f[:n_p]))].copy()
            # -- scroungers, eq. (4)
            cand, owner = [], []
            for i in range(n_p, n):
                rank = i + 1
                if rank > n / 2:
                    Q = rng.standard_normal()
                    cand.append(Q * np.exp((x_worst - x[i]) / rank ** 2))
                else:
                    A = rng.choice([-1.0, 1.0], size=d)
                    step = np.abs(x[i] - x_P) @ (A / d)  # |X_i - X_P| A+, A+ = A^T (A A^T)^-1
                    cand.append(x_P + step * np.ones(d))
                owner.append(i)
            # -- scouts aware of danger, eq. (5)
            i_best = int(np.argmin(f))
            x_best, f_g = x[i_best].copy(), f[i_best]
            for i in rng.choice(n, size=n_s, replace=False):
                if f[i] > f_g:
                    cand.append(x_best + rng.standard_normal(d) * np.abs(x[i] - x_best))
                else:
                    K = rng.uniform(-1.0, 1.0)
                    cand.append(x[i] + K * np.abs(x[i] - x_worst) / ((f[i] - f_w) + eps))
                owner.append(int(i))
            cand = np.clip(np.asarray(cand), LOW, HIGH)
            f_c = ev(cand)
            for c, i in enumerate(owner):  # greedy update
                if f_c[c] < f[i]:
                    x[i], f[i] = cand[c], f_c[c]
    except _BudgetExhausted:
        pass
    return ev.result("ssa")


# --------------------------------------------------------------------------------------
# TPE (optional: Optuna)


def tpe(objective_batch: ObjectiveBatch, n_dims: int, *, budget: int,
        random_state: int | np.random.Generator | None = None,
        population: int | None = None, n_startup_trials: int = 10,
        multivariate: bool = True) -> TuneResult:
    """Tree-structured Parzen estimator, Optuna's ``TPESampler`` (Bergstra et al. 2011).

    Optional: needs Optuna (the ``tune`` extra).  The sampler is seeded from
    ``random_state``; each of the d coordinates is a ``FloatDistribution(-1, 1)``.
    ``population`` trials are asked at once and evaluated as one batch (default 1, i.e.
    sequential TPE; larger batches use Optuna's constant-liar for the pending trials).
    ``n_startup_trials`` random trials come first; ``multivariate`` uses the joint Parzen
    estimator.  Stops at exactly ``budget`` trials.
    """
    population = population or 1
    _check(n_dims, budget, population)
    try:
        import optuna
    except ImportError as exc:
        raise TuningError("tuner 'tpe' needs Optuna: install the 'tune' extra "
                          "(pip install 'nfs-startup[tune]')") from exc
    rng = _rng(random_state)
    seed = int(rng.integers(0, 2**31 - 1))
    dist = {f"x{j}": optuna.distributions.FloatDistribution(LOW, HIGH) for j in range(n_dims)}
    with warnings.catch_warnings():  # multivariate / constant_liar are marked experimental
        warnings.simplefilter("ignore")
        sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=n_startup_trials,
                                             multivariate=multivariate, constant_liar=True)
    verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    ev = _Evaluator(objective_batch, n_dims, budget)
    try:
        study = optuna.create_study(sampler=sampler, direction="minimize")
        while ev.remaining > 0:
            m = min(population, ev.remaining)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                trials = [study.ask(dist) for _ in range(m)]
            X = np.array([[t.params[f"x{j}"] for j in range(n_dims)] for t in trials])
            try:
                f = ev(X)
            except _BudgetExhausted:
                break
            for t, v in zip(trials, f):
                study.tell(t, float(v) if np.isfinite(v) else float("inf"))
    finally:
        optuna.logging.set_verbosity(verbosity)
    return ev.result("tpe")


# --------------------------------------------------------------------------------------
# registry and dispatcher

TUNERS: dict[str, Callable[..., TuneResult]] = {
    "grid": grid,
    "random": random_search,
    "pso": pso,
    "gwo": gwo,
    "hho": hho,
    "ssa": ssa,
    "tpe": tpe,
}
"""Tuner name -> function; every function has the signature of :func:`minimize`."""


def minimize(objective_batch: ObjectiveBatch, n_dims: int, *, method: str = "ssa",
             budget: int, random_state: int | np.random.Generator | None = None,
             population: int | None = None, **options) -> TuneResult:
    """Minimise ``objective_batch`` over [-1, 1]^n_dims with the tuner ``method``.

    Parameters
    ----------
    objective_batch : callable
        ``f(X) -> values``: X of shape (m, n_dims) in the box, values of shape (m,).
    n_dims : int
        Dimension d of the search box.
    method : str
        A key of :data:`TUNERS`: 'grid', 'random', 'pso', 'gwo', 'hho', 'ssa', 'tpe'.
    budget : int
        Maximum number of objective evaluations (see the module docstring for the last,
        partial generation).
    random_state : int, numpy Generator or None
        Seed of every random draw.
    population : int, optional
        Population (swarm, pack, flock) size or batch size; method default if None.
    **options
        Method options (e.g. ``w``, ``c1``, ``c2``, ``v_max`` for 'pso'; ``PD``, ``SD``,
        ``ST`` for 'ssa'); see each function.
    """
    try:
        func = TUNERS[method]
    except (KeyError, TypeError):
        raise TuningError(f"unknown tuner {method!r}; valid tuners: "
                          f"{', '.join(TUNERS)}") from None
    valid = [p for p in inspect.signature(func).parameters
             if p not in ("objective_batch", "n_dims", "budget", "random_state", "population")]
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise TuningError(f"unknown option(s) {', '.join(unknown)} for tuner '{method}'; "
                          f"valid options: {', '.join(valid) or '(none)'}")
    return func(objective_batch, n_dims, budget=budget, random_state=random_state,
                population=population, **options)
