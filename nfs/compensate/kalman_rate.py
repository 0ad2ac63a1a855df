"""The causal temperature rate: a steady-state Kalman filter of a thermometer's T and dT/dt.

Model (the continuous white-noise acceleration model, Bar-Shalom, Li & Kirubarajan 2001,
*Estimation with Applications to Tracking and Navigation*, section 6.2.2), sampled every
dt [s]:

    x_k = [T_k, r_k]           thermometer temperature [K] and its rate [K/s]
    x_k = F x_{k-1} + w_k,     F = [[1, dt], [0, 1]],
                               Q = q [[dt^3/3, dt^2/2], [dt^2/2, dt]]
    y_k = T_k + v_k,           R = quantum^2 / 12 + sigma^2

with q [K^2/s^3] the power spectral density of the rate's random acceleration, and R [K^2]
the reading noise: the uniform quantisation noise of a quantum of 0.0625 K (quantum^2 / 12,
the pseudo-quantisation-noise model of Widrow & Kollar 2008, *Quantization Noise*) plus
sigma = 0.01 K of white noise (the default thermometer; docs/physics.md section 2 gives quantum
0.01-0.0625 K, sigma 0.005-0.02 K).  Only q / R sets the gain.
The steady-state gain K solves the discrete algebraic Riccati equation
(``scipy.linalg.solve_discrete_are``); the filter x_k = (I - K H) F x_{k-1} + K y_k is then a
fixed second-order IIR filter from the readings to the rate (``scipy.signal.ss2tf``,
``scipy.signal.lfilter``).  It starts from the soak: T = the first reading, r = 0 (the unit
sat unpowered at the chamber temperature until power-on), and uses no sample after k.

Why this filter and this q: the causal rates compared on the default scenario (trailing
linear and quadratic fits, growing windows, this filter at three q) are in the user guide
(docs/compensation.md, "Design measurements"); q = 3e-9 K^2/s^3 scored best there.

The first north-finding cycle after power-on carries most of the start-up error, so the
first minutes decide: a trailing window has only the samples since power-on there (a
2-sample slope of a 0.0625 K quantum is +-3.75 K/min), while the filter starts from the
soak's rate 0 and follows the warm-up within its memory; a quadratic read at its window's
end has no lag but 4x the noise of a linear fit, which the nonlinear regressors (SVR, RBF,
BP) turn into drift steps between dwells.  At q = 3e-9 K^2/s^3 the filter's rate has, for
white reading noise, a standard deviation of 0.0086 K/min and lags a constant acceleration
by 28 s (a trailing linear fit of 57 s has the same lag at 0.0100 K/min); its double pole is
0.964 per 1 s sample, so a ramp's rate is exact to 1e-9 K/min about 560 s after the start.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.linalg import solve_discrete_are
from scipy.signal import lfilter, ss2tf

__all__ = ["CAUSAL_RATE", "KalmanRate", "kalman_rate_filter", "kalman_rate_k_per_min"]


@dataclass(frozen=True)
class KalmanRate:
    """The constant-velocity Kalman filter of the causal rate features."""

    accel_psd_k2_per_s3: float = 3e-9
    """q, power spectral density of the rate's random acceleration [K^2/s^3]."""
    quantum_c: float = 0.0625
    """Quantisation step of the thermometer [K] (default thermometer)."""
    noise_c: float = 0.01
    """White reading noise, one standard deviation [K] (default thermometer)."""

    @property
    def reading_variance_k2(self) -> float:
        """R = quantum^2 / 12 + noise^2 [K^2]."""
        return self.quantum_c ** 2 / 12.0 + self.noise_c ** 2


#: The causal rate filter of the feature modes (the choice of q: module docstring).
CAUSAL_RATE = KalmanRate()


@lru_cache(maxsize=64)
def kalman_rate_filter(dt_s: float, accel_psd_k2_per_s3: float, reading_variance_k2: float
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The steady-state filter from readings [K] to the rate estimate [K/s] as (b, a).

    Parameters
    ----------
    dt_s : float
        Sample step [s].
    accel_psd_k2_per_s3 : float
        q [K^2/s^3].
    reading_variance_k2 : float
        R [K^2].

    Returns
    -------
    (ndarray, ndarray)
        Numerator and denominator for ``scipy.signal.lfilter``.
    """
    F = np.array([[1.0, dt_s], [0.0, 1.0]])
    H = np.array([[1.0, 0.0]])
    Q = accel_psd_k2_per_s3 * np.array([[dt_s ** 3 / 3.0, dt_s ** 2 / 2.0],
                                         [dt_s ** 2 / 2.0, dt_s]])
    R = np.array([[reading_variance_k2]])
    P = solve_discrete_are(F.T, H.T, Q, R)           # prior covariance in steady state
    K = P @ H.T / (H @ P @ H.T + R)
    A = (np.eye(2) - K @ H) @ F
    b, a = ss2tf(A, K, np.array([[0.0, 1.0]]), np.zeros((1, 1)))
    return b[0], a


def kalman_rate_k_per_min(temp_c: np.ndarray, time_s: np.ndarray,
                          rate: KalmanRate = CAUSAL_RATE) -> np.ndarray:
    """dT/dt [K/min] of a thermometer from its readings up to each sample only.

    Parameters
    ----------
    temp_c : ndarray
        Thermometer reading [degC].
    time_s : ndarray
        Sample times [s] (uniform step: the median step is used).
    rate : KalmanRate
        The filter's q and reading noise.

    Returns
    -------
    ndarray
        dT/dt [K/min]; NaN before the first finite reading.  A missing reading holds the
        last finite one (no interpolation towards a later sample).
    """
    x = np.asarray(temp_c, dtype=float)
    t = np.asarray(time_s, dtype=float)
    out = np.full(x.size, np.nan)
    finite = np.flatnonzero(np.isfinite(x))
    if finite.size == 0:
        return out
    f0 = int(finite[0])
    held = np.maximum.accumulate(np.where(np.isfinite(x), np.arange(x.size), f0))
    y = x[held][f0:]
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    b, a = kalman_rate_filter(dt, rate.accel_psd_k2_per_s3, rate.reading_variance_k2)
    # The filter is linear and maps the constant state [y0, 0] onto itself, so starting it
    # at rest on y - y0 starts it at the soak state [y0, 0].
    out[f0:] = lfilter(b, a, y - y[0]) * 60.0
    return out
