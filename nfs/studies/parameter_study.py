"""Parameter-level ("system-level") compensation: the parameters each north-finding cycle
calibrates, modelled against temperature and predicted for later cycles.

Liang, Tao, Wang, Guo and Zhao, "System-Level Temperature Compensation Method for the RLG-IMU
Based on HHO-RVR", Journal of Sensors 2021, 6613574 (section 4.1): the unit calibrates itself
by rotation every ~40 min through a slow temperature ramp; each of its temperature-related
parameters is then modelled against temperature, by a cubic least-squares polynomial and by a
relevance vector regression whose kernel width Harris hawks tune by 5-fold cross-validation,
and the models are compared by RMSE, MAE, R^2 and the residual variance (section 4.2).  On our
north finder:

1. **Calibration.**  Every cycle of a rotating schedule (three distinct positions at least)
   gives, besides the heading (docs/physics.md section 5; :mod:`nfs.northfind.level`):

   - the gyro bias b_g = b + Omega_ie sin L b_x [deg/h] (the multiposition fit's b holds
     -Omega_ie sin L b_x of the x accelerometer's bias, removed here);
   - the gyro scale-factor error k = |n| / (Omega_ie cos L) - 1 [ppm], |n| the fitted
     horizontal Earth rate;
   - the accelerometer biases b_x, b_y [ug] from the dwell means of both accelerometers
     (:func:`~nfs.northfind.level.gravity_and_biases`);

   and the mean of each sensor's own thermometer over the cycle (the model's input, as in
   Liang et al.: one temperature per parameter).
2. **Models.**  Each parameter is fitted against its temperature on the training runs' cycles
   by every method of the scenario's ``[compensation] methods`` (LS is Liang et al.'s cubic;
   a tuned method validates by 5-fold cross-validation over the cycles, as Liang et al.), and
   by a constant (the training cycles' mean: a one-off calibration).
3. **Parameter table.**  On the test runs' cycles: RMSE, MAE, R^2 and the residual variance of
   the calibrated parameter minus its prediction (Liang et al., equations (32)-(34)).
4. **Headings.**  The biases a model predicts from a cycle's temperatures (known when the
   cycle ends, so the heading can be output then) are used by the known-bias solve
   (:mod:`nfs.northfind.known_bias`) on the test runs' cycles, with every dwell of the
   schedule, with two positions 90 deg apart (the first two of the schedule) and with one
   (the first): a rotating schedule cancels a bias error, the other two do not, and that is
   where a parameter model pays.  Beside them: the multiposition fit (``bias fitted``) and
   sample-level compensation by the same methods (the scenario's features; the gyro
   compensated sample by sample, the accelerometers by the constant).  One position needs
   the sign of psi + theta from a hint: the run's true heading serves, as a compass would.
5. **Intervals.**  95 %, bias-corrected percentile (:func:`nfs.scoring.intervals.bc_interval`),
   from a bootstrap of blocks of :data:`BLOCK_CYCLES` consecutive test cycles (neighbouring
   calibrations are correlated through the thermal state), every row with the same draws.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from joblib import delayed
from sklearn.model_selection import KFold

from ..constants import POSITION_TOL_DEG, earth_rate_components_dph
from ..errors import NfsError
from ..experiment import simulate_runs
from .scenario_runs import chamber_moves, northfind_runs
from ..run import Run
from ..northfind.known_bias import north_find_known_bias
from ..northfind.solve import distinct_angles
from ..scoring.intervals import MIN_REPLICATES, bc_interval, block_counts
from ..compensate.compensator import prediction_plan
from ..compensate.dataset import drift_dataset
from ..compensate.catalog import MethodSpec
from ..compensate import get_method
from ..compensate.modes import check_features_mode
from .startup_study import (test_scenario, ticker, train_and_predict, train_scenario,
                            training_pool)
from ..compensate.settings import CompensationSettings

__all__ = ["PARAMETERS", "PARAMETER_METRICS", "BLOCK_CYCLES", "CONSTANT", "BIAS_FITTED",
           "CycleParameters", "ParameterRow", "HeadingRow", "ParameterStudy",
           "calibrate_cycles", "run_parameter_study"]

#: parameter -> (description, unit, the thermometer column it is modelled against).
PARAMETERS = {
    "gyro_bias_dph": ("gyro bias", "deg/h", "temp_fog_c"),
    "gyro_scale_ppm": ("gyro scale-factor error", "ppm", "temp_fog_c"),
    "acc_x_bias_ug": ("x accelerometer bias", "ug", "temp_acc_x_c"),
    "acc_y_bias_ug": ("y accelerometer bias", "ug", "temp_acc_y_c"),
}
#: Metrics of the parameter table (Liang et al. 2021, section 4.2), in order.
PARAMETER_METRICS = ("rmse", "mae", "r2", "residual_variance")
#: Consecutive test cycles per bootstrap block.
BLOCK_CYCLES = 10
#: Row of the constant model (the training cycles' mean).
CONSTANT = "constant"
#: Heading row of the multiposition fit (the bias estimated in every cycle).
BIAS_FITTED = "bias fitted"


@dataclass(frozen=True)
class CycleParameters:
    """The parameters every cycle of one run calibrates (arrays over the cycles)."""

    run_name: str
    """The run."""
    t_end_s: np.ndarray
    """End of each cycle from power-on [s]."""
    temperature_c: dict
    """Thermometer column -> its mean over each cycle [C]."""
    values: dict
    """Parameter (:data:`PARAMETERS`) -> its value in each cycle, in the parameter's unit."""


