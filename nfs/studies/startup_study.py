"""The compensation study behind ``nfs table``: train every method, apply, score.

Protocol (the FOG start-up paper, done on equal terms):

1. Training start-ups: the scenario's instrument at its start temperatures (by default all
   seven), simulated with a different seed from the test start-ups, so no test noise is seen
   in training.  The drift target is wavelet-separated; inputs are named thermometer features.
2. Each method is fitted on the stacked, decimated training data.  Tuned methods search their
   hyperparameters with the same budget of evaluations of the same leave-one-run-out (one
   start temperature out) validation error, once per tuner seed (``tuner_seeds``; a grid
   search, which draws nothing, once): the row shown is the seed whose mean is the median,
   and the table gives the spread of the seeds' means.
3. Test start-ups (the scenario's own runs, the ``before`` row): predict the drift from each
   run's thermometers, subtract it from the gyro output, north-find, score the start-up RMSE by
   start temperature.  The drift table scores the predicted drift against the separated drift
   of the test runs over the start-up stage (the FOG start-up paper, Table 2).
4. Uncertainty: every cell and row mean gets a 95 % interval from a two-level bootstrap over
   the test start-ups and their cycles, and rows are compared in pairs on the same start-ups,
   Holm-adjusted (:mod:`nfs.scoring.intervals`).

The features of the test runs and their separated drift are computed once and shared by
every method; the trainings (methods x tuner seeds) run in parallel on ``n_jobs`` worker
processes, each seeded on its own, so the table does not depend on ``n_jobs``; on several
workers they start as soon as the training set is made, while the test start-ups are
simulated.
"""

from __future__ import annotations

import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from joblib import Parallel, delayed, effective_n_jobs
from threadpoolctl import threadpool_limits
from sklearn.exceptions import ConvergenceWarning

from ..compensate.compensator import (DriftCompensator, PredictionPlan, prediction_plan,
                                      train_compensator)
from ..compensate.dataset import DriftDataset, drift_dataset
from ..compensate.catalog import MethodSpec
from ..compensate import get_method
from ..compensate.modes import FEATURE_MODE_NOTES, check_features_mode
from ..compensate.settings import CompensationSettings
from ..denoise import separate_drift
from ..docfields import document_fields
from ..errors import NfsError
from ..experiment import simulate_runs
from ..io.provenance import output_provenance
from ..scoring.heading_table import TableRow, pooled_rmse
from ..workers import close_unread
from .scenario_runs import (northfind_runs, run_scenario, run_stage_errors, stage_names,
                            uncompensated_table)

__all__ = ["train_scenario", "train_method", "train_and_predict", "ticker", "training_pool", "MethodResult",
           "SeedResult", "CompensationStudy", "run_study", "test_scenario", "DriftRow",
           "errors_by_temperature", "table_provenance"]


@document_fields
@dataclass(frozen=True)
class DriftRow:
    """Drift residual over the start-up stage of the test runs (the FOG start-up paper,
    Table 2)."""

    method: str
    mae_dph: float
    """Mean absolute residual [deg/h] (NaN for the uncompensated row)."""
    std_dph: float
    """Standard deviation of the residual within each run, pooled over the runs [deg/h]:
    a constant offset over a run cancels in north finding, its variation does not."""


@document_fields
@dataclass(frozen=True)
class SeedResult:
    """One training of a method (one tuner seed) scored on the test runs."""

    seed: int
    """The method's random_state."""
    rmse_deg: tuple[float, ...]
    """Start-up heading RMSE at each start temperature [deg]."""
    best_params: dict
    """Tuned hyperparameters (empty for an untuned method)."""
    on_bound: tuple[str, ...] = ()
    """Tuned hyperparameters found within 1 % (of the box's width in the tuner's scale) of
    a bound of their box, e.g. ``('C high (100)',)``."""
    startup_errors_deg: tuple = ()
    """Start-up heading errors of its compensated test runs [deg], by start temperature,
    one array per run."""
    fit_time_s: float = float("nan")
    """Wall time of the training [s] (one thread: the tuner's evaluations and the refit)."""

    @property
    def mean_deg(self) -> float:
        """Mean of :attr:`rmse_deg` over the start temperatures [deg]."""
        return float(np.nanmean(self.rmse_deg))


