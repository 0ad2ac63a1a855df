"""Speed and memory of ``nfs sweep`` on many start-ups.

Run as ``python benchmarks/bench_sweep.py`` (``--startups N`` for another size, 1000 by
default; ``--full`` adds the goal's sweep of 10,000 start-ups on 2 workers and its peak
memory, a few minutes; ``--no-dask`` leaves the Dask cluster out).  The sweep: the default
instrument (its coil wound: 14 nodes) and scenario, one start-up per cell (2.5 h at 1 Hz, 4
positions, 150 s dwells), start temperatures -32, 17, 54 and -5 C on an axis and N/4 seeds,
each cell simulated and north-found (no compensation).  Beside it, the same cells with the
coil of two lumped nodes (``instrument = "lumped"``, 7 nodes: the default instrument before
its coil was wound), measured in the same process: the wound coil's cost per start-up
(goal: at most 1.3x), and with ``--full`` both 10,000-start-up sweeps, in seconds and in
units of the reference workload.

Figures, all in this process's machine and load:

- baseline: start-ups simulated alone (:func:`nfs.experiment.simulate_run`, the march with
  one run) and north-found, in a loop in this process (no executor, no store), on the first
  ``--alone`` cells: the work of a sweep without stacking;
- the same cells in batches of 16 cells of one point, the batch of the sweep before the
  march was arithmetic over the runs (its thermal states stacked 16 at a time), and in
  batches of :data:`~nfs.sweep.BATCH_CELLS` (:func:`nfs.sweep.run_cells`, the runs streamed
  in chunks of :data:`~nfs.experiment.STACK_BYTES`): the speed-up of stacking;
- start-ups per second through :func:`nfs.sweep.run_sweep` with 1 local worker (in process)
  and 2 local workers (joblib's loky processes, started by a 4-cell sweep before the timing,
  as a sweep of thousands of cells amortises their start);
- the same on a 2-worker Dask LocalCluster (cluster start-up timed apart);
- the executor's overhead per cell: (sweep time with 1 worker - the batched loop) / cells;
- the arithmetic floor: the floating-point operations of the thermal march of one start-up
  (per sample, the n-node state times the step matrix, 2 n^2, and the drive of the chamber
  and the n node powers through the input matrix, 2 n (n + 1), plus the update, n) at this
  machine's throughput of a plain NumPy matrix product (two 512 x 512 operands, best of 5):
  start-ups per second the arithmetic alone would allow, beside those measured, and the
  goal of 10,000 start-ups in 30 s on 2 cores;
- peak memory (max RSS) of a sweep of N/10 and N cells (and 10,000 with ``--full``), each
  in a fresh process with 1 worker: flat when they are close (goal: 1,000 and 10,000 within
  1.2x);
- a fully stored sweep rerun: ``nfs sweep`` of a 4-cell sweep, every cell stored, as a
  command (the process start, the imports, the table and the figures), in seconds and in
  units of the reference workload ``../shared/tools/refwork.py`` timed beside it (goal
  <= 1 unit).

Each sweep writes into a fresh temporary folder, so every cell is computed.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from nfs.errors import NfsError
from nfs.experiment import STACK_BYTES, simulate_run
from nfs.studies.scenario_runs import northfind_runs
from nfs.config.scenario import load_scenario
from nfs.sweep import (BATCH_CELLS, DaskExecutor, LocalExecutor, cell_batches, cell_tasks,
                       run_cells, run_sweep, sweep_from_dict)

T0 = ([-32.0], [17.0], [54.0], [-5.0])
#: The reference workload of machine-normalised timings ("units").
REFWORK = Path(__file__).resolve().parents[2] / "shared" / "tools" / "refwork.py"


def spec_for(cells: int, instrument: str | None = None):
    """A sweep of ``cells`` single start-ups (rounded down to a multiple of 4, at least 4),
    of the default instrument or of the built-in preset ``instrument``."""
    per = max(1, cells // len(T0))
    axes = {"start_temperatures_c": [list(t) for t in T0]}
    if instrument is not None:
        axes["instrument"] = [instrument]
    return sweep_from_dict({"scenario": "default", "seeds": {"first": 0, "count": per},
                            "axes": axes})


def timed_sweep(spec, executor) -> float:
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        res = run_sweep(spec, d, executor=executor, quiet=True, figures=False)
        dt = time.perf_counter() - t0
    assert res.n_computed == spec.n_cells
    return dt


def baseline(spec, cells: int) -> float:
    """Seconds to simulate alone and north-find the first ``cells`` cells of ``spec``."""
    t0 = time.perf_counter()
    for task in itertools.islice(cell_tasks(spec), cells):
        sc = load_scenario(task.scenario_path, dict(task.scenario_values))
        sc = dataclasses.replace(sc, seed=task.seed)
        northfind_runs([simulate_run(sc.instrument, c).run for c in sc.conditions()],
                       sc.northfind)
    return time.perf_counter() - t0


def batched(spec, size: int) -> float:
    """Seconds to compute every cell of ``spec`` in batches of ``size`` (this process)."""
    t0 = time.perf_counter()
    with threadpool_limits(limits=1):
        for batch in cell_batches(cell_tasks(spec), size):
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


def refwork_s() -> float:
    """The reference workload's seconds on this machine (the faster of two runs)."""
    return min(float(subprocess.run([sys.executable, str(REFWORK)], check=True,
                                    capture_output=True, text=True).stdout.split()[-1])
               for _ in range(2))


