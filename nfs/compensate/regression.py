"""Polynomial regression compensators of Tao et al. (2019): cubic least squares and stepwise
regression.

Both map thermometer features X (n_samples, n_features) -- temperatures T [degC],
temperature rates dT/dt [degC/s], gradients [degC], ... -- to the FOG thermal drift
y [deg/h] with a polynomial in the features, and both follow scikit-learn's estimator
contract (style practice 7): no logic in ``__init__``, ``fit`` returns ``self``, learned
attributes end in ``_``, checked with ``sklearn.utils.estimator_checks``.

Standardisation
    Every feature is standardised before the monomials are formed,
    ``z_j = (x_j - mean_j) / scale_j`` (``mean_``, ``scale_``; a constant feature keeps
    ``scale_j = 1``), so that e.g. T^3 at T ~ 50 degC and (dT/dt)^2 at 1e-3 degC/s give
    columns of order one and the least-squares problem stays well conditioned.
    :class:`CubicLeastSquares` centres and scales (mean and standard deviation): a full
    polynomial, or one of pure powers, spans the same functions whatever the origin.
    :class:`StepwiseRegression` only scales (``mean_ = 0``, ``scale_`` the root mean
    square): its candidates are single monomials, and shifting the origin would turn the
    raw monomial T dT/dt into a mix of z_T z_dT, z_T and z_dT, so that the selection would
    no longer be among the raw monomials of Tao et al. (2019).  ``coef_`` holds
    the coefficients of the monomials *of z*; :meth:`raw_polynomial` and :meth:`equation`
    expand them back to monomials of the features in their own units, the form in which
    Tao et al. (2019) prints its models.

Least squares
    The coefficients solve the (ridge-) least-squares problem with an unpenalised intercept::

        min_{b, k}  sum_i (y_i - b - sum_t k_t phi_t(z_i))^2 + alpha n sum_t k_t^2

    over the n samples (phi_t the monomials).  The penalty is scaled by n, so ``alpha`` [-]
    is relative to the mean square of a standardised term and does not depend on the
    record length; ``alpha = 0`` is ordinary least squares (minimum-norm solution when the
    design is rank deficient, ``numpy.linalg.lstsq``).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np
from scipy import stats
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from nfs.errors import InputError

try:  # scikit-learn >= 1.6
    from sklearn.utils.validation import validate_data as _sk_validate_data
except ImportError:  # pragma: no cover - older scikit-learn
    _sk_validate_data = None

__all__ = [
    "CubicLeastSquares",
    "StepwiseRegression",
    "StepwiseStep",
]


# --------------------------------------------------------------------------------------
# Helpers shared by the polynomial models (and by nfs.compensate.neural)
# --------------------------------------------------------------------------------------

def _validate(estimator: BaseEstimator, X, y="no_validation", *, reset: bool):
    """``sklearn.utils.validation.validate_data`` (or the estimator method before 1.6):
    dense float arrays, finite values, ``n_features_in_`` / ``feature_names_in_``.
    Without ``y`` only X is validated; ``y=None`` passed by a caller of ``fit`` is an
    error (a regressor requires y)."""
    kwargs = dict(reset=reset, dtype=np.float64)
    if not (isinstance(y, str) and y == "no_validation"):
        kwargs["y_numeric"] = True
    if _sk_validate_data is not None:
        return _sk_validate_data(estimator, X, y, **kwargs)
    return estimator._validate_data(X, y, **kwargs)  # pragma: no cover


def _fit_scaling(X: np.ndarray, center: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Offsets and scales of X for ``z = (x - mean) / scale``.

    ``center=True``: column means and standard deviations.  ``center=False``: zero offsets
    and the root mean squares about zero, so that z is x rescaled, nothing more.  A
    (numerically) constant or all-zero column keeps scale 1, so that it maps to a finite z.
    """
    if center:
        mean = X.mean(axis=0)
        scale = X.std(axis=0)
    else:
        mean = np.zeros(X.shape[1])
        scale = np.sqrt(np.mean(X ** 2, axis=0))
    tiny = 10.0 * np.finfo(float).eps * np.maximum(np.abs(X.mean(axis=0)), 1.0)
    scale = np.where(scale > tiny, scale, 1.0)
    return mean, scale


