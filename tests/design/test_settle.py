"""nfs.rivals.decide.settlement: one answer from the decisions between rivals.

Oracle: the rule of the module docstring, on decisions made by hand (Evidence with chosen
Lambda and variance, so that each pair's winner is known): a rival that wins every pair it
is in is the answer (``add`` an effect, ``nothing`` for the model as it is,
``unexplained`` for a change of structure); otherwise a tie of the rivals no other beats,
and those are the rivals a run is designed for.
"""

from __future__ import annotations

from dataclasses import replace
from itertools import combinations

import pytest

from nfs.rivals.decide import DWELL_CHANNELS, Decision, pair_channels, settlement
from nfs.rivals.evidence import Evidence
from nfs.rivals.predict import CHANNELS
from nfs.rivals.models import MODEL, RATE_ALTERNATIVE, Rival
from nfs.instrument import load_instrument

TRANSIENT = "turn_on_transient"


@pytest.fixture(scope="module")
def rivals():
    inst = load_instrument("default")          # has a turn-on transient among its effects
    assert any(e.label == TRANSIENT for e in inst.effects)
    return [Rival(TRANSIENT, "adds the transient", inst, None, 2),
            Rival(RATE_ALTERNATIVE, "a rate term on every node", inst, None, 7),
            Rival(MODEL, "the model as given", inst, None, 0)]


def _decisions(rivals, beats: dict[tuple[str, str], str | None]):
    """Every pair decided as ``beats`` says (winner label or None): Lambda +-50 with
    variance 1 for a winner, 0 for a tie; no price."""
    out = []
    for a, b in combinations([r.label for r in rivals], 2):
        w = beats.get((a, b), beats.get((b, a)))
        llr = 0.0 if w is None else (50.0 if w == a else -50.0)
        out.append(Decision(a, b, Evidence(llr, 4.0, 0.0, 1.0, {}), {}))
    return out


def test_an_effect_that_wins_every_pair_is_added(rivals):
    s = settlement(rivals, _decisions(rivals, {(TRANSIENT, RATE_ALTERNATIVE): TRANSIENT,
                                               (TRANSIENT, MODEL): TRANSIENT,
                                               (RATE_ALTERNATIVE, MODEL): RATE_ALTERNATIVE}))
    assert s.answer.kind == "add" and s.answer.labels == (TRANSIENT,)
    assert s.answer.text.startswith(f"add {TRANSIENT}")
    assert [r.label for r in s.standing] == [TRANSIENT]


def test_the_model_that_wins_every_pair_keeps_the_model(rivals):
    s = settlement(rivals, _decisions(rivals, {(TRANSIENT, MODEL): MODEL,
                                               (RATE_ALTERNATIVE, MODEL): MODEL}))
    assert s.answer.kind == "nothing" and s.answer.labels == ()
    assert s.answer.text.startswith("keep the model as it is")


def test_a_structure_that_wins_is_no_single_effect(rivals):
    s = settlement(rivals, _decisions(rivals, {(TRANSIENT, RATE_ALTERNATIVE): RATE_ALTERNATIVE,
                                               (TRANSIENT, MODEL): TRANSIENT,
                                               (RATE_ALTERNATIVE, MODEL): RATE_ALTERNATIVE}))
    assert s.answer.kind == "unexplained" and s.answer.labels == (RATE_ALTERNATIVE,)
    assert "no single effect" in s.answer.text and "revise the model's structure" in \
        s.answer.text


def test_a_tie_keeps_the_rivals_no_other_beats(rivals):
    # transient and rate term tied, both beat the model
    s = settlement(rivals, _decisions(rivals, {(TRANSIENT, MODEL): TRANSIENT,
                                               (RATE_ALTERNATIVE, MODEL): RATE_ALTERNATIVE}))
    assert s.answer.kind == "tie"
    assert s.answer.labels == (TRANSIENT, RATE_ALTERNATIVE)
    assert [r.label for r in s.standing] == [TRANSIENT, RATE_ALTERNATIVE]
    assert "the model as it is: ruled out" in s.answer.text
    # nothing beats the model: it stands beside the effect
    s = settlement(rivals, _decisions(rivals, {(TRANSIENT, RATE_ALTERNATIVE): TRANSIENT}))
    assert s.answer.kind == "tie" and s.answer.labels == (TRANSIENT, MODEL)
    assert "the model as it is" in s.answer.text
    # a cycle beats everyone: every rival stands
    s = settlement(rivals, _decisions(rivals, {(TRANSIENT, RATE_ALTERNATIVE): TRANSIENT,
                                               (RATE_ALTERNATIVE, MODEL): RATE_ALTERNATIVE,
                                               (TRANSIENT, MODEL): MODEL}))
    assert s.answer.kind == "tie" and set(s.answer.labels) == {r.label for r in rivals}


def test_thermometers_only_between_rivals_that_treat_the_thermal_stage_alike(rivals):
    """pair_channels: every channel when both rivals refit the thermal stage or neither
    does; the dwell channels alone when one does (its free thermal numbers would take up
    the thermometers' misfit)."""
    transient, rate, model = rivals
    heat = replace(transient, label="heat_source:coil_inner", thermal_refit=True)
    split = replace(rate, label="split housing", thermal_refit=True)
    assert pair_channels(transient, model) == CHANNELS
    assert pair_channels(heat, split) == CHANNELS
    assert pair_channels(heat, transient) == DWELL_CHANNELS
    assert pair_channels(model, split) == DWELL_CHANNELS
    assert set(DWELL_CHANNELS) == {"drift_dph", "acc_x_g", "acc_y_g"}


def test_what_the_runs_asked_and_were_refused_is_said(rivals):
    # a rival whose power the drift wanted negative (held at 0 W): a tie and a kept model
    # both say so, once
    heat = "heat_source:coil_1"
    sink = [Rival(heat, "adds heat", rivals[0].instrument, None, 1, True,
                  "the drift asks for -0.31 +- 0.05 W at coil_1 (heat taken away: a sink, not "
                  "a source), held at 0 W"), rivals[2]]
    tie = settlement(sink, _decisions(sink, {}))
    assert tie.answer.kind == "tie"
    assert tie.answer.text.count(f"({heat}: the drift asks for -0.31") == 1
    kept = settlement(sink, _decisions(sink, {(heat, MODEL): MODEL}))
    assert kept.answer.kind == "nothing" and "held at 0 W" in kept.answer.text
    quiet = settlement(rivals, _decisions(rivals, {}))
    assert "held at 0 W" not in quiet.answer.text
