"""The compensation study behind ``nfs table``: train every method, apply, score.

Protocol (seed 004, done on equal terms):

1. Training start-ups: the scenario's instrument at its start temperatures (by default all
   seven), simulated with a different seed from the test start-ups, so no test noise is seen
   in training.  The drift target is wavelet-separated; inputs are named thermometer features.
2. Each method is fitted on the stacked, decimated training data.  Tuned methods search their
   hyperparameters with the same budget of evaluations of the same leave-one-run-out (one
   start temperature out) validation error.
3. Test start-ups (the scenario's own runs, the ``before`` row): predict the drift from each
   run's thermometers, subtract it from the gyro output, north-find, score the start-up RMSE by
   start temperature.  The drift table scores the predicted drift against the separated drift
   of the test runs over the start-up stage (seed 004, Table 2).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from sklearn.exceptions import ConvergenceWarning

from ..denoise import separate_drift
from ..errors import NfsError
from .compensator import DriftCompensator, train_compensator
from .dataset import DriftDataset, drift_dataset
from .methods import TABLE_METHODS, get_method
from .modes import DEFAULT_FEATURE_MODE, FEATURE_MODE_NOTES, check_features_mode

__all__ = ["CompensationSettings", "MethodResult", "CompensationStudy", "run_study",
           "DriftRow"]


@dataclass(frozen=True)
class CompensationSettings:
    """How the compensators are trained and compared (``[compensation]`` of a scenario)."""

    methods: tuple[str, ...] = TABLE_METHODS
    """Method keys, in table order."""
    features: tuple[str, ...] = ("seed004",)
    """Input features (names, sets or patterns) of every method."""
    features_mode: str = DEFAULT_FEATURE_MODE
    """What a feature at t may use, in training and test alike (:mod:`nfs.compensate.modes`):
    ``cycle`` (up to the end of t's north-finding cycle), ``causal`` (up to t) or
    ``offline`` (the whole run: no instrument can compute it)."""
    budget: int = 40
    """Evaluations of the validation error per tuned method (the same for all)."""
    decimate_s: float = 30.0
    """Training samples are kept every ``decimate_s`` [s]."""
    cutoff_period_s: float = 512.0
    """Wavelet cutoff of the drift separation [s] (level 8 at 1 Hz)."""
    train_seed: int = 1
    """Seed of the training start-ups (the test start-ups use the scenario's seed)."""
    train_repeats: int = 1
    """Training start-ups per temperature."""
    train_temperatures_c: tuple[float, ...] | None = None
    """Start temperatures of the training start-ups (None: the scenario's)."""
    random_state: int = 0
    """Seed of every stochastic model and tuner (the first tuner seed)."""
    tuner_seeds: int = 3
    """Seeds of each stochastic tuner (``random_state``, ``random_state + 1``, ...): a tuned
    row is the seed whose mean is the median, and the table gives the spread over seeds."""
    n_jobs: int | None = -1
    """Parallel evaluations of a tuner's population (joblib; -1: every core)."""
    test_repeats: int | None = 5
    """Test start-ups per temperature (None: the scenario's ``repeats``).  The start-up and
    stable RMSE of a single run rest on 5 cycles each (+-30 %); five runs pool 25 (+-14 %)."""
    train_units: tuple[int, ...] | None = None
    """Units that make the training start-ups, ``train_repeats`` per temperature each (None:
    :meth:`~nfs.io.scenario.Scenario.unit_split`: every unit not tested, or unit 0)."""
    test_units: tuple[int, ...] | None = None
    """Units that make the test start-ups, ``test_repeats`` per temperature each (None: the
    last unit)."""


@dataclass(frozen=True)
class DriftRow:
    """Drift residual over the start-up stage of the test runs (seed 004, Table 2)."""

    method: str
    mae_dph: float
    """Mean absolute residual [deg/h] (NaN for the uncompensated row)."""
    std_dph: float
    """Standard deviation of the residual within each run, pooled over the runs [deg/h]:
    a constant offset over a run cancels in north finding, its variation does not."""


@dataclass(frozen=True)
class MethodResult:
    """One method's compensator and its scores on the test runs."""

    compensator: DriftCompensator
    northfind: tuple[Any, ...]
    """NorthFindResult of each compensated test run."""
    drift: DriftRow
    """Drift residual statistics."""


@dataclass(frozen=True)
class CompensationStudy:
    """Everything the study computed."""

    settings: CompensationSettings
    test: Any
    """The :class:`~nfs.experiment.ScenarioResult` of the test start-ups."""
    train_runs: tuple[Any, ...]
    """The training runs (measurements)."""
    dataset: DriftDataset
    """The training data."""
    results: dict[str, MethodResult] = field(default_factory=dict)
    """Method name -> result, in table order."""
    uncompensated_drift: DriftRow | None = None
    """STD of the separated start-up drift of the test runs."""

    def heading_table(self):
        """The heading-RMSE table: before, every method, stable, floor."""
        from ..experiment import stage_errors, uncompensated_table
        from ..report import TableRow, pooled_rmse
        base = uncompensated_table(self.test)
        sc = self.test.scenario
        rows = []
        for name, res in self.results.items():
            vals = []
            for i in range(len(sc.start_temperatures_c)):
                errs = [stage_errors(res.northfind[k], sc.northfind)[0]
                        for k in self.test.runs_at(i)]
                vals.append(pooled_rmse(errs))
            rows.append(TableRow(name, tuple(vals)))
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
        tuned = [get_method(m).name for m in s.methods if get_method(m).tuned]
        if tuned:
            notes += (f"Tuned rows ({', '.join(tuned)}): {s.budget} evaluations each of the "
                      "leave-one-start-temperature-out validation error (the residual's "
                      "standard deviation within the held-out run).",)
        return base.with_rows(rows, notes, features_mode=self.dataset.features_mode)

    def drift_rows(self) -> list[DriftRow]:
        """Drift table rows: the uncompensated separated drift, then each method."""
        out = [self.uncompensated_drift] if self.uncompensated_drift else []
        return out + [r.drift for r in self.results.values()]

    def tuned_parameters(self) -> dict[str, dict[str, float]]:
        """Best hyperparameters found by each tuned method (seed 004, Table 1)."""
        out = {}
        for name, res in self.results.items():
            est = res.compensator.estimator
            if hasattr(est, "best_params_"):
                out[name] = {k: float(v) for k, v in est.best_params_.items()}
        return out


def _pooled_within_std(parts) -> float:
    """sqrt(mean over runs of the variance about each run's own mean)."""
    parts = [p[np.isfinite(p)] for p in parts]
    ss = sum(float(np.sum((p - p.mean()) ** 2)) for p in parts if p.size)
    n = sum(p.size for p in parts)
    return float(np.sqrt(ss / n)) if n else float("nan")


def _test_drift(runs, cutoff_period_s: float, startup_end_s: float):
    """Separated drift of each test run on its start-up, non-moving samples."""
    out = []
    for run in runs:
        sep = separate_drift(run, cutoff_period_s=cutoff_period_s)
        t = np.asarray(run.columns["time_s"])
        mask = (t < startup_end_s) & ~np.asarray(sep.moving, dtype=bool)
        out.append((np.asarray(sep.drift_dph), mask))
    return out


def run_study(scenario, settings: CompensationSettings | None = None, *,
              test=None, progress: Callable[[int, int, str], None] | None = None
              ) -> CompensationStudy:
    """Train every method of ``settings`` on training start-ups, apply to the test start-ups.

    ``test`` is the scenario's :class:`~nfs.experiment.ScenarioResult` if already computed.
    """
    from ..experiment import northfind_runs, run_scenario, simulate_run
    s = settings or scenario.compensation or CompensationSettings()
    specs = [get_method(m) for m in s.methods]
    n_steps = 2 + len(specs)
    step = 0

    def tick(msg):
        nonlocal step
        if progress is not None:
            progress(step, n_steps, msg)
        step += 1

    train_units, test_units = scenario.unit_split(s.train_units, s.test_units)
    if test is None:
        scenario = scenario.made_by(test_units, s.test_repeats or scenario.repeats)
        tick("simulating the test start-ups")
        test = run_scenario(scenario)
    else:
        step += 1
    tick("simulating the training start-ups")
    train_sc = scenario.made_by(
        train_units, s.train_repeats, seed=s.train_seed, name=f"{scenario.name}_train",
        start_temperatures_c=tuple(s.train_temperatures_c or scenario.start_temperatures_c))
    if train_sc.seed == scenario.seed and set(train_units) & set(test_units) and \
            train_sc.start_temperatures_c == scenario.start_temperatures_c:
        raise NfsError("the training start-ups must differ from the test start-ups: "
                       "set compensation.train_seed different from the scenario's seed")
    train_runs = tuple(simulate_run(train_sc.instrument, c).run for c in train_sc.conditions())
    data = drift_dataset(train_runs, list(s.features), decimate_s=s.decimate_s,
                         cutoff_period_s=s.cutoff_period_s,
                         features_mode=check_features_mode(s.features_mode))
    test_runs = [sim.run for sim in test.simulations]
    drifts = _test_drift(test_runs, s.cutoff_period_s, scenario.northfind.startup_end_s)
    study = CompensationStudy(
        settings=s, test=test, train_runs=train_runs, dataset=data,
        uncompensated_drift=DriftRow("denoised (no compensation)", float("nan"),
                                     _pooled_within_std([d[m] for d, m in drifts])))
    for spec in specs:
        tick(f"training {spec.name}")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)   # stated in the notes
            comp = train_compensator(spec.key, data, budget=s.budget,
                                     random_state=s.random_state, n_jobs=s.n_jobs)
        preds = [comp.predict_drift(r) for r in test_runs]
        compensated = [comp.compensate(r, drift_dph=p) for r, p in zip(test_runs, preds)]
        nf = northfind_runs(compensated, scenario.northfind)
        parts = [(d - p)[m] for (d, m), p in zip(drifts, preds)]
        res = np.concatenate(parts)
        res = res[np.isfinite(res)]
        study.results[spec.name] = MethodResult(
            compensator=comp, northfind=tuple(nf),
            drift=DriftRow(spec.name, float(np.mean(np.abs(res))), _pooled_within_std(parts)))
    tick("done")
    return study
