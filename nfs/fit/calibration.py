"""Calibrate a model's free parameters to measured runs.

Bounded nonlinear least squares (:func:`scipy.optimize.least_squares`, method ``trf``,
``x_scale="jac"``; :mod:`nfs.fit.stage`) in two stages.  By default every free
parameter has a Gaussian prior from its row in the table of ranges (:mod:`nfs.fit.prior`: the
typical range of real units as its one-sigma band, on the log for a positive quantity),
entered as rows beside the data rows, which are divided by their noise level: the solution
is the maximum a posteriori estimate, a parameter the runs do not determine stays inside
what real units have instead of running to a bound, and a fit started from another fit's
result meets the same prior.  The box of every parameter lies inside its hard range.

**thermal**
    Free thermal parameters (capacities, conductances, node powers, thermal-effect
    coefficients such as the TEC slopes) and thermometer parameters (lags, offsets).
    Residual: the model's noise-free thermometer readings minus the measured ``temp_fog_c``,
    ``temp_acc_x_c``, ``temp_acc_y_c`` of every run, on a decimated grid (every
    ``decimate_s``).  Each run is replayed with its own start temperature, chamber and
    motion (:func:`nfs.experiment.conditions_from_run`).  For speed the thermal network is
    solved on the decimated grid: the chamber temperature and the turntable's moving
    fraction are averaged over each decimated step and a state-dependent power (the TEC law)
    is held over each decimated step (an O(h) error against the simulator's 1 s hold).  The
    sensed node temperatures are brought back to the run's own time base by cubic Hermite
    interpolation (values and the solver's exact rates at the knots), and the thermometer
    chain of the simulator (:func:`nfs.sensors.thermometer_reading`: lag, thermometer
    effects, offset) runs there with its noise and quantisation switched off; the residual
    is taken at the knots and divided by the thermometer's noise and rounding level
    sqrt(noise_c^2 + quantum_c^2 / 12) (:mod:`nfs.fit.thermal_residual`).  The
    Jacobian is scipy's forward differences with all n + 1 parameter vectors solved as one
    stack (:func:`nfs.fit.stage.forward_jacobian`).
    With a prior, each free thermometer offset is centred on its soak anchor (the readings of
    the first minute after power-on minus T0, :mod:`nfs.fit.soak`).  With ``n_starts``
    > 1, when the solution from the preset stays above the noise (reduced chi-square > 1.5),
    the stage starts again from the preset with every capacity and conductance +-30 %
    (:func:`nfs.fit.stage.perturbed_starts`) and keeps the lowest cost.
**drift**
    Thermal parameters fixed at the thermal fit.  Free: ``gyro.bias_dph``, the gyro effect
    coefficients, the accelerometer biases, accelerometer effect coefficients and the
    turntable tilts.  The thermal solution of each run is computed once, at the run's own
    time base (as the simulator does), and the effects are evaluated on its
    :func:`nfs.experiment.effect_context`; a free parameter of a thermal effect makes the
    stage re-simulate at every evaluation.  Residuals, as means over windows of
    ``decimate_s`` of the samples at rest (:mod:`nfs.fit.drift_residual`): the model
    drift minus the measured drift and, when an accelerometer or turntable parameter is
    free, the model's ``acc_x_g``, ``acc_y_g`` minus the measured ones, each channel divided
    by the standard error of its window means so the units mix on a common scale.  The
    tilts and accelerometer biases start at their linear least-squares solution from the
    window means (:mod:`nfs.fit.sensor_fit`), then move with the rest.  After the stage
    the gyro's ARW, bias instability and rate random walk are fitted to the Allan deviation
    of the full-rate residual at rest (:mod:`nfs.fit.noise_fit`) and set in the fitted
    instrument.

Uncertainties: cov = s^2 (J^T J)^-1 with s^2 = 2 cost / (m - n) of the data rows at the
solution of each stage, or with a prior the posterior (J^T J / s^2 + P^T P)^-1 (pseudo-
inverse; a direction the data rows do not constrain gives an infinite standard error and its
parameters are reported as not identifiable).  These are conditional on the other stage's
parameters and on the model being right.  A parameter that ends on its bound is reported
with what it says about the model's structure (:func:`nfs.fit.departures.bound_advice`).
The result is a :class:`~nfs.fit.fit_result.FitResult`.
"""

from __future__ import annotations

