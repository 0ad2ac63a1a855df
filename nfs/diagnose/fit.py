"""Calibrate a model's free parameters to measured runs.

Bounded nonlinear least squares (:func:`scipy.optimize.least_squares`, method ``trf``,
``x_scale="jac"``; :mod:`nfs.diagnose.stage`) in two stages.  By default every free
parameter has a Gaussian prior centred on its start value (the preset) with the widths of
:mod:`nfs.diagnose.prior`, entered as rows (p - p0) / sigma beside the data rows, which are
divided by their noise level: the solution is the maximum a posteriori estimate, and a
parameter the runs do not determine stays near its preset instead of running to a bound.

**thermal**
    Free thermal parameters (capacities, conductances, node powers, thermal-effect
    coefficients such as the TEC slopes) and thermometer parameters (lags, offsets).
    Residual: the model's noise-free thermometer readings minus the measured ``temp_fog_c``,
    ``temp_acc_x_c``, ``temp_acc_y_c`` of every run, on a decimated grid (every
    ``decimate_s``).  Each run is replayed with its own start temperature, chamber and
    motion (:func:`nfs.experiment.conditions_from_run`).  For speed the thermal network is
    solved on the decimated grid: the chamber temperature and the turntable's moving
    fraction are averaged over each decimated step and a state-dependent power (the TEC law)
    is held over each decimated step (an O(h) error, about 3e-3 K at h = 10 s for the default
    TEC against the simulator's 1 s hold).  The sensed node temperatures are brought back to
    the run's own time base by cubic Hermite interpolation (values and the solver's exact
    rates at the knots), and the thermometer chain of the simulator
    (:func:`nfs.sensors.thermometer_reading`: lag, thermometer effects, offset) runs there
    with its noise and quantisation switched off; the residual is taken at the knots and
    divided by the thermometer's noise and rounding level sqrt(noise_c^2 + quantum_c^2 / 12)
    (:mod:`nfs.diagnose.thermal_residual`).  The Jacobian is scipy's forward differences
    with all n + 1 parameter vectors solved as one stack
    (:func:`nfs.diagnose.stage.forward_jacobian`).
    With a prior, each free thermometer offset is centred on its soak anchor (the readings of
    the first minute after power-on minus T0, :mod:`nfs.diagnose.soak`).  With ``n_starts``
    > 1, when the solution from the preset stays above the noise (reduced chi-square > 1.5),
    the stage starts again from the preset with every capacity and conductance +-30 %
    (:func:`nfs.diagnose.bound_advice.perturbed_starts`) and keeps the lowest cost.
**drift**
    Thermal parameters fixed at the thermal fit.  Free: ``gyro.bias_dph``, the gyro effect
    coefficients, the accelerometer biases, accelerometer effect coefficients and the
    turntable tilts.  The thermal solution of each run is computed once, at the run's own
    time base (as the simulator does), and the effects are evaluated on its
    :func:`nfs.experiment.effect_context`; a free parameter of a thermal effect makes the
    stage re-simulate at every evaluation.  Residuals, as means over windows of
    ``decimate_s`` of the samples at rest (moving samples excluded):

    - drift: model drift minus the measured raw drift ``gyro_dph - Earth projection``
      (:func:`nfs.denoise.earth_rate_projection_dph`, the drift that
      :func:`nfs.denoise.separate_drift` denoises).  Window means are linear, so they do
      not bias fast terms (the turn-on transient) the way the denoiser's shrinkage can;
      ``drift_signal="denoised"`` uses ``separate_drift(run).drift_dph`` instead.  The
      model drift is b + sum of the gyro effect terms + (K - 1) projection
      - Omega_ie sin L (b_x + accelerometer x terms): the last term is the x accelerometer's
      error seen through the elevation in the projection (nfs/denoise/drift.py).
    - ``acc_x_g``, ``acc_y_g``: model sin(e) + bias + accelerometer effects minus measured,
      when an accelerometer or turntable parameter is free.

    Each channel is divided by the standard error of its window means (within-window
    scatter / sqrt(count), median over windows) so the units mix on a common scale.  The
    tilts and accelerometer biases start at their linear least-squares solution from the
    window means (:mod:`nfs.diagnose.sensor_fit`), then move with the rest.  After the stage
    the gyro's ARW, bias instability and rate random walk are fitted to the Allan deviation
    of the full-rate residual at rest (:mod:`nfs.diagnose.noise_fit`) and set in the fitted
    instrument.

Uncertainties: cov = s^2 (J^T J)^-1 with s^2 = 2 cost / (m - n) of the data rows at the
solution of each stage, or with a prior the posterior (J^T J / s^2 + P^T P)^-1 (pseudo-
inverse; a direction the data rows do not constrain gives an infinite standard error and its
parameters are reported as not identifiable).  These are conditional on the other stage's
parameters and on the model being right.  A parameter that ends on its bound is reported
with what it says about the model's structure (:func:`nfs.diagnose.bound_advice.bound_advice`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

import thermal

from ..docfields import document_fields
from ..constants import OMEGA_IE_DPH
from ..denoise import earth_rate_projection_dph, separate_drift
from ..effects.thermometer import THERMOMETERS
from ..errors import InputError, NfsError
from ..experiment import chamber_assumption, conditions_from_run, effect_context, thermal_power
from ..instrument import Instrument
from ..io.atomic import atomic_write_text
from ..io.measurement import Run
from ..sensors import axis_elevation_deg
from .bound_advice import bound_advice, perturbed_starts
from .noise_fit import GyroNoiseEstimate, gyro_noise_from_residual, noise_record
from .params import (_all_paths, expand_paths, fit_bounds, get_param,
                     set_params)
from .prior import build_prior
from .sensor_fit import LEVEL_PATHS, LevelData, level_from_means
from .soak import SoakAnchor, anchor_offsets, soak_offsets
from .stage import StageReport, solve_stage
from .start_state import StartModel
from .thermal_residual import (DEFAULT_START, ThermalRun, decimation_step, prepare_thermal,
                               require_columns, simulate_knots, thermal_residual,
                               start_states, thermal_residual_parts, thermometer_floors)

__all__ = ["StageReport", "FitResult", "fit_model", "fitted_name", "default_free",
           "write_fitted_model",
           "model_drift_dph", "far_from_start", "FAR_FACTOR", "STAGES", "DEFAULT_DECIMATE_S"]

#: The stages of :func:`fit_model`, in order.
STAGES = ("thermal", "drift")

#: Default decimation of the residual grid [s].
DEFAULT_DECIMATE_S = 10.0

_THERMAL_KINDS = ("thermal", "thermometer")
_NOT_FREE_UNITS = ("s", "K", "degC", "channel unit")
"""Effect parameters left out of the default free set: time constants [s], temperature
periods [K], set points [degC] and channel references (collinear with the bias)."""


# ---------------------------------------------------------------------------------------------
# Results

@document_fields
@dataclass(frozen=True)
class FitResult:
    """The fitted instrument and an honest account of the fit."""

    instrument: Instrument
    """The fitted instrument."""
    initial: Instrument
    """The instrument the fit started from."""
    params: dict[str, float]
    """Fitted value of every free parameter {path: value}."""
    initial_params: dict[str, float]
    """Starting value of every free parameter."""
    stderr: dict[str, float]
    """Standard error {path: value} from the Jacobian (inf: not identifiable)."""
    bounds: dict[str, tuple[float, float]]
    """The box each parameter was kept in."""
    at_bound: tuple[str, ...]
    """Parameters that ended on a bound (the fit wanted to go further)."""
    unidentifiable: dict[str, str]
    """Parameters the runs cannot determine, with the reason."""
    stages: dict[str, StageReport]
    """Report of each stage run, by name."""
    rms_before: dict[str, float]
    """Residual RMS per channel with the initial parameters of its stage (thermometers [K],
    ``drift_dph`` [deg/h], ``acc_x_g``/``acc_y_g`` [g]); the drift stage starts from the
    thermally fitted model."""
    rms_after: dict[str, float]
    """Residual RMS per channel after the fit."""
    warnings: tuple[str, ...] = ()
    """Everything a user should know: no convergence, bounds hit, one run, ..."""
    prior_centre: dict[str, float] = field(default_factory=dict)
    """Centre p0 of each parameter's Gaussian prior (the preset, or the soak anchor for a
    thermometer offset); empty without a prior."""
    prior_sigma: dict[str, float] = field(default_factory=dict)
    """Width sigma_p of each prior [unit of the parameter]; inf: no prior on it."""
    prior_shift: dict[str, float] = field(default_factory=dict)
    """(fitted - p0) / sigma_p: how far the data moved each parameter, in prior widths."""
    bound_advice: dict[str, str] = field(default_factory=dict)
    """For each parameter at a bound: what the bound says about the model's structure."""
    soak: SoakAnchor | None = None
    """The thermometer offsets read from the soak at power-on (None: not used)."""
    noise: GyroNoiseEstimate | None = None
    """Gyro noise fitted to the Allan deviation of the drift residual at rest, with the curve
    (None: the drift stage did not run or ``fit_noise`` was off)."""
    start_c: dict[str, np.ndarray] = field(default_factory=dict)
    """Each run's node temperatures at power-on [degC] {run name: (n_nodes,)}, as the thermal
    stage estimated them (:mod:`nfs.diagnose.start_state`); empty: every node at T0."""
    start_amplitudes_c: dict[str, np.ndarray] = field(default_factory=dict)
    """Each run's start amplitudes a [K] (slow modes, then the fast remainder u)."""
    structure: Any = None
    """The refinement of the thermal structure (:class:`nfs.diagnose.refine.Refinement`)
    when :func:`nfs.diagnose.refine.fit_unit` tried one; None otherwise."""

    @property
    def converged(self) -> dict[str, bool]:
        """Convergence of each stage."""
        return {k: s.converged for k, s in self.stages.items()}

    @property
    def cost(self) -> dict[str, float]:
        """Final cost of each stage."""
        return {k: s.cost for k, s in self.stages.items()}

    @property
    def n_residuals(self) -> dict[str, int]:
        """Number of residuals of each stage."""
        return {k: s.n_residuals for k, s in self.stages.items()}

    def summary(self) -> str:
        """A few lines of text: each parameter with its error, flags and warnings."""
        lines = []
        for p, v in self.params.items():
            flag = " (at bound)" if p in self.at_bound else ""
            if p in self.unidentifiable:
                flag += " (not identifiable)"
            shift = self.prior_shift.get(p, math.nan)
            moved = f", {shift:+.2f} prior widths" if math.isfinite(shift) else ""
            lines.append(f"{p} = {v:.6g} +- {self.stderr.get(p, math.nan):.3g}"
                         f" (start {self.initial_params[p]:.6g}{moved}){flag}")
        if self.noise is not None:
            n = self.noise
            lines.append(f"gyro noise from the Allan deviation of the drift residual: "
                         f"N = {n.arw_deg_per_rth_h:.3g} deg/sqrt(h), "
                         f"B = {n.bias_instability_dph:.3g} deg/h, "
                         f"K = {n.rrw_deg_per_h_per_rth_h:.3g} deg/h/sqrt(h)")
        for ch in self.rms_after:
            lines.append(f"rms {ch}: {self.rms_before.get(ch, math.nan):.4g} -> "
                         f"{self.rms_after[ch]:.4g}")
        if self.structure is not None:
            lines.append(self.structure.summary())
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Free parameters

