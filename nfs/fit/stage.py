"""The least-squares core of one stage of :func:`nfs.fit.calibration.fit_model`.

Bounded nonlinear least squares (:func:`scipy.optimize.least_squares`, method ``trf``,
``x_scale="jac"``) of the data rows of a stage plus, when a prior is given, its rows
(x - p0) / sigma (:mod:`nfs.fit.prior`); from the start and, while the best solution is
not settled (data rows above their noise level), from extra
starts; the lowest cost wins.  Standard errors from the data rows or from the posterior, and
the parameters the data rows cannot determine.
"""

from __future__ import annotations

import dataclasses

import math
import time
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import least_squares

from ..docfields import document_fields
from .prior import Prior

__all__ = ["StageReport", "solve_stage", "forward_jacobian", "CHI2_SETTLED", "perturbed_starts",
           "START_FACTOR"]

#: A stage whose data rows have a reduced chi-square at most this fits to its noise: no other
#: start is tried, and the data rows keep their stated noise level beside the prior.
CHI2_SETTLED = 1.5
#: Relative tolerances of the cost and of the step (scipy's ftol, xtol; 1e-8 by default).
#: The data rows are in noise units, so the cost is half a chi-square of 10^4 or more: a
#: relative change of 1e-5 is a few tenths of one unit, where a parameter's standard error
#: moves the cost by 0.5; tighter, a fit of a unit whose structure is not the model's crawls
#: on for tens of evaluations more to the same parameters (to well within their errors).
FTOL = XTOL = 1e-5


@document_fields
@dataclass(frozen=True)
class StageReport:
    """How one stage of the fit went."""

    name: str
    """``thermal`` or ``drift``."""
    free: tuple[str, ...]
    """The parameters this stage fitted."""
    converged: bool
    """True when least_squares stopped on a tolerance (status > 0), not on max_nfev."""
    message: str
    """least_squares' own message."""
    nfev: int
    """Residual evaluations."""
    cost_start: float
    """0.5 sum r^2 at the start (weighted residuals)."""
    cost: float
    """0.5 sum r^2 at the solution (data rows, divided by :attr:`noise_scale`, plus the prior
    rows: the MAP cost)."""
    n_residuals: int
    """m, the number of data residuals (the prior rows not counted)."""
    time_s: float
    """Wall time of the stage [s]."""
    n_prior: int = 0
    """Prior rows (parameters with a finite prior width)."""
    cost_prior: float = 0.0
    """0.5 sum of the squared prior rows at the solution (half the squared shift in prior
    widths, summed)."""
    n_starts: int = 1
    """Starts tried (the preset, then its perturbations while the best solution was not
    settled); the lowest cost was kept."""
    noise_scale: float = 1.0
    """The data rows were divided by this beside the prior rows in the final solve: the RMS
    of the weighted data residual when it stayed above 1 (the model's error counted as
    noise); 1: the stated noise levels held."""
    correlation: np.ndarray | None = None
    """Correlation matrix of the fitted parameters (order :attr:`free`) of the linearised
    problem, whose standard errors are :attr:`nfs.fit.fit_result.FitResult.stderr`
    (zero rows for a parameter the data do not determine); None when not computed."""

    @property
    def stated_cost(self) -> float:
        """:attr:`cost` with its data rows back in their stated noise: (cost - cost_prior)
        noise_scale^2 + cost_prior.  Two fits of the same numbers compare by it; :attr:`cost`
        of a stage that rescaled its data rows is noise_scale^2 smaller in them (seen on a
        unit the model does not describe: 2951 reported for 4562 in the stated noise)."""
        return float((self.cost - self.cost_prior) * self.noise_scale ** 2 + self.cost_prior)


def forward_jacobian(batch, x: np.ndarray, lb: np.ndarray, ub: np.ndarray,
                     f0: np.ndarray | None = None) -> np.ndarray:
    """d r / d x by forward differences, the n (+ 1) evaluations in one call of ``batch``.

    ``batch(xs)`` returns the residual at each of the parameter vectors ``xs``; ``f0``, the
    residual at ``x`` when the caller has it (then only the n moved vectors are solved).  The
    steps are those of :func:`scipy.optimize.least_squares`' ``jac="2-point"`` (relative step
    sqrt(eps) max(1, |x|), sign of x; turned back where it would leave the bounds; the step
    taken as the difference actually represented), so the Jacobian is the one scipy would
    make, computed from one stacked evaluation instead of n + 1 separate ones.
    """
    x = np.asarray(x, dtype=float)
    h = np.sqrt(np.finfo(float).eps) * np.where(x >= 0, 1.0, -1.0) * np.maximum(1.0, np.abs(x))
    lower, upper = x - lb, ub - x
    violated = (x + h < lb) | (x + h > ub)
    fitting = np.abs(h) <= np.maximum(lower, upper)
    h = np.where(violated & fitting, -h, h)
    h = np.where(~fitting & (upper >= lower), upper, h)
    h = np.where(~fitting & (upper < lower), -lower, h)
    xs = [x + np.where(np.arange(x.size) == i, h[i], 0.0) for i in range(x.size)]
    if f0 is None:
        f0, *moved = batch([x] + xs)
    else:
        moved = batch(xs)
    dx = np.array([xs[i][i] - x[i] for i in range(x.size)])
    return (np.column_stack(moved) - np.asarray(f0)[:, None]) / dx


