"""Covariance of window means of the gyro's rate noise, and whitening by its Cholesky factor.

A residual that is the gyro's noise reduced to means over windows at rest is not white: the
bias instability (a sum of first-order Gauss-Markov processes, :func:`nfs.noise.generators.
bias_instability_noise_dph`) correlates neighbouring windows over up to T_c, and the rate
random walk correlates the whole record.  This module gives the covariance [(deg/h)^2] of such
window means, exact for the sampled construction of :func:`nfs.noise.gyro_noise_dph`, and the
whitening L^-1 e (Sigma = L L^T) that turns them into independent unit normals under the null.

Windows are built from *segments*: runs of consecutive samples [a, a + m), sample indices
counted from the first sample of the record (the rate random walk starts there).  A window
mean is the mean over all samples of its segments, so a window cut by a turntable move
(samples skipped) is one window of two segments.

Derivation (every term zero-mean, the three independent, so their covariances add).  Let
S_A = sum_{i in A} y[i] be the sum over segment A = [a1, a2), m = a2 - a1; likewise B =
[b1, b2), n = b2 - b1.  The window mean of window w is (1/M_w) sum_{A in w} S_A with M_w its
number of samples, so Cov(mean_v, mean_w) = (1/(M_v M_w)) sum_{A in v} sum_{B in w}
Cov(S_A, S_B).

* Angle random walk N [deg/sqrt(h)]: white, per-sample variance s_N^2 = (60 N)^2 fs
  [(deg/h)^2] (IEEE Std 952-2020 Annex C; docs/physics.md section 3), so
  Cov(S_A, S_B) = s_N^2 |A cap B|, and a lone m-sample mean has the variance (60 N)^2 fs / m.

* Each Gauss-Markov component of the bias instability B [deg/h]: a stationary AR(1) sequence
  of variance q^2 = B^2 ln(r) / pi and autocovariance q^2 phi^|k|, phi = exp(-1/(fs T_k))
  (:func:`~nfs.noise.generators.bias_instability_noise_dph`).  For disjoint segments, B after
  A with g = b1 - a2 >= 0 samples between them, every pair has j > i and the double sum
  factorises into two geometric sums::

      Cov(S_A, S_B) = q^2 phi^(g + 1) (1 - phi^m) (1 - phi^n) / (1 - phi)^2

  For overlapping segments the sums are increments of the integrated ("phase") process
  X(t) = sum_{i < t} y[i], which has stationary increments of variance V(d) =
  Var(X(t + d) - X(t)) = q^2 F(|d|), F(d) = sum_{i,j < d} phi^|i-j| =
  d + 2 phi (d (1 - phi) - (1 - phi^d)) / (1 - phi)^2 (the geometric sum also behind
  :func:`~nfs.noise.generators.bias_instability_adev_dph`), and the covariance of two
  increments S_A = X(a2) - X(a1), S_B = X(b2) - X(b1) of such a process is the polarisation
  identity of its structure function (derived here: expand each V(t - s) as
  Var X(t) + Var X(s) - 2 Cov(X(s), X(t)) and the Var terms cancel)::

      Cov(S_A, S_B) = (V(b2 - a1) + V(a2 - b1) - V(b2 - a2) - V(b1 - a1)) / 2

  The two agree for disjoint segments; the first is used there because it has no cancellation
  between large terms when the segments are far apart.

* Rate random walk K [deg/h/sqrt(h)]: r[i] = sum_{k <= i} w[k], r[-1] = 0, increments of
  variance s_K^2 = (K/60)^2 / fs (:func:`~nfs.noise.generators.rate_random_walk_noise_dph`),
  so Cov(r[i], r[j]) = s_K^2 (min(i, j) + 1): not stationary, it depends on the absolute
  sample indices.  With M(x, y) = sum_{i < x} sum_{j < y} (min(i, j) + 1), which for
  u = min(x, y), v = max(x, y) sums to (derived here: for i < u the inner sum is
  (i + 1)(v - i/2))::

      M(x, y) = u (u + 1) (3 v - u + 1) / 6

  the segment covariance is the rectangle sum
  Cov(S_A, S_B) = s_K^2 [M(a2, b2) - M(a1, b2) - M(a2, b1) + M(a1, b1)].

Every formula is checked against a Monte Carlo of :func:`nfs.noise.gyro_noise_dph` in
tests/noise/test_covariance.py.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import LinAlgError, cholesky, solve_triangular

from nfs.errors import InputError
from nfs.noise.checks import check_non_negative, check_positive
from nfs.noise.generators import (
    DEFAULT_CORRELATION_TIME_S,
    bias_instability_poles,
    check_bias_instability_times,
)

__all__ = [
    "cholesky_lower",
    "rest_window_segments",
    "segment_sum_covariance",
    "whiten",
    "window_mean_covariance",
]


# --------------------------------------------------------------------------------------------
# argument checks

def _check_segments(starts: np.ndarray, lengths: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(starts)
    m = np.asarray(lengths)
    if a.ndim != 1 or m.shape != a.shape:
        raise InputError(f"starts and lengths must be 1-D arrays of the same length, got "
                         f"shapes {a.shape} and {m.shape}")
    for name, v in (("starts", a), ("lengths", m)):
        if not np.all(np.isfinite(v)) or np.any(v != np.round(v)):
            raise InputError(f"{name} must hold whole numbers of samples")
    a = a.astype(np.int64)
    m = m.astype(np.int64)
    if np.any(a < 0):
        raise InputError("starts must be sample indices >= 0 (counted from the record's "
                         "first sample)")
    if np.any(m < 1):
        raise InputError("lengths must be >= 1 sample")
    return a, m


def _check_labels(window: np.ndarray | None, n_segments: int) -> np.ndarray:
    if window is None:
        return np.arange(n_segments)
    w = np.asarray(window)
    if w.shape != (n_segments,) or (w.size and (not np.all(w == np.round(w)) or w.min() < 0)):
        raise InputError(f"window must hold one integer label >= 0 per segment "
                         f"({n_segments}), got shape {w.shape}")
    w = w.astype(np.int64)
    if w.size and np.unique(w).size != int(w.max()) + 1:
        raise InputError("window labels must be 0, 1, ..., n_windows - 1 with none missing")
    return w


# --------------------------------------------------------------------------------------------
# segments of the samples at rest

def rest_window_segments(sample_index: np.ndarray, window_label: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments (runs of consecutive samples) of windows given sample by sample.

    The diagnosis averages, per window, the samples at rest that fall in it; this turns the
    indices of those samples and their window labels into the segments that
    :func:`window_mean_covariance` takes.

    Parameters
    ----------
    sample_index : array_like of int
        Index [-] of each averaged sample, counted from the record's first sample (the rate
        random walk starts there), strictly increasing.
    window_label : array_like of int
        Window of each sample [-], non-decreasing; any integers (they are renumbered
        0, 1, ... in order).

    Returns
    -------
    starts, lengths, window : numpy.ndarray
        First sample and number of samples of each segment, and the window (0, 1, ...) it
        belongs to.
    """
    i = np.asarray(sample_index)
    lab = np.asarray(window_label)
    if i.ndim != 1 or lab.shape != i.shape or i.size == 0:
        raise InputError(f"sample_index and window_label must be non-empty 1-D arrays of the "
                         f"same length, got shapes {i.shape} and {lab.shape}")
    if np.any(i != np.round(i)) or np.any(lab != np.round(lab)):
        raise InputError("sample_index and window_label must hold integers")
    i = i.astype(np.int64)
    lab = lab.astype(np.int64)
    if np.any(np.diff(i) <= 0) or np.any(np.diff(lab) < 0):
        raise InputError("sample_index must be strictly increasing and window_label "
                         "non-decreasing")
    new = np.ones(i.size, dtype=bool)
    new[1:] = (np.diff(i) != 1) | (np.diff(lab) != 0)
    first = np.flatnonzero(new)
    lengths = np.diff(np.append(first, i.size))
    _, window = np.unique(lab[first], return_inverse=True)
    return i[first], lengths, window.astype(np.int64)


