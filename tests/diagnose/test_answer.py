"""One answer per diagnosis (nfs.diagnose.result.Answer).

Oracle: the rule itself, on hand-made rankings: the top significant candidate that no other
explains is added, unless it is tied with a rate term on every node (then the answer is that
tie, never "add" and "tie" together); a thermal candidate tied with a structural alternative
is a tie; with nothing significant the answer is "nothing beyond noise" when the residual is
consistent with the noise model and the thermal structure fits, else "unexplained"; a
failure is "cannot be determined".  And the ranking: significant first, unphysical last.
"""

from __future__ import annotations

import numpy as np
import pytest

import importlib

from nfs.diagnose.candidate_score import ScoredCandidate
from nfs.diagnose.drift_structure import DriftStructure
from nfs.diagnose.ranking import is_physical, rank_key
from nfs.diagnose.result import ANSWER_KINDS, CandidateScore, Diagnosis


def _score(effect, target=None, significant=False, drop=0.2, coef=None, **kw):
    coef = coef or {"k": 0.1}
    return CandidateScore(effect=effect, target=target, significant=significant,
                          cv_rms_before=1.0, cv_rms_after=1.0 - drop, correlation=0.5,
                          coefficient=coef, interval={k: (v - 0.01, v + 0.01)
                                                      for k, v in coef.items()},
                          wald_p=1e-4, holm_p=1e-3, dof=6.0, n_grid=1,
                          inclusion_frequency=1.0, **kw)


def _diag(ranking, tied=(), white=True, failure=None):
    ds = DriftStructure(nodes=("a",), cv_rms_model=1.0, cv_rms_alternative=0.9,
                        tied=tuple(tied))
    return Diagnosis(ranking=tuple(ranking), not_tried=(),
                     unexplained={"ljung_box": {"consistent": white, "p_value": 0.5,
                                                "variance_ratio": 1.0}},
                     baseline=None, time_s=0.0, drift_structure=ds, failure=failure)


def test_add_the_top_one():
    d = _diag([_score("magnetic", significant=True),
               _score("shupe_rate", "board", significant=True, explained_by="magnetic"),
               _score("shupe_product", significant=False)])
    assert d.answer.kind == "add" and d.answer.labels == ("magnetic",)
    assert d.verdict.startswith("add magnetic (k = 0.1 [0.09, 0.11]") and "tie" not in d.verdict


def test_a_tied_top_is_a_tie_not_an_addition():
    d = _diag([_score("turn_on_transient", significant=True, beyond_structure_p=0.4)],
              tied=("turn_on_transient",))
    assert d.answer.kind == "tie"
    assert d.answer.labels == ("turn_on_transient", "a rate term on every node")
    assert "add " not in d.verdict and "nfs design" in d.verdict
    # with coil nodes, heat released inside the coil is the third explanation
    d = Diagnosis(**{**d.__dict__, "coil_nodes": ("coil_outer", "coil_inner")})
    assert d.answer.labels == ("turn_on_transient", "a rate term on every node",
                               "heat_source:coil_inner")
    assert "heat released inside the coil" in d.verdict


def test_an_untied_transient_is_tied_with_heat_inside_the_coil():
    """A turn-on transient that stands beyond the rate terms is still what heat released in
    the coil, where no thermometer sits, does to the gyro at every start temperature."""
    d = _diag([_score("turn_on_transient", significant=True, beyond_structure_p=0.001)])
    d = Diagnosis(**{**d.__dict__, "coil_nodes": ("coil_outer", "coil_inner")})
    assert d.answer.kind == "tie"
    assert d.answer.labels == ("turn_on_transient", "heat_source:coil_inner")
    assert "power cycle" in d.verdict and "add " not in d.verdict


def test_thermal_structure_tie():
    d = _diag([_score("heat_source", "coil_inner", coef={"power": 1.0},
                      structure_tie="insert node coil_outer-housing")])
    assert d.answer.kind == "tie"
    assert d.answer.labels == ("heat_source:coil_inner", "insert node coil_outer-housing")


def test_nothing_and_unexplained():
    assert _diag([_score("magnetic")]).answer.kind == "nothing"
    assert _diag([_score("magnetic")]).verdict.startswith("nothing beyond noise")
    d = _diag([_score("magnetic")], white=False)
    assert d.answer.kind == "unexplained" and "not the gyro noise" in d.verdict


def test_failure_is_undetermined(monkeypatch):
    d = _diag([], failure="singular")
    assert d.answer.kind == "undetermined"
    assert d.verdict.startswith("cannot be determined from these runs: singular")
    assert set(ANSWER_KINDS) == {"add", "tie", "nothing", "unexplained", "undetermined"}

    def broken(*args, **kwargs):
        raise np.linalg.LinAlgError("Eigenvalues did not converge")
    diagnose_module = importlib.import_module("nfs.diagnose.missing_effect")
    monkeypatch.setattr(diagnose_module, "diagnose_candidates", broken)
    got = diagnose_module.diagnose(None, [])
    assert got.answer.kind == "undetermined" and "Eigenvalues did not converge" in got.verdict
    assert got.to_dict()["answer"]["kind"] == "undetermined"


def test_ranking_puts_unphysical_rows_last():
    neg = _score("heat_source", "board", coef={"power": -4.6}, drop=0.3)
    assert not is_physical(neg) and is_physical(_score("heat_source", coef={"power": 0.5}))
    rows = [ScoredCandidate(candidate=None, score=s, shapes={}, beta=None, cols=[]) for s in (
        neg.__class__(**{**neg.__dict__, "physical": False}),
        _score("magnetic", drop=0.01),
        _score("shupe_rate", significant=True, drop=0.05),
        _score("heat_source", "coil", coef={"power": 1.0}, significant=True, drop=0.02,
               channel="thermometers"))]
    order = [r.score.effect for r in sorted(rows, key=rank_key)]
    assert order == ["heat_source", "shupe_rate", "magnetic", "heat_source"]
    assert sorted(rows, key=rank_key)[-1].score.physical is False


def test_a_heat_sink_the_runs_ask_for_is_named_not_added():
    """Oracle: a heat power the runs want negative beyond chance (the one-sided test run the
    other way, below alpha / n over the ranking) is no heat source: the answer says what is
    left unexplained and names it; at chance level it changes nothing."""
    sink = _score("heat_source", "spool", coef={"power": -0.3}, physical=False,
                  sign_rejected_p=1e-4)
    d = _diag([_score("magnetic"), sink])
    assert d.answer.kind == "unexplained"
    assert "heat_source:spool" in d.verdict and "heat taken away" in d.verdict
    weak = _score("heat_source", "spool", coef={"power": -0.3}, physical=False,
                  sign_rejected_p=0.03)           # above 0.05 / 2
    assert _diag([_score("magnetic"), weak]).answer.kind == "nothing"
