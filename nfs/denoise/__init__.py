"""Wavelet denoising of the FOG output: the drift that compensators learn (docs/physics.md 6).

``wavelet``: the DWT shrinkage denoiser; ``thresholds``: its threshold rules; ``levels``: the
level of a cutoff period and whether a record reaches it (without PyWavelets);
``drift``: the drift of a run (output minus Earth-rate projection), denoised.

The names load on first use (PEP 562, as :mod:`thermal` does): a scenario's reader checks a
cutoff with :mod:`nfs.denoise.levels` and does not import PyWavelets.
"""

from importlib import import_module

#: Public name -> the module that defines it, loaded on first use.
_PUBLIC = {
    **{name: "nfs.denoise.drift" for name in (
        "DEFAULT_CUTOFF_PERIOD_S", "DriftSeparation", "bridge_gaps", "earth_rate_projection_dph",
        "separate_drift")},
    **{name: "nfs.denoise.levels" for name in (
        "cutoff_for_level", "edge_span_samples", "level_for_cutoff")},
    **{name: "nfs.denoise.thresholds" for name in (
        "MAD_TO_SIGMA", "THRESHOLD_RULES", "ThresholdRule", "bayes_shrink_threshold",
        "mad_sigma", "no_threshold", "sure_risk", "sure_threshold", "visu_threshold")},
    **{name: "nfs.denoise.wavelet" for name in (
        "BOUNDARIES", "THRESHOLD_MODES", "DenoiseResult", "wavelet_denoise")},
}

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


def __getattr__(name: str):
    """Load a public name from its module on first use (PEP 562)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'nfs.denoise' has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
