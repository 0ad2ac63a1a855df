"""Accelerometer candidates are scored on their own axis's readings at rest.

Oracle: runs of the default instrument (which has ``acc_bias_temperature`` on both axes,
x: 2e-5 g/K, y: -1.5e-5 g/K); the model lacks the y axis's term.  The y accelerometer never
enters the drift (the north finder's vertical-rate removal reads the x axis only), so only
its own channel can reveal it: there the term reaches 1.5e-5 g/K x ~40 K = 6e-4 g against a
white-noise floor of 20 ug/sqrt(Hz) / sqrt(10 s) ~ 6 ug per window.  The diagnosis must name
acc_bias_temperature:y on acc_y_g with an interval around -1.5e-5 g/K, and the design must
reproduce the linear model of the readings exactly on noise-free runs.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from nfs.diagnose.acc_columns import model_acc_paths, prepare_acc
from nfs.diagnose.columns import prepare_runs
from nfs.diagnose.candidates import candidates
from nfs.diagnose.missing_effect import diagnose
from nfs.scoring.run_stats import clustered_fit, run_grams
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.config.scenario import load_scenario

B_Y = -1.5e-5


def _without_y(inst):
    return inst.with_effects([e for e in inst.effects if not (
        e.name == "acc_bias_temperature" and e.params.get("axis") == "y")])


@pytest.fixture(scope="module")
def case():
    truth = load_instrument("default")
    scen = dataclasses.replace(load_scenario().nominal(), duration_s=5400.0, seed=21)
    runs = [simulate_run(truth, c).run for c in scen.conditions()]
    return truth, _without_y(truth), runs


def test_y_axis_is_a_candidate_on_its_own_channel(case):
    _, model, runs = case
    c = {x.label: x for x in candidates(model, runs)}["acc_bias_temperature:y"]
    assert c.tried and c.channel == "acc_y_g"


def test_design_reproduces_the_readings(case):
    # Oracle: with the truth's own tilts, bias and coefficient the design's columns give
    # back the measured window means to the accelerometer noise (least squares recovers the
    # truth's tilts, bias and b_q1 well inside their noise)
    truth, _, runs = case
    preps, _ = prepare_runs(truth, runs, 10.0)
    acc = prepare_acc(truth, runs, [p.ctx for p in preps], 10.0, "y")
    paths = model_acc_paths(truth, "y")
    assert paths[:3] == ["turntable.tilt_north_deg", "turntable.tilt_east_deg",
                         "accelerometers.bias_y_g"] and paths[3].endswith(".b_q1")
    fit = clustered_fit(run_grams([a.y for a in acc], [a.X for a in acc]))
    tt = truth.turntable
    want = [tt.tilt_north_deg, tt.tilt_east_deg, truth.accelerometers.bias_y_g, B_Y]
    z = (fit.beta - want) / fit.se()
    assert np.all(np.abs(z) < 5.0), (fit.beta, want, fit.se())


def test_hidden_y_axis_term_is_named(case):
    _, model, runs = case
    d = diagnose(model, runs, n_boot=0)
    top = [s for s in d.ranking if s.significant and s.explained_by is None][0]
    assert (top.effect, top.target, top.channel) == ("acc_bias_temperature", "y", "acc_y_g")
    lo, hi = top.interval["b_q1"]
    assert lo < B_Y < hi and hi - lo < 0.1 * abs(B_Y)
    # the y axis does not enter the heading: the start-up heading RMSE does not move
    assert top.heading_rmse_after_deg == pytest.approx(top.heading_rmse_before_deg, rel=1e-9)
