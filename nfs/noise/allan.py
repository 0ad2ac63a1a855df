"""Overlapping Allan deviation of rate data and the fit of the gyro's noise coefficients.

Rate data y [unit] sampled at fs [Hz] become "phase" (integrated rate) x[0] = 0,
x[i] = sum_{j<i} y[j] / fs, and the overlapping Allan variance at tau = m / fs is
(NIST SP 1065, Riley 2008, eq. (11); IEEE Std 952-2020 Annex C)::

    sigma^2(tau) = 1 / (2 tau^2 (N - 2m + 1)) sum_{i=0}^{N-2m} (x[i+2m] - 2 x[i+m] + x[i])^2

with N rate samples (N + 1 phase points, so N - 2m + 1 second differences, the
``n_clusters``).  It equals the mean over every start i of half the squared difference of
two adjacent m-sample averages of y.  One cumulative sum serves every tau: O(N) per tau.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from nfs.docfields import document_fields
from nfs.errors import InputError
from nfs.noise.generators import BI_FLOOR_FACTOR

__all__ = [
    "AllanResult",
    "NoiseFit",
    "allan_deviation",
    "allan_relative_error",
    "fit_noise_coefficients",
    "octave_taus_s",
]


@document_fields
@dataclass(frozen=True)
class AllanResult:
    """Overlapping Allan deviation of one record (:func:`allan_deviation`)."""

    taus_s: np.ndarray
    """Averaging times tau = m / fs [s], as computed (m rounded to an integer)."""
    adev: np.ndarray
    """Overlapping Allan deviation sigma(tau) [unit of the data, e.g. deg/h]."""
    n_clusters: np.ndarray
    """Number of overlapping second differences averaged at each tau, N - 2m + 1 [-]."""
    adev_rel_err: np.ndarray
    """Approximate 1-sigma relative error of ``adev`` [-], 1 / sqrt(2 (N/m - 1))
    (:func:`allan_relative_error`)."""


def allan_relative_error(n_samples: int, m: np.ndarray | int) -> np.ndarray:
    """Approximate 1-sigma relative error [-] of an Allan deviation estimated from
    ``n_samples`` samples at m samples per cluster: 1 / sqrt(2 (N/m - 1)).

    The "percentage error" of IEEE Std 952-2020 Annex C and El-Sheimy, Hou & Niu 2008
    (IEEE TIM 57(1)), written for non-overlapping clusters of white noise.  For white rate
    noise the overlapping estimator does better than this; for flicker and random-walk
    noise its true error depends on the noise type (equivalent degrees of freedom, Riley
    2008) and can be larger, so treat it as a weight, not a confidence interval.  Not yet
    checked against the texts down to equation number.
    """
    m_arr = np.asarray(m, dtype=float)
    ratio = n_samples / m_arr - 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        err = 1.0 / np.sqrt(2.0 * ratio)
    return np.where(ratio > 0.0, err, np.inf)


def octave_taus_s(n_samples: int, sample_rate_hz: float) -> np.ndarray:
    """Octave-spaced averaging times [s]: m = 1, 2, 4, ... while m <= N/2, tau = m / fs."""
    if n_samples < 2:
        raise InputError(f"an Allan deviation needs at least 2 samples, got {n_samples}")
    m_max = n_samples // 2
    m = 2 ** np.arange(int(math.floor(math.log2(m_max))) + 1)
    return m / float(sample_rate_hz)


def allan_deviation(x: np.ndarray, sample_rate_hz: float,
                    taus: np.ndarray | None = None) -> AllanResult:
    """Overlapping Allan deviation of rate data (NIST SP 1065, Riley 2008, eq. (11)).

    Parameters
    ----------
    x : array_like
        Rate samples y [unit, e.g. deg/h], 1-D, finite, at least 2, evenly spaced.
    sample_rate_hz : float
        Sample rate fs [Hz].
    taus : array_like, optional
        Averaging times [s].  Each is rounded to m = round(tau fs) samples, which must lie in
        1 <= m <= N/2 (an :class:`~nfs.errors.InputError` names the first that does not); the
        result keeps their order and the rounded values.  Default: :func:`octave_taus_s`,
        from 1/fs up to about N/(2 fs).

    Returns
    -------
    AllanResult
        ``taus_s`` [s], ``adev`` [unit], ``n_clusters`` = N - 2m + 1 and ``adev_rel_err``.

    Notes
    -----
    The mean is removed before the cumulative sum (the Allan variance ignores a constant
    rate), which keeps the second differences free of round-off on long records with a large
    mean rate such as the Earth rate.
    """
    y = np.asarray(x, dtype=float)
    if y.ndim != 1:
        raise InputError(f"x must be 1-D rate data, got shape {y.shape}")
    n = y.size
    if n < 2:
        raise InputError(f"an Allan deviation needs at least 2 samples, got {n}")
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise InputError(f"x holds a non-finite value at index {bad[0]}")
    fs = float(sample_rate_hz)
    if not math.isfinite(fs) or fs <= 0.0:
        raise InputError(f"sample_rate_hz must be finite and > 0, got {sample_rate_hz!r}")

    if taus is None:
        taus_req = octave_taus_s(n, fs)
    else:
        taus_req = np.atleast_1d(np.asarray(taus, dtype=float))
        if taus_req.ndim != 1:
            raise InputError(f"taus must be 1-D, got shape {taus_req.shape}")
    m_all = np.rint(taus_req * fs)
    for i, (tau, m) in enumerate(zip(taus_req, m_all)):
        if not math.isfinite(tau) or m < 1 or m > n // 2:
            raise InputError(
                f"taus[{i}] = {tau!r} s is {m:g} samples at {fs:g} Hz; it must be between "
                f"1 and N/2 = {n // 2} samples ({1 / fs:g} s to {(n // 2) / fs:g} s)")
    m_all = m_all.astype(np.int64)

    phase = np.empty(n + 1)
    phase[0] = 0.0
    np.cumsum((y - y.mean()) / fs, out=phase[1:])

    adev = np.empty(m_all.size)
    n_clusters = n - 2 * m_all + 1
    for i, m in enumerate(m_all):
        d2 = phase[2 * m:] - 2.0 * phase[m:n + 1 - m] + phase[:n + 1 - 2 * m]
        tau = m / fs
        adev[i] = math.sqrt(np.dot(d2, d2) / (2.0 * tau * tau * d2.size))
    return AllanResult(taus_s=m_all / fs, adev=adev, n_clusters=n_clusters,
                       adev_rel_err=allan_relative_error(n, m_all))


# --------------------------------------------------------------------------------------------
# fit of N, B, K

@dataclass(frozen=True)
class NoiseFit:
    """Gyro noise coefficients read from an Allan deviation of rate data in [deg/h]
    (:func:`fit_noise_coefficients`).

    The first three come from the weighted non-negative least-squares fit of
    sigma^2(tau) = (60 N)^2 / tau + (0.6643 B)^2 + (K/60)^2 tau / 3 (tau [s]) over all the
    points; the ``*_slope_*`` and ``*_floor_*`` fields are the classic graphical readings
    (IEEE Std 952-2020 Annex C; El-Sheimy et al. 2008), NaN where the curve shows no such
    region.
    """

    arw_deg_per_rth_h: float
    """Angle random walk N [deg/sqrt(h)] from the fit."""
    bias_instability_dph: float
    """Bias instability B [deg/h] from the fit (flat term / 0.6643)."""
    rrw_deg_per_h_per_rth_h: float
    """Rate random walk K [deg/h/sqrt(h)] from the fit."""
    arw_slope_deg_per_rth_h: float
    """Classic ARW reading [deg/sqrt(h)]: the -1/2 line through the point whose local log-log
    slope is closest to -1/2, read at tau = 1 h."""
    arw_slope_tau_s: float
    """tau [s] of the point that line goes through."""
    bias_instability_floor_dph: float
    """Classic BI reading [deg/h]: the minimum of the Allan deviation / 0.6643, over the
    points whose relative error is at most ``SLOPE_MAX_REL_ERR`` when errors are given (an
    upper bound of B when ARW or RRW still contribute at the minimum; too low when the curve
    falls again beyond the bias instability's correlation times and no RRW lifts it)."""
    bias_instability_floor_tau_s: float
    """tau [s] of that minimum."""
    rrw_slope_deg_per_h_per_rth_h: float
    """Classic RRW reading [deg/h/sqrt(h)]: the +1/2 line through the point whose local slope
    is closest to +1/2, read at tau = 3 h."""
    rrw_slope_tau_s: float
    """tau [s] of the point that line goes through."""

    def adev_model_dph(self, taus_s: np.ndarray) -> np.ndarray:
        """The fitted Allan deviation [deg/h] at ``taus_s`` [s] (the three fitted terms)."""
        tau = np.asarray(taus_s, dtype=float)
        return np.sqrt((60.0 * self.arw_deg_per_rth_h) ** 2 / tau
                       + (BI_FLOOR_FACTOR * self.bias_instability_dph) ** 2
                       + (self.rrw_deg_per_h_per_rth_h / 60.0) ** 2 * tau / 3.0)


#: A classic slope reading uses only points whose local log-log slope is within this
#: distance of the target slope (-1/2 or +1/2), else it is NaN.
SLOPE_TOLERANCE: float = 0.25

#: A classic reading (slopes and the floor's minimum) uses only points whose relative error
#: is at most this, when the errors are given.
SLOPE_MAX_REL_ERR: float = 0.25


def _slope_reading(taus_s: np.ndarray, adev: np.ndarray, slopes: np.ndarray,
                   usable: np.ndarray, target: float) -> tuple[float, float]:
    """(sigma extrapolated along the target slope to tau = 1 s, tau of the point used)."""
    candidates = np.flatnonzero(usable & (np.abs(slopes - target) <= SLOPE_TOLERANCE))
    if candidates.size == 0:
        return math.nan, math.nan
    i = candidates[np.argmin(np.abs(slopes[candidates] - target))]
    return float(adev[i] * taus_s[i] ** (-target)), float(taus_s[i])


def fit_noise_coefficients(taus_s: np.ndarray, adev: np.ndarray, *,
                           adev_rel_err: np.ndarray | None = None,
                           n_iterations: int = 3) -> NoiseFit:
    """Fit the angle random walk N, bias instability B and rate random walk K to an Allan
    deviation of rate data [deg/h] (IEEE Std 952-2020 Annex C; El-Sheimy et al. 2008).

    Weighted fit: the independent terms' Allan variances add, so with tau [s]

        sigma^2(tau) = a / tau + b + c tau / 3,   a = (60 N)^2, b = (0.6643 B)^2, c = (K/60)^2

    is linear in (a, b, c) >= 0, solved by :func:`scipy.optimize.nnls`.  The standard
    deviation of an estimated sigma^2 is about 2 e sigma^2 (e the relative error of sigma),
    so each row is weighted by 1 / (2 e sigma^2); the first pass uses the measured sigma^2,
    the next ``n_iterations - 1`` the fitted one (iteratively reweighted, which removes the
    bias towards low points).  Units: N = sqrt(a) / 60 [deg/sqrt(h)] (1 sqrt(h) = 60 sqrt(s)),
    B = sqrt(b) / 0.6643 [deg/h], K = 60 sqrt(c) [deg/h/sqrt(h)].  The flat term reads B
    correctly only where the flicker floor is flat; a real or simulated bias instability
    bends down outside its band (:func:`~nfs.noise.generators.bias_instability_band_s`).

    Also returns the classic slope readings (see :class:`NoiseFit`): ARW is the -1/2 line read
    at tau = 1 h, RRW the +1/2 line read at tau = 3 h, BI the minimum over 0.6643.

    Parameters
    ----------
    taus_s : array_like
        Averaging times tau [s], > 0, increasing.
    adev : array_like
        Allan deviation of rate data [deg/h], same length; non-finite or non-positive points
        are left out.
    adev_rel_err : array_like, optional
        Relative 1-sigma error of each ``adev`` [-] (``AllanResult.adev_rel_err``).  Default:
        equal relative errors, which overweights the long, poorly-known taus.
    n_iterations : int
        Number of weighted passes, >= 1.

    Returns
    -------
    NoiseFit
    """
    tau = np.asarray(taus_s, dtype=float)
    sig = np.asarray(adev, dtype=float)
    if tau.ndim != 1 or tau.shape != sig.shape:
        raise InputError(f"taus_s and adev must be 1-D of one length, got shapes {tau.shape} "
                         f"and {sig.shape}")
    rel = np.ones_like(sig) if adev_rel_err is None else np.asarray(adev_rel_err, dtype=float)
    if rel.shape != sig.shape:
        raise InputError(f"adev_rel_err must have the shape of adev {sig.shape}, "
                         f"got {rel.shape}")
    if n_iterations < 1:
        raise InputError(f"n_iterations must be >= 1, got {n_iterations}")
    ok = (np.isfinite(tau) & (tau > 0) & np.isfinite(sig) & (sig > 0)
          & np.isfinite(rel) & (rel > 0))
    if np.count_nonzero(ok) < 3:
        raise InputError(f"fit_noise_coefficients needs at least 3 usable points "
                         f"(finite, tau > 0, adev > 0), got {np.count_nonzero(ok)}")
    order = np.argsort(tau[ok])
    tau, sig, rel = tau[ok][order], sig[ok][order], rel[ok][order]
    avar = sig * sig

    design = np.column_stack([1.0 / tau, np.ones_like(tau), tau / 3.0])
    weight_var = avar
    for _ in range(n_iterations):
        w = 1.0 / (2.0 * rel * weight_var)
        a_w = design * w[:, None]
        scale = np.linalg.norm(a_w, axis=0)          # column scaling: conditioning only
        coef_scaled, _ = nnls(a_w / scale, avar * w)
        coef = coef_scaled / scale
        model = design @ coef
        weight_var = np.where(model > 0.0, model, avar)
    a, b, c = coef

    # classic readings on the log-log curve
    log_tau, log_sig = np.log(tau), np.log(sig)
    slopes = np.gradient(log_sig, log_tau) if tau.size > 1 else np.zeros(1)
    usable = rel <= SLOPE_MAX_REL_ERR if adev_rel_err is not None else np.ones_like(tau, bool)
    arw_at_1s, arw_tau = _slope_reading(tau, sig, slopes, usable, -0.5)
    rrw_at_1s, rrw_tau = _slope_reading(tau, sig, slopes, usable, +0.5)
    usable_idx = np.flatnonzero(usable)
    i_min = int(usable_idx[np.argmin(sig[usable_idx])]) if usable_idx.size else int(np.argmin(sig))
    return NoiseFit(
        arw_deg_per_rth_h=math.sqrt(a) / 60.0,
        bias_instability_dph=math.sqrt(b) / BI_FLOOR_FACTOR,
        rrw_deg_per_h_per_rth_h=60.0 * math.sqrt(c),
        # -1/2 line: sigma(tau) = sigma_1 / sqrt(tau_s) -> N = sigma(1 h) * sqrt(1 h) = sigma_1/60
        arw_slope_deg_per_rth_h=arw_at_1s / 60.0,
        arw_slope_tau_s=arw_tau,
        bias_instability_floor_dph=float(sig[i_min]) / BI_FLOOR_FACTOR,
        bias_instability_floor_tau_s=float(tau[i_min]),
        # +1/2 line: sigma(tau) = s1 sqrt(tau_s); K = sigma(3 h) = s1 sqrt(10800 s) = 60 sqrt(3) s1
        rrw_slope_deg_per_h_per_rth_h=rrw_at_1s * 60.0 * math.sqrt(3.0),
        rrw_slope_tau_s=rrw_tau,
    )
