"""Name the physical effect a model is missing, with run-level statistics.

Missing physics is found by named terms: every registered effect that the model lacks (or
has on another target) is a *candidate* (:mod:`nfs.diagnose.candidates`); each is added to
the model in turn, the linear coefficients are refitted, and the candidate is scored by what
it explains (:mod:`nfs.diagnose.candidate_score`); the scores are then ranked
(:mod:`nfs.diagnose.ranking`).

Method
------
Each candidate is a linear least-squares problem over runs, y_r = [X_r, C_r] beta + e_r:
on the drift channel y_r are the run's 10 s window means of the measured drift minus the
model's fixed part, X_r the model's own drift columns and C_r the candidate's at fixed shape
parameters; an accelerometer candidate is scored on its own axis's window means at rest,
where it shows against a floor of a few ug instead of through the north finder's vertical
rate (X_r: the turntable tilts, the axis bias and the model's effects on the axis;
:mod:`nfs.diagnose.acc_columns`); on the thermometer channel y_r are the three thermometers,
X_r and C_r their Jacobians (:mod:`nfs.diagnose.columns`).  Window means within a run are
strongly autocorrelated, runs are independent, so every statistic is run-level
(:mod:`nfs.scoring.run_stats`), from the per-run Gram matrices:

- **Test.**  The candidate's coefficients are tested against zero with the cluster-robust
  CR2 covariance, one cluster per run (Liang & Zeger 1986; Bell & McCaffrey 2002; Cameron &
  Miller 2015, J. Human Resources 50(2) 317), t with Bell-McCaffrey degrees of freedom
  (at most G - 1, G runs) for one coefficient, Hotelling's F for k (denominator dof from
  the smallest of theirs, at most G - k; :meth:`~nfs.scoring.run_stats.ClusteredFit.test`).
  ``heat_source`` and ``motor_heat`` powers and an extra ``thermometer_lag`` cannot be
  negative: their test is one-sided (:data:`~nfs.diagnose.candidate_score.ONE_SIDED`).
- **Shape search paid for.**  A candidate with shape parameters (tau, D_mag, T_p, phi) is
  tested at every point of its grid (the grid its registration gives, :attr:`nfs.effects.Parameter.grid`) and its
  p-value is Bonferroni's over the grid, min(1, n_grid min_j p_j): valid whatever the
  correlation between grid points, since under "every coefficient is 0" the shape is
  irrelevant, and cheap, since each grid point's columns are computed once.  (Choosing the
  shape on training runs and testing on the others would halve the runs of a 7-run set.)
- **Family-wise control.**  Holm's step-down over all scored candidates of both channels
  (Holm 1979, Scand. J. Statist. 6(2) 65) at ``alpha`` (0.05): ``holm_p``.
- **Cross-validation.**  ``cv_rms_before`` / ``cv_rms_after``: the held-out RMS when each
  start temperature's runs (``run.meta.start_temperature_c``) are left out in turn, pooled
  over folds, model alone / model + candidate; in each fold the shape grid point is chosen
  on the training runs only (:func:`~nfs.scoring.run_stats.group_cv_rms`).
- **Significant** = Holm rejects the candidate AND its cross-validated RMS drops.

Reported beside the test: ``coefficient`` / ``interval``, fitted at shapes refined from the
best grid point by variable projection (:func:`~nfs.diagnose.columns.fit_shapes`), with 95 %
t intervals from the CR2 covariance of the linearised problem (coefficients and shapes
together); ``correlation``, of the baseline residual with the candidate's fitted signature
after the model's columns are projected out of it; ``inclusion_frequency``, over
``n_boot`` resamples of whole runs the fraction in which the CV RMS drops and the clustered
test rejects at ``alpha`` (descriptive, not part of the rule); ``heading_rmse_before_deg`` /
``after``, the start-up heading RMSE pooled over the runs north-finding the measured rate
minus the fitted model drift without / with the candidate (for the top
:data:`~nfs.diagnose.candidate_heading.HEADING_TOP` candidates and every significant one;
:mod:`nfs.diagnose.candidate_heading`).

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
link, a thermometer that sits elsewhere; :mod:`nfs.fit.structure`), scored with it on
the same leave-one-start-temperature-out thermometer residual within its physical bounds
(a power >= 0 W, a lag >= 0 s; :func:`nfs.fit.adequacy.thermal_adequacy`), pooled and
run by run (:func:`nfs.fit.adequacy.beats_structure`): a named heat source that only
fits because the network is wrong is then not significant, and the verdict says the
thermal structure does not fit, where, and what to change.

The drift has a structural alternative of its own (``check_structure``): a real coil weights
its temperature rates differently from the model's Shupe terms, and what the model misses of
that is fitted by whatever candidate has a similar time course (a turn-on transient, a rate
term on some other node).  A drift candidate is named plainly when it also stands beyond a
rate term on every node (its test with those columns in the model, Holm over the drift
candidates; :mod:`nfs.diagnose.drift_structure`); otherwise it is *tied* with the
alternative and the verdict says the runs cannot tell the named effect from a Shupe
weighting the model lacks.

Ranking (:mod:`nfs.diagnose.ranking`): significant thermometer candidates first (a missing
thermal effect also shows in the drift, a missing gyro effect never shows in the
thermometers), then by the relative CV drop.  One effect usually makes several targets
significant (a coil-temperature term on every node whose temperature follows the coil's):
every other significant candidate is refitted with the top one in the model, and if it then
drops the CV RMS by less than :data:`~nfs.diagnose.ranking.CV_DROP` it is marked
``explained_by`` the top one.  This 5 % is a practical threshold of "adds something of its
own", not a test; significance does not use it.

What is left unexplained: the Ljung-Box test of the baseline residual and its
cross-correlation with every channel (thermometers and their rates, accelerometers, the
turntable position's harmonics, ``aux_*``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import USER_ERRORS, NfsError
from ..instrument import Instrument
from ..run import Run
from .acc_columns import acc_grid_columns, model_acc_paths, prepare_acc
from ..fit.adequacy import ThermalAdequacy, thermal_adequacy
from .candidate_heading import ThermalDrift, with_heading
from .candidate_score import (ResidualChannel, ScoredCandidate, best_grid_point,
                              one_sided_sign, residual_channel, score_candidate,
                              score_with_shapes)
from .candidates import Candidate, candidates
from .columns import (PreparedRun, bare_instrument, grid_columns, model_drift_paths, prepare_runs,
                     same_signature, thermal_candidate_columns, thermal_design)
from .drift_structure import DriftStructure, beyond_alternative, rate_columns
from ..fit.calibration import DEFAULT_DECIMATE_S, fit_model, one_blas_thread
from ..fit.fit_result import FitResult
from .ranking import beyond_rate_terms, explained_by_top, rank, significance, structure_rivals
from .result import Diagnosis
from .smoother import smooth_runs
from ..fit.start_state import StartModel
from ..scoring.run_stats import RunGrams, group_cv_rms, run_grams
from ..fit.adequacy import structural_alternatives
from ..fit.structure import effect_alternative
from ..fit.thermal_residual import DEFAULT_START, start_states
from .unexplained import unexplained

__all__ = ["diagnose", "diagnose_candidates", "NODE_TEMPERATURES"]

#: Where the drift candidates' node temperatures come from: ``smoothed`` (estimated from the
#: measured thermometers through the model's network, :mod:`nfs.diagnose.smoother`) or
#: ``model`` (the model's open-loop solution from the chamber temperature).
NODE_TEMPERATURES = ("smoothed", "model")


# ---------------------------------------------------------------------------------------------
# What the steps pass on

@dataclass(frozen=True)
class _Drift:
    """The drift channel of the runs."""

    preps: list[PreparedRun]
    """Every run on the drift channel (window means at rest, the model's columns)."""
    paths: list[str]
    """The model's drift parameters (its columns)."""
    bare: Instrument
    """The instrument the candidates' columns are evaluated on (no bias, no effects)."""
    channel: ResidualChannel
    """Targets, model columns, the model's fit and the run resamples."""


@dataclass(frozen=True)
class _RateTerms:
    """The drift's generic alternative: a rate term on every node beside the model's columns
    (:mod:`nfs.diagnose.drift_structure`)."""

    nodes: tuple[str, ...]
    """The nodes of the rate terms."""
    X: list[np.ndarray]
    """The model's columns and the rate terms, per run."""
    base: RunGrams
    """Their Gram matrices."""
    cv_rms: float
    """Held-out RMS of the drift window means with them [deg/h]."""
    paths: list[str]
    """Names of their columns (the model's paths, then ``rate of <node>``)."""


@dataclass(frozen=True)
class _Scores:
    """Candidates scored on one kind of channel, and those set aside."""

    scored: list[ScoredCandidate]
    """The scored candidates, in candidate order."""
    not_tried: list[Candidate]
    """Candidates set aside (a missing column, the signature of a model parameter)."""
    channels: dict[str, ResidualChannel]
    """The residual channels they were scored on, by name."""


def _not_tried(c: Candidate, reason: str) -> Candidate:
    """Candidate ``c`` set aside for ``reason``."""
    return replace(c, tried=False, reason=reason)


# ---------------------------------------------------------------------------------------------
# The steps

def _cv_groups(runs: Sequence[Run]) -> np.ndarray:
    """The CV group of each run: its start temperature, or the run itself when all runs
    start at the same temperature (leave one run out)."""
    groups = np.unique([r.meta.start_temperature_c for r in runs], return_inverse=True)[1]
    if groups.max() < 1:  # one start temperature: leave one run out
        groups = np.arange(len(runs))
    return groups


def _node_temperatures(inst: Instrument, runs: Sequence[Run], source: str, decimate_s: float,
                       start_c: Mapping[str, np.ndarray]) -> tuple[Any, dict[str, Any]]:
    """The node temperatures the drift candidates are evaluated on, one per run (None: the
    model's own), and what the diagnosis reports of them (``node_temperatures``)."""
    node_info: dict[str, Any] = {"source": source}
    if source != "smoothed":
        return None, node_info
    try:
        sm = smooth_runs(inst, runs, decimate_s=decimate_s, start_c=start_c)
    except USER_ERRORS as exc:
        # a filter these runs leave ill-conditioned: the model's own node temperatures,
        # and the diagnosis says so
        node_info.update(source="model", smoother_failed=str(exc))
        return None, node_info
    node_info.update(q_w2_per_s=sm.q_w2_per_s,
                     significant=(bool(sm.fit.significant) if sm.fit is not None else None),
                     thermometer_rms_c=dict(sm.thermometer_rms_c))
    return sm.runs, node_info


def _run_resamples(groups: np.ndarray, n_boot: int, random_state) -> list[np.ndarray]:
    """``n_boot`` resamples of whole runs (indices, with replacement) drawn from
    ``random_state``, those that keep two CV groups (a CV needs them)."""
    n = groups.size
    rng = np.random.default_rng(random_state)
    boot = [rng.integers(0, n, n) for _ in range(n_boot)]
    return [b for b in boot if len(np.unique(groups[b])) >= 2]


def _rate_terms(drift: _Drift, groups: np.ndarray) -> _RateTerms:
    """A rate term on every node beside the model's drift columns, and its held-out RMS."""
    nodes, rates = rate_columns(drift.preps)
    alt_X = [np.hstack([X, R]) for X, R in zip(drift.channel.Xs, rates)]
    alt_base = run_grams(drift.channel.ys, alt_X)
    return _RateTerms(nodes=nodes, X=alt_X, base=alt_base,
                      cv_rms=group_cv_rms([alt_base], groups)[0],
                      paths=drift.paths + [f"rate of {n}" for n in nodes])


def _accelerometer_axes(inst: Instrument, runs: Sequence[Run], cands: Sequence[Candidate],
                        preps: list[PreparedRun], decimate_s: float, groups: np.ndarray,
                        boot: list[np.ndarray]) -> dict[str, Any]:
    """Per accelerometer axis with a candidate: (its runs,
    :func:`~nfs.diagnose.acc_columns.prepare_acc`; its residual channel), or None when a run
    lacks the axis's column."""
    out: dict[str, Any] = {}
    for c in cands:
        if c.tried and c.kind == "accelerometer" and c.target not in out:
            acc = prepare_acc(inst, runs, [p.ctx for p in preps], decimate_s, c.target)
            out[c.target] = None if acc is None else (acc, residual_channel(
                [a.y for a in acc], [a.X for a in acc], groups, boot))
    return out


def _score_accelerometer(c: Candidate, axis: Any, inst: Instrument, alpha: float
                         ) -> ScoredCandidate | Candidate:
    """An accelerometer candidate on its axis's window means (``axis``: the axis's runs and
    channel, None without the column), or the candidate set aside."""
    if axis is None:
        return _not_tried(c, f"a run lacks the column {c.channel}")
    acc, ch = axis
    grid = acc_grid_columns(c, acc)
    dup = (same_signature(grid[0][1], ch.Xs, model_acc_paths(inst, c.target), 1e-6)
           if len(grid) == 1 else "")
    if dup:
        return _not_tried(c, f"same {c.channel} signature as the model's {dup}")
    return score_candidate(c, ch, grid, alpha, best_grid_point(ch, grid))


def _beyond_rates(c: Candidate, grid: list, drift: _Drift, rates: _RateTerms,
                  groups: np.ndarray) -> tuple[float, float]:
    """A drift candidate tested with the rate terms in the model: (p-value, held-out RMS);
    (1, the alternative's RMS) when its columns lie in the rate terms' span."""
    if len(grid) == 1 and same_signature(grid[0][1], rates.X, rates.paths, 1e-6):
        return 1.0, rates.cv_rms
    return beyond_alternative(rates.base, drift.channel.ys, rates.X, grid, groups,
                              one_sided_sign(c))


def _score_fast_candidates(inst: Instrument, runs: Sequence[Run], cands: Sequence[Candidate],
                           drift: _Drift, rates: _RateTerms | None, groups: np.ndarray,
                           boot: list[np.ndarray], alpha: float, decimate_s: float
                           ) -> tuple[_Scores, dict[str, tuple[float, float]]]:
    """Every gyro candidate on the drift window means and every accelerometer candidate on
    its axis, in candidate order; with ``rates``, each scored gyro candidate also tested
    beyond the rate terms ({label: (p-value, held-out RMS)})."""
    axes = _accelerometer_axes(inst, runs, cands, drift.preps, decimate_s, groups, boot)
    channels = {"drift_dph": drift.channel}
    channels.update({c.channel: axes[c.target][1] for c in cands
                     if c.tried and c.kind == "accelerometer" and axes[c.target] is not None})
    scored, not_tried, beyond = [], [], {}
    for c in cands:
        if c.tried and c.kind == "accelerometer":
            out = _score_accelerometer(c, axes[c.target], inst, alpha)
        elif c.tried and c.channel == "drift_dph":
            grid = grid_columns(c, drift.preps, drift.bare)
            dup = (same_signature(grid[0][1], drift.channel.Xs, drift.paths, 1e-6)
                   if len(grid) == 1 else "")
            if dup:
                out = _not_tried(c, f"same drift signature as the model's {dup}")
            else:
                out = score_with_shapes(c, drift.channel, drift.preps, drift.bare, grid, alpha)
                if rates is not None:
                    beyond[c.label] = _beyond_rates(c, grid, drift, rates, groups)
        else:
            continue
        (scored if isinstance(out, ScoredCandidate) else not_tried).append(out)
    return _Scores(scored, not_tried, channels), beyond


def _structure_check(inst: Instrument, runs: Sequence[Run], thermal_cands: Sequence[Candidate],
                     start_state: StartModel | None) -> ThermalAdequacy:
    """The model's thermal structure against its generic alternatives, every thermal
    candidate scored alike (:func:`nfs.fit.adequacy.thermal_adequacy`)."""

    def alternatives(model: Instrument):
        """The generic alternatives and every thermal candidate, scored alike."""
        return structural_alternatives(model) + [effect_alternative(
            model, c.effect, c.target) for c in thermal_cands]

    return thermal_adequacy(inst, runs, alternatives, start_state=start_state)


def _score_thermal_candidates(inst: Instrument, runs: Sequence[Run],
                              thermal_cands: Sequence[Candidate], decimate_s: float,
                              start_state: StartModel | None, start_c: Mapping[str, Any],
                              groups: np.ndarray, boot: list[np.ndarray], alpha: float
                              ) -> tuple[_Scores, ThermalDrift | None]:
    """Every thermal candidate on the three thermometers, one Gauss-Newton step of the
    thermal refit (:func:`nfs.diagnose.columns.thermal_design`); and the thermal step whose
    drift the heading and ``explained_by`` use (None without thermal candidates)."""
    if not thermal_cands:
        return _Scores([], [], {}), None
    ts = thermal_design(inst, runs, decimate_s, start_state)
    therm = residual_channel([-b0 for b0 in ts.base], ts.X, groups, boot)
    scored, not_tried = [], []
    for c in thermal_cands:
        cols = thermal_candidate_columns(c, inst, ts)
        dup = same_signature(cols, ts.X, ts.paths)
        if dup:
            not_tried.append(_not_tried(
                c, f"same thermometer signature as the model's free {dup}"))
            continue
        scored.append(score_candidate(c, therm, [({}, cols)], alpha))
    thermal = ThermalDrift(inst=inst, ts=ts, beta_model=therm.beta, runs=runs,
                           decimate_s=decimate_s, start_c=start_c)
    return _Scores(scored, not_tried, {"thermometers": therm}), thermal


def _significant(scored: list[ScoredCandidate], beyond: Mapping[str, tuple[float, float]],
                 rates: _RateTerms | None, drift_cv_rms: float,
                 adequacy: ThermalAdequacy | None, alpha: float
                 ) -> tuple[list[ScoredCandidate], DriftStructure | None]:
    """The significance rule over every scored candidate (:mod:`nfs.diagnose.ranking`):
    Holm and the CV drop; the drift candidates beyond the rate terms; the thermal ones
    against the structure's rivals.  Returns the candidates and the drift's structure
    (None when not checked)."""
    if not scored:
        return scored, None
    scored = significance(scored, alpha)
    drift_structure = None
    if beyond:  # does a drift candidate stand beyond a rate term on every node?
        drift_structure, scored = beyond_rate_terms(scored, beyond, rates.nodes, drift_cv_rms,
                                                    rates.cv_rms, alpha)
    if adequacy is not None:  # a thermal candidate must also beat the structure's rivals
        scored = structure_rivals(scored, adequacy, {a.name: a for a in adequacy.alternatives
                                                     if a.kind == "effect"})
    return scored, drift_structure


# ---------------------------------------------------------------------------------------------
# Diagnose

def diagnose(inst: Instrument, runs: Sequence[Run], *, n_boot: int = 20, alpha: float = 0.05,
             random_state=0, decimate_s: float = DEFAULT_DECIMATE_S,
             node_temperatures: str = "smoothed", check_structure: bool = True,
             start_state: StartModel | None = DEFAULT_START,
             start_c: Mapping[str, np.ndarray] | None = None,
             baseline: FitResult | None = None) -> Diagnosis:
    """Score every candidate effect the model lacks (module docstring for the method).

    The keywords are those of :func:`diagnose_candidates`.  A linear algebra that these runs
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
        # one BLAS thread, as the fit: the answer must not depend on the core count
        return one_blas_thread(diagnose_candidates)(
            inst, runs, n_boot=n_boot, alpha=alpha, random_state=random_state,
            decimate_s=decimate_s, node_temperatures=node_temperatures,
            check_structure=check_structure, start_state=start_state, start_c=start_c,
            baseline=baseline)
    except (np.linalg.LinAlgError, FloatingPointError) as exc:
        return Diagnosis(ranking=(), not_tried=(), unexplained={}, baseline=None,
                         time_s=time.perf_counter() - t0, alpha=alpha,
                         failure=f"a least-squares system of these runs is ill-conditioned "
                                 f"({exc}); more runs, longer runs or runs at other start "
                                 "temperatures would condition it")


def diagnose_candidates(inst: Instrument, runs: Sequence[Run], *, n_boot: int = 20,
                        alpha: float = 0.05,
                        random_state=0, decimate_s: float = DEFAULT_DECIMATE_S,
                        node_temperatures: str = "smoothed", check_structure: bool = True,
                        start_state: StartModel | None = DEFAULT_START,
                        start_c: Mapping[str, np.ndarray] | None = None,
                        baseline: FitResult | None = None) -> Diagnosis:
    """Score every candidate effect the model lacks (:func:`diagnose` without its net for
    ill-conditioned runs).

    Parameters
    ----------
    inst : Instrument
        The model, its thermal part already fitted; its drift coefficients are refitted
        here (:func:`~nfs.fit.calibration.fit_model`, drift stage).
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
        (:func:`nfs.fit.adequacy.thermal_adequacy`); a thermal candidate is then
        significant only if it also beats every structural alternative.
    start_state : StartModel or None
        How each run's node temperatures at power-on are estimated
        (:mod:`nfs.fit.start_state`); None: the runs were soaked exactly at T0.
    start_c : mapping {run name: node temperatures [degC]}, optional
        The start states already estimated for this model (a fit's
        :attr:`~nfs.fit.FitResult.start_c`): used as they are, not estimated again.
    baseline : FitResult, optional
        The fit that made ``inst`` (its ``instrument`` is ``inst``): kept as the diagnosis's
        baseline instead of refitting the model's drift stage.

    The cross-validation leaves one start temperature out (one run, when all runs start
    at the same temperature).  Raises NfsError for fewer than 2 runs.
    """
    t0 = time.perf_counter()
    runs = list(runs)
    if len(runs) < 2:
        raise NfsError(f"diagnose needs at least 2 runs (leave-one-run-out validation); got "
                       f"{len(runs)}: from one run a candidate cannot be told from the noise")
    groups = _cv_groups(runs)
    if node_temperatures not in NODE_TEMPERATURES:
        raise NfsError(f"diagnose: node_temperatures must be one of "
                       f"{', '.join(NODE_TEMPERATURES)}, got {node_temperatures!r}")
    # each run's start (an unfinished soak), estimated once for every step below
    if start_c is None:
        start_c = start_states(inst, runs, decimate_s, start_state)
    if baseline is None or baseline.instrument is not inst:
        baseline = fit_model(inst, runs, free=model_drift_paths(inst), stages=("drift",),
                             decimate_s=decimate_s, start_state=start_state, start_c=start_c)
    smoothed, node_info = _node_temperatures(inst, runs, node_temperatures, decimate_s,
                                             start_c)
    preps, paths = prepare_runs(inst, runs, decimate_s, thermal=smoothed, start_c=start_c)
    boot = _run_resamples(groups, n_boot, random_state)
    drift = _Drift(preps, paths, bare_instrument(inst), residual_channel(
        [p.y for p in preps], [p.X for p in preps], groups, boot))
    drift_cv = group_cv_rms([drift.channel.base], groups)[0]
    cands = candidates(inst, runs)
    rates = _rate_terms(drift, groups) if check_structure else None
    fast, beyond = _score_fast_candidates(inst, runs, cands, drift, rates, groups, boot, alpha,
                                          decimate_s)
    thermal_cands = [c for c in cands if c.tried and c.channel == "thermometers"]
    adequacy = (_structure_check(inst, runs, thermal_cands, start_state) if check_structure
                else None)
    therm, thermal = _score_thermal_candidates(inst, runs, thermal_cands, decimate_s,
                                               start_state, start_c, groups, boot, alpha)
    scored, drift_structure = _significant(fast.scored + therm.scored, beyond, rates, drift_cv,
                                           adequacy, alpha)
    scored = rank(scored)
    ranking = with_heading(scored, preps, drift.bare, drift.channel.beta, thermal)
    ranking = explained_by_top(ranking, scored, groups, {**fast.channels, **therm.channels},
                               drift.bare, thermal)
    beta_model = drift.channel.beta
    return Diagnosis(ranking=tuple(ranking),
                     not_tried=tuple([c for c in cands if not c.tried] + fast.not_tried
                                     + therm.not_tried),
                     unexplained=unexplained(
                         inst, preps, [y - X @ beta_model for y, X in zip(drift.channel.ys,
                                                                           drift.channel.Xs)],
                         decimate_s), baseline=baseline,
                     time_s=time.perf_counter() - t0, alpha=alpha,
                     thermal_structure=adequacy, node_temperatures=node_info,
                     drift_structure=drift_structure,
                     coil_nodes=tuple(n for n in (inst.gyro.coil_outer, inst.gyro.coil_inner)
                                      if n))
