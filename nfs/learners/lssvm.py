"""Least-squares support vector machines: LS-SVM and the robust, iteratively reweighted IR-LS-SVM.

LS-SVM (Suykens et al. 2002, "Least Squares Support Vector Machines", World Scientific;
Tao et al. (2019) eq. (5)-(10)) replaces the SVR's tube by squared errors, so that training
is one linear KKT system (:func:`lssvm_solve`); IR-LS-SVM (Suykens, De Brabanter, Lukas &
Vandewalle 2002, Neurocomputing 48; De Brabanter et al. 2009; Tao et al. (2019) eq. (12)-(20),
Table 5) weights the squared errors by a robust weight of each residual
(:mod:`~nfs.learners.weights`) and solves again.  Both use the Gaussian kernel of
:mod:`~nfs.learners.kernels` and are the model of Tao et al. (2019).

Equation numbers "Tao et al. (2019) eq. (n)" count the displayed equations of its stored text
(see :mod:`nfs.learners.kernels`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.linalg

from .kernels import KernelRegressor, kernel_expansion, kernel_from_sq_distances
from .validation import HyperparameterError, check_count, check_positive
from .weights import get_weight_function, robust_scale

__all__ = ["lssvm_solve", "LSSVMRegressor", "IRLSSVMRegressor"]


def lssvm_solve(K: np.ndarray, y: np.ndarray, gamma: float,
                weights: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Solve the (weighted) LS-SVM KKT system for the support values alpha and bias b.

    Tao et al. (2019) eq. (8) (unweighted) and eq. (14) (weighted; Suykens et al. 2002,
    Neurocomputing 48)::

        [ 0        1^T               ] [ b     ]   [ 0 ]
        [ 1   K + diag(1/(gamma v))  ] [ alpha ] = [ y ]

    solved through the Schur complement of H = K + diag(1/(gamma v)), which is symmetric
    positive definite: with H eta = 1 and H nu = y (one Cholesky factorisation),
    b = 1^T nu / 1^T eta and alpha = nu - b eta (Suykens et al. 2002, LS-SVM book, ch. 3;
    not checked to equation number).  If H is numerically not positive definite (gamma
    huge and duplicated inputs) the full system is solved by least squares instead.

    Parameters
    ----------
    K : array (n, n)
        Kernel Gram matrix of the training inputs.
    y : array (n,)
        Targets [unit of y].
    gamma : float
        Regularisation constant (the papers' c) [-], > 0.
    weights : array (n,), optional
        Weights v_k > 0 of the squared errors (1 when omitted: plain LS-SVM).

    Returns
    -------
    alpha : array (n,)
        Support values [unit of y]; sum(alpha) = 0 and alpha_k = gamma v_k e_k with e_k the
        training residual y_k - f(x_k).
    b : float
        Bias [unit of y].

    Cost: O(n^3 / 3) flops and n^2 doubles (n = 3000: ~9e9 flops, 72 MB; the caller
    decimates a start-up record to ~1000 samples).
    """
    y = np.asarray(y, dtype=float)
    n = y.shape[0]
    v = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
    H = np.array(K, dtype=float, copy=True)
    H[np.diag_indices(n)] += 1.0 / (gamma * v)
    try:
        c = scipy.linalg.cho_factor(H, lower=True, check_finite=False)
        sol = scipy.linalg.cho_solve(c, np.column_stack([np.ones(n), y]), check_finite=False)
        eta, nu = sol[:, 0], sol[:, 1]
        b = nu.sum() / eta.sum()
        alpha = nu - b * eta
    except np.linalg.LinAlgError:
        A = np.zeros((n + 1, n + 1))
        A[0, 1:] = A[1:, 0] = 1.0
        A[1:, 1:] = H
        sol = scipy.linalg.lstsq(A, np.concatenate([[0.0], y]), check_finite=False)[0]
        b, alpha = sol[0], sol[1:]
    return alpha, float(b)


