"""Chamber programs in scenario files (nfs/io/chamber.py) and scenario inheritance (``base``
and the built-in default); each test names its oracle."""

from __future__ import annotations

import json

import numpy as np
import pytest

from nfs.errors import ScenarioError
from nfs.instrument import preset_path
from nfs.conditions import conditions_from_run
from nfs.experiment import simulate_run
from nfs.studies.scenario_runs import run_scenario
from nfs.io.measurement import read_run, write_run
from nfs.config.scenario import load_scenario

# The program of the chamber-program example, exactly as written in the user guide
# (docs/scenarios.md, "Chamber programs").
EXAMPLE = """start_temperatures_c = [25.0]
[chamber]
program = [
  { hold_s = 1800.0 },
  { ramp_to_c = 10.0, rate_c_per_min = 1.0 },
  { hold_s = 1800.0 },
  { ramp_to_c = 25.0, rate_c_per_min = 0.5 },
  { hold_s = 1800.0 },
]
"""
# its corners: 1800 s hold, 15 K at 1 K/min = 900 s, hold, 15 K at 0.5 K/min = 1800 s, hold
CORNERS_T = [0.0, 1800.0, 2700.0, 4500.0, 6300.0, 8100.0]
CORNERS_C = [25.0, 25.0, 10.0, 10.0, 25.0, 25.0]

SHORT = '[schedule]\npositions_deg = [0.0, 180.0]\ndwell_s = 100.0\nmove_s = 10.0\n'


def write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def one_line_error(code, err):
    assert code == 2
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("nfs: error: "), err
    return lines[0]


# ---------------------------------------------------------------------- the example as written

def test_example_program_lasts_as_long_as_its_program(tmp_path):
    # Oracle: the corners computed by hand above; the chamber column is the program itself
    # (linear between corners), every other key from the built-in default.
    sc = load_scenario(write(tmp_path, EXAMPLE))
    default = load_scenario()
    assert sc.duration_s is None and sc.run_duration_s(25.0) == 8100.0
    assert (sc.schedule, sc.latitude_deg, sc.seed) == (default.schedule, default.latitude_deg,
                                                      default.seed)
    assert sc.name == "s" and not sc.variability.active
    (cond,) = sc.conditions()
    amb = cond.chamber_c(np.arange(8100.0))
    np.testing.assert_allclose(amb, np.interp(np.arange(8100.0), CORNERS_T, CORNERS_C),
                               rtol=0, atol=1e-12)
    assert amb[2250] == pytest.approx(17.5, abs=1e-12)       # half-way down the first ramp


def test_example_program_simulates_and_tabulates(tmp_path, cli):
    # Oracle: the commands exit 0 on the file exactly as the README writes it; the recorded
    # chamber follows the program; the run north-finds with the default schedule
    # (8100 s / 640 s per cycle = 12 cycles) and the table has its one column.
    p = write(tmp_path, EXAMPLE)
    code, out, err = cli("simulate", p, "-o", tmp_path / "runs", "-q")
    assert code == 0, err
    run = read_run(out.split()[0])
    assert run["time_s"].size == 8100 and run.meta.start_temperature_c == 25.0
    np.testing.assert_allclose(run["temp_chamber_c"],
                               np.interp(run["time_s"], CORNERS_T, CORNERS_C), atol=1e-9)
    code, out, err = cli("table", p, "--no-compensation", "-q", "-o", tmp_path / "tab",
                         "--json", tmp_path / "t.json")
    assert code == 0, err
    assert out.splitlines()[0].startswith("| method | 25 |")
    doc = json.loads((tmp_path / "t.json").read_text())
    # the program ramps: the cycles after the start-up are named for what the chamber does
    assert [r["method"] for r in doc["rows"]] == ["before", "held", "ramping", "floor"]
    res = run_scenario(load_scenario(p))
    assert res.northfind[0].n_cycles == 12


def test_a_program_run_replays_from_its_file(tmp_path):
    # Invariant: the run simulated again from its own file (time base, motion, the recorded
    # chamber column interpolated, same seed) is the same run: what fit / compare /
    # diagnose rely on to put a model beside a measured programmed run.
    sc = load_scenario(write(tmp_path, "duration_s = 3000.0\n" + EXAMPLE))
    cond = sc.conditions()[0]
    r0 = simulate_run(sc.instrument, cond)
    run = read_run(write_run(r0.run, tmp_path / "runs"))
    r1 = simulate_run(sc.instrument, conditions_from_run(run, seed=cond.seed))
    for c in ("gyro_dph", "acc_x_g", "temp_fog_c", "temp_acc_y_c", "temp_chamber_c"):
        np.testing.assert_allclose(r1.run[c], run[c], rtol=0, atol=1e-8, err_msg=c)


