"""Parameter-level compensation (nfs/compensate/parameters.py) and its tables
(nfs/report/parameters.py); each test names its oracle.

A short ramp (5 C -> 35 C over 8.3 h, calibrated every 10.7 min) keeps the tests fast; the
shipped scenario of Liang et al. 2021 runs the same code on a 116.7 h ramp
(scenarios/seed003_ramp_calibration.toml).
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from nfs.studies.parameter_study import (BIAS_FITTED, CONSTANT, PARAMETER_METRICS, PARAMETERS, calibrate_cycles, run_parameter_study)
from nfs.errors import ScenarioError
from nfs.config.scenario import load_scenario
from nfs.northfind import north_find, synthetic_run
from nfs.report.reference import LIANG2021_RVR_OVER_LS_PCT

RAMP = """start_temperatures_c = [5.0]
[chamber]
program = [
  { hold_s = 3600.0 },
  { power_on = true },
  { ramp_to_c = 35.0, over_s = 30000.0 },
]
[compensation]
protocol = "parameters"
methods = ["ls"]
train_repeats = 2
test_repeats = 1
n_jobs = 1
"""


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    p = tmp_path_factory.mktemp("par") / "ramp.toml"
    p.write_text(RAMP)
    return run_parameter_study(load_scenario(p), n_boot=300)


def test_a_noiseless_cycle_calibrates_the_biases_it_was_given():
    # Oracle: an ideal tilted run with gyro bias 0.37 deg/h and accelerometer biases 200 and
    # -150 ug gives them back in every cycle; the scale factor is exact (0 ppm).
    run = synthetic_run(heading_deg=212.7, latitude_deg=34.0, n_cycles=3, bias_dph=0.37,
                        tilt_north_deg=1.5, tilt_east_deg=-2.0)
    cols = dict(run.columns)
    cols["acc_x_g"] = np.asarray(cols["acc_x_g"]) + 2.0e-4
    cols["acc_y_g"] = np.asarray(cols["acc_y_g"]) - 1.5e-4
    n = len(cols["time_s"])
    for col in ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c"):
        cols[col] = np.linspace(20.0, 21.0, n)
    run = dataclasses.replace(run, columns=cols)
    cal = calibrate_cycles(run, north_find(run))
    np.testing.assert_allclose(cal.values["gyro_bias_dph"], 0.37, atol=1e-9)
    np.testing.assert_allclose(cal.values["acc_x_bias_ug"], 200.0, atol=1e-6)
    np.testing.assert_allclose(cal.values["acc_y_bias_ug"], -150.0, atol=1e-6)
    np.testing.assert_allclose(cal.values["gyro_scale_ppm"], 0.0, atol=1e-6)
    assert np.all(np.diff(cal.temperature_c["temp_fog_c"]) > 0)


def test_rows_and_metrics_are_their_definitions(study):
    # Oracle: one row per parameter and model (constant first); R^2 of the constant model
    # is ~0 and its RMSE is the test values' spread about the training mean.
    assert [(r.parameter, r.method) for r in study.parameters] == [
        (p, m) for p in PARAMETERS for m in (CONSTANT, "LS")]
    y = np.concatenate([c.values["gyro_bias_dph"] for c in study.test])
    ytr = np.concatenate([c.values["gyro_bias_dph"] for c in study.train])
    const = study.parameters[0]
    assert const.values["rmse"] == pytest.approx(np.sqrt(np.mean((y - ytr.mean()) ** 2)))
    assert const.values["r2"] == pytest.approx(
        1 - np.sum((y - ytr.mean()) ** 2) / np.sum((y - y.mean()) ** 2))
    n_finite = 0
    for r in study.parameters:
        for k in PARAMETER_METRICS:
            lo, hi = r.intervals[k]
            assert lo <= r.values[k] <= hi or not np.isfinite(lo)
            n_finite += np.isfinite(lo) and np.isfinite(hi)
    # every interval is drawn (a constant model's R^2 may sit on its bound, none is NaN)
    assert n_finite == len(study.parameters) * len(PARAMETER_METRICS)


def test_the_bias_models_follow_temperature(study):
    # Oracle: the instrument's biases follow temperature through a ramp of 30 K: a cubic
    # in the sensor's own temperature explains them (R^2 > 0.9) where a constant does not.
    by = {(r.parameter, r.method): r.values for r in study.parameters}
    for p in ("gyro_bias_dph", "acc_x_bias_ug", "acc_y_bias_ug"):
        assert by[(p, "LS")]["r2"] > 0.9
        assert by[(p, "LS")]["rmse"] < 0.2 * by[(p, CONSTANT)]["rmse"]


def test_a_rotating_schedule_cancels_the_bias_and_one_position_does_not(study):
    # Oracle: with four positions the constant-bias headings equal the fitted ones (a
    # constant bias error cancels, test_known_bias); on one position the predicted bias beats the
    # constant calibration through a 30 K ramp.
    rows = {(h.schedule, h.method): h for h in study.headings}
    fitted = rows[("as run", BIAS_FITTED)].rmse_deg
    # (the constant model's accelerometer biases and scale factor move the levelling by a
    # few parts per million of the heading error: 4.5e-6 on the default instrument)
    assert rows[("as run", CONSTANT)].rmse_deg == pytest.approx(fitted, rel=1e-5)
    # (a predicted scale factor and accelerometer biases move the levelling a hair)
    assert rows[("as run", "LS (parameters)")].rmse_deg == pytest.approx(fitted, rel=1e-3)
    one_c = rows[("one position", CONSTANT)]
    one_p = rows[("one position", "LS (parameters)")]
    assert one_p.rmse_deg < 0.5 * one_c.rmse_deg
    assert one_c.versus_best == "worse"
    assert {h.schedule for h in study.headings} == {"as run", "two positions", "one position"}
    assert rows[("two positions", CONSTANT)].positions_deg == (0.0, 90.0)


def test_table_command_writes_the_tables_with_provenance(tmp_path, cli):
    # Oracle: the JSON keys promised, the same numbers in the CSV, Liang et al.'s figures.
    p = tmp_path / "ramp.toml"
    p.write_text(RAMP)
    code, out, err = cli("table", p, "-q", "-o", tmp_path / "out", "--json", tmp_path / "p.json")
    assert code == 0, err
    assert out.startswith("| parameter | model | RMSE |") and "one position" in out
    doc = json.loads((tmp_path / "p.json").read_text())
    assert doc["protocol"] == "parameters" and doc["provenance"]["versions"]
    assert doc["published_rvr_over_ls_pct"] == LIANG2021_RVR_OVER_LS_PCT
    row = doc["parameters"][1]
    assert set(PARAMETER_METRICS) <= set(row) and len(row["rmse_ci"]) == 2
    csv_text = (tmp_path / "out" / "parameter_table.csv").read_text()
    assert repr(row["rmse"]) in csv_text or str(row["rmse"]) in csv_text
    assert (tmp_path / "out" / "heading_by_schedule.csv").exists()
    # the paper's scenario writes its figures, and the report shows them
    for png in ("parameters_vs_temperature.png", "parameter_residual_vs_time.png"):
        assert (tmp_path / "out" / png).stat().st_size > 20000
        assert f"]({png})" in (tmp_path / "out" / "report.md").read_text()
    # the chamber ramps from power-on: the start-up column says so
    assert doc["startup_stage"] == "start-up, chamber ramping"
    assert "| start-up, chamber ramping RMSE [deg] |" in out


def test_figures_of_the_parameter_study_say_what_they_draw(study):
    # Oracles: each panel's residual is the calibrated parameter minus the row's prediction
    # (the figure's line equals it); signed panels symmetric about 0; Liang et al. 2021's
    # published average (35.27 % in RMSE) in the title; every line labelled.
    from nfs.report.drift_figures import (plot_parameter_residuals,
                                          plot_parameters_vs_temperature)
    fig = plot_parameter_residuals(study)
    named = {t.get_text() for leg in fig.legends for t in leg.get_texts()}
    y = np.concatenate([c.values["gyro_bias_dph"] for c in study.test])
    for ax in fig.axes:
        lo, hi = ax.get_ylim()
        assert lo == pytest.approx(-hi)
        for line in ax.get_lines():
            if np.any(np.asarray(line.get_ydata()) != 0.0):
                assert line.get_label() in named
    ls = next(ln for ln in fig.axes[1].get_lines() if ln.get_label().startswith("LS"))
    np.testing.assert_allclose(ls.get_ydata(), y - study.predicted[("LS", "gyro_bias_dph")])
    assert "35.27 %" in fig.get_suptitle()
    fig = plot_parameters_vs_temperature(study)
    named = {t.get_text() for leg in fig.legends for t in leg.get_texts()}
    assert {"LS model", "constant: training mean (before compensation)"} <= named


def test_a_schedule_that_cannot_calibrate_is_refused_at_load(tmp_path, cli):
    # Oracle: two positions cannot calibrate the scale factor: one located error, exit 2.
    p = tmp_path / "two.toml"
    p.write_text(RAMP + "[schedule]\npositions_deg = [0.0, 180.0]\ndwell_s = 150.0\n")
    with pytest.raises(ScenarioError, match="three distinct positions"):
        load_scenario(p)
    code, _, err = cli("table", p, "-o", tmp_path / "o")
    assert code == 2 and "compensation.protocol" in err and "Traceback" not in err


def test_baseline_refused_before_any_work(tmp_path, cli):
    p = tmp_path / "ramp.toml"
    p.write_text(RAMP)
    base = tmp_path / "b.json"
    # a valid heading table (so the refusal cannot come from reading it)
    base.write_text(json.dumps({"temperatures_c": [20.0],
                                "rows": [{"method": "before", "rmse_deg": [0.01]}]}))
    code, _, err = cli("table", p, "-o", tmp_path / "o", "--baseline", base)
    assert code == 2 and not (tmp_path / "o").exists()
    assert "compensation.protocol" in err, err
