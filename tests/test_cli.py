"""The nfs command: outputs, JSON form, and one-line errors with exit code 2 on bad input."""

import argparse
import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from nfs.cli import build_parser
from nfs.io.measurement import write_run
from nfs.config.presets import default_scenario_path
from nfs.northfind.synthetic import synthetic_run

ROOT = Path(__file__).resolve().parents[1]


def one_line_error(code, err):
    assert code == 2
    lines = [l for l in err.splitlines() if l.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("nfs: error: ") and "Traceback" not in err
    return lines[0]


def test_scenarios_folder_holds_the_builtin_default():
    assert (ROOT / "scenarios" / "startup_7temps.toml").read_text() == \
        default_scenario_path().read_text()


@pytest.mark.parametrize("path", sorted((ROOT / "scenarios").glob("startup_*.toml")),
                         ids=lambda p: p.name)
def test_every_scenario_file_loads(path):
    # Oracle: the file itself; the precise variant differs from the default only in its
    # name, description and the number of start-ups.
    from nfs.config.scenario import load_scenario
    sc = load_scenario(path)
    assert sc.start_temperatures_c == (-32.0, -16.0, -5.0, 17.0, 28.0, 43.0, 54.0)
    if path.stem.endswith("precise"):
        assert (sc.compensation.test_repeats, sc.compensation.train_repeats) == (30, 3)


def _small(scenario_text):
    return scenario_text("small", 7, (-20.0, 40.0), 1300.0, latitude_deg=35.0,
                         true_heading_deg=80.0)


def test_table_simulate_northfind(tmp_path, cli, scenario_text):
    scen = tmp_path / "small.toml"
    scen.write_text(_small(scenario_text))
    code, out, err = cli("table", str(scen), "-o", str(tmp_path / "tab"),
                             "--json", str(tmp_path / "h.json"), "--no-compensation",
                             "--repeats", "1")
    assert code == 0
    assert out.splitlines()[0] == "| method | -20 | 40 | mean | 95 % CI |"
    for suffix in (".md", ".csv", ".json", ".png"):
        assert (tmp_path / "tab" / f"heading_rmse{suffix}").stat().st_size > 0
    doc = json.loads((tmp_path / "h.json").read_text())
    assert doc["temperatures_c"] == [-20.0, 40.0]
    assert [r["method"] for r in doc["rows"]] == ["before", "stable", "floor"]
    before = doc["rows"][0]
    assert before["mean_deg"] == pytest.approx(np.mean(before["rmse_deg"]), rel=1e-6)
    assert before["ci_low_deg"] <= before["mean_deg"] <= before["ci_high_deg"]
    assert "simulating" in err                      # progress on stderr

    code, out, _ = cli("simulate", str(scen), "-o", str(tmp_path / "runs"), "-q")
    assert code == 0 and len(list((tmp_path / "runs").glob("*.csv"))) == 2
    code, out, _ = cli("northfind", str(tmp_path / "runs"),
                           "--json", str(tmp_path / "nf.json"))
    assert code == 0
    nf = json.loads((tmp_path / "nf.json").read_text())
    # The same runs north-found from files give the table's start-up RMSE (all cycles of a
    # 1300 s run end before 3600 s).
    by_t0 = {r["start_temperature_c"]: r["startup_rmse_deg"] for r in nf["runs"]}
    assert by_t0[-20.0] == pytest.approx(before["rmse_deg"][0], abs=1e-8)
    assert by_t0[40.0] == pytest.approx(before["rmse_deg"][1], abs=1e-8)


def test_preset_and_effects(cli):
    code, out, _ = cli("preset")
    assert code == 0 and "default" in out.split()
    code, out, _ = cli("preset", "default")
    assert code == 0 and "[thermal.nodes.housing]" in out
    code, out, _ = cli("effects")
    assert code == 0 and "shupe_product (gyro)" in out
    for name in ("indexing_error", "axis_misalignment", "tilt_exact"):
        assert f"{name} (geometry)" in out
    assert "parameters: offsets_deg [deg], sigma_deg [deg]" in out
    code, out, _ = cli("preset", "startup_7temps")
    assert code == 0 and out == default_scenario_path().read_text()
    code, out, _ = cli("preset")
    scenarios = out.split("scenarios (")[1].split("sweeps (")[0].splitlines()[1:]
    assert [s.strip() for s in scenarios][-3:] == ["startup_7temps", "startup_7temps_fleet",
                                                   "startup_7temps_precise"]
    assert out.split("sweeps (")[1].splitlines()[1:] == ["  dwell_positions", "  latitude",
                                                          "  time_to_spec"]
    code, out, _ = cli("preset", "latitude")
    assert code == 0 and "latitude_deg = [" in out


def test_init_writes_a_starter_that_runs(tmp_path, cli):
    d = tmp_path / "mine"
    code, out, err = cli("init", d)
    assert code == 0, err
    scen = (d / "scenario.toml").read_text()
    assert 'instrument = "instrument.toml"' in scen and scen.count("\n#") > 10  # comments kept
    from nfs.instrument import preset_path
    from nfs.config.scenario import load_scenario
    # the preset's text, named after the folder (every later report names the unit)
    inst = (d / "instrument.toml").read_text()
    assert inst.replace('name = "mine"      # your unit\'s name: reports compare models by it',
                        'name = "default"') == preset_path("default").read_text()
    sc, ref = load_scenario(d / "scenario.toml"), load_scenario()
    assert sc.name == "mine" and sc.instrument.name == "mine"
    # the starter is the default experiment, its instrument read from the file beside it
    assert sc.instrument.to_toml() == dataclasses.replace(ref.instrument, name="mine").to_toml()
    assert sc.start_temperatures_c == ref.start_temperatures_c and sc.seed == ref.seed
    # a second init into the folder, now holding the user's edits, is refused
    (d / "notes.md").write_text("mine")
    code, _, err = cli("init", d)
    assert one_line_error(code, err) and "notes.md" in err
    code, _, err = cli("init", tmp_path / "x", "--from", "nope")
    assert "--from nope: no such scenario or sweep preset" in one_line_error(code, err)
    # a paper's scenario (no instrument line) and a sweep come with their instrument
    code, _, err = cli("init", tmp_path / "paper", "--from", "seed001_ramps")
    assert code == 0, err
    assert load_scenario(tmp_path / "paper" / "scenario.toml").instrument.name == "paper"
    code, _, err = cli("init", tmp_path / "lat", "--from", "latitude")
    assert code == 0 and (tmp_path / "lat" / "sweep.toml").exists(), err


# ---------------------------------------------------------------- bad scenario files

@pytest.mark.parametrize("edit, expect", [
    (lambda s: "colour = 'red'\n" + s, ["key 'colour'", "allowed keys here", "start_temperatures_c"]),
    (lambda s: s.replace("dwell_s = 150.0", "dwel_s = 150.0"),
     ["key 'schedule.dwel_s'", "allowed keys here: positions_deg"]),
    (lambda s: s.replace("positions_deg = [0.0, 90.0, 180.0, 270.0]", "positions_deg = []"),
     ["schedule.positions_deg", "must not be empty"]),
    (lambda s: s.replace('name = "small"', 'name = "small"\ninstrument = "inst.toml"'),
     ["inst.toml", "thermal.nodes.board.capacity_j_per_k", "must be > 0"]),
    (lambda s: s.replace('name = "small"', 'name = "small"\ninstrument = "inst2.toml"'),
     ["inst2.toml", "thermal.links[1].conductance_w_per_k", "must be >= 0"]),
    (lambda s: s + "[[effects]]\nname = 'shupe_gradeint'\nk_r = 0.1\n",
     ["effects[0]", "unknown effect 'shupe_gradeint'", "valid names:", "shupe_gradient"]),
    (lambda s: s + "[[effects]]\nname = 'heat_source'\nnode = 'attic'\npower = 1.0\n",
     ["unknown node 'attic'"]),
    (lambda s: s + "[[effects]]\nname = 'shupe_rate'\n", ["needs parameter 'k_s'"]),
    (lambda s: s + "[[effects]]\nname = 'indexing_error'\noffsets_deg = [0.1, 0.2]\n",
     ["effects[0]", "offsets_deg has 2 value(s), the schedule has 4 position(s)"]),
    (lambda s: s + "[[effects]]\nname = 'tilt_exact'\npitch_deg = 4.0\nroll_deg = 3.5\n",
     ["effects[0]", "exceeds 5 deg"]),
    (lambda s: s + "[[effects]]\nname = 'tilt_exact'\npitch_deg = 1.0\nroll_deg = 0.0\n",
     ["effects[0]", "the platform tilt is given twice", "tilt_north_deg = 0.02"]),
    (lambda s: s + "[schedule\n", ["TOML syntax error"]),
    (lambda s: s + "[compensation]\nfeatures_mode = 'live'\n",
     ["key 'compensation.features_mode'",
      "unknown mode 'live'; choose one of cycle, causal, offline"]),
])
def test_bad_scenario(tmp_path, cli, edit, expect, scenario_text):
    from nfs.instrument import preset_path
    text = preset_path("default").read_text()
    (tmp_path / "inst.toml").write_text(text.replace(
        "capacity_j_per_k = 380.0", "capacity_j_per_k = -380.0"))
    (tmp_path / "inst2.toml").write_text(text.replace(
        "conductance_w_per_k = 0.8", "conductance_w_per_k = -0.8"))
    scen = tmp_path / "bad.toml"
    scen.write_text(edit(_small(scenario_text)))
    out_dir = tmp_path / "out"
    for cmd in (["simulate", str(scen), "-o", str(out_dir)],
                ["table", str(scen), "-o", str(out_dir), "--no-compensation"]):
        code, out, err = cli(*cmd)
        line = one_line_error(code, err)
        assert "bad.toml" in line or "inst" in line
        for e in expect:
            assert e in line, line
        assert not out_dir.exists()       # nothing written, nothing half-written


def test_missing_scenario_file(cli, tmp_path):
    code, _, err = cli("table", str(tmp_path / "nope.toml"))
    assert "nope.toml: file not found" in one_line_error(code, err)


# ---------------------------------------------------------------- bad measurement files

GOOD_CSV = ("time_s,position_deg,moving,gyro_dph,acc_x_g,acc_y_g,temp_fog_c,temp_acc_x_c,"
            "temp_acc_y_c\n"
            + "".join(f"{t},{0 if t < 5 else 180},{int(t == 5)},1.0,0.0,0.0,20.0,20.0,20.0\n"
                      for t in range(11)))
GOOD_TOML = 'format = "nfs-measurement/1"\nlatitude_deg = 30.0\nstart_temperature_c = 20.0\n'


@pytest.mark.parametrize("csv_edit, toml_edit, expect", [
    (lambda s: s.replace("gyro_dph,", "gyro_rate,"), None, ["column", "gyro_dph"]),
    (lambda s: s.replace("3,0,0,1.0", "3,0,0,abc"), None, ["gyro_dph", "row 5"]),
    (lambda s: s.replace("\n4,", "\n2,"), None, ["time_s", "row 6"]),
    (lambda s: s.replace("7,180,0,1.0,0.0,0.0,20.0", "7,180,0,1.0,0.0,0.0,-300.0"), None,
     ["temp_fog_c", "row 9"]),
    (lambda s: s.replace("8,180,0,1.0,0.0", "8,180,0,1.0,2.5"), None, ["acc_x_g", "row 10"]),
    (None, lambda s: s.replace("latitude_deg = 30.0\n", ""), ["latitude_deg"]),
])
def test_bad_measurement(tmp_path, cli, csv_edit, toml_edit, expect):
    csv = GOOD_CSV if csv_edit is None else csv_edit(GOOD_CSV)
    toml = GOOD_TOML if toml_edit is None else toml_edit(GOOD_TOML)
    (tmp_path / "run.csv").write_text(csv)
    (tmp_path / "run.toml").write_text(toml)
    js = tmp_path / "out.json"
    js.write_text("previous")
    code, _, err = cli("northfind", str(tmp_path), "--json", str(js), "--overwrite")
    line = one_line_error(code, err)
    assert "run.csv" in line or "run.toml" in line
    for e in expect:
        assert e in line, line
    assert js.read_text() == "previous"     # nothing already written is lost, even so


def test_console_script_exit_code(tmp_path):
    """The installed entry point: exit code 2, one line, no traceback."""
    p = subprocess.run([sys.executable, "-m", "nfs.cli", "northfind", str(tmp_path / "none")],
                       capture_output=True, text=True)
    assert p.returncode == 2
    assert p.stderr.count("\n") == 1 and "Traceback" not in p.stderr
    h = subprocess.run([sys.executable, "-m", "nfs.cli", "--help"], capture_output=True,
                       text=True)
    assert h.returncode == 0 and "table" in h.stdout and "northfind" in h.stdout


def test_every_command_and_option_has_help():
    # Invariant: `nfs --help` and `nfs CMD --help` explain every command, option and
    # positional argument (argparse leaves help=None when none is given).
    parser = build_parser()
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    assert subs
    missing = []
    for action in subs:
        helps = {c.dest: c.help for c in action._choices_actions}
        for name, sub in action.choices.items():
            if not helps.get(name) and not sub.description:
                missing.append(name)
            for a in sub._actions:
                if isinstance(a, argparse._HelpAction):
                    continue
                if not a.help:
                    missing.append(f"{name} {'/'.join(a.option_strings) or a.dest}")
    assert not missing, f"no help text: {', '.join(missing)}"


def test_northfind_flags_a_two_position_run_and_takes_a_hint(tmp_path, cli):
    # Oracle: an ideal 2-position run (0, 180 deg) at heading 290 deg determines the heading
    # only up to its mirror (70 deg); a coarse hint picks the true branch to 1e-9 deg.
    write_run(synthetic_run(heading_deg=290.0, latitude_deg=35.0, positions_deg=(0.0, 180.0),
                            n_cycles=3, bias_dph=2.0, name="two"), tmp_path / "runs")
    code, out, err = cli("northfind", str(tmp_path / "runs"), "--json",
                         str(tmp_path / "a.json"))
    assert code == 0
    assert "| two |" in out and "ambiguous" in out.splitlines()[2]
    assert any(line.startswith("ambiguous: two:") and "--heading-hint" in line
               for line in out.splitlines())
    assert json.loads((tmp_path / "a.json").read_text())["runs"][0]["ambiguous"] is True
    code, out, err = cli("northfind", str(tmp_path / "runs"), "--heading-hint", "280",
                         "--json", str(tmp_path / "b.json"))
    assert code == 0 and "ambiguous" not in out
    run = json.loads((tmp_path / "b.json").read_text())["runs"][0]
    assert run["ambiguous"] is False
    assert max(abs(c["error_deg"]) for c in run["cycles"]) < 1e-9
    code, out, err = cli("northfind", str(tmp_path / "runs"), "--heading-hint", "nan")
    assert "--heading-hint" in one_line_error(code, err)


def test_runs_are_listed_by_start_temperature(tmp_path, cli, scenario_text):
    # File names sort as text (+17, -32, -5); the runs come out by T0, repeats numerically.
    scen = tmp_path / "order.toml"
    scen.write_text(scenario_text("order", 3, (17.0, -32.0, -5.0), 700.0))
    assert cli("simulate", scen, "-o", tmp_path / "runs", "--repeats", "11", "-q")[0] == 0
    code, out, _ = cli("northfind", tmp_path / "runs", "--json", tmp_path / "nf.json")
    assert code == 0
    runs = json.loads((tmp_path / "nf.json").read_text())["runs"]
    t0 = [r["start_temperature_c"] for r in runs]
    assert t0 == sorted(t0) and t0[0] == -32.0 and t0[-1] == 17.0
    names = [r["name"] for r in runs if r["start_temperature_c"] == -32.0]
    assert names == sorted(names, key=lambda n: int(n.rsplit("r", 1)[1]))


def test_thermometer_resolution_in_millikelvin_is_refused(tmp_path, cli):
    from nfs.instrument import preset_path
    text = preset_path("default").read_text()
    assert "quantum_c = 0.0625" in text
    (tmp_path / "mk.toml").write_text(text.replace("quantum_c = 0.0625", "quantum_c = 62.5", 1))
    (tmp_path / "s.toml").write_text(default_scenario_path().read_text().replace(
        'instrument = "default"', f'instrument = "{tmp_path / "mk.toml"}"'))
    code, _, err = cli("table", tmp_path / "s.toml", "-o", tmp_path / "o", "--no-compensation")
    line = one_line_error(code, err)
    assert "quantum_c" in line and "62.5 K is not a plausible" in line and "mK?" in line
