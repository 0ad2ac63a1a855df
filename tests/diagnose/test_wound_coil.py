"""Fit, structure check and diagnosis on the default instrument, whose coil is wound.

"Measured" runs: the default scenario's 7 start temperatures in its nominal world (soaked
exactly at T0, the tools told so with ``start_state=None``), 2.5 h at 1 Hz, simulated from
the default instrument (a wound coil of 8 thermal layers, ``shupe_winding``) with one effect
it lacks, or none.  Oracle: the generating instrument.  The coil is one body to these tools:
its interior layers are no candidate's target and no structural alternative splits or cuts
them (nfs.instrument.Instrument.target_nodes, nfs.fit.structure).

Measured with noise seed 11 (the strengths of tests/diagnose/test_diagnose.py): clean runs
give "nothing beyond noise"; magnetic m = 0.01 deg/h is named with m = 0.0097 [0.0093,
0.0101]; shupe_product k_p = 0.02 with k_p = 0.0204 [0.0195, 0.0212]; about 6 s a diagnosis.
"""

from __future__ import annotations

import dataclasses

import pytest

from nfs.config.scenario import load_scenario
from nfs.diagnose import diagnose
from nfs.fit.adequacy import thermal_adequacy
from nfs.diagnose.candidates import candidates
from nfs.fit.adequacy import structural_alternatives
from nfs.effects import make_effect
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument

HIDDEN = {"magnetic": {"m": 0.01, "D_mag": 30.0}, "shupe_product": {"k_p": 0.02}}


@pytest.fixture(scope="module")
def default():
    return load_instrument("default")


def _runs(truth, duration_s=9000.0):
    sc = dataclasses.replace(load_scenario().nominal(), duration_s=duration_s, seed=11)
    return [simulate_run(truth, c).run for c in sc.conditions()]


@pytest.fixture(scope="module")
def clean(default):
    return _runs(default)


def test_the_coil_is_one_body_to_the_structure_check(default):
    alts = structural_alternatives(default)
    names = {a.name for a in alts}
    interior = {f"coil_{k}" for k in range(2, 8)}
    assert not any(n in name for name in names for n in interior)
    assert not any(a.kind == "split" and "coil_" in a.name for a in alts)
    assert not any(a.kind == "insert" and "coil_" in a.name for a in alts)
    assert {"link coil_8-board", "link coil_1-electronics", "split housing",
            "insert node electronics-housing"} <= names
    for alt in alts:                        # every alternative keeps the winding as it is
        built = alt.build(alt.start)
        assert built.coil == default.coil
        nodes, links = built.own_parts
        assert len(built.network.links) == len(links) + len(default.coil.annulus.links())
    labels = {c.label for c in candidates(default, _runs(default, 600.0)[:1])}
    assert "heat_source:coil_1" in labels and "heat_source:coil_8" in labels
    assert not any(f"heat_source:{n}" in labels for n in interior)


def test_its_own_runs_are_adequate(default, clean):
    ad = thermal_adequacy(default, clean[::2], start_state=None)
    assert ad.adequate, ad.message
    assert not any(a.beats_model for a in ad.alternatives)


@pytest.mark.integration       # a diagnosis of 7 runs of 2.5 h (as the two below)
def test_clean_runs_name_nothing(default, clean):
    d = diagnose(default, clean, start_state=None)
    assert d.answer.kind == "nothing", d.verdict
    assert not any(s.significant for s in d.ranking)


@pytest.mark.integration
@pytest.mark.parametrize("name", sorted(HIDDEN))
def test_a_hidden_effect_is_named(default, name):
    truth = default.with_effects(list(default.effects) + [make_effect(name, HIDDEN[name])])
    d = diagnose(default, _runs(truth), start_state=None)
    assert d.answer.kind == "add" and d.answer.labels == (name,), d.verdict
    top = d.ranking[0]
    (param, want), = [(k, v) for k, v in HIDDEN[name].items() if k in ("m", "k_p")]
    lo, hi = top.interval[param]
    assert lo <= want <= hi, (param, top.interval[param])