def stored_rerun_s(cells: int = 4) -> float:
    """Wall seconds of ``nfs sweep`` rerun on a sweep whose every cell is stored (the
    faster of two reruns): the process, the imports, the table and the figures."""
    with tempfile.TemporaryDirectory() as d:
        sweep = Path(d) / "sweep.toml"
        sweep.write_text(f'scenario = "default"\n[seeds]\nfirst = 0\ncount = {cells}\n',
                         encoding="utf-8")
        cmd = [sys.executable, "-m", "nfs.cli", "sweep", str(sweep), "-o", str(Path(d) / "out"),
               "--jobs", "1", "-q"]
        subprocess.run(cmd, check=True, capture_output=True)
        best = math.inf
        for _ in range(2):
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            best = min(best, time.perf_counter() - t0)
    return best


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
    ap.add_argument("--startups", "--cells", type=int, default=1000, dest="startups",
                    help="start-ups (one per cell) to sweep")
    ap.add_argument("--alone", type=int, default=100,
                    help="cells of the baseline (each start-up simulated alone)")
    ap.add_argument("--full", action="store_true",
                    help="also 10,000 start-ups on 2 workers and their peak memory")
    ap.add_argument("--no-dask", action="store_true", help="leave the Dask cluster out")
    ap.add_argument("--memory-child", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.memory_child is not None:
        memory_child(args.memory_child)
        return
    spec = spec_for(args.startups)
    n = spec.n_cells
    print(f"{n} start-ups (one per cell): the default start-up (2.5 h at 1 Hz, 4 positions), "
          f"simulated and north-found; {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f} at the start")
    alone = min(n, args.alone)
    t_base = baseline(spec, alone)
    print(f"baseline, each start-up simulated alone and north-found ({alone} cells): "
          f"{alone / t_base:.1f} start-ups/s")
    t16 = batched(spec, 16)
    print(f"batches of 16 cells (the sweep's batch before), this process: {t16:.1f} s, "
          f"{n / t16:.1f} start-ups/s")
    t_stack = batched(spec, BATCH_CELLS)
    print(f"batches of {BATCH_CELLS} cells, streamed in chunks of "
          f"{STACK_BYTES / 2 ** 20:.0f} MiB of marched state, this process: {t_stack:.1f} s, "
          f"{n / t_stack:.1f} start-ups/s; {t16 / t_stack:.2f}x batches of 16, "
          f"{t_base / alone * n / t_stack:.2f}x the baseline")
    lumped = spec_for(args.startups, "lumped")
    cpu = {}
    for name, sp in (("wound", spec), ("lumped", lumped), ("wound", spec), ("lumped", lumped)):
        c0 = time.process_time()
        batched(sp, BATCH_CELLS)
        cpu[name] = min(cpu.get(name, math.inf), (time.process_time() - c0) / sp.n_cells)
    print(f"CPU per start-up, batches of {BATCH_CELLS} cells, this process (the faster of two): "
          f"the wound coil (default, 14 nodes) {1e3 * cpu['wound']:.2f} ms, the lumped coil "
          f"(7 nodes) {1e3 * cpu['lumped']:.2f} ms: {cpu['wound'] / cpu['lumped']:.2f}x "
          f"(goal <= 1.3x)")
    t1 = timed_sweep(spec, LocalExecutor(1))
    print(f"nfs sweep, 1 worker:  {t1:.1f} s, {n / t1:.1f} start-ups/s; executor overhead "
          f"{1e3 * (t1 - t_stack) / n:.2f} ms per cell")
    t_warm = timed_sweep(spec_for(4), LocalExecutor(2))  # start joblib's 2 worker processes
    t2 = timed_sweep(spec, LocalExecutor(2))
    print(f"nfs sweep, 2 workers: {t2:.1f} s, {n / t2:.1f} start-ups/s (workers started apart: "
          f"a 4-cell sweep first, {t_warm:.1f} s); speed-up {t1 / t2:.2f}x over 1 worker")
    sc = load_scenario()
    n_nodes = len(sc.instrument.network.node_names)
    n_samples = int(round(sc.run_duration_s(sc.start_temperatures_c[0]) * sc.sample_rate_hz))
    rate = matmul_flops_per_s()
    floor = rate / march_flops(n_nodes, n_samples)
    print(f"arithmetic floor: {march_flops(n_nodes, n_samples) / 1e6:.1f} Mflop per start-up "
          f"(march of {n_nodes} nodes x {n_samples} samples) at {rate / 1e9:.1f} Gflop/s "
          f"(NumPy matrix product, one process): {floor:.0f} start-ups/s per core; measured "
          f"{n / t2:.1f} start-ups/s on 2 workers = {n / t2 / (2 * floor):.2%} of the floor "
          f"of 2 cores; 10,000 start-ups would take {1e4 * t2 / n:.0f} s at this rate "
          f"(goal <= 30 s)")
    if args.full:
        unit_before = refwork_s()
        big = spec_for(10_000)
        t_big = timed_sweep(big, LocalExecutor(2))
        t_lumped = timed_sweep(spec_for(10_000, "lumped"), LocalExecutor(2))
        unit_full = min(unit_before, refwork_s())
        print(f"10,000 start-ups, nfs sweep on 2 workers: the wound coil {t_big:.1f} s = "
              f"{t_big / unit_full:.1f} units, {big.n_cells / t_big:.1f} start-ups/s (goal "
              f"<= 30 s: 23.1 units at the reference workload's 1.3 s); the lumped coil "
              f"{t_lumped:.1f} s = {t_lumped / unit_full:.1f} units; {t_big / t_lumped:.2f}x "
              f"(reference workload {unit_full:.2f} s here)")
    if not args.no_dask:
        try:
            ex = None
            t0 = time.perf_counter()
            ex = DaskExecutor(workers=2)
            t_start = time.perf_counter() - t0
        except NfsError as exc:  # the optional extra missing: say so, keep the rest
            print(f"Dask LocalCluster: not run ({exc})")
        else:
            try:
                td = timed_sweep(spec, ex)
            finally:
                ex.close()
            print(f"Dask LocalCluster, 2 workers: {td:.1f} s, {n / td:.1f} start-ups/s "
                  f"(cluster start {t_start:.1f} s apart); {t1 / td:.2f}x over 1 local worker")
    sizes = [max(4, n // 10), n] + ([10_000] if args.full and n != 10_000 else [])
    peaks = [peak_memory_mb(c) for c in sizes]
    print("peak memory (max RSS, 1 worker): " + ", ".join(
        f"{p:.0f} MB at {c} start-ups" for c, p in zip(sizes, peaks))
        + f" ({peaks[-1] / peaks[0]:.2f}x from the smallest to the largest; goal 1,000 and "
          f"10,000 within 1.2x)")
    unit = refwork_s()
    rerun = stored_rerun_s()
    print(f"stored rerun (nfs sweep of 4 cells, every cell stored, figures included, as a "
          f"command): {rerun:.2f} s = {rerun / unit:.2f} units (reference workload "
          f"{unit:.2f} s here; goal <= 1 unit)")


if __name__ == "__main__":
    main()
