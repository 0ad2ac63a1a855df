"""The noise a separation is counted in: the sensors' own, raised to what the runs show.

The sensor noise of :func:`nfs.rivals.predict.noise_sigma` is white and ideal.  What a fit
meets on real runs is more: the rivals' residuals on the runs taken carry model error
(neither rival is the unit) and are correlated from one number to the next (a slow
thermal mismatch spans many dwells).  A separation counted in ideal noise would call a
difference decisive that the runs taken already show and the diagnosis could not use.

So each channel's noise is scaled by the excess the runs show (a per-channel factor f_c >= 1):
for each rival, the residual of its fitted prediction on every run taken, whitened by the
sensor noise, with a constant per run removed (the nuisance of
:mod:`nfs.rivals.separation`), gives the mean square s^2 and the lag-1 autocorrelation rho
(pooled within runs, clipped to [0, 0.95]); an AR(1) residual of variance s^2 carries as
much information as white noise of variance s^2 (1 + rho) / (1 - rho) (the effective
sample size n (1 - rho) / (1 + rho): Bayley and Hammersley 1946, J. R. Stat. Soc. Suppl.
8(2) 184), so

    f_c^2 = max(1, mean over rivals of s^2 (1 + rho) / (1 - rho)).

The same factors count the separation of the runs taken and of the proposed run, so a tie on
the runs taken reads as a separation below the margin and the proposed run has to do better
than those runs did.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .predict import CHANNELS, Prediction
from .separation import RivalPrediction

__all__ = ["excess_factors", "scaled"]

_RHO_MAX = 0.95


def excess_factors(measured: Sequence[Prediction], preds: Sequence[RivalPrediction],
                   sigma: Sequence[dict[str, np.ndarray]]) -> dict[str, float]:
    """f_c per channel (module docstring) from the runs' numbers ``measured``
    (:func:`nfs.rivals.predict.reduce_run`), each rival's fitted predictions of them and
    their sensor noise ``sigma``."""
    out = {}
    for c in CHANNELS:
        ratios = []
        for p in preds:
            ss, lag, n = 0.0, 0.0, 0
            for m, q, sg in zip(measured, p.mean, sigma):
                if c not in m.values or c not in q.values:
                    continue
                w = 1.0 / np.maximum(sg[c], 1e-300)
                r = (m.values[c] - q.values[c]) * w
                ok = np.isfinite(r)
                r, w = r[ok], w[ok]
                if r.size < 3:
                    continue
                # the run's constant projected out in the 1/sigma^2 metric, as the
                # separation's nuisance is
                r = r - w * (w @ r) / (w @ w)
                ss += float(r @ r)
                lag += float(r[:-1] @ r[1:])
                n += r.size
            if n == 0 or ss == 0.0:
                continue
            s2 = ss / n
            rho = min(max(lag / ss, 0.0), _RHO_MAX)
            ratios.append(s2 * (1.0 + rho) / (1.0 - rho))
        out[c] = math.sqrt(max(1.0, float(np.mean(ratios)))) if ratios else 1.0
    return out


def scaled(sigma: dict[str, np.ndarray], factors: dict[str, float]) -> dict[str, np.ndarray]:
    """The noise ``sigma`` with every channel scaled by its factor."""
    return {c: v * factors.get(c, 1.0) for c, v in sigma.items()}

