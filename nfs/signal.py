"""Small signal-processing pieces shared by the sensors and the effects."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

__all__ = ["first_order_lag", "uniform_steps"]


def uniform_steps(dt: np.ndarray) -> bool:
    """True when every step of ``dt`` is within 1e-9 of the first (np.allclose's relative test
    without its overhead: it runs for every thermometer of every residual evaluation of a
    fit)."""
    return bool(np.abs(dt - dt[0]).max() <= 1e-9 * abs(dt[0]))


def first_order_lag(x: np.ndarray, time_s: np.ndarray, tau_s: float) -> np.ndarray:
    """First-order lag tau dy/dt = x - y, exact for an input held between samples.

    y[k+1] = a y[k] + (1 - a) x[k],  a = exp(-(t[k+1] - t[k]) / tau)  (zero-order hold),
    starting in equilibrium y[0] = x[0] (the instrument was soaked before power-on).

    Parameters
    ----------
    x : ndarray
        Input samples (e.g. a node temperature [degC]), along the last axis (a stack of
        records is filtered row by row).
    time_s : ndarray
        Sample times [s], strictly increasing.
    tau_s : float
        Time constant tau [s]; 0 returns ``x`` unchanged.
    """
    x = np.asarray(x, dtype=float)
    if tau_s < 0:
        raise ValueError(f"lag time constant must be >= 0, got {tau_s}")
    if tau_s == 0 or x.shape[-1] < 2:
        return x.copy()
    dt = np.diff(np.asarray(time_s, dtype=float))
    if uniform_steps(dt):
        a = np.exp(-dt[0] / tau_s)
        # the filter's state in equilibrium at x[0] is x[0] itself (y = z, z' = (1-a) x + a y;
        # scipy.signal.lfilter_zi gives exactly 1 for this filter, at 20x the cost)
        y, _ = lfilter([0.0, 1.0 - a], [1.0, -a], x, axis=-1, zi=x[..., :1])
        return y
    # Non-uniform sampling: lfilter has no time-varying coefficients, so step by hand.
    a = np.exp(-dt / tau_s)
    y = np.empty_like(x)
    y[..., 0] = x[..., 0]
    for k in range(len(dt)):
        y[..., k + 1] = a[k] * y[..., k] + (1.0 - a[k]) * x[..., k]
    return y
