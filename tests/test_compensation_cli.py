"""nfs table with compensated rows, nfs train and nfs compensate on measurement files."""

import json

import numpy as np
import pytest

import nfs
from nfs.compensate import get_method


COMPENSATION = """[compensation]
methods = ["ls", "ssa-svr"]
budget = 6
tuner_seeds = 2
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
    assert "Beside the FOG start-up paper" in report and "6 evaluations" in report
    # the features mode (default: cycle) in every output that uses the features
    assert "Features mode: cycle (" in out and "Features mode: **cycle**" in report
    assert json.loads((out_dir / "heading_rmse.json").read_text())["features_mode"] == "cycle"
    csv = (out_dir / "heading_rmse.csv").read_text().splitlines()
    head = csv[0].split(",")
    assert head[:5] == ["method", "-20", "10", "40", "mean"] and head[-1] == "features_mode"
    assert head[5:7] == ["mean_ci_low", "mean_ci_high"] and "-20_ci_low" in head
    assert "vs_best" in head and csv[2].endswith(",cycle")
    assert csv[1].startswith("before,") and csv[1].endswith(",")
    # intervals: every row but the floor has one around its mean, cells included
    doc = json.loads((out_dir / "heading_rmse.json").read_text())
    for row in doc["rows"]:
        if row["method"] == "floor":
            assert row["ci_low_deg"] is None and row["cell_ci_deg"] is None
            continue
        if row["mean_deg"] is None:            # stable: these runs end before that stage
            assert row["ci_low_deg"] is None
            continue
        assert row["ci_low_deg"] <= row["mean_deg"] <= row["ci_high_deg"], row
        assert len(row["cell_ci_deg"]) == 3
    pairs = {(c["method_a"], c["method_b"]) for c in doc["comparisons"]}
    assert {("LS", "before"), ("SSA-SVR", "before"), ("SSA-SVR", "LS")} <= pairs
    for c in doc["comparisons"]:
        assert c["ci_low_deg"] <= c["difference_deg"] <= c["ci_high_deg"]
        assert c["p_value"] <= c["p_adjusted"] <= 1.0
        assert c["distinguishable"] == (c["p_adjusted"] < 0.05)
    assert doc["best"] in ("LS", "SSA-SVR")
    rows = {r["method"]: r for r in doc["rows"]}
    assert len(rows["SSA-SVR"]["seed_means_deg"]) == 2 and rows["LS"]["seed_means_deg"] == []
    assert rows["SSA-SVR"]["mean_deg"] == max(rows["SSA-SVR"]["seed_means_deg"])
    assert "95 % CI" in out.splitlines()[0] and "SSA-SVR vs LS: " in out
    row_csv = next(line for line in csv if line.startswith("SSA-SVR,")).split(",")
    assert row_csv[head.index("vs_best")] in ("best", "tie", "worse")
    drift = json.loads((out_dir / "drift_residual.json").read_text())
    assert [d["features_mode"] for d in drift] == [None, "cycle", "cycle"]


LS_ONLY = """[compensation]
methods = ["ls"]
train_seed = 9
test_repeats = 1
n_jobs = 1
"""


def test_table_features_mode_option_and_same_bytes(tmp_path, cli, scenario_text):
    # Determinism: the same seed gives the same bytes in every output file (tables, report,
    # figures), in the mode asked for on the command line.
    scen = tmp_path / "s.toml"
    scen.write_text(scenario_text("modes", 5, (-20.0, 40.0), 2600.0, extra=LS_ONLY))
    outs = []
    for name in ("a", "b"):
        code, out, err = cli("table", str(scen), "-o", str(tmp_path / name), "-q",
                             "--features-mode", "causal")
        assert code == 0, err
        outs.append(out)
    assert outs[0] == outs[1] and "Features mode: causal (" in outs[0]
    files = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert "report.md" in files and "heading_rmse.png" in files
    for name in files:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name
    doc = json.loads((tmp_path / "a" / "heading_rmse.json").read_text())
    assert doc["features_mode"] == "causal"
    code, out, err = cli("table", str(scen), "-o", str(tmp_path / "off"), "-q",
                         "--features-mode", "offline", "--json", str(tmp_path / "off.json"))
    assert code == 0, err
    assert "Features mode: offline (OFFLINE:" in out
    assert json.loads((tmp_path / "off.json").read_text())["features_mode"] == "offline"
    assert "Features mode: **offline**" in (tmp_path / "off" / "report.md").read_text()


def test_train_and_compensate_keep_one_features_mode(tmp_path, cli, scenario_text):
    scen = tmp_path / "s.toml"
    scen.write_text(scenario_text("modes", 5, (-20.0, 40.0), 1300.0))
    assert cli("simulate", str(scen), "-o", str(tmp_path / "runs"), "-q")[0] == 0
    model = tmp_path / "m.npz"
    code, out, err = cli("train", str(tmp_path / "runs"), "--method", "ls", "-o", str(model),
                         "-q", "--features-mode", "causal")
    assert code == 0, err
    assert "(causal mode)" in out
    from nfs.compensate import load_compensator
    assert load_compensator(model).features_mode == "causal"
    code, _, err = cli("compensate", str(tmp_path / "runs"), "--model", str(model),
                       "-o", str(tmp_path / "out"), "--features-mode", "cycle")
    assert code == 2 and "trained in causal mode" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()
    code, _, err = cli("compensate", str(tmp_path / "runs"), "--model", str(model),
                       "-o", str(tmp_path / "out"), "--features-mode", "causal")
    assert code == 0, err


def test_train_and_compensate_round_trip(tmp_path, cli, scen_text):
    scen = tmp_path / "s.toml"
    scen.write_text(scen_text)
    assert cli("simulate", str(scen), "-o", str(tmp_path / "train"), "-q",
                   "--seed", "1")[0] == 0
    assert cli("simulate", str(scen), "-o", str(tmp_path / "test"), "-q",
                   "--seed", "2")[0] == 0
    model = tmp_path / "m.npz"
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
    model = tmp_path / "m.npz"
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
    (["train", "RUNS", "--method", "magic", "-o", "m.npz"], "unknown compensation method"),
    (["compensate", "RUNS", "--model", "nope.npz", "-o", "out"], "model file not found"),
    (["train", "RUNS", "--method", "ls", "-o", "m.npz", "--features-mode", "live"],
     "--features-mode: unknown mode 'live'; choose one of cycle, causal, offline"),
    (["table", "--features-mode", "centred", "-o", "out"],
     "--features-mode: unknown mode 'centred'; choose one of cycle, causal, offline"),
    (["table", "--tuner-seeds", "0", "-o", "out"], "--tuner-seeds must be >= 1, got 0"),
])
def test_bad_compensation_input(tmp_path, cli, scen_text, argv, msg):
    scen = tmp_path / "s.toml"
    scen.write_text(scen_text)
    cli("simulate", str(scen), "-o", str(tmp_path / "runs"), "-q")
    argv = [a.replace("RUNS", str(tmp_path / "runs")) for a in argv]
    code, _, err = cli(*argv)
    assert code == 2 and msg in err and len(err.strip().splitlines()) == 1


def test_bad_tuner_seeds_in_the_scenario_names_the_key(tmp_path, cli, scenario_text):
    scen = tmp_path / "s.toml"
    scen.write_text(scenario_text("bad", 5, (-20.0, 40.0), 1300.0,
                                  extra="[compensation]\ntuner_seeds = 0\n"))
    code, _, err = cli("table", str(scen), "-o", str(tmp_path / "out"), "-q")
    assert code == 2 and "compensation.tuner_seeds" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_before_row_is_the_same_start_ups_with_and_without_compensation(tmp_path, cli,
                                                                         scenario_text):
    # One name, one number: --no-compensation tabulates the full table's test start-ups
    # (test_repeats = 2 here, against repeats = 1 of the scenario itself).
    scen = tmp_path / "s.toml"
    scen.write_text(scenario_text("before", 5, (-20.0, 40.0), 2600.0,
                                  extra=LS_ONLY.replace("test_repeats = 1", "test_repeats = 2")))
    rows = []
    for extra in ([], ["--no-compensation"]):
        code, _, err = cli("table", scen, "-o", tmp_path / f"o{len(extra)}", "-q",
                           "--json", tmp_path / f"t{len(extra)}.json", *extra)
        assert code == 0, err
        doc = json.loads((tmp_path / f"t{len(extra)}.json").read_text())
        rows.append(next(r for r in doc["rows"] if r["method"] == "before"))
    assert rows[0]["rmse_deg"] == rows[1]["rmse_deg"]


PROGRAM = """[chamber]
program = [{ hold_s = 600.0 }, { ramp_to_c = 30.0, rate_c_per_min = 0.5 }, { hold_s = 6000.0 }]
"""


def test_the_baseline_is_checked_against_the_chains_rows(tmp_path, cli, scenario_text):
    # The rows the command checks a baseline against are those of the table the chain
    # makes: under a chamber program that moves the chamber, before, held, ramping and
    # floor (no stable stage), so a baseline of the held stage alone is compared, and the
    # printed table holds the chain's rows in the chain's order.
    scen = tmp_path / "s.toml"
    scen.write_text(scenario_text("prog", 5, (20.0,), 6600.0, extra=PROGRAM))
    rows = nfs.ModelChain.from_scenario(scen, compensate=False).table_rows()
    assert rows == ("before", "held", "ramping", "floor")
    base = tmp_path / "held.json"
    base.write_text(json.dumps({"temperatures_c": [20.0],
                                "rows": [{"method": "held", "rmse_deg": [0.0066]}]}))
    code, out, err = cli("table", scen, "-o", tmp_path / "o", "-q", "--no-compensation",
                         "--baseline", base, "--tolerance", "10")
    assert code == 0, err
    printed = [line.split("|")[1].strip() for line in out.split("\n\n")[0].splitlines()[2:]]
    assert tuple(printed) == rows
    comp = json.loads((tmp_path / "o" / "baseline_comparison.json").read_text())
    assert comp["methods"] == ["held"]
    # a table with compensation names each method's row where the table will have it
    methods = [get_method(m).name for m in nfs.CompensationSettings().methods]
    assert nfs.ModelChain.from_scenario(scen).table_rows() == (
        "before", *methods, "held", "ramping", "floor")
