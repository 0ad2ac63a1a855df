"""nfs table --baseline: every cell against an earlier table, beyond noise and tolerance."""

import json
from pathlib import Path

import numpy as np
import pytest

from nfs.errors import NfsError
from nfs.scoring.baseline import compare_tables
from nfs.scoring.heading_table import HeadingTable, TableRow
from nfs.scoring.tablefile import TableData, read_table

PRESET = Path(__file__).resolve().parents[2] / "nfs" / "presets" / "default_instrument.toml"
LS_ONLY = """[compensation]
methods = ["ls"]
train_seed = 9
test_repeats = 1
n_jobs = 1
"""


def _side(scale=1.0, n_runs=5, n_cycles=5, seed=0, name="m", provenance=None):
    """A one-row table at two start temperatures whose cycle errors are N(0, 0.01) x scale."""
    rng = np.random.default_rng(seed)
    errs = [[0.01 * scale * rng.standard_normal(n_cycles) for _ in range(n_runs)]
            for _ in range(2)]
    rmse = tuple(float(np.sqrt(np.mean(np.concatenate(c) ** 2))) for c in errs)
    return TableData((-20.0, 40.0), {name: rmse, "floor": (0.004, 0.004)}, {name: errs},
                     provenance, None, "synthetic")


def test_identical_tables_differ_by_exactly_zero():
    c = compare_tables(_side(), _side(), paired=True, n_boot=500)
    assert c.exit_code == 0 and c.paired
    for cell in c.cells:
        assert cell.change_deg == 0.0 and cell.ci_low_deg == 0.0 == cell.ci_high_deg
        assert cell.verdict == "within noise"


def test_scaled_errors_change_by_the_scale_and_the_tolerance_decides():
    # Oracle: every cycle error x 1.5 -> every RMSE x 1.5 exactly (+50 %); paired on the
    # same cycles, every replicate moves by +50 % too, so the interval excludes 0.
    c = compare_tables(_side(1.5), _side(), paired=True, n_boot=500)
    m = [x for x in c.cells if x.method == "m"]
    assert all(abs(x.relative - 0.5) < 1e-6 and x.ci_low_deg > 0 for x in m)
    assert [x.verdict for x in m] == ["worse"] * 3 and c.exit_code == 1
    assert c.summary().startswith("3 cells worse beyond noise and 5 %: m at -20 C, m at 40 C, "
                                  "m (mean)")
    # beyond noise but inside a 60 % tolerance: not worse
    c = compare_tables(_side(1.5), _side(), paired=True, n_boot=500, tolerance=0.6)
    assert c.exit_code == 0 and {x.verdict for x in c.cells} == {"within noise"}
    # the mirror image
    c = compare_tables(_side(0.5), _side(), paired=True, n_boot=500)
    assert {x.verdict for x in c.cells if x.method == "m"} == {"better"}


def test_a_row_without_cycle_errors_counts_as_exact():
    new = _side()
    new = TableData(new.temperatures_c, {**new.rmse_deg, "floor": (0.012, 0.004)},
                    new.errors_deg, None, None, "synthetic")
    c = compare_tables(new, _side(), paired=True, n_boot=200)
    floor = {x.column: x for x in c.cells if x.method == "floor"}
    assert floor["-20"].ci_low_deg == floor["-20"].ci_high_deg == pytest.approx(0.008)
    assert floor["-20"].verdict == "worse" and floor["40"].verdict == "within noise"


def test_unpaired_intervals_hold_both_tables_noise():
    # Two draws of the same errors' law: unpaired, the interval of the change is wide and
    # holds 0; paired (as if the same start-ups) the same data would look different.
    a, b = _side(seed=1), _side(seed=2)
    c = compare_tables(a, b, paired=False, n_boot=1000)
    assert not c.paired
    for x in c.cells:
        if x.method == "m":
            assert x.ci_low_deg < x.change_deg < x.ci_high_deg


def test_pairing_follows_the_seed_of_the_test_start_ups():
    p = {"seeds": {"test_start_ups": 5}}
    c = compare_tables(_side(provenance=p), _side(provenance=p), n_boot=100)
    assert c.paired and c.notes[0].startswith("paired: the same test start-ups (seed 5, 5 per")
    c = compare_tables(_side(provenance={"seeds": {"test_start_ups": 6}}),
                       _side(provenance=p), n_boot=100)
    assert not c.paired and "seed 5 in the baseline, 6 now" in c.notes[0]
    c = compare_tables(_side(n_runs=4, provenance=p), _side(provenance=p), n_boot=100)
    assert not c.paired and "numbers of test start-ups" in c.notes[0]


