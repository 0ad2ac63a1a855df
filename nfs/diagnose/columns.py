"""Design matrices of the candidate scores: the drift window means and the thermometers.

Drift channel.  The thermal solution of every run is computed once from the model's
(already fitted) thermal parameters (:func:`nfs.fit.drift_residual.drift_context`) and
the measured drift is reduced to means over windows of ``decimate_s`` at rest
(:func:`nfs.fit.drift_residual.prepare_drift`).  The model drift
(:func:`~nfs.fit.drift_residual.model_drift_dph`) is linear in ``gyro.bias_dph`` and in the
coefficients of the gyro effects (b1, b2, k_r, k_s, k_p, k_m, a, m, A_p, k, s1), so each is a
column of a design matrix on the window means (:class:`PreparedRun`); a candidate adds its
own columns, one per coefficient, at fixed shape parameters (:func:`candidate_columns`).

Thermometer channel.  The residual is the three thermometers at the knots of the thermal
stage (:func:`nfs.fit.calibration.fit_model`); the model's own columns are the Jacobian of the
readings in its free thermal parameters (forward differences), the candidate's the
derivatives of the readings in its parameters at 0 (a power step of 0.05 W, a TEC slope of
0.005 W/K, an extra lag of 5 s: ``thermometer_lag``'s tau is a coefficient of the
linearised reading y - tau dy/dt).  This is one Gauss-Newton step of the thermal refit,
accurate when the model's thermal part is already fitted (``nfs fit``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Mapping, Sequence

import numpy as np
from scipy.optimize import least_squares

from ..effects.registry import EffectInstance
from ..effects import get_effect
from ..instrument import Instrument
from ..run import Run
from ..northfind import heading_rmse, north_find
from .candidates import Candidate, effect_of, shape_grid, split_parameters
from ..fit.drift_residual import (DriftRun, drift_context, drift_context_on, model_drift_dph,
                             prepare_drift, window_means)
from ..fit.free_set import default_free
from ..fit.start_state import StartModel
from ..fit.thermal_residual import DEFAULT_START, prepare_thermal, thermal_residual_parts
from ..fit.params import fit_bounds, get_param, set_params
from ..scoring.run_stats import run_grams, solve

__all__ = ["PreparedRun", "prepare_runs", "bare_instrument", "model_drift_paths",
           "candidate_columns", "grid_columns", "fit_shapes", "startup_heading_rmse",
           "refit_heading_rmse", "ThermalDesign", "thermal_design",
           "thermal_candidate_columns", "same_signature", "thermal_step_instrument"]


@dataclass(frozen=True)
class PreparedRun:
    """One run on the drift channel: the model's columns and the target, per window."""

    run: Run
    """The measured run."""
    rd: DriftRun
    """Its drift-stage preparation (:func:`nfs.fit.drift_residual.prepare_drift`)."""
    ctx: Any
    """Effect context: on the model's open-loop thermal solution or on smoothed node
    temperatures (:func:`prepare_runs`)."""
    lat: float
    """Latitude [deg]."""
    y: np.ndarray
    """Measured drift window means minus the model's fixed part [deg/h]."""
    offset_full: np.ndarray
    """Fixed part of the model drift at full rate [deg/h]."""
    X_full: np.ndarray
    """Model columns at full rate, (n_samples, p)."""
    X: np.ndarray
    """Model columns, window means, (n_windows, p)."""


def bare_instrument(inst: Instrument) -> Instrument:
    """``inst`` with zero bias, unit scale factor, zero accelerometer biases, no effects."""
    return set_params(inst, {"gyro.bias_dph": 0.0, "gyro.scale_factor": 1.0,
                             "accelerometers.bias_x_g": 0.0,
                             "accelerometers.bias_y_g": 0.0}).with_effects([])


def model_drift_paths(inst: Instrument) -> list[str]:
    """Drift-channel parameters of the model: the gyro bias and the gyro effect coefficients."""
    out = ["gyro.bias_dph"]
    for e in inst.effects:
        if e.spec.kind == "gyro":
            coefs, _, _ = split_parameters(e.spec)
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


def prepare_runs(inst: Instrument, runs: Sequence[Run], decimate_s: float,
                 thermal: Sequence[Any] | None = None,
                 start_c: Mapping[str, np.ndarray] | None = None
                 ) -> tuple[list[PreparedRun], list[str]]:
    """Every run on the drift channel, and the model's drift parameter paths (its columns).

    The drift effects are evaluated on the model's open-loop node temperatures (started at
    ``start_c[run name]`` when given, else at T0), or on ``thermal`` (one per run, e.g. the
    smoothed node temperatures of :func:`nfs.diagnose.smoother.smooth_runs`) when given.
    """
    start_c = start_c or {}
    paths = model_drift_paths(inst)
    zero = set_params(inst, {p: 0.0 for p in paths})
    out = []
    for i, run in enumerate(runs):
        rd = prepare_drift(run, decimate_s, False, "raw")
        ctx = (drift_context(inst, rd, start_c.get(run.name)) if thermal is None
               else drift_context_on(inst, rd, thermal[i]))
        lat = rd.cond.latitude_deg
        offset = model_drift_dph(zero, ctx, lat)
        cols = [np.ones_like(offset)]
        for p in paths[1:]:
            cols.append(model_drift_dph(set_params(zero, {p: 1.0}), ctx, lat) - offset)
        X_full = np.column_stack(cols)
        X = np.column_stack([window_means(rd, c) for c in X_full.T])
        y = rd.measured["drift_dph"] - window_means(rd, offset)
        out.append(PreparedRun(run, rd, ctx, lat, y, offset, X_full, X))
    return out, paths


