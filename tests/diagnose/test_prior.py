"""The table of ranges as a Gaussian prior of the fit (nfs.fit.prior, fit_model's prior=).

Oracles: the documented rule (a capacity of typical range 40-100 J/K: log-normal of median
sqrt(40 x 100) and sigma ln(100/40)/2 on the log; a magnitude of typical |x| <= hi: 0 +- hi),
the closed form of the prior rows ((ln x - ln p0) / sigma, (x - p0) / sigma); the same prior
whatever the start (a chain of fits cannot walk); a node no thermometer sees (a bracket
hung on the housing by 0.01 W/K) whose capacity the unregularised fit sends to its bound
(a known failure, checked here so that the contrast is real) and the MAP fit keeps within one
prior width of the preset; with the prior switched off, the fit is plain least squares on the
data rows (scipy.optimize.least_squares run directly on the thermal residual).
"""

import dataclasses
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import least_squares

from thermal import Link, Network, Node

from nfs.fit.calibration import fit_model
from nfs.fit.thermal_residual import prepare_thermal, thermal_residual_parts
from nfs.fit.params import get_param, set_params
from nfs.fit.prior import PRIOR_WIDTHS, build_prior
from nfs.errors import NfsError
from nfs.experiment import simulate_run
from nfs.config.scenario import load_scenario
from nfs.instrument import load_instrument


def lumped_world():
    """The default scenario's nominal world with the lumped-coil preset (``nfs preset
    lumped``: two coil nodes), on which this module's figures were measured."""
    return dataclasses.replace(load_scenario().nominal(), instrument=load_instrument("lumped"))


@pytest.fixture(scope="module")
def scenario():
    return lumped_world()


