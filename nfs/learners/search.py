"""Metaheuristic hyperparameter search with cross-validation by whole runs.

:class:`MetaheuristicSearchCV` is a thin scikit-learn meta-estimator around the plain
optimisers of :mod:`nfs.learners.tuners`: it maps a parameter space (:class:`Real`,
:class:`Integer`) to the tuners' box [-1, 1]^d, scores each candidate by cross-validation
and refits the best one on all the data.  It works with any scikit-learn estimator, e.g.
the FOG start-up paper's SSA-SVR::

    search = MetaheuristicSearchCV(
        SVRRegressor(),
        {"C": Real(1e-2, 1e3, log=True), "sigma": Real(1e-2, 1e2, log=True),
         "epsilon": Real(1e-4, 1e-1, log=True)},
        method="ssa", budget=60, n_jobs=-1, random_state=0,
    ).fit(X, y, groups=run_id)

Validation is by whole runs: ``groups`` are run ids and the default splitter is
``LeaveOneGroupOut`` (the drift noise is correlated in time, so a random K-fold would put
neighbouring, nearly identical samples on both sides of a split and reward over-fitting).

Work done once: an estimator whose ``fit`` takes ``sq_distances`` (the RVR and LS-SVM of
:mod:`~nfs.learners.kernels`) gets the squared distances of each fold's training inputs,
computed once before the tuner starts, and every candidate only turns them into its kernel
(exp(-D2 / (2 sigma^2))), unless the search changes how the inputs are scaled
(``standardize`` in the space).  The SVR is left to LIBSVM's own kernel: its fits are spent
in the SMO iterations, and a precomputed Gram matrix (``kernel="precomputed"``) measured
within +-10 % of it on the table's folds (slower on the quick fits, the exponential of the
n x n matrix included).
"""

from __future__ import annotations

import inspect
import math
import numbers
import time
import warnings
from dataclasses import dataclass
from typing import Mapping

import numpy as np
from joblib import Parallel, delayed
from sklearn.base import BaseEstimator, MetaEstimatorMixin, clone, is_classifier
from sklearn.exceptions import ConvergenceWarning
from sklearn.metrics import check_scoring
from sklearn.model_selection import LeaveOneGroupOut, check_cv
from sklearn.utils import _safe_indexing, check_random_state
from sklearn.utils._tags import get_tags
from sklearn.utils.metaestimators import available_if
from sklearn.utils.validation import check_is_fitted, indexable

from .kernels import KernelRegressor
from .tuners import TuneResult, TuningError, minimize

__all__ = ["Real", "Integer", "MetaheuristicSearchCV"]


@dataclass(frozen=True)
class Real:
    """A real hyperparameter in [low, high], searched on a linear or a log10 scale.

    The tuners' coordinate u in [-1, 1] maps linearly to ``low..high`` (``log=False``) or to
    ``log10(low)..log10(high)`` (``log=True``, e.g. an SVR's C or sigma).
    """

    low: float
    """Lower bound, in the parameter's own unit."""
    high: float
    """Upper bound (> low), in the parameter's own unit."""
    log: bool = False
    """Search log10 of the parameter (requires low > 0)."""

    def __post_init__(self) -> None:
        if not (np.isfinite(self.low) and np.isfinite(self.high) and self.low < self.high):
            raise TuningError(f"Real needs finite low < high, got ({self.low}, {self.high})")
        if self.log and self.low <= 0:
            raise TuningError(f"Real(log=True) needs low > 0, got low={self.low}")

    def _ends(self) -> tuple[float, float]:
        if self.log:
            return math.log10(self.low), math.log10(self.high)
        return float(self.low), float(self.high)

    def from_unit(self, u: float) -> float:
        """Parameter value at box coordinate ``u`` in [-1, 1]."""
        a, b = self._ends()
        v = a + (min(max(float(u), -1.0), 1.0) + 1.0) / 2.0 * (b - a)
        v = 10.0 ** v if self.log else v
        return float(min(max(v, self.low), self.high))

    def to_unit(self, value: float) -> float:
        """Box coordinate of a parameter value (inverse of :meth:`from_unit`)."""
        a, b = self._ends()
        v = math.log10(value) if self.log else float(value)
        return 2.0 * (v - a) / (b - a) - 1.0


