"""The way users work a unit, measured: fit, diagnose, apply what it adds, diagnose again.

The runs come from the independent generator of the tests (``tests/independent/``; it imports
nothing of ``nfs``), one unit of its *family* per set (its structure, noise, chamber,
unfinished soak and the hidden effect's strength drawn from the set's seed), as in
``bench_independent.py``, whose cases, model and hit rule this benchmark reuses.  Where that
benchmark reads the *first* answer, this one works each set as a user does with
:class:`nfs.UnitChain`:

1. fit the model to the 7 runs (:meth:`~nfs.UnitChain.fit`, what ``nfs fit`` does);
2. diagnose (:meth:`~nfs.UnitChain.diagnose`; with ``--decide`` a tie is put to the runs
   first, as ``nfs diagnose --decide``);
3. an answer that adds an effect is applied (:meth:`~nfs.UnitChain.apply`: the effect added,
   every free number refitted) and the unit diagnosed again; with ``--take-ties`` a tie's first
   label that is an effect is applied too ("apply the first of the tied", what a user asked
   to choose does); anything else ends the set;
4. at most ``--rounds`` (default 3) rounds.

Counted per set (the hidden effect's case):

- *hit*: a round adds the hidden effect (the label's effect and the target
  ``bench_independent.TARGETS`` names), or the fit takes the hidden effect up in a number it
  frees anyway (an extra thermometer lag in the thermometer's own lag, extra heat in the
  node's power), moved from the fit of the same unit without it by the hidden amount
  (``bench_independent._absorbed``); the round it came in is printed;
- *tie*: the set ends in a tie whose labels hold the hidden effect (honest), *miss* otherwise;
- for a clean or outside-library set, a *false alarm* when any round adds an effect;
- *extra adds*: effects added on a hidden-effect set before or besides the hidden one.

Also printed: the fitted models' departures (fitted values beyond their typical range in the
table of ranges, :mod:`nfs.fit.departures`; the median per set and the parameters most often
out), values outside their hard range (the goal: none), and the time of fit + diagnose of
each set's first round (the goal: <= 20 s at the slowest set) and of the whole set.

Slow: 20 s to a few minutes per set.  Run: ``python benchmarks/bench_workflow.py [--sets 60]
[--jobs 2] [--seed0 1] [--rounds 3] [--take-ties] [--decide] [--effects magnetic,none]``.
"""

from __future__ import annotations

import argparse
import math
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
from nfs.effects import get_effect
from nfs.errors import NfsError
from nfs.fit.departures import canonical_key
from nfs.io.measurement import read_runs
from nfs.unit import UnitChain

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_independent import (CASES, GOAL_FALSE_ALARMS, GOAL_HITS, NULL_CASES,  # noqa: E402
                               _absorbed, _names, _rate, independent_model, schedule,
                               twin_fit)

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "independent"))
from generator import draw_unit, generate_family_set  # noqa: E402

#: Goal: the slowest set's fit + first diagnosis [s] (2 cores).
GOAL_FIT_DIAGNOSE_S = 20.0
#: Goal: each effect case's hits, out of its sets (4 of 6).
GOAL_PER_CASE = 4 / 6


def _is_effect(label: str) -> bool:
    try:
        get_effect(label.partition(":")[0])
    except (NfsError, KeyError, ValueError):
        return False
    return True


def _impossible(params: dict[str, float]) -> list[str]:
    out = []
    for p, v in params.items():
        row = ranges.find(canonical_key(p))
        if row is not None and row.impossible(float(v)):
            out.append(p)
    return out


