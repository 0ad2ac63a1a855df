"""False alarms of ``nfs diagnose`` on runs made by the model itself (calibration).

Run as ``python benchmarks/bench_false_alarm.py [n_sets]`` (default 20 sets; about 1 min
on an idle 2-core machine).  Each set is the default scenario's 7 start temperatures x 2.5 h at
1 Hz simulated with the default instrument (nfs.experiment.simulate_run with the
load_scenario().nominal() conditions -- the default experiment without run-to-run or
unit-to-unit variability, so the model is exactly the unit -- the scenario seed varied:
1000, 1001, ...), diagnosed with the
default instrument as the model.  Nothing is missing, so every candidate's null hypothesis
holds.  Printed:

- the rate of sets in which some candidate is significant (Holm at family-wise alpha 0.05
  and a CV drop): the family-wise error rate, target <= 5 %, with its Clopper-Pearson 95 %
  interval;
- over all (set, candidate) pairs, the fraction of clustered p-values (before Holm) below
  0.05 and 0.01, which a calibrated test puts near 5 % and 1 %, and the same per channel;
- the candidates with the most p < 0.05;
- the benchmark's own wall time.
"""

from __future__ import annotations

import dataclasses
import sys
import time
import warnings
from collections import Counter

import numpy as np
from joblib import Parallel, delayed
from scipy.stats import binomtest

from nfs.diagnose import diagnose
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.io.scenario import load_scenario

ALPHA = 0.05


def one_set(seed: int) -> dict:
    """Simulate one clean set and diagnose it; the p-values and the verdict."""
    warnings.simplefilter("ignore")
    sc = dataclasses.replace(load_scenario().nominal(), seed=seed)
    runs = [simulate_run(sc.instrument, c).run for c in sc.conditions()]
    d = diagnose(load_instrument("default"), runs, alpha=ALPHA)
    return {"seed": seed, "significant": [f"{s.effect}:{s.target}" for s in d.significant],
            "p": {f"{s.effect}:{s.target}": (s.wald_p, s.channel) for s in d.ranking},
            "time_s": d.time_s}


def main(n_sets: int = 20) -> None:
    t0 = time.perf_counter()
    sets = Parallel(n_jobs=2)(delayed(one_set)(1000 + i) for i in range(n_sets))
    wall = time.perf_counter() - t0
    any_sig = sum(bool(s["significant"]) for s in sets)
    ci = binomtest(any_sig, n_sets).proportion_ci(0.95)
    print(f"{n_sets} clean sets (7 runs x 2.5 h each), default instrument as the model, "
          f"family-wise alpha {ALPHA}")
    print(f"sets with a significant candidate: {any_sig}/{n_sets} = {any_sig / n_sets:.1%} "
          f"(95 % CI {ci.low:.1%}-{ci.high:.1%}; target <= 5 %)")
    for s in sets:
        if s["significant"]:
            print(f"  seed {s['seed']}: " + ", ".join(s["significant"]))
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
    print("most often p < 0.05: " + ", ".join(f"{k} ({n}/{n_sets})"
                                              for k, n in worst.most_common(6)))
    print(f"diagnose {np.mean([s['time_s'] for s in sets]):.1f} s per set; benchmark wall "
          f"time {wall:.0f} s on 2 workers")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
