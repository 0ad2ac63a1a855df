"""Measured aux_* columns the model does not declare: candidates, never a crash.

Runs carry a source-current column ``aux_source_current_ma`` that the model (the default
instrument, which declares only ``aux_tec_power_w``) knows nothing of.  The truth declares
it (so the simulator writes it): 150 mA + 2 mA/K of the electronics temperature, plus a
random walk of 0.02 mA/sqrt(s) that no thermometer sees.
"""

from __future__ import annotations

import dataclasses

import pytest

from nfs.diagnose.candidates import candidates
from nfs.diagnose.missing_effect import diagnose
from nfs.effects import make_effect
from nfs.errors import EffectError, NfsError
from nfs.experiment import simulate_run
from nfs.instrument import AuxChannel, instrument_from_dict, load_instrument
from nfs.config.scenario import load_scenario

CURRENT = AuxChannel(name="aux_source_current_ma", source="temperature:electronics",
                     gain=2.0, offset=150.0, noise=0.01, walk_per_rth_s=0.02)
#: k [deg/h per mA]: 0.01 deg/h per K through the temperature, a wander of about
#: 1e-4 deg/h/sqrt(s) of its own (the strength of the aux_linear case of test_diagnose.py)
K = 0.005


def _runs(hidden: bool, seed: int = 21):
    default = load_instrument("default")
    truth = dataclasses.replace(default, aux=default.aux + (CURRENT,))
    if hidden:
        truth = truth.with_effects(list(truth.effects) + [make_effect(
            "aux_linear", {"channel": CURRENT.name, "k": K})])
    sc = dataclasses.replace(load_scenario().nominal(), seed=seed)
    return [simulate_run(truth, c).run for c in sc.conditions()]


@pytest.fixture(scope="module")
def clean_runs():
    return _runs(hidden=False)


def test_instrument_names_a_measured_channel_it_does_not_simulate(tmp_path):
    """Oracle: the TOML round trip (to_toml -> file -> load_instrument) of a fitted model
    with aux_linear on an undeclared channel gives the same effect; simulating it raises
    one EffectError naming the effect, the channel and the fix."""
    default = load_instrument("default")
    fitted = dataclasses.replace(default.with_effects(list(default.effects) + [make_effect(
        "aux_linear", {"channel": "aux_source_current_ma", "k": K})]), name="unit 7 fitted")
    path = tmp_path / "fitted.toml"
    path.write_text(fitted.to_toml(), encoding="utf-8")
    back = load_instrument(path)
    assert back.effect("aux_linear:aux_source_current_ma").params["k"] == K
    assert instrument_from_dict(fitted.to_dict()).to_dict() == back.to_dict()
    cond = load_scenario().conditions()[0]
    with pytest.raises(EffectError, match=r"aux_linear:aux_source_current_ma.*"
                                          r"declare it under \[\[aux\]\]"):
        simulate_run(back, cond)
    with pytest.raises(NfsError, match="unknown channel 'source_current'"):
        default.with_effects([make_effect("aux_linear", {"channel": "source_current",
                                                         "k": K})])


def test_undeclared_column_is_a_candidate_and_partial_columns_are_noted(clean_runs):
    """Oracle: the column is in every run, so aux_linear on it is a tried candidate; with
    the column dropped from two runs it is not tried and the note names those runs."""
    model = load_instrument("default")
    labels = {c.label: c for c in candidates(model, clean_runs)}
    assert labels["aux_linear:aux_source_current_ma"].tried
    cut = [dataclasses.replace(r, columns={k: v for k, v in r.columns.items()
                                           if k != CURRENT.name}) if i in (1, 4) else r
           for i, r in enumerate(clean_runs)]
    c = {c.label: c for c in candidates(model, cut)}["aux_linear:aux_source_current_ma"]
    assert not c.tried
    assert cut[1].name in c.reason and cut[4].name in c.reason
    assert cut[0].name not in c.reason


def test_diagnose_scores_an_undeclared_column_without_a_hidden_effect(clean_runs):
    """Oracle: nothing is hidden (runs made by the model plus a recorded current it does not
    use): diagnose runs to the end, scores the column and finds nothing significant."""
    d = diagnose(load_instrument("default"), clean_runs)
    s = {(s.effect, s.target): s for s in d.ranking}[("aux_linear", CURRENT.name)]
    assert not d.significant, d.verdict
    assert 0.0 <= s.wald_p <= 1.0


@pytest.mark.integration       # a second set of runs and its diagnosis
def test_diagnose_names_a_hidden_effect_on_an_undeclared_column():
    """Oracle: the hidden truth, aux_linear k = 0.005 deg/h/mA on the undeclared column,
    is the top candidate, significant, and its interval holds the true k."""
    d = diagnose(load_instrument("default"), _runs(hidden=True))
    top = d.ranking[0]
    assert (top.effect, top.target, top.significant) == ("aux_linear", CURRENT.name, True), \
        d.verdict
    lo, hi = top.interval["k"]
    assert lo <= K <= hi
