"""Drift compensation: features, feature modes, the methods, the compensator, the settings.

- :mod:`~nfs.compensate.features`: named features from the thermometers and aux channels,
  in a features mode (:mod:`~nfs.compensate.modes`: cycle, causal, offline) with their rates
  (:mod:`~nfs.compensate.rates`, :mod:`~nfs.compensate.kalman_rate`);
- :mod:`~nfs.compensate.registry`: the compensation methods by name
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

from .compensator import DriftCompensator, load_compensator, train_compensator
from .dataset import DriftDataset, drift_dataset
from .features import (FEATURE_SETS, FeatureError, available_features, compute_features,
                       feature_columns, rate_k_per_min, resolve_features)
from .methods import PAPERS_GROUP, STARTUP_GROUP
from .registry import (METHODS, MethodError, MethodSpec, available_methods, get_method,
                       register_method, table_methods, unregister_method)
from .modes import DEFAULT_FEATURE_MODE, FEATURE_MODES, FeatureModeError, check_features_mode
from .settings import PROTOCOLS, CompensationSettings

__all__ = [
    "DriftCompensator", "load_compensator", "train_compensator", "DriftDataset",
    "drift_dataset", "FEATURE_SETS", "FeatureError", "available_features", "compute_features",
    "feature_columns", "rate_k_per_min", "resolve_features", "METHODS", "MethodSpec",
    "MethodError", "register_method", "unregister_method", "get_method", "available_methods",
    "table_methods", "STARTUP_GROUP", "PAPERS_GROUP", "DEFAULT_FEATURE_MODE", "FEATURE_MODES",
    "FeatureModeError", "check_features_mode", "PROTOCOLS", "CompensationSettings",
]
