"""The sample grid and the inputs of a solve, checked once for every solver.

:func:`thermal.simulate`, :func:`thermal.simulate_many` and :func:`thermal.final_temperature`
take the same sample times, chamber temperature and initial node temperatures; each reads
them through these functions, so a wrong input gets the same :class:`ThermalError` whichever
solver received it, and the three group the intervals into the same step classes (one matrix
exponential per class, equation (5) of thermal/solve.py).
"""

from __future__ import annotations

import numpy as np

from thermal.errors import ThermalError

__all__ = ["as_time", "as_ambient", "as_initial", "step_classes"]


def as_time(time_s: object) -> np.ndarray:
    """The sample times t_k [s] as a 1-D, non-empty, finite, strictly increasing float array,
    else a ThermalError locating the first bad sample."""
    t = np.asarray(time_s, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ThermalError(f"time_s must be a non-empty 1-D array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ThermalError(f"time_s is not finite at sample {int(np.argmin(np.isfinite(t)))}")
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        k = int(bad[0])
        raise ThermalError(f"time_s must be strictly increasing: time_s[{k + 1}] = "
                           f"{t[k + 1]} after time_s[{k}] = {t[k]}")
    return t


def as_ambient(ambient_c: object, time_s: np.ndarray) -> np.ndarray:
    """The chamber temperature T_amb [degC] at every sample of ``time_s`` [s] (checked by
    :func:`as_time`) from a scalar, an array (n_t,) or a callable(t_s) -> float, checked
    finite (a ThermalError names the first time where it is not)."""
    if callable(ambient_c):
        amb = np.array([float(ambient_c(t)) for t in time_s.tolist()])
    else:
        amb = np.asarray(ambient_c, dtype=float)
        if amb.ndim == 0:
            amb = np.full(time_s.shape, float(amb))
        elif amb.shape != time_s.shape:
            raise ThermalError(f"ambient_c must be a scalar, a callable or an array of "
                               f"shape {time_s.shape}, got shape {amb.shape}")
    if not np.all(np.isfinite(amb)):
        k = int(np.argmin(np.isfinite(amb)))
        raise ThermalError(f"ambient_c is not finite at t = {time_s[k]} s")
    return amb


def as_initial(initial_c: object, names) -> np.ndarray:
    """T(t_0) of every node [degC], shape (n,) for the n node ``names``, from a scalar or an
    array (n,), as a new array checked finite (a ThermalError names the first bad node)."""
    n = len(names)
    try:
        t0 = np.broadcast_to(np.asarray(initial_c, dtype=float), (n,)).copy()
    except ValueError:
        raise ThermalError(f"initial_c must be a scalar or have shape ({n},), got shape "
                           f"{np.shape(initial_c)}") from None
    if not np.all(np.isfinite(t0)):
        raise ThermalError(f"initial_c is not finite for node "
                           f"{names[int(np.argmin(np.isfinite(t0)))]!r}")
    return t0


def step_classes(time_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(h, cls): the distinct steps h [s] of the sample times ``time_s`` [s] and, per
    interval k, the index cls[k] into h (one set of step matrices per class).

    Steps that differ by less than the resolution of the time stamps themselves (16 ulp of
    the largest |t|) are one step: a uniform grid from ``np.linspace`` has one class.
    """
    dt = np.diff(time_s)
    if dt.size == 0:
        return np.empty(0), np.empty(0, dtype=int)
    tol = 16.0 * np.spacing(np.max(np.abs(time_s[[0, -1]])))
    unique, inverse = np.unique(dt, return_inverse=True)
    starts = np.concatenate([[True], np.diff(unique) > tol])
    # a class starts where the gap to the previous distinct step exceeds tol
    cluster = np.cumsum(starts) - 1
    first = unique[starts]
    return first, cluster[inverse]
