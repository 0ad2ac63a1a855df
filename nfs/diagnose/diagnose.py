"""Name the physical effect a model is missing (issue 4, parts 3 "Diagnose" and 4 "Apply").

Missing physics is found by named terms (style.md, practice 6): every registered effect that
the model lacks (or has on another target) is a *candidate*; each is added to the model in
turn, the drift coefficients are refitted, and the candidate is scored by what it explains.

Method
------
The thermal solution of every run is computed once, from the model's (already fitted)
thermal parameters (:func:`nfs.diagnose.fit._drift_context`), and the measured drift is
reduced to means over windows of ``decimate_s`` at rest (:func:`nfs.diagnose.fit._prepare_drift`,
the drift stage of :func:`~nfs.diagnose.fit.fit_model`).  The model drift
(:func:`~nfs.diagnose.fit.model_drift_dph`) is linear in ``gyro.bias_dph`` and in the
coefficients of the gyro effects (b1, b2, k_r, k_s, k_p, a, m, A_p, k, s1), so each of these
is a column of a design matrix on the window means; a candidate adds its own columns, one per
coefficient, evaluated with its shape parameters (tau, D_mag, T_p, phi) fixed.  Shape
parameters start from a small grid (:data:`SHAPE_GRID`), the best grid point by in-sample
residual is refined by bounded least squares with the coefficients profiled out (variable
projection).  Every fit, leave-one-run-out fold and bootstrap resample then uses per-run
Gram matrices (Z^T Z, Z^T y, y^T y), so a fold costs a p x p solve.

Scores of a candidate
    - ``cv_rms_before`` / ``cv_rms_after``: leave-one-run-out RMS of the held-out drift
      window means (fit on n-1 runs, predict the held-out run, pooled over runs), model
      alone / model + candidate.  The shape parameters are chosen on all runs (a small
      optimism for candidates that have them).
    - ``correlation``: correlation of the baseline residual with the candidate's fitted
      signature after projecting the model's own columns out of it (partial correlation).
    - ``coefficient`` / ``interval``: fitted values with 95 % intervals from the Jacobian
      (cov = s^2 (J^T J)^-1; window means are autocorrelated, so these are optimistic -
      which is why significance also asks for the run-level scores below).
    - ``inclusion_frequency``: over ``n_boot`` resamples of whole runs (with replacement),
      the fraction in which the leave-one-distinct-run-out CV RMS drops and the Wald test of
      the candidate's coefficients (chi^2 with k dof at 95 %) rejects zero.
    - ``heading_rmse_before_deg`` / ``after``: start-up heading RMSE pooled over the runs,
      north-finding the measured rate minus the fitted model drift, without / with the
      candidate (computed for the top :data:`HEADING_TOP` candidates and every significant
      one; null for the others).

Significant when all of: CV RMS drops by more than :data:`CV_DROP` (5 %), the Wald test
rejects zero at ``alpha``, and ``inclusion_frequency >= 0.8``.  The 5 % is a run-level
threshold: the held-out runs make a drop by chance small, and on runs made by the model
itself the largest drop over all candidates stays well below it
(tests/diagnose/test_diagnose.py).

Thermal and thermometer candidates (``heat_source``, ``motor_heat``, ``tec_power`` on each
node, ``thermometer_lag`` on each thermometer) are scored the same way on the thermometer
channel (``channel = "thermometers"``): the residual is the three thermometers at the knots
of the thermal stage (:func:`nfs.diagnose.fit.fit_model`), the model's own columns are the
Jacobian of the readings in its free thermal parameters (forward differences), and the
candidate's columns are the derivatives of the readings in its parameters at 0 (a power
step of 0.05 W, a TEC slope of 0.005 W/K, an extra lag of 5 s: ``thermometer_lag``'s tau is
a coefficient of the linearised reading y - tau dy/dt).  This is one Gauss-Newton step of
the thermal refit, accurate when the model's thermal part is already fitted (``nfs fit``).
A candidate whose columns lie in the span of the model's (a heat source at a node whose
power the model fits; a motor heating a powered node: the moves are a steady duty cycle)
is listed under ``not_tried`` with the model parameter it duplicates.  Their heading RMSE
is computed with the Gauss-Newton model and a linear drift refit, beside the same step
without the candidate.

Ranking: significant thermometer candidates first (thermometers are upstream of the drift:
a missing thermal effect also shows in the drift, as some node's temperature term, while a
missing gyro effect never shows in the thermometers), then by the relative CV drop.  Every
other significant candidate is refitted with the top one in the model; if it then drops
the CV RMS by less than :data:`CV_DROP` it is marked ``explained_by`` the top one (one
effect makes several targets significant at once).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import chi2

from ..effects import available_effects, get_effect, make_effect
from ..effects.registry import EffectInstance, EffectSpec
from ..effects.thermometer import THERMOMETERS
from ..errors import NfsError
from ..instrument import Instrument
from ..io.measurement import Run
from ..northfind import heading_rmse, north_find
from .fit import (DEFAULT_DECIMATE_S, FitResult, _block, _drift_context, _prepare_drift,
                  _prepare_thermal, _thermal_residual_parts, default_free, fit_model,
                  model_drift_dph)
from .params import fit_bounds, get_param, set_params

__all__ = ["Candidate", "CandidateScore", "Diagnosis", "candidates", "diagnose",
           "apply_candidate", "SHAPE_GRID", "CV_DROP", "MIN_INCLUSION", "HEADING_TOP"]

#: Starting grid of the shape (nonlinear) parameters of the built-in effects.
SHAPE_GRID: dict[str, tuple[float, ...]] = {
    "tau": (60.0, 150.0, 300.0, 600.0, 1200.0),
    "D_mag": (0.0, 45.0, 90.0, 135.0),
    "T_p": (2.0, 5.0, 10.0, 20.0),
    "phi": (0.0, math.pi / 2),
}
#: Relative drop of the leave-one-run-out RMS a significant candidate must exceed.
CV_DROP = 0.05
#: Bootstrap inclusion frequency a significant candidate must reach.
MIN_INCLUSION = 0.8
#: Heading RMSE is computed for this many top-ranked candidates (and every significant one).
HEADING_TOP = 5

_SHAPE_UNITS = ("s", "K", "deg", "rad")
_FIXED_UNITS = ("degC", "channel unit")
_FAST_KINDS = ("gyro", "accelerometer")
_THERMOMETER_TARGETS = tuple(THERMOMETERS)
_MAX_LAG = 30


# ---------------------------------------------------------------------------------------------
# Candidates

@dataclass(frozen=True)
class Candidate:
    """One effect on one target that the model lacks."""

    effect: str
    """Registry name."""
    target: str | None
    """Value of the effect's target parameter (node, axis, thermometer, channel) or None."""
    kind: str
    """The effect's kind (gyro, accelerometer, thermal, thermometer)."""
    coefficients: tuple[str, ...]
    """Parameters that enter linearly (start 0)."""
    shapes: tuple[str, ...]
    """Nonlinear parameters, started from :data:`SHAPE_GRID`."""
    tried: bool
    """False when :func:`diagnose` does not score it (see ``reason``)."""
    reason: str = ""
    """Why it is not tried."""

    @property
    def label(self) -> str:
        return self.effect if self.target is None else f"{self.effect}:{self.target}"

    @property
    def channel(self) -> str:
        """Where it is scored: ``drift_dph`` or ``thermometers`` (the three, in K)."""
        return "drift_dph" if self.kind in _FAST_KINDS else "thermometers"


