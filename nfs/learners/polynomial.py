"""Polynomials in standardised features: the monomial basis and the base of the polynomial models.

The polynomial models (:class:`~nfs.learners.linear.CubicLeastSquares`,
:class:`~nfs.learners.stepwise.StepwiseRegression`, Tao et al. (2019)) map thermometer
features X (n_samples, n_features) -- temperatures T [degC], temperature rates dT/dt
[degC/s], gradients [degC], ... -- to the FOG thermal drift y [deg/h] with a polynomial in
the features.  This module holds what they share: the monomials (:func:`monomial_powers`,
:func:`monomials`), their names, the expansion back to the features' own units
(:func:`raw_polynomial`) and :class:`PolynomialModel` (predict, the raw polynomial, the
printed equation).

Standardisation
    Every feature is standardised before the monomials are formed,
    ``z_j = (x_j - mean_j) / scale_j`` (``mean_``, ``scale_``; a constant feature keeps
    ``scale_j = 1``), so that e.g. T^3 at T ~ 50 degC and (dT/dt)^2 at 1e-3 degC/s give
    columns of order one and the least-squares problem stays well conditioned.
    :class:`~nfs.learners.linear.CubicLeastSquares` centres and scales (mean and standard
    deviation): a full polynomial, or one of pure powers, spans the same functions whatever
    the origin.  :class:`~nfs.learners.stepwise.StepwiseRegression` only scales
    (``mean_ = 0``, ``scale_`` the root mean square): its candidates are single monomials,
    and shifting the origin would turn the raw monomial T dT/dt into a mix of z_T z_dT, z_T
    and z_dT, so that the selection would no longer be among the raw monomials of Tao et al.
    (2019).  ``coef_`` holds the coefficients of the monomials *of z*;
    :meth:`PolynomialModel.raw_polynomial` and :meth:`PolynomialModel.equation` expand them
    back to monomials of the features in their own units, the form in which Tao et al.
    (2019) prints its models.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from .validation import validate

__all__ = [
    "monomial_powers",
    "monomials",
    "feature_names",
    "term_name",
    "raw_polynomial",
    "PolynomialModel",
]


def monomial_powers(n_features: int, degree: int, interactions: bool) -> np.ndarray:
    """Exponents (n_terms, n_features) of every monomial of degree 1 .. ``degree``.

    Ordered by degree, then as ``itertools.combinations_with_replacement`` (the order of
    ``sklearn.preprocessing.PolynomialFeatures``): x0, x1, x0^2, x0 x1, x1^2, ...
    Without ``interactions`` only the pure powers x_j^k are kept."""
    rows = []
    for d in range(1, degree + 1):
        for combo in itertools.combinations_with_replacement(range(n_features), d):
            if not interactions and len(set(combo)) > 1:
                continue
            p = np.zeros(n_features, dtype=np.int64)
            for j in combo:
                p[j] += 1
            rows.append(p)
    if not rows:
        return np.zeros((0, n_features), dtype=np.int64)
    return np.array(rows, dtype=np.int64)


def monomials(Z: np.ndarray, powers: np.ndarray) -> np.ndarray:
    """Columns prod_j Z[:, j] ** powers[t, j] for every term t (Z already standardised)."""
    out = np.ones((Z.shape[0], powers.shape[0]))
    for j in range(Z.shape[1]):
        pj = powers[:, j]
        for k in np.unique(pj[pj > 0]):
            out[:, pj == k] *= (Z[:, j] ** int(k))[:, None]
    return out


def feature_names(estimator: BaseEstimator, n_features: int) -> list[str]:
    names = getattr(estimator, "feature_names_in_", None)
    if names is not None:
        return [str(n) for n in names]
    return [f"x{j}" for j in range(n_features)]


def term_name(powers_row, names) -> str:
    """'1' for the constant, else e.g. 'x0^2 x1' (factors in feature order)."""
    parts = [n if p == 1 else f"{n}^{int(p)}" for n, p in zip(names, powers_row) if p]
    return " ".join(parts) if parts else "1"


def raw_polynomial(powers, coef, intercept, mean, scale):
    """Expand b + sum_t k_t prod_j ((x_j - m_j)/s_j)^{p_tj} into monomials of x.

    Each factor is ((x - m)/s)^p = sum_{q=0}^{p} C(p, q) x^q (-m)^{p-q} / s^p (binomial
    theorem).  Returns (raw_powers, raw_coef, raw_intercept) with raw_powers ordered as
    :func:`monomial_powers` (degree, then lexicographic)."""
    acc: dict[tuple[int, ...], float] = {}
    const = float(intercept)
    n_features = len(mean)
    for row, k in zip(powers, coef):
        # per feature: list of (q, factor) pairs of its binomial expansion
        factors = []
        for j in range(n_features):
            p = int(row[j])
            factors.append([(q, math.comb(p, q) * (-mean[j]) ** (p - q) / scale[j] ** p)
                            for q in range(p + 1)])
        for choice in itertools.product(*factors):
            key = tuple(q for q, _ in choice)
            val = float(k) * math.prod(f for _, f in choice)
            if sum(key) == 0:
                const += val
            else:
                acc[key] = acc.get(key, 0.0) + val
    keys = sorted(acc, key=lambda t: (sum(t), [-q for q in t]))
    raw_powers = np.array(keys, dtype=np.int64).reshape(len(keys), n_features)
    raw_coef = np.array([acc[t] for t in keys], dtype=float)
    return raw_powers, raw_coef, const


class PolynomialModel(RegressorMixin, BaseEstimator):
    """Shared predict / expansion of a fitted polynomial in standardised features.

    A subclass's ``fit`` sets ``mean_``, ``scale_``, ``powers_``, ``coef_``,
    ``intercept_``, ``feature_names_out_`` and ``n_features_in_``."""

    def _design(self, X: np.ndarray) -> np.ndarray:
        return monomials((X - self.mean_) / self.scale_, self.powers_)

    def predict(self, X) -> np.ndarray:
        """Predicted drift y [unit of the training target, e.g. deg/h] for X
        (n_samples, ``n_features_in_``)."""
        check_is_fitted(self, "coef_")
        X = validate(self, X, reset=False)
        return self._design(X) @ self.coef_ + self.intercept_

    def raw_polynomial(self) -> tuple[np.ndarray, np.ndarray, float]:
        """The fitted model as a polynomial in the features in their own units.

        Returns
        -------
        powers : ndarray of int, shape (n_raw_terms, ``n_features_in_``)
            Exponents of each monomial of x (degree, then lexicographic order).
        coef : ndarray, shape (n_raw_terms,)
            Its coefficient [unit of y per unit of the monomial].
        intercept : float
            The constant term [unit of y].

        Expanding ((x - mean)/scale)^p by the binomial theorem can create lower-order
        monomials that are not among ``powers_``; for a full polynomial
        (``CubicLeastSquares(include_interactions=True)``) the set is closed.
        """
        check_is_fitted(self, "coef_")
        return raw_polynomial(self.powers_, self.coef_, self.intercept_,
                               self.mean_, self.scale_)

    def equation(self, precision: int = 6, target: str = "y") -> str:
        """The fitted polynomial in raw feature units as text, e.g.
        ``y = 1.4e-03 + 4.9e-04 T - 4.6e-06 T^2`` (Tao et al. (2019) section 4.2 prints its models
        this way)."""
        powers, coef, intercept = self.raw_polynomial()
        names = feature_names(self, self.n_features_in_)
        text = f"{target} = {intercept:.{precision}g}"
        for row, k in zip(powers, coef):
            sign = "-" if k < 0 else "+"
            text += f" {sign} {abs(k):.{precision}g} {term_name(row, names)}"
        return text