@dataclass(frozen=True)
class Integer:
    """An integer hyperparameter in [low, high] (both included), linear or log10 scale.

    The box [-1, 1] is cut into ``high - low + 1`` equal bins, one per integer (on the log
    scale, bins of equal width in log10 between low - 0.5 and high + 0.5).
    """

    low: int
    """Smallest value."""
    high: int
    """Largest value (>= low)."""
    log: bool = False
    """Search log10 of the parameter (requires low >= 1)."""

    def __post_init__(self) -> None:
        if int(self.low) != self.low or int(self.high) != self.high or self.low > self.high:
            raise TuningError(f"Integer needs integers low <= high, got ({self.low}, {self.high})")
        if self.log and self.low < 1:
            raise TuningError(f"Integer(log=True) needs low >= 1, got low={self.low}")

    def _ends(self) -> tuple[float, float]:
        a, b = self.low - 0.5, self.high + 0.5
        if self.log:
            return math.log10(max(a, 0.5)), math.log10(b)
        return a, b

    def from_unit(self, u: float) -> int:
        """Parameter value at box coordinate ``u`` in [-1, 1]."""
        a, b = self._ends()
        v = a + (min(max(float(u), -1.0), 1.0) + 1.0) / 2.0 * (b - a)
        v = 10.0 ** v if self.log else v
        return int(min(max(round(v), self.low), self.high))

    def to_unit(self, value: int) -> float:
        """Box coordinate of the middle of ``value``'s bin."""
        a, b = self._ends()
        v = math.log10(value) if self.log else float(value)
        return 2.0 * (v - a) / (b - a) - 1.0


def _fit_and_score(estimator, fold, scorer, sq_distances=None) -> tuple[float, float]:
    """Fit ``estimator`` on a fold's training rows, score it on its held-out rows: (score,
    fit time [s]); ``fold`` is (X_train, y_train, X_test, y_test), indexed once for every
    candidate; ``sq_distances`` of the training rows go to a kernel regressor's fit."""
    X_train, y_train, X_test, y_test = fold
    fit_params = {} if sq_distances is None else {"sq_distances": sq_distances}
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        # A candidate that does not converge is scored as it is: the tuner is asking what
        # these hyperparameters give, and a warning per fold per candidate (in every joblib
        # worker) would bury the progress output.
        warnings.simplefilter("ignore", ConvergenceWarning)
        estimator.fit(X_train, y_train, **fit_params)
    fit_time = time.perf_counter() - t0
    score = scorer(estimator, X_test, y_test)
    return float(score), fit_time


def _takes_sq_distances(estimator) -> bool:
    """True for a kernel regressor whose ``fit`` takes the squared distances of its scaled
    training inputs (:meth:`~nfs.learners.kernels.KernelRegressor.training_sq_distances`)."""
    return isinstance(estimator, KernelRegressor) and \
        "sq_distances" in inspect.signature(estimator.fit).parameters


def _search_estimator_has(attr):
    """Delegate ``attr`` to the refitted best estimator (or the unfitted one before fit)."""

    def check(self):
        if not self.refit:
            raise AttributeError(f"'{attr}' needs refit=True")
        getattr(self.best_estimator_ if hasattr(self, "best_estimator_") else self.estimator,
                attr)
        return True

    return check


