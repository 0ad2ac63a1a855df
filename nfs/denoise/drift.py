"""The FOG drift of a run: output minus Earth-rate projection, wavelet-denoised (docs/physics.md 6).

    raw_drift = gyro - Omega_ie [cos L cos A cos e + sin L sin e]       [deg/h]
    A = true_heading + theta (turntable angle),   sin e = f_x (x accelerometer)
    drift = wavelet_denoise(raw_drift with the turntable moves bridged)

This drift is the training target of the compensators (the FOG start-up paper: "the wavelet
transformation
is used to eliminate the non-temperature noise and extract the temperature drift signal").

What the drift holds besides the gyro's thermal drift: the constant bias b, the low-frequency
part of the gyro noise (bias instability, which no denoiser can tell from drift), and
-Omega_ie sin L (f_x - sin e_true), the accelerometer bias seen through the elevation. The last
is what the north finder sees as well, since it tilt-corrects with the same f_x
(:func:`nfs.northfind.solve.tilt_correct`), so the drift defined with f_x is the one a
compensator must remove.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from nfs.errors import InputError, MeasurementError
from nfs.run import Run
from nfs.sensors.fog import earth_rate_along_axis_dph

from .levels import DEFAULT_WAVELET
from .thresholds import ThresholdRule
from .wavelet import DenoiseResult, wavelet_denoise

__all__ = [
    "DEFAULT_CUTOFF_PERIOD_S",
    "TIME_STEP_RTOL",
    "DriftSeparation",
    "earth_rate_projection_dph",
    "separate_drift",
    "bridge_gaps",
]

#: Default cutoff of the drift [s]: at 1 Hz level 8 of the DWT, periods above 512 s = 8.5 min
#: are kept whole (the thermal drift), shorter ones only where they stand out of the noise.
DEFAULT_CUTOFF_PERIOD_S = 512.0

#: Largest relative deviation of a time step from the median step: the wavelet transform
#: needs a uniform grid.
TIME_STEP_RTOL = 0.01


def earth_rate_projection_dph(run: Run, *, scale_factor: float = 1.0) -> np.ndarray:
    """The Earth rate along the FOG axis at every sample of a run [deg/h].

        K Omega_ie (cos L cos A cos e + sin L sin e)     (docs/physics.md section 5)

    with A = true_heading_deg + position_deg (the axis azimuth, clockwise from north),
    e = arcsin(acc_x_g) (the axis elevation sensed by the x accelerometer, docs/physics.md
    section 4), L = latitude_deg, K the scale factor. The projection itself is
    :func:`nfs.sensors.fog.earth_rate_along_axis_dph`.

    Parameters
    ----------
    run : Run
        A run with ``true_heading_deg`` in its metadata.
    scale_factor : float
        K, the gyro's scale factor (1: the output is calibrated in deg/h).

    Returns
    -------
    numpy.ndarray
        [deg/h], NaN where ``acc_x_g`` is missing.

    Raises
    ------
    MeasurementError
        The run has no ``true_heading_deg`` (the drift is then unknown), or ``|acc_x_g|`` > 1 g.
    """
    heading = run.meta.true_heading_deg
    if heading is None:
        raise MeasurementError(
            f"run '{run.name}' has no true_heading_deg: the Earth-rate projection, and so the "
            "drift, is unknown without the true heading", file=run.path, key="true_heading_deg")
    acc_x = np.asarray(run["acc_x_g"], dtype=float)
    with np.errstate(invalid="ignore"):
        too_big = np.abs(acc_x) > 1.0
    if np.any(too_big):
        k = int(np.flatnonzero(too_big)[0])
        raise MeasurementError(
            f"run '{run.name}': |acc_x_g| = {abs(acc_x[k]):.6g} g > 1 g at sample {k} gives no "
            "axis elevation", file=run.path, column="acc_x_g")
    azimuth_deg = heading + np.asarray(run["position_deg"], dtype=float)
    elevation_deg = np.degrees(np.arcsin(acc_x))
    return float(scale_factor) * earth_rate_along_axis_dph(azimuth_deg, elevation_deg,
                                                           run.meta.latitude_deg)


def bridge_gaps(time_s: np.ndarray, values: np.ndarray, untrusted: np.ndarray) -> np.ndarray:
    """``values`` with the untrusted samples replaced by linear interpolation in time.

        y(t) = y(t_a) + (y(t_b) - y(t_a)) (t - t_a) / (t_b - t_a)

    between the trusted samples t_a, t_b either side of each gap; before the first and after
    the last trusted sample the nearest trusted value is held (``numpy.interp``).
    """
    out = np.array(values, dtype=float)
    bad = np.asarray(untrusted, dtype=bool)
    if bad.any():
        good = ~bad
        out[bad] = np.interp(time_s[bad], time_s[good], out[good])
    return out


@dataclass(frozen=True)
class DriftSeparation:
    """Result of :func:`separate_drift`: every stage from the gyro output to the drift."""

    run_name: str
    """Name of the run."""
    time_s: np.ndarray
    """Sample times [s]."""
    projection_dph: np.ndarray
    """The Earth-rate projection along the axis, :func:`earth_rate_projection_dph` [deg/h]."""
    raw_drift_dph: np.ndarray
    """gyro_dph - projection_dph, as measured (NaN where either is missing) [deg/h]."""
    filled_drift_dph: np.ndarray
    """raw_drift_dph with the untrusted samples bridged by linear interpolation: the record
    that was denoised [deg/h]."""
    drift_dph: np.ndarray
    """The denoised drift, the compensators' training target [deg/h]."""
    noise_dph: np.ndarray
    """filled_drift_dph - drift_dph, the non-thermal noise removed [deg/h]; at untrusted
    samples it is the residual of the bridging line, not a measurement."""
    moving: np.ndarray
    """True where the turntable moves (``moving`` == 1)."""
    interpolated: np.ndarray
    """True where raw_drift_dph was replaced: the moves and the missing samples."""
    denoise: DenoiseResult
    """The wavelet denoising of filled_drift_dph (level, thresholds, sigma, edge_s, ...)."""


