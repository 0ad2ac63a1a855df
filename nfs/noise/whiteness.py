"""Is a residual the gyro's noise?  A portmanteau test and a test of scale against the fitted
noise model.

Window means of the gyro's noise are not white (bias instability and rate random walk
correlate them), so a plain Ljung-Box test on a drift residual rejects "white" on clean data
and says nothing about a missing effect.  Under the null "the residual is the noise model"
the window means e_r of run r have the covariance Sigma_r of
:func:`nfs.noise.covariance.window_mean_covariance`; whitened, u_r = L_r^-1 e_r
(Sigma_r = L_r L_r^T), they are independent unit normals.  Two tests of u follow:

* whiteness: the Ljung-Box Q of u, autocorrelations pooled within runs (Ljung & Box 1978,
  Biometrika 65(2) 297-303, eq. (2.1))::

      r_k = sum_runs sum_t u[t] u[t + k] / sum_runs sum_t u[t]^2
      Q = n (n + 2) sum_{k=1}^{h} r_k^2 / (n - k)  ~  chi^2(h)

  with n the number of window means and h = ``lags``;

* scale: sum u^2 ~ chi^2(n - p) (a sum of squares of n - p independent unit normals),
  two-sided, since a residual that is white but three times too large is not the noise
  either.

A residual of a least-squares fit is not the noise itself: e = eps - X beta_hat for the
fitted columns X.  Whitened, L^-1 e = L^-1 eps - (L^-1 X) beta_hat, and projecting out the
whitened columns W = L^-1 X removes the second term whatever beta_hat was, leaving
(I - P_W) L^-1 eps, the generalised-least-squares residual (Kariya & Kurata 2004, Generalized
Least Squares, ch. 2; not checked down to equation number): with ``design`` given the test
uses that projection and p = rank W, so sum u^2 ~ chi^2(n - p) exactly.  A non-linear fit is
covered to first order by its Jacobian at the optimum.

The noise coefficients matter: on 7 runs of 844 window means the scale test sees N 5 % off
every time and B 20 % off most of the time (tests/noise/test_whiteness.py).  Coefficients
fitted to the same residual (:func:`fit_window_noise`, maximum likelihood) keep the size of
the whiteness test but void the scale test (sum u^2 = n at the maximum); coefficients known
beforehand keep both.

Without covariances the test is the plain Ljung-Box on the residual less its pooled mean (the
diagnosis's former test), and the test of scale is not defined.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.linalg import eigh, svd
from scipy.optimize import minimize_scalar
from scipy.stats import chi2

from nfs.docfields import document_fields
from nfs.errors import InputError
from nfs.noise.covariance import cholesky_lower, whiten, window_mean_covariance
from nfs.noise.generators import DEFAULT_CORRELATION_TIME_S

__all__ = [
    "WhitenessResult",
    "WindowNoiseFit",
    "fit_window_noise",
    "ljung_box_q",
    "whiteness_test",
]


@document_fields
@dataclass(frozen=True)
class WhitenessResult:
    """Whiteness and scale of a residual against a noise model (:func:`whiteness_test`)."""

    q: float
    """Ljung-Box statistic Q [-] of the (whitened) residual, eq. (2.1) of Ljung & Box 1978."""
    dof: int
    """Degrees of freedom of Q's chi-square law [-]: the number of lags h."""
    p_value: float
    """P(chi^2(dof) >= Q) [-]: small means autocorrelation the noise model does not explain."""
    white: bool
    """``p_value >= alpha``: no evidence of autocorrelation beyond the noise model."""
    acf: np.ndarray
    """Autocorrelations r_1 ... r_h [-] of the (whitened) residual, pooled within runs."""
    variance_ratio: float
    """sum u^2 / (n - p) [-], the whitened residual's variance per degree of freedom (1 under
    the null); NaN without covariances."""
    variance_dof: int
    """n - p [-]: degrees of freedom of sum u^2 (window means less fitted columns)."""
    variance_p_value: float
    """Two-sided p-value [-] of sum u^2 against chi^2(n - p); NaN without covariances."""
    unit_variance: bool | None
    """``variance_p_value >= alpha``; None without covariances."""
    consistent: bool
    """The residual passes as the noise: both tests at alpha / 2 (Bonferroni, so the false-
    alarm rate is at most alpha); without covariances, ``white``."""
    n: int
    """Number of window means n [-], all runs."""
    n_fitted: int
    """Rank p [-] of the fitted columns projected out (0 without ``design``)."""
    whitened: bool
    """Whether the residual was whitened by a noise-model covariance."""
    alpha: float
    """Significance level [-] of ``white`` and ``unit_variance``."""


