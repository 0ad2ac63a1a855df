"""nfs.UnitChain: a unit's runs and a model, fit -> compare -> diagnose -> apply -> design.

Oracles: every step's result reads back from its JSON as the same result (to_dict then
from_dict then to_dict gives the same text); the start states are estimated once per model;
an option the chain does not have is an error; the chain moves to the model an effect was
added to; on runs the default model made itself the answer is "nothing beyond noise".
"""

import json

import pytest

import nfs
from nfs.cli import main
from nfs.comparison import compare_runs
from nfs.diagnose import apply as apply_module
from nfs.diagnose import missing_effect
from nfs.unit import chain as chain_module

#: Every module that estimates start states when it is not handed them.
ESTIMATORS = (chain_module, compare_runs, missing_effect, apply_module)


def _round_trip(result):
    text = json.dumps(result.to_dict())
    back = type(result).from_dict(json.loads(text))
    assert json.dumps(back.to_dict()) == text
    return back


@pytest.fixture(scope="module")
def runs(tmp_path_factory, scenario_text):
    folder = tmp_path_factory.mktemp("unit")
    # 90 min: a stable stage of half an hour after the start-up hour (the structure check
    # holds each stage's held-out residual to its floor; 5 minutes of it, 10 knots a run,
    # let a free TEC set point beat the model's own structure by 10 % on noise)
    (folder / "s.toml").write_text(scenario_text("uc", 3, (-20.0, 5.0, 40.0), 5400.0))
    assert main(["simulate", str(folder / "s.toml"), "-o", str(folder / "runs"), "-q"]) == 0
    return nfs.read_runs(folder / "runs")


@pytest.fixture(scope="module")
def worked(runs):
    """The chain worked as a user does, every result kept."""
    chain = nfs.UnitChain("default", runs)
    calls = []
    originals = [m.start_states for m in ESTIMATORS]
    out = {"fit": chain.fit()}
    for m, original in zip(ESTIMATORS, originals):
        m.start_states = lambda *a, _f=original, **k: calls.append(1) or _f(*a, **k)
    try:
        out.update(comparison=chain.compare(), finding=chain.diagnose(decide=True),
                   applied=chain.apply("magnetic"))
    finally:
        for m, original in zip(ESTIMATORS, originals):
            m.start_states = original
    out["start_state_estimates"] = len(calls)
    out["chain"] = chain
    return out


@pytest.mark.integration
def test_the_runs_of_the_model_itself_leave_nothing_to_add(worked):
    finding = worked["finding"]
    assert finding.answer.kind == "nothing", finding.verdict
    assert finding.settlement is None and finding.tie is None
    # the fit's start states served the comparison, the diagnosis and the drift effect added
    # (it leaves the network as it is): no module estimated them again
    assert worked["start_state_estimates"] == 0
    assert finding.diagnosis.baseline is worked["fit"]


@pytest.mark.integration
def test_every_result_reads_back_from_its_json(worked):
    fit = _round_trip(worked["fit"])
    assert fit.params == worked["fit"].params
    assert fit.instrument.to_toml() == worked["fit"].instrument.to_toml()
    comparison = _round_trip(worked["comparison"])
    assert comparison.sentences() == worked["comparison"].sentences()
    finding = _round_trip(worked["finding"])
    assert finding.verdict == worked["finding"].verdict
    assert finding.diagnosis.ranking == worked["finding"].diagnosis.ranking
    applied = _round_trip(worked["applied"])
    assert applied.instrument.to_toml() == worked["applied"].instrument.to_toml()


@pytest.mark.integration
def test_apply_moves_the_chain_and_warns_against_its_diagnosis(worked):
    applied, chain = worked["applied"], worked["chain"]
    assert chain.model is applied.instrument and chain.fitted is applied.fit
    assert any(e.name == "magnetic" for e in chain.model.effects)
    assert applied.supported is False and "not significant" in applied.support
    assert applied.warnings[0].startswith("the diagnosis does not support magnetic")
    assert chain.finding is None and len(chain.history) == 4


def test_unknown_options_and_rivals_are_refused_before_any_work(runs):
    chain = nfs.UnitChain("default", runs)
    with pytest.raises(TypeError):
        chain.fit(refin=False)
    with pytest.raises(TypeError):
        chain.diagnose(decid=True)
    with pytest.raises(nfs.NfsError, match="at least two"):
        chain.diagnose(rivals=["model"])
    with pytest.raises(nfs.NfsError, match="has it already"):
        chain.check_rivals(["model", "turn_on_transient"])
    with pytest.raises(nfs.NfsError, match="diagnose first"):
        chain.design()
    with pytest.raises(nfs.NfsError, match="unknown effect"):
        chain.apply("magnetc")
    assert chain.fitted is None and chain.history == []


def test_a_chain_needs_runs():
    with pytest.raises(nfs.NfsError, match="no measurement files"):
        nfs.UnitChain("default", [])
