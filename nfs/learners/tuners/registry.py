"""The tuners by name, and the one function that runs any of them.

:data:`TUNERS` maps a name to its function, :func:`register_tuner` adds one,
:func:`get_tuner` looks one up (an unknown name raises an error listing the valid ones);
:func:`minimize` checks the options against the function's signature and runs it.  A
user's own tuner, with the signature of :func:`minimize`, plugs in as a built-in one does::

    @register_tuner("mine")
    def mine(objective_batch, n_dims, *, budget, random_state=None, population=None):
        ...

(The compensation methods have a registry of the same shape,
:mod:`nfs.compensate.registry`.)
"""

from __future__ import annotations

import inspect
from typing import Callable

import numpy as np

from .evaluation import ObjectiveBatch, TuneResult, TuningError
from .model_based import tpe
from .sampling import grid, random_search
from .swarm import gwo, hho, pso, ssa

__all__ = ["TUNERS", "register_tuner", "get_tuner", "minimize"]

#: The arguments every tuner takes (those :func:`minimize` passes it).
TUNER_ARGUMENTS = ("objective_batch", "n_dims", "budget", "random_state", "population")


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


def register_tuner(name: str, function: Callable[..., TuneResult] | None = None, *,
                   replace: bool = False):
    """Register ``function`` as the tuner ``name`` (a decorator when ``function`` is
    omitted, which returns the function unchanged).

    Parameters
    ----------
    name : str
        The name :func:`minimize` and :class:`~nfs.learners.search.MetaheuristicSearchCV`
        take as ``method``.
    function : callable
        ``function(objective_batch, n_dims, *, budget, random_state, population, **options)
        -> TuneResult``.
    replace : bool
        Replace a tuner registered under ``name`` already (else that is an error).

    Raises
    ------
    TuningError
        ``name`` taken, or ``function`` missing one of the arguments :func:`minimize` passes.
    """
    if function is None:
        def decorator(f: Callable[..., TuneResult]) -> Callable[..., TuneResult]:
            register_tuner(name, f, replace=replace)
            return f
        return decorator
    if not isinstance(name, str) or not name:
        raise TuningError(f"tuner name {name!r}: a non-empty string")
    if name in TUNERS and not replace:
        raise TuningError(f"a tuner '{name}' is registered already; replace=True replaces it")
    params = inspect.signature(function).parameters
    missing = [a for a in TUNER_ARGUMENTS if a not in params]
    if missing:
        raise TuningError(f"tuner '{name}': its function lacks {', '.join(missing)} (the "
                          "signature of minimize)")
    TUNERS[name] = function
    return function


def get_tuner(name: str) -> Callable[..., TuneResult]:
    """The tuner registered as ``name``; TuningError listing the valid ones if none."""
    try:
        return TUNERS[name]
    except (KeyError, TypeError):
        raise TuningError(f"unknown tuner {name!r}; valid tuners: "
                          f"{', '.join(TUNERS)}") from None


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
        Maximum number of objective evaluations (see :mod:`nfs.learners.tuners` for the
        last, partial generation).
    random_state : int, numpy Generator or None
        Seed of every random draw.
    population : int, optional
        Population (swarm, pack, flock) size or batch size; method default if None.
    **options
        Method options (e.g. ``w``, ``c1``, ``c2``, ``v_max`` for 'pso'; ``PD``, ``SD``,
        ``ST`` for 'ssa'); see each function.
    """
    func = get_tuner(method)
    valid = [p for p in inspect.signature(func).parameters if p not in TUNER_ARGUMENTS]
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise TuningError(f"unknown option(s) {', '.join(unknown)} for tuner '{method}'; "
                          f"valid options: {', '.join(valid) or '(none)'}")
    return func(objective_batch, n_dims, budget=budget, random_state=random_state,
                population=population, **options)