def _split_params(spec: EffectSpec) -> tuple[list[str], list[str], list[str]]:
    coefs, shapes, missing = [], [], []
    for p in spec.parameters:
        if p.type is not float or p.name == spec.target:
            continue
        if p.unit in _FIXED_UNITS:
            if p.required:
                missing.append(p.name)
        elif p.unit in _SHAPE_UNITS:
            if p.name not in SHAPE_GRID and p.default is None:
                missing.append(p.name)
            else:
                shapes.append(p.name)
        else:
            coefs.append(p.name)
    return coefs, shapes, missing


def _targets(spec: EffectSpec, inst: Instrument, runs: Sequence[Run]) -> list[str | None]:
    t = spec.target
    if t is None:
        return [None]
    if t == "node":
        par = spec.parameter(t)
        return ([None] if not par.required else []) + list(inst.network.node_names)
    if t == "axis":
        return ["x", "y"]
    if t == "thermometer":
        return list(_THERMOMETER_TARGETS)
    if t == "channel":
        cols = [c for c in runs[0].columns if c.startswith("aux_")] if runs else []
        return [c for c in cols if all(c in r.columns for r in runs)]
    opt = spec.parameter(t).optional
    return [None] if opt else []


def candidates(inst: Instrument, runs: Sequence[Run]) -> list[Candidate]:
    """Every registered effect on every target that ``inst`` does not have.

    Targets: ``node`` -> every thermal node, and None (the effect's default node, e.g. the
    coil mean) when the node parameter is optional; ``axis`` -> x, y; ``thermometer`` ->
    fog, acc_x, acc_y; ``channel`` -> every ``aux_*`` column present in all runs.  Thermal
    and thermometer candidates are linearised at zero: their time constants [s] become
    coefficients (module docstring).  Candidates :func:`diagnose` cannot score (the y
    accelerometer, parameters without a start value) have ``tried = False``.
    """
    present = {(e.name, e.target_value) for e in inst.effects}
    out = []
    for name in available_effects():
        spec = get_effect(name)
        if spec.kind == "null":
            continue
        coefs, shapes, missing = _split_params(spec)
        for target in _targets(spec, inst, runs):
            if (name, target) in present:
                continue
            reason = ""
            if spec.kind not in _FAST_KINDS:
                # linearised at zero (module docstring): time constants become coefficients
                coefs, shapes = coefs + [s for s in shapes
                                         if spec.parameter(s).unit == "s"], []
            if spec.kind == "accelerometer" and target != "x":
                reason = "acts on acc_y_g only, which does not enter the drift"
            elif missing:
                reason = "no start value for " + ", ".join(missing)
            elif not coefs:
                reason = "no linear coefficient to fit"
            out.append(Candidate(name, target, spec.kind, tuple(coefs), tuple(shapes),
                                 tried=not reason, reason=reason))
    return out


def _effect(c: Candidate, values: dict[str, float]) -> EffectInstance:
    params = dict(values)
    if c.target is not None:
        params[get_effect(c.effect).target] = c.target
    return make_effect(c.effect, params)


# ---------------------------------------------------------------------------------------------
# Prepared runs and the linear machinery

@dataclass
class _Prep:
    run: Run
    rd: Any
    ctx: Any
    lat: float
    y: np.ndarray            # measured drift window means minus the model's fixed part
    offset_full: np.ndarray  # fixed part of the model drift at full rate
    X_full: np.ndarray       # model columns at full rate (n_samples, p)
    X: np.ndarray            # model columns, window means (n_windows, p)


def _bare(inst: Instrument) -> Instrument:
    """``inst`` with zero bias, unit scale factor, zero accelerometer biases, no effects."""
    return set_params(inst, {"gyro.bias_dph": 0.0, "gyro.scale_factor": 1.0,
                             "accelerometers.bias_x_g": 0.0,
                             "accelerometers.bias_y_g": 0.0}).with_effects([])


def _model_paths(inst: Instrument) -> list[str]:
    """Drift-channel parameters of the model: the gyro bias and the gyro effect coefficients."""
    out = ["gyro.bias_dph"]
    for e in inst.effects:
        if e.spec.kind == "gyro":
            coefs, _, _ = _split_params(e.spec)
            out += [f"effects.{e.label}.{c}" for c in coefs if e.params.get(c) is not None]
    return out


def _columns(bare: Instrument, effects: list[EffectInstance], ctx, lat: float) -> np.ndarray:
    """Full-rate drift of each effect alone on a bare instrument, as columns."""
    return np.column_stack([model_drift_dph(bare.with_effects([e]), ctx, lat) for e in effects])


