"""Kernel regressors for the FOG thermal drift: SVR, LS-SVM, robust IR-LS-SVM and RVR.

Each maps thermometer features X (n_samples, n_features) to the drift y [deg/h] and is a
scikit-learn regressor (style.md practice 7).  All use the Gaussian RBF kernel written in the
papers' width convention (Tao et al. (2019) eq. (11); the FOG start-up paper Table 1 gives sigma)::

    k(x, x') = exp(-||x - x'||^2 / (2 sigma^2))        (gamma_libsvm = 1 / (2 sigma^2))

computed by one function, :func:`gaussian_kernel` (LIBSVM evaluates the same formula inside
:class:`SVRRegressor` with ``gamma = sigma_to_gamma(sigma)``).

Scaling.  With ``standardize=True`` (the default) every input column is standardised with
its training mean and standard deviation before the kernel is evaluated, so sigma is a width
in units of the inputs' standard deviations and means the same for a temperature [degC] and a
rate [K/min].  None of the seeds states how it scaled its inputs; this is our choice.  What
is done to the target differs by model and is stated in each class.

Models
------
:class:`SVRRegressor`      epsilon-SVR (LIBSVM, Chang & Lin 2011), the model SSA/PSO/GWO tune
                           in the FOG start-up paper (Table 1: C 1.0520, sigma 0.9506).
:class:`LSSVMRegressor`    least-squares SVM (Suykens et al. 2002), Tao et al. (2019) eq. (8), (10).
:class:`IRLSSVMRegressor`  iteratively reweighted LS-SVM with the Huber, Hampel, logistic and
                           myriad weights (Suykens, De Brabanter, Lukas & Vandewalle 2002;
                           De Brabanter et al. 2009), Tao et al. (2019) eq. (14)-(18), Table 5.
:class:`RVRRegressor`      relevance vector regression (Tipping 2001), Liang et al.'s (2021) model.

Equation numbers "Tao et al. (2019) eq. (n)" count the displayed equations of the stored text of
Tao,
Li, Zheng, Wu & Fu 2019 (Sensors 19, 2986), which carries no numbers of its own.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
from scipy.spatial.distance import cdist
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.exceptions import ConvergenceWarning
from sklearn.svm import SVR
from sklearn.utils import gen_batches
from sklearn.utils.validation import check_is_fitted

try:                                     # scikit-learn >= 1.6
    from sklearn.utils.validation import validate_data
except ImportError:                      # pragma: no cover - scikit-learn 1.3 to 1.5
    def validate_data(estimator, X, y="no_validation", **kwargs):
        return estimator._validate_data(X, y, **kwargs)

from ..errors import NfsError

__all__ = [
    "HyperparameterError",
    "gaussian_kernel",
    "sigma_to_gamma",
    "lssvm_solve",
    "robust_scale",
    "unit_weight",
    "huber_weight",
    "hampel_weight",
    "logistic_weight",
    "myriad_weight",
    "WeightFunction",
    "WEIGHT_FUNCTIONS",
    "get_weight_function",
    "SVRRegressor",
    "LSSVMRegressor",
    "IRLSSVMRegressor",
    "RVRRegressor",
]

#: Rows of test inputs whose kernel row block is formed at once in ``predict`` (memory
#: ~ _PREDICT_BATCH x n_train x 8 bytes).
_PREDICT_BATCH = 2048

#: Floor of the Hampel weight beyond c2 (Suykens et al. 2002, Neurocomputing 48, the
#: weighted LS-SVM weights).  Tao et al. (2019) writes 0 there, which makes 1/(gamma v_k)
#: infinite in the KKT system; LS-SVMlab's weightingscheme.m uses 1e-7.
HAMPEL_FLOOR = 1e-4


class HyperparameterError(NfsError, ValueError):
    """A compensator hyperparameter out of its domain (raised by ``fit``, never ``__init__``).

    Also a ValueError, as scikit-learn's own estimators raise for bad parameters.
    """


# --------------------------------------------------------------------------------------
# kernel and shared numerics
# --------------------------------------------------------------------------------------

def sigma_to_gamma(sigma: float) -> float:
    """LIBSVM/scikit-learn RBF ``gamma`` [1/unit^2] for the width ``sigma`` [unit]:
    gamma = 1 / (2 sigma^2), so that exp(-gamma d^2) = exp(-d^2 / (2 sigma^2))."""
    return 1.0 / (2.0 * float(sigma) ** 2)


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

    The squared distances come from ``scipy.spatial.distance.cdist`` (direct differences,
    no ||a||^2 + ||b||^2 - 2 a.b cancellation), so K(X, X) is exactly symmetric.
    """
    sigma = float(sigma)
    if not (np.isfinite(sigma) and sigma > 0.0):
        raise HyperparameterError(f"kernel width sigma must be a positive number, got {sigma}")
    XA = np.asarray(XA, dtype=float)
    XB = XA if XB is None else np.asarray(XB, dtype=float)
    d2 = cdist(XA, XB, "sqeuclidean")
    return np.exp(-d2 / (2.0 * sigma * sigma))