@document_fields
@dataclass(frozen=True)
class MethodResult:
    """One method's compensator and its scores on the test runs (the median tuner seed)."""

    compensator: DriftCompensator
    northfind: tuple[Any, ...]
    """NorthFindResult of each compensated test run."""
    drift: DriftRow
    """Drift residual statistics."""
    seeds: tuple[SeedResult, ...] = ()
    """Every training of the method, by seed (one for an untuned method or a grid)."""
    predicted_drift_dph: tuple[np.ndarray, ...] = ()
    """The drift it predicted for each test run, the one the table scored [deg/h]."""

    @property
    def seed_means_deg(self) -> tuple[float, ...]:
        """Mean start-up RMSE of each seed [deg] (empty when trained once)."""
        return tuple(r.mean_deg for r in self.seeds) if len(self.seeds) > 1 else ()


@document_fields
@dataclass(frozen=True)
class CompensationStudy:
    """Everything the study computed."""

    settings: CompensationSettings
    test: Any
    """The :class:`~nfs.studies.scenario_runs.ScenarioResult` of the test start-ups."""
    train_runs: tuple[Any, ...]
    """The training runs (measurements)."""
    dataset: DriftDataset
    """The training data."""
    results: dict[str, MethodResult] = field(default_factory=dict)
    """Method name -> result, in table order."""
    uncompensated_drift: DriftRow | None = None
    """STD of the separated start-up drift of the test runs."""
    test_separations: tuple[Any, ...] = ()
    """The wavelet separation of each test run (:func:`nfs.denoise.separate_drift`), the
    target every row is scored against: kept for the report, which draws it."""

    def startup_errors(self, method: str) -> list[list[np.ndarray]]:
        """Start-up heading errors [deg] of ``method``'s compensated test runs (a stage row
        of :func:`~nfs.studies.scenario_runs.stage_names`, ``before``, ``stable``, ...: that stage,
        uncompensated), by start temperature, one array per run."""
        stages = stage_names(self.test.scenario)
        if method in stages:
            return errors_by_temperature(self.test, stage=stages.index(method))
        return errors_by_temperature(self.test, self.results[method].northfind)

    def heading_table(self, *, n_boot: int | None = None):
        """The heading-RMSE table: before, every method, stable, floor, with 95 % intervals
        and the paired comparisons (every row against ``before``, SSA-SVR and the best row
        against every other), Holm-adjusted together; ``n_boot`` replicates (default
        :data:`~nfs.scoring.intervals.DEFAULT_N_BOOT`), seeded by ``random_state``."""
        base = uncompensated_table(self.test)
        sc = self.test.scenario
        rows = []
        for name, res in self.results.items():
            errs = self.startup_errors(name)
            rows.append(TableRow(name, tuple(pooled_rmse(e) for e in errs),
                                 seed_means_deg=res.seed_means_deg,
                                 group=get_method(name).group))
        s = self.settings
        temps = (s.train_temperatures_c or sc.start_temperatures_c)
        mode = self.dataset.features_mode
        notes = (
            f"Features mode: {mode} ({FEATURE_MODE_NOTES[mode]}).",
            f"Compensated rows: trained on {len(self.train_runs)} other start-ups (seed "
            f"{s.train_seed}, T0 = {', '.join(f'{t:g}' for t in temps)} C), features "
            f"{', '.join(self.dataset.feature_names)}, drift by wavelet separation "
            f"(cutoff {s.cutoff_period_s:g} s), training samples every {s.decimate_s:g} s.",
        )
        if sc.units > 1:
            tr, te = sc.unit_split(s.train_units, s.test_units)
            notes += (f"Units: trained on {', '.join(map(str, tr))}, tested on "
                      f"{', '.join(map(str, te))} of {sc.units} ("
                      + ("different units" if not set(tr) & set(te) else "shared units")
                      + ").",)
        notes += self._method_notes()
        table = base.with_rows(rows, notes, features_mode=self.dataset.features_mode)
        names = list(self.results)
        pairs = [(m, "before") for m in names]
        best = table.best
        for ref in ("SSA-SVR", best):
            if ref in names:
                pairs += [(ref, m) for m in names if m != ref]
        stages = [r.method for r in base.rows if r.method in stage_names(sc)]
        errors = {n: self.startup_errors(n) for n in (*stages[:1], *names, *stages[1:])}
        variants = {n: [r.startup_errors_deg for r in res.seeds]
                    for n, res in self.results.items() if len(res.seeds) > 1}
        return table.with_intervals(errors, pairs=pairs, variants=variants,
                                    random_state=s.random_state,
                                    **({} if n_boot is None else {"n_boot": n_boot}))

    def _method_notes(self) -> tuple[str, ...]:
        """What the compensated rows rest on: samples, tuning, seeds, box bounds."""
        s = self.settings
        n_all = int(self.dataset.X.shape[0])
        notes = ["Intervals: 95 %, bias-corrected, from a two-level bootstrap over the test "
                 "start-ups and their cycles; vs best: tie = not distinguishable from the "
                 "best compensated row (paired bootstrap of the difference of means over the "
                 "same start-ups, a tuned row drawing one of its seeds per replicate; Holm)."]
        fewer = {n: r.compensator.settings.get("n_samples") for n, r in self.results.items()}
        fewer = {n: k for n, k in fewer.items() if k is not None and k < n_all}
        if fewer:
            notes.append(f"Training samples: {n_all} for every row but "
                         + ", ".join(f"{n} ({k})" for n, k in fewer.items())
                         + ": every k-th sample, the fit costing O(n^2)-O(n^3) per evaluation.")
        else:
            notes.append(f"Training samples: {n_all} for every row.")
        tuned = [n for n in self.results if get_method(n).tuned]
        if tuned:
            seeded = [n for n in tuned if len(self.results[n].seeds) > 1]
            notes.append(
                f"Tuned rows ({', '.join(tuned)}): {s.budget} evaluations each of the "
                "leave-one-start-temperature-out validation error (the residual's standard "
                "deviation within the held-out run)"
                + (f"; {', '.join(seeded)} tuned with {s.tuner_seeds} seeds each, the row is "
                   "the seed with the median mean, seeds (min-max) the spread of their means."
                   if seeded else "."))
            bound = []
            for n in tuned:
                res = self.results[n]
                hits: dict[str, int] = {}
                for r in res.seeds:
                    for b in r.on_bound:
                        hits[b] = hits.get(b, 0) + 1
                bound += [f"{n} {b} ({k}/{len(res.seeds)} seeds)" for b, k in hits.items()]
            if bound:
                notes.append("Tuned optimum on a bound of its box: " + ", ".join(bound)
                             + " (the validation error may fall further outside the box).")
        return tuple(notes)

    def drift_rows(self) -> list[DriftRow]:
        """Drift table rows: the uncompensated separated drift, then each method."""
        out = [self.uncompensated_drift] if self.uncompensated_drift else []
        return out + [r.drift for r in self.results.values()]

    def tuned_parameters(self) -> dict[str, dict[str, float]]:
        """Best hyperparameters found by each tuned method (the FOG start-up paper, Table 1)."""
        out = {}
        for name, res in self.results.items():
            est = res.compensator.estimator
            if hasattr(est, "best_params_"):
                out[name] = {k: float(v) for k, v in est.best_params_.items()}
        return out


