"""Tests of nfs.diagnose.diagnose: name the effect a model lacks, add it, watch the error fall.

"Measured" runs: the default scenario's 7 start temperatures, 2.5 h at 1 Hz, simulated
(nfs.experiment.simulate_run) from an instrument with ONE effect the model lacks; the model
is the default instrument (load_instrument("default")), with that effect removed when the
default has it.  Oracle: the generating instrument (we know which effect is hidden and its
value); the noise floor of the drift channel is the residual RMS of the 10 s window means
when the true instrument's own drift coefficients are fitted (about 0.0064 deg/h: ARW
0.0003 deg/sqrt(h) gives 0.0057 deg/h on a 10 s mean, plus bias instability).  Hidden
strengths relative to that floor (RMS of the hidden term over the runs / floor):
shupe_product k_p = 0.02 (default 0.006) ~7x; magnetic m = 0.01 deg/h, D_mag = 30 deg ~1.1x
(m / sqrt(2) = 0.007 deg/h, constant in time, so its CV drop is clear); turn_on_transient
a = 0.05 deg/h, tau = 300 s ~1x over 2.5 h (98 % of it in the first 10 min).
"""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from nfs.diagnose.diagnose import (CV_DROP, apply_candidate, candidates, diagnose)
from nfs.diagnose.fit import fit_model
from nfs.effects import make_effect
from nfs.errors import NfsError
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.io.scenario import load_scenario

HIDDEN = {
    "shupe_product": {"k_p": 0.02},
    "turn_on_transient": {"a": 0.05, "tau": 300.0},
    "magnetic": {"m": 0.01, "D_mag": 30.0},
}


@pytest.fixture(scope="module")
def scenario():
    return dataclasses.replace(load_scenario(), duration_s=9000.0, seed=11)


@pytest.fixture(scope="module")
def default():
    return load_instrument("default")


def _without(inst, name):
    return inst.with_effects([e for e in inst.effects if e.name != name])


def _case(scenario, default, name):
    model = _without(default, name)
    truth = model.with_effects(list(model.effects) + [make_effect(name, HIDDEN[name])])
    runs = [simulate_run(truth, c).run for c in scenario.conditions()]
    return model, truth, runs


@pytest.fixture(scope="module")
def cases(scenario, default):
    return {name: _case(scenario, default, name) for name in HIDDEN}


@pytest.fixture(scope="module")
def diagnoses(cases):
    return {name: diagnose(model, runs) for name, (model, truth, runs) in cases.items()}


def _floor(truth, runs):
    """Drift residual RMS of the true instrument with its drift coefficients fitted."""
    return fit_model(truth, runs, stages=("drift",)).rms_after["drift_dph"]


def test_candidates_lists_targets_and_skips_model_effects(default, cases):
    model, _, runs = cases["magnetic"]
    cs = candidates(model, runs)
    labels = {c.label for c in cs}
    assert "magnetic" in labels and "shupe_gradient" not in labels  # in the model
    assert "shupe_product:housing" in labels and "shupe_product" not in labels
    assert "aux_linear:aux_tec_power_w" in labels
    assert {"thermometer_lag:fog", "heat_source:board"} <= labels
    by = {c.label: c for c in cs}
    assert not by["heat_source:board"].tried and "thermal" in by["heat_source:board"].reason
    assert by["magnetic"].shapes == ("D_mag",) and by["magnetic"].coefficients == ("m",)


@pytest.mark.parametrize("name", ["shupe_product", "magnetic"])
def test_hidden_effect_is_top_significant_candidate(diagnoses, name):
    # Oracle: the generating instrument has exactly this effect on its default target.
    d = diagnoses[name]
    top = d.ranking[0]
    assert (top.effect, top.target) == (name, None), [(s.effect, s.target) for s in
                                                      d.ranking[:3]]
    assert top.significant and top.inclusion_frequency >= 0.8
    assert top.cv_rms_after < (1 - CV_DROP) * top.cv_rms_before
    # the fitted coefficient's interval holds the true value
    for p, v in HIDDEN[name].items():
        if p in top.interval and p != "tau":
            lo, hi = top.interval[p]
            assert lo - 0.1 * abs(v) <= v <= hi + 0.1 * abs(v), (p, v, top.interval[p])
    assert top.heading_rmse_after_deg <= top.heading_rmse_before_deg