def _center_scale(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Column means and standard deviations (ddof 0); a constant column gets scale 1."""
    mean = A.mean(axis=0)
    scale = A.std(axis=0)
    tiny = 10.0 * np.finfo(float).eps * np.maximum(1.0, np.abs(mean))
    scale = np.where(scale > tiny, scale, 1.0)
    return mean, scale


def _check_positive(name: str, value, *, allow_inf: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise HyperparameterError(f"{name} must be a positive number, got {value!r}") from None
    if not (v > 0.0 and (allow_inf or np.isfinite(v))):
        raise HyperparameterError(f"{name} must be a positive number, got {value!r}")
    return v


def _check_count(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise HyperparameterError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def _spd_inverse(H: np.ndarray) -> np.ndarray:
    """Inverse of a symmetric positive definite matrix (LAPACK potrf + potri; eigen-
    decomposition with the eigenvalues floored at eps x the largest if the Cholesky
    factorisation fails numerically)."""
    c, info = scipy.linalg.lapack.dpotrf(H, lower=True, clean=True)
    if info == 0:
        inv, info = scipy.linalg.lapack.dpotri(c, lower=True)
    if info == 0:
        low = np.tril(inv)
        return low + np.tril(inv, -1).T
    w, V = np.linalg.eigh(H)
    w = np.maximum(w, np.finfo(float).eps * max(w.max(), np.finfo(float).tiny))
    return (V / w) @ V.T


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


def _kernel_expansion(Xs: np.ndarray, centers: np.ndarray, coef: np.ndarray,
                      intercept: float, sigma: float) -> np.ndarray:
    """f(x) = sum_k coef_k k(x, c_k) + intercept, formed in row batches."""
    out = np.empty(Xs.shape[0])
    for sl in gen_batches(Xs.shape[0], _PREDICT_BATCH):
        out[sl] = gaussian_kernel(Xs[sl], centers, sigma) @ coef + intercept
    return out


# --------------------------------------------------------------------------------------
# robust weights (Tao et al. (2019) eq. (15)-(18); De Brabanter et al. 2009)
# --------------------------------------------------------------------------------------

def robust_scale(e: np.ndarray) -> float:
    """Robust standard deviation s = 1.483 MAD(e), MAD(e) = median |e_k - median(e)|.

    Tao et al. (2019) eq. (20); Suykens et al. 2002 (Neurocomputing 48).  1.483 ~ 1/Phi^-1(3/4)
    makes s consistent with the standard deviation for Gaussian errors.  [unit of e]
    """
    e = np.asarray(e, dtype=float)
    return float(1.483 * np.median(np.abs(e - np.median(e))))


def unit_weight(r: np.ndarray) -> np.ndarray:
    """The null weight v = 1 for every standardised residual r (plain LS-SVM; Tao et al.'s (2019)
    "Unweighted" row of Table 5)."""
    return np.ones_like(np.asarray(r, dtype=float))


def huber_weight(r: np.ndarray, beta: float = 1.345) -> np.ndarray:
    """Huber weight (Tao et al. (2019) eq. (15); De Brabanter et al. 2009)::

        v(r) = 1           if |r| < beta
               beta / |r|  if |r| >= beta

    r = e_k / s [-] is the standardised residual; beta [-] the corner.  Default 1.345, the
    usual constant for 95 % efficiency at Gaussian errors (Holland & Welsch 1977); Tao et al. (2019)
    tunes it by robust cross-validation and does not give its value.
    """
    a = np.abs(np.asarray(r, dtype=float))
    with np.errstate(divide="ignore"):
        return np.where(a < beta, 1.0, beta / np.where(a < beta, 1.0, a))


def hampel_weight(r: np.ndarray, c1: float = 2.5, c2: float = 3.0) -> np.ndarray:
    """Hampel weight (Tao et al. (2019) eq. (16), with c1 = b1 = 2.5, c2 = b2 = 3 as there)::

        v(r) = 1                       if |r| <= c1
               (c2 - |r|) / (c2 - c1)  if c1 < |r| <= c2
               1e-4                    otherwise

    The floor 1e-4 (:data:`HAMPEL_FLOOR`) is that of Suykens et al. 2002; Tao et al. (2019) writes
    0,
    which would make the weighted KKT system infinite.  The ramp is floored at it too, so v
    is continuous at |r| = c2.  r [-], c1 < c2 [-].
    """
    a = np.abs(np.asarray(r, dtype=float))
    ramp = (c2 - a) / (c2 - c1)
    v = np.where(a <= c1, 1.0, np.where(a <= c2, ramp, HAMPEL_FLOOR))
    return np.maximum(v, HAMPEL_FLOOR)


def logistic_weight(r: np.ndarray) -> np.ndarray:
    """Logistic weight v(r) = tanh(r) / r, with v(0) = 1 (its limit) (Tao et al. (2019) eq. (17);
    De Brabanter et al. 2009).  r [-]."""
    r = np.asarray(r, dtype=float)
    small = np.abs(r) < 1e-8
    with np.errstate(invalid="ignore", divide="ignore"):
        v = np.tanh(r) / np.where(small, 1.0, r)
    return np.where(small, 1.0, v)


def myriad_weight(r: np.ndarray, delta: float = 2.385) -> np.ndarray:
    """Myriad weight v(r) = delta^2 / (delta^2 + r^2) (Tao et al. (2019) eq. (18); De Brabanter et
    al. 2009).  r [-]; delta [-] the linearity parameter (small: robust, large: least
    squares).  Default 2.385, the Cauchy-weight constant for 95 % Gaussian efficiency
    (Holland & Welsch 1977); Tao et al. (2019) tunes delta by robust cross-validation."""
    r = np.asarray(r, dtype=float)
    d2 = float(delta) ** 2
    return d2 / (d2 + r * r)


@dataclass(frozen=True)
class WeightFunction:
    """One entry of :data:`WEIGHT_FUNCTIONS`."""

    func: Callable[..., np.ndarray]
    """v = func(r, **params): weight [-] of a standardised residual r [-]."""
    params: tuple[str, ...]
    """Names of the IRLSSVMRegressor hyperparameters passed to ``func`` as keywords."""


#: Weight-function registry: name -> function and the hyperparameters it takes.
#: "unweighted" is the null weight (plain LS-SVM).  A user's own function v(r) plugs in by
#: passing it as ``IRLSSVMRegressor(weight=my_function)``.
WEIGHT_FUNCTIONS: dict[str, WeightFunction] = {
    "unweighted": WeightFunction(unit_weight, ()),
    "huber": WeightFunction(huber_weight, ("beta",)),
    "hampel": WeightFunction(hampel_weight, ("c1", "c2")),
    "logistic": WeightFunction(logistic_weight, ()),
    "myriad": WeightFunction(myriad_weight, ("delta",)),
}


def get_weight_function(name: str) -> WeightFunction:
    """The registry entry for ``name`` (case-insensitive); HyperparameterError listing the
    valid names otherwise."""
    try:
        return WEIGHT_FUNCTIONS[str(name).lower()]
    except KeyError:
        raise HyperparameterError(
            f"unknown weight function {name!r}; valid: {', '.join(WEIGHT_FUNCTIONS)}, "
            "or a callable v = f(r)") from None


# --------------------------------------------------------------------------------------
# estimators
# --------------------------------------------------------------------------------------

class _KernelRegressor(RegressorMixin, BaseEstimator):
    """Shared input handling: validation and the (optional) standardisation of X and y."""

    def _fit_scaling(self, X: np.ndarray, y: np.ndarray | None, *, scale_y: bool
                     ) -> tuple[np.ndarray, np.ndarray | None]:
        if self.standardize:
            self.x_mean_, self.x_scale_ = _center_scale(X)
        else:
            self.x_mean_ = np.zeros(X.shape[1])
            self.x_scale_ = np.ones(X.shape[1])
        if not scale_y:
            return self._scale_X(X), y
        if self.standardize:
            m, s = _center_scale(y[:, None])
            self.y_mean_, self.y_scale_ = float(m[0]), float(s[0])
        else:
            self.y_mean_, self.y_scale_ = 0.0, 1.0
        return self._scale_X(X), (y - self.y_mean_) / self.y_scale_

    def _scale_X(self, X: np.ndarray) -> np.ndarray:
        return (np.asarray(X, dtype=float) - self.x_mean_) / self.x_scale_

    def _validate_fit(self, X, y):
        X, y = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        return X, np.asarray(y, dtype=float)

    def _validate_predict(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, dtype=np.float64)
        return self._scale_X(X)


class SVRRegressor(_KernelRegressor):
    """Epsilon-support vector regression with the Gaussian kernel in the sigma convention.

    The model (Tao et al. (2019) eq. (2)-(4); Vapnik; LIBSVM, Chang & Lin 2011, ACM TIST 2(3) 27,
    the
    solver the FOG start-up paper cites) on the scaled problem (x~, y~)::

        f~(x~) = sum_k (a_k - a_k*) k(x~, x~_k) + b,   0 <= a_k, a_k* <= C
        min 1/2 ||w||^2 + C sum_k (xi_k + xi_k*),  |y~_k - f~(x~_k)| <= epsilon + xi_k(*)

    with k the Gaussian kernel of width ``sigma`` (LIBSVM's ``gamma = 1/(2 sigma^2)``,
    :func:`sigma_to_gamma`) and the prediction ``y = y_mean_ + y_scale_ f~(x~)``.

    Parameters
    ----------
    C : float, default 1.0
        Penalty on errors outside the tube [-], > 0.  The FOG start-up paper Table 1: 1.0520
        (SSA-tuned).
    sigma : float, default 1.0
        Kernel width [standard deviations of the inputs when ``standardize``], > 0.  The FOG
        start-up paper
        Table 1: 0.9506.
    epsilon : float, default 0.01
        Half-width of the insensitive tube, in units of the training target's standard
        deviation when ``standardize`` (the tube is +-epsilon * std(y) in deg/h), in units of
        y otherwise; >= 0.
    standardize : bool, default True
        Standardise each input column, and centre the target and divide it by its standard
        deviation (x~ = (x - mean) / std, y~ = (y - mean_y) / std_y, training statistics),
        so that C, sigma and epsilon mean the same whatever the units.  False: x~ = x, y~ = y.

    Attributes
    ----------
    svr_ : sklearn.svm.SVR
        The fitted LIBSVM model on the scaled problem.
    x_mean_, x_scale_ : arrays (n_features,)
        Input standardisation (zeros and ones when not standardised).
    y_mean_, y_scale_ : float
        Target centring and scale [unit of y].
    n_features_in_ : int
    """

    def __init__(self, C: float = 1.0, sigma: float = 1.0, epsilon: float = 0.01,
                 standardize: bool = True):
        self.C = C
        self.sigma = sigma
        self.epsilon = epsilon
        self.standardize = standardize

    def fit(self, X, y):
        """Fit on features X (n_samples, n_features) and drift y (n_samples,). Returns self."""
        X, y = self._validate_fit(X, y)
        C = _check_positive("C", self.C)
        sigma = _check_positive("sigma", self.sigma)
        epsilon = float(self.epsilon)
        if not (np.isfinite(epsilon) and epsilon >= 0.0):
            raise HyperparameterError(f"epsilon must be >= 0, got {self.epsilon!r}")
        Xs, ys = self._fit_scaling(X, y, scale_y=True)
        self.svr_ = SVR(kernel="rbf", gamma=sigma_to_gamma(sigma), C=C,
                        epsilon=epsilon).fit(Xs, ys)
        return self

    def predict(self, X) -> np.ndarray:
        """Predicted drift [unit of y] for features X (n_samples, n_features)."""
        Xs = self._validate_predict(X)
        return self.y_mean_ + self.y_scale_ * self.svr_.predict(Xs)


class LSSVMRegressor(_KernelRegressor):
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

    def _prepare(self, X, y):
        X, y = self._validate_fit(X, y)
        gamma = _check_positive("gamma", self.gamma)
        sigma = _check_positive("sigma", self.sigma)
        Xs, y = self._fit_scaling(X, y, scale_y=False)
        self.X_fit_ = X
        return gaussian_kernel(Xs, Xs, sigma), y, gamma

    def fit(self, X, y):
        """Fit on features X (n_samples, n_features) and drift y (n_samples,). Returns self."""
        K, y, gamma = self._prepare(X, y)
        self.alpha_, self.b_ = lssvm_solve(K, y, gamma)
        return self

    def predict(self, X) -> np.ndarray:
        """Predicted drift [unit of y] for features X (n_samples, n_features)."""
        Xs = self._validate_predict(X)
        return _kernel_expansion(Xs, self._scale_X(self.X_fit_), self.alpha_, self.b_,
                                 self.sigma)


class IRLSSVMRegressor(LSSVMRegressor):
    """Iteratively reweighted LS-SVM: robust LS-SVM regression (Suykens, De Brabanter, Lukas
    & Vandewalle 2002, Neurocomputing 48, 85-105; De Brabanter et al. 2009 for the logistic
    and myriad weights; Tao et al. (2019) section 2.3, eq. (12)-(20)).

    Primal (Tao et al. (2019) eq. (12))::

        min 1/2 w^T w + gamma/2 sum_k v_k e_k^2,   y_k = w^T phi(x~_k) + b + e_k

    Algorithm (Tao et al. (2019) section 2.3; iterated as De Brabanter et al. 2009):

    1. plain LS-SVM (Tao et al. (2019) eq. (8)): alpha, b; residuals e_k = alpha_k / gamma;
    2. robust scale s = 1.483 MAD(e) (:func:`robust_scale`, Tao et al. (2019) eq. (20));
    3. weights v_k = W(e_k / s) with W one of :data:`WEIGHT_FUNCTIONS`;
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
        "huber", "hampel", "logistic", "myriad" or "unweighted" (:data:`WEIGHT_FUNCTIONS`),
        or a function v = f(r) returning positive finite weights.
    max_iter : int, default 10
        Maximum number of weighted solves (>= 1).
    tol : float, default 1e-4
        Stop when ``max_k |v_k(new) - v_k(old)| < tol`` [-].
    beta : float, default 1.345
        Huber corner [-] (:func:`huber_weight`).
    c1, c2 : float, default 2.5, 3.0
        Hampel knots [-] (:func:`hampel_weight`; Tao et al.'s (2019) b1, b2).
    delta : float, default 2.385
        Myriad parameter [-] (:func:`myriad_weight`).
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
        params = {name: _check_positive(name, getattr(self, name)) for name in entry.params}
        if "c1" in params and not params["c1"] < params["c2"]:
            raise HyperparameterError(
                f"Hampel knots need c1 < c2, got c1={self.c1!r}, c2={self.c2!r}")
        return lambda r: entry.func(r, **params)

    def fit(self, X, y):
        """Fit on features X (n_samples, n_features) and drift y (n_samples,). Returns self."""
        W = self._weight_callable()
        max_iter = _check_count("max_iter", self.max_iter)
        tol = _check_positive("tol", self.tol)
        K, y, gamma = self._prepare(X, y)
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


class RVRRegressor(_KernelRegressor):
    """Relevance vector regression: sparse Bayesian kernel regression (Tipping 2001, JMLR 1,
    211-244, section 2; Liang et al.'s (2021) model, there tuned by Harris hawks optimisation).

    Written here by hand: no maintained scikit-learn-compatible RVR package exists.

    Model on the scaled problem (x~, t)::

        t = Phi w + noise,  noise ~ N(0, 1/beta),  Phi = [1, K(x~, x~_1), ..., K(x~, x~_N)]
        p(w_i | alpha_i) = N(0, 1/alpha_i)   (one precision per basis function, bias included)

    Posterior (Tipping 2001 eq. (12)-(13))::

        Sigma = (beta Phi^T Phi + diag(alpha))^-1,   mu = beta Sigma Phi^T t

    Evidence re-estimation (eq. (16)-(18))::

        g_i = 1 - alpha_i Sigma_ii,   alpha_i <- g_i / mu_i^2,
        1/beta <- ||t - Phi mu||^2 / (N - sum_i g_i)

    iterated from alpha_i = 1/N^2 and beta = 100 / var(t) (noise at a tenth of the target's
    standard deviation), pruning each basis function whose alpha_i exceeds
    ``alpha_threshold`` (its weight is then zero), until ``max |Delta log alpha_i|`` < ``tol``
    over the kept ones.  Prediction (eq. (21)-(22))::

        y(x) = phi(x)^T mu,   var(x) = 1/beta + phi(x)^T Sigma phi(x)

    mapped back as ``y_mean_ + y_scale_ y(x)`` and ``y_scale_ sqrt(var(x))``.  Not yet checked
    against Tipping 2001 down to the equation numbers above.

    Parameters
    ----------
    kernel : str, default "rbf"
        Basis kernel; only "rbf" (the Gaussian kernel, :func:`gaussian_kernel`), the one Liang et
        al. (2021) use.
    sigma : float, default 1.0
        Kernel width [standard deviations of the inputs when ``standardize``], > 0; the one
        hyperparameter Liang et al. (2021) tunes.
    max_iter : int, default 300
        Maximum number of re-estimation sweeps (>= 1).
    tol : float, default 1e-3
        Convergence threshold on ``max |Delta log alpha_i|`` [-].
    alpha_threshold : float, default 1e9
        Prune a basis function once its precision exceeds this [1/unit of t^2; t is the
        standardised target when ``standardize``].
    standardize : bool, default True
        Standardise the input columns, and centre the target and divide it by its standard
        deviation, so that ``alpha_threshold`` and the initial noise level mean the same
        whatever the units of y.

    Attributes
    ----------
    relevance_indices_ : array of int (n_rv,)
        Training-sample indices of the relevance vectors.
    relevance_vectors_ : array (n_rv, n_features)
        The relevance vectors (training inputs, as given).
    bias_used_ : bool
        Whether the bias basis function survived the pruning.
    alpha_ : array (n_basis,)
        Precisions of the kept basis functions (bias first when kept) [1/unit of t^2].
    beta_ : float
        Noise precision [1/unit of t^2].
    mu_ : array (n_basis,)
        Posterior mean weights [unit of t].
    Sigma_ : array (n_basis, n_basis)
        Posterior weight covariance [unit of t^2].
    x_mean_, x_scale_, y_mean_, y_scale_ : input and target scaling (see ``standardize``).
    n_iter_ : int
        Re-estimation sweeps made.
    converged_ : bool
        Whether the sweeps converged (else a ConvergenceWarning was issued: typically some
        alpha_i were still growing towards the threshold; their weights are ~0 already).
    n_features_in_ : int
    """

    _KERNELS = ("rbf",)

    def __init__(self, kernel: str = "rbf", sigma: float = 1.0, max_iter: int = 300,
                 tol: float = 1e-3, alpha_threshold: float = 1e9, standardize: bool = True):
        self.kernel = kernel
        self.sigma = sigma
        self.max_iter = max_iter
        self.tol = tol
        self.alpha_threshold = alpha_threshold
        self.standardize = standardize

    @staticmethod
    def _posterior(PtP: np.ndarray, Ptt: np.ndarray, alpha: np.ndarray, beta: float
                   ) -> tuple[np.ndarray, np.ndarray]:
        """mu and Sigma (Tipping 2001 eq. (12)-(13)) from Phi^T Phi and Phi^T t."""
        H = beta * PtP
        H[np.diag_indices_from(H)] += alpha
        Sigma = _spd_inverse(H)
        mu = beta * (Sigma @ Ptt)
        return mu, Sigma

    @staticmethod
    def _posterior_diag(PtP: np.ndarray, Ptt: np.ndarray, alpha: np.ndarray, beta: float
                        ) -> tuple[np.ndarray, np.ndarray]:
        """mu and the diagonal of Sigma, all that a re-estimation sweep needs: from the
        Cholesky factor H = L L^T, Sigma_ii = sum_k (L^-1)_ki^2 and mu = beta L^-T L^-1
        Phi^T t, without forming Sigma (the eigen-decomposition of :func:`_spd_inverse`
        when the factorisation fails)."""
        H = beta * PtP
        H[np.diag_indices_from(H)] += alpha
        c, info = scipy.linalg.lapack.dpotrf(H, lower=True, clean=True)
        if info == 0:
            Li, info = scipy.linalg.lapack.dtrtri(c, lower=True)
        if info == 0:
            return beta * (Li.T @ (Li @ Ptt)), np.einsum("ki,ki->i", Li, Li)
        w, V = np.linalg.eigh(H)
        w = np.maximum(w, np.finfo(float).eps * max(w.max(), np.finfo(float).tiny))
        return beta * (V @ ((V.T @ Ptt) / w)), np.einsum("ik,ik->i", V / w, V)

    def fit(self, X, y):
        """Fit on features X (n_samples, n_features) and drift y (n_samples,). Returns self."""
        X, y = self._validate_fit(X, y)
        if self.kernel not in self._KERNELS:
            raise HyperparameterError(
                f"unknown kernel {self.kernel!r}; valid: {', '.join(self._KERNELS)}")
        sigma = _check_positive("sigma", self.sigma)
        max_iter = _check_count("max_iter", self.max_iter)
        tol = _check_positive("tol", self.tol)
        threshold = _check_positive("alpha_threshold", self.alpha_threshold)
        Xs, t = self._fit_scaling(X, y, scale_y=True)
        n = Xs.shape[0]
        Phi = np.hstack([np.ones((n, 1)), gaussian_kernel(Xs, Xs, sigma)])
        PtP, Ptt = Phi.T @ Phi, Phi.T @ t        # formed once; sub-indexed as bases go
        tiny = np.finfo(float).tiny
        eps = np.finfo(float).eps

        keep = np.arange(n + 1)                 # column 0 is the bias
        alpha = np.full(n + 1, 1.0 / n**2)
        beta = 100.0 / max(float(np.var(t)), eps)
        n_iter, converged = 0, False
        for n_iter in range(1, max_iter + 1):
            Phi_k = Phi[:, keep]
            mu, diag = self._posterior_diag(PtP[np.ix_(keep, keep)], Ptt[keep], alpha[keep],
                                            beta)
            g = np.clip(1.0 - alpha[keep] * diag, eps, 1.0)
            with np.errstate(divide="ignore"):
                alpha_new = g / (mu * mu)
            rss = float(np.sum((t - Phi_k @ mu) ** 2))
            beta = max(n - float(g.sum()), eps * n) / max(rss, tiny)
            beta = min(beta, 1.0 / (eps * max(float(np.var(t)), eps)))  # noise >= 1e-8 std
            finite = np.isfinite(alpha_new)
            dlog = np.log(alpha_new[finite]) - np.log(alpha[keep][finite])
            change = float(np.max(np.abs(dlog), initial=0.0))
            alpha[keep] = alpha_new
            keep = keep[alpha_new < threshold]
            if keep.size == 0 or (change < tol and np.all(finite)):
                converged = True
                break
        if not converged:
            warnings.warn(f"RVR stopped after max_iter={max_iter} sweeps with max |Delta log "
                          f"alpha| = {change:.3g} >= tol={tol:g} (usually bases still on "
                          "their way to pruning; raise max_iter)", ConvergenceWarning,
                          stacklevel=2)

        if keep.size:
            mu, Sigma = self._posterior(PtP[np.ix_(keep, keep)], Ptt[keep], alpha[keep], beta)
        else:
            mu, Sigma = np.zeros(0), np.zeros((0, 0))
        self.bias_used_ = bool(keep.size and keep[0] == 0)
        self.relevance_indices_ = keep[keep > 0] - 1
        self.relevance_vectors_ = X[self.relevance_indices_]
        self.alpha_ = alpha[keep]
        self.beta_ = float(beta)
        self.mu_ = mu
        self.Sigma_ = Sigma
        self.n_iter_ = n_iter
        self.converged_ = converged
        return self

    def predict(self, X, return_std: bool = False):
        """Predicted drift [unit of y] for X (n_samples, n_features); with ``return_std``
        also the predictive standard deviation [unit of y] (Tipping 2001 eq. (22)), noise
        included."""
        Xs = self._validate_predict(X)
        rv = self._scale_X(self.relevance_vectors_)
        mean = np.empty(Xs.shape[0])
        var = np.empty(Xs.shape[0])
        for sl in gen_batches(Xs.shape[0], _PREDICT_BATCH):
            phi = gaussian_kernel(Xs[sl], rv, self.sigma)
            if self.bias_used_:
                phi = np.hstack([np.ones((phi.shape[0], 1)), phi])
            mean[sl] = phi @ self.mu_
            if return_std:
                var[sl] = 1.0 / self.beta_ + np.einsum("ij,jk,ik->i", phi, self.Sigma_, phi)
        y = self.y_mean_ + self.y_scale_ * mean
        if return_std:
            return y, self.y_scale_ * np.sqrt(var)
        return y
