"""Speed of ``fit_model`` on the built-in default scenario (issue 4, "Speed").

Run as ``python benchmarks/bench_fit.py``.  Simulates the 7 default runs (2.5 h each at
1 Hz) from the default instrument with six parameters perturbed by +20 % (the runs of
tests/diagnose/test_fit.py), then fits the unperturbed default to them with the default
free set and both stages, best of 3.  Target: under 10 s on the 2-core machine.
"""

from __future__ import annotations

import time

from nfs.diagnose.fit import default_free, fit_model
from nfs.diagnose.params import get_param, set_params
from nfs.experiment import simulate_run
from nfs.io.scenario import load_scenario

TARGET_S = 10.0
PERTURBED = ("thermal.nodes.coil_inner.capacity_j_per_k",
             "thermal.links.housing-chamber.conductance_w_per_k", "thermometers.fog.lag_s",
             "effects.tec_power.c_h", "effects.shupe_gradient.k_r",
             "effects.bias_temperature.b1")


def main() -> None:
    sc = load_scenario()
    inst = sc.instrument
    truth = set_params(inst, {p: 1.2 * get_param(inst, p) for p in PERTURBED})
    runs = [simulate_run(truth, c).run for c in sc.conditions()]
    best, result = float("inf"), None
    for _ in range(3):
        t0 = time.perf_counter()
        result = fit_model(inst, runs)
        best = min(best, time.perf_counter() - t0)
    samples = sum(r.n_samples for r in runs)
    n_free = len(default_free(inst))
    print(f"fit_model: {len(runs)} runs ({samples} samples), {n_free} free parameters, "
          f"both stages: {best:.2f} s (target < {TARGET_S:g} s; ratio {best / TARGET_S:.2f}, "
          f"{TARGET_S / best:.1f}x under target)")
    for name, rep in result.stages.items():
        print(f"  {name}: {len(rep.free)} parameters, {rep.nfev} evaluations, "
              f"{rep.n_residuals} residuals, {rep.time_s:.2f} s, "
              f"{'converged' if rep.converged else 'NOT converged'}")
    for p in PERTURBED:
        print(f"  {p}: truth {get_param(truth, p):.6g}, fitted {result.params[p]:.6g} "
              f"+- {result.stderr[p]:.2g}")


if __name__ == "__main__":
    main()
