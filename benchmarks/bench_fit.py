"""Speed of ``fit_model`` on the built-in default scenario.

Run as ``python benchmarks/bench_fit.py``.  Simulates the 7 default runs (2.5 h each at
1 Hz) from the default instrument with six parameters perturbed by +20 % (the runs of
tests/diagnose/test_fit.py), then fits the unperturbed default to them with the default
free set, both stages and the default options (the preset as a prior, the soak anchor of the
thermometer offsets, the level start, extra thermal starts when needed, the gyro noise from
the Allan deviation of the residual), best of 3.  Target: under 20 s on the 2-core machine.
The same fit without the prior, the extra starts and the noise fit (the plain least squares
of before) is timed beside it.
"""

from __future__ import annotations

import time

from nfs.diagnose.fit import default_free, fit_model
from nfs.diagnose.params import get_param, set_params
from nfs.experiment import simulate_run
from nfs.io.scenario import load_scenario

TARGET_S = 20.0
PERTURBED = ("thermal.nodes.coil_inner.capacity_j_per_k",
             "thermal.links.housing-chamber.conductance_w_per_k", "thermometers.fog.lag_s",
             "effects.tec_power.c_h", "effects.shupe_gradient.k_r",
             "effects.bias_temperature.b1")


def main() -> None:
    sc = load_scenario().nominal()
    inst = sc.instrument
    truth = set_params(inst, {p: 1.2 * get_param(inst, p) for p in PERTURBED})
    runs = [simulate_run(truth, c).run for c in sc.conditions()]
    best, result = float("inf"), None
    for _ in range(3):
        t0 = time.perf_counter()
        result = fit_model(inst, runs)
        best = min(best, time.perf_counter() - t0)
    plain = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        fit_model(inst, runs, prior=None, n_starts=1, fit_noise=False)
        plain = min(plain, time.perf_counter() - t0)
    samples = sum(r.n_samples for r in runs)
    n_free = len(default_free(inst))
    print(f"fit_model: {len(runs)} runs ({samples} samples), {n_free} free parameters, "
          f"both stages: {best:.2f} s (target < {TARGET_S:g} s; ratio {best / TARGET_S:.2f}, "
          f"{TARGET_S / best:.1f}x under target)")
    print(f"  without prior, extra starts and noise fit: {plain:.2f} s")
    for name, rep in result.stages.items():
        print(f"  {name}: {len(rep.free)} parameters, {rep.nfev} evaluations from "
              f"{rep.n_starts} start(s), {rep.n_residuals} residuals + {rep.n_prior} prior "
              f"rows, {rep.time_s:.2f} s, {'converged' if rep.converged else 'NOT converged'}")
    for p in PERTURBED:
        print(f"  {p}: truth {get_param(truth, p):.6g}, fitted {result.params[p]:.6g} "
              f"+- {result.stderr[p]:.2g} ({result.prior_shift[p]:+.2f} prior widths)")
    n = result.noise
    print(f"  gyro noise: N {n.arw_deg_per_rth_h:.3g} deg/sqrt(h) (truth "
          f"{truth.gyro.arw_deg_per_rth_h:g}), B {n.bias_instability_dph:.3g} deg/h (truth "
          f"{truth.gyro.bias_instability_dph:g})")
    print(f"  at bound: {', '.join(result.at_bound) or 'none'}")


if __name__ == "__main__":
    main()