def _sample_rate_hz(run: Run) -> float:
    t = np.asarray(run["time_s"], dtype=float)
    if t.size < 2:
        raise InputError(f"run '{run.name}' has {t.size} sample(s); the drift needs a record")
    dt = np.diff(t)
    step = float(np.median(dt))
    if not step > 0:
        raise InputError(f"run '{run.name}': time_s does not increase")
    dev = np.abs(dt - step) > TIME_STEP_RTOL * step
    if dev.any():
        k = int(np.flatnonzero(dev)[0])
        raise InputError(
            f"run '{run.name}': time step {dt[k]:.6g} s at t = {t[k]:.6g} s differs from the "
            f"median step {step:.6g} s; the wavelet transform needs uniform sampling "
            "(resample the run or fill the gap with NaN rows)")
    return 1.0 / step


def separate_drift(run: Run, *, cutoff_period_s: float | None = DEFAULT_CUTOFF_PERIOD_S,
                   level: int | None = None, wavelet: str = DEFAULT_WAVELET,
                   rule: str | ThresholdRule = "visu", mode: str = "soft",
                   boundary: str = "smooth-extend", sigma_per_level: bool = False,
                   scale_factor: float = 1.0,
                   thresholds: Sequence[float] | None = None) -> DriftSeparation:
    """The thermal drift of a run: output minus Earth rate, moves bridged, wavelet-denoised.

        raw = gyro_dph - earth_rate_projection_dph(run)                      [deg/h]
        filled = raw, with moving == 1 and missing samples bridged linearly in time
        drift = wavelet_denoise(filled, level from cutoff_period_s, ...).signal

    (docs/physics.md section 6; the FOG start-up paper section on WT preprocessing). Samples taken
    while the
    turntable moves are not trusted (a real gyro senses the table's own rotation then), nor
    are missing ones; both are replaced by the line between their trusted neighbours before
    the transform, and ``interpolated`` says where.

    Parameters
    ----------
    run : Run
        A run with ``true_heading_deg``, uniformly sampled.
    cutoff_period_s : float or None
        Shortest period kept whole [s]; default 512 s (level 8 at 1 Hz). Ignored when
        ``level`` is given.
    level : int, optional
        The DWT level J directly.
    wavelet, rule, mode, boundary, sigma_per_level
        As :func:`nfs.denoise.wavelet.wavelet_denoise`.
    scale_factor : float
        K of the Earth-rate projection (:func:`earth_rate_projection_dph`).
    thresholds : sequence of float, optional
        The thresholds of another separation (``other.denoise.thresholds``) instead of the
        rule's: a noise-free model's drift shrunk as the measured one was
        (:func:`nfs.denoise.wavelet.wavelet_denoise`).

    Returns
    -------
    DriftSeparation

    Raises
    ------
    MeasurementError
        No ``true_heading_deg`` (the message names the run), ``|acc_x_g|`` > 1 g.
    InputError
        Non-uniform time steps, no trusted sample, bad denoising options.
    """
    projection = earth_rate_projection_dph(run, scale_factor=scale_factor)
    fs = _sample_rate_hz(run)
    t = np.asarray(run["time_s"], dtype=float)
    raw = np.asarray(run["gyro_dph"], dtype=float) - projection
    moving = np.asarray(run["moving"], dtype=float) != 0.0
    untrusted = moving | ~np.isfinite(raw)
    if untrusted.all():
        raise InputError(f"run '{run.name}' has no sample with the turntable at rest and both "
                         "gyro_dph and acc_x_g present; no drift to separate")
    filled = bridge_gaps(t, raw, untrusted)
    result = wavelet_denoise(
        filled, sample_rate_hz=fs, cutoff_period_s=None if level is not None else
        cutoff_period_s, level=level, wavelet=wavelet, rule=rule, mode=mode,
        boundary=boundary, sigma_per_level=sigma_per_level, trusted=~untrusted,
        thresholds=thresholds)
    return DriftSeparation(
        run_name=run.name, time_s=t, projection_dph=projection, raw_drift_dph=raw,
        filled_drift_dph=filled, drift_dph=result.signal, noise_dph=result.noise,
        moving=moving, interpolated=untrusted, denoise=result)
