"""The public API's chain: nfs.ModelChain runs simulate -> north-find -> (compensate) -> table
and keeps every intermediate.

Oracles: the table's ``before`` cell is the RMSE of the start-up headings the result keeps
(pooled over the runs at that temperature, recomputed here from the kept north-finding
results); a written table reads back as the table; the chain's table is the table the
``nfs table`` command prints for the same scenario (the CLI calls the chain), and its rows
the ones the chain names before it runs.
"""

import numpy as np
import pytest

import nfs
from nfs.scoring.tablefile import read_table

SCENARIO = """name = "two_temps"
start_temperatures_c = [-20.0, 40.0]
duration_s = 7200.0
[compensation]
test_repeats = 2
"""


@pytest.fixture(scope="module")
def scenario_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("chain") / "two_temps.toml"
    path.write_text(SCENARIO)
    return path


@pytest.fixture(scope="module")
def result(scenario_path):
    return nfs.ModelChain.from_scenario(scenario_path, compensate=False).run_model()


def test_public_names_load():
    for name in nfs.__all__:
        assert getattr(nfs, name) is not None, name
    assert "ModelChain" in dir(nfs)
    with pytest.raises(AttributeError):
        nfs.no_such_name


def test_before_row_is_the_rmse_of_the_kept_headings(result):
    assert result.compensated is False and result.study is None
    runs = result.runs
    sc = runs.scenario               # the test start-ups: test_repeats per temperature
    assert len(runs.simulations) == len(sc.start_temperatures_c) * sc.repeats
    before = result.table.row("before")
    for i, _ in enumerate(sc.start_temperatures_c):
        errors = np.concatenate([
            runs.northfind[k].error_deg[runs.northfind[k].t_end_s <= sc.northfind.startup_end_s]
            for k in runs.runs_at(i)])
        assert errors.size and before.rmse_deg[i] == pytest.approx(float(np.sqrt(np.mean(np.square(errors)))),
                                                   rel=1e-12)


def test_the_chain_names_its_rows_before_it_runs(result, scenario_path):
    chain = nfs.ModelChain.from_scenario(scenario_path, compensate=False)
    assert chain.table_rows() == tuple(r.method for r in result.table.rows)


def test_intermediates_are_kept(result):
    sim = result.runs.simulations[0]
    temps = sim.thermal.temperature_c
    assert temps.shape == (len(sim.thermal.time_s), len(sim.thermal.node_names))
    assert set(sim.gyro_terms_dph)          # every drift term by name
    assert np.isfinite(temps).all()


def test_written_table_reads_back(result, tmp_path):
    paths = result.write(tmp_path)
    assert {p.suffix for p in paths} == {".md", ".csv", ".json", ".png"}
    back = read_table(next(p for p in paths if p.suffix == ".json"))
    assert back.rmse_deg["before"] == pytest.approx(result.table.row("before").rmse_deg,
                                                    rel=1e-6)  # JSON keeps 7 digits


def test_the_command_prints_the_chains_table(result, scenario_path, cli, tmp_path):
    code, out, err = cli("table", scenario_path, "--no-compensation", "-o", tmp_path / "t",
                         "--quiet")
    assert code == 0, err
    assert out == result.markdown
