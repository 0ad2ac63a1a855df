"""Wavelet denoising: separate a slow drift from white noise (docs/physics.md section 6, the FOG
start-up paper).

The record is decomposed with the discrete wavelet transform (DWT, PyWavelets ``wavedec``) to
a level J, the detail coefficients of every level 1..J are shrunk toward zero with a threshold
(soft thresholding, Donoho 1995), the approximation is kept, and the record is rebuilt
(``waverec``)::

    x = s + n                      record = drift + noise
    x -> (a_J, d_J, ..., d_1)      DWT to level J
    d_j -> eta_T(d_j)              eta_T(d) = sign(d) max(|d| - T_j, 0)   (soft)
    s_hat = IDWT(a_J, eta(d_J), ..., eta(d_1)),   noise = x - s_hat

Symbols and conventions:

- ``level`` J: the approximation a_J holds the periods longer than 2^(J+1) samples
  (:func:`~nfs.denoise.levels.level_for_cutoff`); at 1 Hz, J = 8 keeps periods above 512 s = 8.5 min.
- ``sigma``: standard deviation of the white noise per sample, estimated from the finest
  details by the median absolute deviation (:func:`~nfs.denoise.thresholds.mad_sigma`). With an orthonormal wavelet
  white noise of standard deviation sigma gives coefficients of standard deviation sigma at
  every level.
- ``thresholds``: T_j per level, finest first (``thresholds[0]`` is level 1), in the units of
  the record.
- A threshold rule is a function ``rule(detail, sigma, n_samples) -> T`` (``detail``: one
  level's coefficients, ``sigma``: that level's noise standard deviation, ``n_samples``: the
  length of the record). :data:`~nfs.denoise.thresholds.THRESHOLD_RULES` maps the built-in names to rules; a user's own
  function is passed as ``rule=`` the same way.

Because the details below the cutoff are thresholded, not discarded, white noise is removed
but a step or transient large against the noise (a turn-on transient, a heat pulse) is kept,
shrunk by T_j / sqrt(2^j) per surviving coefficient (the bias of soft thresholding).

Record ends: see :data:`BOUNDARIES` and the comment "record ends" in this module's source
(a measured comparison of the extension modes and why "smooth-extend" is the default).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pywt

from ..docfields import document_fields
from ..errors import InputError
from .levels import (DEFAULT_WAVELET, check_edge_fit, check_level, cutoff_for_level,
                     edge_span_samples, level_for_cutoff, positive)
from .thresholds import ThresholdRule, mad_sigma, resolve_rule

__all__ = [
    "THRESHOLD_MODES",
    "BOUNDARIES",
    "DenoiseResult",
    "wavelet_denoise",
]
#: Thresholding functions (``pywt.threshold`` modes) that :func:`wavelet_denoise` accepts.
THRESHOLD_MODES: tuple[str, ...] = ("soft", "hard", "garrote")

#: Record-end treatments. ``"smooth-extend"`` (the default) pads the record itself with an odd
#: extension about a fitted end value (see the comment "record ends"); every other name is a
#: PyWavelets signal-extension mode passed to ``wavedec``/``waverec`` unchanged.
BOUNDARIES: tuple[str, ...] = ("smooth-extend",) + tuple(pywt.Modes.modes)


# --------------------------------------------------------------------------------------------
# record ends
#
# PyWavelets extends the record by L - 1 samples at every level with a chosen mode. Measured
# with db4, level 8, visu, 9000 samples at 1 Hz, white noise 0.018 deg/h, 20 seeds, on a smooth
# drift 0.02 exp(-t/600) + 0.005 (1 - exp(-t/2400)) and on three simulated start-up drifts
# (default instrument at T0 = -32, 17, 54 C): RMS error over the first / last 300 s divided by
# the interior RMS error (1.0 = as good as the interior):
#
#                      smooth      T0 -32     T0 17      T0 54
#   "symmetric"        1.4/2.6     3.0/2.6    2.7/2.6    5.5/2.6
#   "reflect"          1.4/1.5     3.0/1.5    2.7/1.5    5.5/1.5
#   "antireflect"      5.9/8.9     6.0/8.9    6.2/8.9    6.4/8.9
#   "smooth"          10.5/8.7    10.5/8.7   10.5/8.7   10.5/8.7
#   "periodization"    2.1/2.9     5.0/8.0    3.0/1.3    8.5/5.9
#   "smooth-extend"    1.0/1.0     1.4/1.0    2.4/1.0    4.7/1.0
#
# Why: mirroring ("symmetric", "reflect") puts a cusp at t = 0 in a drift that starts with a
# slope, and counts the noise of the end samples twice; pywt's "smooth" extrapolates the slope
# of the two end samples, which for noisy data is noise; "antireflect" is an odd extension
# about the end sample itself, so that sample's noise shifts the whole extension;
# "periodization" joins the cold start to the warm end. "smooth-extend" (the default) keeps
# what is good in the odd extension (the trend continues with a continuous slope, and the
# extension's noise has the statistics of the record's) but pivots on a fit of the end:
#     x(-k) = 2 p0 - x(k),   k = 1 .. pad = (L - 1)(2^J - 1)
# with p0 the value at the end sample of a least-squares fit: a quadratic over the first
# W = 2^J samples (the scale below which the transform treats content as detail), or, when the
# quadratic term over 2W samples is below 2 standard errors, a line over 2W samples (smaller
# variance; the flat end of a run). Likewise at the other end. The transform then runs on the
# padded record and the result is cropped. What remains at the start of a fast start-up drift
# (4.7x at T0 = 54 C) is the denoiser's, not the extension's: the same drift placed inside a
# longer record (its exact odd extension prepended as data) has 6x the interior error over
# those 300 s, since neither the level-8 approximation nor soft-thresholded details follow a
# transient of a minute or two exactly. tests/denoise measure the edge and interior errors.


def _poly_fit(y: np.ndarray, window: int, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares polynomial over y[:window] in k / (window - 1): coefficients (constant
    first) and their covariance from the residual variance."""
    k = np.arange(window, dtype=float) / max(window - 1, 1)
    a = np.vander(k, degree + 1, increasing=True)
    coef, *_ = np.linalg.lstsq(a, y[:window], rcond=None)
    dof = window - degree - 1
    resid = y[:window] - a @ coef
    s2 = float(resid @ resid) / dof if dof > 0 else 0.0
    return coef, np.linalg.pinv(a.T @ a) * s2