def test_table_json_keeps_the_cycle_errors_compactly():
    errs = {"before": [[np.array([0.01, -0.02]), np.array([0.015])],
                       [np.array([0.0123456789123, np.nan]), np.array([])]]}
    t = HeadingTable((-5.0, 17.0), (TableRow("before", (0.0, 0.0)),)).with_intervals(
        errs, n_boot=50)
    text = t.to_json()
    line = next(s for s in text.splitlines() if s.strip().startswith('"before": [[['))
    assert line.strip() == '"before": [[[0.01,-0.02],[0.015]],[[0.012345679,null],[]]]'
    back = read_table(json.loads(text))
    assert back.errors_deg["before"][1][0][0] == 0.012345679
    assert np.isnan(back.errors_deg["before"][1][0][1])
    assert json.loads(text)["provenance"] is None


@pytest.fixture
def scen(tmp_path, scenario_text):
    """A small scenario (two start temperatures, 7100 s: a stable stage), its copy with three
    times the angle random walk, and another scenario (other name and seed)."""
    def write(name, seed, instrument=None, extra=""):
        text = scenario_text(name, seed, (-20.0, 40.0), 7100.0, extra=extra)
        if instrument:
            text = f'instrument = "{instrument}"\n' + text
        path = tmp_path / f"{name}.toml"
        path.write_text(text)
        return path
    arw = PRESET.read_text().replace("arw_deg_per_rth_h = 0.0003 ", "arw_deg_per_rth_h = 0.0009 ")
    assert "0.0009" in arw
    (tmp_path / "arw3.toml").write_text(arw)
    return {"same": write("reg", 5), "arw3": write("reg_arw3", 5, "arw3.toml"),
            "other": write("other", 6)}


def _table(cli, tmp_path, scenario, name, *extra):
    return cli("table", scenario, "-o", tmp_path / name, "-q", "--no-compensation", *extra)


def test_unchanged_rerun_passes_and_three_times_the_arw_fails(tmp_path, cli, scen):
    base = tmp_path / "base.json"
    code, _, err = _table(cli, tmp_path, scen["same"], "b", "--json", base)
    assert code == 0, err
    doc = json.loads(base.read_text())
    prov = doc["provenance"]
    assert set(prov["versions"]) >= {"nfs", "numpy", "scipy", "scikit-learn", "pywavelets"}
    assert prov["seeds"]["test_start_ups"] == 5 and len(prov["scenario"]["sha256"]) == 64
    assert len(prov["scenario"]["instrument"]["sha256"]) == 64 and prov["platform"]
    assert set(doc["errors_deg"]) == {"before", "stable"}

    code, out, err = _table(cli, tmp_path, scen["same"], "again", "--baseline", base)
    assert code == 0, err
    comp = json.loads((tmp_path / "again" / "baseline_comparison.json").read_text())
    assert comp["paired"] and comp["methods"] == ["before", "stable", "floor"]
    assert all(c["verdict"] == "within noise" and c["change_deg"] == 0.0 for c in comp["cells"])
    assert "no cell worse beyond noise and 5 % (9 cells: 0 better, 9 within noise)" in out
    assert (tmp_path / "again" / "baseline_comparison.md").read_text().startswith("# Against")
    manifest = json.loads((tmp_path / "again" / "nfs-manifest.json").read_text())
    assert manifest["inputs"]["baseline"]["file"] == str(base)
    assert "baseline_comparison.json" in {f["path"] for f in manifest["files"]}

    code, out, err = _table(cli, tmp_path, scen["arw3"], "worse", "--baseline", base)
    assert code == 1, err
    comp = json.loads((tmp_path / "worse" / "baseline_comparison.json").read_text())
    cells = {(c["method"], c["temperature_c"]): c for c in comp["cells"]}
    # Oracle: the white-noise floor is proportional to the ARW (closed form): +200 % exactly
    assert cells[("floor", -20.0)]["change_pct"] == pytest.approx(200.0, abs=1e-3)
    # the stable stage's error is partly white noise (the rest bias instability and drift):
    # the same draws with three times the ARW, so between +0 % and +200 % (measured +70 %)
    for t in (-20.0, 40.0):
        assert cells[("stable", t)]["verdict"] == "worse", cells[("stable", t)]
        assert 5.0 < cells[("stable", t)]["change_pct"] < 200.0
    assert "floor at -20 C" in comp["worse"] and "stable at 40 C" in comp["worse"]
    summary = out.strip().splitlines()[-1]
    assert summary.startswith(f"{len(comp['worse'])} cells worse beyond noise and 5 %: ")
    assert "another instrument: the baseline's is" in out and "paired:" in out
    assert "another scenario" in out           # another name: reg -> reg_arw3


