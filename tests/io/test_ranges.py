"""The one table of ranges (nfs.ranges) and the loaders that check every value against it.

Oracles:
- the table's own invariants: finite ranges, typical inside hard, no entry shadowed by an
  earlier one, and a range for every value the shipped files hold (the presets, every
  scenario and sweep under scenarios/, every parameter of every built-in effect);
- the shipped files are the reference design: they load without a warning;
- the preset's comments: the range a value's comment states is the table's typical range;
- hand-made unit slips, whose right unit the test knows (7000 mW, 3.5 kJ/K, 2.5 min, kelvin,
  deg/s, rad/s, m/s^2): each refused or warned about in one line naming the file, the key or
  column and that unit;
- work never started: a refused scenario leaves no run file behind.
"""

from __future__ import annotations

import math
import re
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

from nfs.effects import available_effects, get_effect
from nfs.errors import MeasurementError, ScenarioError
from nfs.instrument import load_instrument, preset_path
from nfs.io.measurement import read_run, write_run
from nfs.config.scenario import load_scenario
from nfs.config.presets import default_scenario_path
from nfs.io.tomlio import dumps_toml
from nfs.parameters import param_paths
from nfs.ranges import (RANGES, RangeWarning, deferred_warnings, find, leaves,
                        MAX_SAMPLES_PER_RUN, warn)
from nfs.sweep import load_sweep

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "scenarios").glob("*.toml"))
SWEEPS = sorted((ROOT / "scenarios" / "sweeps").glob("*.toml"))


def lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.strip()]


# ------------------------------------------------------------------------------------------
# the table


def test_every_range_is_finite_and_typical_lies_inside_hard():
    for r in RANGES:
        lo, hi = r.hard
        tlo, thi = r.typical
        assert math.isfinite(lo) and math.isfinite(hi) and lo <= hi, r.key
        assert lo <= tlo <= thi <= hi, r.key
        assert r.what and r.source, r.key
        for factor, offset, unit in r.slips:
            assert factor > 0 and unit, r.key


def test_no_entry_is_shadowed_by_an_earlier_one():
    # Oracle: a key built from an entry's own pattern finds that entry (first match wins,
    # so a generic pattern placed before a specific one would hide it).
    for r in RANGES:
        key = r.key.replace("*", "x")
        if r.key.startswith("thermal.links.") and "*" in r.key:
            key = "thermal.links.x-y.conductance_w_per_k"
        assert find(key) is r, (r.key, find(key).key if find(key) else None)


def test_a_link_and_an_effect_label_are_found_in_any_form():
    want = find("thermal.links.housing-chamber.conductance_w_per_k")
    assert find("thermal.links.chamber-housing.conductance_w_per_k") is want
    assert find("effects.acc_bias_temperature:x.b_q1") is \
        find("effects.acc_bias_temperature.b_q1")


def _numeric_leaves(tree, canonical=""):
    return [(s, c) for s, c, v in leaves(tree, canonical=canonical)
            if isinstance(v, (int, float)) and not isinstance(v, bool)]


@pytest.mark.parametrize("path", [preset_path("default"), *SCENARIOS],
                         ids=lambda p: Path(p).name)
def test_every_value_of_the_shipped_files_has_a_range(path):
    tree = tomllib.loads(Path(path).read_text())
    missing = [s for s, c in _numeric_leaves(tree) if find(c) is None
               or find(c).key == "effects.*"]
    assert not missing


@pytest.mark.parametrize("path", SWEEPS, ids=lambda p: p.name)
def test_every_value_of_the_shipped_sweeps_has_a_range(path):
    tree = tomllib.loads(path.read_text())
    axes = tree.pop("axes", {})
    assert all(find(c) is not None for _, c in _numeric_leaves(tree, "sweep"))
    for _, c, _ in leaves(axes):
        c = re.sub(r"\.(low|high|log)$", "", c)        # a drawn axis: its ends
        assert find(c) is not None and find(c).key != "effects.*", c


def test_every_parameter_of_every_builtin_effect_and_the_instrument_has_a_range():
    for name in available_effects():
        spec = get_effect(name)
        if not spec.function.__module__.startswith("nfs.effects."):
            continue
        for p in spec.parameters:
            if p.type in (float, tuple):
                r = find(f"effects.{name}.{p.name}")
                assert r is not None and r.key != "effects.*", (name, p.name)
    for path, _ in param_paths(load_instrument("default")):
        assert find(path) is not None, path


