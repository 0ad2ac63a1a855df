"""Speed of chamber programs: the temperature cycle of Tao et al. 2019 (Sensors 19, 2986)
run twice, 51.3 h at 1 Hz, against the default start-up experiment, in one process.

1. Cost per sample of the simulation chain (thermal network under the first-order hold of
   the chamber program, effects, noise, sensors), best of 3: the cycle's one run of 184800
   samples against the default scenario's 7 start-ups of 9000 samples (target: no more per
   sample than a start-up).
2. Wall time of ``nfs table scenarios/seed000_temperature_cycle.toml``: simulate, train every
   row on cycle 1, score cycle 2 with intervals, write the drift table (target: <= 60 s on
   2 cores), beside the wall time of ``nfs table`` on the default scenario (every row of the
   start-up table), both through the command line.
3. Wall time of ``nfs table`` on the two other papers' scenarios: the ramps of Cheng et al.
   2015 (the drift table over runs) and the 116.7 h ramp calibration of Liang et al. 2021
   (parameter-level compensation), beside the same default table.

Run as ``python benchmarks/bench_programs.py``.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import time
import warnings
from pathlib import Path

from timing import best_of

from nfs.cli import main as nfs_main
from nfs.experiment import simulate_runs
from nfs.config.scenario import load_scenario

TARGET_S = 60.0
SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
CYCLE = SCENARIOS / "seed000_temperature_cycle.toml"
OTHERS = {"Cheng et al. 2015 ramps (drift table over runs)": SCENARIOS / "seed001_ramps.toml",
          "Liang et al. 2021 ramp calibration (parameter level)":
              SCENARIOS / "seed003_ramp_calibration.toml"}


def per_sample_us(scenario) -> tuple[float, int]:
    conds = scenario.conditions()
    n = sum(int(round(c.duration_s * c.sample_rate_hz)) for c in conds)
    t = best_of(lambda: simulate_runs(scenario.instrument, conds))
    return 1e6 * t / n, n


def table_s(*argv) -> float:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):
            code = nfs_main(["table", *argv, "-q", "-o", os.path.join(tmp, "out")])
        if code != 0:
            raise SystemExit(f"nfs table {' '.join(argv)} exited {code}")
        return time.perf_counter() - t0


def main() -> None:
    warnings.simplefilter("ignore")
    cycle_us, cycle_n = per_sample_us(load_scenario(CYCLE))
    start_us, start_n = per_sample_us(load_scenario())
    print(f"simulation per sample: cycle program {cycle_us:.2f} us ({cycle_n} samples), "
          f"default start-ups {start_us:.2f} us ({start_n} samples); ratio "
          f"{cycle_us / start_us:.2f}x")
    cycle_s = table_s(str(CYCLE))
    default_s = table_s()
    print(f"nfs table on the temperature cycle (simulate 51.3 h, train every row, drift table "
          f"with intervals, {os.cpu_count()} cores): {cycle_s:.1f} s "
          f"({'under' if cycle_s <= TARGET_S else 'OVER'} the {TARGET_S:.0f} s target)")
    print(f"baseline, nfs table on the default start-up scenario (every row): {default_s:.1f} s;"
          f" ratio {cycle_s / default_s:.2f}x")
    for what, path in OTHERS.items():
        t = table_s(str(path))
        print(f"nfs table {path.name}, {what}: {t:.1f} s; ratio to the default table "
              f"{t / default_s:.2f}x")


if __name__ == "__main__":
    main()
