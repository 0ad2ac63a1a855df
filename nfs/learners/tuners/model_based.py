"""Model-based tuners: the tree-structured Parzen estimator of Optuna (optional).

A baseline beside the metaheuristics of the seed papers (the "TPE-SVR" row), needing Optuna
(the ``tune`` extra).
"""

from __future__ import annotations

import warnings

import numpy as np

from .evaluation import (HIGH, LOW, BudgetExhausted, Evaluator, ObjectiveBatch, TuneResult,
                         TuningError, check_arguments, make_rng)

__all__ = ["tpe"]


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
    check_arguments(n_dims, budget, population)
    try:
        import optuna
    except ImportError as exc:
        raise TuningError("tuner 'tpe' needs Optuna: install the 'tune' extra "
                          "(pip install 'nfs-startup[tune]')") from exc
    rng = make_rng(random_state)
    seed = int(rng.integers(0, 2**31 - 1))
    dist = {f"x{j}": optuna.distributions.FloatDistribution(LOW, HIGH) for j in range(n_dims)}
    with warnings.catch_warnings():  # multivariate / constant_liar are marked experimental
        warnings.simplefilter("ignore")
        sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=n_startup_trials,
                                             multivariate=multivariate, constant_liar=True)
    verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    ev = Evaluator(objective_batch, n_dims, budget)
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
            except BudgetExhausted:
                break
            for t, v in zip(trials, f):
                study.tell(t, float(v) if np.isfinite(v) else float("inf"))
    finally:
        optuna.logging.set_verbosity(verbosity)
    return ev.result("tpe")