import inspect
import functools
import math
import os
from dataclasses import dataclass, field, replace
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
from threadpoolctl import threadpool_limits

from ..errors import NfsError
from ..instrument import Instrument
from ..run import Run
from .drift_residual import (DriftRun, drift_channels, drift_context, model_drift_dph,
                             prepare_drift, window_means)
from .fit_result import FitResult
from .departures import fit_warnings
from .free_set import FIT_STAGES, THERMAL_KINDS, default_free, stage_of
from .noise_fit import GyroNoiseEstimate, gyro_noise_from_residual, noise_record
from .params import expand_paths, fit_bounds, get_param, param_paths, set_params
from .departures import bound_advice, departures
from .prior import Prior, build_prior
from .sensor_fit import LEVEL_PATHS, LevelData, level_from_means
from .soak import anchor_offsets, soak_offsets
from .stage import StageReport, perturbed_starts, solve_stage
from .start_state import StartModel
from .thermal_residual import (DEFAULT_START, ThermalRun, prepare_thermal, simulate_knots,
                               start_states, thermal_residual, thermal_residual_parts,
                               thermometer_floors)

__all__ = ["fit_model", "fitted_name", "DEFAULT_DECIMATE_S", "check_fit_keywords"]

#: Default decimation of the residual grid [s].
DEFAULT_DECIMATE_S = 10.0


# ---------------------------------------------------------------------------------------------
# Residual summaries

def _rms(parts: dict[str, list[np.ndarray]]) -> dict[str, float]:
    """RMS of each channel's residual over all runs [channel unit] (NaN: no residual)."""
    out = {}
    for ch, arrays in parts.items():
        x = np.concatenate(arrays) if arrays else np.empty(0)
        out[ch] = float(np.sqrt(np.mean(x * x))) if x.size else math.nan
    return out


# ---------------------------------------------------------------------------------------------
# Helpers of the stages

def _tec_identifiability(inst: Instrument, data: list[ThermalRun], free: Sequence[str]
                         ) -> dict[str, str]:
    """c_h (c_c) of a TEC law needs samples with the source below (above) T_set."""
    out = {}
    for e in inst.effects:
        if e.name != "tec_power":
            continue
        node = e.params.get("node") or inst.gyro.source
        below = above = 0
        for th in simulate_knots([inst], data)[0]:
            src = th.temperature_c[:, list(th.node_names).index(node)]
            below += int(np.sum(src < e.params["T_set"]))
            above += int(np.sum(src > e.params["T_set"]))
        total = max(below + above, 1)
        for par, n, side in (("c_h", below, "below"), ("c_c", above, "above")):
            path = f"effects.{e.label}.{par}"
            if path in free and n < 0.02 * total:
                out[path] = (f"the source never sits {side} T_set = {e.params['T_set']:g} C "
                             f"in these runs: it needs runs starting {side} T_set")
    return out


_NOISE_FIELDS = ("arw_deg_per_rth_h", "bias_instability_dph", "rrw_deg_per_h_per_rth_h")


def _level_start(base: Instrument, data_d: list[DriftRun], sp: Sequence[str],
                 weights: dict[str, float]) -> dict[str, float]:
    """Tilts and accelerometer biases from the window means at rest by linear least squares
    (:func:`nfs.fit.sensor_fit.level_from_means`), the model's accelerometer effects
    subtracted first."""
    free = [p for p in LEVEL_PATHS if p in sp]
    if not free:
        return {}
    level = set_params(base, {p: 0.0 for p in LEVEL_PATHS})
    rows = []
    for rd in data_d:
        effects = drift_channels(level, rd, rd.ctx)
        a = np.radians(rd.azimuth)
        rows.append(LevelData(cos_a=window_means(rd, np.cos(a)), sin_a=window_means(rd, np.sin(a)),
                              acc_x_g=rd.measured["acc_x_g"] - effects["acc_x_g"],
                              acc_y_g=rd.measured["acc_y_g"] - effects["acc_y_g"]))
    return level_from_means(rows, {p: get_param(base, p) for p in LEVEL_PATHS}, free,
                            scale_x_g=weights["acc_x_g"], scale_y_g=weights["acc_y_g"])