def default_free(inst: Instrument, stages: Sequence[str] = STAGES) -> list[str]:
    """The default free set.

    thermal stage: every node capacity, every conductance to the chamber, every non-zero
    node power, every thermometer lag and offset, the coefficients of the thermal effects
    (TEC slopes c_h, c_c; heat powers).  drift stage: ``gyro.bias_dph``, every coefficient of
    the gyro and accelerometer effects, the accelerometer biases and the turntable tilts.
    Effect time constants [s], temperature periods [K], set points [degC], channel
    references and parameters registered as shapes (shupe_stress's c_m) are left out (list
    them to free them).
    """
    out = []
    for path, kind in _all_paths(inst):
        leaf = path.rsplit(".", 1)[-1]
        if path.startswith("effects."):
            label = path[len("effects."):].rsplit(".", 1)[0]
            par = inst.effect(label).spec.parameter(leaf)
            take = par.unit not in _NOT_FREE_UNITS and not par.shape
        elif kind == "thermal":
            take = (leaf == "capacity_j_per_k"
                    or (leaf == "power_w" and get_param(inst, path) != 0.0)
                    or (leaf == "conductance_w_per_k"
                        and "chamber" in path.split(".")[2].split("-")))
        elif kind == "thermometer":
            take = leaf in ("lag_s", "offset_c")
        elif kind == "drift":
            take = leaf == "bias_dph"
        elif kind == "accelerometer":
            take = leaf in ("bias_x_g", "bias_y_g")
        else:  # turntable
            take = leaf.startswith("tilt_")
        stage = "thermal" if kind in _THERMAL_KINDS else "drift"
        if take and stage in stages:
            out.append(path)
    return out