# ---------------------------------------------------------------------------------- the steps

def corners(tmp_path, program, t0=20.0, extra=""):
    sc = load_scenario(write(tmp_path, f"start_temperatures_c = [{t0}]\n{extra}{SHORT}"
                                       f"[chamber]\nprogram = {program}\n"))
    return sc, sc.chamber.program.corners(t0, 1.0 / sc.sample_rate_hz)


def test_ramp_over_a_time_a_step_and_repeat(tmp_path):
    # Oracle: hand arithmetic; a repeat is its steps written N times; a step is a ramp over
    # one sample interval (1 s).
    _, (t, c) = corners(tmp_path, "[{ ramp_to_c = 30.0, over_s = 600.0 }, { step_to_c = 0.0 },"
                                  " { repeat = 2, steps = [{ hold_s = 100.0 },"
                                  " { ramp_to_c = 10.0, rate_c_per_min = 2.0 },"
                                  " { ramp_to_c = 0.0, over_s = 60.0 }] }]")
    np.testing.assert_allclose(t, [0, 600, 601, 701, 1001, 1061, 1161, 1461, 1521])
    np.testing.assert_allclose(c, [20, 30, 0, 0, 10, 0, 0, 10, 0])


def test_each_start_temperature_runs_the_program_from_its_own_t0(tmp_path):
    # Oracle: a rate ramp takes |target - T0| / rate; the targets are absolute.
    sc = load_scenario(write(tmp_path, "start_temperatures_c = [-20.0, 40.0]\n" + SHORT +
                             "[chamber]\nprogram = [{ hold_s = 600.0 },"
                             " { ramp_to_c = 10.0, rate_c_per_min = 1.0 }]\n"))
    assert [c.duration_s for c in sc.conditions()] == [600.0 + 1800.0, 600.0 + 1800.0]
    c_cold, c_hot = sc.conditions()
    assert c_cold.chamber_c(1500.0) == pytest.approx(-5.0) and \
        c_hot.chamber_c(1500.0) == pytest.approx(25.0)


def test_duration_cuts_or_extends_the_program(tmp_path):
    # Oracle: duration_s written wins; after the program the chamber holds its last value.
    sc, _ = corners(tmp_path, "[{ ramp_to_c = 30.0, over_s = 600.0 }]", extra="duration_s = 1200.0\n")
    (cond,) = sc.conditions()
    assert cond.duration_s == 1200.0 and cond.chamber_c(1100.0) == pytest.approx(30.0)


def test_ripple_adds_to_the_program(tmp_path):
    sc = load_scenario(write(tmp_path, "start_temperatures_c = [20.0]\n" + SHORT +
                             "[chamber]\nripple_c = 0.5\nripple_period_s = 400.0\n"
                             "program = [{ ramp_to_c = 30.0, over_s = 1000.0 }]\n"))
    (cond,) = sc.conditions()
    assert cond.chamber_c(100.0) == pytest.approx(21.0 + 0.5)      # sin(pi / 2) = 1


def test_power_on_after_an_unpowered_soak(tmp_path):
    # Oracles: t = 0 is power-on, the soak is not recorded; soaked unpowered from 20 C, then
    # 10 h (about 10 of the housing's time constants) at 35 C, every node has reached 35 C;
    # the run records 35 C as its soak temperature; and a soak that only holds T0 leaves the
    # nodes at T0, so the run is the run of the program without it.
    sc, _ = corners(tmp_path, "[{ ramp_to_c = 35.0, over_s = 900.0 }, { hold_s = 36000.0 },"
                              " { power_on = true }, { hold_s = 1300.0 }]")
    (cond,) = sc.conditions()
    assert cond.soak_s == 36900.0 and cond.duration_s == 1300.0
    r = simulate_run(sc.instrument, cond)
    assert r.run.meta.start_temperature_c == 35.0
    assert r.run["time_s"][0] == 0.0 and r.run["time_s"].size == 1300
    np.testing.assert_allclose(r.thermal.temperature_c[0], 35.0, atol=1e-4)

    held, _ = corners(tmp_path, "[{ hold_s = 3600.0 }, { power_on = true },"
                                " { hold_s = 1300.0 }]")
    plain, _ = corners(tmp_path, "[{ hold_s = 1300.0 }]")
    a = simulate_run(held.instrument, held.conditions()[0]).run
    b = simulate_run(plain.instrument, plain.conditions()[0]).run
    for c in ("gyro_dph", "temp_fog_c", "temp_chamber_c"):
        np.testing.assert_allclose(a[c], b[c], rtol=0, atol=1e-9, err_msg=c)


