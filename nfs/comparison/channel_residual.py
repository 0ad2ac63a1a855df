"""One channel of one run set beside the model: the residual's statistics by stage and by
turntable position, and the test of whether it follows the positions.

The residual is measured minus model throughout (a positive bias is what the model lacks),
every point carrying its squared noise floor (:mod:`nfs.comparison.compare_runs`).  Its
statistics (:class:`ResidualStats`) are taken over the start-up stage, the stable stage and
the whole run (:class:`StageBounds`), and over each turntable angle, with the window of
``window_s`` where the residual is largest.

Position test (:func:`position_test`): per cycle, the dwell means of the residual minus their
cycle mean (a slow trend cancels); per position the mean over the cycles and its standard
error from the cycle-to-cycle scatter.  :mod:`nfs.comparison.channel_summary` pools the spread
of these per-position means over the runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..run import Run
from .heading import json_value

__all__ = ["ChannelSpec", "CHANNELS", "CHANNEL_BY_KEY", "COMPARISON_STAGES", "StageBounds",
           "ResidualStats", "PositionTest", "ChannelRun", "worst_window", "residual_stats",
           "position_test", "channel_run"]


#: A trace kept for the figures and left out of the JSON record (:mod:`nfs.io.records`).
TRACE = {"record": False}


@dataclass(frozen=True)
class ChannelSpec:
    """One compared channel."""

    key: str
    """Name of the channel in the results (``gyro_drift_dph``, ``temp_fog_c``, ...)."""
    column: str
    """Measurement column it needs."""
    label: str
    """Words for the report."""
    unit: str
    """Unit of the residual."""
    kind: str
    """``thermometer``, ``gyro`` or ``accelerometer``."""


#: The compared channels, in report order.
CHANNELS: tuple[ChannelSpec, ...] = (
    ChannelSpec("temp_fog_c", "temp_fog_c", "FOG thermometer", "C", "thermometer"),
    ChannelSpec("temp_acc_x_c", "temp_acc_x_c", "QFA x thermometer", "C", "thermometer"),
    ChannelSpec("temp_acc_y_c", "temp_acc_y_c", "QFA y thermometer", "C", "thermometer"),
    ChannelSpec("gyro_drift_dph", "gyro_dph", "gyro drift", "deg/h", "gyro"),
    ChannelSpec("acc_x_g", "acc_x_g", "QFA x dwell mean", "g", "accelerometer"),
    ChannelSpec("acc_y_g", "acc_y_g", "QFA y dwell mean", "g", "accelerometer"),
)
CHANNEL_BY_KEY = {c.key: c for c in CHANNELS}
#: The stages of a run the statistics are taken over.
COMPARISON_STAGES = ("startup", "stable", "all")


@dataclass(frozen=True)
class StageBounds:
    """Where a run's stages lie and the window of its worst residual."""

    startup_end_s: float
    """The start-up stage is t < startup_end_s [s]."""
    stable_start_s: float
    """The stable stage is t >= stable_start_s [s]."""
    window_s: float
    """Length of the window of the worst residual [s]."""


@dataclass(frozen=True)
class ResidualStats:
    """Residual statistics of one channel over a set of samples (a stage or a position)."""

    n: int
    """Number of residual points (samples, or dwells for an accelerometer)."""
    rms: float
    """sqrt(mean(r^2)) [channel unit]."""
    bias: float
    """mean(r) [channel unit]."""
    std: float
    """Standard deviation of r [channel unit]."""
    floor_rms: float
    """sqrt(mean(floor^2)): the RMS expected from noise alone [channel unit]."""
    worst_start_s: float
    """Start of the window of ``window_s`` with the largest residual RMS [s]."""
    worst_rms: float
    """RMS of r in that window [channel unit]."""

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (NaN as null; no traces)."""
        return {k: json_value(v) for k, v in vars(self).items()}


@dataclass(frozen=True)
class PositionTest:
    """Whether a residual follows the turntable positions (:func:`position_test`)."""

    theta_deg: tuple[float, ...]
    """Turntable angles theta_k [deg]."""
    bias: tuple[float, ...]
    """Mean over the cycles of the dwell residual minus its cycle mean, per position."""
    stderr: tuple[float, ...]
    """Standard error of each, from the cycle-to-cycle scatter."""
    n_cycles: int
    """Cycles used."""

    @property
    def spread(self) -> float:
        """RMS of the per-position biases [channel unit]."""
        b = np.asarray(self.bias, dtype=float)
        return float(np.sqrt(np.mean(b * b))) if b.size else math.nan

    @property
    def uncertainty(self) -> float:
        """RMS of their standard errors [channel unit]."""
        s = np.asarray(self.stderr, dtype=float)
        return float(np.sqrt(np.mean(s * s))) if s.size else math.nan

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (NaN as null; no traces)."""
        return {"theta_deg": [json_value(v) for v in self.theta_deg],
                "bias": [json_value(v) for v in self.bias],
                "stderr": [json_value(v) for v in self.stderr], "n_cycles": self.n_cycles,
                "spread": json_value(self.spread), "uncertainty": json_value(self.uncertainty)}