def _unit_effects(e: EffectInstance, coefs: Sequence[str]) -> list[EffectInstance]:
    """One copy of ``e`` per coefficient, that coefficient 1 and the others 0."""
    out = []
    for c in coefs:
        params = dict(e.params)
        for d in coefs:
            params[d] = 1.0 if d == c else 0.0
        out.append(EffectInstance(e.spec, params))
    return out


def _prepare(inst: Instrument, runs: Sequence[Run], decimate_s: float) -> tuple[list[_Prep],
                                                                               list[str]]:
    paths = _model_paths(inst)
    zero = set_params(inst, {p: 0.0 for p in paths})
    out = []
    for run in runs:
        rd = _prepare_drift(run, decimate_s, False, "raw")
        ctx = _drift_context(inst, rd)
        lat = rd.cond.latitude_deg
        offset = model_drift_dph(zero, ctx, lat)
        cols = [np.ones_like(offset)]
        for p in paths[1:]:
            cols.append(model_drift_dph(set_params(zero, {p: 1.0}), ctx, lat) - offset)
        X_full = np.column_stack(cols)
        X = np.column_stack([_block(rd, c) for c in X_full.T])
        y = rd.measured["drift_dph"] - _block(rd, offset)
        out.append(_Prep(run, rd, ctx, lat, y, offset, X_full, X))
    return out, paths


def _grams(ys: list[np.ndarray], Zs: list[np.ndarray]):
    """Per-run Gram matrices of the design ``Zs`` and the targets ``ys``."""
    G = np.array([Z.T @ Z for Z in Zs])
    h = np.array([Z.T @ y for Z, y in zip(Zs, ys)])
    yy = np.array([y @ y for y in ys])
    n = np.array([y.size for y in ys], dtype=float)
    return G, h, yy, n


def _solve(G: np.ndarray, h: np.ndarray) -> np.ndarray:
    return np.linalg.lstsq(G, h, rcond=None)[0]


def _sse(beta, G, h, yy):
    return yy - 2.0 * (h @ beta) + np.einsum("i,rij,j->r", beta, G, beta)


def _cv_rms(G, h, yy, n, w=None) -> float:
    """Leave-one-distinct-run-out RMS with run multiplicities ``w``."""
    w = np.ones(len(yy)) if w is None else w
    tot, cnt = 0.0, 0.0
    for r in np.flatnonzero(w > 0):
        wt = w.copy()
        wt[r] = 0.0
        if not (wt > 0).any():
            continue
        beta = _solve(np.tensordot(wt, G, 1), wt @ h)
        tot += w[r] * float(yy[r] - 2.0 * h[r] @ beta + beta @ G[r] @ beta)
        cnt += w[r] * n[r]
    return math.sqrt(max(tot, 0.0) / cnt) if cnt else math.nan


def _wald(G, h, yy, n, w, idx: slice) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """Fit on weighted runs; (beta, cov, Wald statistic of beta[idx], s2)."""
    Gs, hs = np.tensordot(w, G, 1), w @ h
    beta = _solve(Gs, hs)
    sse = float(w @ _sse(beta, G, h, yy))
    m, p = float(w @ n), beta.size
    s2 = max(sse, 0.0) / max(m - p, 1.0)
    cov = np.linalg.pinv(Gs) * s2
    b, c = beta[idx], cov[idx, idx]
    stat = float(b @ np.linalg.pinv(c) @ b) if b.size else 0.0
    return beta, cov, stat, np.array(s2)


# ---------------------------------------------------------------------------------------------
# Results

@dataclass(frozen=True)
class CandidateScore:
    """What one candidate explains."""

    effect: str
    """Registry name."""
    target: str | None
    """Target (node, axis, channel) or None."""
    significant: bool
    """All of: CV drop > CV_DROP, Wald test rejects 0 at alpha, inclusion >= MIN_INCLUSION."""
    cv_rms_before: float
    """Leave-one-run-out RMS of the drift window means, model alone [deg/h]."""
    cv_rms_after: float
    """The same with the candidate [deg/h]."""
    correlation: float
    """Partial correlation of the baseline residual with the candidate's signature."""
    coefficient: dict[str, float]
    """Fitted candidate parameters (coefficients and shapes)."""
    interval: dict[str, tuple[float, float]]
    """95 % intervals from the Jacobian."""
    wald_p: float
    """p-value of the Wald test that all coefficients are 0."""
    inclusion_frequency: float
    """Fraction of run resamples where the CV RMS drops and the Wald test rejects 0."""
    heading_rmse_before_deg: float | None = None
    """Start-up heading RMSE with the baseline model's compensation [deg] (None: not run)."""
    heading_rmse_after_deg: float | None = None
    """The same with the candidate added [deg]."""
    explained_by: str | None = None
    """Label of the top significant candidate when that one explains this one too (its CV
    drop over the model plus the top candidate is below :data:`CV_DROP`)."""
    channel: str = "drift_dph"
    """Residual the CV RMS is taken on: ``drift_dph`` (window means, deg/h) or
    ``thermometers`` (the three thermometers at the knots, K)."""

    @property
    def cv_drop(self) -> float:
        """Relative drop of the CV RMS."""
        return 1.0 - self.cv_rms_after / self.cv_rms_before

    def to_dict(self) -> dict[str, Any]:
        return {"effect": self.effect, "target": self.target, "significant": self.significant,
                "cv_rms_before": self.cv_rms_before, "cv_rms_after": self.cv_rms_after,
                "cv_drop": self.cv_drop, "channel": self.channel,
                "explained_by": self.explained_by,
                "correlation": self.correlation,
                "coefficient": dict(self.coefficient),
                "interval": {k: list(v) for k, v in self.interval.items()},
                "wald_p": self.wald_p, "inclusion_frequency": self.inclusion_frequency,
                "heading_rmse_before_deg": self.heading_rmse_before_deg,
                "heading_rmse_after_deg": self.heading_rmse_after_deg}