def _check_int(value, name: str, low: int, *, allow_none: bool = False) -> None:
    if allow_none and value is None:
        return
    if isinstance(value, bool) or not isinstance(value, Integral) or value < low:
        raise InputError(f"must be an integer >= {low}, got {value!r}", key=name)


def _check_real(value, name: str, low: float, high: float = math.inf, *,
                low_open: bool = False, high_open: bool = False) -> None:
    ok = isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value)
    if ok:
        ok = (value > low if low_open else value >= low) and \
             (value < high if high_open else value <= high)
    if not ok:
        lo = "(" if low_open else "["
        hi = ")" if high_open else "]"
        raise InputError(f"must be a real number in {lo}{low}, {high}{hi}, got {value!r}",
                         key=name)


def _monomial_powers(n_features: int, degree: int, interactions: bool) -> np.ndarray:
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


def _monomials(Z: np.ndarray, powers: np.ndarray) -> np.ndarray:
    """Columns prod_j Z[:, j] ** powers[t, j] for every term t (Z already standardised)."""
    out = np.ones((Z.shape[0], powers.shape[0]))
    for j in range(Z.shape[1]):
        pj = powers[:, j]
        for k in np.unique(pj[pj > 0]):
            out[:, pj == k] *= (Z[:, j] ** int(k))[:, None]
    return out


def _feature_names(estimator: BaseEstimator, n_features: int) -> list[str]:
    names = getattr(estimator, "feature_names_in_", None)
    if names is not None:
        return [str(n) for n in names]
    return [f"x{j}" for j in range(n_features)]


def _term_name(powers_row, names) -> str:
    """'1' for the constant, else e.g. 'x0^2 x1' (factors in feature order)."""
    parts = [n if p == 1 else f"{n}^{int(p)}" for n, p in zip(names, powers_row) if p]
    return " ".join(parts) if parts else "1"


def _ridge_lstsq(Phi: np.ndarray, y: np.ndarray, alpha: float) -> tuple[np.ndarray, float]:
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


def _raw_polynomial(powers, coef, intercept, mean, scale):
    """Expand b + sum_t k_t prod_j ((x_j - m_j)/s_j)^{p_tj} into monomials of x.

    Each factor is ((x - m)/s)^p = sum_{q=0}^{p} C(p, q) x^q (-m)^{p-q} / s^p (binomial
    theorem).  Returns (raw_powers, raw_coef, raw_intercept) with raw_powers ordered as
    :func:`_monomial_powers` (degree, then lexicographic)."""
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


class _PolynomialModel(RegressorMixin, BaseEstimator):
    """Shared predict / expansion of a fitted polynomial in standardised features.

    A subclass's ``fit`` sets ``mean_``, ``scale_``, ``powers_``, ``coef_``,
    ``intercept_``, ``feature_names_out_`` and ``n_features_in_``."""

    def _design(self, X: np.ndarray) -> np.ndarray:
        return _monomials((X - self.mean_) / self.scale_, self.powers_)

    def predict(self, X) -> np.ndarray:
        """Predicted drift y [unit of the training target, e.g. deg/h] for X
        (n_samples, ``n_features_in_``)."""
        check_is_fitted(self, "coef_")
        X = _validate(self, X, reset=False)
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
        return _raw_polynomial(self.powers_, self.coef_, self.intercept_,
                               self.mean_, self.scale_)

    def equation(self, precision: int = 6, target: str = "y") -> str:
        """The fitted polynomial in raw feature units as text, e.g.
        ``y = 1.4e-03 + 4.9e-04 T - 4.6e-06 T^2`` (Tao et al. (2019) section 4.2 prints its models
        this way)."""
        powers, coef, intercept = self.raw_polynomial()
        names = _feature_names(self, self.n_features_in_)
        text = f"{target} = {intercept:.{precision}g}"
        for row, k in zip(powers, coef):
            sign = "-" if k < 0 else "+"
            text += f" {sign} {abs(k):.{precision}g} {_term_name(row, names)}"
        return text


