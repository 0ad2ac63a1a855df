"""The computation of a sweep's cells: what a worker does with a batch of cells.

A cell is one point x one seed (:mod:`nfs.sweep.keys`: its task, canonical inputs and hash,
re-exported here).  The worker (:func:`run_cell`) loads the base scenario with the point's
scenario keys, sets the point's instrument parameters, simulates and north-finds every run of
the cell (:func:`~nfs.studies.scenario_runs.run_scenario`), or, with a method, trains and
applies that compensator as ``nfs table`` does (:func:`~nfs.studies.startup_study.run_study`),
and returns a small record: per run, the cycle times and heading errors of each method, the
stage RMSE, the white-noise floor and the drift statistics.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Iterator

import numpy as np
from threadpoolctl import threadpool_limits

import nfs

from ..studies.startup_study import run_study
from ..compensate.settings import CompensationSettings
from ..errors import NfsError
from ..experiment import iter_simulate_runs
from ..studies.scenario_runs import ScenarioResult, floor_deg, northfind_runs, run_scenario
from ..config.scenario import load_scenario
from ..northfind import heading_rmse
from ..parameters import set_params
from .keys import (STAGES, STORE_FORMAT, CellTask, canonical, cell_key, cell_tasks, digest,
                   scenario_digest)

__all__ = ["CellTask", "canonical", "digest", "scenario_digest", "cell_key", "cell_tasks",
           "run_cell", "run_cells", "cell_batches", "BATCH_CELLS", "STAGES", "STORE_FORMAT"]

#: Cells of one point computed in one task, at most (:func:`run_cells`): enough to stack
#: their start-ups' thermal solves, few enough that a killed sweep loses little.
BATCH_CELLS = 256


def _stats(x: np.ndarray) -> dict[str, float]:
    """Mean, standard deviation and peak-to-peak of a drift over a stage [deg/h]."""
    x = x[np.isfinite(x)]
    if x.size == 0:
        return {"mean": math.nan, "std": math.nan, "ptp": math.nan}
    return {"mean": float(np.mean(x)), "std": float(np.std(x)), "ptp": float(np.ptp(x))}


def _floor(sc) -> float:
    try:
        return floor_deg(sc)
    except NfsError:                       # one position (or no pair): no closed-form floor
        return math.nan


def _cycles(nf, settings) -> dict[str, Any]:
    st = heading_rmse(nf, startup_end_s=settings.startup_end_s,
                      stable_start_s=settings.stable_start_s)
    return {"t_end_s": [float(v) for v in nf.t_end_s],
            "error_deg": [float(v) for v in nf.error_deg],
            "rmse_deg": {"startup": st.startup_deg, "stable": st.stable_deg},
            "n_cycles": {"startup": st.n_startup, "stable": st.n_stable}}


def run_cell(task: CellTask) -> dict[str, Any]:
    """Compute one cell; its record as plain JSON data (module docstring).

    The cell runs on one BLAS thread: a sweep's parallelism is across cells, the matrices
    of one start-up are small (threads there cost more than they give: 3x slower on a loaded
    2-core machine), and one thread gives the same bits in every process.
    """
    with threadpool_limits(limits=1):
        return _compute(task)


#: The scenario of the last point this process loaded, with its (base scenario digest,
#: point): a worker's consecutive batches of one point (a sweep of many seeds) read and check
#: the files once, not once per batch (70 ms of a 256-cell batch's 2 s).  Scenarios are
#: frozen, so the batches share it.  Kept by hand rather than by functools.lru_cache: a
#: point's values may be lists (a sweep over ``start_temperatures_c``), which do not hash,
#: so the key is compared by equality.
_LAST_POINT: list = [None]


def _point_scenario(task: CellTask):
    """The base scenario with the task's point applied (its seed not yet)."""
    key = (task.base_digest, _point(task)) if task.base_digest else None
    last = _LAST_POINT[0]
    if key is not None and last is not None and last[0] == key:
        return last[1]
    sc = load_scenario(task.scenario_path, dict(task.scenario_values))
    if task.instrument_values:
        sc = dataclasses.replace(sc, instrument=set_params(sc.instrument,
                                                           dict(task.instrument_values)))
    if key is not None:
        _LAST_POINT[0] = (key, sc)
    return sc


