"""What a compensation feature at time t may use: the feature modes and their horizons.

A compensator predicts the drift at sample i from features of the thermometers.  How far
past t_i a feature may look decides whether an instrument could compute it:

``cycle`` (the default)
    data up to the end of the north-finding cycle that holds t_i.  A cycle's heading is
    computed from its dwell means and output at the cycle's end (docs/physics.md section 5), so
    a compensator may wait for the cycle's last sample before it subtracts the drift from
    that cycle's samples: no latency is added to any heading.  Samples outside every
    complete cycle (the moves between cycles, a partial cycle at the end, a run with no
    turntable schedule) fall back to ``causal``.
``causal``
    data up to t_i only (a compensated rate output sample by sample, in real time).
``offline``
    the whole run (the centred 121 s Savitzky-Golay rate looks 60 s ahead, and its first
    minute fits the first window): what a test-bench analysis can compute, not an
    instrument.  Every output that uses it says "offline".

The *horizon* of sample i is the index of the last sample its features may use:
h_i = n - 1 (offline), i (causal), or the last sample of i's cycle (cycle).

The cycles are those of the north finder, :func:`nfs.northfind.segment.segment_cycles` on
the run's ``position_deg`` and ``moving`` columns with the schedule of its metadata
(``positions_deg``, ``dwell_s``), so that ``cycle`` mode ends each cycle exactly where
:func:`nfs.northfind.north_find` does (the schedule itself is
:class:`nfs.sensors.turntable.Schedule`: cycles run back to back from power-on, each of
len(positions) x (dwell_s + move_s)).  This is the one import of the north-finding stage
here: one definition of a cycle serves both, and segmenting the turntable record needs none
of the north finder's solving.
"""

from __future__ import annotations

import numpy as np

from ..errors import NfsError
from ..northfind.segment import segment_cycles

__all__ = [
    "DEFAULT_FEATURE_MODE",
    "FEATURE_MODES",
    "FEATURE_MODE_NOTES",
    "FeatureModeError",
    "check_features_mode",
    "cycle_spans",
    "horizon_index",
    "in_cycle_mask",
]

#: The feature modes, the instrument-computable ones first.
FEATURE_MODES = ("cycle", "causal", "offline")

#: The mode used when none is given.
DEFAULT_FEATURE_MODE = "cycle"

#: What each mode means, in the words the tables and reports print.
FEATURE_MODE_NOTES = {
    "cycle": "each feature uses the thermometers up to the end of its north-finding cycle, "
             "when the cycle's heading is output: an instrument computes it with no added "
             "latency",
    "causal": "each feature uses the thermometers up to its own sample only: an instrument "
              "computes it in real time",
    "offline": "OFFLINE: each rate feature looks 60 s ahead (centred Savitzky-Golay "
               "window), the first minute fits the second minute's readings: no instrument "
               "can compute it; a bench analysis of recorded runs",
}


class FeatureModeError(NfsError):
    """An unknown feature mode."""


def check_features_mode(mode: str, option: str = "features mode") -> str:
    """Return ``mode`` if it is one of :data:`FEATURE_MODES`, else raise one clear error.

    Parameters
    ----------
    mode : str
        The mode asked for.
    option : str
        How the user gave it (``--features-mode``): the message starts with it; empty for
        no prefix (a scenario error names its key instead).

    Returns
    -------
    str
        ``mode``.

    Raises
    ------
    FeatureModeError
        ``mode`` is not a known mode; the message names the option and lists the modes.
    """
    if not isinstance(mode, str) or mode not in FEATURE_MODES:
        msg = f"unknown mode {mode!r}; choose one of {', '.join(FEATURE_MODES)}"
        raise FeatureModeError(f"{option}: {msg}" if option else msg)
    return mode


def cycle_spans(run) -> list[tuple[int, int]]:
    """Sample ranges [start, stop) of the run's complete north-finding cycles.

    Parameters
    ----------
    run : Run
        A run with ``time_s``, and ``position_deg`` and ``moving`` when it was made on a
        turntable; its metadata's ``positions_deg`` and ``dwell_s`` give the schedule
        (recovered from the dwells when absent, as the north finder does).

    Returns
    -------
    list of (int, int)
        From the first sample of a cycle's first dwell to one past the last sample of its
        last dwell, in time order; empty when the run has no turntable columns or no
        complete cycle.
    """
    cols = run.columns
    if "position_deg" not in cols or "moving" not in cols:
        return []
    meta = run.meta
    cycles = segment_cycles(np.asarray(cols["time_s"], dtype=float),
                            np.asarray(cols["position_deg"], dtype=float),
                            np.asarray(cols["moving"], dtype=float),
                            getattr(meta, "positions_deg", None),
                            dwell_s=getattr(meta, "dwell_s", None))
    return [(c.dwells[0].start, c.dwells[-1].stop) for c in cycles]


def in_cycle_mask(run) -> np.ndarray:
    """True at every sample of a complete north-finding cycle (:func:`cycle_spans`).

    Parameters
    ----------
    run : Run
        The run.

    Returns
    -------
    ndarray of bool
        One flag per sample; False in the moves between cycles, in a partial cycle and on
        a run without a turntable schedule.
    """
    mask = np.zeros(np.asarray(run.columns["time_s"]).size, dtype=bool)
    for start, stop in cycle_spans(run):
        mask[start:stop] = True
    return mask


def horizon_index(run, mode: str) -> np.ndarray:
    """h_i, the index of the last sample the features of sample i may use.

    Parameters
    ----------
    run : Run
        The run (its ``time_s``; for ``cycle`` also its turntable columns and schedule).
    mode : str
        One of :data:`FEATURE_MODES`.

    Returns
    -------
    ndarray of int
        h_i >= i for every sample: n - 1 (offline), i (causal), the last sample of the
        cycle that holds i, or i outside every cycle (cycle).
    """
    check_features_mode(mode)
    n = np.asarray(run.columns["time_s"]).size
    if mode == "offline":
        return np.full(n, n - 1, dtype=np.intp)
    h = np.arange(n, dtype=np.intp)
    if mode == "cycle":
        for start, stop in cycle_spans(run):
            h[start:stop] = stop - 1
    return h