@dataclass(frozen=True)
class ChannelRun:
    """One channel of one run: the traces and their statistics."""

    channel: str
    """Channel key."""
    run_name: str
    """Name of the run."""
    start_temperature_c: float
    """T0 of the run [degC]."""
    time_s: np.ndarray = field(metadata=TRACE)
    """Time of each residual point [s] (a sample at rest, or a dwell's mid-time)."""
    position_deg: np.ndarray = field(metadata=TRACE)
    """Turntable angle of each point [deg]."""
    measured: np.ndarray = field(metadata=TRACE)
    """Measured value at each point."""
    model: np.ndarray = field(metadata=TRACE)
    """The model's deterministic prediction at each point (its noise-free simulation; for the
    gyro drift, through the same wavelet separation as the measurement)."""
    floor_sq: np.ndarray = field(metadata=TRACE)
    """Squared noise floor at each point (:mod:`nfs.comparison.compare_runs`)."""
    stages: dict[str, ResidualStats]
    """``startup``, ``stable`` and ``all``."""
    positions: dict[float, ResidualStats]
    """Statistics by turntable angle [deg]."""
    position_test: PositionTest
    """The cycle-contrast test of position dependence."""

    @property
    def residual(self) -> np.ndarray:
        """measured - model."""
        return self.measured - self.model

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (NaN as null; no traces)."""
        return {"channel": self.channel, "run": self.run_name,
                "start_temperature_c": json_value(self.start_temperature_c),
                "stages": {k: v.to_dict() for k, v in self.stages.items()},
                "positions": [{"theta_deg": json_value(k), **v.to_dict()}
                              for k, v in self.positions.items()],
                "position_test": self.position_test.to_dict()}


def _rms(x: np.ndarray) -> float:
    """sqrt(mean(x^2)), NaN for no points."""
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def worst_window(t: np.ndarray, r: np.ndarray, window_s: float) -> tuple[float, float]:
    """Start time and RMS of the window [t_i, t_i + window_s) with the largest RMS, over
    windows that lie within the record and hold at least half as many points as the
    fullest window."""
    if t.size == 0:
        return math.nan, math.nan
    c2 = np.concatenate([[0.0], np.cumsum(r * r)])
    stop = np.searchsorted(t, t + window_s, side="left")
    count = stop - np.arange(t.size)
    inside = t + window_s <= t[-1] + (t[1] - t[0] if t.size > 1 else 0.0) + 1e-9
    ok = inside & (count >= 0.5 * count.max())
    if not ok.any():
        return float(t[0]), _rms(r)
    ms = np.where(ok, (c2[stop] - c2[:-1]) / np.maximum(count, 1), -np.inf)
    i = int(np.argmax(ms))
    return float(t[i]), float(np.sqrt(ms[i]))


def residual_stats(t: np.ndarray, r: np.ndarray, f2: np.ndarray, mask: np.ndarray,
                   window_s: float) -> ResidualStats:
    """Statistics of the residual ``r`` at times ``t`` [s] with squared floor ``f2`` over the
    points of ``mask``; the worst window is ``window_s`` long [s]."""
    tt, rr, ff = t[mask], r[mask], f2[mask]
    n = int(rr.size)
    if n == 0:
        return ResidualStats(0, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan)
    ws, wr = worst_window(tt, rr, window_s)
    return ResidualStats(n=n, rms=_rms(rr), bias=float(np.mean(rr)), std=float(np.std(rr)),
                         floor_rms=float(np.sqrt(np.mean(ff))), worst_start_s=ws,
                         worst_rms=wr)


def position_test(values: np.ndarray, cycles: Sequence[Any]) -> PositionTest:
    """Position dependence of a per-sample residual (module docstring).

    The dwell means m_j of consecutive complete cycles (period P dwells) lose their slow
    trend by a centred moving average over one cycle (weights 1/P, or [1/2, 1, ..., 1, 1/2]/P
    for even P, as in classical seasonal decomposition), which holds every position once and
    removes a linear trend exactly; the detrended means are then averaged by turntable angle,
    with the standard error of each mean from their scatter.
    """
    if not cycles:
        return PositionTest((), (), (), 0)
    dwells = [d for c in cycles for d in c.dwells]
    period = len(cycles[0].dwells)
    m = np.full(len(dwells), np.nan)
    for j, d in enumerate(dwells):
        v = values[d.start:d.stop]
        v = v[np.isfinite(v)]
        if v.size:
            m[j] = v.mean()
    theta = np.round(np.mod([d.theta_deg for d in dwells], 360.0), 1)
    if period % 2:
        w = np.full(period, 1.0 / period)
    else:
        w = np.concatenate([[0.5], np.ones(period - 1), [0.5]]) / period
    h = (w.size - 1) // 2
    if len(dwells) < w.size + 2:
        angles = tuple(float(a) for a in np.unique(theta))
        return PositionTest(angles, (math.nan,) * len(angles), (math.nan,) * len(angles),
                            len(cycles))
    trend = np.convolve(m, w, mode="valid")          # trend of dwells h .. n-h-1
    contrast = m[h:len(m) - h] - trend
    th = theta[h:len(m) - h]
    angles, bias, se = [], [], []
    for a in np.unique(theta):
        c = contrast[(th == a) & np.isfinite(contrast)]
        angles.append(float(a))
        bias.append(float(c.mean()) if c.size else math.nan)
        se.append(float(c.std(ddof=1) / math.sqrt(c.size)) if c.size > 1 else math.nan)
    return PositionTest(tuple(angles), tuple(bias), tuple(se), len(cycles))


def channel_run(spec: ChannelSpec, run: Run, t: np.ndarray, pos: np.ndarray,
                measured: np.ndarray, model: np.ndarray, f2: np.ndarray, rest: np.ndarray,
                cycles: Sequence[Any], per_sample_residual: np.ndarray, bounds: StageBounds
                ) -> ChannelRun:
    """One channel of ``run``: the points ``rest`` of the ``measured`` and ``model`` values at
    times ``t`` [s] and turntable angles ``pos`` [deg] with squared floor ``f2``, their
    statistics by stage (``bounds``) and by angle, and the position test of the full-rate
    ``per_sample_residual`` over the north finder's ``cycles``."""
    r = measured - model
    w = bounds.window_s
    stages = {
        "startup": residual_stats(t, r, f2, rest & (t < bounds.startup_end_s), w),
        "stable": residual_stats(t, r, f2, rest & (t >= bounds.stable_start_s), w),
        "all": residual_stats(t, r, f2, rest, w),
    }
    angles = np.round(np.mod(pos, 360.0), 1)
    positions = {}
    for a in np.unique(angles[rest]):
        positions[float(a)] = residual_stats(t, r, f2, rest & (angles == a), w)
    keep = rest
    return ChannelRun(
        channel=spec.key, run_name=run.name,
        start_temperature_c=float(run.meta.start_temperature_c),
        time_s=t[keep], position_deg=pos[keep], measured=measured[keep], model=model[keep],
        floor_sq=f2[keep], stages=stages, positions=positions,
        position_test=position_test(per_sample_residual, cycles))
