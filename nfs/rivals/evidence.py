"""What the runs taken say between two fitted rivals, and how far that can be trusted.

Two rivals a and b fitted to the same runs predict the recorded numbers mu_a and mu_b
(:mod:`nfs.rivals.predict`).  Whitened by the noise of each number (sigma,
:mod:`nfs.rivals.noise_level`) and with a constant per channel and run projected out (P,
the nuisance of :mod:`nfs.rivals.separation`), let

    delta = P (mu_a - mu_b) / sigma,    m = P (y - (mu_a + mu_b) / 2) / sigma.

The log-likelihood ratio of a over b on the measured numbers y is then

    Lambda = (|P (y - mu_b) / sigma|^2 - |P (y - mu_a) / sigma|^2) / 2 = sum_i delta_i m_i,

the least-squares position of the runs on the line from b to a times D = |delta|^2 (the
squared separation): beta = Lambda / D is +1/2 at a and -1/2 at b.  If a is the unit and
the noise is what sigma says, y = mu_a + e and Lambda = D / 2 + sum_i delta_i e_i ~
N(D / 2, D).

Neither rival is the unit.  What the fits leave carries model error that is correlated over
many numbers (a slow thermal mismatch spans many dwells), so the spread of
sum_i delta_i e_i is not D: it is the long-run variance of the scores z_i = delta_i e_i,
estimated from the residual e of the favoured rival with the Bartlett kernel of Newey and
West (1987, Econometrica 55(3) 703),

    V_run = sum_{|k| <= L} (1 - |k| / (L + 1)) sum_i z_i z_{i+k},

per run and group of channels whose numbers share their times (the scores of the dwell
means of the gyro and the accelerometers added number by number, and those of the three
thermometers: one thermal mismatch read by three thermometers is one piece of evidence,
not three; the runs are independent, and so are taken the two groups), with the bandwidth
of Andrews (1991, Econometrica 59(3) 817, eq. 6.4, the AR(1) plug-in of the Bartlett
kernel): L = 1.1447 (alpha n)^(1/3), alpha = 4 rho^2 / ((1 - rho)^2 (1 + rho)^2), rho the
lag-1 autocorrelation of the scores pooled over the runs and groups.  The
variance counted is V = max(D, sum V_run): never less than the sensors' own noise.

A rival with more free numbers fits the runs it was fitted to better even when they add
nothing: by k / 2 in expectation (Wilks 1938), and by k in Akaike's (1974) correction of
the log-likelihood, which Vuong (1989, Econometrica 57(2) 307, sec. 5) applies to his test
of non-nested models.  Here the price is a handicap only: the rival with k more numbers
must beat the other by k more, while having fewer numbers wins nothing by itself (Vuong's
correction would name the smaller rival where the runs cannot tell the two apart; here
that stays a tie, and a designed run is the way out).  With p = k_a - k_b,

    Lambda_adj = max(Lambda - max(p, 0), 0)    for Lambda >= 0 (the runs lean to a),
    Lambda_adj = min(Lambda + max(-p, 0), 0)   for Lambda < 0 (to b),
    Z = Lambda_adj / sqrt(V),

Vuong's statistic with a variance robust to the residual's autocorrelation: N(0, 1) when
the two rivals are equally close to the unit.

The long-run variance is written here rather than taken from statsmodels
(``statsmodels.stats.sandwich_covariance``): that is a heavy dependency for a 20-line
estimator on per-run sums of scores.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .predict import Prediction

__all__ = ["Evidence", "evidence", "bartlett_bandwidth", "long_run_variance"]

#: Largest lag-1 autocorrelation the bandwidth rule takes (the rule diverges at 1).
_RHO_MAX = 0.97


def bartlett_bandwidth(rho: float, n: int) -> int:
    """Andrews' (1991) AR(1) plug-in bandwidth L of the Bartlett kernel for ``n`` scores
    whose residual has lag-1 autocorrelation ``rho`` (module docstring); 0 for rho <= 0,
    at most n - 1."""
    rho = min(float(rho), _RHO_MAX)
    if not rho > 0.0 or n < 2:
        return 0
    alpha = 4.0 * rho ** 2 / ((1.0 - rho) ** 2 * (1.0 + rho) ** 2)
    return int(min(n - 1, math.ceil(1.1447 * (alpha * n) ** (1.0 / 3.0))))


def long_run_variance(z: np.ndarray, bandwidth: int) -> float:
    """The Bartlett-weighted long-run variance of the sum of the scores ``z`` (module
    docstring): the variance of sum(z), uncentred, lags up to ``bandwidth``."""
    z = np.asarray(z, dtype=float)
    v = float(z @ z)
    for k in range(1, min(int(bandwidth), z.size - 1) + 1):
        v += 2.0 * (1.0 - k / (bandwidth + 1.0)) * float(z[:-k] @ z[k:])
    return max(v, 0.0)


@dataclass(frozen=True)
class Evidence:
    """The runs' evidence between rivals a and b (module docstring)."""

    llr: float
    """Lambda: log-likelihood ratio of a over b."""
    d2: float
    """D: squared separation of the two fitted predictions [noise variances]."""
    price: float
    """p = k_a - k_b: how many more numbers a fitted than b."""
    variance: float
    """V: the long-run variance of Lambda counted (at least D)."""
    by_channel: dict[str, float]
    """Lambda of each channel alone."""

    @property
    def adjusted(self) -> float:
        """Lambda_adj: Lambda less the price of the numbers the rival it leans to fits
        beyond the other (module docstring); its sign is the lean of the runs, 0 when the
        price takes it all."""
        if self.llr >= 0.0:
            return max(self.llr - max(self.price, 0.0), 0.0)
        return min(self.llr + max(-self.price, 0.0), 0.0)

    @property
    def z(self) -> float:
        """Vuong's statistic Lambda_adj / sqrt(V); 0 when the rivals predict alike."""
        return self.adjusted / math.sqrt(self.variance) if self.variance > 0.0 else 0.0


