"""Wall time of ``nfs table`` on the default scenario with every default: every row, the
default tuner seeds, the intervals and comparisons, and every output file written (target:
under 60 s on the 2-core machine).

Baseline, timed in the same process: the uncompensated table (``nfs table
--no-compensation``: the test start-ups simulated and north-found, intervals included), the
part of the job that has nothing to train.  Run as ``python benchmarks/bench_table.py``;
prints the time of each stage, the figure, the baseline and their ratio.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import time
import warnings

from nfs.cli import main as nfs_main
from nfs.studies.startup_study import run_study
from nfs.config.scenario import load_scenario
from nfs.report.compensation import write_study

TARGET_S = 60.0


def main() -> None:
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):
            nfs_main(["table", "--no-compensation", "-q", "-o", os.path.join(tmp, "base")])
        baseline = time.perf_counter() - t0

        marks = []
        t0 = time.perf_counter()

        def progress(i, n, msg):
            marks.append((time.perf_counter() - t0, msg))

        scenario = load_scenario()
        study = run_study(scenario, progress=progress)
        marks.append((time.perf_counter() - t0, "tables, intervals, figures, report"))
        write_study(study, os.path.join(tmp, "full"))
        total = time.perf_counter() - t0
    for (t, msg), nxt in zip(marks, marks[1:] + [(total, "")]):
        print(f"  {t:6.1f} s  {msg:<44s} (+{nxt[0] - t:.1f} s)")
    s = study.settings
    print(f"nfs table, every row ({len(s.methods)} methods, budget {s.budget}, "
          f"{s.tuner_seeds} tuner seeds, {os.cpu_count()} cores): {total:.1f} s "
          f"({'under' if total < TARGET_S else 'OVER'} the {TARGET_S:.0f} s target)")
    print(f"baseline, the uncompensated table: {baseline:.1f} s; ratio {total / baseline:.1f}x")


if __name__ == "__main__":
    main()