@dataclass(frozen=True)
class Diagnosis:
    """The ranked candidates and what is left unexplained."""

    ranking: tuple[CandidateScore, ...]
    """Scored candidates: significant thermometer ones first, then by relative CV drop."""
    not_tried: tuple[Candidate, ...]
    """Candidates not scored, each with its reason."""
    unexplained: dict[str, Any]
    """Ljung-Box test of the baseline residual and its cross-correlation with every channel."""
    baseline: FitResult
    """The model's own drift refit (:func:`fit_model`, drift stage)."""
    time_s: float
    """Wall time [s]."""

    @property
    def significant(self) -> list[CandidateScore]:
        return [s for s in self.ranking if s.significant]

    @property
    def verdict(self) -> str:
        """One sentence: the significant candidates, or that none is."""
        sig = self.significant
        if not sig:
            return ("no candidate is significant: the missing effect (if any) is not in the "
                    "library; see 'unexplained'")
        def name(s):
            return s.effect if s.target is None else f"{s.effect}:{s.target}"
        own = [s for s in sig if s.explained_by is None]
        out = "significant: " + ", ".join(f"{name(s)} (CV RMS -{100 * s.cv_drop:.0f} % on "
                                          f"{s.channel})" for s in own)
        by = [s for s in sig if s.explained_by is not None]
        if by:
            out += (f"; also significant alone but explained by {by[0].explained_by}: "
                    + ", ".join(name(s) for s in by))
        return out

    def to_dict(self) -> dict[str, Any]:
        return {"ranking": [s.to_dict() for s in self.ranking],
                "verdict": self.verdict,
                "not_tried": [{"effect": c.effect, "target": c.target, "reason": c.reason}
                              for c in self.not_tried],
                "unexplained": self.unexplained, "time_s": self.time_s}


# ---------------------------------------------------------------------------------------------
# Scoring one candidate

def _cand_columns(c: Candidate, shapes: dict[str, float], preps: list[_Prep],
                  bare: Instrument, full: bool = False) -> list[np.ndarray]:
    e = _effect(c, {**{k: 0.0 for k in c.coefficients}, **shapes})
    units = _unit_effects(e, c.coefficients)
    out = []
    for p in preps:
        F = _columns(bare, units, p.ctx, p.lat)
        out.append(F if full else np.column_stack([_block(p.rd, f) for f in F.T]))
    return out


