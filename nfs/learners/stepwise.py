"""Forward-backward stepwise polynomial regression by partial F tests (Efroymson 1960).

Tao et al.'s (2019) "second-order multivariate stepwise regression" (section 4.2): the terms
of a polynomial in the scaled features (:mod:`~nfs.learners.polynomial`) enter and leave the
model one at a time by their partial F statistics, and the final model is refitted by least
squares (:func:`~nfs.learners.linear.ridge_lstsq`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .linear import ridge_lstsq
from .polynomial import PolynomialModel, feature_names, monomial_powers, monomials, term_name
from .validation import HyperparameterError, check_int, check_real, fit_scaling, validate

__all__ = [
    "StepwiseRegression",
    "StepwiseStep",
]


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


class StepwiseRegression(PolynomialModel):
    """Forward-backward stepwise polynomial regression by partial F tests, Tao et al.'s (2019)
    "second-order multivariate stepwise regression" (section 4.2).

    The candidate library holds monomials of the scaled features z_j = x_j / scale_j
    (T, dT/dt, their cross terms, ... up to ``degree``; scaling without centring, so that
    each candidate is a raw monomial times a constant and the selection is the same in any
    units -- though not for another origin, e.g. kelvin instead of degC, as for every
    polynomial stepwise selection; see :mod:`~nfs.learners.polynomial`).  Starting from the
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
                raise HyperparameterError(f"unknown library {cand!r}; valid: "
                                          f"{', '.join(_CANDIDATE_LIBRARIES)} or an array "
                                          f"of exponents", key="candidates")
            check_int(self.degree, "degree", 1)
            return monomial_powers(n_features, self.degree, cand == "poly")
        powers = np.asarray(cand)
        if (powers.ndim != 2 or powers.shape[1] != n_features or powers.shape[0] == 0
                or not np.issubdtype(powers.dtype, np.integer) or (powers < 0).any()
                or (powers.sum(axis=1) == 0).any()):
            raise HyperparameterError(f"an explicit library must be non-negative integer "
                                      f"exponents of shape (n_candidates, {n_features}) "
                                      f"without the constant term", key="candidates")
        return powers.astype(np.int64)

    def fit(self, X, y):
        """Select terms and fit them to features X (n_samples, n_features) and drift y
        (n_samples,) [deg/h]; returns self."""
        check_real(self.p_enter, "p_enter", 0.0, 1.0, low_open=True, high_open=True)
        check_real(self.p_remove, "p_remove", 0.0, 1.0, low_open=True)
        if self.p_enter > self.p_remove:
            raise HyperparameterError(f"p_enter ({self.p_enter}) must not exceed p_remove "
                                      f"({self.p_remove}), else a term can enter and leave "
                                      f"forever", key="p_enter")
        check_int(self.max_terms, "max_terms", 1, allow_none=True)
        X, y = validate(self, X, y, reset=True)
        n = X.shape[0]
        self.mean_, self.scale_ = fit_scaling(X, center=False)
        self.candidate_powers_ = self._candidate_library(X.shape[1])
        names = feature_names(self, X.shape[1])
        self.candidate_names_ = np.array(
            [term_name(p, names) for p in self.candidate_powers_], dtype=object)

        Phi = monomials((X - self.mean_) / self.scale_, self.candidate_powers_)
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
        self.coef_, self.intercept_ = ridge_lstsq(self._design(X), y, 0.0)
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
