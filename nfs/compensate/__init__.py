"""Drift compensation: features, compensators (scikit-learn estimators), tuners, settings.

- :mod:`~nfs.compensate.features`: named features from the thermometers and aux channels,
  in a features mode (:mod:`~nfs.compensate.modes`: cycle, causal, offline) with their rates
  (:mod:`~nfs.compensate.rates`, :mod:`~nfs.compensate.kalman_rate`);
- :mod:`~nfs.compensate.regression`, :mod:`~nfs.compensate.neural`,
  :mod:`~nfs.compensate.kernels`: the compensators of the seed papers;
- :mod:`~nfs.compensate.tuners`, :mod:`~nfs.compensate.search`: metaheuristic tuners (grid,
  PSO, GWO, HHO, SSA, TPE) and a search-CV wrapper validating by whole runs;
- :mod:`~nfs.compensate.dataset`, :mod:`~nfs.compensate.compensator`,
  :mod:`~nfs.compensate.methods`, :mod:`~nfs.compensate.settings`: training data, a saved
  compensator, the method registry and the ``[compensation]`` settings (the studies that
  use them are in :mod:`nfs.studies`).
"""

from .compensator import DriftCompensator, load_compensator, train_compensator
from .dataset import DriftDataset, drift_dataset
from .features import (FEATURE_SETS, FeatureError, available_features, compute_features,
                       feature_columns, rate_k_per_min, resolve_features)
from .kernels import IRLSSVMRegressor, LSSVMRegressor, RVRRegressor, SVRRegressor
from .methods import METHODS, TABLE_METHODS, MethodSpec, get_method
from .modes import DEFAULT_FEATURE_MODE, FEATURE_MODES, FeatureModeError, check_features_mode
from .neural import BPNetwork, RBFNetwork
from .regression import CubicLeastSquares, StepwiseRegression
from .search import Integer, MetaheuristicSearchCV, Real
from .settings import CompensationSettings
from .tuners import TUNERS, TuneResult, minimize

__all__ = [
    "DriftCompensator", "load_compensator", "train_compensator", "DriftDataset",
    "drift_dataset", "FEATURE_SETS", "FeatureError", "available_features", "compute_features",
    "feature_columns", "rate_k_per_min", "resolve_features", "IRLSSVMRegressor",
    "LSSVMRegressor", "RVRRegressor", "SVRRegressor", "METHODS", "TABLE_METHODS", "MethodSpec",
    "get_method", "BPNetwork", "RBFNetwork", "CubicLeastSquares", "StepwiseRegression",
    "Integer", "MetaheuristicSearchCV", "Real", "CompensationSettings", "TUNERS", "TuneResult", "minimize", "DEFAULT_FEATURE_MODE", "FEATURE_MODES",
    "FeatureModeError", "check_features_mode",
]
