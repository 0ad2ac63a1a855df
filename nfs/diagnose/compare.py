"""Model against measurement, channel by channel: where the model fails.

For every measured run the model is simulated beside it on the run's own time base,
turntable motion, start temperature T0, latitude, heading and chamber
(:func:`nfs.experiment.conditions_from_run`), and each channel is set against the model's
prediction:

==================  ==========================================================================
channel             residual r = measured - model
==================  ==========================================================================
``temp_fog_c``,     thermometer reading minus the model's noise-free reading (sensed node
``temp_acc_x_c``,   temperature through the thermometer's lag and offset, without noise or
``temp_acc_y_c``    quantisation) [degC], every sample at rest
``gyro_drift_dph``  separate_drift(measured).drift_dph - separate_drift(noise-free model
                    run).drift_dph [deg/h]: the model's deterministic prediction through the
                    same wavelet separation, with the measured run's thresholds
``acc_x_g``,        dwell mean of the measured specific force minus the dwell mean of the
``acc_y_g``         model's noise-free one [g], one point per dwell
==================  ==========================================================================

The sign is measured minus model throughout, so a positive bias is what the model lacks.

Noise floor (what the residual would be if the model were right), per sample, squared:

- thermometers: noise_c^2 + quantum_c^2 / 12 of the model's thermometer (white noise plus
  uniform rounding error);
- gyro drift: the model is simulated twice with independent noise (seeds ``(seed, k, SALT,
  0)`` and ``(seed, k, SALT, 1)`` for run k); each separated drift d_a, d_b is the
  deterministic prediction plus one realisation of the noise that leaks through the
  denoiser, so (d_a - d_b)^2 / 2 estimates the variance of a measured run about the
  prediction when the model is right, bias instability and ARW included (an estimate from
  the wavelet noise alone would miss the bias instability, which no denoiser can tell from
  drift);
- accelerometers: sigma^2 / n for a dwell of n samples, sigma the per-sample noise estimated
  from the measured run itself (standard deviation of first differences within the dwells over
  sqrt(2)).

A channel whose pooled residual RMS is within :data:`CONSISTENT_RATIO` times its floor is
"consistent with noise".  Otherwise its failure is put into words from three statistics:

- *when*: the fraction of the excess residual energy sum(r^2 - floor^2) in the first N minutes
  after power-on, pooled over the runs; "concentrated in the first N min" when at least half
  of it lies in a span of at most a third of the run;
- *T0*: the correlation over the runs of the excess RMS sqrt(max(rms^2 - floor^2, 0)) with
  |T0 - 25 C| and with T0 (needs 3 runs at 3 start temperatures);
- *positions*: per cycle, the dwell means of the residual minus their cycle mean (a slow
  trend cancels); per position the mean over the cycles and its standard error from the
  cycle-to-cycle scatter; "follows the turntable positions" when the spread (RMS) of the
  per-position means is :data:`POSITION_RATIO` times their standard error or more, pooled over
  the runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from ..docfields import document_fields
from ..denoise import separate_drift
from ..effects.thermometer import THERMOMETERS
from ..errors import MeasurementError, NfsError
from ..experiment import chamber_assumption, conditions_from_run, simulate_run
from ..instrument import Instrument
from ..io.measurement import Run
from ..northfind import heading_rmse, north_find
from .start_state import StartModel
from .heading import HEADING_ALPHA, HeadingComparison, RunHeading, heading_comparison
from .heading import json_value as _json
from .thermal_residual import DEFAULT_START, start_states

__all__ = [
    "CHANNELS", "CONSISTENT_RATIO", "POSITION_RATIO", "T0_CORRELATION", "SEED_SALT",
    "ChannelSpec", "ResidualStats", "ChannelRun", "PositionTest", "ChannelSummary",
    "RunHeading", "HeadingComparison", "Comparison", "compare", "heading_comparison",
    "noise_free", "CHANNEL_BY_KEY", "STAGES", "HEADING_ALPHA", "format_sig",
]

#: A residual RMS up to this multiple of the noise floor is "consistent with noise".
CONSISTENT_RATIO = 1.5
#: Spread of the per-position biases, in standard errors, from which a residual "follows the
#: turntable positions" (about 1 under the null hypothesis).
POSITION_RATIO = 3.0
#: |correlation| over the runs from which a residual is said to scale with T0 ...
T0_CORRELATION = 0.8
#: ... provided the per-run excess RMS varies by at least this coefficient of variation.
T0_VARIATION = 0.3
#: Reference temperature of |T0 - 25 C| [degC].
T_REF_C = 25.0
#: Spans after power-on tried for "concentrated in the first N min" [min].
EARLY_SPANS_MIN = (5.0, 10.0, 15.0, 20.0, 30.0, 45.0, 60.0)
#: Entropy word that keeps the model's noise streams apart from a scenario's own
#: ``(seed, i_temp, repeat)`` streams, so a model never replays a run's noise exactly.
SEED_SALT = 0xC0DE


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
_BASE_COLUMNS = ("time_s", "position_deg", "moving")
_THERMOMETER_OF = {col: name for name, col in THERMOMETERS.items()}
STAGES = ("startup", "stable", "all")


# --------------------------------------------------------------------------------------------
# Results


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
        return {k: _json(v) for k, v in vars(self).items()}


@dataclass(frozen=True)
class PositionTest:
    """Whether a residual follows the turntable positions (module docstring)."""

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
        return {"theta_deg": [_json(v) for v in self.theta_deg],
                "bias": [_json(v) for v in self.bias],
                "stderr": [_json(v) for v in self.stderr], "n_cycles": self.n_cycles,
                "spread": _json(self.spread), "uncertainty": _json(self.uncertainty)}


@dataclass(frozen=True)
class ChannelRun:
    """One channel of one run: the traces and their statistics."""

    channel: str
    """Channel key."""
    run_name: str
    """Name of the run."""
    start_temperature_c: float
    """T0 of the run [degC]."""
    time_s: np.ndarray
    """Time of each residual point [s] (a sample at rest, or a dwell's mid-time)."""
    position_deg: np.ndarray
    """Turntable angle of each point [deg]."""
    measured: np.ndarray
    """Measured value at each point."""
    model: np.ndarray
    """The model's deterministic prediction at each point (its noise-free simulation; for the
    gyro drift, through the same wavelet separation as the measurement)."""
    floor_sq: np.ndarray
    """Squared noise floor at each point (see the module docstring)."""
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
        return {"channel": self.channel, "run": self.run_name,
                "start_temperature_c": _json(self.start_temperature_c),
                "stages": {k: v.to_dict() for k, v in self.stages.items()},
                "positions": [{"theta_deg": _json(k), **v.to_dict()}
                              for k, v in self.positions.items()],
                "position_test": self.position_test.to_dict()}


@dataclass(frozen=True)
class ChannelSummary:
    """One channel over all runs, and where it fails in words."""

    channel: str
    """Channel key."""
    unit: str
    """Unit of the residual."""
    stages: dict[str, tuple[float, float]]
    """Per stage: (pooled residual RMS, pooled noise floor) [channel unit]."""
    ratio: float
    """Pooled residual RMS / noise floor over the whole runs."""
    stage_ratios: dict[str, float]
    """Pooled residual RMS / noise floor per stage."""
    consistent: bool
    """Every stage's ratio <= CONSISTENT_RATIO."""
    early_fraction: dict[float, float]
    """Span N [min] -> fraction of the excess residual energy in the first N minutes."""
    early_span_min: float | None
    """The shortest span that holds half the excess energy, if it is early (else None)."""
    corr_abs_t0: float
    """Correlation over the runs of the excess RMS with |T0 - 25 C| (NaN if undefined)."""
    corr_t0: float
    """Correlation over the runs of the excess RMS with T0 (NaN if undefined)."""
    t0_variation: float
    """Coefficient of variation of the per-run excess RMS."""
    position_ratio: float
    """Pooled spread of the per-position biases / their standard error."""
    sentence: str
    """Where it fails, in words."""

    def to_dict(self) -> dict[str, Any]:
        return {"channel": self.channel, "unit": self.unit,
                "stages": {k: {"rms": _json(r), "floor": _json(f)}
                           for k, (r, f) in self.stages.items()},
                "ratio": _json(self.ratio),
                "stage_ratios": {k: _json(v) for k, v in self.stage_ratios.items()},
                "consistent": self.consistent,
                "early_fraction": {f"{k:g}": _json(v) for k, v in self.early_fraction.items()},
                "early_span_min": _json(self.early_span_min),
                "corr_abs_t0": _json(self.corr_abs_t0), "corr_t0": _json(self.corr_t0),
                "t0_variation": _json(self.t0_variation),
                "position_ratio": _json(self.position_ratio), "sentence": self.sentence}


@document_fields
@dataclass(frozen=True)
class Comparison:
    """The model against a set of runs (:func:`compare`)."""

    model_name: str
    """Name of the compared instrument model."""
    run_names: tuple[str, ...]
    """The runs, in the order given."""
    start_temperatures_c: tuple[float, ...]
    """T0 of each run [degC]."""
    settings: dict[str, Any]
    """seed, startup_end_s, stable_start_s, window_s."""
    per_run: dict[str, tuple[ChannelRun, ...]]
    """Channel key -> one :class:`ChannelRun` per run."""
    summaries: dict[str, ChannelSummary]
    """Channel key -> :class:`ChannelSummary`."""
    headings: tuple[RunHeading, ...]
    """Heading RMSE per run."""
    heading: HeadingComparison | None = None
    """The heading's own verdict over the runs (:func:`heading_comparison`)."""
    assumptions: tuple[str, ...] = ()
    """What the comparison assumed where the runs do not say (a missing chamber record)."""

    def sentences(self) -> list[str]:
        """"Where it fails", one sentence per channel, in channel order."""
        return [self.summaries[c.key].sentence for c in CHANNELS if c.key in self.summaries]

    @property
    def heading_pooled(self) -> dict[str, float]:
        """RMS over the runs of each heading RMSE column [deg]."""
        out = {}
        for k in ("measured_startup_deg", "measured_stable_deg", "model_startup_deg",
                  "model_stable_deg"):
            v = np.array([getattr(h, k) for h in self.headings], dtype=float)
            v = v[np.isfinite(v)]
            out[k] = float(np.sqrt(np.mean(v * v))) if v.size else math.nan
        return out

    def heading_sentence(self) -> str:
        """Measured against predicted heading RMSE, in words, with the heading's verdict."""
        p = self.heading_pooled
        text = (f"heading RMSE start-up: measured {format_sig(p['measured_startup_deg'])} deg, "
                f"model {format_sig(p['model_startup_deg'])} deg; stable: measured "
                f"{format_sig(p['measured_stable_deg'])} deg, model "
                f"{format_sig(p['model_stable_deg'])} deg (RMS over {len(self.headings)} "
                "run(s))")
        if self.heading is None:
            return text
        drift = self.summaries.get("gyro_drift_dph")
        positions = bool(drift is not None and math.isfinite(drift.position_ratio)
                         and drift.position_ratio >= POSITION_RATIO)
        return text + "; " + self.heading.sentence(
            None if drift is None else drift.consistent, positions)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (NaN as null; no traces)."""
        return {
            "model": self.model_name,
            "runs": [{"name": n, "start_temperature_c": _json(t)}
                     for n, t in zip(self.run_names, self.start_temperatures_c)],
            "settings": {k: _json(v) for k, v in self.settings.items()},
            "residual": "measured - model",
            "channels": {k: {"summary": self.summaries[k].to_dict(),
                             "runs": [cr.to_dict() for cr in self.per_run[k]]}
                         for k in self.summaries},
            "heading": {"runs": [h.to_dict() for h in self.headings],
                        "pooled": {k: _json(v) for k, v in self.heading_pooled.items()},
                        **({} if self.heading is None else self.heading.to_dict()),
                        "sentence": self.heading_sentence()},
            "sentences": self.sentences(),
            "assumptions": list(self.assumptions),
        }


# --------------------------------------------------------------------------------------------
# Small helpers


def format_sig(v: float, digits: int = 3) -> str:
    return "nan" if v is None or not math.isfinite(v) else f"{v:.{digits}g}"


def _fmt_value(v: float, unit: str) -> str:
    """A value with its unit; specific forces in micro-g."""
    if unit == "g":
        return f"{format_sig(v * 1e6, 3)} ug"
    return f"{format_sig(v, 3)} {unit}"


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def noise_free(inst: Instrument) -> Instrument:
    """The instrument without gyro, accelerometer and thermometer noise or quantisation: its
    simulated channels are the model's expectation (aux channels are left as they are)."""
    g = replace(inst.gyro, arw_deg_per_rth_h=0.0, bias_instability_dph=0.0,
                rrw_deg_per_h_per_rth_h=0.0)
    a = replace(inst.accelerometers, noise_ug_per_rth_hz=0.0)
    th = {k: replace(v, noise_c=0.0, quantum_c=0.0) for k, v in inst.thermometers.items()}
    return replace(inst, gyro=g, accelerometers=a, thermometers=th)


def _check_run(run: Run) -> None:
    for col in _BASE_COLUMNS + tuple(c.column for c in CHANNELS):
        if col not in run.columns:
            what = next((c.label for c in CHANNELS if c.column == col), "turntable motion")
            raise MeasurementError(
                f"run '{run.name}' has no column '{col}', which the comparison needs "
                f"({what})", file=run.path, column=col)


def _worst_window(t: np.ndarray, r: np.ndarray, window_s: float) -> tuple[float, float]:
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


def _stats(t, r, f2, mask, window_s) -> ResidualStats:
    tt, rr, ff = t[mask], r[mask], f2[mask]
    n = int(rr.size)
    if n == 0:
        return ResidualStats(0, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan)
    ws, wr = _worst_window(tt, rr, window_s)
    return ResidualStats(n=n, rms=_rms(rr), bias=float(np.mean(rr)), std=float(np.std(rr)),
                         floor_rms=float(np.sqrt(np.mean(ff))), worst_start_s=ws,
                         worst_rms=wr)


def _position_test(values: np.ndarray, cycles) -> PositionTest:
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


# --------------------------------------------------------------------------------------------
# One run


def _run_seed(seed, k: int, role: int):
    base = tuple(seed) if isinstance(seed, (tuple, list)) else (int(seed),)
    return (*base, k, SEED_SALT, role)


def _channel_run(spec, run, t, pos, measured, model, f2, rest, cycles, per_sample_residual,
                 cfg) -> ChannelRun:
    r = measured - model
    stages = {
        "startup": _stats(t, r, f2, rest & (t < cfg["startup_end_s"]), cfg["window_s"]),
        "stable": _stats(t, r, f2, rest & (t >= cfg["stable_start_s"]), cfg["window_s"]),
        "all": _stats(t, r, f2, rest, cfg["window_s"]),
    }
    angles = np.round(np.mod(pos, 360.0), 1)
    positions = {}
    for a in np.unique(angles[rest]):
        positions[float(a)] = _stats(t, r, f2, rest & (angles == a), cfg["window_s"])
    keep = rest
    return ChannelRun(
        channel=spec.key, run_name=run.name,
        start_temperature_c=float(run.meta.start_temperature_c),
        time_s=t[keep], position_deg=pos[keep], measured=measured[keep], model=model[keep],
        floor_sq=f2[keep], stages=stages, positions=positions,
        position_test=_position_test(per_sample_residual, cycles))


def _compare_run(inst: Instrument, clean: Instrument, run: Run, k: int, cfg,
                 start_c: np.ndarray | None) -> tuple[dict[str, ChannelRun], RunHeading]:
    seed = cfg["seed"]
    sim_a, sim_b, expect = (simulate_run(model, conditions_from_run(
        run, seed=_run_seed(seed, k, role), initial_c=start_c))
        for model, role in ((inst, 0), (inst, 1), (clean, 2)))
    expect = expect.run

    t = np.asarray(run["time_s"], dtype=float)
    pos = np.asarray(run["position_deg"], dtype=float)
    rest = np.asarray(run["moving"], dtype=float) == 0.0
    nf_meas = north_find(run)
    nf_model = north_find(sim_a.run)
    cycles = list(nf_meas.cycles)
    out: dict[str, ChannelRun] = {}

    for spec in CHANNELS:
        if spec.kind == "thermometer":
            th = inst.thermometers[_THERMOMETER_OF[spec.column]]
            meas = np.asarray(run[spec.column], dtype=float)
            mod = np.asarray(expect[spec.column], dtype=float)
            f2 = np.full(t.shape, th.noise_c ** 2 + th.quantum_c ** 2 / 12.0)
            ok = rest & np.isfinite(meas)
            out[spec.key] = _channel_run(spec, run, t, pos, meas, mod, f2, ok, cycles,
                                         np.where(ok, meas - mod, np.nan), cfg)
        elif spec.kind == "gyro":
            d_meas = separate_drift(run)
            d_a = separate_drift(sim_a.run).drift_dph
            d_b = separate_drift(sim_b.run).drift_dph
            # the noise-free model shrunk with the measurement's thresholds: its own (near
            # zero) would keep what the measurement's shrinkage took off a position-
            # dependent term, and the residual would show it (wavelet_denoise, thresholds)
            meas = d_meas.drift_dph
            mod = separate_drift(expect, thresholds=d_meas.denoise.thresholds).drift_dph
            ok = ~d_meas.interpolated
            out[spec.key] = _channel_run(spec, run, t, pos, meas, mod, 0.5 * (d_a - d_b) ** 2,
                                         ok, cycles, np.where(ok, meas - mod, np.nan), cfg)
        else:  # accelerometer: dwell means
            meas_s = np.asarray(run[spec.column], dtype=float)
            mod_s = np.asarray(expect[spec.column], dtype=float)
            dwells = [d for c in cycles for d in c.dwells]
            tm, pm, mm, om, f2 = [], [], [], [], []
            diffs = []
            for d in dwells:
                seg = meas_s[d.start:d.stop]
                ok = np.isfinite(seg)
                if ok.sum() < 2:
                    continue
                tm.append(0.5 * (d.t_start_s + d.t_end_s))
                pm.append(d.theta_deg)
                mm.append(seg[ok].mean())
                om.append(mod_s[d.start:d.stop][ok].mean())
                f2.append(ok.sum())
                diffs.append(np.diff(seg[ok]))
            n_pts = np.asarray(f2, dtype=float)
            dd = np.concatenate(diffs) if diffs else np.array([])
            sigma2 = float(np.var(dd) / 2.0) if dd.size > 1 else math.nan
            tm_a = np.asarray(tm, dtype=float)
            mask = np.ones(tm_a.shape, dtype=bool)
            out[spec.key] = _channel_run(
                spec, run, tm_a, np.asarray(pm, dtype=float), np.asarray(mm, dtype=float),
                np.asarray(om, dtype=float), sigma2 / np.maximum(n_pts, 1), mask, cycles,
                np.where(rest, meas_s - mod_s, np.nan), cfg)

    def stage(nf):
        s = heading_rmse(nf, startup_end_s=cfg["startup_end_s"],
                         stable_start_s=cfg["stable_start_s"])
        return s.startup_deg, s.stable_deg

    (mu, ms), (pu, ps) = stage(nf_meas), stage(nf_model)
    heading = RunHeading(run.name, float(run.meta.start_temperature_c), mu, ms, pu, ps)
    return out, heading


# --------------------------------------------------------------------------------------------
# Over the runs: statistics and words


def _corr(x: np.ndarray, y: np.ndarray) -> float:
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return math.nan
    return float(np.corrcoef(x, y)[0, 1])


_STAGE_WORDS = {"startup": "start-up stage", "stable": "stable stage", "all": "whole runs"}


def _ratio(rms: float, floor: float) -> float:
    if not (math.isfinite(rms) and math.isfinite(floor)):
        return math.nan
    return rms / floor if floor > 0 else (math.inf if rms > 0 else 1.0)


def _summarise(spec: ChannelSpec, runs: Sequence[ChannelRun]) -> ChannelSummary:
    stages = {}
    for s in STAGES:
        num = sum(cr.stages[s].n * cr.stages[s].rms ** 2 for cr in runs if cr.stages[s].n)
        fl = sum(cr.stages[s].n * cr.stages[s].floor_rms ** 2 for cr in runs if cr.stages[s].n)
        n = sum(cr.stages[s].n for cr in runs)
        stages[s] = ((math.sqrt(num / n), math.sqrt(fl / n)) if n else (math.nan, math.nan))
    rms, floor = stages["all"]
    ratios = {s: _ratio(*stages[s]) for s in STAGES}
    ratio = ratios["all"]
    worst = max(("startup", "stable"), key=lambda s: ratios[s] if math.isfinite(ratios[s])
                else -1.0)
    consistent = bool(max(v for v in ratios.values() if math.isfinite(v)) <= CONSISTENT_RATIO
                      if any(math.isfinite(v) for v in ratios.values()) else True)

    # when: excess energy in the first N minutes, pooled over the runs
    duration = max((float(cr.time_s[-1]) for cr in runs if cr.time_s.size), default=0.0)
    total = sum(float(np.sum(cr.residual ** 2 - cr.floor_sq)) for cr in runs)
    early: dict[float, float] = {}
    span = None
    for n_min in EARLY_SPANS_MIN:
        part = sum(float(np.sum((cr.residual ** 2 - cr.floor_sq)[cr.time_s < 60.0 * n_min]))
                   for cr in runs)
        early[n_min] = float(np.clip(part / total, 0.0, 1.0)) if total > 0 else math.nan
        if (span is None and total > 0 and early[n_min] >= 0.5
                and 60.0 * n_min <= duration / 3.0):
            span = n_min

    # T0: correlation of the per-run excess RMS
    t0 = np.array([cr.start_temperature_c for cr in runs], dtype=float)
    exc = np.array([math.sqrt(max(cr.stages["all"].rms ** 2 - cr.stages["all"].floor_rms ** 2,
                                  0.0)) for cr in runs])
    c_abs, c_t0 = _corr(np.abs(t0 - T_REF_C), exc), _corr(t0, exc)
    variation = float(np.std(exc) / np.mean(exc)) if np.mean(exc) > 0 else 0.0

    # positions: pooled spread / standard error
    spreads = np.array([cr.position_test.spread for cr in runs], dtype=float)
    uncs = np.array([cr.position_test.uncertainty for cr in runs], dtype=float)
    ok = np.isfinite(spreads) & np.isfinite(uncs) & (uncs > 0)
    pos_ratio = (float(np.sqrt(np.mean(spreads[ok] ** 2)) / np.sqrt(np.mean(uncs[ok] ** 2)))
                 if ok.any() else math.nan)
    pos_spread = float(np.sqrt(np.mean(spreads[ok] ** 2))) if ok.any() else math.nan

    head = (f"{spec.label} ({spec.key}) residual {_fmt_value(rms, spec.unit)} RMS, "
            f"{ratio:.1f}x the noise floor ({_fmt_value(floor, spec.unit)})")
    if math.isfinite(ratios[worst]) and ratios[worst] > max(ratio, CONSISTENT_RATIO):
        head += (f"; {_STAGE_WORDS[worst]} {_fmt_value(stages[worst][0], spec.unit)} RMS, "
                 f"{ratios[worst]:.1f}x its floor")
    if consistent:
        sentence = head + ": consistent with noise."
    else:
        parts = []
        if span is not None:
            parts.append(f"concentrated in the first {span:g} min after power-on "
                         f"({100 * early[span]:.0f}% of the excess residual energy in "
                         f"{100 * 60 * span / duration:.0f}% of the time)")
        elif total > 0:
            last = EARLY_SPANS_MIN[-1]
            parts.append(f"spread over the run ({100 * early[last]:.0f}% of the excess "
                         f"residual energy in the first {last:g} min)")
        n_runs = int(np.isfinite(exc).sum())
        if variation >= T0_VARIATION and math.isfinite(c_abs) and c_abs >= T0_CORRELATION \
                and c_abs >= abs(c_t0):
            parts.append(f"growing with |T0 - 25 C| (correlation {c_abs:.2f} over "
                         f"{n_runs} runs)")
        elif variation >= T0_VARIATION and math.isfinite(c_t0) and abs(c_t0) >= T0_CORRELATION:
            parts.append(f"{'growing' if c_t0 > 0 else 'falling'} with T0 (correlation "
                         f"{c_t0:.2f} over {n_runs} runs)")
        elif variation >= T0_VARIATION and math.isfinite(c_abs) and c_abs <= -T0_CORRELATION:
            parts.append(f"largest near 25 C (correlation with |T0 - 25 C| {c_abs:.2f} over "
                         f"{n_runs} runs)")
        elif math.isfinite(c_abs):
            parts.append(f"not scaling with T0 (correlation with |T0 - 25 C| {c_abs:.2f}, "
                         f"with T0 {c_t0:.2f})")
        if math.isfinite(pos_ratio) and pos_ratio >= POSITION_RATIO:
            parts.append(f"following the turntable positions (per-position bias spread "
                         f"{_fmt_value(pos_spread, spec.unit)}, {pos_ratio:.1f}x its "
                         f"uncertainty)")
        elif math.isfinite(pos_ratio):
            parts.append(f"not following the turntable positions (per-position bias spread "
                         f"{pos_ratio:.1f}x its uncertainty)")
        sentence = head + ", " + ", ".join(parts) + "."
    return ChannelSummary(
        channel=spec.key, unit=spec.unit, stages=stages, ratio=float(ratio),
        stage_ratios=ratios,
        consistent=consistent, early_fraction=early, early_span_min=span, corr_abs_t0=c_abs,
        corr_t0=c_t0, t0_variation=variation, position_ratio=pos_ratio, sentence=sentence)


def compare(inst: Instrument, runs: Sequence[Run], *, seed=0, startup_end_s: float = 3600.0,
            stable_start_s: float = 5400.0, window_s: float = 600.0,
            start_state: StartModel | None = DEFAULT_START) -> Comparison:
    """Set the model ``inst`` beside every measured run, channel by channel.

    Each run is replayed on its own (time base, motion, T0, latitude, heading, chamber), so
    runs with different latitudes or schedules can be compared in one set.

    Parameters
    ----------
    inst : Instrument
        The model (e.g. a fitted one).
    runs : sequence of Run
        The measured runs; each needs ``time_s``, ``position_deg``, ``moving``, ``gyro_dph``,
        ``acc_x_g``, ``acc_y_g`` and the three thermometer columns, and a true heading.
    seed : int or tuple of int
        Root of the model's noise; run k uses ``(seed, k, SEED_SALT, role)``.
    startup_end_s, stable_start_s : float
        Start-up stage t < startup_end_s; stable stage t >= stable_start_s [s]. The heading
        RMSE uses :func:`nfs.northfind.heading_rmse` with the same bounds.
    window_s : float
        Length of the window of the worst residual [s].
    start_state : StartModel or None
        Each run's node temperatures at power-on are estimated from its thermometers
        through the model (:func:`nfs.diagnose.thermal_residual.start_states`: an
        unfinished soak, a unit off its air) and the model starts there; None: at T0.

    Returns
    -------
    Comparison

    Raises
    ------
    NfsError
        No runs, a run missing a needed column (the message names run and column), a run
        without a true heading or without a complete north-finding cycle.
    """
    runs = list(runs)
    if not runs:
        raise NfsError("compare needs at least one run")
    if not window_s > 0:
        raise NfsError(f"window_s must be > 0, got {window_s}")
    for run in runs:
        _check_run(run)
    cfg = {"seed": seed, "startup_end_s": float(startup_end_s),
           "stable_start_s": float(stable_start_s), "window_s": float(window_s)}
    clean = noise_free(inst)
    starts = start_states(inst, runs) if start_state is not None else {}
    per_run: dict[str, list[ChannelRun]] = {c.key: [] for c in CHANNELS}
    headings = []
    for k, run in enumerate(runs):
        chans, heading = _compare_run(inst, clean, run, k, cfg, starts.get(run.name))
        for key, cr in chans.items():
            per_run[key].append(cr)
        headings.append(heading)
    summaries = {c.key: _summarise(c, per_run[c.key]) for c in CHANNELS}
    settings = dict(cfg)
    settings["seed"] = str(seed)
    return Comparison(
        model_name=inst.name, run_names=tuple(r.name for r in runs),
        start_temperatures_c=tuple(float(r.meta.start_temperature_c) for r in runs),
        settings=settings, per_run={k: tuple(v) for k, v in per_run.items()},
        summaries=summaries, headings=tuple(headings),
        heading=heading_comparison(headings, HEADING_ALPHA),
        assumptions=tuple(a for a in (chamber_assumption(runs),) if a))
