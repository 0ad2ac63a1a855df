"""Does ``nfs fit`` identify a unit?  Fitted values beyond their typical range, and beyond
their hard range, on units the model did not make.

The runs come from the independent generator of the tests (``tests/independent/``; it imports
nothing of ``nfs``), one unit of its *family* per set (its coil's layers, capacities, powers,
links, thermometer mounts, TEC law and noise drawn from the set's seed), clean or with one
hidden effect (``--effects``), 7 start temperatures x 2.5 h at 1 Hz.  Each set is fitted as
``nfs fit`` does (:func:`nfs.fit.fit_unit` on ``bench_independent.independent_model``), and
every fitted number (the free parameters and the gyro noise N, B, K) is set beside its row
in the one table of ranges (:mod:`nfs.ranges`): beyond its typical range (a *departure*:
what a physicist reads as the model lacking a structure), beyond its hard range (impossible:
the goal is none).

The count is made here from the table of ranges alone (not from :mod:`nfs.fit.departures`),
so that the script runs unchanged on an older checkout of the package
(``PYTHONPATH=/path/to/old/checkout python benchmarks/bench_identify.py``): the before and
after of a change to the fit are counted alike.

Printed: per set the number of departures and the parameters; the median per set, the
parameters most often out, the values beyond their hard range, and the fit time.

With ``--model lumped`` the fit starts from the lumped preset (two coil nodes, the lumped
Shupe terms): the sets whose coil the fit winds in layers
(:mod:`nfs.fit.wound_alternative`) are counted, and each set's structure steps and drift
cost printed.

Run: ``python benchmarks/bench_identify.py [--sets 12] [--jobs 2] [--seed0 1]
[--effects none,magnetic,heat_source] [--model lumped]``.
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path

from joblib import Parallel, delayed
from threadpoolctl import threadpool_limits

from nfs import ranges
from nfs.fit import fit_unit
from nfs.io.measurement import read_runs

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_independent import independent_model, schedule  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "independent"))
from generator import generate_family_set  # noqa: E402

NOISE = ("gyro.arw_deg_per_rth_h", "gyro.bias_instability_dph", "gyro.rrw_deg_per_h_per_rth_h")


def _key(path: str) -> str:
    m = re.fullmatch(r"effects\.([^.:]+):[^.]*\.(.+)", path)
    return f"effects.{m.group(1)}.{m.group(2)}" if m else path


def one_set(case: str, seed: int, model: str = "default") -> dict:
    """Generate, fit; every fitted number beyond its typical or hard range."""
    warnings.simplefilter("ignore")
    hidden = None if case == "none" else case
    with threadpool_limits(1), tempfile.TemporaryDirectory() as tmp:
        generate_family_set(tmp, seed=seed, hidden=hidden)
        runs = read_runs(tmp)
        t0 = time.perf_counter()
        fit = fit_unit(independent_model(model), runs)
        t_fit = time.perf_counter() - t0
    values = dict(fit.params)
    for p in NOISE:
        obj, leaf = p.split(".")
        values[p] = float(getattr(fit.instrument.gyro, leaf))
    out, impossible = [], []
    for p, v in values.items():
        row = ranges.find(_key(p))
        if row is None:
            continue
        if row.impossible(float(v)):
            impossible.append(p)
        elif row.unusual(float(v)):
            out.append(p)
    steps = getattr(fit.structure, "steps", ()) or ()
    return {"case": case, "seed": seed, "out": out, "impossible": impossible,
            "n": len(values), "t_fit_s": t_fit,
            "structure": [s.name for s in steps],
            "wound": any(getattr(s, "kind", "") == "wound" for s in steps),
            "drift_cost": fit.stages["drift"].stated_cost if "drift" in fit.stages else None}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sets", type=int, default=12)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--seed0", type=int, default=1)
    ap.add_argument("--effects", default="none,magnetic,heat_source,turn_on_transient")
    ap.add_argument("--model", default="default",
                    help="preset the fit starts from: default (wound coil) or lumped")
    args = ap.parse_args(argv)
    cases = tuple(e.strip() for e in args.effects.split(",") if e.strip())
    plan = schedule(cases, args.sets, args.seed0)
    t0 = time.perf_counter()
    rows = list(Parallel(n_jobs=args.jobs)(delayed(one_set)(c, s, args.model) for c, s in plan))
    for r in rows:
        print(f"{r['case']:20s} {r['seed']:4d}  {len(r['out']):2d} of {r['n']} out"
              f"{', impossible ' + ', '.join(r['impossible']) if r['impossible'] else ''}: "
              + ", ".join(r["out"]) + f"  [{r['t_fit_s']:.0f} s; structure: "
              + (", ".join(r["structure"]) or "as given")
              + (f"; drift cost {r['drift_cost']:.0f}" if r["drift_cost"] else "") + "]")
    counts = [len(r["out"]) for r in rows]
    common = Counter(p for r in rows for p in r["out"])
    print(f"\nfitted values beyond their typical range per set: median "
          f"{statistics.median(counts):g}, mean {statistics.mean(counts):.1f}, range "
          f"{min(counts)}-{max(counts)} ({len(rows)} sets)")
    print("most often: " + ", ".join(f"{p} {k}" for p, k in common.most_common(8)))
    print(f"values beyond their hard range: {sum(len(r['impossible']) for r in rows)} "
          "(goal: none)")
    wound = sum(r["wound"] for r in rows)
    if args.model != "default":
        print(f"coil wound in layers by the fit: {wound} of {len(rows)} sets")
    tf = [r["t_fit_s"] for r in rows]
    print(f"fit: median {statistics.median(tf):.1f} s, slowest {max(tf):.1f} s "
          f"({args.jobs} at once); {time.perf_counter() - t0:.0f} s in all")


if __name__ == "__main__":
    main()