class MetaheuristicSearchCV(MetaEstimatorMixin, BaseEstimator):
    """Cross-validated hyperparameter search by a metaheuristic tuner.

    Parameters
    ----------
    estimator : estimator object
        Any scikit-learn estimator; cloned for every fit.
    param_space : dict
        Parameter name (as in ``estimator.get_params()``, e.g. ``"svr__C"`` in a pipeline)
        -> :class:`Real` or :class:`Integer`.  Dimension i of the tuner's box is the i-th
        entry.
    method : str
        Tuner name in :data:`nfs.learners.tuners.TUNERS` ('ssa', 'pso', 'gwo', 'hho', 'random',
        'grid', 'tpe').
    budget : int
        Maximum number of candidates scored (each costs one fit per CV split).
    cv : int, splitter or iterable, optional
        Cross-validation splitter.  None (default) means ``LeaveOneGroupOut()``: one split per
        run, which needs ``groups`` (run ids) in :meth:`fit`.  Otherwise as in scikit-learn's
        ``check_cv``.
    scoring : str or callable
        Scorer (greater is better); default ``"neg_root_mean_squared_error"``.  The tuner
        minimises minus the mean score over the splits.
    n_jobs : int, optional
        Workers for joblib: every (candidate, split) fit of a tuner's batch runs in parallel.
        The result does not depend on ``n_jobs``.
    random_state : int, RandomState, Generator or None
        Seed of the tuner (resolved in fit).
    refit : bool
        Refit ``best_estimator_`` on all the data with ``best_params_``.
    population : int, optional
        Population (batch) size of the tuner; tuner default if None.
    tuner_options : dict, optional
        Further options of the tuner (e.g. ``{"SD": 0.1}`` for 'ssa').
    verbose : int
        > 0 prints one line per tuner batch (evaluations made, best score so far).

    Attributes
    ----------
    best_params_ : dict
        Parameter values of the best candidate.
    best_score_ : float
        Its mean cross-validated score (e.g. minus the RMSE, mean over the splits).
    best_index_ : int
        Its row in ``cv_results_``.
    best_estimator_ : estimator
        Clone of ``estimator`` with ``best_params_`` fitted on all data (``refit=True``).
    n_evaluations_ : int
        Candidates scored (<= budget).
    history_ : ndarray
        Best mean score so far after each evaluation (non-decreasing).
    cv_results_ : dict of arrays
        One row per evaluation in order: ``params``, ``param_<name>``, ``mean_test_score``,
        ``std_test_score``, ``split<k>_test_score``, ``mean_fit_time``, ``rank_test_score``,
        ``unit_x`` (the tuner's position in [-1, 1]^d).
    tune_result_ : TuneResult
        The tuner's own result (box coordinates, objective = minus the mean score).
    n_splits_ : int
        Number of CV splits.
    refit_time_ : float
        Seconds to refit the best estimator.
    """

    def __init__(self, estimator, param_space, *, method="ssa", budget=60, cv=None,
                 scoring="neg_root_mean_squared_error", n_jobs=None, random_state=None,
                 refit=True, population=None, tuner_options=None, verbose=0):
        self.estimator = estimator
        self.param_space = param_space
        self.method = method
        self.budget = budget
        self.cv = cv
        self.scoring = scoring
        self.n_jobs = n_jobs
        self.random_state = random_state
        self.refit = refit
        self.population = population
        self.tuner_options = tuner_options
        self.verbose = verbose

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        sub = get_tags(self.estimator)
        tags.estimator_type = sub.estimator_type
        tags.classifier_tags = sub.classifier_tags
        tags.regressor_tags = sub.regressor_tags
        tags.target_tags = sub.target_tags
        tags.input_tags.sparse = sub.input_tags.sparse
        return tags

    # -- helpers --------------------------------------------------------------------------

    def _space(self) -> list[tuple[str, Real | Integer]]:
        if not isinstance(self.param_space, Mapping) or not self.param_space:
            raise TuningError("param_space must be a non-empty dict name -> Real/Integer")
        valid = self.estimator.get_params(deep=True)
        space = []
        for name, spec in self.param_space.items():
            if name not in valid:
                raise TuningError(f"param_space: {type(self.estimator).__name__} has no "
                                  f"parameter '{name}'; valid: {', '.join(sorted(valid))}")
            if not isinstance(spec, (Real, Integer)):
                raise TuningError(f"param_space['{name}'] must be Real(...) or Integer(...), "
                                  f"got {spec!r}")
            space.append((name, spec))
        return space

    def _seed(self):
        rs = self.random_state
        if rs is None or isinstance(rs, (numbers.Integral, np.random.Generator)):
            return rs
        return int(check_random_state(rs).randint(0, 2**31 - 1))

    # -- fit ------------------------------------------------------------------------------

    def fit(self, X, y=None, groups=None):
        """Tune on (X, y) with CV splits by ``groups``, then refit the best candidate.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
        y : array-like of shape (n_samples,)
        groups : array-like of shape (n_samples,), optional
            Run id of each sample; required by the default ``LeaveOneGroupOut`` splitter.
        """
        space = self._space()
        names = [n for n, _ in space]
        if y is None and get_tags(self.estimator).target_tags.required:
            raise ValueError(f"{type(self).__name__} requires y to be passed, but the target "
                             "y is None")
        X, y, groups = indexable(X, y, groups)
        if self.cv is None:
            if groups is None:
                raise TuningError("the default cv (LeaveOneGroupOut) needs groups= (the run id "
                                  "of each sample); pass groups or an explicit cv")
            cv = LeaveOneGroupOut()
        else:
            cv = check_cv(self.cv, y, classifier=is_classifier(self.estimator))
        splits = list(cv.split(X, y, groups))
        n_splits = len(splits)
        if n_splits < 2:
            raise TuningError(f"cross-validation needs at least 2 splits, got {n_splits} "
                              f"(LeaveOneGroupOut needs at least 2 distinct groups)")
        scorer = check_scoring(self.estimator, scoring=self.scoring)
        base = clone(self.estimator)
        # each fold's rows (X_train, y_train, X_test, y_test), indexed once for every candidate
        folds = [tuple(None if a is None else _safe_indexing(a, rows)
                       for a, rows in ((X, train), (y, train), (X, test), (y, test)))
                 for train, test in splits]
        # each fold's squared distances, once for every candidate (None: not a kernel model)
        if _takes_sq_distances(base) and "standardize" not in names:
            sq = [base.training_sq_distances(fold[0]) for fold in folds]
        else:
            sq = [None] * n_splits

        rows_params: list[dict] = []
        rows_scores: list[np.ndarray] = []
        rows_time: list[float] = []

        def decode(u):
            return {n: s.from_unit(v) for (n, s), v in zip(space, u)}

        # Fold scores by candidate: a tuner that clips several positions to the same corner
        # of the box, or comes back to a candidate, is answered without refitting.
        memo: dict[tuple, np.ndarray] = {}

        with Parallel(n_jobs=self.n_jobs) as parallel:
            def objective_batch(U):
                params = [decode(u) for u in U]
                keys = [tuple(sorted(p.items())) for p in params]
                todo = list(dict.fromkeys(k for k in keys if k not in memo))
                out = parallel(delayed(_fit_and_score)(clone(base).set_params(**dict(k)),
                                                       fold, scorer, d2)
                               for k in todo for fold, d2 in zip(folds, sq))
                out = np.asarray(out, dtype=float).reshape(len(todo), n_splits, 2)
                memo.update(zip(todo, out))
                out = np.stack([memo[k] for k in keys])
                scores, times = out[..., 0], out[..., 1]
                rows_params.extend(params)
                rows_scores.extend(scores)
                rows_time.extend(times.mean(axis=1))
                if self.verbose > 0:
                    best = np.max(np.mean(np.asarray(rows_scores), axis=1))
                    print(f"[{self.method}] {len(rows_params)}/{self.budget} candidates "
                          f"x {n_splits} splits, best mean score {best:.6g}", flush=True)
                return -scores.mean(axis=1)

            res: TuneResult = minimize(objective_batch, len(space), method=self.method,
                                       budget=self.budget, random_state=self._seed(),
                                       population=self.population,
                                       **(self.tuner_options or {}))

        scores = np.asarray(rows_scores).reshape(-1, n_splits)
        mean = scores.mean(axis=1)
        results = {
            "params": rows_params,
            "mean_test_score": mean,
            "std_test_score": scores.std(axis=1),
            "mean_fit_time": np.asarray(rows_time),
            "unit_x": res.all_x,
        }
        for name in names:
            results[f"param_{name}"] = np.array([p[name] for p in rows_params])
        for k in range(n_splits):
            results[f"split{k}_test_score"] = scores[:, k]
        order = np.argsort(-np.where(np.isnan(mean), -np.inf, mean), kind="stable")
        rank = np.empty(len(mean), dtype=int)
        rank[order] = np.arange(1, len(mean) + 1)
        results["rank_test_score"] = rank

        self.tune_result_ = res
        self.cv_results_ = results
        self.n_evaluations_ = res.n_evaluations
        self.n_splits_ = n_splits
        self.best_index_ = int(np.argmin(res.all_f))
        self.best_params_ = dict(rows_params[self.best_index_])
        self.best_score_ = float(mean[self.best_index_])
        self.history_ = -res.history
        self.scorer_ = scorer
        if self.refit:
            t0 = time.perf_counter()
            self.best_estimator_ = clone(base).set_params(**self.best_params_).fit(X, y)
            self.refit_time_ = time.perf_counter() - t0
            if hasattr(self.best_estimator_, "n_features_in_"):
                self.n_features_in_ = self.best_estimator_.n_features_in_
            if hasattr(self.best_estimator_, "feature_names_in_"):
                self.feature_names_in_ = self.best_estimator_.feature_names_in_
        return self

    # -- delegation -----------------------------------------------------------------------

    @available_if(_search_estimator_has("predict"))
    def predict(self, X):
        """Predict with the refitted best estimator."""
        check_is_fitted(self, "best_estimator_")
        return self.best_estimator_.predict(X)

    @available_if(_search_estimator_has("transform"))
    def transform(self, X):
        """Transform with the refitted best estimator."""
        check_is_fitted(self, "best_estimator_")
        return self.best_estimator_.transform(X)

    @available_if(_search_estimator_has("predict"))
    def score(self, X, y=None):
        """Score of the refitted best estimator by ``scoring`` (greater is better)."""
        check_is_fitted(self, "best_estimator_")
        return float(self.scorer_(self.best_estimator_, X, y))
