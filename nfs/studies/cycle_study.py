"""Train on a chamber program's first cycle, test on the others: the drift table of a
temperature-cycling experiment (and the same table over whole runs: :func:`run_runs_study`).

Protocol (Tao, Li, Zheng, Wu and Fu, "High Precision Compensation for a Total Reflection
Prism Laser Gyro Bias in Consideration of High Frequency Oscillator Voltage", Sensors 19(13),
2986, 2019, section 4.1: "the entire cycle was performed twice, once for training and once for
compensation"):

1. The scenario's runs are simulated once; each is cut at the cycles of its chamber program
   (the iterations of the program's first top-level ``repeat``, :mod:`nfs.chamber`).
2. Every method is trained on cycle 1 of every run (drift by wavelet separation, the
   scenario's features and mode, training samples every ``decimate_s``) and predicts the
   drift of the later cycles from their own thermometers and channels.
3. The uncompensated row subtracts the mean bias of cycle 1 (of the training runs with
   :func:`run_runs_study`): a constant calibrated on the training data, the least any user
   applies.
4. Scores on the test cycles, trusted (not moving) samples, residual e = drift - prediction:

   - MAE, STD, RMSE [deg/h] of e on the wavelet-separated drift at every sample (the drift
     table of the start-up study; STD about the residual's mean);
   - bias stability [deg/h]: the sample standard deviation of the 100 s means of the
     compensated bias (gyro output - Earth rate - prediction, noise included): the paper's
     "TRPLG bias stability", its data being given "at intervals of 100 s" (section 4.1);
   - improvement [%] = 100 (1 - bias stability / the uncompensated row's) (Tables 2-5);
   - up-ramp and down-ramp residuals separately (RMSE and signed mean of e where the
     chamber program rises or falls faster than :data:`RAMP_RATE_C_PER_S`; the controller's
     cycling and wander of ``[variability]`` are no ramp): a model missing a rate term
     leaves residuals of opposite signs on the two (thermal hysteresis);
   - heading RMSE [deg] of every north-finding cycle of the test cycles, compensated.

5. Intervals: 95 %, bias-corrected percentile (:func:`nfs.scoring.intervals.bc_interval`) from a
   block bootstrap of the test cycles (Carlstein 1986, non-overlapping blocks of
   :data:`BLOCK_S`: the residual of a thermal model is correlated over tens of minutes, so
   blocks, not samples, are resampled), every row with the same draws (paired), so the
   improvement's interval carries the pairing with the uncompensated row.  Ramps are a few
   blocks long: their intervals are wide and say so.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from joblib import delayed

from ..denoise import earth_rate_projection_dph, separate_drift
from ..errors import NfsError
from ..experiment import simulate_runs
from .scenario_runs import northfind_runs
from ..run import Run
from ..scoring.intervals import MIN_REPLICATES, bc_interval, block_counts
from ..scoring.heading_table import pooled_rmse
from ..compensate.compensator import DriftCompensator, prediction_plan
from ..compensate.dataset import drift_dataset
from ..compensate.catalog import METHODS
from ..compensate import get_method
from ..compensate.modes import check_features_mode
from .startup_study import (test_scenario, ticker, train_and_predict, train_scenario,
                            training_pool)
from ..compensate.settings import CompensationSettings

__all__ = ["CycleRow", "CycleStudy", "PartTrace", "run_cycle_study", "run_runs_study",
           "cut_run", "CYCLE_METRICS", "BIAS_WINDOW_S", "BLOCK_S", "RAMP_RATE_C_PER_S",
           "UNCOMPENSATED"]

#: The table's metrics, in order (JSON keys).
CYCLE_METRICS = ("mae_dph", "std_dph", "rmse_dph", "bias_stability_dph", "improvement_pct")
#: Averaging window of the bias stability [s] (Tao et al. 2019, section 4.1).
BIAS_WINDOW_S = 100.0
#: Block of the bootstrap [s].
BLOCK_S = 1800.0
#: A chamber moving faster than this is ramping [K/s] (0.006 K/min).
RAMP_RATE_C_PER_S = 1e-4
#: Name of the uncompensated row.
UNCOMPENSATED = "uncompensated"
#: Ramp statistics of a row (JSON keys).
RAMP_KEYS = ("up_rmse_dph", "down_rmse_dph", "up_mean_dph", "down_mean_dph")


@dataclass(frozen=True)
class CycleRow:
    """One row of the drift table of a cycling study."""

    method: str
    """Row label (the method's name, or :data:`UNCOMPENSATED`)."""
    values: dict
    """Each of :data:`CYCLE_METRICS` and :data:`RAMP_KEYS` -> its value."""
    intervals: dict
    """The same keys -> (low, high) 95 % interval."""
    heading_rmse_deg: float
    """Heading RMSE of the test cycles' north-finding cycles [deg]."""
    msd_by_part: tuple = ()
    """Mean square deviation of the compensated bias (gyro - Earth rate - prediction) of
    each test part (cycle or run) at its trusted samples [(deg/h)^2]: Cheng et al.'s (2015)
    MSD, their Tables 2-4."""


@dataclass(frozen=True)
class PartTrace:
    """One test part (cycle or run) at its trusted samples: what the figures draw."""

    name: str
    """The part's name."""
    time_s: np.ndarray
    """Time from power-on [s]."""
    temp_fog_c: np.ndarray
    """The FOG thermometer [degC]."""
    drift_dph: np.ndarray
    """Wavelet-separated drift [deg/h]."""
    bias_dph: np.ndarray
    """Gyro output minus Earth rate, noise included [deg/h]."""
    ramp: np.ndarray
    """+1 where the chamber rises, -1 where it falls (faster than
    :data:`RAMP_RATE_C_PER_S`), 0 otherwise."""
    predicted_dph: dict
    """Row name -> its predicted drift [deg/h] (:data:`UNCOMPENSATED`: the constant)."""


@dataclass(frozen=True)
class CycleStudy:
    """Everything :func:`run_cycle_study` computed."""

    scenario: object
    """The scenario."""
    settings: object
    """Its :class:`~nfs.compensate.settings.CompensationSettings`."""
    spans_s: tuple[tuple[float, float], ...]
    """(start, end) of every cycle from power-on [s] (of the first start temperature)."""
    train_runs: tuple[Run, ...]
    """Cycle 1 of every run."""
    test_runs: tuple[Run, ...]
    """The later cycles of every run."""
    rows: tuple[CycleRow, ...]
    """The uncompensated row, then each method."""
    compensators: dict = field(default_factory=dict)
    """Method name -> its trained :class:`~nfs.compensate.compensator.DriftCompensator`."""
    n_boot: int = 0
    """Bootstrap replicates behind the intervals."""
    feature_names: tuple[str, ...] = ()
    """The features every method was trained on."""
    traces: tuple[PartTrace, ...] = ()
    """Every test part's drift, bias, thermometer and each row's prediction (the
    figures')."""

    def row(self, method: str) -> CycleRow:
        for r in self.rows:
            if r.method == method:
                return r
        raise KeyError(method)


def cut_run(run: Run, start_s: float, end_s: float, suffix: str) -> Run:
    """The samples of ``run`` with start_s <= time_s < end_s, named ``{name}_{suffix}``."""
    t = np.asarray(run.columns["time_s"], dtype=float)
    keep = (t >= start_s) & (t < end_s)
    if np.count_nonzero(keep) < 2:
        raise NfsError(f"run '{run.name}' has no samples in {start_s:g} .. {end_s:g} s")
    return Run(name=f"{run.name}_{suffix}",
               columns={k: np.asarray(v)[keep] for k, v in run.columns.items()}, meta=run.meta)


def _spans(scenario) -> list[list[tuple[float, float]]]:
    """The cycle spans of every start temperature's runs; NfsError without cycles."""
    prog = scenario.chamber.program
    if prog is None or len(prog.cycles) < 2:
        raise NfsError(f"scenario '{scenario.name}': compensation.protocol = \"cycles\" needs "
                       "a chamber program whose first top-level step is repeated at least "
                       "twice ({ repeat = 2, steps = [...] }): cycle 1 trains, the others test")
    sample_s = 1.0 / scenario.sample_rate_hz
    return [prog.cycle_spans_s(t0, sample_s) for t0 in scenario.start_temperatures_c]


@dataclass
class _Scored:
    """A test cycle's quantities shared by every row."""

    drift: np.ndarray       # separated drift at the trusted samples [deg/h]
    raw: np.ndarray         # gyro - Earth rate at the trusted samples [deg/h]
    window: np.ndarray      # 100 s window id of each trusted sample (unique over cycles)
    block: np.ndarray       # bootstrap block id of each trusted sample (unique over cycles)
    ramp: np.ndarray        # +1 up-ramp, -1 down-ramp, 0 otherwise, per trusted sample
    trusted: np.ndarray     # the mask into the cycle's samples


def _program_slope(scenario, start_temperature_c: float, t: np.ndarray) -> np.ndarray:
    """Rate of the scenario's chamber program at the times ``t`` from power-on [K/s] (0
    without a program): the ramps the program makes, not the controller's cycling or
    wander that the recorded ``temp_chamber_c`` also carries."""
    prog = scenario.chamber.program
    if prog is None or t.size < 2:
        return np.zeros(t.size)
    chamber = prog.ambient(start_temperature_c, 1.0 / scenario.sample_rate_hz)(t)
    return np.gradient(chamber, t)


def _score_parts(runs: list[Run], cutoff_period_s: float, scenario,
                 start_temperatures_c: list[float]) -> list[_Scored]:
    out, w0, b0 = [], 0, 0
    for run, t0 in zip(runs, start_temperatures_c):
        sep = separate_drift(run, cutoff_period_s=cutoff_period_s)
        t = np.asarray(run.columns["time_s"], dtype=float)
        ok = ~np.asarray(sep.moving, dtype=bool) & np.isfinite(sep.raw_drift_dph)
        rel = t - t[0]
        window = w0 + np.floor(rel / BIAS_WINDOW_S).astype(int)
        block = b0 + np.floor(rel / BLOCK_S).astype(int)
        w0, b0 = int(window.max()) + 1, int(block.max()) + 1
        slope = _program_slope(scenario, t0, t)
        ramp = np.zeros(t.size, dtype=int)
        ramp[slope > RAMP_RATE_C_PER_S] = 1
        ramp[slope < -RAMP_RATE_C_PER_S] = -1
        out.append(_Scored(np.asarray(sep.drift_dph)[ok], np.asarray(sep.raw_drift_dph)[ok],
                           window[ok], block[ok], ramp[ok], ok))
    return out


def _block_sums(parts: list[_Scored], preds: list[np.ndarray], n_blocks: int) -> np.ndarray:
    """Per block: sufficient statistics of one row's residuals, shape (n_blocks, 13)."""
    e = np.concatenate([p.drift - q[p.trusted] for p, q in zip(parts, preds)])
    bias = np.concatenate([p.raw - q[p.trusted] for p, q in zip(parts, preds)])
    window = np.concatenate([p.window for p in parts])
    block = np.concatenate([p.block for p in parts])
    ramp = np.concatenate([p.ramp for p in parts])
    n_w = int(window.max()) + 1
    w_mean = np.bincount(window, bias, n_w) / np.maximum(np.bincount(window, None, n_w), 1)
    w_has = np.bincount(window, None, n_w) > 0
    w_block = np.zeros(n_w, dtype=int)
    w_block[window] = block                      # a window lies in one block (100 | 1800)
    stats = np.zeros((n_blocks, 13))
    cols = [np.ones_like(e), e, e * e, np.abs(e)]
    for k, c in enumerate(cols):
        stats[:, k] = np.bincount(block, c, n_blocks)
    wb = w_block[w_has]
    for k, c in enumerate([np.ones(wb.size), w_mean[w_has], w_mean[w_has] ** 2]):
        stats[:, 4 + k] = np.bincount(wb, c, n_blocks)
    for k, sign in enumerate((1, -1)):
        on = ramp == sign
        for j, c in enumerate([np.ones(np.count_nonzero(on)), e[on], e[on] ** 2]):
            stats[:, 7 + 3 * k + j] = np.bincount(block[on], c, n_blocks)
    return stats


def _metrics(s: np.ndarray) -> dict[str, np.ndarray]:
    """Metrics from summed statistics, shape (..., 13) -> each (...)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        n, s1, s2, sa = s[..., 0], s[..., 1], s[..., 2], s[..., 3]
        nw, w1, w2 = s[..., 4], s[..., 5], s[..., 6]
        out = {"mae_dph": sa / n, "rmse_dph": np.sqrt(s2 / n),
               "std_dph": np.sqrt(np.maximum(s2 / n - (s1 / n) ** 2, 0.0)),
               "bias_stability_dph": np.sqrt(np.maximum(w2 - w1 * w1 / nw, 0.0) / (nw - 1))}
        for k, side in enumerate(("up", "down")):
            nr, r1, r2 = s[..., 7 + 3 * k], s[..., 8 + 3 * k], s[..., 9 + 3 * k]
            out[f"{side}_rmse_dph"] = np.sqrt(r2 / nr)
            out[f"{side}_mean_dph"] = r1 / nr
    return out


def _interval(reps: np.ndarray, est: float) -> tuple[float, float]:
    return bc_interval(reps, est, min_replicates=MIN_REPLICATES)


def run_cycle_study(scenario, settings=None, *, n_boot: int = 2000,
                    progress: Callable[[int, int, str], None] | None = None) -> CycleStudy:
    """Simulate ``scenario``, train every method of ``settings`` (default: the scenario's
    ``[compensation]``) on cycle 1 of its chamber program, and score it on the other cycles
    (module docstring).  ``n_boot`` bootstrap replicates, seeded by ``random_state``."""
    s = settings or scenario.compensation or CompensationSettings()
    spans = _spans(scenario)
    specs = _untuned(s, "a cycling study trains on one cycle")
    tick = ticker(progress, 4 + len(specs))
    tick("simulating the runs")
    sims = simulate_runs(scenario.instrument, scenario.conditions())
    train, test, t0s = [], [], []
    for k, sim in enumerate(sims):
        i_temp = k // scenario.repeats
        for c, (a, b) in enumerate(spans[i_temp]):
            part = cut_run(sim.run, a, b, f"cycle{c + 1}")
            (train if c == 0 else test).append(part)
            if c:
                t0s.append(scenario.start_temperatures_c[i_temp])
    return _drift_study(scenario, s, specs, train, test, n_boot, tick,
                        tuple(tuple(sp) for sp in spans[0]), t0s)


def run_runs_study(scenario, settings=None, *, n_boot: int = 2000,
                   progress: Callable[[int, int, str], None] | None = None) -> CycleStudy:
    """The drift table over whole runs: train every method on the scenario's training runs
    (:func:`~nfs.studies.startup_study.train_scenario`), score it on its test runs
    (:func:`~nfs.studies.startup_study.test_scenario`), as Cheng, Qi, Chen and Landry (Sensors
    15(5), 11189, 2015, section 4.2) model one gyro on its runs and test it on five more.
    The scores are those of :func:`run_cycle_study`, each test run taking the place of a
    test cycle; :attr:`CycleRow.msd_by_part` holds each test run's mean square deviation
    (their Table 2)."""
    s = settings or scenario.compensation or CompensationSettings()
    specs = _untuned(s, "a drift table of runs trains once")
    tick = ticker(progress, 4 + len(specs))
    tick("simulating the runs")
    train_sc = train_scenario(scenario, s)
    train = [r.run for r in simulate_runs(train_sc.instrument, train_sc.conditions())]
    test_sc = test_scenario(scenario, s)
    test = [r.run for r in simulate_runs(test_sc.instrument, test_sc.conditions())]
    t0s = [test_sc.start_temperatures_c[k // test_sc.repeats] for k in range(len(test))]
    return _drift_study(scenario, s, specs, train, test, n_boot, tick, (), t0s)


def _untuned(s, why: str):
    specs = [get_method(m) for m in s.methods]
    for spec in specs:
        if spec.tuned:
            untuned = ", ".join(k for k, m in METHODS.items() if not m.tuned)
            raise NfsError(f"method '{spec.key}' tunes its hyperparameters by leaving one "
                           f"start temperature or run out, and {why}: use an untuned method "
                           f"({untuned}) here")
    return specs


def _drift_study(scenario, s, specs, train, test, n_boot, tick, spans,
                 start_temperatures_c) -> CycleStudy:
    """Train on ``train``, score on the parts ``test`` (module docstring, steps 2-5), each
    run from its start temperature in ``start_temperatures_c``."""
    tick("separating the drift")
    mode = check_features_mode(s.features_mode)
    data = drift_dataset(train, list(s.features), decimate_s=s.decimate_s,
                         cutoff_period_s=s.cutoff_period_s, features_mode=mode)
    parts = _score_parts(test, s.cutoff_period_s, scenario, start_temperatures_c)
    n_blocks = int(max(p.block.max() for p in parts)) + 1
    # the constant calibration: the mean of gyro - Earth rate over the training runs at rest
    train_bias = np.concatenate([
        (np.asarray(r.columns["gyro_dph"], dtype=float) - earth_rate_projection_dph(r))[
            np.asarray(r.columns["moving"], dtype=float) == 0.0] for r in train])
    constant = float(np.nanmean(train_bias))

    plans = [prediction_plan(r, data.feature_names, features_mode=data.features_mode,
                             rate_window_s=data.rate_window_s,
                             stride_s=min(10.0, s.decimate_s)) for r in test]
    comps: dict[str, DriftCompensator] = {}
    preds = {UNCOMPENSATED: [np.full(r.n_samples, constant) for r in test]}
    order = sorted(specs, key=lambda sp: -sp.cost)
    with training_pool(s.n_jobs, len(order)) as parallel:
        for j, comp, pred in parallel(delayed(train_and_predict)(
                j, spec, data, s, s.random_state, plans) for j, spec in enumerate(order)):
            comps[order[j].name], preds[order[j].name] = comp, pred
            tick(f"trained {order[j].name}")
    tick("scoring")
    preds = {n: preds[n] for n in [UNCOMPENSATED] + [spec.name for spec in specs]}
    names = list(preds)
    stats = np.stack([_block_sums(parts, preds[n], n_blocks) for n in names])  # (rows, B, 13)
    rng = np.random.default_rng(s.random_state)
    counts = block_counts(n_blocks, n_boot, rng)             # (n_boot, blocks)
    est = _metrics(stats.sum(axis=1))
    reps = _metrics(np.einsum("rb,nbk->nrk", counts, stats))              # (rows, n_boot)
    est["improvement_pct"] = 100.0 * (1.0 - est["bias_stability_dph"]
                                      / est["bias_stability_dph"][0])
    reps["improvement_pct"] = 100.0 * (1.0 - reps["bias_stability_dph"]
                                       / reps["bias_stability_dph"][:1])
    rows = []
    for i, name in enumerate(names):
        pred_runs = test if name == UNCOMPENSATED else \
            [comps[name].compensate(r, drift_dph=p) for r, p in zip(test, preds[name])]
        nf = northfind_runs(pred_runs, scenario.northfind)
        heading = pooled_rmse(np.asarray(r.error_deg) for r in nf)
        keys = CYCLE_METRICS + RAMP_KEYS
        values = {k: float(est[k][i]) for k in keys}
        intervals = {k: _interval(reps[k][i], values[k]) for k in keys}
        if name == UNCOMPENSATED:
            values["improvement_pct"] = 0.0
            intervals["improvement_pct"] = (0.0, 0.0)
        msd = tuple(float(np.mean((p.raw - q[p.trusted]) ** 2))
                    for p, q in zip(parts, preds[name]))
        rows.append(CycleRow(name, values, intervals, heading, msd))
    traces = tuple(
        PartTrace(run.name, np.asarray(run.columns["time_s"], dtype=float)[p.trusted],
                  np.asarray(run.columns["temp_fog_c"], dtype=float)[p.trusted], p.drift,
                  p.raw, p.ramp, {n: np.asarray(preds[n][k])[p.trusted] for n in names})
        for k, (run, p) in enumerate(zip(test, parts)))
    tick("done")
    return CycleStudy(scenario=scenario, settings=s,
                      spans_s=spans, train_runs=tuple(train),
                      test_runs=tuple(test), rows=tuple(rows), compensators=comps,
                      n_boot=n_boot, feature_names=tuple(data.feature_names),
                      traces=traces)
