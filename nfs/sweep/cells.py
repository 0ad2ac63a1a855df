"""Cells of a sweep: one point x one seed, its hash, and the computation a worker does.

A cell's key is the SHA-256 of its inputs written canonically: the base scenario and its
instrument as loaded (every field of the frozen dataclasses, floats by their exact repr,
effect functions by their qualified name; the file path left out, so a moved file keeps its
cells), the point's axis values, the seed, the compensation method and the code version
``nfs.__version__``.  Equal inputs give the same key on every machine and in every process,
so a rerun finds the cells it already has.

The worker (:func:`run_cell`) loads the base scenario with the point's scenario keys, sets
the point's instrument parameters, simulates and north-finds every run of the cell
(:func:`~nfs.studies.scenario_runs.run_scenario`), or, with a method, trains and applies that
compensator as ``nfs table`` does (:func:`~nfs.studies.startup_study.run_study`), and returns a
small record: per run, the cycle times and heading errors of each method, the stage RMSE,
the white-noise floor and the drift statistics.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import PurePath
from typing import Any, Iterator

import numpy as np
from threadpoolctl import threadpool_limits

import nfs

from ..studies.startup_study import run_study
from ..compensate.settings import CompensationSettings
from ..errors import NfsError
from ..experiment import iter_simulate_runs
from ..studies.scenario_runs import ScenarioResult, floor_deg, northfind_runs, run_scenario
from ..io.provenance import sha256_of_text
from ..config.scenario import load_scenario
from ..northfind import heading_rmse
from ..parameters import set_params
from .definition import SweepSpec

__all__ = ["CellTask", "canonical", "digest", "scenario_digest", "cell_key", "cell_tasks",
           "run_cell", "run_cells", "cell_batches", "BATCH_CELLS", "STAGES", "STORE_FORMAT"]

#: Version of the stored cell record (part of every key: a new format recomputes).
STORE_FORMAT = 1
#: Cells of one point computed in one task, at most (:func:`run_cells`): enough to stack
#: their start-ups' thermal solves, few enough that a killed sweep loses little.
BATCH_CELLS = 256
#: The stages of a run, as in the heading-RMSE table: the start-up stage (cycles ending
#: within ``northfind.startup_end_s``) and the stable stage (cycles starting after
#: ``northfind.stable_start_s``).
STAGES = ("startup", "stable")


def canonical(obj: Any) -> Any:
    """``obj`` as plain JSON data that says everything about its value and nothing else.

    Dataclasses become {"__type__": qualified name, field: value, ...} (a ``path`` field
    is left out: where a file lies is not what it holds), mappings have sorted keys,
    floats are written by ``repr`` (exact), arrays by dtype, shape and the hash of their
    bytes, functions by module and qualified name.
    """
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        out = {"__type__": f"{type(obj).__module__}.{type(obj).__qualname__}"}
        for f in dataclasses.fields(obj):
            if f.name != "path":
                out[f.name] = canonical(getattr(obj, f.name))
        return out
    if isinstance(obj, dict):
        return {str(k): canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, (list, tuple)):
        return [canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return {"__array__": str(obj.dtype), "shape": list(obj.shape),
                "sha256": hashlib.sha256(np.ascontiguousarray(obj).tobytes()).hexdigest()}
    if isinstance(obj, np.generic):
        return canonical(obj.item())
    if isinstance(obj, bool) or obj is None or isinstance(obj, (int, str)):
        return obj
    if isinstance(obj, float):
        return repr(obj)
    if isinstance(obj, enum.Enum):
        return f"{type(obj).__qualname__}.{obj.name}"
    if isinstance(obj, PurePath):
        return str(obj)
    if callable(obj):
        return f"{getattr(obj, '__module__', '?')}.{getattr(obj, '__qualname__', repr(obj))}"
    raise TypeError(f"cannot hash a {type(obj).__name__} canonically")


def digest(obj: Any) -> str:
    """SHA-256 (hex) of :func:`canonical` ``(obj)``."""
    return sha256_of_text(json.dumps(canonical(obj), sort_keys=True, separators=(",", ":")))


def scenario_digest(spec: SweepSpec) -> str:
    """Digest of the base scenario and its instrument as loaded."""
    return digest(spec.scenario)


@dataclass(frozen=True)
class CellTask:
    """What a worker needs to compute one cell (small and picklable)."""

    index: int
    """Position of the cell in the sweep (its row order)."""
    key: str
    """The cell's hash (:func:`cell_key`)."""
    scenario_path: str | None
    """Base scenario file (None: the built-in default)."""
    scenario_values: tuple[tuple[str, Any], ...]
    """The point's scenario keys and values."""
    instrument_values: tuple[tuple[str, float], ...]
    """The point's instrument parameters and values."""
    seed: int
    """The scenario's seed in this cell."""
    method: str | None
    """Compensation method key, or None."""

    @property
    def values(self) -> dict[str, Any]:
        """Every axis value of the point, {key: value}."""
        return dict(self.scenario_values + self.instrument_values)


def cell_key(base_digest: str, values: dict[str, Any], seed: int, method: str | None) -> str:
    """The hash a cell's record is stored under (module docstring)."""
    return digest({"scenario": base_digest, "axes": values, "seed": seed, "method": method,
                   "version": nfs.__version__, "format": STORE_FORMAT})


def cell_tasks(spec: SweepSpec, base_digest: str | None = None) -> Iterator[CellTask]:
    """Every cell of ``spec`` in row order (point-major, then seed), generated lazily."""
    base_digest = base_digest or scenario_digest(spec)
    targets = {a.key: a.target for a in spec.axes}
    path = None if spec.scenario_path is None else str(spec.scenario_path)
    index = 0
    for point in spec.points():
        sc_vals = tuple((k, v) for k, v in point.items() if targets[k] == "scenario")
        inst_vals = tuple((k, float(v)) for k, v in point.items() if targets[k] == "instrument")
        for seed in spec.seeds:
            yield CellTask(index, cell_key(base_digest, point, seed, spec.method), path,
                           sc_vals, inst_vals, seed, spec.method)
            index += 1


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


def _point_scenario(task: CellTask):
    """The base scenario with the task's point applied (its seed not yet)."""
    sc = load_scenario(task.scenario_path, dict(task.scenario_values))
    if task.instrument_values:
        sc = dataclasses.replace(sc, instrument=set_params(sc.instrument,
                                                           dict(task.instrument_values)))
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
        sims = iter_simulate_runs(base.instrument, [c for cs in conds for c in cs])
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