# --------------------------------------------------------------------------------------
# Cubic least squares
# --------------------------------------------------------------------------------------

class CubicLeastSquares(_PolynomialModel):
    """Polynomial least-squares drift model, the "LS model" of Tao et al. (2019) (section 4.1).

    Tao et al. (2019) fits, for one parameter X (temperature, its slope or the oscillator voltage),
    ``B = k0 + k1 X + k2 X^2 + k3 X^3`` by least squares.  Here every feature may enter,
    with its cross terms when ``include_interactions``::

        y_hat = intercept_ + sum_t coef_[t] prod_j z_j ** powers_[t, j],
        z_j = (x_j - mean_[j]) / scale_[j]

    over every monomial of degree 1 .. ``degree`` (see the module docstring for the
    standardisation and the least-squares problem).  With one feature and the defaults
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
        _check_int(self.degree, "degree", 1)
        _check_real(self.alpha, "alpha", 0.0)
        X, y = _validate(self, X, y, reset=True)
        self.mean_, self.scale_ = _fit_scaling(X)
        self.powers_ = _monomial_powers(X.shape[1], self.degree,
                                        bool(self.include_interactions))
        names = _feature_names(self, X.shape[1])
        self.feature_names_out_ = np.array([_term_name(p, names) for p in self.powers_],
                                           dtype=object)
        self.coef_, self.intercept_ = _ridge_lstsq(self._design(X), y, float(self.alpha))
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
        return np.array([_term_name(p, names) for p in self.powers_], dtype=object)


# --------------------------------------------------------------------------------------
# Stepwise regression
# --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class StepwiseStep:
    """One entry or removal of :class:`StepwiseRegression` (its ``history_``)."""

    action: str
    """``'enter'`` or ``'remove'``."""
    term: str
    """Name of the monomial, e.g. ``'x0 x1'``."""
    index: int
    """Its row in ``candidate_powers_``."""
    f_statistic: float
    """Partial F statistic of the term [-] (1 and n - p - 1 degrees of freedom, p the
    number of terms of the larger of the two models compared)."""
    p_value: float
    """Upper tail probability of ``f_statistic`` [-]."""
    n_terms: int
    """Number of terms in the model after the step (intercept not counted)."""
    rss: float
    """Residual sum of squares after the step [unit of y squared]."""


_CANDIDATE_LIBRARIES = ("poly", "pure")


class StepwiseRegression(_PolynomialModel):
    """Forward-backward stepwise polynomial regression by partial F tests, Tao et al.'s (2019)
    "second-order multivariate stepwise regression" (section 4.2).

    The candidate library holds monomials of the scaled features z_j = x_j / scale_j
    (T, dT/dt, their cross terms, ... up to ``degree``; scaling without centring, so that
    each candidate is a raw monomial times a constant and the selection is the same in any
    units -- though not for another origin, e.g. kelvin instead of degC, as for every
    polynomial stepwise selection; see the module docstring).  Starting from the
    intercept alone, Efroymson's procedure repeats:

    1. *Entry*: for every candidate not in the model, the partial F statistic of adding it,
       ``F = (RSS_p - RSS_{p+1}) / (RSS_{p+1} / (n - p - 2))`` (1 and n - p - 2 degrees of
       freedom, p terms before the step); the candidate with the smallest p-value enters
       if that p-value is below ``p_enter`` (and the model has fewer than ``max_terms``
       terms).
    2. *Removal*: after each entry, for every term in the model the partial F of dropping
       it, ``F = (RSS_{p-1} - RSS_p) / (RSS_p / (n - p - 1))``; while the largest p-value
       exceeds ``p_remove`` that term leaves (one at a time, re-tested after each).

    It stops when no candidate enters.  ``p_enter <= p_remove`` (Efroymson's F_in >=
    F_out) is required so that a term cannot enter and leave forever; a model seen before
    also stops the search.  Ties go to the earlier candidate, so the result is
    deterministic.  The final model is refitted by ordinary least squares.

    Parameters
    ----------
    degree : int, default=2
        Highest total degree of a candidate monomial [-]; Tao et al.'s (2019) Model 1 is the full
        second-order library of (T, dT/dt): T, dT/dt, T^2, T dT/dt, (dT/dt)^2.
    candidates : {"poly", "pure"} or array-like of int, default="poly"
        The candidate library: ``"poly"`` every monomial of degree 1 .. ``degree`` with
        cross terms; ``"pure"`` only the pure powers x_j^k; or an explicit array of
        exponents (n_candidates, n_features) (then ``degree`` is not used).
    p_enter : float, default=0.05
        Significance level [-] below which a candidate enters (Tao et al. (2019): 0.05).
    p_remove : float, default=0.10
        Significance level [-] above which a term leaves (Tao et al. (2019): 0.1).
    max_terms : int or None, default=None
        Largest number of terms (intercept not counted); None is no limit beyond
        n_samples - 2.

    Attributes
    ----------
    mean_ : ndarray, shape (``n_features_in_``,)
        Zeros (the features are not centred).
    scale_ : ndarray, shape (``n_features_in_``,)
        Root mean square of each feature [unit of the feature].
    candidate_powers_ : ndarray of int, shape (n_candidates, ``n_features_in_``)
        The candidate library.
    candidate_names_ : ndarray of str, shape (n_candidates,)
        Name of each candidate, e.g. ``'x0 x1'`` (``feature_names_in_`` when fitted on a
        DataFrame).
    selected_ : ndarray of int, shape (n_terms,)
        Rows of ``candidate_powers_`` in the final model, in the order they entered.
    selected_names_ : ndarray of str, shape (n_terms,)
        Their names.
    powers_ : ndarray of int, shape (n_terms, ``n_features_in_``)
        ``candidate_powers_[selected_]``.
    feature_names_out_ : ndarray of str
        Same as ``selected_names_``.
    coef_ : ndarray, shape (n_terms,)
        Coefficient of each selected monomial of the scaled features [unit of y].
    intercept_ : float
        Constant term [unit of y].
    pvalues_ : ndarray, shape (n_terms,)
        Partial-F p-value of each selected term in the final model [-].
    history_ : list of StepwiseStep
        Every entry and removal, in order.
    n_features_in_, feature_names_in_
        As in scikit-learn.

    References
    ----------
    Efroymson, M. A. (1960), "Multiple regression analysis", in Ralston & Wilf (eds.),
    Mathematical Methods for Digital Computers, Wiley, pp. 191-203 (the entry/removal
    F tests).  Tao et al. (2019) section 4.2 (entry at p < 0.05, removal at p > 0.1, Model 1 in
    T, dT/dt and their cross term).  Tao et al. (2019) starts from T, T^2, dT/dt; here the search
    starts from the intercept.  Not yet checked against Efroymson's text step by step.
    """

    def __init__(self, degree: int = 2, candidates="poly", p_enter: float = 0.05,
                 p_remove: float = 0.10, max_terms: int | None = None):
        self.degree = degree
        self.candidates = candidates
        self.p_enter = p_enter
        self.p_remove = p_remove
        self.max_terms = max_terms

    def _candidate_library(self, n_features: int) -> np.ndarray:
        cand = self.candidates
        if isinstance(cand, str):
            if cand not in _CANDIDATE_LIBRARIES:
                raise InputError(f"unknown library {cand!r}; valid: "
                                 f"{', '.join(_CANDIDATE_LIBRARIES)} or an array of "
                                 f"exponents", key="candidates")
            _check_int(self.degree, "degree", 1)
            return _monomial_powers(n_features, self.degree, cand == "poly")
        powers = np.asarray(cand)
        if (powers.ndim != 2 or powers.shape[1] != n_features or powers.shape[0] == 0
                or not np.issubdtype(powers.dtype, np.integer) or (powers < 0).any()
                or (powers.sum(axis=1) == 0).any()):
            raise InputError(f"an explicit library must be non-negative integer exponents "
                             f"of shape (n_candidates, {n_features}) without the constant "
                             f"term", key="candidates")
        return powers.astype(np.int64)

    def fit(self, X, y):
        """Select terms and fit them to features X (n_samples, n_features) and drift y
        (n_samples,) [deg/h]; returns self."""
        _check_real(self.p_enter, "p_enter", 0.0, 1.0, low_open=True, high_open=True)
        _check_real(self.p_remove, "p_remove", 0.0, 1.0, low_open=True)
        if self.p_enter > self.p_remove:
            raise InputError(f"p_enter ({self.p_enter}) must not exceed p_remove "
                             f"({self.p_remove}), else a term can enter and leave forever",
                             key="p_enter")
        _check_int(self.max_terms, "max_terms", 1, allow_none=True)
        X, y = _validate(self, X, y, reset=True)
        n = X.shape[0]
        self.mean_, self.scale_ = _fit_scaling(X, center=False)
        self.candidate_powers_ = self._candidate_library(X.shape[1])
        names = _feature_names(self, X.shape[1])
        self.candidate_names_ = np.array(
            [_term_name(p, names) for p in self.candidate_powers_], dtype=object)

        Phi = _monomials((X - self.mean_) / self.scale_, self.candidate_powers_)
        Phi = Phi - Phi.mean(axis=0)
        yc = y - y.mean()
        max_terms = n - 2 if self.max_terms is None else min(self.max_terms, n - 2)
        selected, history = _stepwise(Phi, yc, float(self.p_enter), float(self.p_remove),
                                      max_terms, self.candidate_names_)

        self.selected_ = np.array(selected, dtype=np.int64)
        self.selected_names_ = self.candidate_names_[self.selected_]
        self.powers_ = self.candidate_powers_[self.selected_]
        self.feature_names_out_ = self.selected_names_.copy()
        self.history_ = history
        self.coef_, self.intercept_ = _ridge_lstsq(self._design(X), y, 0.0)
        self.pvalues_ = _removal_pvalues(Phi[:, self.selected_], yc)[1]
        return self


def _f_pvalue(delta_rss: float, rss: float, df: int) -> tuple[float, float]:
    """Partial F = delta_rss / (rss / df) on (1, df) degrees of freedom, and its p-value.
    An exact fit (rss = 0) with a real gain counts as F = inf, p = 0."""
    if df <= 0:
        return 0.0, 1.0
    delta_rss = max(delta_rss, 0.0)
    if rss <= 0.0:
        return (math.inf, 0.0) if delta_rss > 0.0 else (0.0, 1.0)
    f = delta_rss / (rss / df)
    return f, float(stats.f.sf(f, 1, df))


def _orthonormal_basis(A: np.ndarray) -> np.ndarray:
    if A.shape[1] == 0:
        return np.zeros((A.shape[0], 0))
    return np.linalg.qr(A, mode="reduced")[0]


def _entry_pvalues(Phi: np.ndarray, yc: np.ndarray, selected: list[int],
                   rss_floor: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Partial F and p-value of adding each candidate to the model ``selected``.

    With Q an orthonormal basis of the model's columns and e = yc - Q Q^T yc, a
    candidate's residual r = phi - Q Q^T phi lowers the RSS by (r.e)^2 / (r.r).  Columns
    already in the model, or collinear with it (r.r tiny against phi.phi), get p = 1."""
    n, m = Phi.shape
    Q = _orthonormal_basis(Phi[:, selected])
    e = yc - Q @ (Q.T @ yc)
    rss = float(e @ e)
    R = Phi - Q @ (Q.T @ Phi)
    rr = np.einsum("ij,ij->j", R, R)
    norm2 = np.einsum("ij,ij->j", Phi, Phi)
    valid = rr > 1e-10 * np.maximum(norm2, np.finfo(float).tiny)
    valid[selected] = False
    f = np.zeros(m)
    p = np.ones(m)
    if rss <= rss_floor:  # the model is exact to rounding: nothing left to explain
        return f, p, rss
    df = n - len(selected) - 2
    gain = np.zeros(m)
    gain[valid] = (R[:, valid].T @ e) ** 2 / rr[valid]
    for j in np.flatnonzero(valid):
        f[j], p[j] = _f_pvalue(gain[j], rss - gain[j], df)
    return f, p, rss


