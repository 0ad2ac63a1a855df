"""The registry of compensation methods: the built-in rows, a user's own method, the errors,
and the user guide's snippet (docs/compensation.md, "Your own method"), run as written.

Oracles: the rows of the seed papers in the order of the stored tables (README.md's default
table); a user's ridge regression is a row of the table made through the public API
(nfs.ModelChain), and its cells are the start-up heading RMSE of the north-finding the
study keeps for it, recomputed here; with a vanishing penalty it is the ordinary least
squares of the same standardised features, a second user method trained beside it (the same
drift predicted, so the same cells to 1e-6); the messages, one line each, name what is wrong
and what is known.
"""

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression, Ridge
from sklearn.pipeline import Pipeline, make_pipeline
from sklearn.preprocessing import StandardScaler

import nfs
from nfs.compensate import (CompensationSettings, MethodError, available_methods, get_method,
                            register_method, table_methods, unregister_method)
from nfs.compensate import catalog
from nfs.errors import ScenarioError

ROOT = Path(__file__).resolve().parents[2]

#: The rows of the seed papers, in the stored tables' order (README.md), and TPE-SVR, the
#: optional extra that is not a row of the default table.
SEED_ROWS = ("ls", "stepwise", "bp", "rbf", "lssvm", "ir-lssvm", "svr-grid", "pso-svr",
             "gwo-svr", "ssa-svr", "hho-rvr")


@pytest.fixture
def own():
    """Register methods for one test, and remove them after it: ``own(key, build, **kw)``."""
    keys = []

    def register(key, build, **kwargs):
        keys.append(key)
        return register_method(key, build, **kwargs)
    yield register
    for key in keys:
        if key in available_methods():
            unregister_method(key)


def _ols(*, random_state):
    """A factory of the user's own that names one of the build arguments."""
    return make_pipeline(StandardScaler(), LinearRegression())


def test_the_seed_papers_methods_are_registered_in_the_tables_order():
    assert available_methods() == [*SEED_ROWS, "tpe-svr"]
    assert table_methods() == SEED_ROWS == CompensationSettings().methods
    assert get_method("SSA-SVR") is get_method("ssa-svr") is get_method("SSA-svr")
    assert get_method("ssa-svr").tuner == "ssa" and get_method("ssa-svr").seeded
    assert not get_method("svr-grid").seeded and not get_method("ls").tuned


def test_every_row_of_the_default_table_is_explained_in_the_user_guide():
    text = (ROOT / "docs" / "compensation.md").read_text(encoding="utf-8")
    section = re.search(r"^## What each row means$(.*?)^## ", text, flags=re.M | re.S).group(1)
    for key in table_methods():
        assert f"`{get_method(key).name}`" in section, key


@pytest.mark.parametrize("name", ["magic", "", "ssa_svr"])
def test_an_unknown_method_is_one_line_naming_it_and_the_known_ones(name):
    with pytest.raises(MethodError) as exc:
        get_method(name)
    msg = str(exc.value)
    assert msg == (f"unknown compensation method '{name}'; methods: "
                   + ", ".join(available_methods()))
    assert "\n" not in msg


def test_a_second_registration_is_an_error_unless_replace(own):
    own("ridge", Ridge(), name="Ridge")
    with pytest.raises(MethodError, match=r"^a compensation method 'ridge' is registered "
                                          r"already \(key 'ridge', row 'Ridge'\); "
                                          r"replace=True replaces it$"):
        register_method("ridge", Ridge(alpha=2.0))
    spec = register_method("ridge", Ridge(alpha=2.0), name="Ridge 2", replace=True)
    assert get_method("ridge") is spec and get_method("Ridge 2") is spec
    assert spec.build(budget=1, random_state=0, n_jobs=1).alpha == 2.0
    # a built-in's key or row label is taken, and replace=True does not take another's
    with pytest.raises(MethodError, match="'ls' is registered already"):
        register_method("ls", Ridge())
    with pytest.raises(MethodError, match=r"'ls' is registered already \(key 'ls', row 'LS'\)$"):
        register_method("ridge", Ridge(), name="LS", replace=True)
    assert available_methods()[:len(SEED_ROWS)] == list(SEED_ROWS)


@pytest.mark.parametrize("kwargs, msg", [
    ({"key": "My Method", "build": Ridge()}, "method key 'My Method': lower case, no spaces"),
    ({"key": "m", "build": 3}, "method 'm': build must be a factory or an unfitted estimator"),
    ({"key": "m", "build": lambda alpha: Ridge(alpha)}, "method 'm': its factory needs alpha"),
    ({"key": "m", "build": Ridge(), "max_samples": 0}, "max_samples must be an integer >= 1"),
    ({"key": "m", "build": Ridge(), "model_classes": (len,)}, "not a scikit-learn estimator"),
])
def test_a_method_registered_wrongly_is_one_line(kwargs, msg):
    with pytest.raises(MethodError, match=msg):
        register_method(**kwargs)
    assert "m" not in available_methods()