def _end_pivot(y: np.ndarray, window: int, degree: int | str) -> float:
    """Fitted value at y[0] of the end fit (see the comment above: "auto" chooses between a
    quadratic over ``window`` and a line over twice that)."""
    if degree != "auto":
        return float(_poly_fit(y, window, int(degree))[0][0])
    wide = min(y.size, 2 * window)
    if wide >= 4:
        coef, cov = _poly_fit(y, wide, 2)
        if abs(coef[2]) < 2.0 * math.sqrt(max(cov[2, 2], 0.0)):
            return float(_poly_fit(y, wide, 1)[0][0])   # no significant curvature
    return float(_poly_fit(y, window, 2)[0][0])


def _smooth_extend(x: np.ndarray, pad: int, window: int, degree: int | str) -> np.ndarray:
    """The record with ``pad`` samples of odd extension about fitted end values on each side:
    x(-k) = 2 p0 - x(k) and x(n-1+k) = 2 p_end - x(n-1-k), k = 1 .. pad."""
    p_start = _end_pivot(x, window, degree)
    p_end = _end_pivot(x[::-1], window, degree)
    left = 2.0 * p_start - x[pad:0:-1]
    right = 2.0 * p_end - x[-2:-pad - 2:-1]
    return np.concatenate((left, x, right))


def _mirror_extend(x: np.ndarray, pad: int) -> np.ndarray:
    """The record with ``pad`` mirrored samples on each side: x(-k) = x(k) (whole-sample
    symmetric, PyWavelets' "reflect"); the second guess behind ``edge_error_estimate``."""
    return np.concatenate((x[pad:0:-1], x, x[-2:-pad - 2:-1]))


# --------------------------------------------------------------------------------------------
# the denoiser


