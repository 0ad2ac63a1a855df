"""Wall time of ``nfs diagnose`` with every candidate on 7 runs of 2.5 h at 1 Hz (target: under
20 s on the 2-core machine).  Run as ``python benchmarks/bench_diagnose.py``: the runs are the
default scenario's seven start-ups; the model is the default instrument (best of 2)."""

from __future__ import annotations

import time
import warnings

from nfs.diagnose import diagnose
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.io.scenario import load_scenario


def main() -> None:
    warnings.simplefilter("ignore")
    sc = load_scenario().nominal()
    runs = [simulate_run(sc.instrument, c).run for c in sc.conditions()]
    model = load_instrument("default")
    best, d = float("inf"), None
    for _ in range(2):
        t0 = time.perf_counter()
        d = diagnose(model, runs)
        best = min(best, time.perf_counter() - t0)
    print(f"diagnose 7 runs ({sum(len(r['time_s']) for r in runs)} samples), "
          f"{len(d.ranking)} candidates scored, {len(d.not_tried)} not tried: {best:.1f} s "
          f"(target < 20 s; {20.0 / best:.1f}x under target)")
    print(d.verdict)


if __name__ == "__main__":
    main()