class LSSVMRegressor(KernelRegressor):
    """Least-squares support vector machine regression (Suykens et al. 2002, "Least Squares
    Support Vector Machines", World Scientific, ch. 3; Tao et al. (2019) eq. (5)-(10)).

    Primal (Tao et al. (2019) eq. (5))::

        min 1/2 w^T w + gamma/2 sum_k e_k^2,   y_k = w^T phi(x~_k) + b + e_k

    whose dual is the KKT system of :func:`lssvm_solve` (Tao et al. (2019) eq. (8)) and the model
    (Tao et al. (2019) eq. (10))::

        y(x) = sum_k alpha_k k(x~, x~_k) + b

    with k the Gaussian kernel of width ``sigma`` (Tao et al. (2019) eq. (11)).  The solution is
    linear in y, so the target is not rescaled: ``alpha_`` and ``b_`` are in units of y.

    Parameters
    ----------
    gamma : float, default 1.0
        Regularisation constant (the papers' c) [-], > 0: large fits the data closely, small
        smooths.  Not LIBSVM's kernel gamma.  Tao et al. (2019) Table 5 ("Unweighted"): c = 1362.4.
    sigma : float, default 1.0
        Kernel width [standard deviations of the inputs when ``standardize``], > 0.  Tao et al.
        (2019)
        reports sigma^2 (Table 5: 0.9771, in its own input units): pass sigma = sqrt(sigma2).
    standardize : bool, default True
        Standardise each input column with its training mean and standard deviation.

    Attributes
    ----------
    alpha_ : array (n_samples,)
        Support values [unit of y]; ``sum(alpha_) = 0`` (the constraint from dL/db = 0).
    b_ : float
        Bias [unit of y].
    X_fit_ : array (n_samples, n_features)
        The training inputs, as given (every one is a support vector: LS-SVM is not sparse).
    x_mean_, x_scale_ : arrays (n_features,)
        Input standardisation (zeros and ones when not standardised).
    n_features_in_ : int

    Cost: fit O(n^3 / 3) flops and n^2 doubles (n = 3000: ~9e9 flops, 72 MB); predict
    O(n_test n) (n = 3934, the default training set: 0.8 s to fit).
    """

    def __init__(self, gamma: float = 1.0, sigma: float = 1.0, standardize: bool = True):
        self.gamma = gamma
        self.sigma = sigma
        self.standardize = standardize

    def _prepare(self, X, y, sq_distances):
        X, y = self._validate_fit(X, y)
        gamma = check_positive("gamma", self.gamma)
        sigma = check_positive("sigma", self.sigma)
        Xs, y = self._fit_scaling(X, y, scale_y=False)
        self.X_fit_ = X
        return (kernel_from_sq_distances(self._train_sq_distances(Xs, sq_distances), sigma),
                y, gamma)

    def fit(self, X, y, sq_distances=None):
        """Fit on features X (n_samples, n_features) and drift y (n_samples,). Returns self.

        ``sq_distances``: the squared distances of the scaled training inputs
        (:meth:`~nfs.learners.kernels.KernelRegressor.training_sq_distances` of X) when a
        search already holds them."""
        K, y, gamma = self._prepare(X, y, sq_distances)
        self.alpha_, self.b_ = lssvm_solve(K, y, gamma)
        return self

    def predict(self, X) -> np.ndarray:
        """Predicted drift [unit of y] for features X (n_samples, n_features)."""
        Xs = self._validate_predict(X)
        return kernel_expansion(Xs, self._scale_X(self.X_fit_), self.alpha_, self.b_,
                                 self.sigma)