def test_turn_on_transient_is_among_the_top_significant(diagnoses):
    # Oracle: the hidden a exp(-t/300 s).  Over 2.5 h runs it is nearly collinear with the
    # warm-up of the board node (tau ~5 min: shupe_rate:board, bias_temperature:board fit
    # within 1 % of the same CV RMS), so the test asks for the top 3 and a significant score,
    # not the first place (see the report: a known identifiability limit).
    d = diagnoses["turn_on_transient"]
    top3 = [(s.effect, s.target) for s in d.ranking[:3]]
    assert ("turn_on_transient", None) in top3, top3
    s = next(s for s in d.ranking if s.effect == "turn_on_transient")
    assert s.cv_rms_after < (1 - CV_DROP) * s.cv_rms_before
    assert s.cv_rms_after <= 1.01 * d.ranking[0].cv_rms_after
    assert abs(s.coefficient["a"] - 0.05) < 0.015


def test_no_hidden_effect_no_significant_candidate(scenario, default):
    # Oracle: runs made by the model itself (only noise is left to explain).
    runs = [simulate_run(default, c).run
            for c in dataclasses.replace(scenario, seed=12).conditions()]
    d = diagnose(default, runs)
    assert not d.significant, [(s.effect, s.target, s.cv_drop) for s in d.significant]
    assert "no candidate is significant" in d.verdict
    assert max(s.cv_drop for s in d.ranking) < CV_DROP


@pytest.mark.parametrize("name", ["shupe_product", "magnetic", "turn_on_transient"])
def test_apply_halves_the_excess_and_keeps_heading(cases, name):
    # Oracle: the truth.  The excess of the drift residual over the noise floor,
    # sqrt(rms^2 - floor^2), falls by at least half; heading RMSE does not get worse.
    model, truth, runs = cases[name]
    new, res, rep = apply_candidate(model, runs, name)
    assert any(e.name == name for e in new.effects)
    floor = _floor(truth, runs)
    before, after = rep["rms_before"]["drift_dph"], rep["rms_after"]["drift_dph"]
    excess = lambda r: math.sqrt(max(r * r - floor * floor, 0.0))  # noqa: E731
    assert excess(after) <= 0.5 * excess(before), (before, after, floor)
    assert rep["heading_rmse_after_deg"] <= rep["heading_rmse_before_deg"] * 1.001


def test_to_dict_form_and_unexplained(diagnoses):
    d = diagnoses["magnetic"]
    doc = json.loads(json.dumps(d.to_dict()))
    r = doc["ranking"][0]
    for key in ("effect", "target", "significant", "cv_rms_before", "cv_rms_after",
                "correlation", "coefficient", "interval", "inclusion_frequency",
                "heading_rmse_before_deg", "heading_rmse_after_deg"):
        assert key in r
    assert r["effect"] == "magnetic" and r["target"] is None
    u = doc["unexplained"]
    assert 0.0 <= u["ljung_box"]["p_value"] <= 1.0
    # Oracle: m cos(A - D) follows the turntable position; the baseline residual is not
    # white and its strongest channel is the position's cos or sin.
    assert u["ljung_box"]["p_value"] < 0.01
    assert u["cross_correlation"][0]["channel"] in ("cos_position", "sin_position")


def test_bad_input(cases):
    model, _, runs = cases["magnetic"]
    with pytest.raises(NfsError, match="valid names"):
        apply_candidate(model, runs, "magnetik")
    with pytest.raises(NfsError, match="valid targets"):
        apply_candidate(model, runs, "shupe_product", "nowhere")
    with pytest.raises(NfsError, match="already"):
        apply_candidate(model, runs, "shupe_gradient")
    with pytest.raises(NfsError, match="at least 2 runs"):
        diagnose(model, runs[:1])
