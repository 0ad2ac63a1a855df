"""The shipped scenarios of the papers' own experiments load and run as the papers describe
them; the oracle of each test is the paper's text (cited in the scenario files)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from nfs.experiment import simulate_run
from nfs.studies.scenario_runs import northfind_runs
from nfs.config.scenario import load_scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


@pytest.mark.parametrize("stem, paper", [
    ("seed000_temperature_cycle", "Tao, Li, Zheng, Wu and Fu"),
    ("seed001_ramps", "Cheng, Qi, Chen and Landry"),
    ("seed003_ramp_calibration", "Liang, Tao, Wang, Guo and Zhao"),
])
def test_scenario_cites_its_paper_and_never_a_seed_number(stem, paper):
    text = (SCENARIOS / f"{stem}.toml").read_text()
    assert paper in text
    comments = " ".join(line.split("#", 1)[1] for line in text.splitlines() if "#" in line)
    assert "seed 0" not in comments.lower() and "seed0" not in comments.lower()
    assert load_scenario(SCENARIOS / f"{stem}.toml").name == stem


def test_temperature_cycle_twice():
    # Oracle: Tao et al. 2019, section 4.1: 2 h at 25 C, 1 C/min to -40 C, 6 h, 1 C/min to
    # 70 C, 10 h, 1 C/min to 25 C, 4 h; twice; the oscillator-voltage channel recorded.
    sc = load_scenario(SCENARIOS / "seed000_temperature_cycle.toml")
    cycle_s = 7200 + 65 * 60 + 21600 + 110 * 60 + 36000 + 45 * 60 + 14400
    assert sc.run_duration_s(25.0) == 2 * cycle_s
    (cond,) = sc.conditions()
    t = np.array([0, 7200 + 3900, 7200 + 3900 + 21600 + 6600, cycle_s - 1, cycle_s + 7200 + 1950])
    np.testing.assert_allclose(cond.chamber_c(t), [25.0, -40.0, 70.0, 25.0, -7.5], atol=1e-9)
    r = simulate_run(sc.instrument, cond)
    assert r.run["time_s"].size == 2 * cycle_s
    assert "aux_osc_v" in r.run.columns and "aux_linear:aux_osc_v" in r.gyro_terms_dph


def test_hold_and_ramp_three_gyros_five_times():
    # Oracle: Cheng et al. 2015, section 4.1: 1 h at 10 C, up to 40 C, 2 h; three gyros five
    # times each (start-up r by unit r mod 3).
    sc = load_scenario(SCENARIOS / "seed001_ramps.toml")
    conds = sc.conditions()
    assert len(conds) == 15 and sorted({c.unit for c in conds}) == [0, 1, 2]
    assert [sum(c.unit == u for c in conds) for u in range(3)] == [5, 5, 5]
    assert conds[0].duration_s == 3600 + 150 * 60 + 7200
    assert conds[0].chamber_c(np.array([3600.0, 12600.0])) == pytest.approx([10.0, 40.0])


def test_ramp_calibration_175_cycles_after_a_soak():
    # Oracle: Liang et al. 2021, section 4.1: 4 h soak at 5 C, then 7000 min to 65 C with a
    # calibration every ~40 min, 175 in all; each north-finding cycle is one calibration.
    sc = load_scenario(SCENARIOS / "seed003_ramp_calibration.toml")
    (cond,) = sc.conditions()
    assert cond.soak_s == 4 * 3600.0 and cond.duration_s == 7000 * 60.0
    assert sc.schedule.cycle_s == 2400.0
    r = simulate_run(sc.instrument, cond)
    assert r.run.meta.start_temperature_c == 5.0
    assert r.run["temp_chamber_c"][-1] == pytest.approx(65.0, abs=2e-4)
    (nf,) = northfind_runs([r.run], sc.northfind)
    assert nf.n_cycles == 175


def test_ramps_table_has_the_shape_of_cheng_et_al(tmp_path, cli):
    # Oracle: Cheng et al. 2015, Table 2: compensation on T, dT and T x dT shrinks the mean
    # square deviation of every test run; every row's improvement interval lies above 0.
    code, out, err = cli("table", SCENARIOS / "seed001_ramps.toml", "-q", "-o",
                         tmp_path / "o", "--json", tmp_path / "t.json")
    assert code == 0, err
    doc = json.loads((tmp_path / "t.json").read_text())
    assert doc["protocol"] == "runs" and len(doc["parts"]) == 5
    before = doc["rows"][0]["msd_by_part_dph2"]
    for row in doc["rows"][1:]:
        assert row["improvement_pct_ci"][0] > 0
        assert all(a < b for a, b in zip(row["msd_by_part_dph2"], before))
    assert "Cheng et al. 2015" in out


@pytest.mark.slow  # 9 ramp runs and every method; the cycle and parameter tables run by default
def test_ramp_calibration_table_has_the_shape_of_liang_et_al(tmp_path, cli):
    # Oracle: Liang et al. 2021: the temperature models of the calibrated parameters beat a
    # constant (R^2 near 1 for the biases), and the predicted biases are what a schedule
    # that does not cancel them needs (one position: the parameter rows beat the constant).
    code, out, err = cli("table", SCENARIOS / "seed003_ramp_calibration.toml", "-q", "-o",
                         tmp_path / "o", "--json", tmp_path / "p.json")
    assert code == 0, err
    doc = json.loads((tmp_path / "p.json").read_text())
    by = {(r["parameter"], r["method"]): r for r in doc["parameters"]}
    for method in ("LS", "HHO-RVR"):
        assert by[("gyro_bias_dph", method)]["r2"] > 0.99
        assert by[("gyro_bias_dph", method)]["rmse_ci"][1] < \
            by[("gyro_bias_dph", "constant")]["rmse_ci"][0]
    one = {h["method"]: h for h in doc["headings"] if h["schedule"] == "one position"}
    assert one["HHO-RVR (parameters)"]["heading_rmse_deg_ci"][1] < \
        one["constant"]["heading_rmse_deg_ci"][0]
    assert "Liang et al. 2021" in out
