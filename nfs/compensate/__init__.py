"""Drift compensation: features, feature modes, the methods, the compensator, the settings.

- :mod:`~nfs.compensate.features`: named features from the thermometers and aux channels,
  in a features mode (:mod:`~nfs.compensate.modes`: cycle, causal, offline) with their rates
  (:mod:`~nfs.compensate.rates`, :mod:`~nfs.compensate.kalman_rate`);
- :mod:`~nfs.compensate.catalog`: the method names known without building one (what a
  scenario's reader checks); :mod:`~nfs.compensate.registry`: the compensation methods by name
  (:func:`register_method`, :func:`get_method`): a user's own method is registered as the
  built-in ones are, and runs through the studies, the tables and the model files;
- :mod:`~nfs.compensate.methods`: the compensation methods of the seed papers, each
  built from the estimators and tuners of :mod:`nfs.learners` (LS, stepwise, BP, RBF,
  LSSVM, IR-LSSVM, SVR tuned by grid, PSO, GWO, SSA or TPE, HHO-RVR);
- :mod:`~nfs.compensate.dataset`, :mod:`~nfs.compensate.compensator`,
  :mod:`~nfs.compensate.model_file`, :mod:`~nfs.compensate.settings`: training data, a saved
  compensator and its file, and the ``[compensation]`` settings (the studies that use them
  are in :mod:`nfs.studies`).
"""

from importlib import import_module

#: Public name -> the module that defines it; loaded on first use (SPEC 1, as :mod:`nfs`
#: does), so that reading a scenario's ``[compensation]`` (the settings and the catalogue of
#: method names) loads neither scikit-learn nor the wavelet denoiser.
_PUBLIC = {
    **dict.fromkeys(["DriftCompensator", "load_compensator", "train_compensator"],
                    "nfs.compensate.compensator"),
    **dict.fromkeys(["DriftDataset", "drift_dataset"], "nfs.compensate.dataset"),
    **dict.fromkeys(["FEATURE_SETS", "FeatureError", "available_features", "compute_features",
                     "feature_columns", "rate_k_per_min", "resolve_features"],
                    "nfs.compensate.features"),
    **dict.fromkeys(["PAPERS_GROUP", "STARTUP_GROUP"], "nfs.compensate.methods"),
    **dict.fromkeys(["METHODS", "MethodError", "MethodSpec", "table_methods"],
                    "nfs.compensate.catalog"),
    **dict.fromkeys(["register_method", "unregister_method", "get_method",
                     "available_methods"], "nfs.compensate.registry"),
    **dict.fromkeys(["DEFAULT_FEATURE_MODE", "FEATURE_MODES", "FeatureModeError",
                     "check_features_mode"], "nfs.compensate.modes"),
    **dict.fromkeys(["PROTOCOLS", "CompensationSettings"], "nfs.compensate.settings"),
}

__all__ = list(_PUBLIC)

#: Names handed out without registering the seed papers' methods (no scikit-learn).
_LIGHT = frozenset(["PROTOCOLS", "CompensationSettings", "DEFAULT_FEATURE_MODE",
                    "FEATURE_MODES", "FeatureModeError", "check_features_mode", "MethodError",
                    "table_methods", "FEATURE_SETS", "FeatureError", "available_features",
                    "compute_features", "feature_columns", "rate_k_per_min",
                    "resolve_features"])


def __getattr__(name: str):
    """Load a public name from its module on first use (PEP 562).  The methods of the seed
    papers are registered before anything that builds, looks up or lists methods is
    handed out (the settings, the features and the catalogue's names need none)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'nfs.compensate' has no attribute {name!r}")
    if name not in _LIGHT:
        import_module("nfs.compensate.methods")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