def solve_stage(name: str, fun, x0: np.ndarray, lb: np.ndarray, ub: np.ndarray,
                max_nfev: int | None, paths: Sequence[str], prior: Prior | None = None,
                extra_starts: Sequence[np.ndarray] = (), batch=None):
    """Minimise 0.5 |r|^2 over the box [lb, ub], r = ``fun(x)`` (the data rows, divided by
    their noise level) followed by the rows of ``prior``.

    ``batch(xs)``, when given, evaluates ``fun`` at several parameter vectors at once; the
    Jacobian is then :func:`forward_jacobian` (scipy's own forward differences otherwise).

    From ``x0``, then from each of ``extra_starts`` while the best solution is not settled
    (:func:`_settled`), each extra start with a third of ``max_nfev``; the solution of
    lowest cost is kept.  With a prior and a data
    residual above its stated noise, the data rows are divided by their RMS and the solve
    repeated from there (:attr:`StageReport.noise_scale`).  Standard errors: see
    :func:`_errors`.

    Returns
    -------
    (scipy OptimizeResult, StageReport, {path: stderr}, {path: why not identifiable},
    [paths at a bound])
    """
    t0 = time.perf_counter()
    x0 = np.clip(x0, lb, ub)
    r0 = fun(x0)
    m = r0.size
    use_prior = prior is not None and bool(prior.active.any())

    last: list = [None, None]   # the last data rows least_squares asked for, at x

    def data_rows(x):
        r = fun(x)
        last[:] = [np.array(x, dtype=float), r]
        return r

    def total(x):
        r = data_rows(x)
        return np.concatenate([r, prior.rows(x)]) if use_prior else r

    def jacobian(scale: float):
        """The Jacobian of the data rows divided by ``scale`` and of the prior rows."""
        if batch is None:
            return "2-point"

        def jac(x):
            # least_squares asks for the Jacobian where it has just evaluated the residual
            f0 = last[1] if last[0] is not None and np.array_equal(last[0], x) else None
            j = forward_jacobian(batch, x, lb, ub, f0) / scale
            return np.vstack([j, prior.jacobian(x)]) if use_prior else j
        return jac

    best, nfev, tried = None, 0, 0
    r_start = np.concatenate([r0, prior.rows(x0)]) if use_prior else r0
    for xs in [x0, *[np.clip(x, lb, ub) for x in extra_starts]]:
        if best is not None and _settled(best, m, lb, ub):
            break
        # an extra start only has to show a lower basin: a third of the evaluations
        budget = max_nfev if best is None or max_nfev is None else max(10, max_nfev // 3)
        res = least_squares(total, xs, jac=jacobian(1.0), bounds=(lb, ub), method="trf",
                            x_scale="jac", max_nfev=budget, ftol=FTOL, xtol=XTOL)
        nfev, tried = nfev + int(res.nfev), tried + 1
        if best is None or res.cost < best.cost:
            best = res
    res = best
    # With a prior, the data rows must carry their real noise level for the two kinds of row
    # to weigh right: when the residual stays above the stated noise (the model's own error
    # counts as noise to the prior), divide the data rows by the residual's RMS in noise
    # units (an empirical-Bayes estimate of the noise scale) and solve once more from there.
    noise_scale = 1.0
    if use_prior and _chi2(res, m) > CHI2_SETTLED:
        noise_scale = math.sqrt(_chi2(res, m))

        def scaled(x):
            return np.concatenate([data_rows(x) / noise_scale, prior.rows(x)])

        res = least_squares(scaled, res.x, jac=jacobian(noise_scale), bounds=(lb, ub),
                            method="trf", x_scale="jac", ftol=FTOL, xtol=XTOL,
                            max_nfev=(None if max_nfev is None
                                      else max(min(10, max_nfev), max_nfev // 2)))
        nfev += int(res.nfev)
    cost_prior = float(0.5 * np.sum(res.fun[m:] ** 2))
    report = StageReport(name=name, free=tuple(paths), converged=bool(res.status > 0),
                         message=str(res.message), nfev=nfev,
                         cost_start=float(0.5 * r_start @ r_start), cost=float(res.cost),
                         n_residuals=int(m), time_s=time.perf_counter() - t0,
                         n_prior=int(res.fun.size - m), cost_prior=cost_prior,
                         n_starts=tried, noise_scale=noise_scale)
    jac = np.asarray(res.jac, dtype=float)
    stderr, unident, corr = _errors(jac[:m], res.fun[:m], paths,
                                    prior.jacobian(res.x) if use_prior else None)
    report = dataclasses.replace(report, correlation=corr)
    span = ub - lb
    at = [p for i, p in enumerate(paths)
          if res.active_mask[i] != 0
          or (np.isfinite(span[i]) and min(res.x[i] - lb[i], ub[i] - res.x[i]) <= 1e-6 * span[i])]
    return res, report, stderr, unident, at


def _chi2(res, m: int) -> float:
    """Reduced chi-square of the data rows (the first m) of a solution."""
    return float(res.fun[:m] @ res.fun[:m]) / max(m - res.x.size, 1)


def _settled(res, m: int, lb: np.ndarray, ub: np.ndarray) -> bool:
    """A solution no other start needs to challenge: the data rows at their noise level
    (reduced chi-square <= :data:`CHI2_SETTLED`; a lower minimum could only fit noise).  A
    parameter on a bound with the data at their noise level is a sign of the structure,
    not of a corner another start would leave (on units of another structure the extra
    starts came back to the same cost, at three times the time)."""
    return _chi2(res, m) <= CHI2_SETTLED


def _errors(jac: np.ndarray, r: np.ndarray, paths: Sequence[str],
            jac_prior: np.ndarray | None
            ) -> tuple[dict[str, float], dict[str, str], np.ndarray]:
    """Standard errors, the parameters the data rows cannot determine and the correlation
    matrix.

    Data only: cov = s^2 (J^T J)^-1, s^2 = |r|^2 / (m - n), through the SVD of J (a
    pseudo-inverse).  With a prior, the posterior of the linearised problem: the data rows
    (whitened by their stated noise, which the residual says is s times too small) and the
    prior rows P give cov = (J^T J / s^2 + P^T P)^-1 (Tarantola 2005, *Inverse Problem
    Theory*, sec. 3.2: the Gaussian linear case).  A direction the data rows do not
    constrain gives the parameters in it an infinite standard error (the value there is the
    prior's, not a measurement; :attr:`nfs.fit.fit_result.FitResult.prior_sigma` holds
    its width) and names them.
    """
    m, n = jac.shape
    s2 = float(r @ r) / max(m - n, 1)
    col = np.sqrt(np.sum(jac * jac, axis=0))
    col_safe = np.where(col > 0, col, 1.0)
    _, sv, vt = np.linalg.svd(jac / col_safe, full_matrices=False)
    tol = max(m, n) * np.finfo(float).eps * 1e4 * (sv[0] if sv.size else 0.0)
    good = sv > tol
    if jac_prior is None:
        inv = (vt[good].T / sv[good] ** 2) @ vt[good]
        stderr = np.sqrt(np.maximum(np.diag(inv), 0.0) * s2) / col_safe
    else:
        h = jac.T @ jac / max(s2, np.finfo(float).tiny) + jac_prior.T @ jac_prior
        d = np.sqrt(np.maximum(np.diag(h), np.finfo(float).tiny))
        inv = np.linalg.pinv(h / np.outer(d, d))
        stderr = np.sqrt(np.maximum(np.diag(inv), 0.0)) / d
    sd = np.sqrt(np.maximum(np.diag(inv), 0.0))
    sd_safe = np.where(sd > 0, sd, 1.0)
    corr = np.clip(inv / np.outer(sd_safe, sd_safe), -1.0, 1.0)
    corr[sd == 0] = 0.0
    corr[:, sd == 0] = 0.0
    unident = {}
    for i, p in enumerate(paths):
        weak = col[i] == 0 or (np.abs(vt[~good, i]) > 0.1).any()
        if weak:
            stderr[i] = math.inf
            unident[p] = ("the residual does not depend on it" if col[i] == 0 else
                          "collinear with other free parameters on these runs")
            corr[i, :] = 0.0
            corr[:, i] = 0.0
    return dict(zip(paths, stderr)), unident, corr


#: Relative perturbation of capacities and conductances in the extra starts.
START_FACTOR = 0.3


def perturbed_starts(paths: Sequence[str], x0: np.ndarray, lb: np.ndarray, ub: np.ndarray,
                     factor: float = START_FACTOR) -> list[np.ndarray]:
    """Extra starts: every capacity x(1 + f) with every conductance x(1 - f), and the reverse.

    The first slows every time constant C/G of the network by (1 + f)/(1 - f) (x1.9 at
    f = 0.3), the second speeds it up as much; powers, lags and offsets keep their start.
    Clipped into the box.  Empty when no capacity or conductance is free.
    """
    cap = np.array([p.endswith(".capacity_j_per_k") for p in paths])
    cond = np.array([p.endswith(".conductance_w_per_k") for p in paths])
    if not (cap.any() or cond.any()):
        return []
    out = []
    for sign in (+1.0, -1.0):
        x = np.array(x0, dtype=float)
        x[cap] *= 1.0 + sign * factor
        x[cond] *= 1.0 - sign * factor
        out.append(np.clip(x, lb, ub))
    return out
