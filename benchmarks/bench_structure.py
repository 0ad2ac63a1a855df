"""Speed of the thermal structure check (nfs.fit.adequacy.thermal_adequacy).

Run as ``python benchmarks/bench_structure.py``.  Simulates the 7 default runs (2.5 h each at
1 Hz) from the default instrument with a hidden link electronics-coil_inner of 0.3 W/K, then
times, in the same process and on the same runs (residual grid every 30 s):

- baseline: the model's own thermal fit, ``fit_model(default, runs, stages=("thermal",),
  decimate_s=30)`` (20 free parameters);
- ``thermal_adequacy(default, runs)``: the model's chord refit, 13 structural alternatives
  screened, the best 4 fitted, the CV verdict.

Each timed once (``REPEATS``); prints both, the ratio, and the verdict.  Target: the check within
about 10 s on the 2-core machine, about the cost of the baseline.
"""

from __future__ import annotations

import time

from nfs.fit.calibration import fit_model
from nfs.fit.adequacy import thermal_adequacy
from nfs.fit.structure import free_link
from nfs.experiment import simulate_run
from nfs.config.scenario import load_scenario

REPEATS = 1
DECIMATE_S = 30.0
TARGET_S = 10.0


def _best(f):
    """(best wall time [s], its CPU time [s], result): the CPU time shows a loaded machine."""
    best, cpu, out = float("inf"), float("nan"), None
    for _ in range(REPEATS):
        t0, c0 = time.perf_counter(), time.process_time()
        out = f()
        wall = time.perf_counter() - t0
        if wall < best:
            best, cpu = wall, time.process_time() - c0
    return best, cpu, out


def main() -> None:
    sc = load_scenario().nominal()
    inst = sc.instrument
    truth = free_link(inst, "electronics", "coil_inner").build([0.3])
    runs = [simulate_run(truth, c).run for c in sc.conditions()]
    t_base, c_base, fit = _best(lambda: fit_model(inst, runs, stages=("thermal",),
                                          decimate_s=DECIMATE_S))
    t_check, c_check, ad = _best(lambda: thermal_adequacy(inst, runs, decimate_s=DECIMATE_S))
    samples = sum(r.n_samples for r in runs)
    print(f"{len(runs)} runs ({samples} samples), residual grid {DECIMATE_S:g} s, best of "
          f"{REPEATS}")
    print(f"baseline fit_model thermal stage: {t_base:.2f} s wall, {c_base:.2f} s CPU "
          f"({fit.stages['thermal'].nfev} least-squares evaluations besides its Jacobians, "
          f"{len(fit.params)} parameters)")
    print(f"thermal_adequacy: {t_check:.2f} s wall, {c_check:.2f} s CPU, "
          f"{ad.n_evaluations} residual evaluations (target <= {TARGET_S:g} s); ratio to "
          f"baseline {t_check / t_base:.2f} wall, {c_check / c_base:.2f} CPU")
    print(f"verdict: adequate={ad.adequate}; {ad.message}")
    for a in ad.alternatives[:5]:
        print(f"  {a.name}: CV {1000 * a.cv_rms_before_k:.1f} -> {1000 * a.cv_rms_after_k:.1f}"
              f" mK, {', '.join(f'{p.split(chr(46))[-2]}={v:.3g}' for p, v in a.params.items())}"
              f"{'' if a.refined else ' (screened)'}")


if __name__ == "__main__":
    main()
