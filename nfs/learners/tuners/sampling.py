"""Tuners that place their positions in advance: the grid and random search.

Neither learns from the values it sees; random search is the baseline every metaheuristic
must beat (Bergstra & Bengio 2012), and the grid the search of the FOG start-up paper's
"SVR (grid)" row.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .evaluation import (HIGH, LOW, BudgetExhausted, Evaluator, ObjectiveBatch, TuneResult,
                         TuningError, check_arguments, make_rng, uniform_population)

__all__ = ["grid", "random_search"]


def _evaluate_fixed(objective_batch: ObjectiveBatch, n_dims: int, budget: int,
                    points: np.ndarray, population: int | None, method: str) -> TuneResult:
    """Evaluate a set of positions fixed in advance (grid, random search) in batches of
    ``population`` (default: one batch), up to the budget."""
    ev = Evaluator(objective_batch, n_dims, budget)
    step = population or len(points)
    try:
        for start in range(0, len(points), step):
            ev(points[start:start + step])
    except BudgetExhausted:
        pass
    return ev.result(method)


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
    check_arguments(n_dims, budget, population)
    if kind not in ("auto", "factorial", "sobol"):
        raise TuningError(f"grid kind must be 'auto', 'factorial' or 'sobol', got {kind!r}")
    rng = make_rng(random_state)
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


def random_search(objective_batch: ObjectiveBatch, n_dims: int, *, budget: int,
                  random_state: int | np.random.Generator | None = None,
                  population: int | None = None) -> TuneResult:
    """Random search: ``budget`` positions drawn uniformly in the box (Bergstra & Bengio 2012).

    The baseline every tuner must beat: no model, no memory.  ``population`` positions are
    evaluated per batch (default: all at once).  Uniform in the normalised box is
    log-uniform on a log-scaled real range.
    """
    check_arguments(n_dims, budget, population)
    rng = make_rng(random_state)
    points = uniform_population(rng, budget, n_dims)
    return _evaluate_fixed(objective_batch, n_dims, budget, points, population, "random")
