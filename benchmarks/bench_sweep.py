"""Speed and memory of ``nfs sweep`` on many start-ups.

Run as ``python benchmarks/bench_sweep.py`` (``--cells N`` for a quicker run; ``--no-dask``
to leave the Dask cluster out).  The sweep: the default instrument and scenario, one start-up
per cell (2.5 h at 1 Hz, 4 positions, 150 s dwells), start temperatures -32, 17, 54 and
-5 C on an axis and N/4 seeds, each cell simulated and north-found (no compensation).

Figures, all in this process's machine and load:

- baseline: every cell's start-up simulated alone (:func:`nfs.experiment.simulate_run`,
  the single-run thermal march) and north-found, in a loop in this process (no executor, no
  store): the work of a sweep without stacking;
- the cell function (:func:`nfs.sweep.run_cell`) in a loop: a cell alone (what a resumed
  sweep's stray cell costs: the stacked march with one run);
- the same cells in batches of ``BATCH_CELLS`` of one point (:func:`nfs.sweep.run_cells`),
  their start-ups' thermal states stacked (one march over the samples for the whole batch):
  the speed-up of stacking;
- cells per second through :func:`nfs.sweep.run_sweep` with 1 local worker (in process) and
  2 local workers (joblib's loky processes, started by a 4-cell sweep before the timing, as
  a sweep of thousands of cells amortises their start): the speed-up of 2 workers (target
  >= 1.7x on 2 cores);
- cells per second on a 2-worker Dask LocalCluster (cluster start-up timed apart);
- the executor's overhead per cell: (sweep time with 1 worker - the batched loop) / cells
  (the store, the hashing, the table and its bookkeeping);
- peak memory (max RSS) of a sweep of 100 and of N cells, each in a fresh process with
  1 worker: flat when the two are close;
- the arithmetic floor: the floating-point operations of the thermal march of one start-up
  (per sample, the n-node state times the step matrix, 2 n^2, and the drive of the chamber
  and the n node powers through the input matrix, 2 n (n + 1), plus the update, n) at this
  machine's throughput of a plain NumPy matrix product (two 512 x 512 operands, best of 5):
  start-ups per second the arithmetic alone would allow, beside those measured, and the
  goal of 10,000 start-ups in 30 s on 2 cores.

Each sweep writes into a fresh temporary folder, so every cell is computed.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

from nfs.experiment import simulate_run
from nfs.studies.scenario_runs import northfind_runs
from nfs.config.scenario import load_scenario
from nfs.sweep import (BATCH_CELLS, LocalExecutor, cell_batches, cell_tasks, run_cell, run_cells,
                       run_sweep, sweep_from_dict)

T0 = ([-32.0], [17.0], [54.0], [-5.0])


def spec_for(cells: int):
    """A sweep of ``cells`` single start-ups (rounded down to a multiple of 4, at least 4)."""
    per = max(1, cells // len(T0))
    return sweep_from_dict({"scenario": "default", "seeds": {"first": 0, "count": per},
                            "axes": {"start_temperatures_c": [list(t) for t in T0]}})


def timed_sweep(spec, executor) -> float:
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        res = run_sweep(spec, d, executor=executor, quiet=True, figures=False)
        dt = time.perf_counter() - t0
    assert res.n_computed == spec.n_cells
    return dt


def baseline(spec) -> float:
    t0 = time.perf_counter()
    for task in cell_tasks(spec):
        sc = load_scenario(task.scenario_path, dict(task.scenario_values))
        sc = dataclasses.replace(sc, seed=task.seed)
        northfind_runs([simulate_run(sc.instrument, c).run for c in sc.conditions()],
                       sc.northfind)
    return time.perf_counter() - t0


def cells_alone(spec) -> float:
    t0 = time.perf_counter()
    for task in cell_tasks(spec):
        run_cell(task)
    return time.perf_counter() - t0


def batched(spec) -> float:
    t0 = time.perf_counter()
    for batch in cell_batches(cell_tasks(spec)):
        run_cells(batch)
    return time.perf_counter() - t0


def peak_memory_mb(cells: int) -> float:
    """Max RSS [MB] of a fresh process running a sweep of ``cells`` cells with 1 worker."""
    out = subprocess.run([sys.executable, __file__, "--memory-child", str(cells)],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])["max_rss_mb"]


def memory_child(cells: int) -> None:
    spec = spec_for(cells)
    timed_sweep(spec, LocalExecutor(1))
    rss_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(json.dumps({"cells": spec.n_cells, "max_rss_mb": rss_kb / 1024.0}))


def matmul_flops_per_s(size: int = 512, repeats: int = 5) -> float:
    """Throughput of a plain NumPy matrix product on this machine [flop/s] (best of
    ``repeats``; 2 size^3 operations each)."""
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((size, size)), rng.standard_normal((size, size))
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        a @ b
        best = min(best, time.perf_counter() - t0)
    return 2.0 * size ** 3 / best


def march_flops(n_nodes: int, n_samples: int) -> float:
    """Operations of the thermal march of one start-up (module docstring)."""
    n = n_nodes
    return n_samples * (2.0 * n * n + 2.0 * n * (n + 1) + n)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=1000, help="start-ups (cells) to sweep")
    ap.add_argument("--no-dask", action="store_true", help="leave the Dask cluster out")
    ap.add_argument("--memory-child", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.memory_child is not None:
        memory_child(args.memory_child)
        return
    spec = spec_for(args.cells)
    n = spec.n_cells
    print(f"{n} cells: one default start-up each (2.5 h at 1 Hz), simulated and north-found")
    t_base = baseline(spec)
    print(f"baseline (each start-up simulated alone and north-found, in a loop): "
          f"{t_base:.1f} s, "
          f"{n / t_base:.1f} cells/s")
    t_alone = cells_alone(spec)
    print(f"cell function alone, in a loop: {t_alone:.1f} s, {n / t_alone:.1f} cells/s")
    t_stack = batched(spec)
    print(f"stacked, batches of {BATCH_CELLS} cells of one point (this process): "
          f"{t_stack:.1f} s, {n / t_stack:.1f} cells/s; {t_base / t_stack:.2f}x the baseline")
    t1 = timed_sweep(spec, LocalExecutor(1))
    print(f"nfs sweep, 1 worker:  {t1:.1f} s, {n / t1:.1f} cells/s; executor overhead "
          f"{1e3 * (t1 - t_stack) / n:.1f} ms per cell")
    t_warm = timed_sweep(spec_for(4), LocalExecutor(2))  # start joblib's 2 worker processes
    t2 = timed_sweep(spec, LocalExecutor(2))
    print(f"nfs sweep, 2 workers: {t2:.1f} s, {n / t2:.1f} cells/s (workers started apart: a "
          f"4-cell sweep first, {t_warm:.1f} s); speed-up {t1 / t2:.2f}x over 1 worker "
          f"(target >= 1.7x on 2 cores)")
    sc = load_scenario()
    n_nodes = len(sc.instrument.network.node_names)
    n_samples = int(round(sc.run_duration_s(sc.start_temperatures_c[0]) * sc.sample_rate_hz))
    rate = matmul_flops_per_s()
    floor = rate / march_flops(n_nodes, n_samples)
    print(f"arithmetic floor: {march_flops(n_nodes, n_samples) / 1e6:.1f} Mflop per start-up "
          f"(march of {n_nodes} nodes x {n_samples} samples) at {rate / 1e9:.1f} Gflop/s "
          f"(NumPy matrix product, one process): {floor:.0f} start-ups/s per core; measured "
          f"{n / t2:.1f} start-ups/s on 2 workers = {n / t2 / (2 * floor):.2%} of the floor "
          f"of 2 cores; 10,000 start-ups would take {1e4 * t2 / n:.0f} s (goal <= 30 s)")
    if not args.no_dask:
        try:
            from nfs.sweep import DaskExecutor
            t0 = time.perf_counter()
            ex = DaskExecutor(workers=2)
            t_start = time.perf_counter() - t0
        except Exception as exc:  # the optional extra missing: say so, keep the rest
            print(f"Dask LocalCluster: not run ({exc})")
        else:
            try:
                td = timed_sweep(spec, ex)
            finally:
                ex.close()
            print(f"Dask LocalCluster, 2 workers: {td:.1f} s, {n / td:.1f} cells/s "
                  f"(cluster start {t_start:.1f} s apart); {t1 / td:.2f}x over 1 local worker")
    small = peak_memory_mb(100)
    big = peak_memory_mb(n)
    print(f"peak memory (max RSS, 1 worker): {small:.0f} MB at 100 cells, {big:.0f} MB at "
          f"{n} cells ({big / small:.2f}x)")


if __name__ == "__main__":
    main()