def _range_warnings(load):
    """The RangeWarnings (their messages) that ``load()`` raises, and what it returned."""
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        out = load()
    return [str(w.message) for w in seen if issubclass(w.category, RangeWarning)], out


@pytest.mark.parametrize("path", [*SCENARIOS, *SWEEPS], ids=lambda p: p.name)
def test_the_shipped_files_load_without_a_warning(path):
    # Oracle: the shipped files are the reference design, every value typical.
    loader = load_sweep if path.parent.name == "sweeps" else load_scenario
    got, loaded = _range_warnings(lambda: loader(path))
    assert got == [], got
    assert loaded is not None
    got, inst = _range_warnings(lambda: load_instrument("default"))
    assert got == [] and inst.name == "default", got


# ------------------------------------------------------------------------------------------
# one source: the preset's comments state the table's typical ranges

_NUMBER = r"\d+(?:\.\d+)?(?:e[-+]?\d+)?"
_RANGE_IN_COMMENT = re.compile(rf"({_NUMBER})\s*(?:-|to)\s*({_NUMBER})")


def preset_comment_ranges(text: str) -> list[tuple[str, tuple[float, float]]]:
    """(canonical key path, (low, high)) of every value line whose comment states a range
    (the first "A-B" or "A to B" of the comment on the value's own line)."""
    out, prefix, table_array = [], "", None
    for raw in text.splitlines():
        line = raw.strip()
        if m := re.fullmatch(r"\[\[([\w.]+)\]\]", line):
            table_array, prefix = m.group(1), m.group(1)
            continue
        if m := re.fullmatch(r"\[([\w.]+)\]", line):
            table_array, prefix = None, m.group(1)
            continue
        m = re.fullmatch(r"(\w+)\s*=\s*([^#]*?)\s*(?:#\s*(.*))?", line)
        if not m:
            continue
        key, value, comment = m.groups()
        if table_array == "effects" and key == "name":
            prefix = f"effects.{tomllib.loads(f'v = {value}')['v']}"
        elif table_array == "thermal.links" and key == "between":
            a, b = tomllib.loads(f"v = {value}")["v"]
            prefix = f"thermal.links.{a}-{b}"
        found = _RANGE_IN_COMMENT.search(comment or "")
        if found:
            out.append((f"{prefix}.{key}" if prefix else key,
                        (float(found.group(1)), float(found.group(2)))))
    return out


def test_comment_parser():
    text = ('[thermal.nodes.board]\npower_w = 7.0  # 3-8 W\n[[thermal.links]]\n'
            'between = ["a", "b"]\nconductance_w_per_k = 1.0  # x, 1e-5 to 5e-5\n'
            '[[effects]]\nname = "tau_thing"\ntau = 1.0\n')
    assert preset_comment_ranges(text) == [("thermal.nodes.board.power_w", (3.0, 8.0)),
                                           ("thermal.links.a-b.conductance_w_per_k",
                                            (1e-5, 5e-5))]


def test_the_presets_comments_state_the_tables_typical_ranges():
    stated = preset_comment_ranges(preset_path("default").read_text())
    assert len(stated) >= 35                     # nearly every value states its range
    wrong = [(key, rng, find(key).typical if find(key) else None) for key, rng in stated
             if find(key) is None or find(key).typical != rng]
    assert not wrong


# ------------------------------------------------------------------------------------------
# warnings: held until a load succeeds, each once

def test_warnings_are_held_until_the_load_succeeds_and_dropped_on_error():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(ValueError):
            with deferred_warnings():
                warn("first")
                raise ValueError
        with deferred_warnings():
            with deferred_warnings():                # nested: one holder
                warn("second", key=1)
                warn("second again", key=1)          # same key: once
            assert not caught
    assert [str(w.message) for w in caught] == ["second"]


# ------------------------------------------------------------------------------------------
# instrument and scenario: unit slips and values that cannot run, via the command line