@dataclass(frozen=True)
class ParameterRow:
    """One parameter modelled by one method, scored on the test cycles."""

    parameter: str
    """Key of :data:`PARAMETERS`."""
    method: str
    """Method name, or :data:`CONSTANT`."""
    values: dict
    """Each of :data:`PARAMETER_METRICS` -> its value (RMSE, MAE in the parameter's unit,
    residual variance in its square, R^2 dimensionless)."""
    intervals: dict
    """The same keys -> (low, high) 95 % interval."""


@dataclass(frozen=True)
class HeadingRow:
    """Heading RMSE of one way of knowing the biases, on one schedule."""

    schedule: str
    """``as run``, ``two positions`` or ``one position``."""
    positions_deg: tuple
    """The dwells used in each cycle [deg]."""
    method: str
    """:data:`BIAS_FITTED`, :data:`CONSTANT`, ``<method> (parameters)`` or ``<method>
    (samples)``."""
    rmse_deg: float
    """RMS heading error of every test cycle [deg]."""
    interval: tuple
    """Its 95 % interval [deg]."""
    startup_rmse_deg: float
    """RMS heading error of the test cycles ending within the start-up stage [deg]."""
    startup_interval: tuple
    """Its 95 % interval [deg]."""
    versus_best: str = ""
    """``best`` (lowest RMSE of its schedule), ``tie`` (the paired bootstrap difference to the
    best row holds 0 in its 95 % interval) or ``worse``."""


@dataclass(frozen=True)
class ParameterStudy:
    """Everything :func:`run_parameter_study` computed."""

    scenario: object
    """The scenario."""
    settings: object
    """Its :class:`~nfs.compensate.settings.CompensationSettings`."""
    train: tuple
    """:class:`CycleParameters` of every training run."""
    test: tuple
    """:class:`CycleParameters` of every test run."""
    parameters: tuple
    """:class:`ParameterRow` per parameter and model (constant first)."""
    headings: tuple
    """:class:`HeadingRow` per schedule and row."""
    models: dict = field(default_factory=dict)
    """(method name, parameter) -> the fitted estimator."""
    n_boot: int = 0
    """Bootstrap replicates behind the intervals."""
    described: dict = field(default_factory=lambda: dict(PARAMETERS))
    """Parameter -> (description, unit, thermometer column): :data:`PARAMETERS`."""
    block_cycles: int = BLOCK_CYCLES
    """Consecutive test cycles per bootstrap block."""
    predicted: dict = field(default_factory=dict)
    """(row name, parameter) -> the prediction for every test cycle, the test runs' cycles
    one after the other (:attr:`test`'s order), in the parameter's unit (the figures')."""
    startup_stage: str = "start-up"
    """Name of the start-up stage of the heading table: ``start-up``, or ``start-up, chamber
    ramping`` when the chamber program moves the chamber during a start-up cycle of a test run
    (:func:`~nfs.studies.scenario_runs.chamber_moves`)."""


def _schedule_angles(result) -> np.ndarray:
    return np.asarray(result.theta_deg, dtype=float)[0]


