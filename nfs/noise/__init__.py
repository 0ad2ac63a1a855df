"""Noise: the gyro's angle random walk, bias instability and rate random walk, white noise,
and the overlapping Allan deviation with the fit of the noise coefficients
(IEEE Std 952-2020 Annex C; NIST SP 1065)."""

from nfs.noise.allan import (
    AllanResult,
    NoiseFit,
    allan_deviation,
    allan_relative_error,
    fit_noise_coefficients,
    octave_taus_s,
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

__all__ = [
    "AllanResult",
    "BI_FLOOR_FACTOR",
    "BI_POLES_PER_DECADE",
    "DEFAULT_CORRELATION_TIME_S",
    "GyroNoise",
    "NoiseFit",
    "allan_deviation",
    "allan_relative_error",
    "angle_random_walk_noise_dph",
    "bias_instability_adev_dph",
    "bias_instability_band_s",
    "bias_instability_noise_dph",
    "fit_noise_coefficients",
    "gyro_noise_dph",
    "octave_taus_s",
    "rate_random_walk_noise_dph",
    "white_noise",
]
