"""A sweep's size before it runs: its missing cells, their runs, time and disk
(:mod:`nfs.studies.job_estimate`; ``nfs sweep`` refuses a sweep past its limits without
``--yes``).

The cells still missing from the store are counted without writing anything; their runs
and samples are the base scenario's (an axis over ``duration_s``, ``sample_rate_hz`` or
``start_temperatures_c`` changes them: the estimate then says the base's); the time per
sample is calibrated on the base scenario, simulated and north-found, and shared among the
workers; the disk is the cells' records (a few numbers per north-finding cycle).
"""

from __future__ import annotations

from pathlib import Path

from ..studies.job_estimate import JobEstimate, calibrate, run_samples
from .definition import SweepSpec
from .keys import cell_tasks, scenario_digest
from .store import CellStore

__all__ = ["RECORD_BYTES_PER_CYCLE", "RECORD_BYTES_PER_RUN", "missing_cells",
           "sweep_samples", "estimate_sweep"]

#: Bytes of a cell record per north-finding cycle of a run (its end time and heading
#: error, about 20 characters each in JSON) and per run besides (name, stages, drift
#: statistics) [B].
RECORD_BYTES_PER_CYCLE = 45.0
RECORD_BYTES_PER_RUN = 700.0


def missing_cells(spec: SweepSpec, output: str | Path) -> int:
    """Cells of ``spec`` not stored in ``output`` yet (nothing written)."""
    store = CellStore(output)
    return sum(not store.has(t.key) for t in cell_tasks(spec, scenario_digest(spec)))


def sweep_samples(spec: SweepSpec, n_cells: int) -> int:
    """Samples ``n_cells`` cells simulate, as the base scenario's runs."""
    return n_cells * sum(run_samples(spec.scenario.conditions()))


def estimate_sweep(spec: SweepSpec, n_cells: int, workers: int = 1) -> JobEstimate:
    """The estimate of ``n_cells`` cells of ``spec`` on ``workers`` processes (module
    docstring)."""
    sc = spec.scenario
    conds = sc.conditions()
    cal = calibrate(sc, northfind=True, conditions=conds)
    runs = n_cells * len(conds)
    samples = sweep_samples(spec, n_cells)
    cycles = sum(c.duration_s // sc.schedule.cycle_s for c in conds)
    disk = n_cells * (cycles * RECORD_BYTES_PER_CYCLE + len(conds) * RECORD_BYTES_PER_RUN)
    how = (f"{n_cells} cells of the base scenario's {len(conds)} run(s); time from "
           f"{cal.samples} samples simulated and north-found here, "
           f"{1e6 * (cal.simulate_s + cal.northfind_s):.3g} us per sample, on "
           f"{workers} worker(s)"
           + ("; a compensation method's training comes on top" if spec.method else ""))
    return JobEstimate(command="nfs sweep", runs=runs, samples=samples,
                       seconds=samples * (cal.simulate_s + cal.northfind_s) / max(workers, 1),
                       disk_bytes=disk, memory_bytes=0.0, how=how)