def calibrate_cycles(run: Run, result) -> CycleParameters:
    """The parameters of every cycle of ``result`` (a :func:`~nfs.northfind.north_find` of
    ``run`` on a schedule of three distinct positions or more; module docstring, step 1)."""
    theta = np.radians(np.asarray(result.theta_deg, dtype=float))
    if len(distinct_angles(theta[0], np.radians(POSITION_TOL_DEG))) < 3:
        raise NfsError(f"run '{run.name}': a cycle calibrates the biases and the scale factor "
                       "only on a rotating schedule of three distinct positions or more "
                       f"(this one: {', '.join(f'{v:g}' for v in _schedule_angles(result))} "
                       "deg)")
    bx, by = np.asarray(result.acc_bias_g, dtype=float).T   # fitted with the up vector
    omega_h, omega_v = earth_rate_components_dph(result.latitude_deg)
    values = {"gyro_bias_dph": np.asarray(result.bias_dph) + omega_v * bx,
              "gyro_scale_ppm": 1e6 * (np.asarray(result.horizontal_rate_dph) / omega_h - 1.0),
              "acc_x_bias_ug": 1e6 * bx, "acc_y_bias_ug": 1e6 * by}
    t = np.asarray(run.columns["time_s"], dtype=float)
    # each cycle's samples t_start <= t <= t_end as an index range (time is increasing):
    # found once, not a mask over the whole run per cycle and thermometer
    lo = np.searchsorted(t, [c.t_start_s for c in result.cycles], side="left")
    hi = np.searchsorted(t, [c.t_end_s for c in result.cycles], side="right")
    temps = {}
    for col in dict.fromkeys(th for _, _, th in PARAMETERS.values()):
        if col not in run.columns:
            raise NfsError(f"run '{run.name}' has no column '{col}': the parameter models "
                           "need each sensor's thermometer")
        v = np.asarray(run.columns[col], dtype=float)
        temps[col] = np.array([np.nanmean(v[a:b]) for a, b in zip(lo, hi)])
    return CycleParameters(run.name, np.asarray(result.t_end_s, dtype=float), temps, values)


def _stack(cals, parameter: str) -> tuple[np.ndarray, np.ndarray]:
    col = PARAMETERS[parameter][2]
    x = np.concatenate([c.temperature_c[col] for c in cals])[:, None]
    y = np.concatenate([c.values[parameter] for c in cals])
    return x, y


def _fit(spec: MethodSpec, parameter: str, x, y, budget: int, seed: int):
    """Fit ``spec``'s estimator of ``parameter`` against its thermometer (the method itself
    is sent to the worker, which may not have it registered)."""
    est = spec.build(budget=budget, random_state=seed, n_jobs=1)
    if spec.tuned:   # Liang et al. 2021, section 4.1: 5-fold cross-validation over the cycles
        est.set_params(cv=KFold(5, shuffle=True, random_state=seed))
    ok = np.isfinite(x[:, 0]) & np.isfinite(y)
    est.fit(x[ok], y[ok])        # in training_pool: the capped iterations' warning ignored
    return spec.name, parameter, est


def _blocks(cals) -> np.ndarray:
    """Bootstrap block of every test cycle (consecutive cycles of one run)."""
    out, b0 = [], 0
    for c in cals:
        ids = b0 + np.arange(len(c.t_end_s)) // BLOCK_CYCLES
        out.append(ids)
        b0 = int(ids.max()) + 1 if ids.size else b0
    return np.concatenate(out)


