"""Speed of ``fit_model`` on the built-in default scenario.

Run as ``python benchmarks/bench_fit.py``.  Simulates the 7 default runs (2.5 h each at
1 Hz) from the default instrument with six parameters perturbed by +20 % (the runs of
tests/diagnose/test_fit.py), then fits the unperturbed default to them with the default
free set, both stages and the default options (the preset as a prior, the soak anchor of the
thermometer offsets, the level start, extra thermal starts when needed, the gyro noise from
the Allan deviation of the residual), best of 3.  Target: under 20 s on the 2-core machine.
The same fit without the prior, the extra starts and the noise fit (the plain least squares
of before) is timed beside it.

Then the same on runs the model did not make, the case of a real unit: the 7 start-ups of
the independent generator (``tests/independent/generator.py``, seed 1, nothing hidden),
fitted from the default instrument with the effects the generator's unit has in kind.  The
thermal stage's residual then stays above its noise, so the extra starts run and the
forward-difference Jacobians are most of the work; beside the fit's time, one Jacobian of
the thermal residual solved as one stack of the n + 1 parameter vectors (as the fit does,
:mod:`nfs.fit.thermal_residual`) against the same n + 1 residuals solved one by one.
"""

from __future__ import annotations

import sys
import tempfile
import time
import warnings
from pathlib import Path

from timing import best_of

from nfs.fit.calibration import fit_model
from nfs.fit.free_set import default_free
from nfs.fit.params import get_param, set_params
from nfs.fit.thermal_residual import prepare_thermal, thermal_residual_parts
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.io.measurement import read_runs
from nfs.config.scenario import load_scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "independent"))
from generator import generate_set  # noqa: E402

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
    results = []
    best = best_of(lambda: results.append(fit_model(inst, runs)))
    result = results[-1]
    plain = best_of(lambda: fit_model(inst, runs, prior=None, n_starts=1, fit_noise=False))
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
    independent()


def independent() -> None:
    """The fit on the independent generator's runs; one thermal Jacobian stacked vs not."""
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as tmp:
        generate_set(tmp, seed=1)
        runs = read_runs(tmp)
    inst = load_instrument("default")
    inst = inst.with_effects([e for e in inst.effects if e.name in (
        "tec_power", "bias_temperature", "shupe_gradient", "shupe_rate")])
    t0 = time.perf_counter()
    result = fit_model(inst, runs)
    t_fit = time.perf_counter() - t0
    rep = result.stages["thermal"]
    print(f"fit_model on the independent generator's 7 runs: {t_fit:.1f} s (target < "
          f"{TARGET_S:g} s; ratio {t_fit / TARGET_S:.2f}); thermal stage {rep.time_s:.1f} s, "
          f"{rep.nfev} evaluations from {rep.n_starts} start(s), reduced chi-square "
          f"{rep.noise_scale ** 2:.1f}")
    data = [prepare_thermal(r, 10.0) for r in runs]
    free = default_free(inst, ("thermal",))
    models = [inst] + [set_params(inst, {p: get_param(inst, p) * (1 + 1.5e-8)}) for p in free]
    stacked = best_of(lambda: thermal_residual_parts(models, data))
    alone = best_of(lambda: [thermal_residual_parts([m], data) for m in models])
    print(f"  one thermal Jacobian ({len(models)} residuals): stacked {stacked * 1e3:.0f} ms, "
          f"one by one {alone * 1e3:.0f} ms (stacked {alone / stacked:.1f}x faster)")


if __name__ == "__main__":
    main()
