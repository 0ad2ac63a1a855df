"""The measurement side's rooms from the top: every public name reachable, the names that
moved still resolve (with a DeprecationWarning naming the new home), subpackages are
attributes of ``nfs``."""

import pytest

import nfs


@pytest.mark.parametrize("name", ["UnitChain", "FitResult", "Comparison", "Diagnosis",
                                  "Finding", "Settlement", "Applied", "Design", "fit_model",
                                  "fit_unit", "compare", "make_effect"])
def test_the_measurement_side_from_the_top(name):
    assert getattr(nfs, name).__name__ == name


def test_subpackages_are_attributes():
    assert nfs.design.base_conditions.__module__ == "nfs.design.space"
    assert nfs.diagnose.diagnose.__module__ == "nfs.diagnose.missing_effect"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        nfs.nothing


@pytest.mark.parametrize("package, name, home", [
    ("diagnose", "fit_model", "nfs.fit"), ("diagnose", "compare", "nfs.comparison"),
    ("diagnose", "write_report", "nfs.report.compare_report"),
    ("design", "rival_models", "nfs.rivals"), ("design", "Separation", "nfs.rivals")])
def test_moved_names_resolve_for_one_release(package, name, home):
    with pytest.warns(DeprecationWarning, match=f"moved to {home}.{name}"):
        value = getattr(getattr(nfs, package), name)
    assert value is getattr(__import__(home, fromlist=[name]), name)
    with pytest.raises(AttributeError):
        getattr(getattr(nfs, package), "not_a_name")


@pytest.mark.parametrize("call", [
    lambda inst: nfs.fit_unit(inst, [], refin=False),
    lambda inst: nfs.rivals.rival_model(inst, [], "magnetic", decimate=10.0),
    lambda inst: nfs.rivals.rival_models(inst, [], ["model", "magnetic"], start=None),
    lambda inst: nfs.rivals.settle_tie(None, inst, [], starts=None)])
def test_keywords_handed_on_to_the_fit_are_checked_before_any_work(call):
    # as python-control's kwargs tests: a misspelt option is an error, not ignored
    with pytest.raises(TypeError, match="unexpected keyword argument"):
        call(nfs.load_instrument("default"))