def _whitened(y, mu, w):
    """P (y - mu) / sigma of one channel and run (``w`` = 1 / sigma)."""
    r = (y - mu) * w
    return r - w * ((w @ r) / (w @ w))


def _grids(run: Prediction, channels: Sequence[str]) -> list[list[str]]:
    """The channels of one run grouped by the times of their numbers (the dwell means share
    the dwells, the thermometers their reading times)."""
    groups: list[list[str]] = []
    for c in channels:
        t = np.asarray(run.time_s.get(c, ()), dtype=float)
        for g in groups:
            if np.array_equal(np.asarray(run.time_s.get(g[0], ()), dtype=float), t):
                g.append(c)
                break
        else:
            groups.append([c])
    return groups


def evidence(measured: Sequence[Prediction], mu_a: Sequence[Prediction],
             mu_b: Sequence[Prediction], sigma: Sequence[dict[str, np.ndarray]],
             channels: Sequence[str], price: float = 0.0) -> Evidence:
    """The evidence of the runs ``measured`` between the predictions ``mu_a`` and ``mu_b``
    of each run, in the noise ``sigma`` (module docstring); ``price`` = k_a - k_b.

    The channels whose numbers share their times in a run (the dwell means, the
    thermometers) add their scores number by number before the long-run variance, so that
    model error common to them (one thermal mismatch read by three thermometers) is counted
    once with its correlation, not as independent evidence."""
    by = {c: 0.0 for c in channels}
    d2 = 0.0
    score_sets: dict[str, list[np.ndarray]] = {"a": [], "b": []}
    for yr, ar, br, sr in zip(measured, mu_a, mu_b, sigma):
        for group in _grids(yr, channels):
            n = np.asarray(yr.values[group[0]]).size
            z = {"a": np.zeros(n), "b": np.zeros(n)}
            for c in group:
                y, a, b = (np.asarray(p.values[c], dtype=float) for p in (yr, ar, br))
                ok = np.isfinite(y) & np.isfinite(a) & np.isfinite(b)
                if not ok.any():
                    continue
                w = 1.0 / np.maximum(np.asarray(sr[c], dtype=float)[ok], 1e-300)
                ra, rb = _whitened(y[ok], a[ok], w), _whitened(y[ok], b[ok], w)
                d = _whitened(a[ok], b[ok], w)
                by[c] += 0.5 * float(rb @ rb - ra @ ra)
                d2 += float(d @ d)
                z["a"][ok] += d * ra
                z["b"][ok] += d * rb
            for key in z:
                score_sets[key].append(z[key])
    llr = float(sum(by.values()))
    favoured = "a" if llr >= 0.0 else "b"
    scores = score_sets[favoured]
    ss = sum(float(z @ z) for z in scores)
    lag = sum(float(z[:-1] @ z[1:]) for z in scores)
    rho = lag / ss if ss > 0.0 else 0.0
    v = sum(long_run_variance(z, bartlett_bandwidth(rho, z.size)) for z in scores)
    return Evidence(llr, d2, float(price), max(d2, v), by)