def _noise_of(model: Instrument, data_d: list[DriftRun]) -> GyroNoiseEstimate:
    """Allan fit of the full-rate drift residual at rest, gyro - projection - model drift,
    after the start-up hour and with its position harmonics removed
    (:func:`nfs.fit.noise_fit.noise_record`)."""
    recs = []
    for rd in data_d:
        e = (np.asarray(rd.run["gyro_dph"], dtype=float) - rd.projection
             - model_drift_dph(model, rd.ctx, rd.cond.latitude_deg))
        recs.append(noise_record(e[rd.trusted], rd.cond.time_s[rd.trusted],
                                 rd.azimuth[rd.trusted]))
    fs = float(np.median([rd.cond.sample_rate_hz for rd in data_d]))
    return gyro_noise_from_residual(recs, fs)


# ---------------------------------------------------------------------------------------------
# The stages

@dataclass(frozen=True)
class _Solver:
    """What every stage's solve shares: the boxes, the prior, the starts, the budget."""

    bounds: dict[str, tuple[float, float]]
    """The box of every free parameter."""
    prior: Prior | None
    """The Gaussian prior of the free parameters (None: none)."""
    n_starts: int
    """Most starts of the thermal stage."""
    max_nfev: int | None
    """Residual evaluations allowed per stage."""


@dataclass(frozen=True)
class _StageOutcome:
    """One stage run: the instrument it ended with and what it reports."""

    instrument: Instrument
    """The model after the stage."""
    report: StageReport | None = None
    """The solve's report (None: no parameter of the stage was free)."""
    stderr: dict[str, float] = field(default_factory=dict)
    """Standard error of each parameter it solved for."""
    unidentifiable: dict[str, str] = field(default_factory=dict)
    """Parameters it cannot determine, with the reason."""
    at_bound: tuple[str, ...] = ()
    """Parameters that ended on a bound."""
    rms_before: dict[str, float] = field(default_factory=dict)
    """Residual RMS per channel before the stage."""
    rms_after: dict[str, float] = field(default_factory=dict)
    """Residual RMS per channel after it."""


def _solve(name: str, fun, base: Instrument, sp: list[str], start: Mapping[str, float],
           solver: _Solver, batch=None) -> _StageOutcome:
    """Solve stage ``name`` from ``base`` over the free paths ``sp`` started at ``start``
    (:func:`nfs.fit.stage.solve_stage`; the thermal stage with up to ``n_starts - 1``
    perturbed extra starts)."""
    lb, ub = (np.array([solver.bounds[p][i] for p in sp]) for i in (0, 1))
    x0 = np.array([start[p] for p in sp])
    extra = (perturbed_starts(sp, x0, lb, ub)[:solver.n_starts - 1] if name == "thermal"
             else [])
    res, rep, se, un, at = solve_stage(name, fun, x0, lb, ub, solver.max_nfev, sp,
                                       None if solver.prior is None else solver.prior.subset(sp),
                                       extra, batch=batch)
    return _StageOutcome(instrument=set_params(base, dict(zip(sp, res.x))), report=rep,
                         stderr=se, unidentifiable=un, at_bound=tuple(at))


def _thermal_stage(inst: Instrument, runs: Sequence[Run], sp: list[str],
                   start: Mapping[str, float], solver: _Solver, decimate_s: float,
                   start_state: StartModel | None
                   ) -> tuple[_StageOutcome, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The thermal stage (module docstring) from ``inst`` over the free paths ``sp``.

    Returns the outcome, each run's start estimated with the fitted parameters {run name:
    node temperatures [degC]} and its start amplitudes [K] (both empty without
    ``start_state``).
    """
    data = [prepare_thermal(r, decimate_s) for r in runs]
    rms_before = _rms(thermal_residual_parts([inst], data, start_state)[0])
    solved = _StageOutcome(instrument=inst)
    if sp:
        # each thermometer's rows divided by its noise and rounding level, so the cost is
        # chi-square-like beside the prior rows
        floor = thermometer_floors(inst)

        def fun_many(xs) -> list[np.ndarray]:
            # the parameter vectors of a Jacobian solved as one stack (thermal_residual),
            # each run's start profiled out with its prior rows
            models = [set_params(inst, dict(zip(sp, x))) for x in xs]
            res = thermal_residual(models, data, start_state)
            return [np.concatenate([a / floor[c] for c, arrs in parts.items()
                                    for a in arrs] + [rows])
                    for parts, rows in zip(res.parts, res.start_rows)]

        solved = _solve("thermal", lambda x: fun_many([x])[0], inst, sp, start, solver,
                        batch=fun_many)
        solved = replace(solved, unidentifiable={
            **solved.unidentifiable, **_tec_identifiability(solved.instrument, data, sp)})
    fitted = solved.instrument
    final = thermal_residual([fitted], data, start_state)
    start_c: dict[str, np.ndarray] = {}
    amplitudes: dict[str, np.ndarray] = {}
    if start_state is not None:
        start_c = {rd.run.name: final.start_c[0][i] for i, rd in enumerate(data)}
        amplitudes = {rd.run.name: final.amplitudes_c[0][i] for i, rd in enumerate(data)}
    return (replace(solved, rms_before=rms_before, rms_after=_rms(final.parts[0])),
            start_c, amplitudes)


def _drift_parts(model: Instrument, data_d: list[DriftRun], channels: Iterable[str],
                 start_c: Mapping[str, np.ndarray], resimulate: bool
                 ) -> dict[str, list[np.ndarray]]:
    """Model minus measured window means of every channel, per run; the thermal network
    replayed for ``model`` when ``resimulate`` (a thermal parameter is free), else the
    runs' stored effect contexts."""
    parts: dict[str, list[np.ndarray]] = {ch: [] for ch in channels}
    for rd in data_d:
        ctx = drift_context(model, rd, start_c.get(rd.run.name)) if resimulate else rd.ctx
        for ch, y in drift_channels(model, rd, ctx).items():
            parts[ch].append(y - rd.measured[ch])
    return parts


