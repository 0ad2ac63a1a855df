"""Rival models: each explanation fitted to the runs, with its parameter uncertainty.

Runs: three short start-ups (1 h at 1 Hz; -16, 17 and 43 C; nominal world) of the default
instrument with a 0.5 W heat source at coil_inner; the model is the default instrument.
Oracles: what each kind of rival adds to the model (one more node, a rate term per node,
the effect), the heat source's fitted power within three standard errors of the truth, and the draws' sample
statistics against the fit's own standard errors and correlations (2000 draws).
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

import nfs
from nfs.diagnose import Answer
from nfs.rivals import MODEL, RATE_ALTERNATIVE, rival_model
from nfs.rivals.finding import rivals_of
from nfs.rivals.models import _drift_cost, unseen_nodes
from nfs.fit.stage import StageReport
from nfs.effects import make_effect
from nfs.errors import NfsError


@pytest.fixture(scope="module")
def world():
    model = nfs.load_instrument("lumped")      # two coil nodes: coil_inner is unseen
    truth = model.with_effects(list(model.effects) + [
        make_effect("heat_source", {"node": "coil_inner", "power": 0.5})])
    sc = nfs.load_scenario().nominal()
    runs = [nfs.simulate_run(truth, dataclasses.replace(sc.conditions()[i], duration_s=3600.0)).run
            for i in (1, 3, 5)]
    return model, runs


def test_each_kind_of_rival_adds_its_explanation(world):
    model, runs = world
    heat = rival_model(model, runs, "heat_source:coil_inner", start_state=None)
    assert any(e.label == "heat_source:coil_inner" for e in heat.instrument.effects)
    # no thermometer reads coil_inner (unseen_heat_rival: fitted from the thermometers and
    # from the drift, the lower joint cost kept; here the thermometers' fit); three 1 h runs
    # determine the power loosely (0.29 +- 0.14 W measured; 0.52 +- 0.06 W from 2.5 h runs):
    # the truth within three of the fit's standard errors
    p = "effects.heat_source:coil_inner.power"
    assert abs(heat.fit.params[p] - 0.5) < 3.0 * heat.fit.stderr[p] < 0.6
    assert heat.fit.params[p] >= 0.0 and heat.n_added == 1 and heat.thermal_refit
    rate = rival_model(model, runs, RATE_ALTERNATIVE, start_state=None)
    labels = {e.label for e in rate.instrument.effects}
    assert {f"shupe_rate:{n}" for n in model.network.node_names if n != "coil_inner"} <= labels \
        or {f"shupe_rate:{n}" for n in model.network.node_names} <= labels
    node = rival_model(model, runs, "insert node coil_outer-housing", start_state=None)
    assert len(node.instrument.network.node_names) == len(model.network.node_names) + 1
    same = rival_model(model, runs, MODEL, start_state=None)
    assert same.instrument is model and same.fit is not None


def test_unseen_nodes_are_those_no_thermometer_reads():
    # a wound coil: the FOG thermometer reads the outer face's layer; the spool and the
    # spool-side face are unseen, the interior layers are not targets of their own
    assert unseen_nodes(nfs.load_instrument("default")) == (
        "housing", "board", "spool", "coil_1")
    model = nfs.load_instrument("lumped")
    # fog reads electronics and coil_outer, each QFA thermometer its own QFA
    assert unseen_nodes(model) == ("housing", "board", "coil_inner")
    seen = dataclasses.replace(model, thermometers={
        **model.thermometers,
        "fog": dataclasses.replace(model.thermometers["fog"], nodes={"coil_inner": 1.0})})
    assert "coil_inner" not in unseen_nodes(seen) and "coil_outer" in unseen_nodes(seen)


def test_draws_follow_the_fit_s_covariance(world):
    model, runs = world
    r = rival_model(model, runs, "heat_source:coil_inner", start_state=None)
    stage = r.fit.stages["drift"]
    paths = [p for p in stage.free if np.isfinite(r.fit.stderr.get(p, np.inf))
             and r.fit.stderr[p] > 0][:4]
    draws = r.draws(2000, np.random.default_rng(5))
    x = np.array([[nfs.fit.get_param(d, p) for p in paths] for d in draws])
    sd = np.array([r.fit.stderr[p] for p in paths])
    np.testing.assert_allclose(x.std(axis=0), sd, rtol=0.1)
    idx = [list(stage.free).index(p) for p in paths]
    want = np.asarray(stage.correlation)[np.ix_(idx, idx)]
    np.testing.assert_allclose(np.corrcoef(x.T), want, atol=0.1)
    for p, col in zip(paths, x.T):          # inside the fit's box
        lo, hi = r.fit.bounds[p]
        assert col.min() >= lo and col.max() <= hi


def test_rivals_from_a_diagnosis():
    tie = Answer("tie", ("a", "b"), "...")
    assert rivals_of(tie) == ["a", "b"]
    # the diagnosis's own tie when nfs diagnose went on to decide it
    assert rivals_of(Answer("add", ("a",), "add a"), tie) == ["a", "b"]
    assert rivals_of(Answer("add", ("m",), "add m")) == [MODEL, "m"]
    with pytest.raises(NfsError, match="no tie"):
        rivals_of(Answer("nothing", (), "quiet"))


def test_drift_cost_is_compared_in_the_stated_noise():
    """Closed form: a drift stage that rescaled its data rows by s reports (data / s^2) +
    prior; the comparison puts the data back on the stated scale, data + prior."""
    def fit(cost, prior, s):
        rep = StageReport(name="drift", free=("gyro.bias_dph",), converged=True, message="",
                          nfev=1, cost_start=cost, cost=cost, n_residuals=100, time_s=0.0,
                          cost_prior=prior, noise_scale=s)
        return SimpleNamespace(stages={"drift": rep})

    assert _drift_cost(fit(3546.8, 0.0, 1.0)) == pytest.approx(3546.8)
    # 4562 in the stated noise reported as 4562 / 1.54 + 2 once rescaled by s = sqrt(1.54)
    assert _drift_cost(fit(4562.0 / 1.54 + 2.0, 2.0, 1.54 ** 0.5)) == pytest.approx(4564.0)
    assert _drift_cost(fit(2963.0, 0.0, 1.54 ** 0.5)) > _drift_cost(fit(3546.8, 0.0, 1.0))


def test_a_heat_sink_is_reported_not_silently_held_at_zero():
    # Oracle: a unit whose coil loses heat (-0.5 W at coil_inner: a sink, which no heat
    # source is): the drift-first fit asks for a negative power, the rival holds it at 0 W
    # and says so, in words a settlement prints.
    model = nfs.load_instrument("lumped")
    truth = model.with_effects(list(model.effects) + [
        make_effect("heat_source", {"node": "coil_inner", "power": -0.5})])
    sc = nfs.load_scenario().nominal()
    runs = [nfs.simulate_run(truth, dataclasses.replace(sc.conditions()[i], duration_s=3600.0)
                             ).run for i in (1, 3, 5)]
    heat = rival_model(model, runs, "heat_source:coil_inner", start_state=None)
    assert heat.fit.params["effects.heat_source:coil_inner.power"] >= 0.0
    assert heat.rejected.startswith("the drift asks for -"), heat.rejected
    assert "W at coil_inner" in heat.rejected and "held at 0 W" in heat.rejected