def candidate_columns(c: Candidate, shapes: dict[str, float], preps: list[PreparedRun],
                      bare: Instrument, full: bool = False) -> list[np.ndarray]:
    """The candidate's drift columns per run, one per coefficient (that coefficient 1, the
    others 0, shapes fixed): window means, or at full rate when ``full``."""
    e = effect_of(c, {**{k: 0.0 for k in c.coefficients}, **shapes})
    units = _unit_effects(e, c.coefficients)
    out = []
    for p in preps:
        F = _columns(bare, units, p.ctx, p.lat)
        out.append(F if full else np.column_stack([window_means(p.rd, f) for f in F.T]))
    return out


def _shape_bounds(c: Candidate, x0: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    spec = get_effect(c.effect)
    lb, ub = [], []
    for s in c.shapes:
        par = spec.parameter(s)
        v, unit = x0[s], par.unit
        if par.bounds is not None:
            lo, hi = par.bounds
        elif unit in ("s", "K"):
            grid = par.grid if par.grid is not None else (v,)
            lo, hi = min(grid) / 5.0, max(grid) * 5.0
        elif unit == "deg":
            lo, hi = v - 360.0, v + 360.0
        else:
            lo, hi = v - 2 * math.pi, v + 2 * math.pi
        lb.append(lo)
        ub.append(hi)
    return np.array(lb), np.array(ub)


def grid_columns(c: Candidate, preps: list[PreparedRun], bare: Instrument
                 ) -> list[tuple[dict[str, float], list[np.ndarray]]]:
    """(shape values, the candidate's window-mean columns per run) at every grid point of
    its shape parameters (:func:`~nfs.diagnose.candidates.shape_grid`)."""
    return [(g, candidate_columns(c, g, preps, bare)) for g in shape_grid(c)]


def fit_shapes(c: Candidate, preps: list[PreparedRun], bare: Instrument,
               grid: list[tuple[dict[str, float], list[np.ndarray]]] | None = None
               ) -> tuple[dict[str, float], list[np.ndarray]]:
    """Shape parameters on all runs: the grid point of smallest residual, refined by bounded
    least squares with the coefficients profiled out (variable projection; Golub & Pereyra
    1973, SIAM J. Numer. Anal. 10(2) 413).  Returns (shapes, columns per run)."""
    grid = grid_columns(c, preps, bare) if grid is None else grid
    ys = [p.y for p in preps]
    sse = []
    for _, cols in grid:
        g = run_grams(ys, [np.hstack([p.X, cc]) for p, cc in zip(preps, cols)])
        sse.append(float(g.sse(solve(*_pooled(g))).sum()))
    best, cols = grid[int(np.argmin(sse))]
    if not c.shapes:
        return {}, cols
    y = np.concatenate(ys)
    X = np.vstack([p.X for p in preps])

    def resid(x: np.ndarray) -> np.ndarray:
        Z = np.hstack([X, np.vstack(candidate_columns(c, dict(zip(c.shapes, x)), preps,
                                                      bare))])
        return y - Z @ np.linalg.lstsq(Z, y, rcond=None)[0]

    x0 = np.array([best[s] for s in c.shapes])
    lb, ub = _shape_bounds(c, best)
    try:
        res = least_squares(resid, x0, bounds=(lb, ub), x_scale=np.maximum(np.abs(x0), 1.0),
                            max_nfev=30)
    except Exception:  # keep the grid point when a refinement step fails
        return dict(best), cols
    shapes = dict(zip(c.shapes, map(float, res.x)))
    return shapes, candidate_columns(c, shapes, preps, bare)


def _pooled(g) -> tuple[np.ndarray, np.ndarray]:
    return g.gram.sum(0), g.moment.sum(0)


def startup_heading_rmse(preps: list[PreparedRun], model_full: list[np.ndarray],
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


#: Finite-difference step of a thermal candidate's parameter, started at 0, by unit.
_THERMAL_STEP = {"W": 0.05, "W/K": 0.005, "s": 5.0}
#: A thermal candidate whose column keeps less than this fraction of its norm after the
#: model's own columns are projected out is the same physics as a model parameter.
_SAME_SIGNATURE = 1e-3


@dataclass(frozen=True)
class ThermalDesign:
    """The thermometer channel of every run, linearised at the model's thermal parameters."""

    data: list[Any]
    """:func:`nfs.fit.thermal_residual.prepare_thermal` of each run."""
    paths: list[str]
    """The model's free thermal parameters."""
    values: np.ndarray
    """Their values in the model."""
    base: list[np.ndarray]
    """Model minus measured, the three thermometers stacked, per run [K]."""
    X: list[np.ndarray]
    """d model / d parameter, per run."""
    start: StartModel | None = DEFAULT_START
    """How each run's start was profiled (:mod:`nfs.fit.start_state`)."""


def _thermal_resid(models: Sequence[Instrument], data, start: StartModel | None
                   ) -> list[list[np.ndarray]]:
    """Per model, per run: model minus measured, the three thermometers stacked [K] (the
    models solved as one stack)."""
    return [[np.concatenate([parts[c][i] for c in parts]) for i in range(len(data))]
            for parts in thermal_residual_parts(models, data, start)]


def thermal_design(inst: Instrument, runs: Sequence[Run], decimate_s: float,
                   start: StartModel | None = DEFAULT_START) -> ThermalDesign:
    """The thermometer residual of the model and its Jacobian in the free thermal parameters
    (:func:`~nfs.fit.free_set.default_free`, thermal stage), by forward differences, each
    run's start profiled (``start``, :mod:`nfs.fit.start_state`)."""
    data = [prepare_thermal(r, decimate_s) for r in runs]
    paths = default_free(inst, ("thermal",))
    values = np.array([get_param(inst, p) for p in paths])
    steps = [1e-3 * abs(v) if v else 1e-2 for v in values]
    base, *moved_all = _thermal_resid(
        [inst] + [set_params(inst, {p: v + h}) for p, v, h in zip(paths, values, steps)], data, start)
    cols: list[list[np.ndarray]] = [[] for _ in runs]
    for h, moved in zip(steps, moved_all):
        for i, (m, b0) in enumerate(zip(moved, base)):
            cols[i].append((m - b0) / h)
    X = [np.column_stack(c) if c else np.zeros((b0.size, 0)) for c, b0 in zip(cols, base)]
    return ThermalDesign(data, paths, values, base, X, start)


def thermal_candidate_columns(c: Candidate, inst: Instrument, ts: ThermalDesign
                              ) -> list[np.ndarray]:
    """d model / d coefficient at 0 of a thermal or thermometer candidate, per run."""
    spec = get_effect(c.effect)
    cols: list[list[np.ndarray]] = [[] for _ in ts.data]
    steps = [_THERMAL_STEP.get(spec.parameter(name).unit, 1e-3) for name in c.coefficients]
    models = [inst.with_effects(list(inst.effects) + [effect_of(
        c, {k: (h if k == name else 0.0) for k in c.coefficients})])
        for name, h in zip(c.coefficients, steps)]
    for h, moved in zip(steps, _thermal_resid(models, ts.data, ts.start)):
        for i, (m, b0) in enumerate(zip(moved, ts.base)):
            cols[i].append((m - b0) / h)
    return [np.column_stack(cc) for cc in cols]


def same_signature(cols: list[np.ndarray], Xs: list[np.ndarray], paths: Sequence[str],
                   tol: float = _SAME_SIGNATURE) -> str:
    """The model parameter (of ``paths``, the columns of ``Xs``) that a candidate's columns
    ``cols`` duplicate, '' when they add a new direction: a candidate whose columns keep
    less than ``tol`` of their norm once the model's are projected out cannot be told from
    the model (a heat source at a node whose power the model fits, to the accuracy of the
    finite differences: 1e-3; the Shupe rate of the inner coil, exactly the model's
    coil-mean rate minus half its radial-gradient rate: 1e-6)."""
    X, Z = np.vstack(Xs), np.vstack(cols)
    if X.shape[1] == 0:
        return ""
    XZ = X.T @ Z
    zz = float(np.sum(Z * Z))
    rest2 = zz - float(np.sum(XZ * solve(X.T @ X, XZ.T).T))  # |Z - X (X^T X)^-1 X^T Z|^2
    if rest2 > tol ** 2 * zz:
        return ""
    r = [abs(float(x @ Z[:, 0])) / (np.linalg.norm(x) * np.linalg.norm(Z[:, 0]) or 1.0)
         for x in X.T]
    return paths[int(np.argmax(r))]


def thermal_step_instrument(inst: Instrument, ts: ThermalDesign, beta_m: np.ndarray,
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
        out = out.with_effects(list(out.effects) + [effect_of(c, values)])
    return out


def refit_heading_rmse(preps: list[PreparedRun]) -> float:
    """Start-up heading RMSE of prepared runs with the model's drift coefficients refitted
    (linear)."""
    beta = solve(*_pooled(run_grams([p.y for p in preps], [p.X for p in preps])))
    return startup_heading_rmse(preps, [p.offset_full + p.X_full @ beta for p in preps])

