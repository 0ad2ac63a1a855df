"""The drift stage's residual: a run's window means at rest and the model's drift on them.

:func:`prepare_drift` reduces a measured run to means over windows of ``decimate_s`` of its
samples at rest (moving samples excluded; :class:`DriftRun`), for the channels

- ``drift_dph``: the measured raw drift ``gyro_dph - Earth projection``
  (:func:`nfs.denoise.earth_rate_projection_dph`, the drift that
  :func:`nfs.denoise.separate_drift` denoises).  Window means are linear, so they do not
  bias fast terms (the turn-on transient) the way the denoiser's shrinkage can;
  ``drift_signal="denoised"`` uses ``separate_drift(run).drift_dph`` instead;
- ``acc_x_g``, ``acc_y_g``: the accelerometers' specific force [g], when asked for.

Each channel carries the standard error of its window means (within-window scatter /
sqrt(count), median over windows), by which a fit divides it so that the units mix on a
common scale.

:func:`drift_context` replays the model's thermal network on the run's own time base (as the
simulator does, started at given node temperatures) and gives the
:func:`nfs.experiment.effect_context` the effects are evaluated on.  On it, the model drift
(:func:`model_drift_dph`) is

    d = b + sum_j g_j + (K - 1) P - Omega_ie sin L (b_x + sum_j a_j)                 [deg/h]

with b the gyro bias, g_j the gyro effect terms, K the scale factor, P the Earth-rate
projection, L the latitude, b_x the x accelerometer's bias and a_j its effect terms: the
last term is the x accelerometer's error seen through the elevation in the projection
(nfs/denoise/drift.py).  The accelerometer channels of the model are sin(e) + bias +
accelerometer effects, e the axis elevation on the tilted turntable
(:func:`nfs.sensors.axis_elevation_deg`).  :func:`drift_channels` gives their window means,
:func:`window_means` those of any full-rate signal on the run's windows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

import thermal

from ..constants import OMEGA_IE_DPH
from ..denoise import earth_rate_projection_dph, separate_drift
from ..errors import InputError, NfsError
from ..conditions import conditions_from_run
from ..experiment import effect_context
from ..heat import thermal_power
from ..instrument import Instrument
from ..run import Run
from ..sensors import axis_elevation_deg
from .thermal_residual import decimation_step, require_columns

__all__ = ["DriftRun", "prepare_drift", "drift_context", "drift_context_on", "window_means",
           "sensor_errors", "model_drift_dph", "drift_channels"]


@dataclass
class DriftRun:
    """A run prepared for the drift stage: its windows at rest and their measured means."""

    run: Run
    """The measured run."""
    cond: Any
    """Its conditions (:func:`nfs.experiment.conditions_from_run`)."""
    k: int
    """Samples per window."""
    windows: np.ndarray
    """Window index of every trusted sample."""
    trusted: np.ndarray
    """Samples at rest with every channel finite (bool, full rate)."""
    keep: np.ndarray
    """Windows with at least half their samples trusted (bool, per window)."""
    counts: np.ndarray
    """Trusted samples of each window."""
    projection: np.ndarray
    """Earth-rate projection at full rate [deg/h]."""
    measured: dict[str, np.ndarray]
    """Window means of the measured channels (``drift_dph`` [deg/h], ``acc_x_g``,
    ``acc_y_g`` [g]), kept windows only."""
    scale: dict[str, float]
    """Standard error of a window mean, per channel [channel unit]."""
    azimuth: np.ndarray
    """Azimuth of the x axis at full rate [deg]."""
    aux: dict[str, np.ndarray]
    """The run's ``aux_*`` columns."""
    ctx: Any = None
    """The effect context the drift stage evaluates the model on (set by the fit)."""


def prepare_drift(run: Run, decimate_s: float, acc_channels: bool,
                  drift_signal: str) -> DriftRun:
    """``run`` as window means of ``decimate_s`` at rest (module docstring); the
    accelerometer channels too when ``acc_channels``.

    Raises
    ------
    InputError
        A column the drift stage needs is missing, the run has no true heading or no sample
        at rest.
    NfsError
        ``drift_signal`` is not ``"raw"`` or ``"denoised"``.
    """
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
    # at rest, with every channel logged (a missing gyro sample stays out of its window
    # even where the denoised drift bridges it)
    trusted = (np.asarray(run["moving"], dtype=float) == 0.0) & np.isfinite(
        np.asarray(run["gyro_dph"], dtype=float))
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
    return DriftRun(run=run, cond=cond, k=k, windows=w, trusted=trusted, keep=keep,
                    counts=counts, projection=proj, measured=measured, scale=scale,
                    azimuth=azimuth, aux=aux)


