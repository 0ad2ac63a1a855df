"""What ``nfs table --baseline`` adds to ``nfs table`` (target: at most 1 s), and how often it
cries wolf.

Speed.  Baseline, timed in the same process: ``nfs table --no-compensation`` on the default
scenario (7 start temperatures x 5 test start-ups).  Figure: the comparison of that table with
its own JSON (:func:`nfs.scoring.baseline.compare_tables`, paired, 4000 replicates), and of a
table of the full default shape (16 rows: before, 14 compensated rows, stable; plus the
floor), the largest the default scenario writes.  With ``--full``, the full ``nfs table`` is
timed as well, with and without ``--baseline`` (about a minute each on two cores).

Calibration (``--calibrate N``).  Two runs that differ only by their seed (no change at all)
are compared unpaired, for N pairs of seeds: the fraction of cells flagged ``worse`` (beyond
noise and 5 %) is the false-alarm rate per cell; the fraction of pairs with at least one such
cell is the rate at which ``--baseline`` would exit 1 on a change that changed nothing but the
draws.

    python benchmarks/bench_baseline.py [--full] [--calibrate N]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import tempfile
import time
import warnings

import numpy as np

from nfs.cli import main as nfs_main
from nfs.scoring.baseline import compare_tables

TARGET_S = 1.0


def _nfs(*argv) -> tuple[int, float]:
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        code = nfs_main([str(a) for a in argv])
    return code, time.perf_counter() - t0


def _full_shape(doc: dict, n_rows: int = 14) -> dict:
    """The uncompensated table's JSON grown to the full table's rows: ``n_rows`` rows whose
    cycle errors are the ``before`` row's scaled by 0.3..0.9 (the compensated rows' range)."""
    out = json.loads(json.dumps(doc))
    before = next(r for r in out["rows"] if r["method"] == "before")
    for k in range(n_rows):
        s = 0.3 + 0.6 * k / max(1, n_rows - 1)
        name = f"method {k}"
        out["rows"].insert(1 + k, {**before, "method": name,
                                   "rmse_deg": [None if v is None else s * v
                                                for v in before["rmse_deg"]]})
        out["errors_deg"][name] = [[[None if v is None else s * v for v in run] for run in col]
                                   for col in out["errors_deg"]["before"]]
    return out


def speed(tmp: str, full: bool) -> None:
    base = os.path.join(tmp, "base.json")
    code, t_table = _nfs("table", "--no-compensation", "-q", "-o", os.path.join(tmp, "t"),
                         "--json", base)
    assert code == 0
    doc = json.loads(open(base, encoding="utf-8").read())
    t0 = time.perf_counter()
    compare_tables(doc, base)
    t_cmp = time.perf_counter() - t0
    big = _full_shape(doc)
    t0 = time.perf_counter()
    c = compare_tables(big, big)
    t_big = time.perf_counter() - t0
    print(f"nfs table --no-compensation (default scenario): {t_table:.2f} s")
    print(f"  --baseline's comparison of that table ({len(doc['rows'])} rows): {t_cmp:.2f} s "
          f"({t_cmp / t_table:.1%} of the table)")
    print(f"  comparison of a full-shape table ({len(big['rows'])} rows, "
          f"{len(c.cells)} cells): {t_big:.2f} s "
          f"({'within' if t_big <= TARGET_S else 'OVER'} the {TARGET_S:g} s target)")
    if full:
        full_json = os.path.join(tmp, "full.json")
        code, t_full = _nfs("table", "-q", "-o", os.path.join(tmp, "f1"), "--json", full_json)
        code2, t_full_b = _nfs("table", "-q", "-o", os.path.join(tmp, "f2"), "--baseline",
                               full_json)
        print(f"nfs table (every row): {t_full:.1f} s; with --baseline: {t_full_b:.1f} s "
              f"(+{t_full_b - t_full:.1f} s; exit {code2})")


def calibrate(tmp: str, n: int) -> None:
    flagged, cells, pairs_flagged = 0, 0, 0
    for k in range(n):
        paths = []
        for seed in (10 + 2 * k, 11 + 2 * k):
            p = os.path.join(tmp, f"seed{seed}.json")
            code, _ = _nfs("table", "--no-compensation", "-q", "--seed", seed,
                           "-o", os.path.join(tmp, f"s{seed}"), "--json", p)
            assert code == 0
            paths.append(p)
        c = compare_tables(paths[1], paths[0])
        counted = [x for x in c.cells if x.verdict != "n/a" and x.method != "floor"]
        w = [x for x in counted if x.verdict == "worse"]
        flagged += len(w)
        cells += len(counted)
        pairs_flagged += bool(w)
        print(f"  seeds {10 + 2 * k} vs {11 + 2 * k}: {len(w)} of {len(counted)} cells worse"
              + (f" ({', '.join(x.label() for x in w)})" if w else ""))
    print(f"seed-only change, unpaired, {n} pairs: {flagged} of {cells} cells flagged worse "
          f"({flagged / max(cells, 1):.1%} per cell; the floor, exact, left out); "
          f"{pairs_flagged} of {n} comparisons would exit 1")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true", help="also time the full nfs table")
    ap.add_argument("--calibrate", type=int, default=0, metavar="N",
                    help="pairs of seeds for the false-alarm rate")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    np.seterr(all="ignore")
    with tempfile.TemporaryDirectory() as tmp:
        speed(tmp, args.full)
        if args.calibrate:
            calibrate(tmp, args.calibrate)


if __name__ == "__main__":
    main()
