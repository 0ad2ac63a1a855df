"""How far apart two rivals' predictions of a run are, in units of the measurement noise.

For rivals a and b, the numbers a run records (:mod:`nfs.rivals.predict`) are y = mu_a + e
under a, y = mu_b + e under b, with e ~ N(0, S), S = diag(sigma^2) the sensor noise.  Each
rival's prediction is itself uncertain: its parameters come from a fit
(:meth:`nfs.rivals.models.Rival.draws`), which spreads mu_a by the covariance
V_a = U_a U_a^T (U_a: the draws' deviations from the fitted prediction over sqrt(K - 1)).
With C the nuisance directions every rival re-fits freely on a new run (a constant per
channel and run: a turn-on bias, a thermometer offset, an accelerometer bias), the
separation is the Mahalanobis distance of the difference d = mu_a - mu_b,

    D = d^T P^T (S + P V P^T)^-1 P d,     V = V_a + V_b, P: the projection out of span(C)
                                           in the metric S^-1,

(the nuisance constants integrated out under a flat prior),

computed whitened (z = d / sigma, M = [U_a U_b] / sigma, both projected) with the
Woodbury identity: D = |z|^2 - (M^T z)^T (I + M^T M)^-1 (M^T z).  It is the
Buzzi-Ferraris and Forzatti (1983) divergence with parameter uncertainty, and for Gaussian
rivals the expected log-likelihood ratio is E_a[log L_a / L_b] = D / 2 (the Kullback-Leibler
divergence of two normals of one covariance, which KL-optimal designs maximise: Lopez-Fidalgo,
Tommasi and Trandafir 2007, J. R. Stat. Soc. B 69(2) 231).  The separation is reported as
sqrt(D), in noise standard deviations: a test of a against b at ``margin`` standard
deviations (default 3) needs D >= margin^2.

Closed forms (tests/design/test_separation.py): without draws and nuisance, D is
sum (d_i / sigma_i)^2; with a constant per channel free, sum ((d_i - dbar) / sigma)^2 for
equal sigma; a difference along one draw direction u of length |z| gives
|z|^2 / (1 + |u|^2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .predict import CHANNELS, Prediction

__all__ = ["RivalPrediction", "Separation", "separation", "MARGIN_SIGMA"]

#: Default margin of a design: a 3-sigma test between every pair of rivals.
MARGIN_SIGMA = 3.0


@dataclass(frozen=True)
class RivalPrediction:
    """A rival's predictions of some runs: at its fitted parameters and at K draws."""

    mean: list[Prediction]
    """One prediction per run, at the fitted parameters."""
    draws: list[list[Prediction]] = field(default_factory=list)
    """draws[k][r]: draw k's prediction of run r."""

    def until(self, t_end_s: float) -> "RivalPrediction":
        """The predictions of a run stopped at ``t_end_s`` (one run only)."""
        return RivalPrediction([p.until(t_end_s) for p in self.mean],
                               [[p.until(t_end_s) for p in d] for d in self.draws])


@dataclass(frozen=True)
class Separation:
    """sqrt(D) of a pair of rivals, in noise standard deviations (module docstring)."""

    sigma: float
    """sqrt(D) over every channel together."""
    by_channel: dict[str, float]
    """sqrt(D) of each channel alone."""
    n_numbers: int
    """Recorded numbers compared."""

    @property
    def expected_llr(self) -> float:
        """E[log likelihood ratio] = D / 2 for the true rival against the other."""
        return 0.5 * self.sigma ** 2

    def to_dict(self) -> dict:
        return {"sigma": self.sigma, "expected_log_likelihood_ratio": self.expected_llr,
                "by_channel": dict(self.by_channel), "n_numbers": self.n_numbers}


def _stack(preds: Sequence[Prediction], channels: Sequence[str]) -> np.ndarray:
    return np.concatenate([p.values[c] for p in preds for c in channels]) if preds else \
        np.zeros(0)


def _groups(preds: Sequence[Prediction], channels: Sequence[str]) -> np.ndarray:
    """Nuisance group (a constant per channel and run) of every stacked number."""
    out, g = [], 0
    for p in preds:
        for c in channels:
            out.append(np.full(p.values[c].size, g))
            g += 1
    return np.concatenate(out) if out else np.zeros(0, dtype=int)


def _distance(z: np.ndarray, m: np.ndarray) -> float:
    """D of the whitened, projected difference z and draw directions m (n, k): the
    Woodbury form |z|^2 - (m^T z)^T (I + m^T m)^-1 (m^T z)."""
    if z.size == 0:
        return 0.0
    if m.size == 0:
        return float(z @ z)
    mz = m.T @ z
    inner = np.eye(m.shape[1]) + m.T @ m
    return float(max(z @ z - mz @ np.linalg.solve(inner, mz), 0.0))


def _project(x: np.ndarray, w: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """Whitened x with each group's constant projected out: x - w_i sum_g(w x) / sum_g w^2,
    w = 1/sigma (x: (n,) or (n, k))."""
    n_g = int(groups.max()) + 1 if groups.size else 0
    ww = np.bincount(groups, weights=w * w, minlength=n_g)
    if x.ndim == 1:
        s = np.bincount(groups, weights=w * x, minlength=n_g)
        return x - w * (s / np.where(ww > 0, ww, 1.0))[groups]
    out = np.empty_like(x)
    for j in range(x.shape[1]):
        s = np.bincount(groups, weights=w * x[:, j], minlength=n_g)
        out[:, j] = x[:, j] - w * (s / np.where(ww > 0, ww, 1.0))[groups]
    return out


def _whitened(a: RivalPrediction, b: RivalPrediction, sigma: Sequence[dict[str, np.ndarray]],
              channels: Sequence[str], nuisance: bool) -> tuple[np.ndarray, np.ndarray]:
    s = np.concatenate([np.maximum(sg[c], 1e-300) for sg in sigma for c in channels])
    w = 1.0 / s
    z = (_stack(a.mean, channels) - _stack(b.mean, channels)) * w
    cols = []
    for r in (a, b):
        k = len(r.draws)
        if k < 2:
            continue
        base = _stack(r.mean, channels)
        for d in r.draws:
            cols.append((_stack(d, channels) - base) * w / math.sqrt(k - 1))
    m = np.column_stack(cols) if cols else np.zeros((z.size, 0))
    if nuisance and z.size:
        g = _groups(a.mean, channels)
        z = _project(z, w, g)
        m = _project(m, w, g) if m.size else m
    return z, m


def separation(a: RivalPrediction, b: RivalPrediction,
               sigma: Sequence[dict[str, np.ndarray]], *,
               channels: Sequence[str] = CHANNELS, nuisance: bool = True) -> Separation:
    """sqrt(D) of rivals ``a`` and ``b`` (module docstring) on the runs they both predict;
    ``sigma[r]``: the noise of run r's numbers by channel (:func:`noise_sigma`)."""
    chans = [c for c in channels if all(c in p.values for p in a.mean)]
    z, m = _whitened(a, b, sigma, chans, nuisance)
    total = math.sqrt(_distance(z, m))
    by = {}
    for c in chans:
        zc, mc = _whitened(a, b, sigma, [c], nuisance)
        by[c] = math.sqrt(_distance(zc, mc))
    return Separation(total, by, int(z.size))
