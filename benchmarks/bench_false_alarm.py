"""False alarms of ``nfs fit`` + ``nfs diagnose`` (and ``nfs compare``) on the package's own
default world, where nothing is missing from the model.

Run as ``python benchmarks/bench_false_alarm.py [--sets 20] [--seed0 1000] [--compare]
[--nominal] [--jobs 2]``.  Each set is the default scenario (``scenarios/startup_7temps.toml``,
the built-in default): 7 start temperatures x 2.5 h at 1 Hz, simulated with its realistic
variability (unfinished soaks from a 23 C laboratory, a chamber that wanders and cycles,
the unit's parameters scattered: :mod:`nfs.variability`), the scenario seed varied
(``--seed0``, ``--seed0 + 1``, ...), exactly what ``nfs simulate
scenarios/startup_7temps.toml -o runs --seed S`` writes.  Then what a user does: fit the
default model to the runs (:func:`nfs.fit.fit_unit`, as `nfs fit` does), diagnose with the fitted model
(:func:`nfs.diagnose.diagnose`) and, with ``--compare``, set the fitted model beside the runs
(:func:`nfs.comparison.compare`).  The model's structure is the truth's, so any named effect is
a false alarm.  ``--nominal`` runs the world without variability instead.

Printed:

- per set: the diagnosis's answer, whether the thermal structure was called adequate, the
  worst thermometer's held-out residual in floors, and with ``--compare`` the channels and
  the heading flagged;
- the rates with Clopper-Pearson 95 % intervals: sets where an effect is named (the false
  alarm, goal <= 5 %), ties, "unexplained", thermal structure inadequate; with
  ``--compare``, the heading verdict's false alarms and each channel's;
- over all (set, candidate) pairs, the fraction of clustered p-values (before Holm) below
  0.05 and 0.01, which a calibrated test puts near 5 % and 1 %, per channel;
- the time of the fit and the diagnosis per set and the wall time.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
import warnings
from collections import Counter

import numpy as np
from joblib import Parallel, delayed
from scipy.stats import binomtest

from nfs.comparison import compare
from nfs.diagnose import diagnose
from nfs.fit import fit_unit
from nfs.experiment import simulate_run
from nfs.config.scenario import load_scenario

ALPHA = 0.05


def one_set(seed: int, nominal: bool, with_compare: bool) -> dict:
    """Simulate one clean set, fit, diagnose (and compare); the outcome."""
    warnings.simplefilter("ignore")
    sc = load_scenario()
    sc = dataclasses.replace(sc.nominal() if nominal else sc, seed=seed)
    runs = [simulate_run(sc.instrument, c).run for c in sc.conditions()]
    t0 = time.perf_counter()
    fit = fit_unit(sc.instrument, runs)
    t_fit = time.perf_counter() - t0
    d = diagnose(fit.instrument, runs, alpha=ALPHA)
    t_diag = time.perf_counter() - t0 - t_fit
    ts = d.thermal_structure
    out = {"seed": seed, "answer": d.answer.kind, "labels": d.answer.labels,
           "text": d.answer.text,
           "adequate": None if ts is None else ts.adequate,
           "worst_floor": None if ts is None else ts.worst.ratio,
           "p": {f"{s.effect}:{s.target}": (s.wald_p, s.channel) for s in d.ranking},
           "t_fit_s": t_fit, "t_diag_s": t_diag}
    if with_compare:
        c = compare(fit.instrument, runs)
        out["flagged"] = [k for k, s in c.summaries.items() if not s.consistent]
        out["heading_consistent"] = c.heading.consistent
        out["heading_ratio"] = c.heading.ratio
    return out


def _rate(k: int, n: int, what: str, goal: str = "") -> str:
    ci = binomtest(k, n).proportion_ci(0.95)
    return (f"{what}: {k}/{n} = {k / n:.0%} (95 % CI {ci.low:.0%}-{ci.high:.0%})"
            + (f"; goal {goal}" if goal else ""))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sets", type=int, default=20, help="clean sets (default 20)")
    ap.add_argument("--seed0", type=int, default=1000, help="scenario seed of the first set")
    ap.add_argument("--jobs", type=int, default=2, help="sets at once (joblib)")
    ap.add_argument("--nominal", action="store_true",
                    help="the world without variability (soaked exactly, still chamber)")
    ap.add_argument("--compare", action="store_true",
                    help="also nfs compare each set: the heading verdict's false alarms")
    args = ap.parse_args(argv)
    n = args.sets
    t0 = time.perf_counter()
    sets = Parallel(n_jobs=args.jobs)(delayed(one_set)(args.seed0 + i, args.nominal,
                                                       args.compare) for i in range(n))
    wall = time.perf_counter() - t0
    world = load_scenario()
    desc = ("nominal (no variability)" if args.nominal else
            world.variability.describe())
    print(f"{n} clean sets of the default scenario (7 runs x 2.5 h), seeds {args.seed0}-"
          f"{args.seed0 + n - 1}; world: {desc}")
    for s in sets:
        line = (f"  seed {s['seed']}: {s['answer']:12s} thermal "
                f"{'adequate' if s['adequate'] else 'INADEQUATE'} (worst {s['worst_floor']:.2f}x"
                f" its floor held out)")
        if args.compare:
            line += (f"; compare flags {','.join(s['flagged']) or '-'}; heading "
                     f"{'ok' if s['heading_consistent'] else 'FLAGGED'}")
        if s["answer"] != "nothing":
            line += f"; {s['text'][:160]}"
        print(line)
    kinds = Counter(s["answer"] for s in sets)
    print(_rate(kinds["add"], n, "sets where an effect is named (false alarm)", "<= 5 %"))
    print(_rate(kinds["tie"], n, "sets answered with a tie"))
    print(_rate(kinds["unexplained"] + kinds["undetermined"], n,
                "sets answered 'unexplained' or 'undetermined'"))
    print(_rate(sum(s["adequate"] is False for s in sets), n,
                "sets whose thermal structure is called inadequate"))
    if args.compare:
        print(_rate(sum(not s["heading_consistent"] for s in sets), n,
                    f"nfs compare: heading flagged (Holm over 2 stages at {ALPHA})", "<= 5 %"))
        chans = Counter(k for s in sets for k in s["flagged"])
        for k, v in chans.most_common():
            print("  " + _rate(v, n, f"channel {k} flagged"))
    p = np.array([v[0] for s in sets for v in s["p"].values()])
    chan = np.array([v[1] for s in sets for v in s["p"].values()])
    print(f"clustered p-values before Holm, {p.size} (set, candidate) pairs: "
          f"P(p < 0.05) = {np.mean(p < 0.05):.3f}, P(p < 0.01) = {np.mean(p < 0.01):.3f} "
          f"(calibrated: 0.05, 0.01; conservative below)")
    for ch in np.unique(chan):
        q = p[chan == ch]
        print(f"  {ch}: {q.size} pairs, P(p < 0.05) = {np.mean(q < 0.05):.3f}, "
              f"P(p < 0.01) = {np.mean(q < 0.01):.3f}, median p {np.median(q):.2f}")
    worst = Counter(k for s in sets for k, v in s["p"].items() if v[0] < 0.05)
    print("most often p < 0.05: " + ", ".join(f"{k} ({m}/{n})"
                                              for k, m in worst.most_common(6)))
    tf = np.median([s["t_fit_s"] for s in sets])
    td = np.median([s["t_diag_s"] for s in sets])
    print(f"per set ({args.jobs} at once): fit median {tf:.1f} s, diagnose median {td:.1f} s; "
          f"wall time {wall:.0f} s")


if __name__ == "__main__":
    main()