def work_set(case: str, seed: int, rounds: int, take_ties: bool, decide: bool) -> dict:
    """Generate one family set and work it as a user does; the outcome."""
    warnings.simplefilter("ignore")
    hidden = None if case == "none" else case
    row = {"case": case, "seed": seed, "rounds": [], "outcome": "?", "hit_round": None,
           "extra": [], "departures": [], "impossible": [], "t_first_s": math.nan,
           "t_total_s": math.nan, "world": "?"}
    t0 = time.perf_counter()
    try:
        with threadpool_limits(1), tempfile.TemporaryDirectory() as tmp:
            truth = generate_family_set(tmp, seed=seed, hidden=hidden)
            unit = draw_unit(seed).unit
            row["world"] = f"{unit.coil.n_layers} layers, {unit.tec_law}"
            runs = read_runs(tmp)
            params = truth.get("params", {})
            twin = twin_fit(seed, hidden, params)     # the oracle's fit: not timed
            t1 = time.perf_counter()
            chain = UnitChain(independent_model(), runs)
            fit = chain.fit()
            row["departures"] = list(fit.departures)
            row["impossible"] = _impossible(fit.params)
            absorbed = _absorbed(hidden, fit, twin, params)
            end = None
            for k in range(1, rounds + 1):
                finding = chain.diagnose(decide=decide)
                if k == 1:
                    row["t_first_s"] = time.perf_counter() - t1
                a = finding.answer
                row["rounds"].append(f"{a.kind} {', '.join(a.labels) or '-'}")
                take = None
                if a.kind == "add":
                    take = a.labels[0]
                elif a.kind == "tie" and take_ties:
                    take = next((lab for lab in a.labels if _is_effect(lab)), None)
                if take is None:
                    end = a
                    break
                if hidden is not None and _names(take, hidden):
                    row["hit_round"] = k        # named: applying it would add nothing here
                    break
                row["extra"].append(take)
                applied = chain.apply(take)
                row["impossible"] += _impossible(applied.fit.params)
                if hidden is not None and not absorbed:
                    absorbed = _absorbed(hidden, applied.fit, twin, params)
            if case in NULL_CASES:
                row["outcome"] = "false alarm" if row["extra"] else (
                    "tie" if end is not None and end.kind == "tie" else "quiet")
            elif row["hit_round"] is not None or absorbed:
                row["outcome"] = "hit"
                row["absorbed"] = absorbed
            elif end is not None and end.kind == "tie" and any(_names(lab, case)
                                                              for lab in end.labels):
                row["outcome"] = "tie"
            else:
                row["outcome"] = "miss"
    except Exception as exc:       # a benchmark reports a failing set, it does not stop
        row["outcome"] = "error" if case in NULL_CASES else "miss"
        row["rounds"].append(f"error {type(exc).__name__}: {exc}")
    row["t_total_s"] = time.perf_counter() - t0
    return row


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sets", type=int, default=60, help="total sets over the cases")
    ap.add_argument("--effects", default="", help="comma-separated cases (default: all)")
    ap.add_argument("--jobs", type=int, default=2, help="parallel sets (joblib)")
    ap.add_argument("--seed0", type=int, default=1, help="seed of the first set")
    ap.add_argument("--rounds", type=int, default=3, help="diagnose/apply rounds at most")
    ap.add_argument("--take-ties", action="store_true",
                    help="apply a tie's first effect label, as a user asked to choose does")
    ap.add_argument("--decide", action="store_true",
                    help="put a tie to the runs before answering (nfs diagnose --decide)")
    args = ap.parse_args(argv)
    cases = tuple(e.strip() for e in args.effects.split(",") if e.strip()) or CASES
    unknown = set(cases) - set(CASES)
    if unknown:
        ap.error(f"unknown case(s) {', '.join(sorted(unknown))}; valid: {', '.join(CASES)}")
    plan = schedule(cases, args.sets, args.seed0)
    t0 = time.perf_counter()
    print(f"{'case':26s} {'seed':>4s}  {'outcome':11s} rounds  [unit; departures; first fit + "
          "diagnose s; set s]", flush=True)
    rows = []
    for r in Parallel(n_jobs=args.jobs, return_as="generator_unordered")(
            delayed(work_set)(c, s, args.rounds, args.take_ties, args.decide)
            for c, s in plan):
        rows.append(r)
        hit = (f" (round {r['hit_round']})" if r["hit_round"] else
               f" ({r['absorbed']})" if r.get("absorbed") else "")
        print(f"{r['case']:26s} {r['seed']:4d}  {r['outcome']:11s}{hit} "
              + " | ".join(r["rounds"])
              + f"  [{r['world']}; {len(r['departures'])} out; {r['t_first_s']:.0f} s; "
              f"{r['t_total_s']:.0f} s]", flush=True)
    wall = time.perf_counter() - t0
    order = {cs: i for i, cs in enumerate(plan)}
    rows.sort(key=lambda r: order[(r["case"], r["seed"])])
    print()
    worst_case = 1.0
    for case in dict.fromkeys(r["case"] for r in rows):
        sub = [r for r in rows if r["case"] == case]
        n = Counter(r["outcome"] for r in sub)
        if case in NULL_CASES:
            print(f"{case:26s} false alarms {n['false alarm']}/{len(sub)}, ties "
                  f"{n['tie']}/{len(sub)}, errors {n['error']}")
        else:
            worst_case = min(worst_case, n["hit"] / len(sub))
            rounds = Counter(r["hit_round"] for r in sub if r["hit_round"])
            absorbed = sum(1 for r in sub if r["outcome"] == "hit" and not r["hit_round"])
            by = ", ".join([f"round {k}: {v}" for k, v in sorted(rounds.items())]
                           + ([f"taken up by a free parameter: {absorbed}"] if absorbed else []))
            print(f"{case:26s} hits {n['hit']}/{len(sub)}" + (f" ({by})" if by else "")
                  + f", honest "
                  f"ties {n['tie']}/{len(sub)}, misses {n['miss']}/{len(sub)}, extra adds "
                  f"{sum(len(r['extra']) for r in sub)}")
    hits = [r for r in rows if r["case"] not in NULL_CASES]
    nulls = [r for r in rows if r["case"] in NULL_CASES]
    if hits:
        k = sum(r["outcome"] == "hit" for r in hits)
        print(f"hit rate (a round adds the hidden effect): {_rate(k, len(hits))} "
              f"(goal >= {100 * GOAL_HITS:.0f} %); worst effect case {100 * worst_case:.0f} % "
              f"(goal >= {100 * GOAL_PER_CASE:.0f} %)")
        ties = [r for r in hits if r["outcome"] in ("tie", "miss") and r["rounds"]
                and r["rounds"][-1].startswith("tie")]
        print(f"  sets ending in a tie: {len(ties)}, the truth outside "
              f"{sum(r['outcome'] != 'tie' for r in ties)} (goal: inside every tie)")
    if nulls:
        k = sum(r["outcome"] == "false alarm" for r in nulls)
        print(f"false-alarm rate (a clean or outside-library set gets an effect added): "
              f"{_rate(k, len(nulls))} (goal <= {100 * GOAL_FALSE_ALARMS:.0f} %)")
    dep = [len(r["departures"]) for r in rows]
    out = Counter(p for r in rows for p in r["departures"])
    print(f"fitted models: parameters beyond their typical range per set median "
          f"{statistics.median(dep) if dep else 0:g} (range {min(dep, default=0)}-"
          f"{max(dep, default=0)}); most often: "
          + ", ".join(f"{p} {v}" for p, v in out.most_common(5)))
    print(f"  values outside their hard range: {sum(len(r['impossible']) for r in rows)} "
          "(goal: none)")
    tf = [r["t_first_s"] for r in rows if math.isfinite(r["t_first_s"])]
    tt = [r["t_total_s"] for r in rows]
    print(f"time ({args.jobs} sets at once, one BLAS thread each): fit + first diagnosis "
          f"median {statistics.median(tf) if tf else math.nan:.1f} s, slowest "
          f"{max(tf, default=math.nan):.1f} s (goal <= {GOAL_FIT_DIAGNOSE_S:.0f} s); whole set "
          f"median {statistics.median(tt):.0f} s, slowest {max(tt):.0f} s; {len(rows)} sets "
          f"in {wall:.0f} s")


if __name__ == "__main__":
    main()