def _instrument(tmp_path, change) -> Path:
    d = tomllib.loads(preset_path("default").read_text())
    d["name"] = "unit 7"      # a copy of a preset named as such (else one line renames it)
    change(d)
    path = tmp_path / "inst.toml"
    path.write_text(dumps_toml(d))
    return path


def _scenario(tmp_path, text: str, name="s.toml") -> Path:
    """A scenario of one start at 17 C for 1800 s, unless ``text`` says otherwise."""
    given = tomllib.loads(text)
    base = "".join(line for key, line in (("start_temperatures_c", "start_temperatures_c = "
                                                                    "[17.0]\n"),
                                          ("duration_s", "duration_s = 1800.0\n"))
                   if key not in given)
    path = tmp_path / name
    path.write_text(base + text)
    return path


def _set(path, value):
    def change(d):
        tbl = d
        for k in path[:-1]:
            tbl = tbl[k]
        tbl[path[-1]] = value
    return change


def test_milliwatts_written_as_watts_are_refused_with_the_unit(tmp_path, cli):
    inst = _instrument(tmp_path, _set(("thermal", "nodes", "board", "power_w"), 7000.0))
    scen = _scenario(tmp_path, f'instrument = "{inst}"\n')
    code, out, err = cli("simulate", scen, "-o", tmp_path / "out", "-q")
    assert code == 2 and len(lines(err)) == 1 and "Traceback" not in err
    assert f"{inst}, key 'thermal.nodes.board.power_w': 7000 W is impossible" in err
    assert "mW? (7 W)" in err
    assert not list((tmp_path / "out").glob("*.csv"))


def test_kilojoules_and_minutes_run_with_one_warning_line_each(tmp_path, cli):
    inst = _instrument(tmp_path, _set(("thermal", "nodes", "housing", "capacity_j_per_k"), 3.5))
    scen = _scenario(tmp_path, f'instrument = "{inst}"\n[schedule]\n'
                               "positions_deg = [0.0, 90.0, 180.0, 270.0]\ndwell_s = 2.5\n")
    code, out, err = cli("simulate", scen, "-o", tmp_path / "out", "-q")
    assert code == 0, err
    got = lines(err)
    assert len(got) == 2 and all(line.startswith("nfs: warning: ") for line in got)
    assert "key 'thermal.nodes.housing.capacity_j_per_k': 3.5 J/K is unusual" in got[0]
    assert "2000-4500 J/K" in got[0] and "kJ/K? (3500 J/K)" in got[0]
    assert "key 'schedule.dwell_s': 2.5 s is unusual" in got[1] and "minutes? (150 s)" in got[1]


def test_a_refused_file_shows_its_error_and_no_warning(tmp_path, cli):
    scen = _scenario(tmp_path, "[schedule]\npositions_deg = [0.0, 0.0]\ndwell_s = 2.5\n")
    code, out, err = cli("simulate", scen, "-o", tmp_path / "out", "-q")
    assert code == 2 and len(lines(err)) == 1
    assert "key 'schedule.positions_deg'" in err and "same position" in err


