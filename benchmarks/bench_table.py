"""Where the time of ``nfs table`` goes, on the default scenario with every default (every
row, the default tuner seeds, the intervals and comparisons, every output file), in reference
units.

Printed, all measured in this process or its children:

1. the reference workload (``../shared/tools/refwork.py``: kernel-SVR fits, dense linear
   algebra, FFTs) timed before and after, the faster of each pair: "units" are seconds divided
   by its seconds on the same machine at the same load;
2. ``nfs table`` itself, run as a command: wall and CPU seconds (its workers included) and
   the figure in units beside the goal (:data:`GOAL_UNITS`);
3. the figures before the tuned trainings were made cheaper (:data:`BEFORE_DEFAULT`,
   stored: measured on the code before those changes) and before the RVR's sweeps used the
   kernel's low-rank factor (:data:`BEFORE_RVR_FACTOR_DEFAULT`), and the baseline, the uncompensated
   table (``nfs table --no-compensation``: the test start-ups simulated and north-found,
   intervals included), the part of the job that has nothing to train;
4. the breakdown, stage by stage, of the same work done in this process: simulation of the
   test and training start-ups, the wavelet separation of every run, the study (training
   start-ups, features, every training on the study's workers, predictions and north-finding
   of the compensated runs), each row's training (wall seconds of each of its trainings on one
   thread, summed over the tuner seeds), the intervals and paired comparisons, and the report
   with its figures.

Run as ``python benchmarks/bench_table.py`` (``--scenario FILE --n-jobs N`` for another
scenario or one worker: ``--scenario scenarios/seed003_ramp_calibration.toml --n-jobs 1``
times that command alone, its goal :data:`GOAL_ONE_WORKER_UNITS`).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import os
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from nfs.cli import main as nfs_main
from nfs.compensate.settings import CompensationSettings
from nfs.config.scenario import load_scenario
from nfs.denoise import separate_drift
from nfs.experiment import simulate_runs
from nfs.report.compensation import write_study
from nfs.studies.scenario_runs import run_scenario
from nfs.studies.startup_study import run_study, test_scenario, train_scenario

ROOT = Path(__file__).resolve().parents[1]
REFWORK = ROOT.parent / "shared" / "tools" / "refwork.py"
#: ``nfs table`` on the default scenario, every core [reference units].
GOAL_UNITS = 12.0
#: ``nfs table scenarios/seed003_ramp_calibration.toml --n-jobs 1`` [reference units].
GOAL_ONE_WORKER_UNITS = 10.0
#: The default table before its tuned trainings were made cheaper (SVR rows on every 2nd
#: training sample, RVR pruning at alpha 1e9, LIBSVM's predict, the eigen-decomposition for
#: a singular RVR posterior), measured by this script on the 2-core AMD EPYC, idle, the
#: reference workload 1.72 s: (wall [s], CPU [s], reference units).
BEFORE_DEFAULT = (49.6, 80.0, 28.7)
#: The default table before the RVR's sweeps worked on the kernel's low-rank factor (the code
#: of commit 543fc67), measured by this script on the same machine, idle: (wall [s], CPU [s],
#: reference units).
BEFORE_RVR_FACTOR_DEFAULT = (29.3, 47.0, 17.1)
#: The same for ``--scenario scenarios/seed003_ramp_calibration.toml --n-jobs 1``, idle:
#: (wall [s], reference units).
BEFORE_RVR_FACTOR_ONE_WORKER = (27.3, 15.3)


def refwork_s(n: int = 2) -> float:
    """The faster of ``n`` runs of the reference workload [s] (each in a fresh process, as
    ``python ../shared/tools/refwork.py`` prints it)."""
    out = [float(subprocess.run([sys.executable, str(REFWORK)], capture_output=True,
                                text=True, check=True).stdout.split()[-1]) for _ in range(n)]
    return min(out)


def command_s(args: list[str]) -> tuple[float, float]:
    """Wall and CPU seconds (user + system, its children included) of ``nfs ARGS`` run as a
    command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "nfs.cli", *args], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def breakdown(scenario_path: str | None, n_jobs: int | None) -> list[tuple[str, float]]:
    """(stage, seconds) of the table's work done stage by stage in this process."""
    scenario = load_scenario(scenario_path)
    s = scenario.compensation or CompensationSettings()
    if n_jobs is not None:
        s = dataclasses.replace(s, n_jobs=n_jobs)
    out = []
    t0 = time.perf_counter()
    test = run_scenario(test_scenario(scenario, s))
    out.append((f"simulation: {len(test.simulations)} test start-ups, north-found",
                time.perf_counter() - t0))
    t0 = time.perf_counter()
    train_sc = train_scenario(scenario, s)
    train_runs = [r.run for r in simulate_runs(train_sc.instrument, train_sc.conditions())]
    out.append((f"simulation: {len(train_runs)} training start-ups", time.perf_counter() - t0))
    t0 = time.perf_counter()
    for run in [sim.run for sim in test.simulations] + train_runs:
        separate_drift(run, cutoff_period_s=s.cutoff_period_s)
    out.append((f"separation: wavelet, {len(test.simulations) + len(train_runs)} runs, once "
                "each", time.perf_counter() - t0))
    t0 = time.perf_counter()
    study = run_study(scenario, s, test=test)
    out.append((f"study: training start-ups, features, {len(s.methods)} rows trained on "
                f"n_jobs={s.n_jobs}, compensated runs north-found (wall)",
                time.perf_counter() - t0))
    for name, res in study.results.items():
        times = [r.fit_time_s for r in res.seeds]
        out.append((f"  training {name} ({len(times)} x, one thread each)", sum(times)))
    t0 = time.perf_counter()
    table = study.heading_table()
    out.append(("intervals and paired comparisons", time.perf_counter() - t0))
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        write_study(study, tmp, table=table)
        out.append(("report: tables, figures, report.md", time.perf_counter() - t0))
    return out


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default=None, help="scenario file (default: built-in)")
    p.add_argument("--n-jobs", type=int, default=None, help="workers (default: scenario's)")
    args = p.parse_args(argv)
    warnings.simplefilter("ignore")
    one_worker = args.n_jobs == 1
    goal = GOAL_ONE_WORKER_UNITS if one_worker else GOAL_UNITS
    ref0 = refwork_s()
    with tempfile.TemporaryDirectory() as tmp:
        cmd = ["table", "-q", "-o", os.path.join(tmp, "full")]
        cmd += [args.scenario] if args.scenario else []
        cmd += ["--n-jobs", str(args.n_jobs)] if args.n_jobs is not None else []
        wall, cpu = command_s(cmd)
        base = None
        if args.scenario is None:
            t0 = time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):
                nfs_main(["table", "--no-compensation", "-q", "-o", os.path.join(tmp, "base")])
            base = time.perf_counter() - t0
    stages = breakdown(args.scenario, args.n_jobs) if args.scenario is None else []
    ref = min(ref0, refwork_s())
    what = "nfs table " + " ".join(cmd[4:])
    print(f"reference workload (refwork.py, best of 4 runs, before and after): {ref:.2f} s "
          f"[{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}]")
    print(f"{what.strip()}: {wall:.1f} s wall, {cpu:.1f} s CPU: {wall / ref:.1f} units "
          f"({'within' if wall / ref <= goal else 'OVER'} the goal of {goal:g} units)")
    if args.scenario is None and not one_worker:
        w0, c0, u0 = BEFORE_DEFAULT
        print(f"before the cheaper trainings (BEFORE_DEFAULT, same machine, idle): {w0:.1f} s "
              f"wall, {c0:.0f} s CPU: {u0:.1f} units; now {u0 / (wall / ref):.2f}x faster")
        w0, c0, u0 = BEFORE_RVR_FACTOR_DEFAULT
        print(f"before the RVR's kernel factor (BEFORE_RVR_FACTOR_DEFAULT, same machine, idle): "
              f"{w0:.1f} s wall, {c0:.0f} s CPU: {u0:.1f} units; now {u0 / (wall / ref):.2f}x "
              "faster")
    elif one_worker and args.scenario and "seed003" in args.scenario:
        w0, u0 = BEFORE_RVR_FACTOR_ONE_WORKER
        print(f"before the RVR's kernel factor (BEFORE_RVR_FACTOR_ONE_WORKER, idle): {w0:.1f} s "
              f"wall: {u0:.1f} units; now {u0 / (wall / ref):.2f}x faster")
    if base is not None:
        print(f"baseline, the uncompensated table (--no-compensation): {base:.1f} s, "
              f"{base / ref:.1f} units; the full table is {wall / base:.1f}x it")
    if stages:
        print("where the time goes (the same work in this process, stage by stage):")
        for name, sec in stages:
            print(f"  {sec:7.1f} s  {sec / ref:5.1f} units  {name}")


if __name__ == "__main__":
    main()
