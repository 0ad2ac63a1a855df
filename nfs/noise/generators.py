"""Noise generators: white noise, and the gyro's angle random walk, bias instability and rate
random walk (IEEE Std 952-2020, Annex C).

Every function draws from the ``rng`` (a :class:`numpy.random.Generator`) it is given and from
nothing else, so the same seed gives the same bytes.  Units live in the names: rates in
[deg/h], time in [s], sample rates in [Hz].

Allan-deviation signatures of the three gyro terms, rate data in [deg/h], tau in [s]
(IEEE Std 952-2020 Annex C; El-Sheimy, Hou & Niu 2008, IEEE TIM 57(1) 140-149; not yet
checked against the texts down to equation number)::

    angle random walk N [deg/sqrt(h)]    sigma(tau) = 60 N / sqrt(tau)          slope -1/2
    bias instability  B [deg/h]          sigma(tau) = sqrt(2 ln2 / pi) B       slope  0
                                                    = 0.6643 B  (flicker floor)
    rate random walk  K [deg/h/sqrt(h)]  sigma(tau) = (K / 60) sqrt(tau / 3)    slope +1/2

(the factors 60 convert sqrt(h) to sqrt(s): 1 sqrt(h) = 60 sqrt(s); with tau in hours the
same lines read N / sqrt(tau_h) and K sqrt(tau_h / 3)).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.signal import lfilter

from nfs.errors import InputError
from nfs.noise.checks import check_n_samples, check_non_negative, check_positive, check_rng

__all__ = [
    "BI_FLOOR_FACTOR",
    "BI_POLES_PER_DECADE",
    "DEFAULT_CORRELATION_TIME_S",
    "GyroNoise",
    "angle_random_walk_noise_dph",
    "bias_instability_adev_dph",
    "bias_instability_band_s",
    "bias_instability_noise_dph",
    "bias_instability_poles",
    "check_bias_instability_times",
    "gyro_noise_dph",
    "rate_random_walk_noise_dph",
    "white_noise",
]

#: sqrt(2 ln 2 / pi) = 0.6643: the Allan deviation of flicker (1/f) rate noise of bias
#: instability B is this factor times B (IEEE Std 952-2020 Annex C; El-Sheimy et al. 2008).
BI_FLOOR_FACTOR: float = math.sqrt(2.0 * math.log(2.0) / math.pi)

#: Number of first-order Gauss-Markov processes per decade of correlation time in the
#: bias-instability construction (see :func:`bias_instability_noise_dph`).
BI_POLES_PER_DECADE: int = 1

#: Default longest correlation time T_c [s] of the bias-instability construction: the Allan
#: floor holds (within 5 %) up to T_c / 3 = 20 min, which covers a north-finding cycle and the
#: start-up stage's minute scales (docs/physics.md sections 1 and 5). (est.)
DEFAULT_CORRELATION_TIME_S: float = 3600.0

# The band where the floor of the sampled construction is within 5 % of 0.6643 B runs from
# _BAND_LO_SAMPLES / fs to T_c / _BAND_HI_DIVISOR: the worst deviation of the closed form
# (bias_instability_adev_dph) over that band is 4.7 % for every fs T_c from 100 to 1e6
# (300 log-spaced values checked); over 1/fs <= tau <= T_c it is 10.7 %.  T_c must be at
# least _MIN_TC_SAMPLES sample intervals so that the band spans more than a decade.
_BAND_LO_SAMPLES = 2.0
_BAND_HI_DIVISOR = 3.0
_MIN_TC_SAMPLES = 100.0


# --------------------------------------------------------------------------------------------
# white noise

def white_noise(n_samples: int, sample_rate_hz: float, density_per_rth_hz: float, *,
                rng: np.random.Generator,
                sided: Literal["one", "two"] = "one") -> np.ndarray:
    """White Gaussian noise of a given amplitude spectral density.

    Each sample stands for the average of the continuous noise over one sample interval
    (an integrating sensor), so the sampled noise is Allan-consistent:

    ============  ===============================  ==============================
    ``sided``     per-sample standard deviation    Allan deviation at tau [s]
    ============  ===============================  ==============================
    ``"one"``     density * sqrt(fs / 2)           density / sqrt(2 tau)
    ``"two"``     density * sqrt(fs)               density / sqrt(tau)
    ============  ===============================  ==============================

    ``"one"`` (default) reads the density as a one-sided amplitude spectral density, the
    data-sheet convention where the rms noise in a band 0..B is density * sqrt(B) (e.g. a QFA's
    20 ug/sqrt(Hz), docs/physics.md section 4): the rms over the Nyquist band fs/2 is the
    per-sample standard deviation.  ``"two"`` reads it as the square root of the two-sided
    PSD S over -fs/2..fs/2 (variance S fs), the IEEE Std 952 convention in which the angle
    random walk coefficient N is sqrt(S) and sigma_Allan(tau) = N / sqrt(tau)
    (IEEE Std 952-2020 Annex C).  A one-sided density D equals sqrt(2) times the two-sided one.

    Parameters
    ----------
    n_samples : int
        Number of samples [-], >= 0.
    sample_rate_hz : float
        Sample rate fs [Hz], > 0.
    density_per_rth_hz : float
        Amplitude spectral density [unit/sqrt(Hz)], >= 0; the output is in [unit].
    rng : numpy.random.Generator
        Source of every random draw (``n_samples`` standard normals).
    sided : {"one", "two"}
        Which convention ``density_per_rth_hz`` follows (see the table).

    Returns
    -------
    numpy.ndarray
        ``n_samples`` float64 values [unit], zero mean.
    """
    n = check_n_samples(n_samples)
    fs = check_positive("sample_rate_hz", sample_rate_hz)
    density = check_non_negative("density_per_rth_hz", density_per_rth_hz)
    rng = check_rng(rng)
    if sided == "one":
        std = density * math.sqrt(fs / 2.0)
    elif sided == "two":
        std = density * math.sqrt(fs)
    else:
        raise InputError(f"sided must be 'one' or 'two', got {sided!r}")
    return std * rng.standard_normal(n)


# --------------------------------------------------------------------------------------------
# gyro terms, one function per IEEE 952 term

def angle_random_walk_noise_dph(n_samples: int, sample_rate_hz: float,
                                arw_deg_per_rth_h: float, *,
                                rng: np.random.Generator) -> np.ndarray:
    """Angle random walk: white rate noise of coefficient N (IEEE Std 952-2020 Annex C).

    Per-sample standard deviation (N * 60) * sqrt(fs) [deg/h] (docs/physics.md section 3), so that
    sigma_Allan(tau) = 60 N / sqrt(tau) [deg/h] with tau in [s], i.e. N / sqrt(tau_h).  N is the
    square root of the two-sided rate PSD, (60 N)^2 [(deg/h)^2/Hz]: this is
    :func:`white_noise` with ``sided="two"`` and density 60 N [deg/h/sqrt(Hz)].

    Parameters
    ----------
    n_samples : int
        Number of samples [-].
    sample_rate_hz : float
        Sample rate fs [Hz].
    arw_deg_per_rth_h : float
        Angle random walk N [deg/sqrt(h)], >= 0 (docs/physics.md: 0.0003-0.001).
    rng : numpy.random.Generator
        Source of every random draw.

    Returns
    -------
    numpy.ndarray
        Rate noise [deg/h].
    """
    arw = check_non_negative("arw_deg_per_rth_h", arw_deg_per_rth_h)
    return white_noise(n_samples, sample_rate_hz, 60.0 * arw, rng=rng, sided="two")


@functools.lru_cache(maxsize=64)
def bias_instability_poles(sample_rate_hz: float,
                           correlation_time_s: float) -> tuple[np.ndarray, float]:
    """The first-order Gauss-Markov components of the bias-instability construction.

    Returns the correlation times T_k [s] (read-only array), log-spaced
    ``BI_POLES_PER_DECADE`` per decade from one sample interval 1/fs to T_c, and the variance
    of each component per B^2, q^2 / B^2 = ln(r) / pi [1] with r the ratio of neighbouring
    T_k (see :func:`bias_instability_noise_dph`).  The generator, the closed-form Allan
    deviation and the covariance of window means (:mod:`nfs.noise.covariance`) all build on
    these, so the three describe one process.  Kept per (fs, T_c), which every run of an
    instrument shares (np.geomspace costs a tenth of a default start-up's gyro noise).
    Arguments unchecked: pass them through :func:`check_bias_instability_times` first.

    Parameters
    ----------
    sample_rate_hz : float
        Sample rate fs [Hz], > 0.
    correlation_time_s : float
        Longest correlation time T_c [s], >= 100 sample intervals.
    """
    t_min = 1.0 / sample_rate_hz
    decades = math.log10(correlation_time_s / t_min)
    n_poles = max(2, math.ceil(BI_POLES_PER_DECADE * decades - 1e-9) + 1)
    times_s = np.geomspace(t_min, correlation_time_s, n_poles)
    times_s.flags.writeable = False
    ratio = (correlation_time_s / t_min) ** (1.0 / (n_poles - 1))
    return times_s, math.log(ratio) / math.pi


def check_bias_instability_times(sample_rate_hz: float,
                                 correlation_time_s: float) -> tuple[float, float]:
    """(fs [Hz], T_c [s]) as floats, both finite and > 0 and T_c at least 100 sample
    intervals (below that the flat Allan floor of the construction has no band to exist
    in), else an InputError naming the argument."""
    fs = check_positive("sample_rate_hz", sample_rate_hz)
    t_c = check_positive("correlation_time_s", correlation_time_s)
    shortest = _MIN_TC_SAMPLES / fs
    if t_c < shortest:
        raise InputError(
            f"correlation_time_s must be >= {_MIN_TC_SAMPLES:g} sample "
            f"intervals ({shortest:g} s at {fs:g} Hz) for the bias-instability floor to exist, "
            f"got {t_c!r}")
    return fs, t_c


def bias_instability_noise_dph(n_samples: int, sample_rate_hz: float,
                               bias_instability_dph: float, *,
                               correlation_time_s: float = DEFAULT_CORRELATION_TIME_S,
                               rng: np.random.Generator) -> np.ndarray:
    """Bias instability: approximate flicker (1/f) rate noise whose Allan deviation has the
    flat floor 0.6643 B (IEEE Std 952-2020 Annex C; El-Sheimy et al. 2008).

    Flicker rate noise has the two-sided PSD S(f) = B^2 / (2 pi f) and the Allan variance
    (2 ln 2 / pi) B^2 at every tau.  It is approximated by a sum of independent first-order
    Gauss-Markov processes (a standard construction of 1/f noise from relaxation processes;
    Keshner 1982, Proc. IEEE 70(3)) with correlation times T_k log-spaced, ``BI_POLES_PER_DECADE``
    per decade, from one sample interval 1/fs to ``correlation_time_s`` = T_c, neighbours a
    ratio r apart.  Component k has the PSD 2 q^2 T_k / (1 + (2 pi f T_k)^2); summing over
    ln T with the density 1 / ln r gives q^2 / (2 f ln r) between 1/(2 pi T_c) and
    fs/(2 pi), so each component gets the variance

        q^2 = B^2 ln(r) / pi

    Each is simulated exactly at the sample instants as the AR(1) recursion
    x[n] = phi x[n-1] + q sqrt(1 - phi^2) w[n], phi = exp(-1 / (fs T_k)), started from its
    stationary distribution (no start-up transient of the noise itself).

    Band of the floor: the closed-form Allan deviation of the sampled construction
    (:func:`bias_instability_adev_dph`) is within 5 % of 0.6643 B for
    2/fs <= tau <= T_c/3 (:func:`bias_instability_band_s`) and within 11 % for
    1/fs <= tau <= T_c (checked for fs T_c from 100 to 1e6).  Above the band the process,
    being bounded, falls as 1/sqrt(tau) like white noise (the PSD is flat below
    1/(2 pi T_c)).  With one pole per decade the PSD stays within 0.5 dB of B^2 / (2 pi f)
    from 3/(2 pi T_c) to fs/(6 pi).  The n components' total standard deviation is
    B sqrt(n ln(fs T_c) / ((n - 1) pi)) (1.8 B for 1 Hz and 1 h, n = 5).

    Parameters
    ----------
    n_samples : int
        Number of samples [-].
    sample_rate_hz : float
        Sample rate fs [Hz].
    bias_instability_dph : float
        Bias instability B [deg/h], >= 0 (docs/physics.md: 0.002-0.005).
    correlation_time_s : float
        Longest correlation time T_c [s], >= 100 sample intervals; sets the upper end of the
        floor's band.
    rng : numpy.random.Generator
        Source of every random draw (per component: one normal for the initial state, then
        ``n_samples`` normals).

    Returns
    -------
    numpy.ndarray
        Rate noise [deg/h], zero mean, stationary.
    """
    n = check_n_samples(n_samples)
    b = check_non_negative("bias_instability_dph", bias_instability_dph)
    fs, t_c = check_bias_instability_times(sample_rate_hz, correlation_time_s)
    rng = check_rng(rng)
    times_s, q2_per_b2 = bias_instability_poles(fs, t_c)
    q = b * math.sqrt(q2_per_b2)
    out = np.zeros(n)
    for t_k in times_s:
        x_init = q * rng.standard_normal()
        w = rng.standard_normal(n)
        if n == 0:
            continue
        phi = math.exp(-1.0 / (fs * t_k))
        gain = q * math.sqrt(1.0 - phi * phi)
        x, _ = lfilter([gain], [1.0, -phi], w, zi=[phi * x_init])
        out += x
    return out


def bias_instability_adev_dph(taus_s: np.ndarray, sample_rate_hz: float,
                              bias_instability_dph: float, *,
                              correlation_time_s: float = DEFAULT_CORRELATION_TIME_S,
                              ) -> np.ndarray:
    """Closed-form Allan deviation [deg/h] of the sampled process that
    :func:`bias_instability_noise_dph` generates.

    Each component is a stationary AR(1) sequence of variance q^2 and autocovariance
    q^2 phi^|k|; its Allan variance over m samples, Var(mean of m) - Cov(adjacent means), is
    (derived here from the definition, summing the geometric series)::

        sigma_k^2(m) = (q^2 / m^2) [m + 2 phi (m (1 - phi) - (1 - phi^m)) / (1 - phi)^2
                                      - phi (1 - phi^m)^2 / (1 - phi)^2]

    and the components, being independent, add.  Exact at tau = m / fs (the formula is
    evaluated at m = tau fs, so it interpolates smoothly between).  Large m gives the
    white-noise limit q^2 (1 + phi) / ((1 - phi) m).  It documents the band of the floor and
    is the oracle of the generator's test.

    Parameters
    ----------
    taus_s : array_like
        Averaging times tau [s], > 0.
    sample_rate_hz, bias_instability_dph, correlation_time_s
        As in :func:`bias_instability_noise_dph`.
    """
    b = check_non_negative("bias_instability_dph", bias_instability_dph)
    fs, t_c = check_bias_instability_times(sample_rate_hz, correlation_time_s)
    tau = np.asarray(taus_s, dtype=float)
    if np.any(~np.isfinite(tau)) or np.any(tau <= 0.0):
        raise InputError("taus_s must be finite and > 0")
    m = tau * fs
    times_s, q2_per_b2 = bias_instability_poles(fs, t_c)
    q2 = b * b * q2_per_b2
    avar = np.zeros_like(tau)
    for t_k in times_s:
        phi = math.exp(-1.0 / (fs * t_k))
        one_minus_phi = -math.expm1(-1.0 / (fs * t_k))
        one_minus_phi_m = -np.expm1(-m / (fs * t_k))
        avar += (q2 / m**2) * (m + (2.0 * phi * (m * one_minus_phi - one_minus_phi_m)
                                    - phi * one_minus_phi_m**2) / one_minus_phi**2)
    return np.sqrt(np.maximum(avar, 0.0))


def bias_instability_band_s(sample_rate_hz: float,
                            correlation_time_s: float = DEFAULT_CORRELATION_TIME_S,
                            ) -> tuple[float, float]:
    """The band (tau_lo, tau_hi) [s] = (2/fs, T_c/3) in which the Allan deviation of
    :func:`bias_instability_noise_dph` is within 5 % of its flat floor 0.6643 B."""
    fs, t_c = check_bias_instability_times(sample_rate_hz, correlation_time_s)
    return _BAND_LO_SAMPLES / fs, t_c / _BAND_HI_DIVISOR


def rate_random_walk_noise_dph(n_samples: int, sample_rate_hz: float,
                               rrw_deg_per_h_per_rth_h: float, *,
                               rng: np.random.Generator) -> np.ndarray:
    """Rate random walk: integrated white noise (IEEE Std 952-2020 Annex C).

    The rate is a random walk r[n] = r[n-1] + w[n], r[-1] = 0, with increments of standard
    deviation (K/60) / sqrt(fs) [deg/h], i.e. a Brownian rate of diffusion (K/60)^2
    [(deg/h)^2/s].  Its Allan variance over m samples is (K/60)^2 (2 m^2 + 1) / (6 m fs), which
    tends to sigma^2(tau) = (K/60)^2 tau / 3 [deg/h]^2, tau [s], i.e. K^2 tau_h / 3
    (exact to 1/(2 m^2), 0.5 % at m = 10).  It starts at zero at the first sample
    (not stationary).

    Parameters
    ----------
    n_samples : int
        Number of samples [-].
    sample_rate_hz : float
        Sample rate fs [Hz].
    rrw_deg_per_h_per_rth_h : float
        Rate random walk K [deg/h/sqrt(h)], >= 0.
    rng : numpy.random.Generator
        Source of every random draw (``n_samples`` normals).

    Returns
    -------
    numpy.ndarray
        Rate noise [deg/h].
    """
    n = check_n_samples(n_samples)
    fs = check_positive("sample_rate_hz", sample_rate_hz)
    k = check_non_negative("rrw_deg_per_h_per_rth_h", rrw_deg_per_h_per_rth_h)
    rng = check_rng(rng)
    step = (k / 60.0) / math.sqrt(fs)
    return np.cumsum(step * rng.standard_normal(n))


# --------------------------------------------------------------------------------------------
# the gyro's sum

def gyro_noise_dph(n_samples: int, sample_rate_hz: float, *, arw_deg_per_rth_h: float,
                   bias_instability_dph: float = 0.0, rrw_deg_per_h_per_rth_h: float = 0.0,
                   correlation_time_s: float = DEFAULT_CORRELATION_TIME_S,
                   rng: np.random.Generator) -> np.ndarray:
    """Gyro rate noise [deg/h]: angle random walk + bias instability + rate random walk
    (IEEE Std 952-2020 Annex C; docs/physics.md section 3).

    The sum of :func:`angle_random_walk_noise_dph` (N), :func:`bias_instability_noise_dph`
    (B, T_c) and :func:`rate_random_walk_noise_dph` (K); the three are independent, so their
    Allan variances add:

        sigma^2(tau) ~ (60 N)^2 / tau + (0.6643 B)^2 + (K/60)^2 tau / 3   [deg/h]^2, tau [s]

    (the middle term over the band of :func:`bias_instability_band_s`).  Each term draws from
    its own child generator, seeded in a fixed order from ``rng`` (three integers), whether or
    not its coefficient is zero: switching one term off leaves the others' realisations
    unchanged (ablation).

    Parameters
    ----------
    n_samples : int
        Number of samples [-].
    sample_rate_hz : float
        Sample rate fs [Hz].
    arw_deg_per_rth_h : float
        Angle random walk N [deg/sqrt(h)].
    bias_instability_dph : float
        Bias instability B [deg/h].
    rrw_deg_per_h_per_rth_h : float
        Rate random walk K [deg/h/sqrt(h)].
    correlation_time_s : float
        Longest correlation time T_c [s] of the bias-instability construction; checked only
        when B > 0.
    rng : numpy.random.Generator
        Source of every random draw.

    Returns
    -------
    numpy.ndarray
        ``n_samples`` rate-noise values [deg/h].
    """
    n = check_n_samples(n_samples)
    rng = check_rng(rng)
    arw_rng, bi_rng, rrw_rng = (np.random.default_rng(int(s))
                                for s in rng.integers(0, 2**63 - 1, size=3, dtype=np.int64))
    out = angle_random_walk_noise_dph(n, sample_rate_hz, arw_deg_per_rth_h, rng=arw_rng)
    if check_non_negative("bias_instability_dph", bias_instability_dph) > 0.0:
        out += bias_instability_noise_dph(n, sample_rate_hz, bias_instability_dph,
                                    correlation_time_s=correlation_time_s, rng=bi_rng)
    if check_non_negative("rrw_deg_per_h_per_rth_h", rrw_deg_per_h_per_rth_h) > 0.0:
        out += rate_random_walk_noise_dph(n, sample_rate_hz, rrw_deg_per_h_per_rth_h,
                                          rng=rrw_rng)
    return out


@dataclass(frozen=True)
class GyroNoise:
    """The gyro's noise coefficients (IEEE Std 952-2020 Annex C), for an instrument
    description to hold; :meth:`generate` draws a record with :func:`gyro_noise_dph`."""

    arw_deg_per_rth_h: float = 0.0
    """Angle random walk N [deg/sqrt(h)] (docs/physics.md: 0.0003-0.001)."""
    bias_instability_dph: float = 0.0
    """Bias instability B [deg/h]: the Allan floor is 0.6643 B (docs/physics.md: 0.002-0.005)."""
    rrw_deg_per_h_per_rth_h: float = 0.0
    """Rate random walk K [deg/h/sqrt(h)]: sigma_Allan(tau_h) = K sqrt(tau_h / 3)."""
    correlation_time_s: float = DEFAULT_CORRELATION_TIME_S
    """Longest correlation time T_c [s] of the bias-instability construction; the floor holds
    (within 5 %) for 2/fs <= tau <= T_c / 3; >= 100 sample intervals."""

    def __post_init__(self) -> None:
        check_non_negative("arw_deg_per_rth_h", self.arw_deg_per_rth_h)
        check_non_negative("bias_instability_dph", self.bias_instability_dph)
        check_non_negative("rrw_deg_per_h_per_rth_h", self.rrw_deg_per_h_per_rth_h)
        check_positive("correlation_time_s", self.correlation_time_s)

    def generate(self, n_samples: int, sample_rate_hz: float,
                 rng: np.random.Generator) -> np.ndarray:
        """``n_samples`` of rate noise [deg/h] at ``sample_rate_hz`` [Hz]
        (:func:`gyro_noise_dph`)."""
        return gyro_noise_dph(n_samples, sample_rate_hz,
                              arw_deg_per_rth_h=self.arw_deg_per_rth_h,
                              bias_instability_dph=self.bias_instability_dph,
                              rrw_deg_per_h_per_rth_h=self.rrw_deg_per_h_per_rth_h,
                              correlation_time_s=self.correlation_time_s, rng=rng)