@pytest.mark.parametrize("text, key, what", [
    ("[schedule]\npositions_deg = [0.0, 0.0]\ndwell_s = 150.0\n", "schedule.positions_deg",
     "same position"),
    ("[schedule]\npositions_deg = [0.0, 360.0, 90.0]\ndwell_s = 150.0\n",
     "schedule.positions_deg", "same position"),
    ("[schedule]\npositions_deg = [0.0, 90.0]\ndwell_s = 150.0\n", "schedule.positions_deg",
     "cannot determine the heading"),
    ("duration_s = 1e300\n", "duration_s", "impossible"),
    ("duration_s = 2e6\nsample_rate_hz = 10.0\n", "duration_s",
     f"more than the {MAX_SAMPLES_PER_RUN:g} one run may hold"),
    ("sample_rate_hz = 1e-300\n", "sample_rate_hz", "impossible"),
    ("start_temperatures_c = [17.0, 17.0]\n", "start_temperatures_c", "twice"),
    ("start_temperatures_c = [290.15]\n", "start_temperatures_c", "Kelvin?"),
    ("[northfind]\nstartup_end_s = 1e-300\n", "northfind.startup_end_s",
     "before the first north-finding cycle ends"),
    ("[northfind]\nsettle_s = 150.0\n", "northfind.settle_s", "whole dwell"),
    ("[variability]\nsoak_h = 1e300\n", "variability.soak_h", "impossible"),
    ("[variability]\ncapacity_rel_std = 1e300\n", "variability.capacity_rel_std",
     "impossible"),
    ("[chamber]\nprogram = [{ repeat = 100000, steps = [{ hold_s = 600.0 }, "
     "{ hold_s = 600.0 }] }]\n", "chamber.program[0].repeat", "impossible"),
    ("[chamber]\nprogram = [{ repeat = 1000, steps = [{ repeat = 1000, steps = "
     "[{ hold_s = 600.0 }] }] }]\n", "chamber.program[0].repeat", "more than the 100000"),
    ("[[added_effects]]\nname = \"magnetic\"\nm = nan\nD_mag = 0.0\n", "added_effects[0].m",
     "finite"),
    ("[compensation]\nn_jobs = 0\n", "compensation.n_jobs", "must not be 0"),
    ("[compensation]\nmethods = []\n", "compensation.methods", "at least one method"),
    ("[compensation]\ncutoff_period_s = 100000.0\n", "compensation.cutoff_period_s",
     "cannot be separated"),
    # 99 W more on the board (1.2 W/K to the housing): a steady rise of about 160 K
    ("[[added_effects]]\nname = \"heat_source\"\nnode = \"board\"\npower = 99.0\n",
     "thermal.nodes.board", "steady-state rise"),
])
def test_a_scenario_that_cannot_run_is_refused_before_any_work(tmp_path, cli, text, key, what):
    scen = _scenario(tmp_path, text)
    code, out, err = cli("simulate", scen, "-o", tmp_path / "out", "-q")
    assert code == 2 and len(lines(err)) == 1 and "Traceback" not in err, err
    assert f"{scen}, key '{key}'" in err and what in err, err
    assert not list((tmp_path / "out").glob("*.csv"))


def test_a_powered_node_without_a_path_to_the_chamber_is_refused(tmp_path):
    def cut(d):
        d["thermal"]["links"] = [l for l in d["thermal"]["links"] if "qfa_y" not in l["between"]]
    with pytest.raises(ScenarioError, match="no thermal path to the chamber") as exc:
        load_instrument(_instrument(tmp_path, cut))
    assert exc.value.key == "thermal.nodes.qfa_y"


def test_a_network_that_would_cook_is_refused(tmp_path):
    # 60 W through 0.3 W/K: a steady rise of 200 K above the chamber
    def hot(d):
        d["thermal"]["nodes"]["board"]["power_w"] = 60.0
        for link in d["thermal"]["links"]:
            if "board" in link["between"]:
                link["conductance_w_per_k"] = 0.3
    with pytest.raises(ScenarioError, match="steady-state rise") as exc:
        load_instrument(_instrument(tmp_path, hot))
    assert exc.value.key == "thermal.nodes.board"


def test_a_sweep_axis_is_checked_and_warned_about_by_its_own_name(tmp_path, cli):
    scen = _scenario(tmp_path, "")
    sweep = tmp_path / "sw.toml"
    sweep.write_text(f'scenario = "{scen}"\nseeds = [1]\n[axes]\n'
                     '"thermal.nodes.board.power_w" = [7.0, 7000.0]\n')
    code, out, err = cli("sweep", sweep, "-o", tmp_path / "out", "-q")
    assert code == 2 and len(lines(err)) == 1
    assert f"{sweep}, key 'axes.thermal.nodes.board.power_w'" in err and "mW?" in err
    sweep.write_text(f'scenario = "{scen}"\nseeds = {{ first = 0, count = 1000000000 }}\n')
    code, out, err = cli("sweep", sweep, "-o", tmp_path / "out", "-q")
    assert code == 2 and "key 'seeds.count'" in err and "impossible" in err
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sweep.write_text(f'scenario = "{scen}"\nseeds = [1]\n[axes]\n'
                         'schedule.dwell_s = [150.0, 2.5]\n')
        load_sweep(sweep)
    got = [str(w.message) for w in caught if w.category is RangeWarning]
    assert len(got) == 1 and "key 'axes.schedule.dwell_s'" in got[0], got


