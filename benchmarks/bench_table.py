"""Wall time of ``nfs table`` with every row at its default budget (target: under 60 s on the
2-core machine).  Run as ``python benchmarks/bench_table.py``; prints the time of each stage
of the compensation study, the total and its ratio to the target."""

from __future__ import annotations

import time
import warnings

from nfs.compensate.study import run_study
from nfs.io.scenario import load_scenario


def main() -> None:
    warnings.simplefilter("ignore")
    marks = []
    t0 = time.perf_counter()

    def progress(i, n, msg):
        marks.append((time.perf_counter() - t0, msg))

    study = run_study(load_scenario(), progress=progress)
    study.heading_table()
    total = time.perf_counter() - t0
    for (t, msg), nxt in zip(marks, marks[1:] + [(total, "")]):
        print(f"  {msg:<40s} {nxt[0] - t:6.1f} s")
    print(f"nfs table, every row, budget {study.settings.budget}: {total:.1f} s "
          f"(target < 60 s; {60.0 / total:.2f}x under target)")


if __name__ == "__main__":
    main()