class IRLSSVMRegressor(LSSVMRegressor):
    """Iteratively reweighted LS-SVM: robust LS-SVM regression (Suykens, De Brabanter, Lukas
    & Vandewalle 2002, Neurocomputing 48, 85-105; De Brabanter et al. 2009 for the logistic
    and myriad weights; Tao et al. (2019) section 2.3, eq. (12)-(20)).

    Primal (Tao et al. (2019) eq. (12))::

        min 1/2 w^T w + gamma/2 sum_k v_k e_k^2,   y_k = w^T phi(x~_k) + b + e_k

    Algorithm (Tao et al. (2019) section 2.3; iterated as De Brabanter et al. 2009):

    1. plain LS-SVM (Tao et al. (2019) eq. (8)): alpha, b; residuals e_k = alpha_k / gamma;
    2. robust scale s = 1.483 MAD(e) (:func:`~nfs.learners.weights.robust_scale`, Tao et
       al. (2019) eq. (20));
    3. weights v_k = W(e_k / s) with W one of
       :data:`~nfs.learners.weights.WEIGHT_FUNCTIONS`;
    4. solve the weighted system (Tao et al. (2019) eq. (14)): diagonal K + diag(1 / (gamma v_k));
       new residuals e_k = alpha_k / (gamma v_k) (= y_k - f(x_k));
    5. repeat 2-4 until the weights change by less than ``tol`` (``max |v_new - v_old|``) or
       ``max_iter`` weighted solves.  ``max_iter=1`` is the single reweighting of Suykens et
       al. 2002 and of Tao et al.'s (2019) algorithm.

    The model is y(x) = sum_k alpha_k k(x~, x~_k) + b, as LS-SVM.

    Parameters
    ----------
    gamma : float, default 1.0
        Regularisation constant (the papers' c) [-], > 0.  Tao et al. (2019) Table 5 (T, dT/dt, U
        inputs): 4.058e5 Huber, 26.32 Hampel, 3.478e4 logistic, 76.08 myriad.
    sigma : float, default 1.0
        Kernel width [standard deviations of the inputs when ``standardize``], > 0.  Tao et al.
        (2019)
        gives sigma^2 (Table 5: 2.2799, 0.1263, 1.0623, 0.1458): pass sqrt.
    weight : str or callable, default "huber"
        "huber", "hampel", "logistic", "myriad" or "unweighted"
        (:data:`~nfs.learners.weights.WEIGHT_FUNCTIONS`),
        or a function v = f(r) returning positive finite weights.
    max_iter : int, default 10
        Maximum number of weighted solves (>= 1).
    tol : float, default 1e-4
        Stop when ``max_k |v_k(new) - v_k(old)| < tol`` [-].
    beta : float, default 1.345
        Huber corner [-] (:func:`~nfs.learners.weights.huber_weight`).
    c1, c2 : float, default 2.5, 3.0
        Hampel knots [-] (:func:`~nfs.learners.weights.hampel_weight`; Tao et al.'s (2019)
        b1, b2).
    delta : float, default 2.385
        Myriad parameter [-] (:func:`~nfs.learners.weights.myriad_weight`).
    standardize : bool, default True
        Standardise each input column with its training mean and standard deviation.

    Attributes
    ----------
    alpha_, b_, X_fit_, x_mean_, x_scale_, n_features_in_ : as :class:`LSSVMRegressor`
        (``sum(alpha_) = 0`` still holds).
    weights_ : array (n_samples,)
        Final weights v_k [-] (small for the points treated as outliers).
    scale_ : float
        Last robust scale s [unit of y].
    n_iter_ : int
        Number of weighted solves made (0 if the plain fit had zero robust scale).
    """

    def __init__(self, gamma: float = 1.0, sigma: float = 1.0, weight="huber",
                 max_iter: int = 10, tol: float = 1e-4, beta: float = 1.345,
                 c1: float = 2.5, c2: float = 3.0, delta: float = 2.385,
                 standardize: bool = True):
        self.gamma = gamma
        self.sigma = sigma
        self.weight = weight
        self.max_iter = max_iter
        self.tol = tol
        self.beta = beta
        self.c1 = c1
        self.c2 = c2
        self.delta = delta
        self.standardize = standardize

    def _weight_callable(self) -> Callable[[np.ndarray], np.ndarray]:
        if callable(self.weight):
            return self.weight
        entry = get_weight_function(self.weight)
        params = {name: check_positive(name, getattr(self, name)) for name in entry.params}
        if "c1" in params and not params["c1"] < params["c2"]:
            raise HyperparameterError(
                f"Hampel knots need c1 < c2, got c1={self.c1!r}, c2={self.c2!r}")
        return lambda r: entry.func(r, **params)

    def fit(self, X, y, sq_distances=None):
        """Fit on features X (n_samples, n_features) and drift y (n_samples,). Returns self.

        ``sq_distances``: as :meth:`LSSVMRegressor.fit`."""
        W = self._weight_callable()
        max_iter = check_count("max_iter", self.max_iter)
        tol = check_positive("tol", self.tol)
        K, y, gamma = self._prepare(X, y, sq_distances)
        alpha, b = lssvm_solve(K, y, gamma)
        v = np.ones_like(y)
        e = alpha / gamma
        s = robust_scale(e)
        n_iter = 0
        for _ in range(max_iter):
            s = robust_scale(e)
            if not (np.isfinite(s) and s > 0.0):
                break                     # residuals (mostly) zero: nothing to reweight
            v_new = np.asarray(W(e / s), dtype=float)
            if v_new.shape != y.shape or not np.all(np.isfinite(v_new) & (v_new > 0.0)):
                raise HyperparameterError(
                    f"weight function {self.weight!r} must return one positive finite weight "
                    "per sample (floor zero weights, e.g. at 1e-4 as Suykens et al. 2002)")
            alpha, b = lssvm_solve(K, y, gamma, v_new)
            e = alpha / (gamma * v_new)
            n_iter += 1
            change = float(np.max(np.abs(v_new - v)))
            v = v_new
            if change < tol:
                break
        self.alpha_, self.b_ = alpha, b
        self.weights_ = v
        self.scale_ = s
        self.n_iter_ = n_iter
        return self

