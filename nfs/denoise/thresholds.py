"""Threshold rules of the wavelet denoiser: the noise level from the finest details (MAD) and
the thresholds T_j per level (universal/VisuShrink, SURE, BayesShrink; Donoho & Johnstone
1994, 1995; Chang, Yu & Vetterli 2000), each a function ``rule(detail, sigma, n_samples) -> T``
in the units of the record (:data:`THRESHOLD_RULES`; a user's own rule plugs in the same way).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..errors import InputError

__all__ = ["MAD_TO_SIGMA", "ThresholdRule", "THRESHOLD_RULES", "mad_sigma", "no_threshold",
           "visu_threshold", "sure_risk", "sure_threshold", "bayes_shrink_threshold",
           "resolve_rule"]

#: Phi^-1(3/4) = 0.6745: ``median(|d|) / MAD_TO_SIGMA`` is sigma for Gaussian d of zero mean.
MAD_TO_SIGMA: float = 0.6744897501960817

#: A threshold rule: ``rule(detail, sigma, n_samples) -> threshold`` in the units of ``detail``.
ThresholdRule = Callable[[np.ndarray, float, int], float]


# --------------------------------------------------------------------------------------------
# noise level and threshold rules


def mad_sigma(detail: np.ndarray) -> float:
    """Noise standard deviation from detail coefficients by the median absolute deviation.

        ``sigma = median(|d|) / 0.6745``

    (Donoho & Johnstone 1994, Biometrika 81(3) 425-455; Donoho 1995, IEEE Trans. Inf. Theory
    41(3) 613-627; section numbers not checked against the papers), applied to the
    finest-level details d_1, where a smooth signal leaves almost nothing and the median
    ignores the few large coefficients it does leave. 0.6745 is Phi^-1(3/4) (:data:`MAD_TO_SIGMA`).

    Parameters
    ----------
    detail : array_like
        Detail coefficients [units of the record].

    Returns
    -------
    float
        sigma [units of the record]; 0 for an empty array.
    """
    d = np.asarray(detail, dtype=float)
    if d.size == 0:
        return 0.0
    return float(np.median(np.abs(d)) / MAD_TO_SIGMA)


def no_threshold(detail: np.ndarray, sigma: float, n_samples: int) -> float:
    """The null rule: T = 0, every coefficient kept (the transform alone, a perfect
    reconstruction up to round-off)."""
    return 0.0


def visu_threshold(sigma: float, n: int) -> float:
    """Universal threshold of VisuShrink.

        T = sigma sqrt(2 ln n)

    (Donoho & Johnstone 1994, Biometrika 81(3) 425-455, the universal threshold; equation
    number not checked against the paper: with probability tending to 1 every pure-noise
    coefficient of n lies below T.)

    Parameters
    ----------
    sigma : float
        Noise standard deviation of the coefficients [units of the record].
    n : int
        Number of samples of the record (n >= 1; n = 1 gives T = 0).
    """
    n = int(n)
    if n < 1:
        raise InputError(f"visu_threshold needs n >= 1 samples, got {n}")
    return float(sigma) * math.sqrt(2.0 * math.log(n))


def sure_risk(t: float | np.ndarray, x: np.ndarray) -> np.ndarray:
    """Stein's unbiased risk estimate of soft thresholding at t for unit-variance data.

        ``SURE(t; x) = m - 2 #{i : |x_i| <= t} + sum_i min(|x_i|, t)^2``

    (Donoho & Johnstone 1995, JASA 90(432) 1200-1224, from Stein 1981, Ann. Stat. 9(6)
    1135-1151; section number not checked), m = len(x):
    an unbiased estimate of E ||eta_t(x) - mu||^2 for x ~ N(mu, I). Vectorised over t.
    """
    x = np.abs(np.asarray(x, dtype=float))
    t = np.asarray(t, dtype=float)
    tt = t[..., None]
    return (x.size - 2.0 * np.sum(x <= tt, axis=-1)
            + np.sum(np.minimum(x, tt) ** 2, axis=-1))


def sure_threshold(coeffs: np.ndarray, sigma: float, *, hybrid: bool = True) -> float:
    """SureShrink threshold of one level's coefficients (Donoho & Johnstone 1995).

    With x = d / sigma (m coefficients) and t_u = sqrt(2 ln m):

        t_S = argmin_{0 <= t <= t_u} SURE(t; x)            (:func:`sure_risk`)

    SURE is piecewise increasing in t between the sorted ``|x_i|``, so its minimum over
    [0, t_u] lies at t = 0 or at one of the ``|x_i| <= t_u``; those are the candidates searched
    (with cumulative sums, O(m log m)). The hybrid rule (section 2.4 of the paper; WaveLab's
    ``HybridThresh``) falls back to the universal threshold when the level is sparse, where
    SURE is unreliable:

        s^2 = (sum x_i^2 - m) / m,   gamma = (log2 m)^(3/2) / sqrt(m)
        t = t_u  if s^2 <= gamma,  else  min(t_S, t_u)

    Returns T = sigma t [units of the record]. (Section numbers not checked against the
    paper; the formulas match WaveLab 802's ``ValSUREThresh`` and ``HybridThresh``.)

    Parameters
    ----------
    coeffs : array_like
        One level's detail coefficients [units of the record].
    sigma : float
        Their noise standard deviation [units of the record]; 0 gives T = 0.
    hybrid : bool
        Apply the sparsity test (SureShrink proper); False returns the pure SURE minimiser.
    """
    d = np.asarray(coeffs, dtype=float).ravel()
    sigma = float(sigma)
    m = d.size
    if m == 0 or sigma <= 0.0:
        return 0.0
    x = np.abs(d) / sigma
    t_u = math.sqrt(2.0 * math.log(m)) if m > 1 else 0.0
    if hybrid:
        s2 = (float(np.sum(x * x)) - m) / m
        gamma = math.log2(m) ** 1.5 / math.sqrt(m)
        if s2 <= gamma:
            return sigma * t_u
    xs = np.sort(x)
    csum = np.cumsum(xs * xs)
    k = np.arange(1, m + 1)
    # SURE at t = xs[k-1]: m - 2k + sum_{i<=k} xs_i^2 + (m - k) xs_k^2 (ties: the last of a
    # run of equal values counts them all, so take the risk at the last index of each value).
    risk = m - 2.0 * k + csum + (m - k) * xs * xs
    last_of_value = np.append(xs[1:] != xs[:-1], True)
    ok = last_of_value & (xs <= t_u)
    candidates = np.concatenate(([0.0], xs[ok]))
    risks = np.concatenate(([float(m)], risk[ok]))  # SURE(0) = m
    t_s = float(candidates[int(np.argmin(risks))])
    return sigma * min(t_s, t_u)


def bayes_shrink_threshold(coeffs: np.ndarray, sigma: float) -> float:
    """BayesShrink threshold of one level's coefficients (Chang, Yu & Vetterli 2000).

        T = sigma^2 / sigma_x,   sigma_x = sqrt(max(sigma_y^2 - sigma^2, 0)),
        sigma_y^2 = mean(d^2)

    (IEEE Trans. Image Process. 9(9) 1532-1546; section not checked against the paper, the
    formula matches scikit-image's ``_bayes_thresh``: the threshold that nearly
    minimises the Bayes risk of soft thresholding for a generalised-Gaussian prior, with the
    signal variance sigma_x^2 estimated from the observed variance sigma_y^2.) When
    sigma_y <= sigma the level looks like pure noise and T = ``max |d|`` (all coefficients set to
    zero), as the paper prescribes.

    Parameters
    ----------
    coeffs : array_like
        One level's detail coefficients [units of the record], assumed of zero mean.
    sigma : float
        Their noise standard deviation [units of the record].
    """
    d = np.asarray(coeffs, dtype=float).ravel()
    sigma = float(sigma)
    if d.size == 0 or sigma <= 0.0:
        return 0.0
    var_x = float(np.mean(d * d)) - sigma * sigma
    if var_x <= 0.0:
        return float(np.max(np.abs(d)))
    return sigma * sigma / math.sqrt(var_x)


def _visu_rule(detail: np.ndarray, sigma: float, n_samples: int) -> float:
    return visu_threshold(sigma, n_samples)


def _sure_rule(detail: np.ndarray, sigma: float, n_samples: int) -> float:
    return sure_threshold(detail, sigma)


def _bayes_rule(detail: np.ndarray, sigma: float, n_samples: int) -> float:
    return bayes_shrink_threshold(detail, sigma)


#: Built-in threshold rules by name, each ``rule(detail, sigma, n_samples) -> T``:
#: ``none`` (the null rule, T = 0), ``visu`` (:func:`visu_threshold` with n the record length),
#: ``sure`` (:func:`sure_threshold`, hybrid) and ``bayes`` (:func:`bayes_shrink_threshold`).
THRESHOLD_RULES: dict[str, ThresholdRule] = {
    "none": no_threshold,
    "visu": _visu_rule,
    "sure": _sure_rule,
    "bayes": _bayes_rule,
}


def resolve_rule(rule: str | ThresholdRule) -> tuple[str, ThresholdRule]:
    if callable(rule):
        return getattr(rule, "__name__", "custom"), rule
    if isinstance(rule, str) and rule in THRESHOLD_RULES:
        return rule, THRESHOLD_RULES[rule]
    raise InputError(f"unknown threshold rule {rule!r}; valid rules: "
                     f"{', '.join(THRESHOLD_RULES)} (or a function "
                     "rule(detail, sigma, n_samples) -> threshold)")