def ljung_box_q(parts: Sequence[np.ndarray], lags: int) -> tuple[float, np.ndarray]:
    """Ljung-Box Q [-] and the autocorrelations r_1 ... r_h [-] of series taken as zero-mean,
    pooled within runs (Ljung & Box 1978, Biometrika 65(2) 297, eq. (2.1)).

    r_k = sum_runs sum_t x[t] x[t+k] / sum_runs sum_t x[t]^2 (no pair spans two runs) and
    Q = n (n + 2) sum_k r_k^2 / (n - k), n the total length.  Lags a run is too short for
    contribute nothing from it.  Subtract any mean before calling.
    """
    n = sum(p.size for p in parts)
    den = sum(float(p @ p) for p in parts)
    acf = np.zeros(lags)
    if den > 0.0:
        for k in range(1, lags + 1):
            acf[k - 1] = sum(float(p[k:] @ p[:-k]) for p in parts if p.size > k) / den
    k = np.arange(1, lags + 1)
    q = float(n * (n + 2) * np.sum(acf**2 / (n - k)))
    return q, acf


def _check_parts(residual_parts: Sequence[np.ndarray]) -> list[np.ndarray]:
    if isinstance(residual_parts, np.ndarray) or len(residual_parts) == 0:
        raise InputError("residual_parts must be a non-empty list of 1-D arrays, one per run")
    parts = []
    for i, p in enumerate(residual_parts):
        a = np.asarray(p, dtype=float)
        if a.ndim != 1 or a.size == 0:
            raise InputError(f"residual_parts[{i}] must be a non-empty 1-D array, got shape "
                             f"{a.shape}")
        if not np.all(np.isfinite(a)):
            raise InputError(f"residual_parts[{i}] has non-finite values")
        parts.append(a)
    return parts


