"""Noise: the gyro's angle random walk, bias instability and rate random walk, white noise,
the overlapping Allan deviation with the fit of the noise coefficients
(IEEE Std 952-2020 Annex C; NIST SP 1065), pooled over many short records (a north finder's
dwells) with bootstrap intervals of N, B, K, the covariance of window means of the gyro's noise
and the test of whether a residual is that noise (Ljung & Box 1978 on the whitened
residual)."""

from nfs.noise.allan import (
    AllanResult,
    NoiseFit,
    allan_deviation,
    allan_relative_error,
    fit_noise_coefficients,
    octave_taus_s,
)
from nfs.noise.covariance import (
    cholesky_lower,
    rest_window_segments,
    segment_sum_covariance,
    whiten,
    window_mean_covariance,
)
from nfs.noise.generators import (
    BI_FLOOR_FACTOR,
    BI_POLES_PER_DECADE,
    DEFAULT_CORRELATION_TIME_S,
    GyroNoise,
    angle_random_walk_noise_dph,
    bias_instability_adev_dph,
    bias_instability_band_s,
    bias_instability_noise_dph,
    gyro_noise_dph,
    rate_random_walk_noise_dph,
    white_noise,
)
from nfs.noise.pooled import (
    NoiseFitIntervals,
    PooledAllan,
    fit_pooled_noise,
    half_octave_taus_s,
    pooled_allan,
)
from nfs.noise.whiteness import (
    WhitenessResult,
    WindowNoiseFit,
    fit_window_noise,
    ljung_box_q,
    whiteness_test,
)

__all__ = [
    "AllanResult",
    "BI_FLOOR_FACTOR",
    "BI_POLES_PER_DECADE",
    "DEFAULT_CORRELATION_TIME_S",
    "GyroNoise",
    "NoiseFit",
    "NoiseFitIntervals",
    "PooledAllan",
    "WhitenessResult",
    "WindowNoiseFit",
    "allan_deviation",
    "allan_relative_error",
    "angle_random_walk_noise_dph",
    "bias_instability_adev_dph",
    "bias_instability_band_s",
    "bias_instability_noise_dph",
    "cholesky_lower",
    "fit_noise_coefficients",
    "fit_pooled_noise",
    "fit_window_noise",
    "gyro_noise_dph",
    "half_octave_taus_s",
    "ljung_box_q",
    "octave_taus_s",
    "pooled_allan",
    "rate_random_walk_noise_dph",
    "rest_window_segments",
    "segment_sum_covariance",
    "white_noise",
    "whiten",
    "whiteness_test",
    "window_mean_covariance",
]
