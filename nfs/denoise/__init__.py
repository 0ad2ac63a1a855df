"""Wavelet denoising of the FOG output: the drift that compensators learn (docs/physics.md 6).

``wavelet``: the DWT shrinkage denoiser; ``thresholds``: its threshold rules; ``levels``: the
level of a cutoff period;
``drift``: the drift of a run (output minus Earth-rate projection), denoised.
"""

from nfs.denoise.drift import (
    DEFAULT_CUTOFF_PERIOD_S,
    DriftSeparation,
    bridge_gaps,
    earth_rate_projection_dph,
    separate_drift,
)
from nfs.denoise.levels import cutoff_for_level, edge_span_samples, level_for_cutoff
from nfs.denoise.thresholds import (MAD_TO_SIGMA, THRESHOLD_RULES, ThresholdRule,
                                    bayes_shrink_threshold, mad_sigma, no_threshold, sure_risk,
                                    sure_threshold, visu_threshold)
from nfs.denoise.wavelet import BOUNDARIES, THRESHOLD_MODES, DenoiseResult, wavelet_denoise

__all__ = [
    "BOUNDARIES",
    "DEFAULT_CUTOFF_PERIOD_S",
    "MAD_TO_SIGMA",
    "THRESHOLD_MODES",
    "THRESHOLD_RULES",
    "DenoiseResult",
    "DriftSeparation",
    "ThresholdRule",
    "bayes_shrink_threshold",
    "bridge_gaps",
    "cutoff_for_level",
    "earth_rate_projection_dph",
    "edge_span_samples",
    "level_for_cutoff",
    "mad_sigma",
    "no_threshold",
    "separate_drift",
    "sure_risk",
    "sure_threshold",
    "visu_threshold",
    "wavelet_denoise",
]