def _drift_stage(inst: Instrument, runs: Sequence[Run], sp: list[str],
                 kinds: Mapping[str, str], start: Mapping[str, float], solver: _Solver,
                 decimate_s: float, drift_signal: str, start_c: Mapping[str, np.ndarray],
                 fit_noise: bool) -> tuple[_StageOutcome, GyroNoiseEstimate | None]:
    """The drift stage (module docstring) from ``inst`` over the free paths ``sp``, the
    runs started at ``start_c``; then, with ``fit_noise``, the gyro noise from the Allan
    deviation of the residual at rest.  Returns the outcome and the noise estimate."""
    acc_ch = any(kinds[p] in ("accelerometer", "turntable") for p in sp)
    data_d = [prepare_drift(r, decimate_s, acc_ch, drift_signal) for r in runs]
    resim = any(kinds[p] in THERMAL_KINDS for p in sp)
    for rd in data_d:
        rd.ctx = drift_context(inst, rd, start_c.get(rd.run.name))
    weights = {ch: float(np.median([rd.scale[ch] for rd in data_d]))
               for ch in data_d[0].measured}

    def fun(x):
        parts = _drift_parts(set_params(inst, dict(zip(sp, x))), data_d, weights, start_c,
                             resim)
        return np.concatenate([a / weights[ch] for ch, arrs in parts.items() for a in arrs])

    rms_before = _rms(_drift_parts(inst, data_d, weights, start_c, resim))
    if "acc_x_g" in weights:
        start = {**start, **_level_start(inst, data_d, sp, weights)}
    solved = _solve("drift", fun, inst, sp, start, solver)
    fitted = solved.instrument
    rms_after = _rms(_drift_parts(fitted, data_d, weights, start_c, resim))
    noise = None
    if fit_noise:
        noise = _noise_of(fitted, data_d)
        fitted = set_params(fitted, {f"gyro.{k}": getattr(noise, k) for k in _NOISE_FIELDS})
    return replace(solved, instrument=fitted, rms_before=rms_before, rms_after=rms_after), noise


# ---------------------------------------------------------------------------------------------
# The fit

def check_fit_keywords(keywords: Mapping[str, Any], caller: str) -> None:
    """TypeError, before any work, when ``keywords`` that ``caller`` hands on to
    :func:`fit_model` hold one it does not take (as an unknown keyword of any function)."""
    takes = inspect.signature(fit_model).parameters
    unknown = [k for k in keywords if k not in takes or k in ("inst", "runs")]
    if unknown:
        raise TypeError(f"{caller}() got an unexpected keyword argument {unknown[0]!r} "
                        f"(it passes keywords on to fit_model: "
                        f"{', '.join(k for k in takes if k not in ('inst', 'runs'))})")


