"""Speed of the whole simulation chain on the built-in default scenario.

Run as ``python benchmarks/bench_simulate.py``.  Simulates the 7 default runs (2.5 h each at
1 Hz: thermal network with the per-sample TEC law, effects, noise, sensors, thermometers) and
north-finds them, in one process, best of 5: run by run (:func:`nfs.experiment.simulate_run`)
and stacked (:func:`nfs.experiment.simulate_runs`, as ``nfs table`` does).  Targets (simulator issue): simulation of the 7
runs under 1 s in total; north-finding the 7 runs under 0.1 s.  The thermal solver alone is
compared with scipy.integrate.solve_ivp in benchmarks/bench_thermal.py.
"""

from __future__ import annotations

import time

from nfs.experiment import simulate_run, simulate_runs
from nfs.studies.scenario_runs import northfind_runs
from nfs.config.scenario import load_scenario


def best_of(f, n=5):
    best = float("inf")
    out = None
    for _ in range(n):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    sc = load_scenario()
    conds = sc.conditions()
    t_sim, sims = best_of(lambda: [simulate_run(sc.instrument, c) for c in conds])
    runs = [s.run for s in sims]
    t_nf, _ = best_of(lambda: northfind_runs(runs, sc.northfind))
    n = len(conds)
    samples = sum(len(r["time_s"]) for r in runs)
    t_stack, _ = best_of(lambda: simulate_runs(sc.instrument, conds))
    print(f"simulate {n} default runs ({samples} samples) run by run: {t_sim:.3f} s "
          f"(target < 1 s; {1.0 / t_sim:.1f}x under target)")
    print(f"the same runs stacked (simulate_runs): {t_stack:.3f} s; "
          f"{t_sim / t_stack:.2f}x faster than run by run")
    print(f"north-find {n} runs: {t_nf:.4f} s (target < 0.1 s; {0.1 / t_nf:.1f}x under target)")


if __name__ == "__main__":
    main()
