"""Learners: scikit-learn estimators and hyperparameter tuners, with no domain imports.

The regressors of the seed papers, each mapping a feature matrix X (n_samples,
n_features) to a target y (the FOG drift [deg/h] in this package), and the metaheuristics
that tune them.  Every estimator follows scikit-learn's contract (no logic
in ``__init__``, ``fit`` returns ``self``, learned attributes end in ``_``, random_state
resolved in ``fit``) and passes ``sklearn.utils.estimator_checks``.  Nothing here knows of
runs, features or north finding: this package imports only :mod:`nfs.errors` and
:mod:`nfs.docfields` of nfs, and :mod:`nfs.compensate` builds its methods from it.

By concept:

- :mod:`~nfs.learners.validation`: the hyperparameter checks, input validation and
  standardisation every learner shares;
- polynomial models (Tao et al. (2019)): :mod:`~nfs.learners.polynomial` (the monomial
  basis), :mod:`~nfs.learners.linear` (:class:`CubicLeastSquares`, the least-squares solver),
  :mod:`~nfs.learners.stepwise` (:class:`StepwiseRegression`);
- networks: :mod:`~nfs.learners.neural` (:class:`BPNetwork` of the FOG start-up paper,
  :class:`RBFNetwork` of Cheng et al. (2015));
- kernel models: :mod:`~nfs.learners.kernels` (the Gaussian kernel and its algebra),
  :mod:`~nfs.learners.svr` (:class:`SVRRegressor`, the FOG start-up paper),
  :mod:`~nfs.learners.lssvm` (:class:`LSSVMRegressor`, :class:`IRLSSVMRegressor`, Tao et
  al. (2019)) with the robust weights of :mod:`~nfs.learners.weights`, and
  :mod:`~nfs.learners.rvr` (:class:`RVRRegressor`, Liang et al. (2021));
- tuning: :mod:`~nfs.learners.tuners` (grid, random, PSO, GWO, HHO, SSA, TPE: plain
  minimisers on the box [-1, 1]^d, :func:`minimize` by name, :func:`register_tuner` for
  a user's own) and
  :mod:`~nfs.learners.search` (:class:`MetaheuristicSearchCV`, a search-CV wrapper over any
  estimator, by whole runs when given groups).

Equation numbers "Tao et al. (2019) eq. (n)" count the displayed equations of the stored
text of Tao, Li, Zheng, Wu & Fu 2019 (Sensors 19, 2986), which carries no numbers of its own.
"""

from .linear import CubicLeastSquares
from .lssvm import IRLSSVMRegressor, LSSVMRegressor
from .neural import BPNetwork, RBFNetwork
from .rvr import RVRRegressor
from .search import Integer, MetaheuristicSearchCV, Real
from .stepwise import StepwiseRegression, StepwiseStep
from .svr import SVRRegressor
from .tuners import (TUNERS, TuneResult, TuningError, default_population, get_tuner, grid,
                     gwo, hho, minimize, pso, random_search, register_tuner, ssa, tpe)
from .validation import HyperparameterError
from .weights import WEIGHT_FUNCTIONS

__all__ = [
    # estimators
    "CubicLeastSquares", "StepwiseRegression", "StepwiseStep", "BPNetwork", "RBFNetwork",
    "SVRRegressor", "LSSVMRegressor", "IRLSSVMRegressor", "RVRRegressor", "WEIGHT_FUNCTIONS",
    "HyperparameterError",
    # tuners and the search
    "TUNERS", "register_tuner", "get_tuner", "TuneResult", "TuningError", "minimize",
    "default_population", "grid",
    "random_search", "pso", "gwo", "hho", "ssa", "tpe", "MetaheuristicSearchCV", "Real",
    "Integer",
]