def fitted_name(model_name: str, runs: Sequence[Run]) -> str:
    """Name of a model fitted to ``runs``: ``'<model> fitted to <source>'``, the source being
    the runs' common folder, else their names' common prefix, else their count (a model that
    was itself fitted keeps the name of the model it started from)."""
    folders = {r.path.parent.name for r in runs if r.path is not None}
    if len(folders) == 1 and all(r.path is not None for r in runs) and folders != {""}:
        source = f"the runs in {folders.pop()}/"
    else:
        prefix = os.path.commonprefix([r.name for r in runs]).rstrip("_-. ")
        source = f"{prefix}*" if len(runs) > 1 and prefix else \
            (runs[0].name if len(runs) == 1 else f"{len(runs)} runs")
    base = model_name.split(" fitted to ")[0]  # a refit names the first model, not a chain
    return f"{base} fitted to {source}"


def one_blas_thread(f):
    """Run ``f`` on one BLAS thread.  The fits' least squares land in different minima when
    the rounding of a multi-threaded BLAS changes with the core count (measured on a unit of
    the independent family: thermal cost 8981 on one thread, 9483 on two, and another answer
    of the diagnosis), so a fit's answer would depend on the machine; the systems are small,
    and one thread loses no time."""
    @functools.wraps(f)
    def pinned(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return f(*args, **kwargs)
    return pinned


@one_blas_thread
def fit_model(inst: Instrument, runs: Sequence[Run], free: Iterable[str] | None = None, *,
              stages: Sequence[str] = FIT_STAGES, decimate_s: float = DEFAULT_DECIMATE_S,
              max_nfev: int | None = 100, drift_signal: str = "raw",
              prior: Mapping[str, float | str] | str | None = "default",
              prior_scale: float = 1.0, soak_anchor: bool = True, n_starts: int = 1,
              fit_noise: bool = True, start_state: StartModel | None = DEFAULT_START,
              start_c: Mapping[str, np.ndarray] | None = None) -> FitResult:
    """Calibrate the free parameters of ``inst`` to ``runs`` (module docstring for the method).

    Parameters
    ----------
    inst : Instrument
        The model to start from.
    runs : sequence of Run
        Measured runs (any start temperatures, schedules, latitudes: each is replayed with
        its own).
    free : iterable of str, optional
        Parameter paths or glob patterns (:mod:`nfs.fit.params`); default
        :func:`default_free`.  Thermal and thermometer parameters go to the thermal stage,
        the others to the drift stage (all to the drift stage when only it runs).
    stages : sequence of str
        Which of ``("thermal", "drift")`` to run, in that order.
    decimate_s : float
        Spacing of the residual grid [s] (thermal knots; drift window length).
    max_nfev : int, optional
        Residual evaluations allowed per stage; a stage that hits it is reported as not
        converged.
    drift_signal : ``"raw"`` or ``"denoised"``
        Measured drift to fit: window means of gyro - projection, or the wavelet-denoised
        drift of :func:`nfs.denoise.separate_drift`.
    prior : ``"default"``, mapping or None
        Gaussian prior on every free parameter (:mod:`nfs.fit.prior`): ``"default"``
        takes it from the table of ranges (:func:`~nfs.fit.prior.range_prior`); a mapping
        {path or pattern: width} overrides some, centred on the start value (a number:
        absolute width; ``"30%"``: relative); None: no prior (unregularised least squares).
    prior_scale : float
        Multiplies every prior width; inf switches the prior off.
    soak_anchor : bool
        With a prior: centre each free thermometer offset on its reading in the first minute
        after power-on minus T0 (:func:`nfs.fit.soak.soak_offsets`), with the width of
        its standard error; runs that were not soaked are named in the warnings.
    n_starts : int
        Most starts of the thermal stage: the preset, then up to two perturbations of it
        (every capacity and conductance +-30 %,
        :func:`nfs.fit.stage.perturbed_starts`), tried only while the best
        solution stays above the noise (reduced chi-square > 1.5); the lowest cost is
        kept.  1 (default): the preset only.
    start_state : StartModel or None
        How each run's node temperatures at power-on are estimated with the thermal
        parameters (:mod:`nfs.fit.start_state`: an unfinished soak, a unit off its
        air); None: every node at T0, the soak taken as complete.
    start_c : mapping {run name: node temperatures [degC]}, optional
        The runs' starts when the thermal stage does not run (default: estimated from the
        thermometers through ``inst`` with ``start_state``).
    fit_noise : bool
        After the drift stage, fit the gyro's ARW, bias instability and rate random walk to the
        Allan deviation of the drift residual at rest (:mod:`nfs.fit.noise_fit`) and set
        them in the fitted instrument.

    Raises
    ------
    NfsError
        No runs, an unknown stage or parameter, a run without a channel a stage needs, no
        true_heading_deg for the drift stage.
    """
    runs = list(runs)
    if not runs:
        raise NfsError("fit_model: no runs to fit")
    stages = tuple(stages)
    for s in stages:
        if s not in FIT_STAGES:
            raise NfsError(f"fit_model: unknown stage '{s}'; stages: {', '.join(FIT_STAGES)}")
    if not decimate_s > 0:
        raise NfsError(f"fit_model: decimate_s must be > 0, got {decimate_s}")
    paths = default_free(inst, stages) if free is None else expand_paths(inst, list(free))
    kinds = dict(param_paths(inst))
    by_stage = {s: [p for p in paths if stage_of(kinds[p], stages) == s] for s in stages}
    bounds = {p: fit_bounds(inst, p) for p in paths}
    initial_params = {p: get_param(inst, p) for p in paths}
    if n_starts < 1:
        raise NfsError(f"fit_model: n_starts must be >= 1, got {n_starts}")
    if isinstance(prior, str) and prior != "default":
        raise NfsError(f"fit_model: prior must be 'default', a mapping of widths or None, "
                       f"got '{prior}'")
    use_prior = prior is not None and math.isfinite(prior_scale)
    pr = (build_prior(inst, paths, initial_params, None if prior == "default" else prior,
                      prior_scale) if use_prior else None)
    start = dict(initial_params)
    soak = None
    if pr is not None and soak_anchor and any(p.endswith(".offset_c") for p in paths):
        soak = soak_offsets(inst, runs, start=start_state if "thermal" in stages else None)
        pr, start = anchor_offsets(pr, start, soak, prior_scale)
    solver = _Solver(bounds=bounds, prior=pr, n_starts=n_starts, max_nfev=max_nfev)

    outcomes: list[_StageOutcome] = []
    current = inst
    noise = None
    amplitudes: dict[str, np.ndarray] = {}
    if "thermal" in stages:
        thermal, start_c, amplitudes = _thermal_stage(current, runs, by_stage["thermal"], start,
                                                      solver, decimate_s, start_state)
        outcomes.append(thermal)
        current = thermal.instrument
    elif start_c is not None:
        start_c = dict(start_c)
    else:
        start_c = ({} if start_state is None else
                   start_states(inst, runs, decimate_s, start_state))
    if "drift" in stages and by_stage["drift"]:
        drift, noise = _drift_stage(current, runs, by_stage["drift"], kinds, start, solver,
                                    decimate_s, drift_signal, start_c, fit_noise)
        outcomes.append(drift)
        current = drift.instrument

    reports = {o.report.name: o.report for o in outcomes if o.report is not None}
    stderr = {p: v for o in outcomes for p, v in o.stderr.items()}
    unident = {p: v for o in outcomes for p, v in o.unidentifiable.items()}
    at_bound = [p for o in outcomes for p in o.at_bound]
    params = {p: get_param(current, p) for p in paths}
    advice = {p: bound_advice(p, params[p], bounds[p]) for p in at_bound}
    shifts = {} if pr is None else pr.shift([params[q] for q in pr.paths])
    departed = departures({**params, **({} if noise is None else noise.values())},
                          {**stderr, **({} if noise is None else noise.stderr())})
    warnings = fit_warnings(runs, paths, params, initial_params, kinds, bounds, reports,
                            at_bound, advice, shifts, unident, soak, departed=tuple(departed))
    current = replace(current, name=fitted_name(inst.name, runs))
    return FitResult(instrument=current, initial=inst, params=params,
                     initial_params=initial_params, stderr=stderr, bounds=bounds,
                     at_bound=tuple(at_bound), unidentifiable=unident, stages=reports,
                     rms_before={k: v for o in outcomes for k, v in o.rms_before.items()},
                     rms_after={k: v for o in outcomes for k, v in o.rms_after.items()},
                     warnings=tuple(warnings),
                     prior_centre={} if pr is None else dict(zip(pr.paths, pr.centre.tolist())),
                     prior_sigma={} if pr is None else dict(zip(pr.paths, pr.linear_sigma().tolist())),
                     prior_shift=shifts,
                     bound_advice=advice, departures=departed, soak=soak, noise=noise,
                     start_c=start_c,
                     start_amplitudes_c=amplitudes)
