"""The tuners by name, and the one function that runs any of them.

:data:`TUNERS` maps a name to its function; :func:`minimize` checks the name and the
options against the function's signature (an unknown one raises an error listing the valid
ones) and runs it.  A user's own tuner, with the signature of :func:`minimize`, plugs in as
``TUNERS["mine"] = my_tuner``.
"""

from __future__ import annotations

import inspect
from typing import Callable

import numpy as np

from .evaluation import ObjectiveBatch, TuneResult, TuningError
from .model_based import tpe
from .sampling import grid, random_search
from .swarm import gwo, hho, pso, ssa

__all__ = ["TUNERS", "minimize"]


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
