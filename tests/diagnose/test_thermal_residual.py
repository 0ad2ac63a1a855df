"""The thermal stage's residual solved for a stack of instruments, and its Jacobian.

Oracles: a stack gives every instrument the bits it gets alone; the lag stepped from knot to
knot equals the lag run over the full-rate record (the simulator's own chain); the
stacked forward differences equal scipy's ``2-point`` ones; a fit with them lands where
scipy's own finite differences land.  Runs from the independent generator (not our
simulator), short.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.optimize._numdiff import approx_derivative

import thermal
from independent import generator as g
from nfs.fit.free_set import default_free
from nfs.fit.params import get_param, set_params
from nfs.fit.stage import FTOL, XTOL, forward_jacobian, solve_stage
from nfs.fit.thermal_residual import (StatefulLaw, prepare_thermal, simulate_knots,
                                           thermal_residual_parts)
from nfs.effects import make_effect
from nfs.errors import NfsError
from nfs.heat import thermal_power
from nfs.instrument import load_instrument
from nfs.io.measurement import read_runs


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = tmp_path_factory.mktemp("indep")
    g.generate_set(out, seed=4, start_temperatures_c=(-20.0, 40.0), duration_s=1800.0)
    return read_runs(out)


@pytest.fixture(scope="module")
def models():
    """The default instrument and every default-free thermal parameter moved by 10 %."""
    inst = load_instrument("default")
    free = default_free(inst, ("thermal",))
    return [inst] + [set_params(inst, {p: 1.1 * get_param(inst, p) + 0.01}) for p in free]


def _same(a, b):
    for col in a:
        for x, y in zip(a[col], b[col]):
            np.testing.assert_array_equal(x, y)


def test_a_stack_gives_each_instrument_its_own_bits(runs, models):
    data = [prepare_thermal(r, 10.0) for r in runs]
    stacked = thermal_residual_parts(models, data)
    assert len(stacked) == len(models)
    for m, parts in zip(models, stacked):
        _same(parts, thermal_residual_parts([m], data)[0])
    # and the models differ: the stack did not hand one answer to all
    assert not np.array_equal(stacked[0]["temp_fog_c"][0], stacked[1]["temp_fog_c"][0])


def test_stacked_march_is_thermal_simulate(runs, models):
    """Oracle: thermal.simulate of each instrument on the knots (the TEC law through
    nfs.experiment.thermal_power), to 1e-9 K."""
    data = [prepare_thermal(r, 10.0) for r in runs]
    knots = simulate_knots(models[:4], data)
    for s, m in enumerate(models[:4]):
        for rd, k in zip(data, knots[s]):
            power, _, _ = thermal_power(m, rd.t_knot, rd.moving_knot)
            ref = thermal.simulate(m.network, rd.t_knot, ambient_c=rd.ambient_knot,
                                   initial_c=rd.t0_c, power_w=power)
            assert np.max(np.abs(k.temperature_c - ref.temperature_c)) < 1e-9
            assert np.max(np.abs(k.rate_c_per_s - ref.rate_c_per_s)) < 1e-9


def test_a_stack_must_share_its_effects_nodes(runs, models):
    """Instruments whose thermal effects sit on other nodes cannot share a march."""
    data = [prepare_thermal(r, 10.0) for r in runs]
    inst = models[0]
    a, b = (inst.with_effects(list(inst.effects) + [make_effect(
        "heat_source", {"node": node, "power": 1.0})]) for node in ("board", "housing"))
    with pytest.raises(NfsError, match="same node"):
        simulate_knots([a, b], data)


def test_non_uniform_knots_are_solved_run_by_run(runs, models):
    """A run whose time base is not uniform takes thermal.simulate per instrument; the
    stack still gives each instrument its own answer."""
    data = [prepare_thermal(r, 10.0) for r in runs]
    rd = data[0]
    t = rd.t_knot.copy()
    t[5:] += 0.5    # one longer step
    data[0] = dataclasses.replace(rd, t_knot=t)
    knots = simulate_knots(models[:3], data)
    for s, m in enumerate(models[:3]):
        alone = simulate_knots([m], data)[0]
        for a, b in zip(knots[s], alone):
            np.testing.assert_array_equal(a.temperature_c, b.temperature_c)


def test_knot_stepped_lag_equals_the_full_rate_lag(runs, models):
    """Oracle: the same readings with the lag run over the 1 Hz record (per_knot = 0
    forces that path), to 1e-9 K; with a long thermometer lag too."""
    data = [prepare_thermal(r, 10.0) for r in runs]
    slow = [set_params(m, {"thermometers.fog.lag_s": 400.0}) for m in models[:2]]
    for insts in (models[:4], slow):
        fast = thermal_residual_parts(insts, data)
        full = thermal_residual_parts(insts, [dataclasses.replace(d, per_knot=0)
                                              for d in data])
        for a, b in zip(fast, full):
            for col in a:
                for x, y in zip(a[col], b[col]):
                    assert np.max(np.abs(x - y)) < 1e-9
    assert all(d.per_knot == 10 for d in data)


def test_thermometer_effect_takes_the_full_rate_path(runs, models):
    """A thermometer effect (an extra lag) is applied on the full-rate record, record by
    record; its readings lag the plain ones."""
    data = [prepare_thermal(r, 10.0) for r in runs]
    inst = models[0]
    lagged = inst.with_effects(list(inst.effects) + [make_effect(
        "thermometer_lag", {"thermometer": "fog", "tau": 120.0})])
    both = thermal_residual_parts([inst, lagged], data)
    _same(both[1], thermal_residual_parts([lagged], data)[0])
    d_plain = both[0]["temp_fog_c"][0]
    d_lag = both[1]["temp_fog_c"][0]
    assert np.max(np.abs(d_plain - d_lag)) > 0.01   # the unit warms: a lag reads colder


def test_state_law_for_scalars_only():
    """A user's law that takes scalars only is called per run; one that takes arrays but not
    array parameters is called per instrument; both give the elementwise values."""
    def scalar_law(t, temperature, moving, *, c):
        if temperature > 25.0:        # fails on arrays
            return c * (temperature - 25.0)
        return 0.0

    def array_law(t, temperature, moving, *, c):
        return float(c) * np.maximum(0.0, np.asarray(temperature) - 25.0)  # float(array) fails

    temp = np.array([[20.0, 30.0, 40.0], [26.0, 10.0, 50.0]])
    mv = np.zeros(3)
    want = np.array([[0.0, 5.0, 15.0], [0.2, 0.0, 5.0]])
    for f, mode in ((scalar_law, "per run"), (array_law, "per instrument")):
        law = StatefulLaw(f, [{"c": 1.0}, {"c": 0.2}], 3)
        np.testing.assert_allclose(law(0.0, temp, mv, np.tile(mv, 2)), want, rtol=1e-15)
        assert law.mode == mode

    def named_law(t, temperature, moving, *, c, curve):  # a parameter that is no number
        return (c if curve == "linear" else 2 * c) * np.maximum(0.0, temperature - 25.0)

    law = StatefulLaw(named_law, [{"c": 1.0, "curve": "linear"},
                                   {"c": 0.1, "curve": "double"}], 3)
    assert law.mode == "per instrument"
    np.testing.assert_allclose(law(0.0, temp, mv, np.tile(mv, 2)), want, rtol=1e-15)


def test_forward_jacobian_is_scipys_two_point():
    """Oracle: scipy.optimize._numdiff.approx_derivative('2-point') with the same bounds,
    including a parameter on its upper bound (the step turns back) and one at 0."""
    def fun(x):
        t = np.linspace(0.0, 3.0, 40)
        return x[0] * np.exp(-x[1] * t) + x[2] * t ** 2 - np.sin(x[3] * t)

    def batch(xs):
        return [fun(x) for x in xs]

    x = np.array([1.5, 0.7, 0.0, 2.0])
    lb, ub = np.array([0.0, 0.1, -1.0, 0.0]), np.array([5.0, 0.7, 1.0, 10.0])
    want = approx_derivative(fun, x, method="2-point", bounds=(lb, ub))
    np.testing.assert_array_equal(forward_jacobian(batch, x, lb, ub), want)
    np.testing.assert_array_equal(forward_jacobian(batch, x, lb, ub, f0=fun(x)), want)


def test_solve_stage_with_a_batch_lands_where_scipy_lands():
    """The same minimum as least_squares with its own finite differences (a bounded
    exponential fit with a prior-free stage), with the stage's termination tolerances
    (xtol = ftol = nfs.fit.stage.FTOL) on the same path to 1e-7."""
    t = np.linspace(0.0, 5.0, 60)
    rng = np.random.default_rng(0)
    y = 2.0 * np.exp(-0.8 * t) + 0.3 + 0.01 * rng.standard_normal(t.size)

    def fun(x):
        return x[0] * np.exp(-x[1] * t) + x[2] - y

    lb, ub = np.array([0.0, 0.0, -1.0]), np.array([10.0, 5.0, 1.0])
    x0 = np.array([1.0, 0.3, 0.0])
    a = solve_stage("thermal", fun, x0, lb, ub, 200, ["a", "k", "c"])[0]
    b = solve_stage("thermal", fun, x0, lb, ub, 200, ["a", "k", "c"],
                    batch=lambda xs: [fun(x) for x in xs])[0]
    ref = least_squares(fun, x0, bounds=(lb, ub), method="trf", x_scale="jac", ftol=FTOL,
                        xtol=XTOL)
    np.testing.assert_allclose(b.x, a.x, rtol=1e-7)
    np.testing.assert_allclose(b.x, ref.x, rtol=1e-7)
    assert math.isclose(b.cost, ref.cost, rel_tol=1e-10)