def test_table_widths(scenario):
    inst = scenario.instrument
    paths = ["thermal.nodes.coil_outer.capacity_j_per_k", "thermometers.fog.offset_c",
             "effects.shupe_gradient.k_r", "accelerometers.bias_x_g"]
    start = {p: get_param(inst, p) for p in paths}
    pr = build_prior(inst, paths, start)
    # coil_outer 40-100 J/K (log-normal); offset |x| <= 0.5 K, k_r |x| 0.1-1, bias |x| <= 4 mg
    np.testing.assert_allclose(pr.sigma, [math.log(100 / 40) / 2, 0.5, 1.0, 0.004])
    np.testing.assert_allclose(pr.centre, [math.sqrt(40 * 100), 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(pr.is_log, [True, False, False, False])
    # the prior does not depend on where the fit starts: a chain of fits meets the same one
    moved = {**start, "thermal.nodes.coil_outer.capacity_j_per_k": 9.5,
             "effects.shupe_gradient.k_r": -3.0}
    again = build_prior(inst, paths, moved)
    np.testing.assert_array_equal(again.centre, pr.centre)
    np.testing.assert_array_equal(again.sigma, pr.sigma)
    # overrides (centred on the start value): absolute, relative, and a global scale
    pr2 = build_prior(inst, paths, start, {"thermometers.*.offset_c": 0.1,
                                           "thermal.nodes.*": "20%"}, prior_scale=2.0)
    np.testing.assert_allclose(pr2.sigma, [2 * 0.2 * 95.0, 0.2, 2.0, 0.008])
    np.testing.assert_allclose(pr2.centre[:2], [95.0, 0.0])
    # the rows: on the log for the capacity (one sigma up: x = median e^sigma)
    sig = math.log(2.5) / 2
    x = np.array([math.sqrt(4000) * math.exp(sig), -0.25, 0.0, 0.008])
    np.testing.assert_allclose(pr.rows(x), [1.0, -0.5, 0.0, 2.0])
    assert pr.shift(x)["thermometers.fog.offset_c"] == pytest.approx(-0.5)
    # the Jacobian of a log row is 1 / (x sigma); a linear row's 1 / sigma
    np.testing.assert_allclose(np.diag(pr.jacobian(x)),
                               [1 / (x[0] * sig), 1 / 0.5, 1.0, 1 / 0.004])
    # a width in the parameter's unit: the half-width of the one-sigma band, which for the
    # geometric centre is half the typical range exactly
    assert pr.linear_sigma()[0] == pytest.approx((100 - 40) / 2)
    assert all(w.reason for w in PRIOR_WIDTHS.values())
    with pytest.raises(NfsError, match="thermometers.fog.offset_c"):
        build_prior(inst, paths, start, {"thermometers.fog.offset_c": -1.0})
    with pytest.raises(NfsError, match="prior_scale"):
        build_prior(inst, paths, start, prior_scale=0.0)


def test_drawing_and_unknown_parameters_keep_the_start_centred_prior(scenario):
    inst = load_instrument("default")
    paths = ["coil.outer_radius_m"]
    start = {p: get_param(inst, p) for p in paths}
    pr = build_prior(inst, paths, start)
    assert pr.centre[0] == start[paths[0]]
    assert pr.sigma[0] == pytest.approx(0.05 * start[paths[0]])


def test_unseen_capacity_stays_at_its_prior(scenario):
    inst = scenario.instrument
    net = inst.network
    inst = replace(inst, network=Network(nodes=net.nodes + (Node("bracket", 60.0, 0.0),),
                                         links=net.links + (Link("bracket", "housing", 0.01),)))
    conds = [replace(c, duration_s=1800.0) for c in scenario.conditions()[:2]]
    runs = [simulate_run(inst, c).run for c in conds]
    free = ["thermal.nodes.bracket.capacity_j_per_k", "thermal.nodes.coil_inner.capacity_j_per_k",
            "thermometers.fog.lag_s"]
    bracket = "thermal.nodes.bracket.capacity_j_per_k"
    # soaked exactly (the nominal world), and the fit is told so: a start free per run would
    # take up part of what the bracket's capacity does to the first half hour
    plain = fit_model(inst, runs, free, stages=("thermal",), prior=None, start_state=None)
    assert bracket in plain.at_bound          # the failure the prior is there to prevent
    res = fit_model(inst, runs, free, stages=("thermal",), start_state=None)
    assert res.at_bound == ()
    assert abs(res.prior_shift[bracket]) <= 1.0
    # a node of a north finder: 10-10000 J/K, log-normal (a weak prior, wide in J/K)
    assert res.prior_sigma[bracket] == pytest.approx(math.sqrt(1e5) * math.sinh(math.log(1000) / 2))
    # the posterior is never wider than the prior, and the seen parameters barely move
    assert res.stderr[bracket] <= res.prior_sigma[bracket]
    for p in free[1:]:
        assert abs(res.params[p] - get_param(inst, p)) <= 3 * res.stderr[p]


def test_no_prior_is_plain_least_squares(scenario):
    inst = scenario.instrument
    cond = replace(scenario.conditions()[0], duration_s=1800.0)
    truth = set_params(inst, {"thermometers.fog.lag_s": 40.0,
                              "thermal.nodes.coil_outer.capacity_j_per_k": 110.0})
    runs = [simulate_run(truth, cond).run]
    free = ["thermometers.fog.lag_s", "thermal.nodes.coil_outer.capacity_j_per_k"]
    off = fit_model(inst, runs, free, stages=("thermal",), prior_scale=math.inf, n_starts=1)
    none = fit_model(inst, runs, free, stages=("thermal",), prior=None, n_starts=1)
    assert off.params == none.params and off.stderr == none.stderr
    assert off.prior_shift == {} and off.stages["thermal"].n_prior == 0
    # the unregularised objective, solved directly
    data = [prepare_thermal(r, 10.0) for r in runs]

    def fun(x):
        parts = thermal_residual_parts([set_params(inst, dict(zip(free, x)))], data)[0]
        return np.concatenate([a for arrs in parts.values() for a in arrs])

    x0 = np.array([get_param(inst, p) for p in free])
    ref = least_squares(fun, x0, bounds=([0, 9.5], [300, 950]), method="trf", x_scale="jac")
    for p, v in zip(free, ref.x):
        assert abs(off.params[p] - v) <= 0.05 * off.stderr[p], p



def test_bad_prior_arguments(scenario):
    inst = scenario.instrument
    run = simulate_run(inst, replace(scenario.conditions()[0], duration_s=60.0)).run
    with pytest.raises(NfsError, match="prior must be"):
        fit_model(inst, [run], ["thermometers.fog.lag_s"], stages=("thermal",), prior="wide")
    with pytest.raises(NfsError, match="n_starts"):
        fit_model(inst, [run], ["thermometers.fog.lag_s"], stages=("thermal",), n_starts=0)