# --------------------------------------------------------------------------------------------
# covariance of segment sums, one function per noise term

def _overlap(a1, a2, b1, b2) -> np.ndarray:
    return np.maximum(0, np.minimum(a2, b2) - np.maximum(a1, b1))


def _gm_increment_variance(d: np.ndarray, one_minus_phi: float, rate: float) -> np.ndarray:
    """F(|d|) = sum_{i,j < |d|} phi^|i-j| [-], phi = exp(-rate), one_minus_phi = 1 - phi."""
    d = np.abs(d).astype(float)
    phi = 1.0 - one_minus_phi
    one_minus_phi_d = -np.expm1(-rate * d)
    return d + 2.0 * phi * (d * one_minus_phi - one_minus_phi_d) / one_minus_phi**2


def _gm_segment_cov(a: np.ndarray, m: np.ndarray, lag: np.ndarray,
                    overlapping: tuple[np.ndarray, np.ndarray],
                    t_k_samples: float) -> np.ndarray:
    """sum_{i in A} sum_{j in B} phi^|i-j| [-] over every pair of segments (A, B),
    phi = exp(-1/t_k_samples); ``lag`` is the gap between disjoint segments plus one [-]
    (ignored where they overlap) and ``overlapping`` the (row, column) indices of the pairs
    that overlap."""
    rate = 1.0 / t_k_samples
    one_minus_phi = -math.expm1(-rate)
    # disjoint, B after A with g = b1 - a2 samples between (or A after B):
    # phi^(g + 1) times the outer product of the two segments' (1 - phi^m) / (1 - phi)
    geo = -np.expm1(-rate * m) / one_minus_phi
    cov = np.exp(lag * -rate)
    cov *= geo[:, None]
    cov *= geo[None, :]
    # overlapping (few pairs: a segment with itself): polarisation of the phase increments
    rows, cols = overlapping
    if rows.size:
        p1, p2 = a[rows], a[rows] + m[rows]
        q1, q2 = a[cols], a[cols] + m[cols]
        cov[rows, cols] = 0.5 * (_gm_increment_variance(q2 - p1, one_minus_phi, rate)
                                 + _gm_increment_variance(p2 - q1, one_minus_phi, rate)
                                 - _gm_increment_variance(q2 - p2, one_minus_phi, rate)
                                 - _gm_increment_variance(q1 - p1, one_minus_phi, rate))
    return cov


