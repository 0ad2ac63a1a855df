"""Each run's start estimated with the fit (nfs.fit.start_state).

Oracles: the free modes of a network satisfy A v = -v / tau (an eigenvector), and the fast
remainder u is C-orthogonal to the slow modes with 1 in the span of [v_1, u]; an unpowered
soak from T_from for t_soak leaves expm(A t_soak) (T_from - T0) 1 (the closed form of the
homogeneous linear system); the amplitudes' solve is the least-squares solution of the
augmented system [G; diag(1/w)] a = [-r0; c/w]; runs started at a known state along the
basis are recovered by the fit; and the package's own default world (unfinished soaks, a
wandering chamber, unit scatter) fits its thermometers within 1.5x their noise floor
sqrt(0.01^2 + 0.0625^2 / 12) = 0.0206 K, where a fit that starts every run at T0 is several
times above it.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.linalg import expm

from nfs.diagnose.missing_effect import diagnose
from nfs.fit.calibration import fit_model
from nfs.fit.refine import fit_unit
from nfs.fit.start_state import (FAST_WIDTH_C, SLOW_WIDTH_C, StartModel, solve_amplitudes,
                                      soak_history, start_basis, start_prior)
from nfs.fit.thermal_residual import (prepare_thermal, start_states, thermal_residual,
                                           thermometer_floors)
from nfs.errors import InputError
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.config.scenario import load_scenario

FLOOR_K = math.hypot(0.01, 0.0625 / math.sqrt(12.0))


@pytest.fixture(scope="module")
def default():
    return load_instrument("default")


def test_modes_are_eigenvectors(default):
    net = default.network
    taus, v = net.modes()
    a, _ = net.matrices()
    assert np.all(np.diff(taus) <= 0)                      # longest first
    for i in range(v.shape[1]):
        np.testing.assert_allclose(a @ v[:, i], -v[:, i] / taus[i], atol=1e-12)
        assert np.max(np.abs(v[:, i])) == pytest.approx(1.0)
    np.testing.assert_allclose(taus, net.time_constants_s(), rtol=1e-10)


def test_basis_slow_mode_and_fast_remainder(default):
    net = default.network
    basis = start_basis(net, 1, fast=True)
    c = net.capacity_j_per_k
    v1, u = basis[:, 0], basis[:, 1]
    assert abs(v1 @ (c * u)) < 1e-9 * np.sum(c)             # C-orthogonal
    coef, *_ = np.linalg.lstsq(basis, np.ones(c.size), rcond=None)
    np.testing.assert_allclose(basis @ coef, 1.0, atol=1e-12)  # a uniform offset is in the span
    # a unit set off its air puts nearly all of it on the slow mode
    assert abs(coef[0]) > 5 * abs(coef[1])
    assert start_basis(net, 1).shape == (c.size, 1)


def test_soak_history_prior_is_the_closed_form(default):
    net = default.network
    basis = start_basis(net, 1, fast=True)
    model = StartModel(fast=True)
    t0, t_from, hours = -32.0, 23.0, 4.0
    centre, width = start_prior(net, basis, t0, (t_from, hours), model)
    a, _ = net.matrices()
    dev = expm(a * 3600.0 * hours) @ np.full(a.shape[0], t_from - t0)
    # after 4 h only the slow mode is left: the projection reproduces the deviation
    np.testing.assert_allclose(basis @ centre, dev, atol=2e-3 * np.max(np.abs(dev)))
    assert 0.1 < centre[0] < 1.0                            # a few tenths of a kelvin at -32 C
    assert width[0] == pytest.approx(max(0.5 * abs(centre[0]), 0.2))
    # no history: zero centre, the default widths
    c0, w0 = start_prior(net, basis, t0, None, model)
    np.testing.assert_array_equal(c0, 0.0)
    np.testing.assert_array_equal(w0, [SLOW_WIDTH_C, FAST_WIDTH_C])


def test_amplitudes_solve_the_augmented_least_squares():
    rng = np.random.default_rng(3)
    g = rng.normal(size=(50, 2))
    r0 = rng.normal(size=50)
    centre, width = np.array([0.3, -0.1]), np.array([1.0, 0.1])
    a = solve_amplitudes(r0, g, centre, width)
    big = np.vstack([g, np.diag(1.0 / width)])
    rhs = np.concatenate([-r0, centre / width])
    want, *_ = np.linalg.lstsq(big, rhs, rcond=None)
    np.testing.assert_allclose(a, want, rtol=1e-12)


def test_soak_history_keys(default):
    sc = load_scenario().nominal()
    cond = dataclasses.replace(sc.conditions()[0], duration_s=600.0)
    run = simulate_run(default, cond).run
    assert soak_history(run) is None
    meta = dataclasses.replace(run.meta, extra={"soak_from_c": 22.0, "soak_h": 3.5})
    assert soak_history(dataclasses.replace(run, meta=meta)) == (22.0, 3.5)
    for extra, key in (({"soak_from_c": 22.0}, "soak_h"), ({"soak_from_c": 22.0, "soak_h": -1},
                                                          "soak_h"),
                       ({"soak_from_c": "warm", "soak_h": 2.0}, "soak_from_c")):
        bad = dataclasses.replace(run, meta=dataclasses.replace(run.meta, extra=extra))
        with pytest.raises(InputError, match=key):
            soak_history(bad)


def test_simulated_unfinished_soak_records_its_history(default):
    """The default scenario's unfinished soaks write the laboratory's temperature and the
    drawn soak time into the sidecar, as a laboratory log would."""
    sc = load_scenario()
    cond = dataclasses.replace(sc.conditions()[0], duration_s=60.0)
    run = simulate_run(sc.instrument, cond).run
    t_from, hours = soak_history(run)
    assert t_from == sc.variability.soak_from_c
    assert 0.5 * sc.variability.soak_h < hours < 2.0 * sc.variability.soak_h


def test_known_starts_are_recovered():
    """Runs started at T0 + a_1 v_1 + b u (soak-history-free) with the model's own
    parameters: the profiled amplitudes (u freed) come back to within 10 mK and the
    residual sits at the floor; started at T0 the same runs miss by far more.  On the
    lumped-coil preset: a wound coil's share of u decays in seconds, before the first 10 s
    knot, so its b is not seen there (the fit's start is, which is what the fit needs)."""
    default = load_instrument("lumped")
    sc = load_scenario().nominal()
    basis = start_basis(default.network, 1, fast=True)
    truth = {-32.0: (0.6, 0.05), 17.0: (-0.3, -0.04), 54.0: (-0.45, 0.08)}
    runs = []
    for cond in sc.conditions():
        if cond.start_temperature_c in truth:
            start = cond.start_temperature_c + basis @ np.array(truth[cond.start_temperature_c])
            runs.append(simulate_run(default, dataclasses.replace(
                cond, duration_s=3600.0, initial_c=start)).run)
    data = [prepare_thermal(r, 10.0) for r in runs]
    res = thermal_residual([default], data, StartModel(fast=True))
    for i, run in enumerate(runs):
        want = truth[run.meta.start_temperature_c]
        np.testing.assert_allclose(res.amplitudes_c[0][i], want, atol=0.01)
    floors = thermometer_floors(default)
    for col, parts in res.parts[0].items():
        x = np.concatenate(parts)
        assert np.sqrt(np.mean(x * x)) < 1.1 * floors[col], col
    soaked = thermal_residual([default], data, None).parts[0]
    x = np.concatenate(soaked["temp_fog_c"])
    assert np.sqrt(np.mean(x * x)) > 3 * floors["temp_fog_c"]
    states = start_states(default, runs, start=StartModel(fast=True))
    np.testing.assert_allclose(states[runs[0].name], res.start_c[0][0])


@pytest.fixture(scope="module")
def realistic_runs():
    """The default scenario (realistic variability), seed 11: what `nfs simulate
    scenarios/startup_7temps.toml -o runs --seed 11` writes."""
    sc = dataclasses.replace(load_scenario(), seed=11)
    sims = [simulate_run(sc.instrument, c) for c in sc.conditions()]
    return sc.instrument, sims


def test_default_world_fits_its_thermometers(realistic_runs):
    inst, sims = realistic_runs
    runs = [s.run for s in sims]
    fit = fit_model(inst, runs, stages=("thermal",))
    for col in ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c"):
        assert fit.rms_after[col] < 1.5 * FLOOR_K, (col, fit.rms_after[col])
    assert fit.at_bound == ()
    assert set(fit.start_c) == {r.name for r in runs}
    # every capacity stays within 2 prior widths of the preset (it was pushed 6 away, or to a
    # bound, when every run started at T0)
    for p, shift in fit.prior_shift.items():
        if p.endswith("capacity_j_per_k"):
            assert abs(shift) < 2.0, (p, shift)
    # the slow amplitudes hold the truth's starts (the unit's own network, projected on the
    # model's slow mode: the unfinished soak from 23 C plus each start's common offset, 0.68 K
    # at -32 C, -0.18 K at 43 C, +0.14 K at 54 C on this seed) from run to run within 0.05 K;
    # their common part trades with the thermometer offsets (measured: +0.17 K here, the
    # offsets 0.15 K low), within 0.25 K
    basis = start_basis(inst.network, 1)
    err = []
    for sim in sims:
        dev = sim.thermal.temperature_c[0] - sim.run.meta.start_temperature_c
        truth, *_ = np.linalg.lstsq(basis, dev, rcond=None)
        err.append(fit.start_amplitudes_c[sim.run.name][0] - truth[0])
    err = np.array(err)
    assert np.all(np.abs(err - err.mean()) < 0.05), err
    assert abs(err.mean()) < 0.25, err
    soaked = fit_model(inst, runs, stages=("thermal",), start_state=None, n_starts=1)
    assert soaked.rms_after["temp_fog_c"] > 3 * FLOOR_K


def _clean_set(seed):
    """What `nfs simulate scenarios/startup_7temps.toml -o runs --seed S`, `nfs fit` and
    `nfs diagnose` give on the default world: (diagnosis, thermal structure adequate)."""
    sc = dataclasses.replace(load_scenario(), seed=seed)
    runs = [simulate_run(sc.instrument, c).run for c in sc.conditions()]
    fit = fit_unit(sc.instrument, runs)
    d = diagnose(fit.instrument, runs)
    return d, d.thermal_structure.adequate


@pytest.mark.integration       # simulate, fit and diagnose the default world's 7 runs
def test_the_default_world_names_nothing():
    """Oracle: the model's structure is the truth's (nothing is missing), with every run's
    soak unfinished, the chamber wandering and the unit's parameters scattered: no effect is
    named and the thermal structure is adequate (seed 11, where starting every run at T0 had
    answered "add shupe_rate:electronics" and called the structure inadequate at 5-10x the
    floor).  Measured on this seed with the wound coil: "nothing beyond noise", the worst
    thermometer 1.02x its floor held out; the slow test below runs seeds 11-20 (10 of 10
    "nothing")."""
    d, adequate = _clean_set(11)
    assert d.answer.kind in ("nothing", "tie"), d.verdict
    assert adequate


@pytest.mark.slow
def test_ten_clean_sets_of_the_default_world():
    """Seeds 11-20: "nothing beyond noise" on at least 9, the structure adequate on at least
    9 (measured with benchmarks/bench_false_alarm.py --seed0 11 --sets 10: 10 and 10)."""
    out = [_clean_set(s) for s in range(11, 21)]
    assert sum(d.answer.kind == "nothing" for d, _ in out) >= 9, [d.verdict for d, _ in out]
    assert sum(ok for _, ok in out) >= 9
