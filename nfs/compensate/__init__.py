"""Drift compensation: features, feature modes, the methods, the compensator, the settings.

- :mod:`~nfs.compensate.features`: named features from the thermometers and aux channels,
  in a features mode (:mod:`~nfs.compensate.modes`: cycle, causal, offline) with their rates
  (:mod:`~nfs.compensate.rates`, :mod:`~nfs.compensate.kalman_rate`);
- :mod:`~nfs.compensate.methods`: the compensation methods of the seed papers by name, each
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
from .methods import METHODS, TABLE_METHODS, MethodSpec, get_method
from .modes import DEFAULT_FEATURE_MODE, FEATURE_MODES, FeatureModeError, check_features_mode
from .settings import PROTOCOLS, CompensationSettings

__all__ = [
    "DriftCompensator", "load_compensator", "train_compensator", "DriftDataset",
    "drift_dataset", "FEATURE_SETS", "FeatureError", "available_features", "compute_features",
    "feature_columns", "rate_k_per_min", "resolve_features", "METHODS", "TABLE_METHODS",
    "MethodSpec", "get_method", "DEFAULT_FEATURE_MODE", "FEATURE_MODES", "FeatureModeError",
    "check_features_mode", "PROTOCOLS", "CompensationSettings",
]