def _shape_bounds(c: Candidate, x0: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    spec = get_effect(c.effect)
    lb, ub = [], []
    for s in c.shapes:
        v, unit = x0[s], spec.parameter(s).unit
        if unit in ("s", "K"):
            lo, hi = min(SHAPE_GRID.get(s, (v,))) / 5.0, max(SHAPE_GRID.get(s, (v,))) * 5.0
        elif unit == "deg":
            lo, hi = v - 360.0, v + 360.0
        else:
            lo, hi = v - 2 * math.pi, v + 2 * math.pi
        lb.append(lo)
        ub.append(hi)
    return np.array(lb), np.array(ub)


def _fit_shapes(c: Candidate, preps, bare) -> tuple[dict[str, float], list[np.ndarray]]:
    """Best shape parameters: grid, then variable-projection refinement on all runs."""
    spec = get_effect(c.effect)
    y = np.concatenate([p.y for p in preps])
    X = np.vstack([p.X for p in preps])

    def resid(shapes: dict[str, float]):
        cols = _cand_columns(c, shapes, preps, bare)
        Z = np.hstack([X, np.vstack(cols)])
        beta = np.linalg.lstsq(Z, y, rcond=None)[0]
        return y - Z @ beta, cols

    if not c.shapes:
        return {}, resid({})[1]
    grid = [()]
    for s in c.shapes:
        values = SHAPE_GRID.get(s) or (spec.parameter(s).default,)
        grid = [g + (v,) for g in grid for v in values]
    best = min(grid, key=lambda g: float(np.sum(resid(dict(zip(c.shapes, g)))[0] ** 2)))
    x0 = dict(zip(c.shapes, best))
    lb, ub = _shape_bounds(c, x0)
    try:
        res = least_squares(lambda x: resid(dict(zip(c.shapes, x)))[0], np.array(best),
                            bounds=(lb, ub), x_scale=np.maximum(np.abs(best), 1.0),
                            max_nfev=30)
        x0 = dict(zip(c.shapes, map(float, res.x)))
    except Exception:  # keep the grid point when a refinement step fails
        pass
    return x0, resid(x0)[1]


def _score_columns(c: Candidate, names: Sequence[str], ys: list[np.ndarray],
                   Xs: list[np.ndarray], cols: list[np.ndarray], base_grams,
                   e_base: np.ndarray, rng: np.random.Generator, n_boot: int, alpha: float,
                   shape_se=None) -> tuple[CandidateScore, np.ndarray]:
    """Score candidate columns ``cols`` (coefficients ``names``) added to the model's ``Xs``.

    ``shape_se(beta_c, Zs, s2)`` -> (values, standard errors) of the shape parameters.
    Returns the score and the joint coefficients (model's, then the candidate's).
    """
    Zs = [np.hstack([X, cc]) for X, cc in zip(Xs, cols)]
    G, h, yy, n = _grams(ys, Zs)
    pm = Xs[0].shape[1]
    idx = slice(pm, G.shape[1])
    w1 = np.ones(len(ys))
    cv_before = _cv_rms(*base_grams)
    cv_after = _cv_rms(G, h, yy, n)
    beta, cov, stat, s2 = _wald(G, h, yy, n, w1, idx)
    k = idx.stop - idx.start
    wald_p = float(chi2.sf(stat, k))
    coef = dict(zip(names, map(float, beta[idx])))
    se = dict(zip(names, np.sqrt(np.maximum(np.diag(cov)[idx], 0.0))))
    if shape_se is not None:
        values, errors = shape_se(beta[idx], Zs, float(s2))
        coef.update(values)
        se.update(errors)
    interval = {p: (coef[p] - 1.96 * se[p], coef[p] + 1.96 * se[p]) for p in coef}
    # partial correlation: the candidate's fitted signature with the model's columns projected out
    X = np.vstack(Xs)
    sig = np.concatenate([cc @ beta[idx] for cc in cols])
    sig_perp = sig - X @ np.linalg.lstsq(X, sig, rcond=None)[0]
    den = float(np.linalg.norm(sig_perp) * np.linalg.norm(e_base))
    corr = float(sig_perp @ e_base / den) if den > 0 else 0.0
    # inclusion frequency over resamples of whole runs
    crit = chi2.ppf(1.0 - alpha, k)
    hits = 0
    Gb, hb, yyb, nb = base_grams
    for _ in range(n_boot):
        w = np.bincount(rng.integers(0, len(ys), len(ys)), minlength=len(ys)).astype(float)
        if np.count_nonzero(w) < 2:
            continue
        ok_cv = _cv_rms(G, h, yy, n, w) < _cv_rms(Gb, hb, yyb, nb, w)
        ok_w = _wald(G, h, yy, n, w, idx)[2] > crit
        hits += bool(ok_cv and ok_w)
    incl = hits / n_boot if n_boot else math.nan
    significant = bool(cv_after < (1.0 - CV_DROP) * cv_before and wald_p < alpha
                       and incl >= MIN_INCLUSION)
    score = CandidateScore(effect=c.effect, target=c.target, significant=significant,
                           cv_rms_before=cv_before, cv_rms_after=cv_after, correlation=corr,
                           coefficient=coef, interval=interval, wald_p=wald_p,
                           inclusion_frequency=incl, channel=c.channel)
    return score, beta


def _score(c: Candidate, preps: list[_Prep], bare: Instrument, base_grams,
           e_base: np.ndarray, rng: np.random.Generator, n_boot: int, alpha: float) -> tuple[
               CandidateScore, dict[str, float], np.ndarray, list[np.ndarray]]:
    """Score a gyro or accelerometer candidate on the drift window means.

    Returns (score, shape parameters, joint coefficients, the candidate's columns per run).
    """
    shapes, cols = _fit_shapes(c, preps, bare)

    def shape_se(beta_c, Zs, s2):
        # standard errors from the Jacobian of the fitted contribution (finite differences)
        contrib0 = np.concatenate([cc @ beta_c for cc in cols])
        J = [np.vstack(Zs)]
        for s in c.shapes:
            hstep = 1e-4 * max(abs(shapes[s]), 1.0)
            cols_s = _cand_columns(c, {**shapes, s: shapes[s] + hstep}, preps, bare)
            J.append(((np.concatenate([cc @ beta_c for cc in cols_s]) - contrib0)
                      / hstep)[:, None])
        J = np.hstack(J)
        cov_full = np.linalg.pinv(J.T @ J) * s2
        m = Zs[0].shape[1]
        errors = {s: float(math.sqrt(max(cov_full[m + i, m + i], 0.0)))
                  for i, s in enumerate(c.shapes)}
        return {s: float(shapes[s]) for s in c.shapes}, errors

    score, beta = _score_columns(c, c.coefficients, [p.y for p in preps],
                                 [p.X for p in preps], cols, base_grams, e_base, rng, n_boot,
                                 alpha, shape_se if c.shapes else None)
    return score, shapes, beta, cols


# ---------------------------------------------------------------------------------------------
# Heading RMSE of a compensated run

def _startup_heading_rmse(preps: list[_Prep], model_full: list[np.ndarray],
                          startup_end_s: float = 3600.0) -> float:
    """Pooled start-up heading RMSE north-finding gyro_dph minus the model drift [deg]."""
    sq, cnt = 0.0, 0
    for p, d in zip(preps, model_full):
        run = p.run
        cols = dict(run.columns)
        cols["gyro_compensated_dph"] = np.asarray(run["gyro_dph"], dtype=float) - d
        nf = north_find(replace(run, columns=cols), gyro_column="gyro_compensated_dph")
        st = heading_rmse(nf, startup_end_s=startup_end_s)
        if st.n_startup:
            sq += st.startup_deg ** 2 * st.n_startup
            cnt += st.n_startup
    return math.sqrt(sq / cnt) if cnt else math.nan


# ---------------------------------------------------------------------------------------------
# Unexplained: whiteness and cross-correlation

def _ljung_box(parts: list[np.ndarray], lags: int = 20) -> dict[str, float]:
    """Ljung-Box Q on the residual window means, autocorrelations pooled within runs
    (Ljung & Box 1978, Biometrika 65(2) 297, eq. (2.1)): Q = n (n+2) sum r_k^2 / (n-k)."""
    x = [p - np.mean(np.concatenate(parts)) for p in parts]
    n = sum(p.size for p in x)
    den = sum(float(p @ p) for p in x)
    q = 0.0
    r = []
    for k in range(1, lags + 1):
        rk = sum(float(p[k:] @ p[:-k]) for p in x if p.size > k) / den if den > 0 else 0.0
        r.append(rk)
        q += rk * rk / (n - k)
    q *= n * (n + 2)
    return {"Q": q, "lags": lags, "p_value": float(chi2.sf(q, lags)), "n": n,
            "white": bool(chi2.sf(q, lags) >= 0.01), "acf": r[:5]}


def _xcorr(e: list[np.ndarray], x: list[np.ndarray], max_lag: int) -> tuple[float, int]:
    """max |r| over lags (residual lagging the channel by ``lag`` windows) within runs."""
    mx = np.mean(np.concatenate(x))
    me = np.mean(np.concatenate(e))
    xs = [v - mx for v in x]
    es = [v - me for v in e]
    den = math.sqrt(sum(float(v @ v) for v in xs) * sum(float(v @ v) for v in es))
    if den == 0:
        return 0.0, 0
    best, lag = 0.0, 0
    for L in range(-max_lag, max_lag + 1):
        s = 0.0
        for ev, xv in zip(es, xs):
            m = ev.size
            if abs(L) >= m:
                continue
            s += float(ev[L:] @ xv[:m - L]) if L >= 0 else float(ev[:m + L] @ xv[-L:])
        r = s / den
        if abs(r) > abs(best):
            best, lag = r, L
    return best, lag


def _unexplained(preps: list[_Prep], e_parts: list[np.ndarray], decimate_s: float
                 ) -> dict[str, Any]:
    chans: dict[str, list[np.ndarray]] = {}
    for p in preps:
        run, rd = p.run, p.rd
        t = _block(rd, np.asarray(run["time_s"], dtype=float))
        series = {}
        for col in THERMOMETERS.values():
            if col in run.columns:
                v = _block(rd, np.asarray(run[col], dtype=float))
                series[col] = v
                series[f"d{col}/dt"] = np.gradient(v, t) if v.size > 1 else v * 0
        for col in ("acc_x_g", "acc_y_g"):
            if col in run.columns:
                series[col] = _block(rd, np.asarray(run[col], dtype=float))
        pos = np.radians(np.asarray(run["position_deg"], dtype=float))
        for k in (1, 2):  # first and second harmonics of the turntable position
            suffix = "" if k == 1 else "_2"
            for f, fn in (("cos", np.cos), ("sin", np.sin)):
                v = fn(k * pos)
                v[np.abs(v) < 1e-9] = 0.0  # sin(pi) = 1e-16 is not a signal
                series[f"{f}{suffix}_position"] = _block(rd, v)
        for col in run.columns:
            if col.startswith("aux_"):
                series[col] = _block(rd, np.asarray(run[col], dtype=float))
        for k, v in series.items():
            chans.setdefault(k, []).append(v)
    rows = []
    for name, parts in chans.items():
        if len(parts) != len(preps):
            continue
        r, lag = _xcorr(e_parts, parts, _MAX_LAG)
        rows.append({"channel": name, "max_abs_r": abs(r), "r": r,
                     "lag_s": lag * decimate_s})
    rows.sort(key=lambda d: -d["max_abs_r"])
    return {"ljung_box": _ljung_box(e_parts), "cross_correlation": rows,
            "residual_rms_dph": float(np.sqrt(np.mean(np.concatenate(e_parts) ** 2)))}


# ---------------------------------------------------------------------------------------------
# Thermal and thermometer candidates: linearised thermometer residual

#: Finite-difference step of a thermal candidate's parameter, started at 0, by unit.
_THERMAL_STEP = {"W": 0.05, "W/K": 0.005, "s": 5.0}
#: A thermal candidate whose column keeps less than this fraction of its norm after the
#: model's own columns are projected out is the same physics as a model parameter.
_SAME_SIGNATURE = 1e-3


@dataclass
class _ThermalSet:
    data: list[Any]            # fit._ThermalRun per run
    paths: list[str]           # the model's free thermal parameters
    values: np.ndarray
    base: list[np.ndarray]     # model minus measured, three thermometers stacked, per run
    X: list[np.ndarray]        # d model / d parameter, per run


def _thermal_resid(model: Instrument, data) -> list[np.ndarray]:
    parts = _thermal_residual_parts(model, data)
    return [np.concatenate([parts[c][i] for c in parts]) for i in range(len(data))]


def _thermal_set(inst: Instrument, runs: Sequence[Run], decimate_s: float) -> _ThermalSet:
    """The thermometer residual of the model and its Jacobian in the free thermal parameters
    (:func:`~nfs.diagnose.fit.default_free`, thermal stage), by forward differences."""
    data = [_prepare_thermal(r, decimate_s) for r in runs]
    paths = default_free(inst, ("thermal",))
    values = np.array([get_param(inst, p) for p in paths])
    base = _thermal_resid(inst, data)
    cols: list[list[np.ndarray]] = [[] for _ in runs]
    for p, v in zip(paths, values):
        h = 1e-3 * abs(v) if v else 1e-2
        moved = _thermal_resid(set_params(inst, {p: v + h}), data)
        for i, (m, b0) in enumerate(zip(moved, base)):
            cols[i].append((m - b0) / h)
    X = [np.column_stack(c) if c else np.zeros((b0.size, 0)) for c, b0 in zip(cols, base)]
    return _ThermalSet(data, paths, values, base, X)


def _thermal_cand_columns(c: Candidate, inst: Instrument, ts: _ThermalSet
                          ) -> list[np.ndarray]:
    """d model / d coefficient at 0 of a thermal or thermometer candidate, per run."""
    spec = get_effect(c.effect)
    cols: list[list[np.ndarray]] = [[] for _ in ts.data]
    for name in c.coefficients:
        h = _THERMAL_STEP.get(spec.parameter(name).unit, 1e-3)
        e = _effect(c, {k: (h if k == name else 0.0) for k in c.coefficients})
        moved = _thermal_resid(inst.with_effects(list(inst.effects) + [e]), ts.data)
        for i, (m, b0) in enumerate(zip(moved, ts.base)):
            cols[i].append((m - b0) / h)
    return [np.column_stack(cc) for cc in cols]


def _same_signature(cols: list[np.ndarray], ts: _ThermalSet) -> str:
    """The model parameter a candidate duplicates ('' when it adds a new direction)."""
    X, Z = np.vstack(ts.X), np.vstack(cols)
    if X.shape[1] == 0:
        return ""
    rest = Z - X @ np.linalg.lstsq(X, Z, rcond=None)[0]
    if np.linalg.norm(rest) > _SAME_SIGNATURE * np.linalg.norm(Z):
        return ""
    r = [abs(float(x @ Z[:, 0])) / (np.linalg.norm(x) * np.linalg.norm(Z[:, 0]) or 1.0)
         for x in X.T]
    return ts.paths[int(np.argmax(r))]


def _thermal_instrument(inst: Instrument, ts: _ThermalSet, beta_m: np.ndarray,
                        c: Candidate | None = None, beta_c: np.ndarray | None = None
                        ) -> Instrument:
    """The Gauss-Newton step of the linearised thermal fit, within the fit bounds."""
    x = ts.values + beta_m
    new = {}
    for p, v in zip(ts.paths, x):
        lo, hi = fit_bounds(inst, p)
        new[p] = float(np.clip(v, lo, hi))
    out = set_params(inst, new)
    if c is not None:
        spec = get_effect(c.effect)
        values = {k: float(b) if spec.parameter(k).unit != "s" else max(float(b), 0.0)
                  for k, b in zip(c.coefficients, beta_c)}  # a lag cannot be negative
        out = out.with_effects(list(out.effects) + [_effect(c, values)])
    return out


def _drift_heading(preps: list[_Prep]) -> float:
    """Start-up heading RMSE of prepared runs with the model's drift coefficients refitted
    (linear)."""
    G, h, _, _ = _grams([p.y for p in preps], [p.X for p in preps])
    beta = _solve(G.sum(0), h.sum(0))
    return _startup_heading_rmse(preps, [p.offset_full + p.X_full @ beta for p in preps])


def _explained_by_top(ranking: list[CandidateScore], scored, drift_design, thermal_design,
                      bare: Instrument, after_thermal) -> list[CandidateScore]:
    """Mark the significant candidates that the top significant one explains.

    One effect usually makes several targets significant at once (a coil-temperature term on
    the coil, the housing and the board: their temperatures move together; a missing heat
    source also shows in the drift as a temperature term on some node).  Each other
    significant candidate is refitted with the top one in the model; when its own CV drop
    over model + top is below :data:`CV_DROP`, it adds nothing the top one does not explain
    and gets ``explained_by`` = the top's label.  A drift candidate under a thermal top one
    is refitted on the drift of the thermal model with the top one added
    (``after_thermal(candidate, joint coefficients)`` -> prepared runs).
    """
    sig = [i for i, s in enumerate(ranking) if s.significant]
    if len(sig) < 2:
        return ranking
    by = {(s[0].effect, s[0].target): s for s in scored}
    top = ranking[sig[0]]
    label = top.effect if top.target is None else f"{top.effect}:{top.target}"
    c_top, _, _, beta_top, cols_top = by[(top.effect, top.target)]
    designs = {top.channel: (drift_design if top.channel == "drift_dph" else thermal_design,
                             cols_top)}
    if top.channel == "thermometers" and any(ranking[i].channel == "drift_dph"
                                             for i in sig[1:]):
        preps = after_thermal(c_top, beta_top)
        designs["drift_dph"] = (([p.y for p in preps], [p.X for p in preps]), None)
    else:
        preps = None
    out = list(ranking)
    for i in sig[1:]:
        s = ranking[i]
        if s.channel not in designs:
            continue
        (ys, Xs), top_cols = designs[s.channel]
        X_top = Xs if top_cols is None else [np.hstack([X, t]) for X, t in zip(Xs, top_cols)]
        c, _, shapes, _, cols = by[(s.effect, s.target)]
        if top_cols is None:  # a drift candidate on the thermal top's drift
            cols = _cand_columns(c, shapes, preps, bare)
        cv_top = _cv_rms(*_grams(ys, X_top))
        Z = [np.hstack([X, cc]) for X, cc in zip(X_top, cols)]
        if _cv_rms(*_grams(ys, Z)) > (1.0 - CV_DROP) * cv_top:
            out[i] = replace(s, explained_by=label)
    return out


# ---------------------------------------------------------------------------------------------
# Diagnose

def diagnose(inst: Instrument, runs: Sequence[Run], *, n_boot: int = 20, alpha: float = 0.01,
             random_state=0, decimate_s: float = DEFAULT_DECIMATE_S) -> Diagnosis:
    """Score every candidate effect the model lacks (module docstring for the method).

    ``inst`` is the model with its thermal part already fitted; its drift coefficients are
    refitted here (:func:`fit_model`, drift stage).  Raises NfsError for fewer than 2 runs
    (leave-one-run-out needs two).
    """
    t0 = time.perf_counter()
    runs = list(runs)
    if len(runs) < 2:
        raise NfsError(f"diagnose needs at least 2 runs (leave-one-run-out validation); got "
                       f"{len(runs)}: from one run a candidate cannot be told from the noise")
    paths = _model_paths(inst)
    baseline = fit_model(inst, runs, free=paths, stages=("drift",), decimate_s=decimate_s)
    preps, paths = _prepare(inst, runs, decimate_s)
    bare = _bare(inst)
    base_grams = _grams([p.y for p in preps], [p.X for p in preps])
    beta_model = _solve(base_grams[0].sum(0), base_grams[1].sum(0))
    e_parts = [p.y - p.X @ beta_model for p in preps]
    e_base = np.concatenate(e_parts)
    rng = np.random.default_rng(random_state)
    cands = candidates(inst, runs)
    scored = []
    for c in cands:
        if c.tried and c.channel == "drift_dph":
            scored.append((c, *_score(c, preps, bare, base_grams, e_base, rng, n_boot, alpha)))
    base_full = [p.offset_full + p.X_full @ beta_model for p in preps]
    h_before = _startup_heading_rmse(preps, base_full) if scored else math.nan
    not_tried = [c for c in cands if not c.tried]
    thermal_cands = [c for c in cands if c.tried and c.channel == "thermometers"]
    ts = _thermal_set(inst, runs, decimate_s) if thermal_cands else None
    if ts is not None:
        ys_t = [-b0 for b0 in ts.base]
        grams_t = _grams(ys_t, ts.X)
        beta_t = _solve(grams_t[0].sum(0), grams_t[1].sum(0))
        e_t = np.concatenate([y - X @ beta_t for y, X in zip(ys_t, ts.X)])
        h_before_t = None
        for c in thermal_cands:
            cols = _thermal_cand_columns(c, inst, ts)
            dup = _same_signature(cols, ts)
            if dup:
                not_tried.append(replace(c, tried=False, reason=(
                    f"same thermometer signature as the model's free {dup}")))
                continue
            score, beta = _score_columns(c, c.coefficients, ys_t, ts.X, cols, grams_t, e_t,
                                         rng, n_boot, alpha)
            scored.append((c, score, {}, beta, cols))
    # Thermometers are upstream of the drift: a missing thermal effect moves the coil
    # temperatures and also shows in the drift (as some node's temperature term), a missing
    # gyro effect never shows in the thermometers.  Significant thermometer candidates rank
    # first; within each group, by the relative drop of the CV RMS.
    scored.sort(key=lambda s: (not (s[1].significant and s[1].channel == "thermometers"),
                               s[1].cv_rms_after / s[1].cv_rms_before))
    drift_of: dict[tuple[str, str | None], list[_Prep]] = {}

    def after_thermal(c, beta):  # the drift of the GN thermal model with candidate c added
        key = (c.effect, c.target)
        if key not in drift_of:
            pm = len(ts.paths)
            drift_of[key] = _prepare(_thermal_instrument(inst, ts, beta[:pm], c, beta[pm:]),
                                     runs, decimate_s)[0]
        return drift_of[key]

    ranking = []
    for i, (c, s, shapes, beta, _) in enumerate(scored):
        if i < HEADING_TOP or s.significant:
            if c.channel == "drift_dph":
                pm = preps[0].X.shape[1]
                full = _cand_columns(c, shapes, preps, bare, full=True)
                model_full = [p.offset_full + p.X_full @ beta[:pm] + f @ beta[pm:]
                              for p, f in zip(preps, full)]
                s = replace(s, heading_rmse_before_deg=h_before,
                            heading_rmse_after_deg=_startup_heading_rmse(preps, model_full))
            else:
                # the linearised thermal refit (one Gauss-Newton step) then the drift refit,
                # beside the same step without the candidate
                if h_before_t is None:
                    h_before_t = _drift_heading(_prepare(_thermal_instrument(inst, ts, beta_t),
                                                         runs, decimate_s)[0])
                s = replace(s, heading_rmse_before_deg=h_before_t,
                            heading_rmse_after_deg=_drift_heading(after_thermal(c, beta)))
        ranking.append(s)

    ranking = _explained_by_top(ranking, scored, ([p.y for p in preps], [p.X for p in preps]),
                                (ys_t, ts.X) if ts is not None else None, bare, after_thermal)
    return Diagnosis(ranking=tuple(ranking), not_tried=tuple(not_tried),
                     unexplained=_unexplained(preps, e_parts, decimate_s), baseline=baseline,
                     time_s=time.perf_counter() - t0)


# ---------------------------------------------------------------------------------------------
# Apply

_THERMAL_STARTS = {"tau": 20.0}


def apply_candidate(inst: Instrument, runs: Sequence[Run], name: str,
                    target: str | None = None, *, decimate_s: float = DEFAULT_DECIMATE_S
                    ) -> tuple[Instrument, FitResult, dict[str, Any]]:
    """Add effect ``name`` (on ``target``) to ``inst``, refit, and report before/after.

    Gyro and accelerometer effects: the drift stage refits the model's drift coefficients and
    the new effect's coefficients and shape parameters (shapes started at the best point of
    :data:`SHAPE_GRID`).  Thermal and thermometer effects: both stages, default free set plus
    the new effect's parameters.  Returns (new instrument, FitResult, report) where the report
    holds ``rms_before``/``rms_after`` per channel (before = the model as given) and the
    pooled start-up ``heading_rmse_before_deg``/``heading_rmse_after_deg``.

    Raises NfsError for an unknown effect or target (listing the valid ones) or an effect
    the model already has on that target.
    """
    runs = list(runs)
    if not runs:
        raise NfsError("apply_candidate: no runs")
    spec = get_effect(name)  # EffectError (an NfsError) listing the valid names
    valid = _targets(spec, inst, runs)
    if target not in valid:
        shown = ", ".join("(none)" if v is None else v for v in valid) or "(none)"
        raise NfsError(f"effect '{name}' has no target '{target}'; valid targets: {shown}")
    if any(e.name == name and e.target_value == target for e in inst.effects):
        raise NfsError(f"the model already has '{name}'" + (f" on '{target}'" if target else ""))
    coefs, shapes, missing = _split_params(spec)
    c = Candidate(name, target, spec.kind, tuple(coefs), tuple(shapes), tried=True)
    starts: dict[str, float] = {k: 0.0 for k in coefs}
    if spec.kind in _FAST_KINDS:
        preps, _ = _prepare(inst, runs, decimate_s)
        best, _ = _fit_shapes(c, preps, _bare(inst))
        starts.update(best)
    else:
        for s in shapes:
            starts[s] = _THERMAL_STARTS.get(s, SHAPE_GRID.get(s, (1.0,))[0])
    e = _effect(c, starts)
    new = inst.with_effects(list(inst.effects) + [e])
    new_paths = [f"effects.{e.label}.{p}" for p in coefs + shapes]
    if spec.kind in _FAST_KINDS:
        result = fit_model(new, runs, free=_model_paths(inst) + new_paths, stages=("drift",),
                           decimate_s=decimate_s)
    else:
        free = list(dict.fromkeys(default_free(new) + new_paths))
        result = fit_model(new, runs, free=free, stages=("thermal", "drift"),
                           decimate_s=decimate_s)
    fitted = result.instrument

    def heading(model: Instrument) -> float:
        preps_m = []
        full = []
        for run in runs:
            rd = _prepare_drift(run, decimate_s, False, "raw")
            ctx = _drift_context(model, rd)
            p = _Prep(run, rd, ctx, rd.cond.latitude_deg, rd.measured["drift_dph"],
                      np.zeros(0), np.zeros((0, 0)), np.zeros((0, 0)))
            preps_m.append(p)
            full.append(model_drift_dph(model, ctx, p.lat))
        return _startup_heading_rmse(preps_m, full)

    report = {"effect": name, "target": target, "rms_before": dict(result.rms_before),
              "rms_after": dict(result.rms_after),
              "heading_rmse_before_deg": heading(inst),
              "heading_rmse_after_deg": heading(fitted), "warnings": list(result.warnings)}
    return fitted, result, report