# ------------------------------------------------------------------------------------------
# measurement files in the wrong units


@pytest.fixture(scope="module")
def simulated_run(tmp_path_factory):
    """One simulated run at T0 = -32 C (the default instrument, 1300 s)."""
    folder = tmp_path_factory.mktemp("run")
    scen = folder / "m.toml"
    scen.write_text("start_temperatures_c = [-32.0]\nduration_s = 1300.0\n")
    from nfs.experiment import simulate_run
    sc = load_scenario(scen)
    return simulate_run(sc.instrument, sc.conditions()[0]).run


def _written(run, folder, **changes):
    """``run`` written with some columns changed (bypassing the writer's checks)."""
    path = write_run(run, folder)
    if changes:
        cols = dict(run.columns)
        for name, f in changes.items():
            cols[name] = f(np.asarray(cols[name]))
        text = ",".join(cols) + "\n" + "\n".join(
            ",".join(repr(float(v)) for v in row) for row in zip(*cols.values())) + "\n"
        path.write_text(text)
    return path


def test_the_simulated_run_reads_back_without_a_warning(simulated_run, tmp_path):
    # Oracle: the simulator's own run is typical in every column, and reads back as written.
    got, back = _range_warnings(lambda: read_run(_written(simulated_run, tmp_path)))
    assert got == [], got
    assert set(back.columns) == set(simulated_run.columns)
    for name, values in simulated_run.columns.items():
        np.testing.assert_allclose(np.asarray(back[name], dtype=float),
                                   np.asarray(values, dtype=float), rtol=1e-12, atol=0,
                                   err_msg=name)


@pytest.mark.parametrize("column, change, unit", [
    ("temp_fog_c", lambda v: v + 273.15, "kelvin?"),
    ("gyro_dph", lambda v: v / 3600.0, "deg/s?"),
    ("gyro_dph", lambda v: np.radians(v) / 3600.0, "rad/s?"),
    ("gyro_dph", lambda v: np.radians(v), "rad/h?"),
    ("acc_x_g", lambda v: v * 0 + 9.80665, "m/s^2?"),
])
def test_a_column_in_another_unit_is_refused_naming_it(simulated_run, tmp_path, column,
                                                       change, unit):
    path = _written(simulated_run, tmp_path, **{column: change})
    with pytest.raises(MeasurementError) as exc:
        read_run(path)
    assert exc.value.column == column and exc.value.file == str(path)
    assert unit in str(exc.value) and "\n" not in str(exc.value)


def test_a_tilted_run_in_metres_per_second_squared_warns(simulated_run, tmp_path):
    # a 1 deg tilt in m/s^2 reads as a 10 deg tilt in g: possible, unusual
    tilt = math.sin(math.radians(1.0)) * 9.80665
    path = _written(simulated_run, tmp_path, acc_x_g=lambda v: v * 0 + tilt)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_run(path)
    got = [str(w.message) for w in caught if w.category is RangeWarning]
    assert len(got) == 1 and "column 'acc_x_g'" in got[0] and "m/s^2?" in got[0]


def test_a_sidecar_in_kelvin_is_refused(simulated_run, tmp_path):
    path = write_run(simulated_run, tmp_path)
    toml = path.with_suffix(".toml")
    toml.write_text(toml.read_text().replace("start_temperature_c = -32.0",
                                             "start_temperature_c = 241.15"))
    with pytest.raises(MeasurementError, match="Kelvin") as exc:
        read_run(path)
    assert exc.value.key == "start_temperature_c"


def test_a_required_column_with_no_value_is_refused(simulated_run, tmp_path):
    path = _written(simulated_run, tmp_path, gyro_dph=lambda v: v * np.nan)
    with pytest.raises(MeasurementError, match="every sample is missing") as exc:
        read_run(path)
    assert exc.value.column == "gyro_dph"


def test_measured_kelvin_via_the_command_line_is_one_line(simulated_run, tmp_path, cli):
    path = _written(simulated_run, tmp_path, temp_fog_c=lambda v: v + 273.15)
    code, out, err = cli("northfind", path)
    assert code == 2 and len(lines(err)) == 1 and "Traceback" not in err
    assert f"{path}, column 'temp_fog_c'" in err and "kelvin?" in err and out == ""
