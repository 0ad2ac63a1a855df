"""Time to spec: how long after power-on the heading stays within a user's specification.

The start-up question of a north-finder's user: powered on at T0, when can the heading be
trusted?  For a run north-found cycle by cycle (:func:`~nfs.northfind.north_find`), with
cycle k output at t_k (the end of its last dwell, :attr:`NorthFindResult.t_end_s`) and
heading error e_k, and a specification s [deg]:

    time to spec = t_k*   with k* the first cycle such that |e_j| <= s for every j >= k*

i.e. the output time of the first cycle of the final unbroken run of in-spec cycles.  The
same on the rolling RMSE of the last ``window`` cycles,

    r_k = sqrt( (1/W) sum_{j = k-W+1}^{k} e_j^2 ),   k >= W - 1 (0-based),

answers "when does the heading's RMS error over a window of W cycles stay within spec".

Meaning of the special values: ``inf`` when the last cycle (or the last rolling RMSE) is out
of spec (the run never settled within it, up to its end: the answer is censored by the run's
length); ``nan`` when there is no finite error to judge (unknown true heading, no cycle, or
fewer than W cycles for the rolling RMSE).  Cycles with a NaN error (no data) are left out.
A run within spec from its first cycle gets that cycle's output time, the earliest answer a
north finder can give.
"""

from __future__ import annotations

import math

import numpy as np

from nfs.errors import NfsError

__all__ = ["median_time_s", "time_to_spec_s", "rolling_rmse_deg", "run_time_to_spec_s", "DEFAULT_WINDOW"]

#: Cycles of the rolling RMSE by default: five, as many as a stage RMSE of the default
#: schedule rests on (the start-up hour holds five 640 s cycles).
DEFAULT_WINDOW = 5


def _check(spec_deg: float) -> None:
    if not (isinstance(spec_deg, (int, float)) and math.isfinite(spec_deg) and spec_deg > 0):
        raise NfsError(f"a heading specification must be a finite angle > 0 deg, got "
                       f"{spec_deg!r}")


def time_to_spec_s(t_s, error_deg, spec_deg: float) -> float:
    """Time after power-on after which every value of ``error_deg`` stays within
    ``spec_deg`` (module docstring).

    Parameters
    ----------
    t_s : array_like
        Output time of each cycle, increasing [s after power-on].
    error_deg : array_like
        Heading error of each cycle [deg] (NaN: no data, left out).
    spec_deg : float
        The specification s > 0 [deg]; ``|e| <= s`` is within spec.

    Returns
    -------
    float
        The time [s]; ``inf`` when the last finite error is out of spec; ``nan`` when there
        is no finite error.
    """
    _check(spec_deg)
    t = np.asarray(t_s, dtype=float)
    e = np.asarray(error_deg, dtype=float)
    if t.shape != e.shape:
        raise NfsError(f"time_to_spec_s: {t.size} times but {e.size} errors")
    ok = np.isfinite(e)
    t, e = t[ok], e[ok]
    if e.size == 0:
        return math.nan
    out = np.flatnonzero(np.abs(e) > spec_deg)
    if out.size == 0:
        return float(t[0])
    last = int(out[-1])
    return math.inf if last == e.size - 1 else float(t[last + 1])


def rolling_rmse_deg(error_deg, window: int) -> np.ndarray:
    """r_k = sqrt(mean of e_j^2 over the ``window`` cycles ending at k) [deg].

    The first ``window - 1`` values are NaN (an incomplete window), and so is every window
    after a NaN error (no data): drop those first, as :func:`run_time_to_spec_s` does.
    """
    if isinstance(window, bool) or not isinstance(window, int) or window < 1:
        raise NfsError(f"the rolling RMSE window must be a positive number of cycles, got "
                       f"{window!r}")
    e = np.asarray(error_deg, dtype=float)
    sq = np.concatenate([[0.0], np.cumsum(e ** 2)])
    out = np.full(e.size, np.nan)
    if e.size >= window:
        out[window - 1:] = np.sqrt((sq[window:] - sq[:-window]) / window)
    return out


def run_time_to_spec_s(t_s, error_deg, spec_deg: float, window: int = DEFAULT_WINDOW
                       ) -> tuple[float, float]:
    """(time to spec of every cycle, time to spec of the rolling RMSE over ``window``
    cycles) of one run [s]: :func:`time_to_spec_s` on the errors and on
    :func:`rolling_rmse_deg`."""
    t = np.asarray(t_s, dtype=float)
    e = np.asarray(error_deg, dtype=float)
    ok = np.isfinite(e)
    t, e = t[ok], e[ok]
    return (time_to_spec_s(t, e, spec_deg),
            time_to_spec_s(t, rolling_rmse_deg(e, window), spec_deg))


def median_time_s(values) -> float:
    """Median of times to spec that are not NaN (``inf``, never within spec, counts) [s];
    NaN when none is."""
    v = [x for x in values if not math.isnan(x)]
    return float(np.median(v)) if v else math.nan