def _point(task: CellTask) -> tuple:
    """Cells with equal points (and no method) can be simulated together."""
    return (task.scenario_path, task.scenario_values, task.instrument_values, task.method)


def cell_batches(tasks, size: int | None = None) -> Iterator[list[CellTask]]:
    """Consecutive tasks of one point without a compensation method, ``size`` at most
    (default :data:`BATCH_CELLS`), as lists; a task with a method is a batch of its own."""
    size = BATCH_CELLS if size is None else size
    batch: list[CellTask] = []
    for task in tasks:
        if batch and (task.method is not None or _point(task) != _point(batch[0])
                      or len(batch) >= size):
            yield batch
            batch = []
        batch.append(task)
        if task.method is not None:
            yield batch
            batch = []
    if batch:
        yield batch


def run_cells(tasks: list[CellTask]) -> list[dict[str, Any]]:
    """Compute a batch of cells (:func:`cell_batches`); their records, in order.

    The cells of one point share the instrument: every start-up of the batch is simulated
    with its thermal state stacked beside the others (:func:`~nfs.experiment.iter_simulate_runs`),
    whose arithmetic gives each run the same bits whatever is stacked beside it, so a cell's
    record does not depend on its batch; the runs stream through (simulated, north-found,
    reduced to the cell's record), so a batch holds a bounded number of runs.  A cell with a compensation method is computed
    alone (:func:`run_cell`).
    """
    tasks = list(tasks)
    if tasks[0].method is not None or any(_point(t) != _point(tasks[0]) for t in tasks):
        return [run_cell(t) for t in tasks]
    with threadpool_limits(limits=1):
        base = _point_scenario(tasks[0])
        scenarios = [dataclasses.replace(base, seed=t.seed) for t in tasks]
        conds = [sc.conditions() for sc in scenarios]
        # the record reads the gyro, the accelerometers and the drift: no thermometer,
        # chamber or aux column is made (each sensor has its own stream: no other bit moves)
        sims = iter_simulate_runs(base.instrument, [c for cs in conds for c in cs],
                                  channels=())
        records = []
        for task, sc, cs in zip(tasks, scenarios, conds):
            # a cell's runs, north-found and reduced to its record before the next cell's
            # are finished: a batch holds one chunk of marched states, not every run
            mine = tuple(next(sims) for _ in cs)
            nf = northfind_runs([s.run for s in mine], sc.northfind)
            records.append(_record(task, ScenarioResult(sc, mine, tuple(nf)), None))
        return records


def _compute(task: CellTask) -> dict[str, Any]:
    sc = dataclasses.replace(_point_scenario(task), seed=task.seed)
    compensated = None
    if task.method is None:
        res = run_scenario(sc)
    else:
        base = sc.compensation or CompensationSettings()
        settings = dataclasses.replace(base, methods=(task.method,), tuner_seeds=1,
                                       test_repeats=None, n_jobs=1)
        study = run_study(sc, settings)
        res = study.test
        compensated = next(iter(study.results.values())).northfind
    return _record(task, res, compensated)


def _record(task: CellTask, res, compensated) -> dict[str, Any]:
    """A cell's record from its simulated and north-found runs (and compensated ones)."""
    nfset = res.scenario.northfind
    floor = _floor(res.scenario)
    runs = []
    for k, (sim, nf) in enumerate(zip(res.simulations, res.northfind)):
        t = np.asarray(sim.run.columns["time_s"])
        drift = np.asarray(sim.drift_dph)
        methods = {"none": _cycles(nf, nfset)}
        if compensated is not None:
            methods[task.method] = _cycles(compensated[k], nfset)
        runs.append({
            "name": sim.conditions.name,
            "start_temperature_c": float(sim.conditions.start_temperature_c),
            "unit": int(sim.conditions.unit),
            "floor_deg": floor,
            "drift_dph": {"startup": _stats(drift[t <= nfset.startup_end_s]),
                          "stable": _stats(drift[t >= nfset.stable_start_s])},
            "methods": methods,
        })
    return {"key": task.key, "format": STORE_FORMAT, "version": nfs.__version__,
            "axes": task.values, "seed": task.seed, "method": task.method, "runs": runs}