def _removal_pvalues(A: np.ndarray, yc: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Partial F and p-value of dropping each column of the model A (centred).

    Dropping term k raises the RSS by b_k^2 / [(A^T A)^-1]_kk; with A = Q R,
    (A^T A)^-1 = R^-1 R^-T, whose diagonal is the squared row norms of R^-1."""
    n, p = A.shape
    if p == 0:
        return np.zeros(0), np.ones(0), float(yc @ yc)
    Q, Rm = np.linalg.qr(A, mode="reduced")
    qty = Q.T @ yc
    e = yc - Q @ qty
    rss = float(e @ e)
    diag_r = np.abs(np.diag(Rm))
    f = np.zeros(p)
    pv = np.ones(p)
    if (diag_r <= 1e-10 * max(diag_r.max(), np.finfo(float).tiny)).any():
        return f, pv, rss  # rank deficient: cannot happen with the entry test's guard
    Rinv = np.linalg.solve(Rm, np.eye(p))
    b = Rinv @ qty
    increase = b ** 2 / np.einsum("ij,ij->i", Rinv, Rinv)
    df = n - p - 1
    for k in range(p):
        f[k], pv[k] = _f_pvalue(float(increase[k]), rss, df)
    return f, pv, rss


def _stepwise(Phi: np.ndarray, yc: np.ndarray, p_enter: float, p_remove: float,
              max_terms: int, names) -> tuple[list[int], list[StepwiseStep]]:
    """Efroymson's entry/removal loop (see :class:`StepwiseRegression`) on the centred
    candidate columns Phi and centred target yc."""
    selected: list[int] = []
    history: list[StepwiseStep] = []
    seen = {frozenset()}
    rss_floor = 1e-20 * float(yc @ yc) + np.finfo(float).tiny
    while len(selected) < max_terms:
        f, p, _ = _entry_pvalues(Phi, yc, selected, rss_floor)
        best = int(np.argmin(p))
        if not p[best] < p_enter:
            break
        selected.append(best)
        rss = _removal_pvalues(Phi[:, selected], yc)[2]
        history.append(StepwiseStep("enter", str(names[best]), best, float(f[best]),
                                    float(p[best]), len(selected), rss))
        while len(selected) > 1:
            fr, pr, _ = _removal_pvalues(Phi[:, selected], yc)
            worst = int(np.argmax(pr))
            if not pr[worst] > p_remove:
                break
            gone = selected.pop(worst)
            rss = _removal_pvalues(Phi[:, selected], yc)[2]
            history.append(StepwiseStep("remove", str(names[gone]), gone, float(fr[worst]),
                                        float(pr[worst]), len(selected), rss))
        key = frozenset(selected)
        if key in seen:
            break
        seen.add(key)
    return selected, history
