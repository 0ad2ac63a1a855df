"""Epsilon-support vector regression with the Gaussian kernel in the papers' sigma convention.

The model the FOG start-up paper tunes with SSA, PSO and GWO (Table 1: C 1.0520, sigma
0.9506), solved by LIBSVM (Chang & Lin 2011) through scikit-learn's ``SVR``.

Equation numbers "Tao et al. (2019) eq. (n)" count the displayed equations of its stored text
(see :mod:`nfs.learners.kernels`).
"""

from __future__ import annotations

import numpy as np
from sklearn.svm import SVR

from .kernels import KernelRegressor, kernel_expansion, kernel_from_sq_distances
from .validation import HyperparameterError, check_positive

__all__ = ["SVRRegressor"]


class SVRRegressor(KernelRegressor):
    """Epsilon-support vector regression with the Gaussian kernel in the sigma convention.

    The model (Tao et al. (2019) eq. (2)-(4); Vapnik; LIBSVM, Chang & Lin 2011, ACM TIST 2(3) 27,
    the
    solver the FOG start-up paper cites) on the scaled problem (x~, y~)::

        f~(x~) = sum_k (a_k - a_k*) k(x~, x~_k) + b,   0 <= a_k, a_k* <= C
        min 1/2 ||w||^2 + C sum_k (xi_k + xi_k*),  |y~_k - f~(x~_k)| <= epsilon + xi_k(*)

    with k the Gaussian kernel of width ``sigma`` (LIBSVM's ``gamma = 1/(2 sigma^2)``,
    :func:`~nfs.learners.kernels.sigma_to_gamma`) and the prediction ``y = y_mean_ + y_scale_ f~(x~)``.

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
        The fitted LIBSVM model on the scaled problem, on the precomputed Gaussian kernel
        (its ``support_``, ``dual_coef_`` and ``intercept_``; its ``predict`` takes kernel
        rows, not features).
    support_vectors_ : array (n_sv, n_features)
        The support vectors, scaled (x~).
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

    def fit(self, X, y, sq_distances=None):
        """Fit on features X (n_samples, n_features) and drift y (n_samples,). Returns self.

        LIBSVM solves the dual on the Gram matrix K = exp(-D2 / (2 sigma^2)) given to it
        (``kernel="precomputed"``), D2 the squared distances of the scaled training inputs:
        ``sq_distances`` when a search already holds them
        (:meth:`~nfs.learners.kernels.KernelRegressor.training_sq_distances` of X),
        computed here otherwise.  The same problem as LIBSVM's own RBF kernel, whose entries
        differ from these by rounding (in LIBSVM they come from ||a||^2 + ||b||^2 - 2 a.b);
        a search's 210 fits per seed then spend no time evaluating kernels (the kernel of
        a new sigma is one exponential per entry of D2, which the search computes once per
        fold), 10-30 % of a fit with many support vectors."""
        X, y = self._validate_fit(X, y)
        C = check_positive("C", self.C)
        sigma = check_positive("sigma", self.sigma)
        epsilon = float(self.epsilon)
        if not (np.isfinite(epsilon) and epsilon >= 0.0):
            raise HyperparameterError(f"epsilon must be >= 0, got {self.epsilon!r}")
        Xs, ys = self._fit_scaling(X, y, scale_y=True)
        K = kernel_from_sq_distances(self._train_sq_distances(Xs, sq_distances), sigma)
        self.svr_ = SVR(kernel="precomputed", C=C, epsilon=epsilon).fit(K, ys)
        self.support_vectors_ = Xs[self.svr_.support_]
        return self

    def predict(self, X) -> np.ndarray:
        """Predicted drift [unit of y] for features X (n_samples, n_features).

        The fitted expansion f~(x~) = sum_k (a_k - a_k*) k(x~, x~_k) + b over LIBSVM's
        support vectors, evaluated by :func:`~nfs.learners.kernels.kernel_expansion` (the
        kernel of every model here) rather than by LIBSVM's predict: the same function to
        ~1e-13 of the target's STD, 1.4-4x faster (a search scores every candidate on each
        held-out fold this way)."""
        Xs = self._validate_predict(X)
        svr = self.svr_
        # a model fitted on LIBSVM's own RBF kernel (a model file of an earlier version)
        # holds its support vectors inside LIBSVM's model
        centres = getattr(self, "support_vectors_", None)
        if centres is None:
            centres = svr.support_vectors_
        f = kernel_expansion(Xs, centres, svr.dual_coef_[0], float(svr.intercept_[0]),
                             self.sigma)
        return self.y_mean_ + self.y_scale_ * f

