"""Population metaheuristics: particle swarm, grey wolf, Harris hawks and sparrow search.

One plain function per published algorithm, side by side, each with its
update equations and the paper's equation numbers, and what the budget does to its
schedule.  The tuned rows of the seed papers: PSO-, GWO- and SSA-SVR (the FOG start-up
paper), HHO-RVR (Liang et al. (2021)).  See :mod:`nfs.learners.tuners` for the bias toward
the origin of the box that several published update rules carry.
"""

from __future__ import annotations

import math

import numpy as np

from .evaluation import (HIGH, LOW, BudgetExhausted, Evaluator, ObjectiveBatch, TuneResult,
                         TuningError, check_arguments, default_population, generations,
                         make_rng, uniform_population)

__all__ = ["pso", "gwo", "hho", "ssa"]


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
    check_arguments(n_dims, budget, population)
    rng = make_rng(random_state)
    vclamp = v_max * (HIGH - LOW)
    ev = Evaluator(objective_batch, n_dims, budget)
    n_gen = generations(budget, population, population)
    w0, w1 = (w, w) if np.isscalar(w) else w
    x = uniform_population(rng, population, n_dims)
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
    except BudgetExhausted:
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
    check_arguments(n_dims, budget, population, min_pop=3)
    rng = make_rng(random_state)
    ev = Evaluator(objective_batch, n_dims, budget)
    n_gen = generations(budget, population, population)
    x = uniform_population(rng, population, n_dims)
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
    except BudgetExhausted:
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
    check_arguments(n_dims, budget, population, min_pop=2)
    rng = make_rng(random_state)
    ev = Evaluator(objective_batch, n_dims, budget)
    n, d = population, n_dims
    x = uniform_population(rng, n, d)
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
    except BudgetExhausted:
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
    check_arguments(n_dims, budget, population, min_pop=2)
    for name, val in (("PD", PD), ("SD", SD), ("ST", ST)):
        if not 0.0 < val <= 1.0:
            raise TuningError(f"ssa option {name} must be in (0, 1], got {val!r}")
    rng = make_rng(random_state)
    ev = Evaluator(objective_batch, n_dims, budget)
    n, d = population, n_dims
    n_p = max(1, min(n, int(round(PD * n))))
    n_s = max(1, min(n, int(round(SD * n))))
    iter_max = generations(budget, n, n + n_s)
    eps = np.finfo(float).eps
    x = uniform_population(rng, n, d)
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
    except BudgetExhausted:
        pass
    return ev.result("ssa")
