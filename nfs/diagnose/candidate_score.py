"""One candidate scored on one residual channel, with run-level statistics.

Each candidate is a linear least-squares problem over runs, y_r = [X_r, C_r] beta + e_r
(:mod:`nfs.scoring.run_stats`): y_r the channel's residual of run r, X_r the model's own columns
and C_r the candidate's, at fixed shape parameters.  :func:`score_candidate` gives

- the clustered test of its coefficients against zero (CR2, one cluster per run; one-sided
  for a coefficient physics keeps positive, :data:`ONE_SIDED`), at every grid point of its
  shapes, its p-value Bonferroni's over the grid, min(1, n_grid min_j p_j);
- the leave-one-start-temperature-out CV RMS without and with it (the grid point chosen on
  each fold's training runs);
- its coefficients with 95 % t intervals from the CR2 covariance (coefficients and shapes
  together when its shapes were refined, :func:`score_with_shapes`);
- the partial correlation of the baseline residual with its fitted signature;
- its inclusion frequency over resamples of whole runs (descriptive).

Significance (Holm over all candidates, and the CV drop) is decided over the whole family
(:mod:`nfs.diagnose.ranking`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..effects import get_effect
from ..instrument import Instrument
from .candidates import Candidate
from .columns import PreparedRun, candidate_columns, fit_shapes
from .result import CandidateScore
from ..fit.structure import positive_parameter
from ..scoring.intervals import positive_interval
from ..scoring.run_stats import RunGrams, augmented_grams, clustered_fit, group_cv_rms, run_grams, solve

__all__ = ["ONE_SIDED", "ScoredCandidate", "ResidualChannel", "residual_channel",
           "one_sided_sign", "score_candidate", "best_grid_point", "score_with_shapes"]

#: (effect, coefficient) -> sign of the only physical alternative: one-sided tests.
ONE_SIDED = {("heat_source", "power"): 1, ("motor_heat", "power"): 1,
             ("thermometer_lag", "tau"): 1}


@dataclass(frozen=True)
class ScoredCandidate:
    """A scored candidate and what later steps need of it."""

    candidate: Candidate
    """The candidate."""
    score: CandidateScore
    """What it explains."""
    shapes: dict[str, float]
    """Its refined shape parameters."""
    beta: np.ndarray
    """Joint coefficients (the model's, then the candidate's)."""
    cols: list[np.ndarray]
    """The candidate's columns per run at ``shapes``."""


@dataclass(frozen=True)
class ResidualChannel:
    """One residual channel: targets, model columns and what every candidate shares."""

    ys: list[np.ndarray]
    """The target of each run."""
    Xs: list[np.ndarray]
    """The model's columns of each run."""
    base: RunGrams
    """Gram matrices of the model's columns alone."""
    beta: np.ndarray
    """The model's coefficients."""
    groups: np.ndarray
    """CV group (start temperature) of each run."""
    boot: list[np.ndarray]
    """Resamples of whole runs (indices), shared by the candidates."""
    boot_cv: list[float]
    """The model's CV RMS on each resample."""


def residual_channel(ys: list[np.ndarray], Xs: list[np.ndarray], groups: np.ndarray,
                     boot: list[np.ndarray]) -> ResidualChannel:
    """The channel of targets ``ys`` and model columns ``Xs`` per run, with the model's fit
    and its CV RMS on every resample ``boot``."""
    base = run_grams(ys, Xs)
    boot_cv = [group_cv_rms([base], groups, np.bincount(b, minlength=len(ys)))[0]
               for b in boot]
    return ResidualChannel(ys, Xs, base, clustered_fit(base).beta, groups, boot, boot_cv)


def one_sided_sign(c: Candidate) -> int:
    """+1 when the candidate's one coefficient is physically positive (:data:`ONE_SIDED`),
    else 0 (a two-sided test)."""
    return ONE_SIDED.get((c.effect, c.coefficients[0]), 0) if len(c.coefficients) == 1 else 0