def _stage_of(kind: str, stages: Sequence[str]) -> str:
    if kind in _THERMAL_KINDS and "thermal" in stages:
        return "thermal"
    return "drift"


# ---------------------------------------------------------------------------------------------
# Per-run data

@dataclass
class _DriftRun:
    """A run prepared for the drift stage."""

    run: Run
    cond: Any
    k: int
    windows: np.ndarray         # window index of every trusted sample
    trusted: np.ndarray
    keep: np.ndarray            # windows with enough trusted samples
    counts: np.ndarray
    projection: np.ndarray
    measured: dict[str, np.ndarray]   # window means of the measured channels
    scale: dict[str, float]           # standard error of a window mean, per channel
    azimuth: np.ndarray
    aux: dict[str, np.ndarray]
    ctx: Any = None


def _prepare_drift(run: Run, decimate_s: float, acc_channels: bool,
                   drift_signal: str) -> _DriftRun:
    require_columns(run, ("time_s", "position_deg", "moving", "gyro_dph", "acc_x_g"), "drift")
    if acc_channels:
        require_columns(run, ("acc_y_g",), "drift")
    if run.meta.true_heading_deg is None:
        raise InputError(f"run '{run.name}' has no true_heading_deg: the drift stage needs the "
                         "Earth-rate projection, which needs the true heading",
                         file=run.path, key="true_heading_deg")
    cond = conditions_from_run(run)
    t = np.asarray(run["time_s"], dtype=float)
    k = decimation_step(t, decimate_s)
    proj = earth_rate_projection_dph(run)
    if drift_signal == "denoised":
        drift = separate_drift(run).drift_dph
    elif drift_signal == "raw":
        drift = np.asarray(run["gyro_dph"], dtype=float) - proj
    else:
        raise NfsError(f"drift_signal must be 'raw' or 'denoised', got '{drift_signal}'")
    channels = {"drift_dph": drift}
    if acc_channels:
        channels["acc_x_g"] = np.asarray(run["acc_x_g"], dtype=float)
        channels["acc_y_g"] = np.asarray(run["acc_y_g"], dtype=float)
    trusted = np.asarray(run["moving"], dtype=float) == 0.0
    for v in channels.values():
        trusted &= np.isfinite(v)
    if not trusted.any():
        raise InputError(f"run '{run.name}' has no sample at rest with the gyro and "
                         "accelerometer channels present", file=run.path)
    w = (np.arange(t.size) // k)[trusted]
    n_w = int(w.max()) + 1
    counts = np.bincount(w, minlength=n_w)
    keep = counts >= max(1, k // 2)
    measured, scale = {}, {}
    for name, v in channels.items():
        x = v[trusted]
        mean = np.bincount(w, weights=x, minlength=n_w)
        sq = np.bincount(w, weights=x * x, minlength=n_w)
        c = np.maximum(counts, 1)
        m = mean / c
        var = np.maximum(sq / c - m * m, 0.0) / np.maximum(c - 1, 1)
        measured[name] = m[keep]
        se = float(np.median(np.sqrt(var[keep]))) if k > 1 else float(np.std(np.diff(x)))
        scale[name] = se if se > 0 else 1.0
    aux = {c: np.asarray(v, dtype=float) for c, v in run.columns.items() if c.startswith("aux_")}
    azimuth = np.mod(cond.true_heading_deg + np.asarray(run["position_deg"], dtype=float), 360.0)
    return _DriftRun(run=run, cond=cond, k=k, windows=w, trusted=trusted, keep=keep,
                     counts=counts, projection=proj, measured=measured, scale=scale,
                     azimuth=azimuth, aux=aux)


def _drift_context(inst: Instrument, rd: _DriftRun, start_c: np.ndarray | None = None):
    """The effect context of ``inst`` replayed on the run, started at ``start_c`` (node
    temperatures at power-on [degC]; None: T0 everywhere)."""
    cond = rd.cond
    t = cond.time_s
    _, moving = cond.turntable(t)
    power, _, _ = thermal_power(inst, t, moving)
    ambient = cond.start_temperature_c if cond.chamber_c is None else cond.chamber_c(t)
    th = thermal.simulate(inst.network, t, ambient_c=ambient,
                          initial_c=cond.start_temperature_c if start_c is None else start_c,
                          power_w=power,
                          ambient_hold="first-order")   # the recorded chamber, interpolated
    return effect_context(inst, th, rd.azimuth, rd.projection, moving, rd.aux)


def _block(rd: _DriftRun, x: np.ndarray) -> np.ndarray:
    n_w = rd.counts.size
    return (np.bincount(rd.windows, weights=x[rd.trusted], minlength=n_w)[rd.keep]
            / rd.counts[rd.keep])


def _sensor_models(inst: Instrument, ctx) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Full-rate model gyro error (bias + effects + (K - 1) projection) and accelerometer
    errors (bias + effects) per axis, on the samples of ``ctx``."""
    n = ctx.earth_rate_dph.size
    acc = {"x": np.full(n, inst.accelerometers.bias_x_g),
           "y": np.full(n, inst.accelerometers.bias_y_g)}
    g = inst.gyro
    gyro = np.full(n, g.bias_dph)
    if g.scale_factor != 1.0:
        gyro = gyro + (g.scale_factor - 1.0) * ctx.earth_rate_dph
    for e in inst.effects:
        if e.spec.kind == "gyro":
            gyro = gyro + e.spec.function(ctx, **e.params)
        elif e.spec.kind == "accelerometer":
            ax = e.params.get("axis")
            acc[ax] = acc[ax] + e.spec.function(ctx, **e.params)
    return gyro, acc


def model_drift_dph(inst: Instrument, ctx, latitude_deg: float) -> np.ndarray:
    """The model drift the drift stage fits, at every sample of ``ctx`` [deg/h].

    b + sum of the gyro effect terms + (K - 1) projection - Omega_ie sin L (b_x + x
    accelerometer terms), evaluated on an :class:`~nfs.effects.EffectContext` whose
    ``earth_rate_dph`` is the run's Earth-rate projection (module docstring, **drift**).
    Subtracting it from ``gyro_dph`` gives the model-compensated rate.
    """
    gyro, acc = _sensor_models(inst, ctx)
    return gyro - OMEGA_IE_DPH * math.sin(math.radians(latitude_deg)) * acc["x"]


def _drift_models(inst: Instrument, rd: _DriftRun, ctx) -> dict[str, np.ndarray]:
    """Window means of the model's drift and accelerometer channels."""
    gyro, acc = _sensor_models(inst, ctx)
    lat = math.radians(rd.cond.latitude_deg)
    drift = gyro - OMEGA_IE_DPH * math.sin(lat) * acc["x"]
    out = {"drift_dph": _block(rd, drift)}
    if "acc_x_g" in rd.measured:
        tt = inst.turntable
        for axis, offset in (("x", 0.0), ("y", 90.0)):
            elev = axis_elevation_deg(rd.azimuth + offset, tt.tilt_north_deg, tt.tilt_east_deg)
            out[f"acc_{axis}_g"] = _block(rd, np.sin(np.radians(elev)) + acc[axis])
    return out


# ---------------------------------------------------------------------------------------------
# Residual summaries

def _rms(parts: dict[str, list[np.ndarray]]) -> dict[str, float]:
    out = {}
    for ch, arrays in parts.items():
        x = np.concatenate(arrays) if arrays else np.empty(0)
        out[ch] = float(np.sqrt(np.mean(x * x))) if x.size else math.nan
    return out


# ---------------------------------------------------------------------------------------------
# The fit

def _tec_identifiability(inst: Instrument, data: list[ThermalRun], free: Sequence[str]
                         ) -> dict[str, str]:
    """c_h (c_c) of a TEC law needs samples with the source below (above) T_set."""
    out = {}
    for e in inst.effects:
        if e.name != "tec_power":
            continue
        node = e.params.get("node") or inst.gyro.source
        below = above = 0
        for th in simulate_knots([inst], data)[0]:
            src = th.temperature_c[:, list(th.node_names).index(node)]
            below += int(np.sum(src < e.params["T_set"]))
            above += int(np.sum(src > e.params["T_set"]))
        total = max(below + above, 1)
        for par, n, side in (("c_h", below, "below"), ("c_c", above, "above")):
            path = f"effects.{e.label}.{par}"
            if path in free and n < 0.02 * total:
                out[path] = (f"the source never sits {side} T_set = {e.params['T_set']:g} C "
                             f"in these runs: it needs runs starting {side} T_set")
    return out


_NOISE_FIELDS = ("arw_deg_per_rth_h", "bias_instability_dph", "rrw_deg_per_h_per_rth_h")


def _level_start(base: Instrument, data_d: list[_DriftRun], sp: Sequence[str],
                 weights: dict[str, float]) -> dict[str, float]:
    """Tilts and accelerometer biases from the window means at rest by linear least squares
    (:func:`nfs.diagnose.sensor_fit.level_from_means`), the model's accelerometer effects
    subtracted first."""
    free = [p for p in LEVEL_PATHS if p in sp]
    if not free:
        return {}
    level = set_params(base, {p: 0.0 for p in LEVEL_PATHS})
    rows = []
    for rd in data_d:
        effects = _drift_models(level, rd, rd.ctx)
        a = np.radians(rd.azimuth)
        rows.append(LevelData(cos_a=_block(rd, np.cos(a)), sin_a=_block(rd, np.sin(a)),
                              acc_x_g=rd.measured["acc_x_g"] - effects["acc_x_g"],
                              acc_y_g=rd.measured["acc_y_g"] - effects["acc_y_g"]))
    return level_from_means(rows, {p: get_param(base, p) for p in LEVEL_PATHS}, free,
                            scale_x_g=weights["acc_x_g"], scale_y_g=weights["acc_y_g"])


def _noise_of(model: Instrument, data_d: list[_DriftRun]) -> GyroNoiseEstimate:
    """Allan fit of the full-rate drift residual at rest, gyro - projection - model drift,
    after the start-up hour and with its position harmonics removed
    (:func:`nfs.diagnose.noise_fit.noise_record`)."""
    recs = []
    for rd in data_d:
        e = (np.asarray(rd.run["gyro_dph"], dtype=float) - rd.projection
             - model_drift_dph(model, rd.ctx, rd.cond.latitude_deg))
        recs.append(noise_record(e[rd.trusted], rd.cond.time_s[rd.trusted],
                                 rd.azimuth[rd.trusted]))
    fs = float(np.median([rd.cond.sample_rate_hz for rd in data_d]))
    return gyro_noise_from_residual(recs, fs)


#: A fitted value this many times its start (or its inverse), or this many prior widths
#: away, is reported as moved far: one effect or node explaining what another should.
FAR_FACTOR = 3.0


def _has_scale(path: str, kind: str) -> bool:
    """A parameter whose size, not only its sign, is physics: a capacity, conductance,
    power, lag or an effect coefficient (an offset, a bias or a tilt is a zero-centred
    number, judged by its prior width only)."""
    leaf = path.rsplit(".", 1)[-1]
    if kind in ("thermal", "thermometer"):
        return leaf != "offset_c"
    return path.startswith("effects.")


def far_from_start(start: float, value: float, prior_shift: float | None,
                   by_ratio: bool = True) -> str:
    """'from a to b (k times; s prior widths)' when ``value`` is far from ``start``
    (with ``by_ratio``: :data:`FAR_FACTOR` times or its inverse, or a change of sign; always:
    that many prior widths), else ''."""
    ratio = value / start if start else math.nan
    far = (by_ratio and start != 0 and (ratio > FAR_FACTOR or ratio < 1.0 / FAR_FACTOR)) or (
        prior_shift is not None and math.isfinite(prior_shift)
        and abs(prior_shift) > FAR_FACTOR)
    if not far:
        return ""
    what = [f"{ratio:.2g} times" if math.isfinite(ratio) else ""]
    if prior_shift is not None and math.isfinite(prior_shift):
        what.append(f"{prior_shift:+.1f} prior widths")
    return f"from {start:.4g} to {value:.4g} (" + "; ".join(w for w in what if w) + ")"


def fitted_name(model_name: str, runs: Sequence[Run]) -> str:
    """Name of a model fitted to ``runs``: ``'<model> fitted to <source>'``, the source being
    the runs' common folder, else their names' common prefix, else their count (a model that
    was itself fitted keeps the name of the model it started from)."""
    folders = {r.path.parent.name for r in runs if r.path is not None}
    if len(folders) == 1 and all(r.path is not None for r in runs) and folders != {""}:
        source = f"the runs in {folders.pop()}/"
    else:
        prefix = os.path.commonprefix([r.name for r in runs]).rstrip("_-. ")
        source = f"{prefix}*" if len(runs) > 1 and prefix else \
            (runs[0].name if len(runs) == 1 else f"{len(runs)} runs")
    base = model_name.split(" fitted to ")[0]  # a refit names the first model, not a chain
    return f"{base} fitted to {source}"


def fit_model(inst: Instrument, runs: Sequence[Run], free: Iterable[str] | None = None, *,
              stages: Sequence[str] = STAGES, decimate_s: float = DEFAULT_DECIMATE_S,
              max_nfev: int | None = 100, drift_signal: str = "raw",
              prior: Mapping[str, float | str] | str | None = "default",
              prior_scale: float = 1.0, soak_anchor: bool = True, n_starts: int = 1,
              fit_noise: bool = True, start_state: StartModel | None = DEFAULT_START,
              start_c: Mapping[str, np.ndarray] | None = None) -> FitResult:
    """Calibrate the free parameters of ``inst`` to ``runs`` (module docstring for the method).

    Parameters
    ----------
    inst : Instrument
        The model to start from.
    runs : sequence of Run
        Measured runs (any start temperatures, schedules, latitudes: each is replayed with
        its own).
    free : iterable of str, optional
        Parameter paths or glob patterns (:mod:`nfs.diagnose.params`); default
        :func:`default_free`.  Thermal and thermometer parameters go to the thermal stage,
        the others to the drift stage (all to the drift stage when only it runs).
    stages : sequence of str
        Which of ``("thermal", "drift")`` to run, in that order.
    decimate_s : float
        Spacing of the residual grid [s] (thermal knots; drift window length).
    max_nfev : int, optional
        Residual evaluations allowed per stage; a stage that hits it is reported as not
        converged.
    drift_signal : ``"raw"`` or ``"denoised"``
        Measured drift to fit: window means of gyro - projection, or the wavelet-denoised
        drift of :func:`nfs.denoise.separate_drift`.
    prior : ``"default"``, mapping or None
        Gaussian prior on every free parameter, centred on its start value
        (:mod:`nfs.diagnose.prior`): ``"default"`` takes the widths of
        :data:`~nfs.diagnose.prior.PRIOR_WIDTHS`; a mapping {path or pattern: width}
        overrides some (a number: absolute width; ``"30%"``: relative); None: no prior
        (unregularised least squares).
    prior_scale : float
        Multiplies every prior width; inf switches the prior off.
    soak_anchor : bool
        With a prior: centre each free thermometer offset on its reading in the first minute
        after power-on minus T0 (:func:`nfs.diagnose.soak.soak_offsets`), with the width of
        its standard error; runs that were not soaked are named in the warnings.
    n_starts : int
        Most starts of the thermal stage: the preset, then up to two perturbations of it
        (every capacity and conductance +-30 %,
        :func:`nfs.diagnose.bound_advice.perturbed_starts`), tried only while the best
        solution stays above the noise (reduced chi-square > 1.5); the lowest cost is
        kept.  1 (default): the preset only; with each run's start estimated, the extra
        starts ended at the same or a higher cost on the units of the independent family
        where they ran, at twice the time.
    start_state : StartModel or None
        How each run's node temperatures at power-on are estimated with the thermal
        parameters (:mod:`nfs.diagnose.start_state`: an unfinished soak, a unit off its
        air); None: every node at T0, the soak taken as complete.
    start_c : mapping {run name: node temperatures [degC]}, optional
        The runs' starts when the thermal stage does not run (default: estimated from the
        thermometers through ``inst`` with ``start_state``).
    fit_noise : bool
        After the drift stage, fit the gyro's ARW, bias instability and rate random walk to the
        Allan deviation of the drift residual at rest (:mod:`nfs.diagnose.noise_fit`) and set
        them in the fitted instrument.

    Raises
    ------
    NfsError
        No runs, an unknown stage or parameter, a run without a channel a stage needs, no
        true_heading_deg for the drift stage.
    """
    runs = list(runs)
    if not runs:
        raise NfsError("fit_model: no runs to fit")
    stages = tuple(stages)
    for s in stages:
        if s not in STAGES:
            raise NfsError(f"fit_model: unknown stage '{s}'; stages: {', '.join(STAGES)}")
    if not decimate_s > 0:
        raise NfsError(f"fit_model: decimate_s must be > 0, got {decimate_s}")
    paths = default_free(inst, stages) if free is None else expand_paths(inst, list(free))
    kinds = dict(_all_paths(inst))
    by_stage = {s: [p for p in paths if _stage_of(kinds[p], stages) == s] for s in stages}
    bounds = {p: fit_bounds(inst, p) for p in paths}
    initial_params = {p: get_param(inst, p) for p in paths}
    if n_starts < 1:
        raise NfsError(f"fit_model: n_starts must be >= 1, got {n_starts}")
    if isinstance(prior, str) and prior != "default":
        raise NfsError(f"fit_model: prior must be 'default', a mapping of widths or None, "
                       f"got '{prior}'")
    use_prior = prior is not None and math.isfinite(prior_scale)
    pr = (build_prior(inst, paths, initial_params, None if prior == "default" else prior,
                      prior_scale) if use_prior else None)
    start = dict(initial_params)
    soak = None
    if pr is not None and soak_anchor and any(p.endswith(".offset_c") for p in paths):
        soak = soak_offsets(inst, runs, start=start_state if "thermal" in stages else None)
        pr, start = anchor_offsets(pr, start, soak, prior_scale)

    current = inst
    noise = None
    amplitudes: dict[str, np.ndarray] = {}
    if "thermal" in stages:
        start_c = {}
    elif start_c is not None:
        start_c = dict(start_c)
    else:
        start_c = ({} if start_state is None else
                   start_states(inst, runs, decimate_s, start_state))
    stage_reports: dict[str, StageReport] = {}
    stderr: dict[str, float] = {}
    unident: dict[str, str] = {}
    at_bound: list[str] = []
    rms_before: dict[str, float] = {}
    rms_after: dict[str, float] = {}
    warnings: list[str] = []

    def stage(name: str, fun, base: Instrument, sp: list[str], batch=None) -> Instrument:
        """Solve one stage from ``base`` over the free paths ``sp``; record its report."""
        lb, ub = (np.array([bounds[p][i] for p in sp]) for i in (0, 1))
        x0 = np.array([start[p] for p in sp])
        extra = perturbed_starts(sp, x0, lb, ub)[:n_starts - 1] if name == "thermal" else []
        res, rep, se, un, at = solve_stage(name, fun, x0, lb, ub, max_nfev, sp,
                                           None if pr is None else pr.subset(sp), extra,
                                           batch=batch)
        stage_reports[name] = rep
        stderr.update(se)
        unident.update(un)
        at_bound.extend(at)
        return set_params(base, dict(zip(sp, res.x)))

    if "thermal" in stages:
        data = [prepare_thermal(r, decimate_s) for r in runs]
        sp = by_stage["thermal"]
        rms_before.update(_rms(thermal_residual_parts([current], data, start_state)[0]))
        if sp:
            base = current
            # each thermometer's rows divided by its noise and rounding level, so the cost is
            # chi-square-like beside the prior rows
            floor = thermometer_floors(base)

            def fun_many(xs) -> list[np.ndarray]:
                # the parameter vectors of a Jacobian solved as one stack (thermal_residual),
                # each run's start profiled out with its prior rows
                models = [set_params(base, dict(zip(sp, x))) for x in xs]
                res = thermal_residual(models, data, start_state)
                return [np.concatenate([a / floor[c] for c, arrs in parts.items()
                                        for a in arrs] + [rows])
                        for parts, rows in zip(res.parts, res.start_rows)]

            current = stage("thermal", lambda x: fun_many([x])[0], base, sp, batch=fun_many)
            unident.update(_tec_identifiability(current, data, sp))
        final = thermal_residual([current], data, start_state)
        rms_after.update(_rms(final.parts[0]))
        if start_state is not None:
            start_c = {rd.run.name: final.start_c[0][i] for i, rd in enumerate(data)}
            amplitudes = {rd.run.name: final.amplitudes_c[0][i] for i, rd in enumerate(data)}

    if "drift" in stages and by_stage["drift"]:
        sp = by_stage["drift"]
        acc_ch = any(kinds[p] in ("accelerometer", "turntable") for p in sp)
        data_d = [_prepare_drift(r, decimate_s, acc_ch, drift_signal) for r in runs]
        resim = any(kinds[p] in _THERMAL_KINDS for p in sp)
        for rd in data_d:
            rd.ctx = _drift_context(current, rd, start_c.get(rd.run.name))
        base = current
        weights = {ch: float(np.median([rd.scale[ch] for rd in data_d]))
                   for ch in data_d[0].measured}

        def parts_of(model) -> dict[str, list[np.ndarray]]:
            parts: dict[str, list[np.ndarray]] = {ch: [] for ch in weights}
            for rd in data_d:
                ctx = _drift_context(model, rd, start_c.get(rd.run.name)) if resim else rd.ctx
                for ch, y in _drift_models(model, rd, ctx).items():
                    parts[ch].append(y - rd.measured[ch])
            return parts

        def fun(x):
            parts = parts_of(set_params(base, dict(zip(sp, x))))
            return np.concatenate([a / weights[ch] for ch, arrs in parts.items() for a in arrs])

        rms_before.update(_rms(parts_of(base)))
        if "acc_x_g" in weights:
            start.update(_level_start(base, data_d, sp, weights))
        current = stage("drift", fun, base, sp)
        rms_after.update(_rms(parts_of(current)))
        if fit_noise:
            noise = _noise_of(current, data_d)
            current = set_params(current, {f"gyro.{k}": getattr(noise, k) for k in _NOISE_FIELDS})

    params = {p: get_param(current, p) for p in paths}
    for s, rep in stage_reports.items():
        if not rep.converged:
            warnings.append(f"{s} stage did not converge ({rep.nfev} evaluations): {rep.message}")
    advice = {p: bound_advice(p, params[p], bounds[p]) for p in at_bound}
    for p in at_bound:
        warnings.append(f"{p} ended at its bound {bounds[p]} (value {params[p]:.6g}): "
                        f"{advice[p]}")
    shifts = {} if pr is None else pr.shift([params[q] for q in pr.paths])
    for p in paths:
        if p not in at_bound and p not in unident:
            far = far_from_start(initial_params[p], params[p], shifts.get(p),
                                 by_ratio=_has_scale(p, kinds[p]))
            if far:
                warnings.append(f"{p} moved {far}: the runs push it far from the model's "
                                "value, where it may stand in for an effect the model lacks "
                                "(nfs diagnose)")
    if soak is not None:
        warnings.extend(soak.warnings)
    if chamber_assumption(runs):
        warnings.append(chamber_assumption(runs))
    for p, why in unident.items():
        warnings.append(f"{p} is not identifiable: {why}")
    if len(runs) == 1:
        t0 = runs[0].meta.start_temperature_c
        warnings.append(f"a single run (T0 = {t0:g} C): parameters whose effect depends on "
                        "the start temperature cannot be separated; "
                        + (", ".join(unident) if unident else "none flagged by the Jacobian")
                        + " reported as not identifiable")
    current = replace(current, name=fitted_name(inst.name, runs))
    return FitResult(instrument=current, initial=inst, params=params,
                     initial_params=initial_params, stderr=stderr, bounds=bounds,
                     at_bound=tuple(at_bound), unidentifiable=unident, stages=stage_reports,
                     rms_before=rms_before, rms_after=rms_after, warnings=tuple(warnings),
                     prior_centre={} if pr is None else dict(zip(pr.paths, pr.centre.tolist())),
                     prior_sigma={} if pr is None else dict(zip(pr.paths, pr.sigma.tolist())),
                     prior_shift=shifts,
                     bound_advice=advice, soak=soak, noise=noise, start_c=start_c,
                     start_amplitudes_c=amplitudes)


def write_fitted_model(result: FitResult, path: str | Path) -> Path:
    """Write the fitted instrument as a TOML file a user can read and edit.

    A header comment lists every fitted parameter with its standard error and start value,
    the parameters at a bound or not identifiable, and each stage's convergence.  Written
    atomically (:func:`nfs.io.atomic.atomic_write_text`).
    """
    path = Path(path)
    lines = [f"# Instrument fitted by nfs.diagnose.fit_model from '{result.initial.name}'.",
             "# Fitted parameters (value +- standard error; start value):"]
    for p, v in result.params.items():
        flags = []
        if p in result.at_bound:
            flags.append("AT BOUND")
        if p in result.unidentifiable:
            flags.append("NOT IDENTIFIABLE")
        flag = f"  [{', '.join(flags)}]" if flags else ""
        shift = result.prior_shift.get(p, math.nan)
        moved = f", {shift:+.2f} prior widths" if math.isfinite(shift) else ""
        lines.append(f"#   {p} = {v:.6g} +- {result.stderr.get(p, math.nan):.3g}"
                     f"; start {result.initial_params[p]:.6g}{moved}{flag}")
    if result.noise is not None:
        n = result.noise
        lines.append(f"# gyro noise from the Allan deviation of the drift residual at rest: "
                     f"arw {n.arw_deg_per_rth_h:.3g}, bias instability "
                     f"{n.bias_instability_dph:.3g}, rrw {n.rrw_deg_per_h_per_rth_h:.3g}")
    for s, rep in result.stages.items():
        lines.append(f"# {s} stage: {'converged' if rep.converged else 'NOT CONVERGED'} "
                     f"after {rep.nfev} evaluations, cost {rep.cost:.6g} on "
                     f"{rep.n_residuals} residuals")
    for ch, v in result.rms_after.items():
        lines.append(f"# residual RMS {ch}: {result.rms_before.get(ch, math.nan):.4g} -> {v:.4g}")
    if result.structure is not None:
        lines += [f"# {line}" for line in result.structure.summary().splitlines()]
    for w in result.warnings:
        lines.append(f"# warning: {w}")
    atomic_write_text(path, "\n".join(lines) + "\n" + result.instrument.to_toml())
    return path