def errors_by_temperature(result, northfind=None, *, stage: int = 0
                          ) -> list[list[np.ndarray]]:
    """Heading errors [deg] of one stage of every run of a scenario result, by start
    temperature, one array per run: the input of
    :meth:`~nfs.scoring.heading_table.HeadingTable.with_intervals`.

    Parameters
    ----------
    result : ScenarioResult
        The runs (:func:`~nfs.studies.scenario_runs.run_scenario`).
    northfind : sequence of NorthFindResult, optional
        North-finding of each run (default: the result's own, uncompensated).
    stage : int
        Index into :func:`~nfs.studies.scenario_runs.stage_names`: 0 the start-up stage; 1 the
        stable stage (with a chamber program that moves the chamber: the held stage, 2 the
        ramping one).
    """
    sc = result.scenario
    return [[run_stage_errors(result, k, northfind)[stage] for k in result.runs_at(i)]
            for i in range(len(sc.start_temperatures_c))]


def _pooled_within_std(parts) -> float:
    """sqrt(mean over runs of the variance about each run's own mean)."""
    parts = [p[np.isfinite(p)] for p in parts]
    ss = sum(float(np.sum((p - p.mean()) ** 2)) for p in parts if p.size)
    n = sum(p.size for p in parts)
    return float(np.sqrt(ss / n)) if n else float("nan")