def score_candidate(c: Candidate, ch: ResidualChannel,
                    grid: list[tuple[dict[str, float], list[np.ndarray]]],
                    alpha: float, refined: tuple[dict[str, float], list[np.ndarray]] | None = None,
                    shape_jac: list[np.ndarray] | None = None) -> ScoredCandidate:
    """Score candidate ``c`` on channel ``ch`` (module docstring).

    ``grid``: (shape values, columns per run) at every grid point (one entry without
    shapes); ``refined``: the estimate's shapes and columns (default the only grid point);
    ``shape_jac``: per run, d(fitted contribution)/d(shape) at the estimate, for the
    intervals of the shapes.  ``significant`` is set after Holm
    (:func:`nfs.diagnose.ranking.significance`).
    """
    pm, k = ch.Xs[0].shape[1], len(c.coefficients)
    idx = list(range(pm, pm + k))
    sign = one_sided_sign(c)
    designs = [augmented_grams(ch.base, ch.ys, ch.Xs, cols) for _, cols in grid]
    fits = [clustered_fit(g) for g in designs]
    tests = [f.test(idx, sign) for f in fits]
    j = int(np.argmin([t[1] for t in tests]))
    wald_p = min(1.0, len(designs) * tests[j][1])
    # the other side of a one-sided coefficient: what the runs ask for that physics refuses
    other = (min(1.0, len(designs) * min(f.test(idx, -sign)[1] for f in fits))
             if sign else None)
    cv_before = group_cv_rms([ch.base], ch.groups)[0]
    cv_after = group_cv_rms(designs, ch.groups)[0]
    shapes, cols = refined if refined is not None else grid[0]
    g = designs[0] if refined is None else augmented_grams(ch.base, ch.ys, ch.Xs, cols)
    fit = clustered_fit(g)
    beta = fit.beta
    names, values = list(c.coefficients), list(beta[idx])
    if shape_jac is not None:  # the linearised problem in coefficients and shapes together
        fit = clustered_fit(augmented_grams(g, ch.ys, [np.hstack([X, C]) for X, C in
                                                       zip(ch.Xs, cols)], shape_jac))
        idx = idx + list(range(pm + k, pm + k + len(c.shapes)))
        names += list(c.shapes)
        values += [shapes[s] for s in c.shapes]
    half = [fit.half_width(i) for i in idx]
    coef = {n: float(v) for n, v in zip(names, values)}
    # a positive quantity's interval on its log: no negative time constant or power
    interval = {n: (positive_interval(v, h) if positive_parameter(c.effect, n)
                    else (float(v - h), float(v + h)))
                for n, v, h in zip(names, values, half)}
    # partial correlation of the baseline residual e with the candidate's fitted signature
    # s = C b_c, the model's columns projected out of s (e is orthogonal to them already):
    # r = s^T e / (|s_perp| |e|), every term from the Gram blocks
    A = g.gram.sum(0)
    bc = beta[pm:]
    Xs_ = A[:pm, pm:] @ bc
    ss = float(bc @ A[pm:, pm:] @ bc)
    se_ = float(bc @ (g.moment.sum(0)[pm:] - A[pm:, :pm] @ ch.beta))
    perp = ss - float(Xs_ @ solve(A[:pm, :pm], Xs_))
    ee = float(ch.base.sse(ch.beta).sum())
    corr = se_ / math.sqrt(perp * ee) if perp > 0 and ee > 0 else 0.0
    # inclusion frequency over resamples of whole runs (descriptive)
    hits = 0
    for pick, cv0 in zip(ch.boot, ch.boot_cv):
        w = np.bincount(pick, minlength=len(ch.ys)).astype(float)
        hits += bool(group_cv_rms([g], ch.groups, w)[0] < cv0 and clustered_fit(
            g.take(pick)).test(list(range(pm, pm + k)), sign)[1] < alpha)
    score = CandidateScore(effect=c.effect, target=c.target, significant=False,
                           cv_rms_before=cv_before, cv_rms_after=cv_after, correlation=corr,
                           coefficient=coef, interval=interval, wald_p=wald_p, holm_p=wald_p,
                           dof=float(tests[j][2]), n_grid=len(designs),
                           inclusion_frequency=hits / len(ch.boot) if ch.boot else math.nan,
                           channel=c.channel, sign_rejected_p=other)
    return ScoredCandidate(c, score, dict(shapes), beta, cols)


def best_grid_point(ch: ResidualChannel, grid: list[tuple[dict[str, float], list[np.ndarray]]]
                    ) -> tuple[dict[str, float], list[np.ndarray]]:
    """The grid point of smallest pooled residual (the shapes of a candidate scored without
    a refinement of its shapes)."""

    def sse(cols):
        g = augmented_grams(ch.base, ch.ys, ch.Xs, cols)
        return float(g.sse(clustered_fit(g).beta).sum())
    return min(grid, key=lambda gc: sse(gc[1])) if len(grid) > 1 else grid[0]


def score_with_shapes(c: Candidate, ch: ResidualChannel, preps: list[PreparedRun], bare: Instrument,
                      grid, alpha: float) -> ScoredCandidate:
    """Score a gyro candidate on the drift window means, its shapes refined by variable
    projection (:func:`~nfs.diagnose.columns.fit_shapes`) and their intervals from the
    linearised problem."""
    if not c.shapes:
        return score_candidate(c, ch, grid, alpha)
    shapes, cols = fit_shapes(c, preps, bare, grid)
    beta_c = clustered_fit(augmented_grams(ch.base, ch.ys, ch.Xs, cols)).beta[
        ch.Xs[0].shape[1]:]
    jac: list[list[np.ndarray]] = [[] for _ in preps]
    spec = get_effect(c.effect)
    for s in c.shapes:  # d(fitted contribution)/d(shape), forward differences
        step = 1e-4 * max(abs(shapes[s]), 1.0)
        bounds = spec.parameter(s).bounds
        if bounds is not None and shapes[s] + step > bounds[1]:
            step = -step            # a shape on its upper bound: the backward difference
        moved = candidate_columns(c, {**shapes, s: shapes[s] + step}, preps, bare)
        for i, (m, c0) in enumerate(zip(moved, cols)):
            jac[i].append((m - c0) @ beta_c / step)
    return score_candidate(c, ch, grid, alpha, (shapes, cols), [np.column_stack(J) for J in jac])