def drift_context(inst: Instrument, rd: DriftRun, start_c: np.ndarray | None = None):
    """The effect context of ``inst`` replayed on the run, started at ``start_c`` (node
    temperatures at power-on [degC]; None: T0 everywhere)."""
    cond = rd.cond
    t = cond.time_s
    _, moving = cond.turntable(t)
    powered = cond.powered(t)
    power, _, _ = thermal_power(inst, t, moving, powered)
    ambient = cond.start_temperature_c if cond.chamber_c is None else cond.chamber_c(t)
    th = thermal.simulate(inst.network, t, ambient_c=ambient,
                          initial_c=cond.start_temperature_c if start_c is None else start_c,
                          power_w=power,
                          ambient_hold="first-order")   # the recorded chamber, interpolated
    return effect_context(inst, th, rd.azimuth, rd.projection, moving, rd.aux, powered)


def drift_context_on(inst: Instrument, rd: DriftRun, temperatures: Any):
    """The effect context of a prepared run on given node temperatures ``temperatures`` (a
    :class:`thermal.ThermalResult` or :class:`nfs.diagnose.smoother.SmoothedThermal` on the
    run's own time base) instead of the model's open-loop solution."""
    t = rd.cond.time_s
    if np.shape(temperatures.time_s) != t.shape:
        raise NfsError(f"run '{rd.run.name}': node temperatures on "
                       f"{np.size(temperatures.time_s)} samples for a run of {t.size}")
    _, moving = rd.cond.turntable(t)
    return effect_context(inst, temperatures, rd.azimuth, rd.projection, moving, rd.aux,
                          rd.cond.powered(t))


def window_means(rd: DriftRun, x: np.ndarray) -> np.ndarray:
    """Means of the full-rate signal ``x`` over the run's kept windows, trusted samples
    only [unit of x]."""
    n_w = rd.counts.size
    return (np.bincount(rd.windows, weights=x[rd.trusted], minlength=n_w)[rd.keep]
            / rd.counts[rd.keep])


def sensor_errors(inst: Instrument, ctx) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Full-rate model gyro error (bias + effects + (K - 1) projection) [deg/h] and
    accelerometer errors (bias + effects) per axis [g], on the samples of ``ctx``."""
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


def _drift_of(gyro_dph: np.ndarray, acc_x_g: np.ndarray, latitude_deg: float) -> np.ndarray:
    """d = gyro error - Omega_ie sin L (x accelerometer error) [deg/h] (module docstring)."""
    return gyro_dph - OMEGA_IE_DPH * math.sin(math.radians(latitude_deg)) * acc_x_g


def model_drift_dph(inst: Instrument, ctx, latitude_deg: float) -> np.ndarray:
    """The model drift the drift stage fits, at every sample of ``ctx`` [deg/h].

    b + sum of the gyro effect terms + (K - 1) projection - Omega_ie sin L (b_x + x
    accelerometer terms), evaluated on an :class:`~nfs.effects.EffectContext` whose
    ``earth_rate_dph`` is the run's Earth-rate projection (module docstring).
    Subtracting it from ``gyro_dph`` gives the model-compensated rate.
    """
    gyro, acc = sensor_errors(inst, ctx)
    return _drift_of(gyro, acc["x"], latitude_deg)


def drift_channels(inst: Instrument, rd: DriftRun, ctx) -> dict[str, np.ndarray]:
    """Window means of the model's drift [deg/h] and, when the run was prepared with them,
    accelerometer channels [g] (module docstring)."""
    gyro, acc = sensor_errors(inst, ctx)
    out = {"drift_dph": window_means(rd, _drift_of(gyro, acc["x"], rd.cond.latitude_deg))}
    if "acc_x_g" in rd.measured:
        tt = inst.turntable
        for axis, offset in (("x", 0.0), ("y", 90.0)):
            elev = axis_elevation_deg(rd.azimuth + offset, tt.tilt_north_deg, tt.tilt_east_deg)
            out[f"acc_{axis}_g"] = window_means(rd, np.sin(np.radians(elev)) + acc[axis])
    return out