def _check_design(design: Sequence[np.ndarray], parts: list[np.ndarray]) -> list[np.ndarray]:
    if len(design) != len(parts):
        raise InputError(f"design must have one block per run ({len(parts)}), got "
                         f"{len(design)}")
    blocks = []
    for i, (x, p) in enumerate(zip(design, parts)):
        a = np.asarray(x, dtype=float)
        if a.ndim == 1:
            a = a[:, None]
        if a.ndim != 2 or a.shape[0] != p.size:
            raise InputError(f"design[{i}] must have {p.size} rows (run {i}'s window means), "
                             f"got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise InputError(f"design[{i}] has non-finite values")
        blocks.append(a)
    if len({b.shape[1] for b in blocks}) != 1:
        raise InputError("design blocks must all have the same columns (a column that does "
                         "not act on a run is zero in its block)")
    return blocks


def _project_out(parts: list[np.ndarray], blocks: list[np.ndarray]
                 ) -> tuple[list[np.ndarray], int]:
    """Residual of the least-squares fit of the stacked ``blocks`` to the stacked ``parts``
    (orthogonal projection onto the complement of their column space) and the rank."""
    x = np.vstack(blocks)
    e = np.concatenate(parts)
    # an SVD rather than lstsq: its singular values give the rank used for the dof
    u, s, _ = svd(x, full_matrices=False)
    rank = int(np.sum(s > s[0] * max(x.shape) * np.finfo(float).eps)) if s.size else 0
    basis = u[:, :rank]
    e = e - basis @ (basis.T @ e)
    bounds = np.cumsum([0] + [p.size for p in parts])
    return [e[a:b] for a, b in zip(bounds[:-1], bounds[1:])], rank


def whiteness_test(residual_parts: list[np.ndarray],
                   covariances: list[np.ndarray] | None = None, *, lags: int = 20,
                   alpha: float = 0.01, design: list[np.ndarray] | None = None,
                   factors: list[np.ndarray] | None = None) -> WhitenessResult:
    """Test whether a residual is the gyro's noise: Ljung-Box on the residual whitened by the
    noise model's covariance, and a chi-square test of its scale.

    Each run's residual e_r (window means [deg/h]) is whitened, u_r = L_r^-1 e_r with
    Sigma_r = L_r L_r^T (:func:`nfs.noise.covariance.whiten`); if ``design`` is given, the
    whitened fitted columns are projected out of u (the GLS residual, module docstring).  Then

        Q = n (n + 2) sum_{k=1}^{h} r_k^2 / (n - k) ~ chi^2(h)   (Ljung & Box 1978, eq. (2.1))
        sum u^2 ~ chi^2(n - p)   (two-sided)

    with r_k pooled within runs (:func:`ljung_box_q`).  Without ``covariances`` the pooled
    mean is subtracted and the plain Ljung-Box results (the test the diagnosis used before:
    on the gyro's noise it rejects, because bias instability correlates the window means).

    Parameters
    ----------
    residual_parts : list of numpy.ndarray
        Residual window means [deg/h] of each run, in time order.
    covariances : list of numpy.ndarray, optional
        Covariance Sigma_r [(deg/h)^2] of each run's window means under the noise model
        (:func:`nfs.noise.covariance.window_mean_covariance`); runs are independent.
    lags : int
        Number of lags h of Q [-], 1 <= h < n.
    alpha : float
        Significance level [-], 0 < alpha < 1.
    design : list of numpy.ndarray, optional
        Columns fitted to the residual (least squares or otherwise), one (n_r, p) block per
        run with the same p columns (zero where a column does not act on a run); for a
        non-linear fit its Jacobian at the optimum.
    factors : list of numpy.ndarray, optional
        Lower Cholesky factors L_r (:func:`nfs.noise.covariance.cholesky_lower`) instead of
        ``covariances``, to reuse one factorisation across many residuals.

    Returns
    -------
    WhitenessResult
    """
    parts = _check_parts(residual_parts)
    if isinstance(lags, bool) or not isinstance(lags, (int, np.integer)):
        raise InputError(f"lags must be an integer, got {lags!r}")
    n = sum(p.size for p in parts)
    if not 1 <= lags < n:
        raise InputError(f"lags must be >= 1 and < the number of window means ({n}), got "
                         f"{lags}")
    alpha = float(alpha)
    if not 0.0 < alpha < 1.0:
        raise InputError(f"alpha must be in (0, 1), got {alpha!r}")
    if covariances is not None and factors is not None:
        raise InputError("give covariances or factors, not both")
    mats = covariances if covariances is not None else factors
    whitened = mats is not None
    if whitened:
        if len(mats) != len(parts):
            raise InputError(f"need one covariance per run ({len(parts)}), got {len(mats)}")
        what = "covariances" if covariances is not None else "factors"
        lows = []
        for i, (c, p) in enumerate(zip(mats, parts)):
            c = np.asarray(c, dtype=float)
            if c.shape != (p.size, p.size):
                raise InputError(f"{what}[{i}] must be {p.size} x {p.size} (run {i}'s window "
                                 f"means), got shape {c.shape}")
            lows.append(cholesky_lower(c, f"covariances[{i}]") if covariances is not None
                        else c)
        u = [whiten(p, factor=low) for p, low in zip(parts, lows)]
    else:
        mean = float(np.mean(np.concatenate(parts)))
        u = [p - mean for p in parts]
    n_fitted = 0
    if design is not None:
        blocks = _check_design(design, parts)
        if whitened:
            blocks = [whiten(x, factor=low) for x, low in zip(blocks, lows)]
        u, n_fitted = _project_out(u, blocks)
    q, acf = ljung_box_q(u, lags)
    p_value = float(chi2.sf(q, lags))
    variance_dof = n - n_fitted
    if whitened and variance_dof > 0:
        ss = sum(float(v @ v) for v in u)
        variance_ratio = ss / variance_dof
        variance_p = float(min(1.0, 2.0 * min(chi2.cdf(ss, variance_dof),
                                              chi2.sf(ss, variance_dof))))
        unit_variance: bool | None = variance_p >= alpha
        consistent = min(p_value, variance_p) >= alpha / 2.0
    else:
        variance_ratio, variance_p, unit_variance = math.nan, math.nan, None
        consistent = p_value >= alpha
    return WhitenessResult(q=q, dof=lags, p_value=p_value, white=p_value >= alpha, acf=acf,
                           variance_ratio=variance_ratio, variance_dof=variance_dof,
                           variance_p_value=variance_p, unit_variance=unit_variance,
                           consistent=consistent, n=n, n_fitted=n_fitted, whitened=whitened,
                           alpha=alpha)


# --------------------------------------------------------------------------------------------
# the noise model fitted to the window means themselves

@dataclass(frozen=True)
class WindowNoiseFit:
    """Angle random walk and bias instability fitted by maximum likelihood to residual window
    means (:func:`fit_window_noise`)."""

    arw_deg_per_rth_h: float
    """Angle random walk N [deg/sqrt(h)]."""
    bias_instability_dph: float
    """Bias instability B [deg/h] (0 when the fit sits at the lower bound of B^2 / N^2)."""
    log_likelihood: float
    """Gaussian log-likelihood of the window means at the fit [-]."""
    n: int
    """Number of window means n [-], all runs."""


def _layout_key(segments: tuple[np.ndarray, np.ndarray, np.ndarray | None]) -> bytes:
    starts, lengths, window = segments
    labels = np.arange(np.size(starts)) if window is None else window
    return b"|".join(np.ascontiguousarray(v, dtype=np.int64).tobytes()
                     for v in (starts, lengths, labels))


def fit_window_noise(residual_parts: list[np.ndarray],
                     segments: list[tuple[np.ndarray, np.ndarray, np.ndarray | None]],
                     sample_rate_hz: float, *,
                     correlation_time_s: float = DEFAULT_CORRELATION_TIME_S
                     ) -> WindowNoiseFit:
    """Maximum-likelihood angle random walk N and bias instability B of residual window
    means, rate random walk left out (K = 0).

    The covariance of run r's window means is linear in the squared coefficients,
    Sigma_r = N^2 A_r + B^2 C_r, with A_r and C_r the covariances at N = 1 and B = 1
    (:func:`nfs.noise.covariance.window_mean_covariance`).  With A_r = L L^T and the
    eigendecomposition L^-1 C_r L^-T = U diag(lambda) U^T (once per window layout),
    z = U^T L^-1 e_r has independent entries of variance N^2 (1 + rho lambda_i),
    rho = B^2 / N^2, so the Gaussian log-likelihood costs O(n) per evaluation and N^2 has the
    closed-form maximiser for given rho (the profile likelihood; e.g. Harville 1977, JASA
    72(358) 320, for the linear covariance model)::

        N^2(rho) = (1/n) sum z_i^2 / (1 + rho lambda_i)
        -2 log L(rho) = n log N^2(rho) + sum log(1 + rho lambda_i) + n (1 + log 2 pi)
                        + 2 sum log diag L

    maximised over log rho in [-30, 30] by a bounded scalar search
    (scipy.optimize.minimize_scalar; B = 0 when it ends at the lower bound).  At the maximum the whitened residual has
    sum u^2 = n exactly, so the test of scale of :func:`whiteness_test` is void with these
    coefficients: the scale must come from coefficients known beforehand (the instrument's
    declared noise, or a fit to other runs).  The whiteness test with them keeps its size
    (measured in tests/noise/test_whiteness.py).

    Parameters
    ----------
    residual_parts : list of numpy.ndarray
        Residual window means [deg/h] of each run.
    segments : list of (starts, lengths, window)
        Each run's windows as :func:`nfs.noise.covariance.window_mean_covariance` takes them
        (``window`` may be None); runs with the same layout share one eigendecomposition.
    sample_rate_hz : float
        Sample rate fs [Hz].
    correlation_time_s : float
        Longest correlation time T_c [s] of the bias-instability construction.

    Returns
    -------
    WindowNoiseFit
    """
    parts = _check_parts(residual_parts)
    if len(segments) != len(parts):
        raise InputError(f"segments must have one (starts, lengths, window) per run "
                         f"({len(parts)}), got {len(segments)}")
    # per window layout: L (A = L L^T), the eigenvalues lambda and vectors U, log det L
    layouts: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray, float]] = {}
    z2, lam = [], []
    log_det_a = 0.0
    for i, (p, seg) in enumerate(zip(parts, segments)):
        key = _layout_key(seg)
        if key not in layouts:
            starts, lengths, window = seg
            kw = dict(correlation_time_s=correlation_time_s, window=window)
            a = window_mean_covariance(starts, lengths, sample_rate_hz, arw_deg_per_rth_h=1.0,
                                       **kw)
            c = window_mean_covariance(starts, lengths, sample_rate_hz, arw_deg_per_rth_h=0.0,
                                       bias_instability_dph=1.0, **kw)
            low = cholesky_lower(a, f"segments[{i}] white covariance")
            m = whiten(whiten(c, factor=low).T, factor=low)      # L^-1 C L^-T
            lam_r, vec = eigh(0.5 * (m + m.T))
            layouts[key] = (low, np.maximum(lam_r, 0.0), vec,
                            float(np.sum(np.log(np.diag(low)))))
        low, lam_r, vec, log_diag = layouts[key]
        if low.shape[0] != p.size:
            raise InputError(f"segments[{i}] has {low.shape[0]} windows but "
                             f"residual_parts[{i}] has {p.size} means")
        z2.append((vec.T @ whiten(p, factor=low)) ** 2)
        lam.append(lam_r)
        log_det_a += log_diag
    z2_all = np.concatenate(z2)
    lam_all = np.concatenate(lam)
    n = z2_all.size

    def neg2_loglik(log_rho: float) -> float:
        w = 1.0 + math.exp(log_rho) * lam_all
        theta = float(np.mean(z2_all / w))
        return n * math.log(theta) + float(np.sum(np.log(w)))

    res = minimize_scalar(neg2_loglik, bounds=(-30.0, 30.0), method="bounded",
                          options={"xatol": 1e-6})
    rho = math.exp(res.x) if res.x > -29.0 else 0.0
    n2 = float(np.mean(z2_all / (1.0 + rho * lam_all)))
    loglik = -0.5 * (neg2_loglik(math.log(rho)) if rho > 0 else n * math.log(n2)) \
        - 0.5 * n * (1.0 + math.log(2.0 * math.pi)) - log_det_a
    return WindowNoiseFit(arw_deg_per_rth_h=math.sqrt(n2),
                          bias_instability_dph=math.sqrt(rho * n2), log_likelihood=loglik, n=n)
