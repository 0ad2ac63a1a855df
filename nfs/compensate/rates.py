"""Temperature rates dT/dt of the thermometers, centred (offline) or within a horizon.

A finite difference of a thermometer quantised to q = 0.0625 K is a train of spikes
(+-q / dt = +-3.75 K/min at 1 Hz): every rate here is the derivative of a least-squares
polynomial fitted over a window of W samples (Savitzky & Golay 1964, Anal. Chem. 36(8),
1627), as SciPy computes it (``scipy.signal.savgol_coeffs``).  For white reading noise of
standard deviation sigma [K] and sample step dt [s] the slope of a linear fit evaluated at
the window's centre has the standard deviation (the least-squares slope's variance
sigma^2 / sum_k (t_k - t_mean)^2, with sum_k (t_k - t_mean)^2 = dt^2 W (W^2 - 1) / 12 for W
equally spaced samples)

    sigma_r = sigma sqrt(12 / (W (W^2 - 1))) / dt       [K/s]

and the same fit evaluated at the window's end as well (a linear fit's slope does not
depend on where it is read).  But read at the end, a linear fit returns the slope at the
window's centre, (W - 1) dt / 2 earlier: a lag.  A quadratic fit read at its end has no lag
for a quadratic signal, at 4x the noise (the root sum of squares of the coefficients of
``savgol_coeffs(W, 2, deriv=1, pos=W-1)`` is 3.97-4.03 sigma_r for W from 61 to 601).

The window of sample i is chosen by one rule: W samples, as nearly centred on i as the
samples 0 .. h_i allow, h_i being the horizon of :mod:`nfs.compensate.modes` (fewer than W
when only h_i + 1 < W samples exist, with the polynomial order lowered to fit: a single
sample gives the rate 0 of a constant).  With W = 121 s and order 2 (the FOG start-up paper's rates,
averaging 2 min of quantisation steps; the centred quadratic's derivative is the centred
linear fit's slope, sigma_r):

- offline (h_i = n - 1): the centred window, and at the run's ends the first or last window
  read off-centre: exactly ``scipy.signal.savgol_filter(mode="interp")``, which computes it;
- cycle (h_i = the last sample of i's north-finding cycle): the centred window wherever it
  ends inside the cycle, which is every sample but the last (W - 1) / 2 of a cycle (and, as
  offline, the first (W - 1) / 2 of the run, read off the first window, which ends inside
  the first cycle); those read the cycle's last W samples off-centre.  Measured over five
  training seeds and six methods this scores as the offline filter (0.0094 against
  0.0093 deg mean start-up heading RMSE); reading a linear fit off-centre instead (lag for
  less noise) moved BP from 0.0124 to 0.0096 deg and SSA-SVR from 0.0095 to 0.0130 deg.
  Outside every cycle the rate is the causal one.
- causal: not a window (a trailing window has only the samples since power-on in the first
  minutes, which decide the start-up): the Kalman filter of :mod:`nfs.compensate.kalman_rate`.

Missing samples (NaN) are held at the last finite reading within a horizon (no
interpolation towards a later sample); before a thermometer's first finite reading the rate
is NaN.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.signal import lfilter, savgol_coeffs, savgol_filter

__all__ = [
    "rate_k_per_min",
    "savgol_rate_k_per_min",
    "window_samples",
    "windowed_rate_k_per_min",
]


def window_samples(window_s: float, time_s: np.ndarray) -> tuple[int, float]:
    """The odd number of samples W of a window of ``window_s`` and the sample step dt.

    Parameters
    ----------
    window_s : float
        Window length [s].
    time_s : ndarray
        Sample times [s]; their median step is the step used (the grid is taken as uniform,
        as a thermometer channel sampled with the gyro is).

    Returns
    -------
    (int, float)
        W (odd, at least 1) and dt [s].
    """
    t = np.asarray(time_s, dtype=float)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    return max(1, round(window_s / dt) | 1), dt


def savgol_rate_k_per_min(temp_c: np.ndarray, time_s: np.ndarray, window_s: float = 121.0,
                          polyorder: int = 2) -> np.ndarray:
    """dT/dt [K/min] by the centred Savitzky-Golay derivative over the whole run (offline).

    A polynomial of order ``polyorder`` over a centred window of ``window_s`` is
    differentiated at its centre; the first and last (W - 1) / 2 samples use the first and
    last window (``mode="interp"``), so the rate of the first minute uses the second
    minute's readings.  NaN samples are interpolated from their neighbours (both sides).

    Parameters
    ----------
    temp_c : ndarray
        Thermometer reading [degC].
    time_s : ndarray
        Sample times [s].
    window_s : float
        Window length [s].
    polyorder : int
        Order of the local polynomial.

    Returns
    -------
    ndarray
        dT/dt [K/min] at every sample.
    """
    t = np.asarray(time_s, dtype=float)
    x = np.asarray(temp_c, dtype=float)
    ok = np.isfinite(x)
    if not ok.all():
        if ok.sum() < 2:
            return np.full_like(x, np.nan)
        x = np.interp(t, t[ok], x[ok])
    w, dt = window_samples(window_s, t)
    w = min(w, x.size if x.size % 2 else x.size - 1)
    if w <= polyorder:
        return np.gradient(x, t) * 60.0
    return savgol_filter(x, w, polyorder, deriv=1, delta=dt, mode="interp") * 60.0


@lru_cache(maxsize=4096)
def _slope_coefficients(n: int, polyorder: int, pos: int) -> np.ndarray:
    """Weights c with dT/dt(pos) = c . x[0:n] / dt: the derivative at sample ``pos`` of the
    least-squares polynomial of order min(polyorder, n - 1) through n samples."""
    order = min(polyorder, n - 1)
    if order < 1:
        return np.zeros(n)
    c = savgol_coeffs(n, order, deriv=1, delta=1.0, pos=pos, use="dot")
    c.flags.writeable = False
    return c


def windowed_rate_k_per_min(temp_c: np.ndarray, time_s: np.ndarray, horizon: np.ndarray,
                            window_s: float, polyorder: int) -> np.ndarray:
    """dT/dt [K/min] of a local polynomial fitted to samples 0 .. h_i only, at every sample i.

    The window of sample i holds m_i = min(W, h'_i + 1) samples starting at
    s_i = clip(i - (W - 1) / 2, 0, h'_i - m_i + 1) and is read at position i - s_i (the rule
    of the module docstring), where h'_i is the horizon counted from the thermometer's first
    finite reading.

    Parameters
    ----------
    temp_c : ndarray
        Thermometer reading [degC].
    time_s : ndarray
        Sample times [s] (uniform step).
    horizon : ndarray of int
        h_i >= i, the last sample sample i may use (:func:`nfs.compensate.modes.horizon_index`).
    window_s : float
        Window length [s].
    polyorder : int
        Order of the local polynomial.

    Returns
    -------
    ndarray
        dT/dt [K/min]; NaN before the first finite reading.
    """
    x = np.asarray(temp_c, dtype=float)
    t = np.asarray(time_s, dtype=float)
    h = np.asarray(horizon, dtype=np.intp)
    n = x.size
    if h.shape != x.shape or np.any(h < np.arange(n)) or (n and h.max() >= n):
        raise ValueError("horizon must hold, for every sample i, an index h_i in [i, n)")
    out = np.full(n, np.nan)
    finite = np.flatnonzero(np.isfinite(x))
    if finite.size == 0:
        return out
    f0 = int(finite[0])
    # hold the last finite reading over a gap: causal at every horizon
    held = np.maximum.accumulate(np.where(np.isfinite(x), np.arange(n), f0))
    x = x[held][f0:]
    hz = h[f0:] - f0
    w, dt = window_samples(window_s, t)
    i = np.arange(x.size)
    m = np.minimum(w, hz + 1)
    s = np.clip(i - (w - 1) // 2, 0, hz - m + 1)
    pos = i - s
    rate = np.empty(x.size)
    # Samples share a filter when they share (m, pos).  SciPy has no filter whose window
    # changes from sample to sample, so each group's windows are gathered here; the largest
    # group (the steady filter of the mode) is one fixed FIR run by lfilter.
    key = m * (w + 1) + pos
    keys, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    big = int(np.argmax(counts))
    order = np.argsort(inverse, kind="stable")
    bounds = np.concatenate(([0], np.cumsum(counts)))
    for g, k in enumerate(keys):
        sel = order[bounds[g]:bounds[g + 1]]
        mg, pg = int(k // (w + 1)), int(k % (w + 1))
        c = _slope_coefficients(mg, polyorder, pg)
        if g == big:
            # lfilter(b) gives y[j] = sum_k b[k] x[j - k]: with b = c reversed, y[j] is the
            # window x[j - m + 1 .. j] weighted by c, i.e. the window starting at j - m + 1.
            y = lfilter(c[::-1], 1.0, x)
            rate[sel] = y[s[sel] + mg - 1]
        else:
            windows = np.lib.stride_tricks.sliding_window_view(x, mg)
            rate[sel] = windows[s[sel]] @ c
    out[f0:] = rate * (60.0 / dt)
    return out


def rate_k_per_min(temp_c: np.ndarray, time_s: np.ndarray, window_s: float = 121.0,
                   polyorder: int = 2, *, horizon: np.ndarray | None = None) -> np.ndarray:
    """dT/dt [K/min] of a thermometer by a local polynomial: centred, or within a horizon.

    Parameters
    ----------
    temp_c : ndarray
        Thermometer reading [degC].
    time_s : ndarray
        Sample times [s].
    window_s : float
        Window length [s].
    polyorder : int
        Order of the local polynomial.
    horizon : ndarray of int, optional
        h_i, the last sample the rate at i may use; None: the whole run, the offline
        :func:`savgol_rate_k_per_min`.

    Returns
    -------
    ndarray
        dT/dt [K/min] at every sample.
    """
    if horizon is None:
        return savgol_rate_k_per_min(temp_c, time_s, window_s, polyorder)
    return windowed_rate_k_per_min(temp_c, time_s, horizon, window_s, polyorder)