def _test_drift(runs, cutoff_period_s: float, startup_end_s: float):
    """Each test run's separation, and its start-up, non-moving samples."""
    out = []
    for run in runs:
        sep = separate_drift(run, cutoff_period_s=cutoff_period_s)
        t = np.asarray(run.columns["time_s"])
        mask = (t < startup_end_s) & ~np.asarray(sep.moving, dtype=bool)
        out.append((sep, mask))
    return out


def test_scenario(scenario, settings: CompensationSettings | None = None):
    """The scenario's test start-ups: ``test_repeats`` per start temperature by each test unit.

    The one definition of the start-ups behind a table's uncompensated rows, whether or not
    the table also compensates (``nfs table --no-compensation`` tabulates the same start-ups
    as the full table's ``before`` row).
    """
    s = settings or scenario.compensation or CompensationSettings()
    _, test_units = scenario.unit_split(s.train_units, s.test_units)
    return scenario.made_by(test_units, s.test_repeats or scenario.repeats)


def train_scenario(scenario, settings: CompensationSettings | None = None):
    """The scenario's training start-ups: ``train_repeats`` per training temperature by each
    training unit, with the training seed.  NfsError when they would be the test start-ups."""
    s = settings or scenario.compensation or CompensationSettings()
    train_units, test_units = scenario.unit_split(s.train_units, s.test_units)
    train_sc = scenario.made_by(
        train_units, s.train_repeats, seed=s.train_seed, name=f"{scenario.name}_train",
        start_temperatures_c=tuple(s.train_temperatures_c or scenario.start_temperatures_c))
    if train_sc.seed == scenario.seed and set(train_units) & set(test_units) and \
            train_sc.start_temperatures_c == scenario.start_temperatures_c:
        raise NfsError("the training start-ups must differ from the test start-ups: "
                       "set compensation.train_seed different from the scenario's seed")
    return train_sc


def table_provenance(scenario, settings: CompensationSettings | None = None, *,
                     compensated: bool = True) -> dict:
    """The ``provenance`` of a heading table of ``scenario`` (as loaded, before the test
    start-ups are picked): versions, platform, scenario and instrument hashes, and every seed
    behind its numbers (:func:`~nfs.io.provenance.output_provenance`).

    ``test_start_ups`` is the seed of the test start-ups (two tables with the same one, and
    as many start-ups, are compared start-up by start-up: :mod:`nfs.scoring.baseline`).
    """
    s = settings or scenario.compensation or CompensationSettings()
    seeds = {"test_start_ups": scenario.seed}
    if compensated:
        seeds.update(training_start_ups=s.train_seed, models=s.random_state,
                     tuner_seeds=s.tuner_seeds, bootstrap=s.random_state)
    else:
        seeds["bootstrap"] = scenario.seed
    return output_provenance(scenario=scenario, seeds=seeds)