def test_a_baseline_of_another_scenario_still_compares_and_says_so(tmp_path, cli, scen):
    base = tmp_path / "other.json"
    assert _table(cli, tmp_path, scen["other"], "o", "--json", base)[0] == 0
    code, out, err = _table(cli, tmp_path, scen["same"], "s", "--baseline", base,
                            "--tolerance", "0.5")
    assert code in (0, 1), err
    assert "another scenario: the baseline's is 'other'" in out
    assert "unpaired: other test start-ups (seed 6 in the baseline, 5 now)" in out
    assert "another instrument" not in out


def test_baseline_with_compensation_and_without(tmp_path, cli, scenario_text):
    scen = tmp_path / "s.toml"
    scen.write_text(scenario_text("comp", 5, (-20.0, 40.0), 2600.0, extra=LS_ONLY))
    base = tmp_path / "full.json"
    assert cli("table", scen, "-o", tmp_path / "a", "-q", "--json", base)[0] == 0
    code, out, err = cli("table", scen, "-o", tmp_path / "b", "-q", "--baseline", base)
    assert code == 0, err
    comp = json.loads((tmp_path / "b" / "baseline_comparison.json").read_text())
    assert comp["methods"] == ["before", "LS", "stable", "floor"]
    # runs of 2600 s have no stable stage (5400 s on): a row of "-", and a note says why
    assert "| stable | - | - | - |" in out
    assert ("stable: - at every start temperature: the runs (2600 s) end before the stable "
            "stage starts (5400 s).") in out
    assert all(c["change_deg"] in (0.0, None) for c in comp["cells"])
    # the uncompensated table against the full one: the rows they share
    code, out, err = cli("table", scen, "-o", tmp_path / "c", "-q", "--no-compensation",
                         "--baseline", base)
    assert code == 0, err
    assert "rows only in the baseline, not compared: LS" in out
    assert "| before | 0 % | 0 % | 0 % |" in out


@pytest.mark.parametrize("content, msg", [
    (None, "cannot read the file"),
    ("{not json", "not JSON"),
    ("[1, 2]", "not a heading table written by nfs table --json"),
    ('{"temperatures_c": [-20.0], "rows": [{"method": "before", "rmse_deg": [0.1, 0.2]}]}',
     "'rmse_deg' needs 1 numbers"),
    ('{"temperatures_c": [99.0], "rows": [{"method": "before", "rmse_deg": [0.1]}]}',
     "no start temperature in common with the table"),
    ('{"temperatures_c": [-20.0], "rows": [{"method": "magic", "rmse_deg": [0.1]}]}',
     "no row in common with the table"),
])
def test_bad_baseline_is_one_located_line_before_any_work(tmp_path, cli, scenario_text,
                                                          content, msg):
    scen = tmp_path / "s.toml"
    scen.write_text(scenario_text("bad", 5, (-20.0, 40.0), 1300.0))
    base = tmp_path / "base.json"
    if content is not None:
        base.write_text(content)
    code, out, err = cli("table", scen, "-o", tmp_path / "out", "-q", "--no-compensation",
                         "--baseline", base)
    assert code == 2 and msg in err and str(base) in err, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("argv, msg", [
    (["--tolerance", "0.1"], "--tolerance needs --baseline"),
    (["--baseline", "B", "--tolerance", "-1"], "--tolerance must be a finite number >= 0"),
])
def test_bad_tolerance(tmp_path, cli, argv, msg):
    argv = [str(tmp_path / "b.json") if a == "B" else a for a in argv]
    code, _, err = cli("table", "-o", tmp_path / "out", "-q", *argv)
    assert code == 2 and msg in err and len(err.strip().splitlines()) == 1


def test_compare_tables_refuses_a_bad_tolerance():
    with pytest.raises(NfsError, match="tolerance"):
        compare_tables(_side(), _side(), tolerance=float("nan"))


def test_northfind_json_records_its_provenance(tmp_path, cli, scenario_text):
    scen = tmp_path / "s.toml"
    scen.write_text(scenario_text("nf", 5, (-20.0,), 1300.0))
    assert cli("simulate", scen, "-o", tmp_path / "runs", "-q")[0] == 0
    for name in ("a.json", "b.json"):
        assert cli("northfind", tmp_path / "runs", "--json", tmp_path / name)[0] == 0
    doc = json.loads((tmp_path / "a.json").read_text())
    prov = doc["provenance"]
    assert prov["versions"]["nfs"] and len(prov["runs"][0]["sha256"]) == 64
    # no time stamp: the same inputs give the same bytes
    assert (tmp_path / "a.json").read_bytes() == (tmp_path / "b.json").read_bytes()
