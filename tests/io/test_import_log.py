"""``nfs import``: a chamber log of three files (tests/io/chamber_logs.py) made one run.

Oracles:
- the log is written from a run the package simulated, every value in its shortest exact
  text: the gyro's source comes back as simulated up to the unit conversions (a few ulps),
  its times bitwise; a column resampled by linear interpolation lies between the two
  samples that bracket it, so it differs from the simulated column by at most the
  simulated column's own spread over that bracket (a bound computed from the simulation);
  ``previous`` and ``nearest`` pick the sample that their definition names, exactly;
- a shifted clock (power-on 5 s before the gyro's first stamp) shifts time_s by exactly 5 s
  and changes no column;
- north finding on the imported run gives the simulated run's headings (the same gyro and
  accelerometer samples);
- gaps: the spans a shortened or holed source leaves uncovered are known from the rows
  deleted; the cut keeps the longest covered stretch.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

import nfs
from nfs.errors import InputError, MeasurementError
from nfs.io import import_log, read_mapping, read_run

KELVIN_ULPS = 1e-12   # T + 273.15 - 273.15 in double: a few ulps of 273 K


def one_line_error(code, err):
    assert code == 2
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("nfs: error: "), err
    assert "Traceback" not in err
    return lines[0]


def bracket_spread(x: np.ndarray, every: int) -> np.ndarray:
    """For each sample i, max - min of x over the samples every*(i // every) ..
    every*(i // every) + every (the bracket of two samples of a source logged every
    ``every`` samples; clipped at the end)."""
    n = x.size
    k = np.arange(n) // every
    out = np.empty(n)
    for j in np.unique(k):
        seg = x[j * every: min(j * every + every + 1, n)]
        out[k == j] = seg.max() - seg.min()
    return out


def edit(path, old, new):
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new, 1))


# ---------------------------------------------------------------------------- the good log

def test_imported_run_is_the_simulated_run(log, simulated):
    run = import_log(log)
    sim = simulated.columns
    assert run.name == simulated.name and run.caveats == ()
    assert list(run.columns)[:9] == list(nfs.run.REQUIRED_COLUMNS)
    assert run.columns["time_s"].tobytes() == sim["time_s"].tobytes()       # bitwise
    for name in ("position_deg", "moving"):
        assert np.array_equal(run.columns[name], sim[name])
    for name in ("gyro_dph", "acc_x_g", "acc_y_g"):                          # mdeg/h, m/s^2
        np.testing.assert_allclose(run.columns[name], sim[name], rtol=1e-13, atol=1e-18)
    for name in ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c"):              # 1 Hz, kelvin
        error = np.abs(run.columns[name] - sim[name])
        assert np.all(error <= bracket_spread(sim[name], 10) + KELVIN_ULPS), name
        assert np.all(error[::10] <= KELVIN_ULPS)                           # at its samples
    error = np.abs(run.columns["temp_chamber_c"] - sim["temp_chamber_c"])   # 0.1 Hz
    assert np.all(error <= bracket_spread(sim["temp_chamber_c"], 100) + 1e-12)
    m, s = run.meta, simulated.meta
    assert (m.latitude_deg, m.start_temperature_c, m.true_heading_deg, m.positions_deg,
            m.dwell_s, m.move_s) == (s.latitude_deg, s.start_temperature_c,
                                     s.true_heading_deg, s.positions_deg, s.dwell_s, s.move_s)
    assert m.sample_rate_hz == 10.0 and m.duration_s == 1300.0 == s.duration_s
    account = m.extra["imported"]
    assert account["mapping"] == "log.toml"
    assert "temp_fog_c (T_fog_K, K) by linear" in account["resampling"][0]
    assert account["resampling"][-1].startswith("linear: linear interpolation")


def test_imported_run_north_finds_as_the_simulated_run(log, simulated):
    a = nfs.north_find(import_log(log))
    b = nfs.north_find(simulated)
    assert a.n_cycles == b.n_cycles >= 2
    np.testing.assert_allclose(a.heading_deg, b.heading_deg, rtol=0, atol=1e-9)


def test_command_writes_the_run_as_imported(log, tmp_path, cli):
    code, out, err = cli("import", log, "-o", tmp_path / "out")
    assert code == 0, err
    assert "by linear" in out and "time base: gyro.csv" in out
    written = read_run(tmp_path / "out" / "log_T-20C_r0.csv")
    again = import_log(log)
    for name, values in again.columns.items():
        assert written.columns[name].tobytes() == values.tobytes(), name
    assert written.meta == again.meta
    assert (tmp_path / "out" / "nfs-manifest.json").is_file()


def test_stated_clock_shifts_time_and_changes_no_column(log):
    base = import_log(log)
    # power-on 5 s before the gyro's first stamp; the relative loggers started with the gyro
    edit(log, '[run]\n', '[run]\npower_on = "2024-03-01 07:59:55.000000"\n')
    for source in ("thermometers", "chamber"):
        edit(log, f'[sources.{source}]\n', f'[sources.{source}]\ntime_offset_s = 5.0\n')
    run = import_log(log)
    assert np.array_equal(run.columns["time_s"], base.columns["time_s"] + 5.0)
    for name, values in base.columns.items():     # the same up to the rounding of t + 5
        if name != "time_s":
            np.testing.assert_allclose(run.columns[name], values, rtol=0, atol=1e-9)


@pytest.mark.parametrize("method", ["previous", "nearest"])
def test_previous_and_nearest_pick_the_sample_they_name(log, simulated, method):
    edit(log, 'columns.temp_fog_c = { column = "T_fog_K", unit = "K" }',
         f'columns.temp_fog_c = {{ column = "T_fog_K", unit = "K", method = "{method}" }}')
    run = import_log(log)
    i = np.arange(simulated.n_samples)
    # gyro sample i lies between thermometer samples i // 10 and i // 10 + 1; a tie
    # (i % 10 == 5) goes to the earlier
    k = i // 10 if method == "previous" else np.minimum((i + 4) // 10, i.size // 10 - 1)
    logged = simulated.columns["temp_fog_c"][10 * k] + 273.15 - 273.15
    assert np.array_equal(run.columns["temp_fog_c"], logged)
    assert f"temp_fog_c (T_fog_K, K) by {method}" in run.meta.extra["imported"]["resampling"][0]


# ---------------------------------------------------------------------------- gaps

def _drop_rows(path, first, last):
    """Delete the file's lines first..last (1-based, inclusive)."""
    lines = path.read_text().splitlines()
    del lines[first - 1:last]
    path.write_text("\n".join(lines) + "\n")


#: The chamber's samples at 980 ... 1290 s (its lines 102 ... 133: two lines of preamble and
#: the header, then the sample at 10 j s on line 4 + j).
CHAMBER_TAIL = (102, 133)


def test_a_short_source_is_refused_with_its_span(log, cli, tmp_path):
    # without its last 32 samples the chamber logs 0-970 s and covers up to 980 s (one of
    # its steps held), so 980.1-1299.9 s of the gyro's times are not covered
    _drop_rows(log.with_name("chamber.csv"), *CHAMBER_TAIL)
    with pytest.raises(MeasurementError, match=r"chamber.csv \(sources.chamber\) does not "
                       r"cover 980.1-1299.9 s of the gyro's 0-1299.9 s") as exc:
        import_log(log)
    assert exc.value.file.endswith("chamber.csv")
    line = one_line_error(*cli("import", log, "-o", tmp_path / "out")[::2])
    assert "give --cut to keep the 0-980 s every source covers" in line
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_cut_keeps_the_covered_span_and_says_so(log, simulated, cli, tmp_path):
    _drop_rows(log.with_name("chamber.csv"), *CHAMBER_TAIL)
    run = import_log(log, cut=True)
    t = run.columns["time_s"]
    assert (t[0], t[-1], t.size) == (0.0, 980.0, 9801)
    np.testing.assert_allclose(run.columns["gyro_dph"], simulated.columns["gyro_dph"][:9801],
                               rtol=1e-13)
    assert run.meta.extra["imported"]["cut"].startswith("cut to 0-980 s of the gyro's "
                                                         "0-1299.9 s (9801 of 13000 rows)")
    assert run.meta.duration_s == 980.1            # the record as written: whole
    code, out, err = cli("import", log, "-o", tmp_path / "out", "--cut")
    assert code == 0, err
    assert "cut: cut to 0-980 s" in out
    sidecar = tomllib.loads((tmp_path / "out" / "log_T-20C_r0.toml").read_text())
    assert sidecar["imported"]["cut"] == run.meta.extra["imported"]["cut"]


def test_a_hole_is_a_gap_unless_the_mapping_allows_it(log):
    # thermometer samples at 300 ... 310 s deleted (lines 302..312): a step of 12 s, over 3
    # of its 1 s steps
    _drop_rows(log.with_name("thermometers.csv"), 302, 312)
    with pytest.raises(MeasurementError, match=r"thermometers.csv \(sources.thermometers\) "
                                               r"does not cover 299.1-310.9 s"):
        import_log(log)
    run = import_log(log, cut=True)          # the longer stretch: 310.9 ... 1299.9 s
    assert (run.columns["time_s"][0], run.columns["time_s"][-1]) == (311.0, 1299.9)
    edit(log, "[sources.gyro]", "[align]\nmax_gap_samples = 20\n\n[sources.gyro]")
    assert import_log(log).n_samples == 13000  # 12 s is within 20 steps: not a gap


def test_a_hole_in_the_gyro_log_is_a_gap(log):
    # gyro samples at 100.0 ... 100.9 s deleted (lines 1002..1011): a step of 1.1 s, over 3
    # of its 0.1 s steps
    _drop_rows(log.with_name("gyro.csv"), 1002, 1011)
    with pytest.raises(MeasurementError, match=r"gyro.csv: a gap: gyro.csv \(sources.gyro\) has "
                                               r"holes at 99.9-101 s \(steps over 3 of its "
                                               r"0.1 s\)"):
        import_log(log)
    run = import_log(log, cut=True)          # the longer stretch: 101 ... 1299.9 s
    assert (run.columns["time_s"][0], run.columns["time_s"][-1]) == (101.0, 1299.9)


# ---------------------------------------------------------------------------- unit slips

@pytest.mark.parametrize("old, new, file, column, words", [
    ('{ column = "Rate_mdph", unit = "mdeg/h" }', '"Rate_mdph"', "gyro.csv", "Rate_mdph",
     "not deg/h; mdeg/h?"),
    ('{ column = "T_fog_K", unit = "K" }', '"T_fog_K"', "thermometers.csv", "T_fog_K",
     "kelvin?"),
], ids=["mdeg/h as deg/h", "kelvin as degC"])
def test_unit_slip_names_the_source_file_and_column(log, cli, tmp_path, old, new, file,
                                                    column, words):
    edit(log, old, new)
    line = one_line_error(*cli("import", log, "-o", tmp_path / "out")[::2])
    assert f"{file}, column '{column}':" in line and words in line
    assert "log.toml" in line                  # where the unit was given


# ---------------------------------------------------------------------------- bad input

BAD_MAPPINGS = [
    # (id, old text, new text, what the line must hold)
    ("unknown table", "[sources.gyro]", "[aling]\n[sources.gyro]", "log.toml, key 'aling'"),
    ("latitude missing", "latitude_deg = 30.0\n", "", "log.toml, key 'run.latitude_deg'"),
    ("latitude out of range", "latitude_deg = 30.0", "latitude_deg = 95.0",
     "log.toml, key 'run.latitude_deg'"),
    ("unknown unit", 'unit = "mdeg/h"', 'unit = "mdeg/hr"',
     "log.toml, key 'sources.gyro.columns.gyro_dph.unit'"),
    ("unknown method", 'column = "T_fog_K", unit = "K" }',
     'column = "T_fog_K", unit = "K", method = "cubic" }',
     "log.toml, key 'sources.thermometers.columns.temp_fog_c.method'"),
    ("missing file", 'file = "chamber.csv"', 'file = "air.csv"',
     "log.toml, key 'sources.chamber.file'"),
    ("column not in header", 'columns.temp_chamber_c = "Air"',
     'columns.temp_chamber_c = "Luft"', "chamber.csv, row 3: no column 'Luft'"),
    ("required column unmapped", 'columns.acc_y_g = { column = "AccY_ms2", unit = "m/s^2" }\n',
     "", "log.toml, key 'sources': no source gives the required column acc_y_g"),
    ("mapped twice", 'columns.temp_chamber_c = "Air"',
     'columns.temp_chamber_c = "Air"\ncolumns.temp_fog_c = "Air"',
     "log.toml, key 'sources.chamber.columns.temp_fog_c'"),
    ("decimal is separator", 'file = "thermometers.csv"',
     'file = "thermometers.csv"\ndecimal = ","', "log.toml, key 'sources.thermometers.decimal'"),
    ("two clocks", 'time_unit = "ms"', 'time_unit = "ms"\ntime_format = "%S"',
     "log.toml, key 'sources.thermometers.time_unit'"),
    ("not a format column", 'columns.moving = "Moving"', 'columns.moving_flag = "Moving"',
     "log.toml, key 'sources.gyro.columns.moving_flag'"),
    ("time as a column", 'columns.moving = "Moving"',
     'columns.moving = "Moving"\ncolumns.time_s = "Table_deg"',
     "log.toml, key 'sources.gyro.columns.time_s'"),
    ("decimal comma not said", 'decimal = ","\n', "",
     "gyro.csv, column 'Rate_mdph', row 2: cannot read"),
    ("power-on not a time", "[run]\n", '[run]\npower_on = "at eight"\n',
     "log.toml, key 'run.power_on'"),
]


@pytest.mark.parametrize("old, new, words", [b[1:] for b in BAD_MAPPINGS],
                         ids=[b[0] for b in BAD_MAPPINGS])
def test_bad_mapping_is_one_line_naming_file_and_key(log, cli, tmp_path, old, new, words):
    edit(log, old, new)
    line = one_line_error(*cli("import", log, "-o", tmp_path / "out")[::2])
    assert words in line
    with pytest.raises(InputError):
        import_log(log)


def _replace_line(path, line, new):
    lines = path.read_text().splitlines()
    lines[line - 1] = new(lines[line - 1])
    path.write_text("\n".join(lines) + "\n")


BAD_SOURCES = [
    ("bad time stamp", "gyro.csv", 5, lambda s: "2024-03-01 08:00:00,4" + s[26:],
     "gyro.csv, column 'Timestamp', row 5: cannot read '2024-03-01 08:00:00,4'"),
    ("time going back", "thermometers.csv", 6, lambda s: "1000" + s[s.index(","):],
     "thermometers.csv, column 't_ms', row 6: time does not increase"),
    ("not a number", "chamber.csv", 7, lambda s: s.split("\t")[0] + "\tn/a",
     "chamber.csv, column 'Air', row 7: cannot read 'n/a' as a number"),
    ("below absolute zero", "thermometers.csv", 4,
     lambda s: ",".join(s.split(",")[:1] + ["-5.0"] + s.split(",")[2:]),
     "thermometers.csv, column 'T_fog_K', row 4: temperature"),
    ("moving not a flag", "gyro.csv", 9, lambda s: ";".join(
        s.split(";")[:3] + ["2"] + s.split(";")[4:]),
     "gyro.csv, column 'Moving', row 9: must be 0 or 1"),
    ("a field too many", "thermometers.csv", 5, lambda s: s + ",1",
     "thermometers.csv, row 5: row has 5 fields, the header has 4; a decimal comma"),
]


@pytest.mark.parametrize("file, line, change, words", [b[1:] for b in BAD_SOURCES],
                         ids=[b[0] for b in BAD_SOURCES])
def test_bad_source_row_is_one_line_naming_file_column_and_row(log, cli, tmp_path, file,
                                                               line, change, words):
    _replace_line(log.with_name(file), line, change)
    assert words in one_line_error(*cli("import", log, "-o", tmp_path / "out")[::2])


# ---------------------------------------------------------------------------- asked for

def test_missing_samples_refused_then_read_with_allow_nan(log, cli, tmp_path):
    _replace_line(log.with_name("thermometers.csv"), 4,
                  lambda s: ",".join(s.split(",")[:1] + [""] + s.split(",")[2:]))
    line = one_line_error(*cli("import", log, "-o", tmp_path / "out")[::2])
    assert "thermometers.csv, column 'T_fog_K', row 4: 1 missing sample" in line
    assert "--allow-nan" in line
    run = import_log(log, allow_nan=True)
    nan = np.flatnonzero(np.isnan(run.columns["temp_fog_c"]))
    # the sample at 2 s is missing: every gyro time strictly inside its brackets (1-2 s and
    # 2-3 s) is missing too; at 1 s and 3 s the samples there are given as they are
    assert (nan[0], nan[-1], nan.size) == (11, 29, 19)
    assert run.caveats == ("thermometers.csv: 1 missing sample read with --allow-nan (left "
                           "out where they fall: a dwell mean, a fit window; a chamber "
                           "record with a gap is set aside for T0): T_fog_K: 1 (row 4)",)
    code, out, _ = cli("import", log, "-o", tmp_path / "out", "--allow-nan")
    assert code == 0 and "note: thermometers.csv: 1 missing sample" in out


def test_a_gyro_log_cut_while_written_is_refused_then_read_with_partial(log):
    gyro = log.with_name("gyro.csv")
    gyro.write_text(gyro.read_text()[:-30])        # the last line loses its last fields
    with pytest.raises(MeasurementError, match=r"gyro.csv, row 13001: .* cut while being "
                                               r"written; 12999 complete rows found"):
        import_log(log)
    run = import_log(log, partial=True)
    assert run.n_samples == 12999
    assert run.caveats[0].startswith("partial, read with --partial: 12999 complete rows "
                                     "found, at least 13000 expected")
    edit(log, "move_s = 10.0\n", "move_s = 10.0\nduration_s = 1300.0\n")
    run = import_log(log, partial=True)
    assert "12999 rows found, 13000 expected (duration_s = 1300 s in [run] of log.toml)" \
        in run.caveats[0]
    assert run.meta.extra["imported"]["caveats"] == list(run.caveats)


def test_read_mapping_gives_each_source_and_the_gyro(log):
    m = read_mapping(log)
    assert [s.name for s in m.sources] == ["gyro", "thermometers", "chamber"]
    assert m.gyro.name == "gyro" and m.gyro.separator == ";" and m.gyro.decimal == ","
    chamber = m.sources[2]
    assert (chamber.separator, chamber.skip_rows, chamber.time_unit) == ("\t", 2, "min")
    fog = next(c for c in m.sources[1].columns if c.target == "temp_fog_c")
    assert (fog.factor, fog.offset, fog.method) == (1.0, -273.15, "linear")
