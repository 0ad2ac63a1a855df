"""The Gaussian kernel of the kernel regressors, and the input handling they share.

The kernel regressors (:mod:`~nfs.learners.svr`, :mod:`~nfs.learners.lssvm`,
:mod:`~nfs.learners.rvr`) map thermometer features X (n_samples, n_features) to the drift y
[deg/h] with the Gaussian RBF kernel written in the papers' width convention (Tao et al.
(2019) eq. (11); the FOG start-up paper Table 1 gives sigma)::

    k(x, x') = exp(-||x - x'||^2 / (2 sigma^2))        (gamma_libsvm = 1 / (2 sigma^2))

computed by one function, :func:`gaussian_kernel`, as ``exp(-D2 / (2 sigma^2))`` of the
squared distances D2 (:func:`squared_distances`, :func:`kernel_from_sq_distances`), and summed
over training points by :func:`kernel_expansion`.

Reuse.  The kernel of a new width is a cheap transform of the same squared distances, so a
search over sigma computes D2 once per training set (cross-validation fold) and each
candidate only exponentiates it: :meth:`KernelRegressor.training_sq_distances` gives D2 of
the inputs as ``fit`` scales them, and the tuned regressors' ``fit(X, y, sq_distances=D2)``
takes it instead of computing it again (bit for bit the same kernel).

Scaling.  With ``standardize=True`` (the default) every input column is standardised with
its training mean and standard deviation before the kernel is evaluated
(:class:`KernelRegressor`), so sigma is a width in units of the inputs' standard deviations
and means the same for a temperature [degC] and a rate [K/min].  None of the seeds states
how it scaled its inputs; this is our choice.  What is done to the target differs by model
and is stated in each class.

Equation numbers "Tao et al. (2019) eq. (n)" count the displayed equations of the stored
text of Tao, Li, Zheng, Wu & Fu 2019 (Sensors 19, 2986), which carries no numbers of its own.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils import gen_batches
from sklearn.utils.validation import check_is_fitted

from .validation import HyperparameterError, fit_scaling, validate

__all__ = [
    "PREDICT_BATCH",
    "sigma_to_gamma",
    "squared_distances",
    "kernel_from_sq_distances",
    "gaussian_kernel",
    "kernel_expansion",
    "KernelRegressor",
]

#: Rows of test inputs whose kernel row block is formed at once in ``predict`` (memory
#: ~ PREDICT_BATCH x n_train x 8 bytes).
PREDICT_BATCH = 2048


def sigma_to_gamma(sigma: float) -> float:
    """LIBSVM/scikit-learn RBF ``gamma`` [1/unit^2] for the width ``sigma`` [unit]:
    gamma = 1 / (2 sigma^2), so that exp(-gamma d^2) = exp(-d^2 / (2 sigma^2))."""
    return 1.0 / (2.0 * float(sigma) ** 2)


def squared_distances(XA: np.ndarray, XB: np.ndarray | None = None) -> np.ndarray:
    """Squared Euclidean distances D2[i, j] = ||XA[i] - XB[j]||^2 [unit of the inputs ^2].

    Parameters
    ----------
    XA : array (n_a, n_features)
    XB : array (n_b, n_features), optional
        Defaults to ``XA`` (the training set against itself).

    Returns
    -------
    D2 : array (n_a, n_b), >= 0, exactly 0 on the diagonal of D2(X, X).

    From ``scipy.spatial.distance.cdist`` (direct differences, no ||a||^2 + ||b||^2 - 2 a.b
    cancellation), so D2(X, X) is exactly symmetric.
    """
    XA = np.asarray(XA, dtype=float)
    XB = XA if XB is None else np.asarray(XB, dtype=float)
    return cdist(XA, XB, "sqeuclidean")


def kernel_from_sq_distances(d2: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian kernel exp(-D2 / (2 sigma^2)) of squared distances ``d2`` [unit^2] for the
    width ``sigma`` [unit], > 0 (Tao et al. (2019) eq. (11)); entries in (0, 1]."""
    return _gaussian_in_place(np.negative(np.asarray(d2, dtype=float)), sigma)


def _gaussian_in_place(minus_d2: np.ndarray, sigma: float) -> np.ndarray:
    """exp(-D2 / (2 sigma^2)) written over ``minus_d2`` (-D2, an array this module owns),
    the operations of the formula in its order: (-D2) / (2 sigma^2), then exp.  In place:
    a prediction's kernel rows (2048 x a few hundred) are megabytes, and each temporary of
    that size is a fresh mapping whose pages fault in on first touch (the kernel of 35 test
    runs against 470 support vectors: 0.20 s with two temporaries, 0.06 s in place)."""
    sigma = float(sigma)
    if not (np.isfinite(sigma) and sigma > 0.0):
        raise HyperparameterError(f"kernel width sigma must be a positive number, got {sigma}")
    minus_d2 /= 2.0 * sigma * sigma
    return np.exp(minus_d2, out=minus_d2)