# ----------------------------------------------------------------------------- located errors

@pytest.mark.parametrize("program, key, words", [
    ("[{ ramp_to_c = 10.0, rate_c_per_min = -1.0 }]", "chamber.program[0].rate_c_per_min",
     "never reaches its target"),
    ("[{ ramp_to_c = 10.0, rate_c_per_min = 0.0 }]", "chamber.program[0].rate_c_per_min",
     "must be > 0"),
    ("[{ ramp_to_c = 10.0, over_s = 0.0 }]", "chamber.program[0].over_s", "must be > 0"),
    ("[{ hold_s = 600.0 }, { ramp_to_c = 10.0, rate = 1.0 }]", "chamber.program[1].rate",
     "unknown key"),
    ("[{ hold_s = 600.0, ramp_to_c = 10.0 }]", "chamber.program[0]", "mixes hold and ramp"),
    ("[{ ramp_to_c = 10.0 }]", "chamber.program[0]", "exactly one of rate_c_per_min"),
    ("[{ hold_s = nan }]", "chamber.program[0].hold_s", "finite"),
    ("[{ ramp_to_c = inf, over_s = 60.0 }]", "chamber.program[0].ramp_to_c", "finite"),
    ("[{ ramp_to_c = 200.0, over_s = 60.0 }]", "chamber.program[0].ramp_to_c",
     "outside the chamber range"),
    ("[{ step_to_c = 298.15 }]", "chamber.program[0].step_to_c", "Kelvin?"),
    ("[{ repeat = 2, steps = [{ hold_s = 60.0 }, { hold = 1 }] }]",
     "chamber.program[0].steps[1]", "names no step kind"),
    ("[{ repeat = 0, steps = [{ hold_s = 60.0 }] }]", "chamber.program[0].repeat", ">= 1"),
    ("[{ repeat = 2, steps = [{ power_on = true }, { hold_s = 60.0 }] }]",
     "chamber.program[0].steps[0]", "cannot be inside a repeat"),
    ("[{ power_on = true }, { hold_s = 900.0 }, { power_on = true }]", "chamber.program[2]",
     "a second power_on"),
    ("[{ hold_s = 900.0 }, { power_on = true }]", "chamber.program", "nothing would be"),
    ("[]", "chamber.program", "non-empty list"),
    ("[{ hold_s = 100.0 }]", "chamber.program", "shorter than one north-finding cycle"),
])
def test_bad_program_is_one_located_error(tmp_path, cli, program, key, words):
    # Oracle: the file, the key and the reason on one line, exit 2, before anything runs
    # (no output folder made).
    p = write(tmp_path, f"start_temperatures_c = [20.0]\n{SHORT}[chamber]\nprogram = {program}\n")
    with pytest.raises(ScenarioError) as exc:
        load_scenario(p)
    assert exc.value.key == key and exc.value.file == str(p) and words in exc.value.message
    code, _, err = cli("simulate", p, "-o", tmp_path / "out")
    line = one_line_error(code, err)
    assert str(p) in line and key in line
    assert not (tmp_path / "out").exists()


def test_start_temperatures_in_kelvin_are_refused_with_a_hint(tmp_path, cli):
    # Oracle: 241.15 K and 290.15 K are -32 C and 17 C; the message says so.
    p = write(tmp_path, "start_temperatures_c = [241.15, 290.15]\n")
    code, _, err = cli("table", p, "--no-compensation")
    line = one_line_error(code, err)
    assert str(p) in line and "start_temperatures_c" in line and "Kelvin?" in line
    assert "-32.00 C" in line
    with pytest.raises(ScenarioError, match="outside the chamber range"):
        load_scenario(write(tmp_path, "start_temperatures_c = [-80.0]\n"))


# ------------------------------------------------------------------------------- inheritance