def _param_metrics(s: np.ndarray) -> dict:
    """Metrics from summed (n, sum e, sum e^2, sum |e|, sum y, sum y^2), shape (..., 6)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        n, e1, e2, ea, y1, y2 = (s[..., k] for k in range(6))
        mse = e2 / n
        return {"rmse": np.sqrt(mse), "mae": ea / n,
                "r2": 1.0 - e2 / (y2 - y1 * y1 / n),
                "residual_variance": mse - (e1 / n) ** 2}


def _interval(reps: np.ndarray, est: float) -> tuple[float, float]:
    return bc_interval(reps, est, min_replicates=MIN_REPLICATES)


def _block_sums(cols: list[np.ndarray], block: np.ndarray, n_blocks: int) -> np.ndarray:
    ok = np.all([np.isfinite(c) for c in cols], axis=0)
    return np.stack([np.bincount(block[ok], c[ok], n_blocks) for c in cols], axis=-1)


def _subsets(result) -> list[tuple[str, tuple[float, ...] | None]]:
    theta = _schedule_angles(result)
    first = float(theta[0])
    quarter = [float(v) for v in theta[1:] if abs(((v - first) % 360.0) - 90.0) < 0.5
               or abs(((v - first) % 360.0) - 270.0) < 0.5]
    out: list[tuple[str, tuple[float, ...] | None]] = [("as run", None)]
    if quarter:
        out.append(("two positions", (first, quarter[0])))
    out.append(("one position", (first,)))
    return out


def run_parameter_study(scenario, settings=None, *, n_boot: int = 2000,
                        progress: Callable[[int, int, str], None] | None = None
                        ) -> ParameterStudy:
    """Simulate the scenario's training and test runs, calibrate every cycle, model each
    parameter against temperature by every method of ``settings`` (default: the scenario's
    ``[compensation]``) and score the parameters and the headings on the test runs (module
    docstring)."""
    s = settings or scenario.compensation or CompensationSettings()
    specs = [get_method(m) for m in s.methods]
    tick = ticker(progress, 6 + len(specs))

    tick("simulating the training runs")
    train_sc, test_sc = train_scenario(scenario, s), test_scenario(scenario, s)
    train_runs = [r.run for r in simulate_runs(train_sc.instrument, train_sc.conditions())]
    tick("simulating the test runs")
    test_runs = [r.run for r in simulate_runs(test_sc.instrument, test_sc.conditions())]
    tick("calibrating every cycle")
    train_nf = northfind_runs(train_runs, scenario.northfind)
    test_nf = northfind_runs(test_runs, scenario.northfind)
    train = tuple(calibrate_cycles(r, nf) for r, nf in zip(train_runs, train_nf))
    test = tuple(calibrate_cycles(r, nf) for r, nf in zip(test_runs, test_nf))

    models: dict = {}
    jobs = [(spec, p) for spec in sorted(specs, key=lambda sp: -sp.cost) for p in PARAMETERS]
    with training_pool(s.n_jobs, len(jobs)) as parallel:
        for name, p, est in parallel(delayed(_fit)(spec, p, *_stack(train, p), s.budget,
                                                   s.random_state) for spec, p in jobs):
            models[(name, p)] = est
    tick("modelled every parameter")

    block = _blocks(test)
    n_blocks = int(block.max()) + 1
    rng = np.random.default_rng(s.random_state)
    counts = block_counts(n_blocks, n_boot, rng)
    rows: list[ParameterRow] = []
    predicted: dict = {}      # (row, parameter) -> per test run, per cycle
    split = np.cumsum([len(c.t_end_s) for c in test])[:-1]
    for p in PARAMETERS:
        y_tr = _stack(train, p)[1]
        x_te, y_te = _stack(test, p)
        const = float(np.nanmean(y_tr))
        preds = {CONSTANT: np.full(y_te.shape, const)}
        for spec in specs:
            preds[spec.name] = models[(spec.name, p)].predict(np.nan_to_num(x_te))
        for name, pred in preds.items():
            e = y_te - pred
            stats = _block_sums([np.ones_like(e), e, e * e, np.abs(e), y_te, y_te * y_te],
                                block, n_blocks)
            est = _param_metrics(stats.sum(axis=0))
            reps = _param_metrics(counts @ stats)
            rows.append(ParameterRow(p, name, {k: float(est[k]) for k in PARAMETER_METRICS},
                                     {k: _interval(reps[k], float(est[k]))
                                      for k in PARAMETER_METRICS}))
            predicted[(name, p)] = np.split(pred, split)

    tick("compensating the test runs sample by sample")
    mode = check_features_mode(s.features_mode)
    data = drift_dataset(train_runs, list(s.features), decimate_s=s.decimate_s,
                         cutoff_period_s=s.cutoff_period_s, features_mode=mode)
    plans = [prediction_plan(r, data.feature_names, features_mode=data.features_mode,
                             rate_window_s=data.rate_window_s,
                             stride_s=min(10.0, s.decimate_s)) for r in test_runs]
    sample_nf: dict = {}
    order = sorted(specs, key=lambda sp: -sp.cost)
    with training_pool(s.n_jobs, len(order)) as parallel:
        for j, comp, preds in parallel(delayed(train_and_predict)(
                j, spec.key, data, s, s.random_state, plans) for j, spec in enumerate(order)):
            runs = [comp.compensate(r, drift_dph=p) for r, p in zip(test_runs, preds)]
            sample_nf[order[j].name] = northfind_runs(runs, scenario.northfind)
            tick(f"compensated by {order[j].name} sample by sample")

    tick("north-finding with the biases known")
    headings = _heading_rows(scenario, test_nf, test, predicted, sample_nf, specs, block,
                             n_blocks, counts)
    tick("done")
    return ParameterStudy(scenario=scenario, settings=s, train=train, test=test,
                          parameters=tuple(rows), headings=tuple(headings), models=models,
                          n_boot=n_boot, startup_stage=_startup_stage(test_sc, test_nf),
                          predicted={k: np.concatenate(v) for k, v in predicted.items()})


def _startup_stage(test_sc, test_nf) -> str:
    """``start-up``, or ``start-up, chamber ramping`` when the program moves the chamber in a
    start-up cycle of a test run."""
    end = test_sc.northfind.startup_end_s
    for k, nf in enumerate(test_nf):
        t0 = test_sc.start_temperatures_c[k // test_sc.repeats]
        up = np.asarray(nf.t_end_s) <= end
        if np.any(chamber_moves(test_sc, t0, nf.t_start_s, nf.t_end_s)[up]):
            return "start-up, chamber ramping"
    return "start-up"


def _heading_rows(scenario, test_nf, test, predicted, sample_nf, specs, block, n_blocks,
                  counts) -> list[HeadingRow]:
    startup_end = scenario.northfind.startup_end_s
    up = np.concatenate([c.t_end_s <= startup_end for c in test])
    rows, reps_of = [], {}

    def biases(name, i):
        return {"gyro_bias_dph": predicted[(name, "gyro_bias_dph")][i],
                "scale_factor": 1e-6 * predicted[(name, "gyro_scale_ppm")][i],
                "acc_x_bias_g": 1e-6 * predicted[(name, "acc_x_bias_ug")][i],
                "acc_y_bias_g": 1e-6 * predicted[(name, "acc_y_bias_ug")][i]}

    def add(schedule, positions, method, errors):
        e = np.concatenate(errors)
        out = []
        for mask in (np.ones(e.shape, bool), up):
            e2 = np.where(mask, e * e, np.nan)
            stats = _block_sums([np.where(mask, 1.0, np.nan), e2], block, n_blocks)
            with np.errstate(invalid="ignore", divide="ignore"):
                est = float(np.sqrt(stats[:, 1].sum() / stats[:, 0].sum()))
                reps = np.sqrt((counts @ stats[:, 1]) / (counts @ stats[:, 0]))
            # one block or fewer holds the stage: no interval can be drawn
            enough = np.count_nonzero(stats[:, 0] > 0) >= 2
            out.append((est, _interval(reps, est) if enough else (np.nan, np.nan)))
            reps_of.setdefault(len(rows), []).append(reps)
        shown = tuple(float(v) for v in (positions if positions is not None
                                         else _schedule_angles(test_nf[0])))
        rows.append(HeadingRow(schedule, shown, method, out[0][0], out[0][1], out[1][0],
                               out[1][1]))

    for schedule, positions in _subsets(test_nf[0]):
        if positions is None:
            add(schedule, positions, BIAS_FITTED, [np.asarray(nf.error_deg) for nf in test_nf])

        def solve(nf, **kw):
            return north_find_known_bias(nf, positions_deg=positions,
                                         heading_hint_deg=nf.true_heading_deg, **kw).error_deg

        for name in [CONSTANT] + [sp.name for sp in specs]:
            label = name if name == CONSTANT else f"{name} (parameters)"
            add(schedule, positions, label,
                [solve(nf, **biases(name, i)) for i, nf in enumerate(test_nf)])
        const = biases(CONSTANT, 0)
        for spec in specs:
            add(schedule, positions, f"{spec.name} (samples)",
                [solve(nf, gyro_bias_dph=0.0, scale_factor=const["scale_factor"][0],
                       acc_x_bias_g=const["acc_x_bias_g"][0],
                       acc_y_bias_g=const["acc_y_bias_g"][0]) for nf in sample_nf[spec.name]])
    for schedule in dict.fromkeys(r.schedule for r in rows):
        idx = [i for i, r in enumerate(rows) if r.schedule == schedule]
        best = min(idx, key=lambda i: rows[i].rmse_deg)
        for i in idx:
            diff = reps_of[i][0] - reps_of[best][0]
            lo, hi = _interval(diff, rows[i].rmse_deg - rows[best].rmse_deg)
            verdict = "best" if i == best else ("worse" if lo > 0 else "tie")
            rows[i] = dataclasses.replace(rows[i], versus_best=verdict)
    return rows
