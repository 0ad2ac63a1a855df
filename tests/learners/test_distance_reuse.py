"""The squared distances computed once per training set and reused by every kernel fit.

Oracles: the closed form of the standardised squared distance and of the Gaussian kernel; the
identity of the reuse (a fit given the distances is the fit that computes them, bit for bit);
a search that reuses them scores every candidate exactly as fresh fits do, and so picks the
same hyperparameters on a seeded problem; and the count of distance matrices a search makes
(one per fold, not one per candidate and fold).
"""

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import ConvergenceWarning
from sklearn.model_selection import LeaveOneGroupOut

from nfs.learners import (IRLSSVMRegressor, LSSVMRegressor, MetaheuristicSearchCV, Real,
                          RVRRegressor, SVRRegressor)
from nfs.learners import kernels
from nfs.learners.kernels import (gaussian_kernel, kernel_from_sq_distances,
                                  squared_distances)


def _grouped(n_groups=5, per_group=30, seed=3):
    """Smooth target of two inputs of different units, runs as groups (seeded)."""
    rng = np.random.default_rng(seed)
    groups = np.repeat(np.arange(n_groups), per_group)
    X = np.column_stack([rng.uniform(-30.0, 50.0, groups.size),
                         rng.uniform(-0.5, 0.5, groups.size) + 0.1 * groups])
    y = 0.02 * np.sin(X[:, 0] / 15.0) + 0.05 * X[:, 1] + 0.001 * rng.standard_normal(groups.size)
    return X, y, groups


def test_squared_distances_closed_form_and_kernel():
    # Oracle: ||a - b||^2 by hand; exp(-d2 / (2 sigma^2)) by hand.
    A = np.array([[0.0, 0.0], [3.0, 4.0]])
    B = np.array([[1.0, 1.0]])
    d2 = squared_distances(A, B)
    assert d2.tolist() == [[2.0], [13.0]]
    D = squared_distances(A)
    assert np.array_equal(D, D.T) and np.all(np.diag(D) == 0.0) and D[0, 1] == 25.0
    np.testing.assert_allclose(kernel_from_sq_distances(d2, 2.0), np.exp(-d2 / 8.0),
                               rtol=1e-15)
    assert np.array_equal(kernel_from_sq_distances(D, 0.7), gaussian_kernel(A, sigma=0.7))
    with pytest.raises(ValueError, match="sigma"):
        kernel_from_sq_distances(D, 0.0)


@pytest.mark.parametrize("standardize", [True, False])
def test_training_sq_distances_are_those_of_the_scaled_inputs(standardize):
    # Oracle: the inputs standardised by hand (column means and population standard
    # deviations), then the squared distances by hand.
    X, _, _ = _grouped()
    d2 = RVRRegressor(standardize=standardize).training_sq_distances(X)
    Z = (X - X.mean(0)) / X.std(0) if standardize else X
    ref = ((Z[:, None, :] - Z[None, :, :]) ** 2).sum(-1)
    np.testing.assert_allclose(d2, ref, rtol=1e-12, atol=1e-12)


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")
@pytest.mark.parametrize("estimator", [RVRRegressor(sigma=1.5, max_iter=30),
                                       LSSVMRegressor(gamma=50.0, sigma=1.2),
                                       IRLSSVMRegressor(gamma=50.0, sigma=1.2,
                                                        weight="myriad"),
                                       SVRRegressor(C=5.0, sigma=1.2, epsilon=0.05)],
                         ids=lambda e: type(e).__name__)
def test_fit_given_the_distances_is_the_fit_that_computes_them(estimator):
    # Oracle: identity.  The distances passed are those fit computes, so every bit agrees.
    X, y, _ = _grouped()
    plain = clone(estimator).fit(X, y)
    d2 = estimator.training_sq_distances(X)
    reused = clone(estimator).fit(X, y, sq_distances=d2)
    assert np.array_equal(plain.predict(X), reused.predict(X))
    with pytest.raises(ValueError, match="sq_distances"):
        clone(estimator).fit(X, y, sq_distances=d2[:-1, :-1])


def test_search_reuses_one_distance_matrix_per_fold_and_scores_as_fresh_fits(monkeypatch):
    # Oracles: (1) count: the search makes one distance matrix per fold (5), not one per
    # candidate and fold (budget x 5); (2) identity: every candidate's fold scores equal
    # those of a fresh fit without the distances, so the tuner's path and its chosen sigma
    # are those of a search that recomputes them.
    X, y, groups = _grouped()
    calls = []
    original = kernels.KernelRegressor.training_sq_distances

    def counted(self, Xtrain):
        calls.append(len(Xtrain))
        return original(self, Xtrain)

    monkeypatch.setattr(kernels.KernelRegressor, "training_sq_distances", counted)
    search = MetaheuristicSearchCV(RVRRegressor(max_iter=30, tol=1e-2),
                                   {"sigma": Real(0.3, 10.0, log=True)}, method="hho",
                                   budget=8, random_state=4, scoring="neg_mean_squared_error")
    with pytest.warns(ConvergenceWarning):    # the refit, 30 sweeps
        search.fit(X, y, groups=groups)
    splits = list(LeaveOneGroupOut().split(X, y, groups))
    assert calls == [len(train) for train, _ in splits]
    for i, params in enumerate(search.cv_results_["params"]):
        for k, (train, test) in enumerate(splits):
            with pytest.warns(ConvergenceWarning):
                fresh = RVRRegressor(max_iter=30, tol=1e-2, **params).fit(X[train], y[train])
            score = -np.mean((y[test] - fresh.predict(X[test])) ** 2)
            assert search.cv_results_[f"split{k}_test_score"][i] == score
    best = int(np.argmax(search.cv_results_["mean_test_score"]))
    assert search.best_params_ == search.cv_results_["params"][best]


class _OwnDistances(SVRRegressor):
    """A kernel regressor whose fit takes no distances (it makes its own)."""

    def fit(self, X, y):
        return super().fit(X, y)


def test_search_without_distances_for_other_estimators(monkeypatch):
    # Invariant: a kernel regressor whose fit takes no distances is searched as before: no
    # distance matrix is made for it.
    X, y, groups = _grouped(n_groups=3, per_group=15)

    def refused(self, Xtrain):
        raise AssertionError("a distance matrix for an estimator that takes none")

    search = MetaheuristicSearchCV(_OwnDistances(), {"C": Real(0.1, 10.0, log=True)},
                                   method="grid", budget=3, random_state=0)
    monkeypatch.setattr(kernels.KernelRegressor, "training_sq_distances", refused)
    search.fit(X, y, groups=groups)
    assert search.n_evaluations_ == 3