def test_base_file_gives_every_key_left_out(tmp_path):
    # Oracle: the keys written in the base, overridden table by table by the file; paths in
    # the base stay relative to the base's folder; name and description are the file's.
    (tmp_path / "lib").mkdir()
    # the preset's text under a name of its own (a file named "default" would be warned about)
    (tmp_path / "lib" / "unit.toml").write_text(
        preset_path("default").read_text().replace('name = "default"', 'name = "unit"', 1))
    write(tmp_path / "lib", 'name = "parent"\ndescription = "the parent"\n'
          'instrument = "unit.toml"\nstart_temperatures_c = [-10.0, 30.0]\nseed = 5\n'
          + SHORT + "[compensation]\nmethods = ['ls']\ntest_repeats = 2\n"
          "[chamber]\nprogram = [{ hold_s = 900.0 }]\n", "parent.toml")
    child = write(tmp_path, 'base = "lib/parent.toml"\nseed = 6\n'
                  "[compensation]\ntest_repeats = 3\n", "child.toml")
    sc = load_scenario(child)
    assert sc.name == "child" and sc.description == ""
    assert sc.start_temperatures_c == (-10.0, 30.0) and sc.seed == 6
    assert sc.compensation.methods == ("ls",) and sc.compensation.test_repeats == 3
    assert sc.schedule.positions_deg == (0.0, 180.0)
    assert sc.run_duration_s(-10.0) == 900.0
    assert sc.instrument == load_scenario(tmp_path / "lib" / "parent.toml").instrument


def test_missing_base_and_a_loop_are_located_errors(tmp_path):
    p = write(tmp_path, 'base = "nowhere.toml"\n')
    with pytest.raises(ScenarioError, match="not found") as exc:
        load_scenario(p)
    assert exc.value.key == "base" and exc.value.file == str(p)
    write(tmp_path, 'base = "b.toml"\n', "a.toml")
    write(tmp_path, 'base = "a.toml"\n', "b.toml")
    with pytest.raises(ScenarioError, match="loop back") as exc:
        load_scenario(tmp_path / "a.toml")
    assert exc.value.key == "base"


def test_an_error_in_the_base_names_the_base(tmp_path):
    write(tmp_path, "start_temperatures_c = [20.0]\nrepeats = 0\n", "parent.toml")
    child = write(tmp_path, 'base = "parent.toml"\n', "child.toml")
    with pytest.raises(ScenarioError) as exc:
        load_scenario(child)
    assert exc.value.file == str(tmp_path / "parent.toml") and exc.value.key == "repeats"


def test_an_empty_file_is_the_default_without_its_scatter(tmp_path):
    # Oracle: the built-in default, minus what is never inherited (name, description,
    # variability).
    sc = load_scenario(write(tmp_path, ""))
    d = load_scenario()
    assert sc.start_temperatures_c == d.start_temperatures_c and sc.seed == d.seed
    assert sc.duration_s == d.duration_s == 9000.0 and sc.compensation == d.compensation
    assert sc.instrument == d.instrument and not sc.variability.active
    assert d.variability.active


def test_scenario_adds_aux_channels_and_effects(tmp_path):
    # Oracle: the instrument's channels and effects with the scenario's appended; the added
    # aux_linear effect is k (aux - aux_ref) of the simulated channel, sample by sample; a
    # channel the instrument has already is refused.
    text = ("start_temperatures_c = [20.0]\nduration_s = 700.0\n" + SHORT +
            '[[aux]]\nname = "aux_osc_v"\nsource = "power:electronics"\ngain = 0.1\n'
            'offset = 4.0\n[[added_effects]]\nname = "aux_linear"\nchannel = "aux_osc_v"\n'
            "k = 0.03\naux_ref = 4.3\n")
    sc = load_scenario(write(tmp_path, text))
    d = load_scenario().instrument
    assert [a.name for a in sc.instrument.aux] == [a.name for a in d.aux] + ["aux_osc_v"]
    assert [e.name for e in sc.instrument.effects] == [e.name for e in d.effects] + ["aux_linear"]
    r = simulate_run(sc.instrument, sc.conditions()[0])
    np.testing.assert_allclose(r.gyro_terms_dph["aux_linear:aux_osc_v"],
                               0.03 * (r.run["aux_osc_v"] - 4.3), rtol=0, atol=1e-15)
    with pytest.raises(ScenarioError, match="already has a channel") as exc:
        load_scenario(write(tmp_path, text.replace("aux_osc_v", "aux_tec_power_w")))
    assert exc.value.key == "aux"
