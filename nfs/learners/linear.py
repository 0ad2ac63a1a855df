"""Polynomial least squares: the cubic "LS model" of Tao et al. (2019), and the solver it shares.

:class:`CubicLeastSquares` maps thermometer features to the FOG thermal drift y [deg/h] with
a polynomial in the standardised features (:mod:`~nfs.learners.polynomial`) fitted by
:func:`ridge_lstsq`, which the stepwise regression (its final refit) and the RBF network (its
output layer) use too.

Least squares
    The coefficients solve the (ridge-) least-squares problem with an unpenalised intercept::

        min_{b, k}  sum_i (y_i - b - sum_t k_t phi_t(z_i))^2 + alpha n sum_t k_t^2

    over the n samples (phi_t the columns: monomials, hidden activations).  The penalty is
    scaled by n, so ``alpha`` [-] is relative to the mean square of a standardised term and
    does not depend on the record length; ``alpha = 0`` is ordinary least squares
    (minimum-norm solution when the design is rank deficient, ``numpy.linalg.lstsq``).
"""

from __future__ import annotations

import math

import numpy as np
from sklearn.utils.validation import check_is_fitted

from nfs.errors import InputError

from .polynomial import PolynomialModel, feature_names, monomial_powers, term_name
from .validation import check_int, check_real, fit_scaling, validate

__all__ = [
    "ridge_lstsq",
    "CubicLeastSquares",
]


def ridge_lstsq(Phi: np.ndarray, y: np.ndarray, alpha: float) -> tuple[np.ndarray, float]:
    """Coefficients and unpenalised intercept minimising
    ||y - b - Phi k||^2 + alpha n ||k||^2 (see the module docstring), by ``lstsq`` of the
    centred problem stacked with sqrt(alpha n) I -- no normal equations are formed."""
    n, m = Phi.shape
    y_mean = float(y.mean())
    if m == 0:
        return np.zeros(0), y_mean
    phi_mean = Phi.mean(axis=0)
    A = Phi - phi_mean
    b = y - y_mean
    if alpha > 0.0:
        A = np.vstack([A, math.sqrt(alpha * n) * np.eye(m)])
        b = np.concatenate([b, np.zeros(m)])
    coef = np.linalg.lstsq(A, b, rcond=None)[0]
    return coef, y_mean - float(phi_mean @ coef)


class CubicLeastSquares(PolynomialModel):
    """Polynomial least-squares drift model, the "LS model" of Tao et al. (2019) (section 4.1).

    Tao et al. (2019) fits, for one parameter X (temperature, its slope or the oscillator voltage),
    ``B = k0 + k1 X + k2 X^2 + k3 X^3`` by least squares.  Here every feature may enter,
    with its cross terms when ``include_interactions``::

        y_hat = intercept_ + sum_t coef_[t] prod_j z_j ** powers_[t, j],
        z_j = (x_j - mean_[j]) / scale_[j]

    over every monomial of degree 1 .. ``degree`` (see :mod:`~nfs.learners.polynomial` for
    the standardisation, the module docstring for the least-squares problem).  With one
    feature and the defaults
    it is exactly Tao et al.'s (2019) cubic.

    Parameters
    ----------
    degree : int, default=3
        Highest total degree of a monomial [-]; 3 is Tao et al.'s (2019) cubic.
    include_interactions : bool, default=True
        Keep the cross terms (e.g. T dT/dt, T^2 U); False keeps only the pure powers
        x_j^k, i.e. one cubic per feature added together.
    alpha : float, default=0.0
        Ridge penalty [-] relative to the mean square of a standardised term
        (penalty alpha * n * ||coef_||^2, intercept not penalised); 0 is ordinary least
        squares, a tiny value (1e-10 .. 1e-6) steadies a nearly collinear design.

    Attributes
    ----------
    mean_, scale_ : ndarray, shape (``n_features_in_``,)
        Standardisation of each feature [unit of the feature].
    powers_ : ndarray of int, shape (n_terms, ``n_features_in_``)
        Exponent of each feature in each monomial (order of
        ``sklearn.preprocessing.PolynomialFeatures`` without the bias column).
    feature_names_out_ : ndarray of str, shape (n_terms,)
        Name of each monomial, e.g. ``'T^2 dTdt'`` (of the standardised features).
    coef_ : ndarray, shape (n_terms,)
        Coefficient of each standardised monomial [unit of y].
    intercept_ : float
        Constant term [unit of y].
    n_features_in_, feature_names_in_
        As in scikit-learn.

    References
    ----------
    Tao et al. (2019) (TRPLG bias compensation with IR-LSSVM, compared with LS and stepwise
    regression), section 4.1, the cubic LS model ``B = k0 + k1 X + k2 X^2 + k3 X^3``.
    """

    def __init__(self, degree: int = 3, include_interactions: bool = True,
                 alpha: float = 0.0):
        self.degree = degree
        self.include_interactions = include_interactions
        self.alpha = alpha

    def fit(self, X, y):
        """Fit the polynomial to features X (n_samples, n_features) and drift y
        (n_samples,) [deg/h]; returns self."""
        check_int(self.degree, "degree", 1)
        check_real(self.alpha, "alpha", 0.0)
        X, y = validate(self, X, y, reset=True)
        self.mean_, self.scale_ = fit_scaling(X)
        self.powers_ = monomial_powers(X.shape[1], self.degree,
                                        bool(self.include_interactions))
        names = feature_names(self, X.shape[1])
        self.feature_names_out_ = np.array([term_name(p, names) for p in self.powers_],
                                           dtype=object)
        self.coef_, self.intercept_ = ridge_lstsq(self._design(X), y, float(self.alpha))
        return self

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        """Names of the monomials, in the order of ``coef_``."""
        check_is_fitted(self, "powers_")
        if input_features is None:
            return self.feature_names_out_.copy()
        names = [str(n) for n in input_features]
        if len(names) != self.n_features_in_:
            raise InputError(f"input_features has {len(names)} names, the model "
                             f"{self.n_features_in_} features")
        return np.array([term_name(p, names) for p in self.powers_], dtype=object)
