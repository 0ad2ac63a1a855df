"""The unit's power state over a run: power cycles (warm restarts) and time since power-on.

A run starts at power-on (t = 0).  A chamber program's ``{ power_off_s = S }`` step
(:mod:`nfs.chamber`) switches the unit off for S seconds and on again.  A measured run says
so in its optional ``powered`` column (1 on, 0 off); while off its sensor columns hold NaN.

Two quantities follow from the power state, for the simulator and for every fit that
replays a run:

- the heat released inside the unit, gated: P_j(t) = P_j s(t) with s(t) in {0, 1} the power
  state, held over each sample interval like every heat input (:func:`thermal.simulate`);
- the time since the latest power-on, t_on(t) = t - t_k for the last switch-on t_k <= t
  (t_on = t without power cycles): turn-on effects are functions of it
  (``turn_on_transient``: a exp(-t_on / tau)), so a warm restart starts them again.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["POWERED_COLUMN", "powered_mask", "since_power_on_s", "off_spans_s"]

#: The optional measurement column of the power state (1.0 on, 0.0 off).
POWERED_COLUMN = "powered"


def powered_mask(time_s: np.ndarray, off_spans_s: Sequence[tuple[float, float]]
                 ) -> np.ndarray:
    """s(t_k): False at samples with t_off <= t_k < t_on of any span, True elsewhere."""
    t = np.asarray(time_s, dtype=float)
    on = np.ones(t.shape, dtype=bool)
    for t_off, t_on in off_spans_s:
        on &= ~((t >= t_off) & (t < t_on))
    return on


def since_power_on_s(time_s: np.ndarray, powered: np.ndarray | None) -> np.ndarray:
    """t_on(t_k) = t_k - t_switch-on [s], the switch-on being t = 0 or the first powered
    sample after an off span; 0 while off.  ``powered`` None: t itself."""
    t = np.asarray(time_s, dtype=float)
    if powered is None:
        return t
    on = np.asarray(powered, dtype=bool)
    if on.all():
        return t
    starts = on & ~np.concatenate([[False], on[:-1]])
    starts[0] = bool(on[0])
    # the time of the latest switch-on at or before each sample (t[0] before any)
    idx = np.maximum.accumulate(np.where(starts, np.arange(t.size), 0))
    out = t - t[idx]
    out[~on] = 0.0
    return out


def off_spans_s(time_s: np.ndarray, powered: np.ndarray | None
                ) -> tuple[tuple[float, float], ...]:
    """The (switched off, switched on) spans of a recorded power state [s]; an off span
    still open at the end closes one sample after the last."""
    if powered is None:
        return ()
    t = np.asarray(time_s, dtype=float)
    on = np.asarray(powered, dtype=float) > 0.5
    if on.all():
        return ()
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    edges = np.diff(np.concatenate([[1], on.astype(int), [1]]))
    offs, ons = np.flatnonzero(edges == -1), np.flatnonzero(edges == 1)
    return tuple((float(t[a]), float(t[b]) if b < t.size else float(t[-1] + dt))
                 for a, b in zip(offs, ons))