@document_fields
@dataclass(frozen=True)
class DenoiseResult:
    """Result of :func:`wavelet_denoise`."""

    signal: np.ndarray
    """s_hat, the denoised record [units of the record]."""
    noise: np.ndarray
    """x - s_hat, what was removed [units of the record]."""
    sigma: float
    """Noise standard deviation per sample from the finest details, :func:`~nfs.denoise.thresholds.mad_sigma`
    [units of the record]."""
    sigma_per_level: tuple[float, ...]
    """Noise standard deviation used at each level, finest first (all equal to ``sigma``
    unless ``sigma_per_level=True`` was asked) [units of the record]."""
    level: int
    """J, the decomposition level."""
    cutoff_period_s: float
    """Nominal cutoff 2^(J+1) / fs of the approximation [s]."""
    wavelet: str
    """Wavelet name (PyWavelets)."""
    rule: str
    """Name of the threshold rule ("fixed": thresholds given by the caller)."""
    mode: str
    """Thresholding function: soft, hard or garrote."""
    boundary: str
    """Record-end treatment (:data:`BOUNDARIES`)."""
    thresholds: tuple[float, ...]
    """T_j of each level, finest first (``thresholds[0]`` is level 1) [units of the record]."""
    edge_samples: int
    """(L - 1)(2^J - 1), samples at each end that boundary effects reach
    (:func:`~nfs.denoise.levels.edge_span_samples`; at most half the record)."""
    edge_s: float
    """``edge_samples`` / fs [s]."""
    edge_error_estimate: tuple[float, float]
    """Estimated RMS error of ``signal`` over the first and the last ``edge_s`` [units of the
    record]: sqrt(f^2 + D^2), with f = sigma / sqrt(2^J) the interior noise floor (white
    noise left in the approximation) and D the RMS difference, over each edge span, between
    this result and the same denoising under a second reasonable guess of what lies beyond
    the record (mirror padding for "smooth-extend", "smooth-extend" for a PyWavelets mode).
    An indicator of how far the ends can be trusted, not a bound (tests/denoise measure it
    within a factor 2 of the true edge error)."""
    sample_rate_hz: float
    """fs [Hz]."""


def _wavelet(name: str | pywt.Wavelet) -> pywt.Wavelet:
    if isinstance(name, pywt.Wavelet):
        return name
    try:
        return pywt.Wavelet(name)
    except (ValueError, TypeError):
        raise InputError(f"unknown or non-discrete wavelet {name!r}; valid names: "
                         f"pywt.wavelist(kind='discrete'), e.g. db4, sym8, coif3") from None


@functools.lru_cache(maxsize=None)
def _cover_wavelet(filter_length: int) -> pywt.Wavelet:
    """A filter bank of ones of length L: its DWT of a 0/1 mask is > 0 exactly at the
    coefficients whose support touches a masked sample (the same indexing as any wavelet of
    length L)."""
    ones = [1.0] * int(filter_length)
    return pywt.Wavelet(f"cover{filter_length}", filter_bank=[ones, ones, ones, ones])


def _clean_coefficients(excluded: np.ndarray, filter_length: int, level: int,
                        ext_mode: str) -> list[np.ndarray]:
    """Per level (finest first), True at the detail coefficients that see no excluded
    sample, nor PyWavelets' own extension ("constant" mode carries the excluded ends out;
    "periodization", whose coefficients are fewer, wraps them around)."""
    mode = "periodization" if ext_mode == "periodization" else "constant"
    cover = pywt.wavedec(excluded.astype(float), _cover_wavelet(filter_length),
                         mode=mode, level=level)
    return [cover[-j] == 0.0 for j in range(1, level + 1)]


