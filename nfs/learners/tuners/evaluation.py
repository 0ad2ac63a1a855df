"""The box, the budget and the record that every tuner shares.

A tuner minimises ``objective_batch`` over the normalised box [:data:`LOW`, :data:`HIGH`]^d
(see :mod:`nfs.learners.tuners` for the interface, the budget and the conventions).  Every
evaluation goes through one :class:`Evaluator`, which clips the positions to the box, counts
them against the budget, records them and returns a :class:`TuneResult`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from nfs.docfields import document_fields
from nfs.errors import NfsError

__all__ = [
    "ObjectiveBatch",
    "LOW",
    "HIGH",
    "TuningError",
    "TuneResult",
    "BudgetExhausted",
    "Evaluator",
    "make_rng",
    "check_arguments",
    "default_population",
    "uniform_population",
    "generations",
]

#: ``f(X) -> values``: X of shape (m, d) in the box, values of shape (m,) (lower is better).
ObjectiveBatch = Callable[[np.ndarray], np.ndarray]

#: The normalised search box [LOW, HIGH]^d.
LOW, HIGH = -1.0, 1.0


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
    """Name of the tuner in :data:`~nfs.learners.tuners.TUNERS`."""


class BudgetExhausted(Exception):
    """Raised by :class:`Evaluator` when the budget is spent; a tuner catches it and returns
    its result (control flow inside a tuner, never seen by its caller)."""


class Evaluator:
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
        """Evaluations left in the budget."""
        return self.budget - self.n

    @property
    def spent_fraction(self) -> float:
        """Evaluations made / budget [-] (HHO's time t/T)."""
        return self.n / self.budget

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """Evaluate the rows of ``X`` (clipped to the box) that the budget allows.

        Returns the values of the rows.  When the batch is cut by the budget, or spends its
        last evaluation, the evaluated rows are recorded and :class:`BudgetExhausted` is
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
            raise BudgetExhausted
        return f

    def result(self, method: str) -> TuneResult:
        """The record of every evaluation made, as the result of tuner ``method``."""
        if self.n == 0:
            raise TuningError(f"tuner '{method}' made no evaluation")
        all_x = np.concatenate(self.xs)
        all_f = np.concatenate(self.fs)
        i = int(np.argmin(all_f))
        return TuneResult(x_best=all_x[i].copy(), f_best=float(all_f[i]), n_evaluations=self.n,
                          history=np.minimum.accumulate(all_f), all_x=all_x, all_f=all_f,
                          method=method)


def make_rng(random_state: int | np.random.Generator | None) -> np.random.Generator:
    """The one Generator of a tuner run: ``random_state`` itself when a Generator, else one
    seeded by it (a legacy RandomState gives the seed of its next draw)."""
    if isinstance(random_state, np.random.Generator):
        return random_state
    if isinstance(random_state, np.random.RandomState):
        return np.random.default_rng(random_state.randint(0, 2**31 - 1))
    return np.random.default_rng(random_state)


def check_arguments(n_dims: int, budget: int, population: int | None,
                    min_pop: int = 1) -> None:
    """TuningError unless ``n_dims`` and ``budget`` are positive integers and ``population``
    None or an integer >= ``min_pop``."""
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


def uniform_population(rng: np.random.Generator, n: int, d: int) -> np.ndarray:
    """``n`` positions drawn uniformly in the box, shape (n, d)."""
    return rng.uniform(LOW, HIGH, size=(n, d))


def generations(budget: int, population: int, per_generation: int) -> int:
    """Number of (possibly partial) generations after the initial population."""
    return max(1, math.ceil((budget - population) / per_generation))
