"""Wall time of ``nfs fit`` and ``nfs diagnose`` on 7 runs of 2.5 h at 1 Hz (target: each under
20 s on the 2-core machine), on the default world and on units the model did not make.

Run as ``python benchmarks/bench_diagnose.py [--family 3]``.  Sets:

- the default scenario with its realistic variability, seed 11 (what ``nfs simulate
  scenarios/startup_7temps.toml -o runs --seed 11`` writes), the default instrument as the
  model;
- ``--family N`` clean sets of the independent family (``tests/independent/family.py``,
  seeds 1..N), fitted from the default instrument with the effects those units have in kind
  (as ``benchmarks/bench_independent.py`` does).

Each set: :func:`nfs.fit.fit_unit` (what ``nfs fit`` runs: both stages, then the
structure check on held-out runs and its refinement where a thermometer is missed by more
than 2x) and :func:`nfs.diagnose.diagnose` with the fitted model, each timed once (the
reference workload of ``../shared/tools/refwork.py``, timed in the same process, puts the
figures in reference units).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
import warnings
from pathlib import Path

from nfs.diagnose import diagnose
from nfs.fit import fit_unit
from nfs.experiment import simulate_run
from nfs.io.measurement import read_runs
from nfs.config.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "independent"))
sys.path.insert(0, str(ROOT / "benchmarks"))
from family import generate_family_set  # noqa: E402
from bench_independent import independent_model  # noqa: E402

TARGET_S = 20.0


def _reference_s() -> float:
    """Seconds of the shared reference workload, when ../shared is beside the project."""
    ref = ROOT.parent / "shared" / "tools" / "refwork.py"
    if not ref.exists():
        return float("nan")
    import runpy
    t0 = time.perf_counter()
    runpy.run_path(str(ref), run_name="refwork")
    return time.perf_counter() - t0


def _time(model, runs) -> tuple[float, float, str]:
    t0 = time.perf_counter()
    fit = fit_unit(model, runs)
    t_fit = time.perf_counter() - t0
    d = diagnose(fit.instrument, runs)
    return t_fit, time.perf_counter() - t0 - t_fit, d.answer.kind


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--family", type=int, default=3, help="clean family sets (seeds 1..N)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    ref = _reference_s()
    rows = []
    sc = dataclasses.replace(load_scenario(), seed=11)
    runs = [simulate_run(sc.instrument, c).run for c in sc.conditions()]
    rows.append(("default world, seed 11", *_time(sc.instrument, runs)))
    for seed in range(1, args.family + 1):
        with tempfile.TemporaryDirectory() as tmp:
            generate_family_set(tmp, seed=seed)
            runs = read_runs(tmp)
        rows.append((f"family unit, seed {seed}", *_time(independent_model(), runs)))
    print(f"{'set':26s} {'fit [s]':>8s} {'diagnose [s]':>13s}  answer")
    for name, tf, td, kind in rows:
        print(f"{name:26s} {tf:8.1f} {td:13.1f}  {kind}")
    worst = max(max(tf, td) for _, tf, td, _ in rows)
    print(f"slowest step {worst:.1f} s (target < {TARGET_S:g} s each: "
          f"{'met' if worst < TARGET_S else 'NOT met'}); reference workload {ref:.2f} s, "
          f"slowest step {worst / ref:.1f} reference units")


if __name__ == "__main__":
    main()
