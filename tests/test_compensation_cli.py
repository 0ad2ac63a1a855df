"""nfs table with compensated rows, nfs train and nfs compensate on measurement files."""

import json

import numpy as np
import pytest


COMPENSATION = """[compensation]
methods = ["ls", "ssa-svr"]
budget = 6
train_seed = 9
test_repeats = 1
n_jobs = 1
"""


@pytest.fixture
def scen_text(scenario_text):
    return scenario_text("comp", 5, (-20.0, 10.0, 40.0), 3900.0, extra=COMPENSATION)


def test_table_with_compensation_writes_every_output(tmp_path, cli, scen_text):
    scen = tmp_path / "s.toml"
    scen.write_text(scen_text)
    out_dir = tmp_path / "out"
    code, out, err = cli("table", str(scen), "-o", str(out_dir), "-q")
    assert code == 0, err
    methods = [l.split("|")[1].strip() for l in out.splitlines()[2:] if l.startswith("| ")]
    assert methods == ["before", "LS", "SSA-SVR", "stable", "floor"]
    for name in ("heading_rmse.md", "heading_rmse.csv", "heading_rmse.json", "heading_rmse.png",
                 "drift_residual.md", "drift_residual.csv", "drift_residual.json",
                 "svr_parameters.md", "svr_parameters.csv", "svr_parameters.json",
                 "drift_vs_compensated.png", "report.md"):
        assert (out_dir / name).stat().st_size > 0, name
    params = json.loads((out_dir / "svr_parameters.json").read_text())
    assert set(params["SSA-SVR"]) == {"C", "sigma", "epsilon"}
    report = (out_dir / "report.md").read_text()
    assert "Beside seed 004" in report and "6 evaluations" in report


def test_train_and_compensate_round_trip(tmp_path, cli, scen_text):
    scen = tmp_path / "s.toml"
    scen.write_text(scen_text)
    assert cli("simulate", str(scen), "-o", str(tmp_path / "train"), "-q",
                   "--seed", "1")[0] == 0
    assert cli("simulate", str(scen), "-o", str(tmp_path / "test"), "-q",
                   "--seed", "2")[0] == 0
    model = tmp_path / "m.joblib"
    code, out, err = cli("train", str(tmp_path / "train"), "--method", "ls",
                             "-o", str(model), "-q")
    assert code == 0, err
    assert "LS trained on 3 run(s)" in out
    code, out, err = cli("compensate", str(tmp_path / "test"), "--model",
                             str(model), "-o", str(tmp_path / "comp"))
    assert code == 0, err
    from nfs.io.measurement import read_runs
    raw = read_runs(tmp_path / "test")
    comp = read_runs(tmp_path / "comp")
    for r, c in zip(raw, comp):
        # Invariant: compensated = raw - predicted drift, and the raw output is kept.
        np.testing.assert_array_equal(c["gyro_uncompensated_dph"], r["gyro_dph"])
        np.testing.assert_allclose(c["gyro_dph"], r["gyro_dph"] - c["drift_model_dph"],
                                   atol=1e-12)
    code, out, _ = cli("northfind", str(tmp_path / "comp"))
    assert code == 0 and out.count("| comp_T") == 3


def test_compensate_refuses_runs_without_its_channels(tmp_path, cli, scen_text):
    scen = tmp_path / "s.toml"
    scen.write_text(scen_text)
    cli("simulate", str(scen), "-o", str(tmp_path / "runs"), "-q")
    model = tmp_path / "m.joblib"
    code, _, err = cli("train", str(tmp_path / "runs"), "--method", "ls",
                           "--features", "T_fog", "aux_tec_power_w", "-o", str(model), "-q")
    assert code == 0, err
    # strip the aux channel from one run
    from nfs.io.measurement import read_run, write_run
    import dataclasses
    victim = sorted((tmp_path / "runs").glob("*.csv"))[0]
    run = read_run(victim)
    cols = {k: v for k, v in run.columns.items() if k != "aux_tec_power_w"}
    write_run(dataclasses.replace(run, columns=cols), tmp_path / "bad")
    code, _, err = cli("compensate", str(tmp_path / "bad"), "--model", str(model),
                           "-o", str(tmp_path / "out"))
    assert code == 2 and "has no column 'aux_tec_power_w'" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("argv, msg", [
    (["train", "RUNS", "--method", "magic", "-o", "m.joblib"], "unknown compensation method"),
    (["compensate", "RUNS", "--model", "nope.joblib", "-o", "out"], "model file not found"),
])
def test_bad_compensation_input(tmp_path, cli, scen_text, argv, msg):
    scen = tmp_path / "s.toml"
    scen.write_text(scen_text)
    cli("simulate", str(scen), "-o", str(tmp_path / "runs"), "-q")
    argv = [a.replace("RUNS", str(tmp_path / "runs")) for a in argv]
    code, _, err = cli(*argv)
    assert code == 2 and msg in err and len(err.strip().splitlines()) == 1
