"""Name the physical effect a model is missing, with run-level statistics.

Missing physics is found by named terms (style.md, practice 6): every registered effect that
the model lacks (or has on another target) is a *candidate*
(:mod:`nfs.diagnose.candidates`); each is added to the model in turn, the linear
coefficients are refitted, and the candidate is scored by what it explains.

Method
------
Each candidate is a linear least-squares problem over runs, y_r = [X_r, C_r] beta + e_r:
on the drift channel y_r are the run's 10 s window means of the measured drift minus the
model's fixed part, X_r the model's own drift columns and C_r the candidate's at fixed shape
parameters; an accelerometer candidate is scored on its own axis's window means at rest,
where it shows against a floor of a few ug instead of through the north finder's vertical
rate (X_r: the turntable tilts, the axis bias and the model's effects on the axis;
:mod:`nfs.diagnose.acc_design`); on the thermometer channel y_r are the three thermometers,
X_r and C_r their Jacobians (:mod:`nfs.diagnose.design`).  Window means within a run are strongly
autocorrelated, runs are independent, so every statistic is run-level
(:mod:`nfs.diagnose.stats`), from the per-run Gram matrices:

- **Test.**  The candidate's coefficients are tested against zero with the cluster-robust
  CR2 covariance, one cluster per run (Liang & Zeger 1986; Bell & McCaffrey 2002; Cameron &
  Miller 2015, J. Human Resources 50(2) 317), t with Bell-McCaffrey degrees of freedom
  (at most G - 1, G runs) for one coefficient, Hotelling's F for k (denominator dof from
  the smallest of theirs, at most G - k; :meth:`~nfs.diagnose.stats.ClusteredFit.test`).
  ``heat_source`` and ``motor_heat`` powers and an extra ``thermometer_lag`` cannot be
  negative: their test is one-sided (:data:`ONE_SIDED`).
- **Shape search paid for.**  A candidate with shape parameters (tau, D_mag, T_p, phi) is
  tested at every point of its grid (:data:`~nfs.diagnose.candidates.SHAPE_GRID`) and its
  p-value is Bonferroni's over the grid, min(1, n_grid min_j p_j): valid whatever the
  correlation between grid points, since under "every coefficient is 0" the shape is
  irrelevant, and cheap, since each grid point's columns are computed once.  (Choosing the
  shape on training runs and testing on the others would halve the runs of a 7-run set.)
- **Family-wise control.**  Holm's step-down over all scored candidates of both channels
  (Holm 1979, Scand. J. Statist. 6(2) 65) at ``alpha`` (0.05): ``holm_p``.
- **Cross-validation.**  ``cv_rms_before`` / ``cv_rms_after``: the held-out RMS when each
  start temperature's runs (``run.meta.start_temperature_c``) are left out in turn, pooled
  over folds, model alone / model + candidate; in each fold the shape grid point is chosen
  on the training runs only (:func:`~nfs.diagnose.stats.group_cv_rms`).
- **Significant** = Holm rejects the candidate AND its cross-validated RMS drops.

Reported beside the test: ``coefficient`` / ``interval``, fitted at shapes refined from the
best grid point by variable projection (:func:`~nfs.diagnose.design.fit_shapes`), with 95 %
t intervals from the CR2 covariance of the linearised problem (coefficients and shapes
together); ``correlation``, of the baseline residual with the candidate's fitted signature
after the model's columns are projected out of it; ``inclusion_frequency``, over
``n_boot`` resamples of whole runs the fraction in which the CV RMS drops and the clustered
test rejects at ``alpha`` (descriptive, not part of the rule); ``heading_rmse_before_deg`` /
``after``, the start-up heading RMSE pooled over the runs north-finding the measured rate
minus the fitted model drift without / with the candidate (for the top
:data:`HEADING_TOP` candidates and every significant one).

Node temperatures of the drift candidates.  A real unit's thermal network is never the
model's, so the model's open-loop node temperatures (simulated from the chamber
temperature) are wrong in ways that a drift candidate can mimic: the drift misfit would be
blamed on whatever candidate follows the thermal error.  By default
(``node_temperatures="smoothed"``) the drift columns are evaluated on node temperatures
estimated from the measured thermometers through the model's network, a Kalman filter and
smoother whose unmodelled heat has its scale fitted by maximum likelihood
(:func:`nfs.diagnose.smoother.smooth_runs`); on runs the model explains the scale goes to
zero and the smoothed states are the open-loop ones.

Thermal and thermometer candidates (``heat_source``, ``motor_heat``, ``tec_power`` on each
node, ``thermometer_lag`` on each thermometer) are scored on the thermometers (``channel =
"thermometers"``) with one Gauss-Newton step of the thermal refit.  A candidate whose
columns lie in the span of the model's (a heat source at a node whose power the model fits)
is listed under ``not_tried`` with the model parameter it duplicates.  A thermal candidate
must also beat the generic structural alternatives of the network (one more node, a free
link, a thermometer that sits elsewhere; :mod:`nfs.diagnose.structure`), scored with it on
the same leave-one-start-temperature-out thermometer residual within its physical bounds
(a power >= 0 W, a lag >= 0 s; :func:`nfs.diagnose.adequacy.thermal_adequacy`), pooled and
run by run (:func:`nfs.diagnose.adequacy.beats_structure`): a named
heat source that only fits because the network is wrong is then not significant, and the
verdict says the thermal structure does not fit, where, and what to change.

The drift has a structural alternative of its own (``check_structure``): a real coil weights
its temperature rates differently from the model's Shupe terms, and what the model misses of
that is fitted by whatever candidate has a similar time course (a turn-on transient, a rate
term on some other node).  A drift candidate is named plainly when it also stands beyond a rate
term on every node (its test with those columns in the model, Holm over the drift
candidates; :mod:`nfs.diagnose.drift_structure`);
otherwise it is *tied* with the alternative and the verdict says the runs cannot tell the
named effect from a Shupe weighting the model lacks.

Ranking: significant thermometer candidates first (a missing thermal effect also shows in
the drift, a missing gyro effect never shows in the thermometers), then by the relative CV
drop.  One effect usually makes several targets significant (a coil-temperature term on
every node whose temperature follows the coil's): every other significant candidate is
refitted with the top one in the model, and if it then drops the CV RMS by less than
:data:`CV_DROP` it is marked ``explained_by`` the top one.  This 5 % is a practical
threshold of "adds something of its own", not a test; significance does not use it.

What is left unexplained: the Ljung-Box test of the baseline residual and its
cross-correlation with every channel (thermometers and their rates, accelerometers, the
turntable position's harmonics, ``aux_*``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from ..errors import USER_ERRORS, NfsError, ThermalError
from ..instrument import Instrument
from ..io.measurement import Run
from .adequacy import MODEL_RIVAL, structure_rival, thermal_adequacy
from .acc_design import AccRun, acc_grid_columns, model_acc_paths, prepare_acc
from .apply import apply_candidate
from .candidates import SHAPE_GRID, Candidate, candidates
from .design import (PreparedRun, bare_instrument, candidate_columns, fit_shapes,
                     grid_columns, model_drift_paths, prepare_runs, refit_heading_rmse,
                     same_signature, startup_heading_rmse, thermal_candidate_columns,
                     thermal_design, thermal_step_instrument)
from .drift_structure import DriftStructure, beyond_alternative, rate_columns
from .fit import DEFAULT_DECIMATE_S, fit_model
from .smoother import smooth_runs
from .start_state import StartModel
from .thermal_residual import DEFAULT_START, start_states
from .stats import (RunGrams, augmented_grams, clustered_fit, group_cv_rms, holm,
                    run_grams, solve)
from .structure import effect_alternative, physical_lower, structural_alternatives
from .result import CandidateScore, Diagnosis
from .unexplained import unexplained

__all__ = ["Candidate", "CandidateScore", "Diagnosis", "candidates", "diagnose",
           "apply_candidate", "SHAPE_GRID", "CV_DROP", "HEADING_TOP", "ONE_SIDED",
           "NODE_TEMPERATURES"]

#: Where the drift candidates' node temperatures come from: ``smoothed`` (estimated from the
#: measured thermometers through the model's network, :mod:`nfs.diagnose.smoother`) or
#: ``model`` (the model's open-loop solution from the chamber temperature).
NODE_TEMPERATURES = ("smoothed", "model")

#: A significant candidate is ``explained_by`` the top one when, refitted with the top one
#: in the model, it drops the CV RMS by less than this fraction (not used for significance).
CV_DROP = 0.05
#: Heading RMSE is computed for this many top-ranked candidates (and every significant one).
HEADING_TOP = 5
#: (effect, coefficient) -> sign of the only physical alternative: one-sided tests.
ONE_SIDED = {("heat_source", "power"): 1, ("motor_heat", "power"): 1,
             ("thermometer_lag", "tau"): 1}


# ---------------------------------------------------------------------------------------------
# Scoring one candidate

@dataclass(frozen=True)
class _Scored:
    """A scored candidate and what later steps need of it."""

    candidate: Candidate
    score: CandidateScore
    shapes: dict[str, float]   # refined shape parameters
    beta: np.ndarray           # joint coefficients (model's, then the candidate's)
    cols: list[np.ndarray]     # the candidate's columns per run at ``shapes``


@dataclass(frozen=True)
class _Channel:
    """One residual channel: targets, model columns and what every candidate shares."""

    ys: list[np.ndarray]
    Xs: list[np.ndarray]
    base: RunGrams             # Gram matrices of the model's columns alone
    beta: np.ndarray           # the model's coefficients
    groups: np.ndarray         # CV group (start temperature) of each run
    boot: list[np.ndarray]     # resamples of whole runs (indices), shared by the candidates
    boot_cv: list[float]       # the model's CV RMS on each resample


def _channel(ys, Xs, groups, boot) -> _Channel:
    base = run_grams(ys, Xs)
    boot_cv = [group_cv_rms([base], groups, np.bincount(b, minlength=len(ys)))[0]
               for b in boot]
    return _Channel(ys, Xs, base, clustered_fit(base).beta, groups, boot, boot_cv)


def _score(c: Candidate, ch: _Channel, grid: list[tuple[dict[str, float], list[np.ndarray]]],
           alpha: float, refined: tuple[dict[str, float], list[np.ndarray]] | None = None,
           shape_jac: list[np.ndarray] | None = None) -> _Scored:
    """Score candidate ``c`` on channel ``ch`` (module docstring).

    ``grid``: (shape values, columns per run) at every grid point (one entry without
    shapes); ``refined``: the estimate's shapes and columns (default the only grid point);
    ``shape_jac``: per run, d(fitted contribution)/d(shape) at the estimate, for the
    intervals of the shapes.  ``significant`` is set after Holm (:func:`diagnose`).
    """
    pm, k = ch.Xs[0].shape[1], len(c.coefficients)
    idx = list(range(pm, pm + k))
    sign = ONE_SIDED.get((c.effect, c.coefficients[0]), 0) if k == 1 else 0
    designs = [augmented_grams(ch.base, ch.ys, ch.Xs, cols) for _, cols in grid]
    tests = [clustered_fit(g).test(idx, sign) for g in designs]
    j = int(np.argmin([t[1] for t in tests]))
    wald_p = min(1.0, len(designs) * tests[j][1])
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
    interval = {n: (float(v - h), float(v + h)) for n, v, h in zip(names, values, half)}
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
                           channel=c.channel)
    return _Scored(c, score, dict(shapes), beta, cols)


def _best_grid_point(ch: _Channel, grid: list[tuple[dict[str, float], list[np.ndarray]]]
                     ) -> tuple[dict[str, float], list[np.ndarray]]:
    """The grid point of smallest pooled residual (the shapes of a candidate scored without
    a refinement of its shapes)."""

    def sse(cols):
        g = augmented_grams(ch.base, ch.ys, ch.Xs, cols)
        return float(g.sse(clustered_fit(g).beta).sum())
    return min(grid, key=lambda gc: sse(gc[1])) if len(grid) > 1 else grid[0]


def _score_drift(c: Candidate, ch: _Channel, preps: list[PreparedRun], bare: Instrument,
                 grid, alpha: float) -> _Scored:
    """Score a gyro or accelerometer candidate on the drift window means."""
    if not c.shapes:
        return _score(c, ch, grid, alpha)
    shapes, cols = fit_shapes(c, preps, bare, grid)
    beta_c = clustered_fit(augmented_grams(ch.base, ch.ys, ch.Xs, cols)).beta[
        ch.Xs[0].shape[1]:]
    jac: list[list[np.ndarray]] = [[] for _ in preps]
    for s in c.shapes:  # d(fitted contribution)/d(shape), forward differences
        step = 1e-4 * max(abs(shapes[s]), 1.0)
        moved = candidate_columns(c, {**shapes, s: shapes[s] + step}, preps, bare)
        for i, (m, c0) in enumerate(zip(moved, cols)):
            jac[i].append((m - c0) @ beta_c / step)
    return _score(c, ch, grid, alpha, (shapes, cols), [np.column_stack(J) for J in jac])


def _explained_by_top(ranking: list[CandidateScore], scored: list[_Scored], groups, channels,
                      bare: Instrument, after_thermal) -> list[CandidateScore]:
    """Mark the significant candidates that the top significant one explains.

    Each other significant candidate is refitted with the top one in the model; when its own
    CV drop over model + top is below :data:`CV_DROP`, it adds nothing the top one does not
    explain and gets ``explained_by`` = the top's label.  A drift candidate under a thermal
    top one is refitted on the drift of the thermal model with the top one added
    (``after_thermal(scored top)`` -> prepared runs).
    """
    sig = [i for i, s in enumerate(ranking) if s.significant]
    if len(sig) < 2:
        return ranking
    by = {(s.candidate.effect, s.candidate.target): s for s in scored}
    top = by[(ranking[sig[0]].effect, ranking[sig[0]].target)]
    label = top.candidate.label
    top_ch = channels[top.candidate.channel]
    own = {top.candidate.channel: ((top_ch.ys, top_ch.Xs), top.cols)}
    preps = None
    if top.candidate.channel == "thermometers" and any(
            ranking[i].channel == "drift_dph" for i in sig[1:]):
        preps = after_thermal(top)
        own["drift_dph"] = (([p.y for p in preps], [p.X for p in preps]), None)
    out = list(ranking)
    for i in sig[1:]:
        s = ranking[i]
        if s.channel not in own:
            continue
        (ys, Xs), top_cols = own[s.channel]
        X_top = Xs if top_cols is None else [np.hstack([X, t]) for X, t in zip(Xs, top_cols)]
        rec = by[(s.effect, s.target)]
        cols = rec.cols if top_cols is not None else candidate_columns(
            rec.candidate, rec.shapes, preps, bare)
        cv_top = group_cv_rms([run_grams(ys, X_top)], groups)[0]
        Z = [np.hstack([X, cc]) for X, cc in zip(X_top, cols)]
        if group_cv_rms([run_grams(ys, Z)], groups)[0] > (1.0 - CV_DROP) * cv_top:
            out[i] = replace(s, explained_by=label)
    return out


def _heading_or_nan(f) -> float:
    """A heading RMSE after a linearised thermal step, or NaN where that step leaves the
    network unphysical (a capacity through zero: the node temperatures are not finite)."""
    try:
        v = float(f())
    except (np.linalg.LinAlgError, FloatingPointError, ValueError, ThermalError):
        return math.nan
    return v if math.isfinite(v) else math.nan


def _physical(sc: CandidateScore) -> bool:
    """No coefficient below its physical bound (a heat power or a lag below 0)."""
    for k, v in sc.coefficient.items():
        lo = physical_lower(sc.effect, k)
        if lo is not None and v < lo:
            return False
    return True


def _rank_key(s: _Scored) -> tuple:
    """Significant thermometer candidates first (a missing thermal effect also shows in the
    drift, a missing gyro effect never in the thermometers), then significant drift and
    accelerometer ones, then the rest, unphysical ones last; within each group by the
    relative drop of the CV RMS."""
    sc = s.score
    group = (0 if sc.channel == "thermometers" else 1) if sc.significant else \
        (2 if sc.physical else 3)
    return group, sc.cv_rms_after / sc.cv_rms_before


# ---------------------------------------------------------------------------------------------
# Diagnose

def diagnose(inst: Instrument, runs: Sequence[Run], **kwargs) -> Diagnosis:
    """Score every candidate effect the model lacks (module docstring for the method).

    Keywords are those of :func:`diagnose_candidates`.  A linear algebra that these runs
    leave ill-conditioned (a singular or non-finite system in a candidate's refit) does not
    end in a traceback: the diagnosis comes back with its ``failure`` set and the answer
    "cannot be determined from these runs", with the reason.

    Raises
    ------
    NfsError
        Fewer than 2 runs, a bad setting, a run without a column a stage needs.
    """
    t0 = time.perf_counter()
    try:
        return diagnose_candidates(inst, runs, **kwargs)
    except (np.linalg.LinAlgError, FloatingPointError) as exc:
        return Diagnosis(ranking=(), not_tried=(), unexplained={}, baseline=None,
                         time_s=time.perf_counter() - t0, alpha=kwargs.get("alpha", 0.05),
                         failure=f"a least-squares system of these runs is ill-conditioned "
                                 f"({exc}); more runs, longer runs or runs at other start "
                                 "temperatures would condition it")


def diagnose_candidates(inst: Instrument, runs: Sequence[Run], *, n_boot: int = 20,
                        alpha: float = 0.05,
                        random_state=0, decimate_s: float = DEFAULT_DECIMATE_S,
                        node_temperatures: str = "smoothed", check_structure: bool = True,
                        start_state: StartModel | None = DEFAULT_START) -> Diagnosis:
    """Score every candidate effect the model lacks (:func:`diagnose` without its net for
    ill-conditioned runs).

    Parameters
    ----------
    inst : Instrument
        The model, its thermal part already fitted; its drift coefficients are refitted
        here (:func:`fit_model`, drift stage).
    runs : sequence of Run
        Measured runs (at least 2).
    n_boot : int
        Resamples of whole runs for ``inclusion_frequency``.
    alpha : float
        Family-wise error rate of Holm's procedure over all scored candidates.
    random_state : int or Generator
        Seed of the run resampling.
    decimate_s : float
        Window of the drift means [s].
    node_temperatures : ``"smoothed"`` or ``"model"``
        Node temperatures the drift candidates are evaluated on (:data:`NODE_TEMPERATURES`).
    check_structure : bool
        Set the model's thermal structure against generic alternatives
        (:func:`nfs.diagnose.adequacy.thermal_adequacy`); a thermal candidate is then
        significant only if it also beats every structural alternative.
    start_state : StartModel or None
        How each run's node temperatures at power-on are estimated
        (:mod:`nfs.diagnose.start_state`); None: the runs were soaked exactly at T0.

    The cross-validation leaves one start temperature out (one run, when all runs start
    at the same temperature).  Raises NfsError for fewer than 2 runs.
    """
    t0 = time.perf_counter()
    runs = list(runs)
    if len(runs) < 2:
        raise NfsError(f"diagnose needs at least 2 runs (leave-one-run-out validation); got "
                       f"{len(runs)}: from one run a candidate cannot be told from the noise")
    groups = np.unique([r.meta.start_temperature_c for r in runs], return_inverse=True)[1]
    if groups.max() < 1:  # one start temperature: leave one run out
        groups = np.arange(len(runs))
    if node_temperatures not in NODE_TEMPERATURES:
        raise NfsError(f"diagnose: node_temperatures must be one of "
                       f"{', '.join(NODE_TEMPERATURES)}, got {node_temperatures!r}")
    paths = model_drift_paths(inst)
    # each run's start (an unfinished soak), estimated once for every stage below
    start_c = start_states(inst, runs, decimate_s, start_state)
    baseline = fit_model(inst, runs, free=paths, stages=("drift",), decimate_s=decimate_s,
                         start_state=start_state, start_c=start_c)
    node_info: dict[str, Any] = {"source": node_temperatures}
    smoothed = None
    if node_temperatures == "smoothed":
        try:
            sm = smooth_runs(inst, runs, decimate_s=decimate_s, start_c=start_c)
        except USER_ERRORS as exc:
            # a filter these runs leave ill-conditioned: the model's own node temperatures,
            # and the diagnosis says so
            node_info.update(source="model", smoother_failed=str(exc))
        else:
            smoothed = sm.runs
            node_info.update(q_w2_per_s=sm.q_w2_per_s,
                             significant=(bool(sm.fit.significant) if sm.fit is not None
                                          else None),
                             thermometer_rms_c=dict(sm.thermometer_rms_c))
    preps, paths = prepare_runs(inst, runs, decimate_s, thermal=smoothed, start_c=start_c)
    bare = bare_instrument(inst)
    rng = np.random.default_rng(random_state)
    boot = [rng.integers(0, len(runs), len(runs)) for _ in range(n_boot)]
    boot = [b for b in boot if len(np.unique(groups[b])) >= 2]  # a CV needs two groups
    drift = _channel([p.y for p in preps], [p.X for p in preps], groups, boot)
    drift_cv = group_cv_rms([drift.base], groups)[0]
    drift_structure = None
    beta_model = drift.beta
    cands = candidates(inst, runs)
    not_tried = [c for c in cands if not c.tried]
    scored = []
    beyond: dict[str, tuple[float, float]] = {}   # drift candidate -> over the alternative
    if check_structure:
        nodes, rates = rate_columns(preps)
        alt_X = [np.hstack([X, R]) for X, R in zip(drift.Xs, rates)]
        alt_base = run_grams(drift.ys, alt_X)
        cv_alt = group_cv_rms([alt_base], groups)[0]
        alt_paths = paths + [f"rate of {n}" for n in nodes]
    channels = {"drift_dph": drift}
    acc_runs: dict[str, list[AccRun] | None] = {}
    for c in cands:
        if c.tried and c.kind == "accelerometer":
            if c.target not in acc_runs:
                acc_runs[c.target] = prepare_acc(inst, runs, [p.ctx for p in preps],
                                                 decimate_s, c.target)
            acc = acc_runs[c.target]
            if acc is None:
                not_tried.append(replace(c, tried=False, reason=(
                    f"a run lacks the column {c.channel}")))
                continue
            if c.channel not in channels:
                channels[c.channel] = _channel([a.y for a in acc], [a.X for a in acc],
                                               groups, boot)
            ch = channels[c.channel]
            grid = acc_grid_columns(c, acc)
            dup = (same_signature(grid[0][1], ch.Xs, model_acc_paths(inst, c.target), 1e-6)
                   if len(grid) == 1 else "")
            if dup:
                not_tried.append(replace(c, tried=False, reason=(
                    f"same {c.channel} signature as the model's {dup}")))
                continue
            scored.append(_score(c, ch, grid, alpha, _best_grid_point(ch, grid)))
        elif c.tried and c.channel == "drift_dph":
            grid = grid_columns(c, preps, bare)
            dup = same_signature(grid[0][1], drift.Xs, paths, 1e-6) if len(grid) == 1 else ""
            if dup:
                not_tried.append(replace(c, tried=False, reason=(
                    f"same drift signature as the model's {dup}")))
                continue
            scored.append(_score_drift(c, drift, preps, bare, grid, alpha))
            if check_structure:
                sign = ONE_SIDED.get((c.effect, c.coefficients[0]), 0) if len(
                    c.coefficients) == 1 else 0
                beyond[c.label] = ((1.0, cv_alt) if len(grid) == 1 and same_signature(
                    grid[0][1], alt_X, alt_paths, 1e-6) else beyond_alternative(
                    alt_base, drift.ys, alt_X, grid, groups, sign))
    thermal_cands = [c for c in cands if c.tried and c.channel == "thermometers"]
    adequacy = None
    if check_structure:
        def alternatives(model: Instrument):
            """The generic alternatives and every thermal candidate, scored alike."""
            return structural_alternatives(model) + [effect_alternative(
                model, c.effect, c.target) for c in thermal_cands]

        adequacy = thermal_adequacy(inst, runs, alternatives, start_state=start_state)
        effect_alt = {a.name: a for a in adequacy.alternatives
                     if a.kind == "effect"}
    ts = thermal_design(inst, runs, decimate_s, start_state) if thermal_cands else None
    if ts is not None:
        therm = _channel([-b0 for b0 in ts.base], ts.X, groups, boot)
        beta_t = therm.beta
        channels["thermometers"] = therm
        for c in thermal_cands:
            cols = thermal_candidate_columns(c, inst, ts)
            dup = same_signature(cols, ts.X, ts.paths)
            if dup:
                not_tried.append(replace(c, tried=False, reason=(
                    f"same thermometer signature as the model's free {dup}")))
                continue
            scored.append(_score(c, therm, [({}, cols)], alpha))
    # family-wise control over every scored candidate, then "and the CV RMS drops"
    if scored:
        reject, adj = holm([s.score.wald_p for s in scored], alpha)
        scored = [replace(s, score=replace(
            s.score, holm_p=float(a), significant=bool(r and s.score.cv_rms_after
                                                       < s.score.cv_rms_before)))
                  for s, r, a in zip(scored, reject, adj)]
        if beyond:  # does a drift candidate stand beyond a rate term on every node?
            labels = list(beyond)
            holm_beyond = dict(zip(labels, holm([beyond[b][0] for b in labels], alpha)[1]))
            rate_drops = {s.candidate.label: s.score.cv_drop for s in scored
                          if s.candidate.effect == "shupe_rate"}
            drift_structure = DriftStructure(
                nodes=nodes, cv_rms_model=drift_cv, cv_rms_alternative=cv_alt,
                tied=tuple(s.candidate.label for s in scored if s.score.significant
                           and holm_beyond.get(s.candidate.label, 0.0) > alpha),
                best_rate=max(rate_drops, key=rate_drops.get) if rate_drops else None)
            scored = [replace(s, score=replace(
                s.score, beyond_structure_p=float(holm_beyond[s.candidate.label])))
                if s.candidate.label in beyond else s for s in scored]
        if adequacy is not None:  # a thermal candidate must also beat the structure's rivals
            for i, s in enumerate(scored):
                if s.candidate.channel != "thermometers" or not s.score.significant:
                    continue
                alt = effect_alt.get(s.candidate.label)
                r = MODEL_RIVAL if alt is None else structure_rival(alt, adequacy)
                scored[i] = replace(s, score=replace(
                    s.score, significant=r is None,
                    structure_tie=None if r in (None, MODEL_RIVAL) else r))
    # Thermometers are upstream of the drift: significant thermometer candidates rank first;
    # within each group, by the relative drop of the CV RMS.
    scored = [replace(s, score=replace(s.score, physical=_physical(s.score))) for s in scored]
    scored.sort(key=_rank_key)
    drift_of: dict[str, list[PreparedRun]] = {}

    def after_thermal(s: _Scored) -> list[PreparedRun]:
        """The drift of the Gauss-Newton thermal model with candidate ``s`` added."""
        if s.candidate.label not in drift_of:
            pm = len(ts.paths)
            drift_of[s.candidate.label] = prepare_runs(thermal_step_instrument(
                inst, ts, s.beta[:pm], s.candidate, s.beta[pm:]), runs, decimate_s,
                start_c=start_c)[0]
        return drift_of[s.candidate.label]

    ranking = []
    h_before = h_before_t = None
    for i, s in enumerate(scored):
        sc = s.score
        if i < HEADING_TOP or sc.significant:
            if s.candidate.kind == "accelerometer":
                # the axis's error enters the heading through the drift (the x axis: the
                # north finder's vertical-rate removal; the y axis: not at all)
                if h_before is None:
                    h_before = startup_heading_rmse(
                        preps, [p.offset_full + p.X_full @ beta_model for p in preps])
                k = len(s.candidate.coefficients)
                full = candidate_columns(s.candidate, s.shapes, preps, bare, full=True)
                model_full = [p.offset_full + p.X_full @ beta_model + f @ s.beta[-k:]
                              for p, f in zip(preps, full)]
                sc = replace(sc, heading_rmse_before_deg=h_before,
                             heading_rmse_after_deg=startup_heading_rmse(preps, model_full))
            elif s.candidate.channel == "drift_dph":
                if h_before is None:
                    h_before = startup_heading_rmse(
                        preps, [p.offset_full + p.X_full @ beta_model for p in preps])
                pm = preps[0].X.shape[1]
                full = candidate_columns(s.candidate, s.shapes, preps, bare, full=True)
                model_full = [p.offset_full + p.X_full @ s.beta[:pm] + f @ s.beta[pm:]
                              for p, f in zip(preps, full)]
                sc = replace(sc, heading_rmse_before_deg=h_before,
                             heading_rmse_after_deg=startup_heading_rmse(preps, model_full))
            else:
                # the linearised thermal refit (one Gauss-Newton step) then the drift refit,
                # beside the same step without the candidate
                if h_before_t is None:
                    h_before_t = _heading_or_nan(lambda: refit_heading_rmse(prepare_runs(
                        thermal_step_instrument(inst, ts, beta_t), runs, decimate_s,
                        start_c=start_c)[0]))
                sc = replace(sc, heading_rmse_before_deg=h_before_t,
                             heading_rmse_after_deg=_heading_or_nan(
                                 lambda: refit_heading_rmse(after_thermal(s))))
        ranking.append(sc)
    ranking = _explained_by_top(ranking, scored, groups, channels, bare, after_thermal)
    return Diagnosis(ranking=tuple(ranking), not_tried=tuple(not_tried),
                     unexplained=unexplained(
                         inst, preps, [y - X @ beta_model for y, X in zip(drift.ys, drift.Xs)],
                         decimate_s), baseline=baseline,
                     time_s=time.perf_counter() - t0, alpha=alpha,
                     thermal_structure=adequacy, node_temperatures=node_info,
                     drift_structure=drift_structure,
                     coil_nodes=tuple(n for n in (inst.gyro.coil_outer, inst.gyro.coil_inner)
                                      if n))