def _rrw_m(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """M(x, y) = sum_{i<x} sum_{j<y} (min(i,j) + 1) = u (u+1) (3v - u + 1) / 6 [-]."""
    u = np.minimum(x, y).astype(float)
    v = np.maximum(x, y).astype(float)
    return u * (u + 1.0) * (3.0 * v - u + 1.0) / 6.0


def segment_sum_covariance(starts: np.ndarray, lengths: np.ndarray, sample_rate_hz: float, *,
                           arw_deg_per_rth_h: float, bias_instability_dph: float = 0.0,
                           rrw_deg_per_h_per_rth_h: float = 0.0,
                           correlation_time_s: float = DEFAULT_CORRELATION_TIME_S
                           ) -> np.ndarray:
    """Covariance [(deg/h)^2] of the sums of the gyro's rate noise over segments of samples.

    Cov(S_A, S_B), S_A = sum_{i in A} y[i], A = [starts[k], starts[k] + lengths[k]), for the
    noise of :func:`nfs.noise.gyro_noise_dph`: the sum of the white (ARW), Gauss-Markov
    (bias instability, one term per component) and random-walk (RRW) covariances of the
    module docstring.

    Parameters
    ----------
    starts, lengths : array_like of int
        First sample [-] (counted from the record's first sample) and number of samples [-]
        of each segment.
    sample_rate_hz : float
        Sample rate fs [Hz].
    arw_deg_per_rth_h : float
        Angle random walk N [deg/sqrt(h)], >= 0.
    bias_instability_dph : float
        Bias instability B [deg/h], >= 0.
    rrw_deg_per_h_per_rth_h : float
        Rate random walk K [deg/h/sqrt(h)], >= 0.
    correlation_time_s : float
        Longest correlation time T_c [s] of the bias-instability construction (checked only
        when B > 0).

    Returns
    -------
    numpy.ndarray
        (n_segments, n_segments) symmetric covariance [(deg/h)^2].
    """
    a, m = _check_segments(starts, lengths)
    fs = check_positive("sample_rate_hz", sample_rate_hz)
    arw = check_non_negative("arw_deg_per_rth_h", arw_deg_per_rth_h)
    b = check_non_negative("bias_instability_dph", bias_instability_dph)
    k = check_non_negative("rrw_deg_per_h_per_rth_h", rrw_deg_per_h_per_rth_h)
    a1, a2 = a[:, None], (a + m)[:, None]
    b1, b2 = a[None, :], (a + m)[None, :]
    cov = (60.0 * arw) ** 2 * fs * _overlap(a1, a2, b1, b2).astype(float)
    if b > 0.0:
        fs, t_c = check_bias_instability_times(fs, correlation_time_s)
        times_s, q2_per_b2 = bias_instability_poles(fs, t_c)
        gap = np.maximum(b1 - a2, a1 - b2)
        overlapping = np.nonzero(gap < 0)
        lag = np.maximum(gap, 0).astype(float) + 1.0
        af, mf = a.astype(float), m.astype(float)
        for t_k in times_s:
            cov += b * b * q2_per_b2 * _gm_segment_cov(af, mf, lag, overlapping, fs * t_k)
    if k > 0.0:
        s2 = (k / 60.0) ** 2 / fs
        cov += s2 * (_rrw_m(a2, b2) - _rrw_m(a1, b2) - _rrw_m(a2, b1) + _rrw_m(a1, b1))
    return cov


def window_mean_covariance(starts: np.ndarray, lengths: np.ndarray, sample_rate_hz: float, *,
                           arw_deg_per_rth_h: float, bias_instability_dph: float = 0.0,
                           rrw_deg_per_h_per_rth_h: float = 0.0,
                           correlation_time_s: float = DEFAULT_CORRELATION_TIME_S,
                           window: np.ndarray | None = None) -> np.ndarray:
    """Covariance [(deg/h)^2] of window means of the gyro's rate noise (ARW + bias
    instability + RRW), exact for the sampled construction of :func:`nfs.noise.gyro_noise_dph`.

    Cov(mean_v, mean_w) = (1 / (M_v M_w)) sum_{A in v} sum_{B in w} Cov(S_A, S_B), M_w the
    number of samples of window w and Cov(S_A, S_B) from :func:`segment_sum_covariance`
    (derivation in the module docstring).  A lone window of m samples of white noise alone has
    the variance (60 N)^2 fs / m.  Windows need not be contiguous nor adjacent: the samples
    skipped while the turntable moves enter through the sample positions (the AR(1) lags
    between windows are counted in samples of the record).

    Parameters
    ----------
    starts, lengths : array_like of int
        Segments: first sample [-] (counted from the record's first sample, where the rate
        random walk starts) and number of samples [-] of each run of consecutive samples
        averaged (:func:`rest_window_segments` builds them from sample indices).
    sample_rate_hz : float
        Sample rate fs [Hz].
    arw_deg_per_rth_h, bias_instability_dph, rrw_deg_per_h_per_rth_h, correlation_time_s
        The noise coefficients N [deg/sqrt(h)], B [deg/h], K [deg/h/sqrt(h)] and T_c [s], as
        in :func:`nfs.noise.gyro_noise_dph`.
    window : array_like of int, optional
        Window (0, 1, ..., n_windows - 1) of each segment; by default each segment is its own
        window.

    Returns
    -------
    numpy.ndarray
        (n_windows, n_windows) covariance of the window means [(deg/h)^2], windows in label
        order.
    """
    a, m = _check_segments(starts, lengths)
    labels = _check_labels(window, a.size)
    cov = segment_sum_covariance(a, m, sample_rate_hz, arw_deg_per_rth_h=arw_deg_per_rth_h,
                                 bias_instability_dph=bias_instability_dph,
                                 rrw_deg_per_h_per_rth_h=rrw_deg_per_h_per_rth_h,
                                 correlation_time_s=correlation_time_s)
    if window is None:
        w = 1.0 / m
        return cov * w[:, None] * w[None, :]
    n_windows = int(labels.max()) + 1 if labels.size else 0
    counts = np.bincount(labels, weights=m, minlength=n_windows)
    avg = np.zeros((n_windows, a.size))
    avg[labels, np.arange(a.size)] = 1.0 / counts[labels]
    mean_cov = avg @ cov @ avg.T
    return 0.5 * (mean_cov + mean_cov.T)   # symmetric to the last bit, for the Cholesky


# --------------------------------------------------------------------------------------------
# whitening

def cholesky_lower(covariance: np.ndarray, name: str = "covariance") -> np.ndarray:
    """Lower Cholesky factor L of a covariance, Sigma = L L^T (scipy.linalg.cholesky).

    Raises :class:`~nfs.errors.InputError` when ``covariance`` is not a finite, symmetric,
    positive-definite square matrix (``name`` locates it in the message).
    """
    c = np.asarray(covariance, dtype=float)
    if c.ndim != 2 or c.shape[0] != c.shape[1]:
        raise InputError(f"{name} must be a square matrix, got shape {c.shape}")
    if not np.all(np.isfinite(c)):
        raise InputError(f"{name} has non-finite entries")
    scale = float(np.max(np.abs(np.diag(c)))) if c.size else 0.0
    if c.size and not np.allclose(c, c.T, rtol=1e-10, atol=1e-12 * scale):
        raise InputError(f"{name} is not symmetric")
    try:
        return cholesky(c, lower=True)
    except LinAlgError:
        raise InputError(f"{name} is not positive definite") from None


def whiten(values: np.ndarray, covariance: np.ndarray | None = None, *,
           factor: np.ndarray | None = None) -> np.ndarray:
    """Whiten by the Cholesky factor of a covariance: u = L^-1 values, Sigma = L L^T.

    If ``values`` ~ N(0, Sigma), then u ~ N(0, I): independent unit normals (the
    innovations of the noise model; Kay 1993, Fundamentals of Statistical Signal Processing
    I, section 4.5, prewhitening).  Solved with scipy.linalg.solve_triangular, never by
    forming L^-1.

    Parameters
    ----------
    values : array_like
        (n,) residual or (n, p) columns [unit of sqrt(Sigma)], e.g. window means [deg/h].
    covariance : array_like, optional
        (n, n) covariance Sigma [unit^2].
    factor : array_like, optional
        Its lower Cholesky factor L (:func:`cholesky_lower`), to reuse one factorisation;
        give exactly one of ``covariance`` and ``factor``.

    Returns
    -------
    numpy.ndarray
        L^-1 values [-], same shape as ``values``.
    """
    if (covariance is None) == (factor is None):
        raise InputError("whiten needs exactly one of covariance and factor")
    low = cholesky_lower(covariance) if factor is None else np.asarray(factor, dtype=float)
    v = np.asarray(values, dtype=float)
    if v.ndim not in (1, 2) or v.shape[0] != low.shape[0]:
        raise InputError(f"values must have {low.shape[0]} rows (the covariance's size), "
                         f"got shape {v.shape}")
    return solve_triangular(low, v, lower=True, check_finite=True)