def run_study(scenario, settings: CompensationSettings | None = None, *,
              test=None, progress: Callable[[int, int, str], None] | None = None
              ) -> CompensationStudy:
    """Train every method of ``settings`` on training start-ups, apply to the test start-ups.

    ``test`` is the scenario's :class:`~nfs.studies.scenario_runs.ScenarioResult` if already
    computed.
    """
    s = settings or scenario.compensation or CompensationSettings()
    specs = [get_method(m) for m in s.methods]
    jobs = [(spec, seed) for spec in specs for seed in _seeds(spec, s)]
    tick = ticker(progress, 3 + len(jobs))

    train_sc = train_scenario(scenario, s)
    if test is None:
        scenario = test_scenario(scenario, s)       # checked before any training starts
    # costliest trainings first, so that the workers finish together
    order = sorted(range(len(jobs)), key=lambda j: -jobs[j][0].cost)
    done: dict[int, SeedResult] = {}
    fitted: dict[int, tuple] = {}
    with training_pool(s.n_jobs, len(jobs)) as parallel:
        ready = parallel.start()          # the workers import while the training set is made
        tick("simulating the training start-ups")
        train_runs = tuple(r.run for r in simulate_runs(train_sc.instrument,
                                                        train_sc.conditions()))
        data = drift_dataset(train_runs, list(s.features), decimate_s=s.decimate_s,
                             cutoff_period_s=s.cutoff_period_s,
                             features_mode=check_features_mode(s.features_mode))
        for _ in ready:
            pass
        # on several workers the trainings start now, and the test start-ups are simulated,
        # separated and featured meanwhile (with one, each training when its turn comes)
        trained = parallel(delayed(train_method)(j, jobs[j][0], data, s, jobs[j][1])
                           for j in order)
        if test is None:
            tick("simulating the test start-ups")
            test = run_scenario(scenario)
        else:
            tick(None)
        test_runs = [sim.run for sim in test.simulations]
        drifts = _test_drift(test_runs, s.cutoff_period_s, scenario.northfind.startup_end_s)
        # the features of every test run, once for every method (they share features, mode)
        plans = [prediction_plan(r, data.feature_names, features_mode=data.features_mode,
                                 rate_window_s=data.rate_window_s,
                                 stride_s=min(10.0, s.decimate_s)) for r in test_runs]
        study = CompensationStudy(
            settings=s, test=test, train_runs=train_runs, dataset=data,
            uncompensated_drift=DriftRow("denoised (no compensation)", float("nan"),
                                         _pooled_within_std([np.asarray(d.drift_dph)[m]
                                                             for d, m in drifts])),
            test_separations=tuple(d for d, _ in drifts))
        for j, comp in trained:
            spec, seed = jobs[j]
            tick(f"trained {spec.name}" + (f" (seed {seed})" if spec.seeded else ""))
            preds = [comp.predict_drift(plan=p) for p in plans]
            nf = northfind_runs([comp.compensate(r, drift_dph=p)
                                 for r, p in zip(test_runs, preds)], scenario.northfind)
            errs = errors_by_temperature(test, nf)
            rmse = tuple(pooled_rmse(e) for e in errs)
            params, bound = _tuned(comp.estimator)
            done[j] = SeedResult(seed, rmse, params, bound,
                                 tuple(tuple(e) for e in errs), comp.fit_time_s)
            fitted[j] = (comp, nf, preds)
    tick("intervals")
    for spec in specs:
        idx = [j for j in range(len(jobs)) if jobs[j][0] is spec]
        ranked = sorted(idx, key=lambda j: (done[j].mean_deg, done[j].seed))
        pick = ranked[len(ranked) // 2]                 # the median seed (upper for even)
        comp, nf, preds = fitted[pick]
        parts = [(np.asarray(d.drift_dph) - p)[m] for (d, m), p in zip(drifts, preds)]
        res = np.concatenate(parts)
        res = res[np.isfinite(res)]
        study.results[spec.name] = MethodResult(
            compensator=comp, northfind=tuple(nf),
            drift=DriftRow(spec.name, float(np.mean(np.abs(res))), _pooled_within_std(parts)),
            seeds=tuple(done[j] for j in idx),
            predicted_drift_dph=tuple(np.asarray(p, dtype=float) for p in preds))
    tick("done")
    return study


def _quiet(fn, *args, **kwargs):
    """``fn(*args, **kwargs)`` as a training runs in :func:`training_pool`: on one BLAS
    thread, with the capped iterations' ConvergenceWarning ignored (RVR's evidence sweeps,
    BP's epochs: part of the recipes).  Set where the training runs: in a worker process of
    its own, or in this process's one thread when ``n_jobs`` is 1."""
    with threadpool_limits(limits=1), warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return fn(*args, **kwargs)


class _Trainings:
    """The pool of :func:`training_pool`: called like :class:`joblib.Parallel` on
    ``delayed`` calls, each run through :func:`_quiet`."""

    def __init__(self, parallel: Parallel):
        self._parallel = parallel
        self._results = None

    def __call__(self, calls):
        self._results = self._parallel((_quiet, (fn, *args), kwargs)
                                       for fn, args, kwargs in calls)
        return self._results

    def start(self):
        """Start every worker now: one empty job each, whose unpickling imports this module
        (the package, NumPy, SciPy, scikit-learn: about 1.3 s) while this process goes on
        (the default study about 1 s sooner: 0.2-1.6 s in three runs, each beside one
        without it).  The jobs' results (None) must be consumed before the next call."""
        self._results = self._parallel(delayed(_ready)()
                                       for _ in range(effective_n_jobs(self._parallel.n_jobs)))
        return self._results

    def close(self) -> None:
        """Cancel the jobs whose results were left unread (an error or an interrupt in the
        study), without joblib's warning that it cancelled them."""
        if self._results is not None:
            close_unread(self._results)


def _ready() -> None:
    """The empty job of :meth:`_Trainings.start`."""


@contextmanager
def training_pool(n_jobs: int | None, trainings: int | None = None):
    """The pool the ``trainings`` of a study run in (results as they finish): joblib's loky
    worker processes, ``n_jobs`` of them (-1: one per core) but no more than there are
    trainings (each worker holds about 0.3 GB), or this process when that is one.  Each
    training runs on one BLAS thread with the capped iterations' ConvergenceWarning
    ignored (:func:`_quiet`); this process's own work meanwhile (the test start-ups,
    predictions, north-finding) on one BLAS thread too.

    Processes, not threads: an RVR's evidence sweeps are many NumPy calls on matrices of a
    few hundred rows, and hold the interpreter lock for much of their time, so two
    trainings in threads of one process wait for each other (two HHO-RVR trainings of the
    default table: 3.4 s each alone on one thread, 7.7 and 8.4 s side by side in two
    threads, 4.3 and 4.8 s in two processes; the whole study 26.6 s in threads, 23.7 s in
    processes, the same table).  A worker starts once per process (joblib keeps the loky
    executor) and imports the package on its first training; the training set and the
    fitted estimators are small to pickle.  One BLAS thread: the trainings' matrices are
    small, and a BLAS thread pool beside the workers (or in the one thread of ``n_jobs=1``)
    spins more than it computes (``nfs table seed003_ramp_calibration --n-jobs 1``: 155 s
    with it, 54 s without, the same table)."""
    workers = effective_n_jobs(n_jobs)
    if trainings is not None:
        workers = max(1, min(workers, trainings))
    with threadpool_limits(limits=1), Parallel(n_jobs=workers, backend="loky",
                                               return_as="generator_unordered") as parallel:
        pool = _Trainings(parallel)
        try:
            yield pool
        finally:
            pool.close()


def ticker(progress: Callable[[int, int, str], None] | None, n_steps: int):
    """``tick(msg)``: calls ``progress(step, n_steps, msg)`` and counts the step (a step
    skipped with ``tick(None)`` is counted without a call)."""
    step = 0

    def tick(msg: str | None) -> None:
        nonlocal step
        if progress is not None and msg is not None:
            progress(step, n_steps, msg)
        step += 1
    return tick


def _seeds(spec: MethodSpec, s: CompensationSettings) -> list[int]:
    """The random_state of each training of ``spec``: ``tuner_seeds`` of them for a tuner
    that draws (not the grid), one otherwise."""
    n = s.tuner_seeds if spec.seeded else 1
    return [s.random_state + k for k in range(n)]


def train_method(j: int, spec: MethodSpec, data: DriftDataset, s: CompensationSettings,
                 seed: int):
    """Train ``spec`` (the method itself: a worker may not have it registered) with ``seed``
    on one worker, its tuner's evaluations serial: (j, compensator), ``j`` passed through to
    tell the jobs apart.  Run in :func:`training_pool` (the capped iterations' warning
    ignored)."""
    return j, train_compensator(spec, data, budget=s.budget, random_state=seed, n_jobs=1)


def train_and_predict(j: int, spec: MethodSpec, data: DriftDataset, s: CompensationSettings,
                      seed: int, plans: list[PredictionPlan]):
    """:func:`train_method`, then the drift of every test run predicted from its plan:
    (j, compensator, predictions)."""
    _, comp = train_method(j, spec, data, s, seed)
    return j, comp, [comp.predict_drift(plan=p) for p in plans]


def _tuned(estimator) -> tuple[dict, tuple[str, ...]]:
    """A search's best parameters and those within 1 % of a bound of its box."""
    space = getattr(estimator, "param_space", None)
    best = getattr(estimator, "best_params_", None)
    if not space or best is None:
        return {}, ()
    params = {k: float(v) for k, v in best.items()}
    bound = []
    for name, dim in space.items():
        u = dim.to_unit(params[name])
        if u <= -0.98:
            bound.append(f"{name} low ({dim.low:g})")
        elif u >= 0.98:
            bound.append(f"{name} high ({dim.high:g})")
    return params, tuple(bound)