def gaussian_kernel(XA: np.ndarray, XB: np.ndarray | None = None, sigma: float = 1.0
                    ) -> np.ndarray:
    """Gaussian RBF Gram matrix K[i, j] = exp(-||XA[i] - XB[j]||^2 / (2 sigma^2)).

    Parameters
    ----------
    XA : array (n_a, n_features)
    XB : array (n_b, n_features), optional
        Defaults to ``XA`` (the training Gram matrix).
    sigma : float
        Kernel width [unit of the (standardised) inputs], > 0.  Tao et al. (2019) eq. (11) and the
        FOG
        start-up paper use this convention; Tao et al. (2019) reports sigma^2.

    Returns
    -------
    K : array (n_a, n_b), entries in (0, 1], exactly 1 on the diagonal of K(X, X).

    :func:`kernel_from_sq_distances` of :func:`squared_distances`, so K(X, X) is exactly
    symmetric.
    """
    d2 = squared_distances(XA, XB)
    return _gaussian_in_place(np.negative(d2, out=d2), sigma)


def kernel_expansion(Xs: np.ndarray, centers: np.ndarray, coef: np.ndarray,
                     intercept: float, sigma: float) -> np.ndarray:
    """f(x) = sum_k coef_k k(x, c_k) + intercept for every row x of ``Xs``, formed in row
    batches of :data:`PREDICT_BATCH`.

    Parameters
    ----------
    Xs : array (n, n_features)
        Inputs, scaled as the centres.
    centers : array (n_centers, n_features)
        Kernel centres c_k (the training inputs of LS-SVM).
    coef : array (n_centers,)
        Weights [unit of f].
    intercept : float
        [unit of f].
    sigma : float
        Kernel width [unit of the scaled inputs].
    """
    out = np.empty(Xs.shape[0])
    for sl in gen_batches(Xs.shape[0], PREDICT_BATCH):
        out[sl] = gaussian_kernel(Xs[sl], centers, sigma) @ coef + intercept
    return out


class KernelRegressor(RegressorMixin, BaseEstimator):
    """Base of the kernel regressors: validation and the (optional) standardisation of X
    and y (the attribute ``standardize`` of the subclass decides).

    Sets, in ``fit``, ``x_mean_`` and ``x_scale_`` (arrays (n_features,): zeros and ones when
    not standardised) and, when the target is scaled too, ``y_mean_`` and ``y_scale_``
    [unit of y].
    """

    def _fit_scaling(self, X: np.ndarray, y: np.ndarray | None, *, scale_y: bool
                     ) -> tuple[np.ndarray, np.ndarray | None]:
        if self.standardize:
            self.x_mean_, self.x_scale_ = fit_scaling(X)
        else:
            self.x_mean_ = np.zeros(X.shape[1])
            self.x_scale_ = np.ones(X.shape[1])
        if not scale_y:
            return self._scale_X(X), y
        if self.standardize:
            m, s = fit_scaling(y[:, None])
            self.y_mean_, self.y_scale_ = float(m[0]), float(s[0])
        else:
            self.y_mean_, self.y_scale_ = 0.0, 1.0
        return self._scale_X(X), (y - self.y_mean_) / self.y_scale_

    def _scale_X(self, X: np.ndarray) -> np.ndarray:
        return (np.asarray(X, dtype=float) - self.x_mean_) / self.x_scale_

    def training_sq_distances(self, X) -> np.ndarray:
        """Squared distances between the rows of ``X`` scaled as :meth:`fit` scales them
        (standardised with X's own means and standard deviations when ``standardize``)
        [standard deviations^2, or unit^2 of X], shape (n, n).

        What a search computes once per training set and passes to ``fit(X, y,
        sq_distances=...)`` of every candidate (a new sigma only rescales it); the
        estimator is not changed.
        """
        X = np.asarray(X, dtype=float)
        if self.standardize:
            mean, scale = fit_scaling(X)
            X = (X - mean) / scale
        return squared_distances(X)

    def _train_sq_distances(self, Xs: np.ndarray, sq_distances) -> np.ndarray:
        """D2 of the scaled training inputs ``Xs``: ``sq_distances`` when given (checked
        for its shape), computed otherwise."""
        if sq_distances is None:
            return squared_distances(Xs)
        d2 = np.asarray(sq_distances, dtype=float)
        n = Xs.shape[0]
        if d2.shape != (n, n):
            raise ValueError(f"sq_distances must be the ({n}, {n}) squared distances of the "
                             f"training inputs, got shape {d2.shape}")
        return d2

    def _validate_fit(self, X, y):
        X, y = validate(self, X, y, reset=True)
        return X, np.asarray(y, dtype=float)

    def _validate_predict(self, X):
        check_is_fitted(self)
        X = validate(self, X, reset=False)
        return self._scale_X(X)