def _transform_and_shrink(xp: np.ndarray, wav: pywt.Wavelet, ext_mode: str, level: int,
                          outside: np.ndarray, untrusted: np.ndarray, n: int,
                          rule: ThresholdRule, thr_mode: str, keep_approximation: bool,
                          per_level: bool, fixed: Sequence[float] | None = None):
    """DWT, noise level, thresholds, shrinkage, inverse DWT of the (padded) record.

    The noise level and the rules see the coefficients computed from neither ``outside``
    samples (the padding, PyWavelets' extension) nor ``untrusted`` ones; at coarse levels,
    where almost every coefficient touches an untrusted sample (a move every few minutes),
    those computed from the record proper, and failing that the whole level. Every
    coefficient is shrunk.
    """
    coeffs = pywt.wavedec(xp, wav, mode=ext_mode, level=level)
    inside = _clean_coefficients(outside, wav.dec_len, level, ext_mode)
    clean = (_clean_coefficients(outside | untrusted, wav.dec_len, level, ext_mode)
             if untrusted.any() else inside)

    def usable(j: int) -> np.ndarray:  # coeffs = [a_J, d_J, ..., d_1]: level j is coeffs[-j]
        d = coeffs[-j]
        n_inside = np.count_nonzero(inside[j - 1])
        if np.count_nonzero(clean[j - 1]) >= max(2, n_inside // 2):
            return d[clean[j - 1]]
        return d[inside[j - 1]] if n_inside >= 2 else d

    sigma = mad_sigma(usable(1))
    sigmas = []
    thresholds = []
    for j in range(1, level + 1):
        d_use = usable(j)
        s_j = mad_sigma(d_use) if per_level else sigma
        t_j = float(rule(d_use, s_j, n)) if fixed is None else float(fixed[j - 1])
        if not math.isfinite(t_j) or t_j < 0.0:
            raise InputError(f"threshold rule returned {t_j!r} at level {j}; "
                             "a threshold must be finite and >= 0")
        sigmas.append(s_j)
        thresholds.append(t_j)
        coeffs[-j] = pywt.threshold(coeffs[-j], t_j, mode=thr_mode)
    if not keep_approximation:
        coeffs[0] = pywt.threshold(coeffs[0], thresholds[-1], mode=thr_mode)
    y = pywt.waverec(coeffs, wav, mode=ext_mode)
    return y, sigma, tuple(sigmas), tuple(thresholds)


def wavelet_denoise(x: np.ndarray, *, sample_rate_hz: float = 1.0,
                    cutoff_period_s: float | None = None, level: int | None = None,
                    wavelet: str = DEFAULT_WAVELET, rule: str | ThresholdRule = "visu",
                    mode: str = "soft", keep_approximation: bool = True,
                    boundary: str = "smooth-extend", sigma_per_level: bool = False,
                    edge_fit_samples: int | None = None, edge_fit_degree: int | str = "auto",
                    trusted: np.ndarray | None = None,
                    thresholds: Sequence[float] | None = None) -> DenoiseResult:
    """Denoise a uniformly sampled record by wavelet shrinkage (Donoho & Johnstone 1994).

        x -> DWT to level J -> d_j shrunk with T_j (rule) -> IDWT -> s_hat;  noise = x - s_hat

    with T_j = rule(d_j, sigma_j, n), sigma_j = ``median(|d_1|) / 0.6745`` for white noise
    (Donoho 1995) or ``median(|d_j|) / 0.6745`` per level for correlated noise (Johnstone &
    Silverman 1997, JRSS B 59(2) 319-351). The level-J approximation is kept, so what is
    slower than 2^(J+1) samples passes untouched, and what is faster passes only where it
    stands out of the noise.

    Parameters
    ----------
    x : array_like
        The record, 1-D, finite, uniformly sampled [any unit; the results share it].
    sample_rate_hz : float
        fs [Hz]; converts ``cutoff_period_s`` to a level and the edge span to seconds.
    cutoff_period_s : float, optional
        Shortest period the approximation keeps [s]; gives J by :func:`~nfs.denoise.levels.level_for_cutoff`.
    level : int, optional
        J directly. Give exactly one of ``cutoff_period_s`` and ``level``.
    wavelet : str
        A discrete PyWavelets wavelet (db4, sym8, coif3, ...).
    rule : str or callable
        A name of :data:`~nfs.denoise.thresholds.THRESHOLD_RULES` or a function ``rule(detail, sigma, n_samples)``
        (called once per level in each of the two passes: the result and the second guess
        behind ``edge_error_estimate``).
    mode : str
        Thresholding function, one of :data:`THRESHOLD_MODES` (soft: Donoho 1995).
    keep_approximation : bool
        Keep a_J as is (the method). False also shrinks a_J with the level-J threshold.
    boundary : str
        Record ends, one of :data:`BOUNDARIES`: "smooth-extend" (odd extension about a
        local polynomial fit of each end, over ``edge_span_samples`` samples, then cropped) or
        a PyWavelets extension mode.
    sigma_per_level : bool
        Estimate the noise level at every level (for coloured noise) instead of once from the
        finest details.
    edge_fit_samples : int, optional
        W, samples of the end fit of "smooth-extend" (default 2^J, at most the record).
    edge_fit_degree : int or "auto"
        Degree of that fit; "auto" (default): a quadratic over W (follows the curvature of a
        start-up drift) unless the quadratic term over 2W is not significant (< 2 standard
        errors), then a line over 2W (half the variance at a flat end).
    trusted : array of bool, optional
        False at samples that carry no measured noise (bridged gaps, filled moves): the noise
        level and the threshold rules then use only coefficients computed from trusted
        samples (a bridged gap would otherwise pull the median of ``|d_1|`` down). Every sample
        is still denoised. Default: all trusted.
    thresholds : sequence of float, optional
        T_j of every level, finest first (as :attr:`DenoiseResult.thresholds`), used instead
        of the rule's: puts a second record through the same shrinkage as a first one (a
        noise-free model beside a measurement: soft thresholding is not linear, and a noise-free
        record's own thresholds would shrink it less than the measurement was shrunk).

    Returns
    -------
    DenoiseResult

    Raises
    ------
    InputError
        An empty, non-1-D or non-finite record; neither or both of cutoff and level; a level
        beyond what the record supports (:func:`~nfs.denoise.levels.check_level`); an unknown
        rule, mode, boundary or wavelet.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise InputError(f"wavelet_denoise needs a 1-D record of at least 2 samples, "
                         f"got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        bad = int(np.flatnonzero(~np.isfinite(x))[0])
        raise InputError(f"record holds a non-finite value at sample {bad} "
                         "(fill or interpolate missing samples first)")
    fs = positive("sample_rate_hz", sample_rate_hz)
    if (cutoff_period_s is None) == (level is None):
        raise InputError("give exactly one of cutoff_period_s and level")
    if level is None:
        level = level_for_cutoff(cutoff_period_s, fs)
    if isinstance(level, bool) or not isinstance(level, (int, np.integer)) or level < 1:
        raise InputError(f"level must be an integer >= 1, got {level!r}")
    level = int(level)
    wav = _wavelet(wavelet)
    rule_name, rule_fn = resolve_rule(rule)
    fixed = None if thresholds is None else [float(v) for v in thresholds]
    if fixed is not None:
        if len(fixed) != level or not all(math.isfinite(v) and v >= 0 for v in fixed):
            raise InputError(f"thresholds must be {level} finite values >= 0 (one per level, "
                             f"finest first), got {fixed}")
        rule_name = "fixed"
    if mode not in THRESHOLD_MODES:
        raise InputError(f"unknown thresholding mode {mode!r}; valid modes: "
                         f"{', '.join(THRESHOLD_MODES)}")
    if boundary not in BOUNDARIES:
        raise InputError(f"unknown boundary {boundary!r}; valid boundaries: "
                         f"{', '.join(BOUNDARIES)}")
    n = x.size
    # The transform sees the record plus its extension under "smooth-extend".
    check_level(level, n, wav.name, wav.dec_len, extended=boundary == "smooth-extend")
    edge = min(edge_span_samples(level, wav.dec_len), n // 2)

    pad = min(edge_span_samples(level, wav.dec_len), n - 1)
    window, degree = check_edge_fit(level, n, edge_fit_samples, edge_fit_degree)

    untrusted = np.zeros(n, dtype=bool) if trusted is None else ~np.asarray(trusted, bool)
    if untrusted.shape != (n,):
        raise InputError(f"trusted must be a mask of the record's {n} samples, "
                         f"got shape {untrusted.shape}")

    def run(extension: str):
        if extension == "smooth-extend":
            xp, p, ext_mode = _smooth_extend(x, pad, window, degree), pad, "symmetric"
        elif extension == "mirror":
            xp, p, ext_mode = _mirror_extend(x, pad), pad, "symmetric"
        else:
            xp, p, ext_mode = x, 0, extension
        # Samples outside the record proper (the padding; without padding the end samples
        # stand for PyWavelets' own extension) and the untrusted ones.
        outside = np.zeros(n + 2 * p, dtype=bool)
        outside[:p + 1] = outside[-p - 1:] = True
        untrusted_p = np.concatenate((np.zeros(p, bool), untrusted, np.zeros(p, bool)))
        y, s, s_lv, t_lv = _transform_and_shrink(xp, wav, ext_mode, level, outside,
                                                 untrusted_p, n, rule_fn, mode,
                                                 keep_approximation, sigma_per_level,
                                                 fixed)
        return y[p:p + n], s, s_lv, t_lv

    signal, sigma, sigmas, used = run(boundary)
    # A second guess of what lies beyond the ends: mirror padding for "smooth-extend",
    # "smooth-extend" for a PyWavelets mode.
    alt = run("mirror" if boundary == "smooth-extend" else "smooth-extend")[0]
    floor = sigma / math.sqrt(2.0 ** level)
    diff = signal - alt
    est = tuple(float(math.sqrt(floor * floor + np.mean(part * part)))
                for part in (diff[:edge], diff[n - edge:])) if edge > 0 else (floor, floor)
    return DenoiseResult(
        signal=signal, noise=x - signal, sigma=sigma, sigma_per_level=sigmas, level=level,
        cutoff_period_s=cutoff_for_level(level, fs), wavelet=wav.name, rule=rule_name, mode=mode,
        boundary=boundary, thresholds=used, edge_samples=edge, edge_s=edge / fs,
        edge_error_estimate=est, sample_rate_hz=fs)