def test_a_factory_is_given_the_arguments_it_names_and_unset_seeds_are_set(own):
    calls = []

    def tuned(*, budget, random_state, n_jobs):
        calls.append((budget, random_state, n_jobs))
        return Ridge()
    own("t", tuned, tuner="mine")
    get_method("t").build(budget=7, random_state=3, n_jobs=2)
    assert calls == [(7, 3, 2)] and get_method("t").tuned and get_method("t").seeded
    own("o", _ols)
    assert isinstance(get_method("o").build(budget=1, random_state=0, n_jobs=1), Pipeline)
    # an estimator is cloned for every training; a random_state left at None is the seed's
    proto = make_pipeline(StandardScaler(), Ridge(solver="sag"))
    own("r", proto)
    est = get_method("r").build(budget=1, random_state=5, n_jobs=1)
    assert est is not proto and est.get_params()["ridge__random_state"] == 5
    assert proto.get_params()["ridge__random_state"] is None
    own("fixed", Ridge(solver="sag", random_state=11))
    assert get_method("fixed").build(budget=1, random_state=5, n_jobs=1).random_state == 11


def test_a_registered_method_is_a_default_row_unless_table_false(own):
    own("ridge", Ridge(), name="Ridge")
    own("quiet", Ridge(), name="Quiet", table=False)
    assert CompensationSettings().methods == (*SEED_ROWS, "ridge")


def test_a_scenario_names_a_registered_method_and_an_unknown_one_by_its_key(
        tmp_path, own, scenario_text):
    path = tmp_path / "s.toml"
    path.write_text(scenario_text("s", 5, (-20.0, 40.0), 2600.0,
                                  extra='[compensation]\nmethods = ["LS", "Ridge"]\n'))
    with pytest.raises(ScenarioError) as exc:
        nfs.load_scenario(path)
    assert "compensation.methods" in str(exc.value)
    assert "unknown compensation method 'Ridge'; methods: ls, stepwise" in str(exc.value)
    own("ridge", Ridge(), name="Ridge")
    assert nfs.load_scenario(path).compensation.methods == ("ls", "ridge")


def test_a_users_ridge_regression_is_a_row_of_the_table(tmp_path, own, scenario_text):
    own("ridge", make_pipeline(StandardScaler(), Ridge(alpha=1e-9)), name="Ridge",
        reference="ridge regression on the features")
    own("ols", _ols, name="OLS", group="least squares")
    path = tmp_path / "s.toml"
    path.write_text(scenario_text("own", 5, (-20.0, 40.0), 2600.0))
    scenario = nfs.load_scenario(path)
    # on two worker processes: the methods, registered here only, are sent to them
    settings = dataclasses.replace(CompensationSettings(), methods=("ls", "ridge", "ols"),
                                   train_seed=9, test_repeats=1, n_jobs=2)
    chain = nfs.ModelChain(scenario, settings)
    result = chain.run_model()
    names = [r.method for r in result.table.rows]
    assert names == ["before", "LS", "Ridge", "OLS", "stable", "floor"]
    assert chain.table_rows() == tuple(names)
    assert "\n| Ridge | " in result.markdown and "\n| OLS | " in result.markdown
    ridge = result.table.row("Ridge")
    assert ridge.group == "other methods" and result.table.row("OLS").group == "least squares"
    # its cells: the start-up heading RMSE of its compensated test runs, as kept
    study = result.study
    nf = study.results["Ridge"].northfind
    end_s = study.test.scenario.northfind.startup_end_s
    for i in range(2):
        errors = np.concatenate([nf[k].error_deg[nf[k].t_end_s <= end_s]
                                 for k in study.test.runs_at(i)])
        assert ridge.rmse_deg[i] == pytest.approx(float(np.sqrt(np.mean(errors ** 2))),
                                                  rel=1e-12)
    # a vanishing penalty is least squares: the same drift, the same cells
    np.testing.assert_allclose(ridge.rmse_deg, result.table.row("OLS").rmse_deg, rtol=1e-6)
    assert ridge.rmse_deg != result.table.row("LS").rmse_deg     # another model than cubic LS
    assert isinstance(study.results["Ridge"].compensator.estimator, Pipeline)


def test_the_user_guides_own_method_snippet_runs(tmp_path, monkeypatch, capsys):
    text = (ROOT / "docs" / "compensation.md").read_text(encoding="utf-8")
    section = re.search(r"^## Your own method$(.*?)^## ", text, flags=re.M | re.S).group(1)
    code = re.search(r"^```python\n(.*?)^```$", section, flags=re.M | re.S).group(1)
    monkeypatch.chdir(tmp_path)
    try:
        exec(compile(code, "docs/compensation.md", "exec"), {"__name__": "__main__"})
    finally:
        if "ridge" in available_methods():
            unregister_method("ridge")
    out = capsys.readouterr().out
    rows = [line.split("|")[1].strip() for line in out.splitlines() if line.startswith("| ")]
    assert rows == ["method", "before", "LS", "Ridge", "stable", "floor"]
    assert (tmp_path / "ridge.npz").is_file()


def test_a_plug_in_registers_its_methods_on_the_first_look_up_that_misses(monkeypatch):
    class EntryPoint:
        name = "plug"

        def load(self):
            register_method("plugged", Ridge(), name="Plugged")

    monkeypatch.setattr(catalog, "_entry_points_loaded", False)
    monkeypatch.setattr(catalog.metadata, "entry_points",
                        lambda group: [EntryPoint()] if group == catalog.ENTRY_POINT_GROUP
                        else [])
    try:
        assert get_method("Plugged").key == "plugged"
        assert "plugged" in available_methods()
    finally:
        unregister_method("plugged")
