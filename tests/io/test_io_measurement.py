"""The measurement format nfs-measurement/1 (nfs.io.measurement).

Oracles:
- round trip: write -> read is the identity, bitwise (an invariant of the writer, which uses
  the shortest exact text of each double);
- hand-written files: their values are typed in the test, so the expected arrays are known
  exactly;
- bad files: each names the file, column, line (header = line 1) or key that the test broke,
  so the location in the error is known exactly.
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from nfs.errors import MeasurementError
from nfs.io.csv_columns import _parse_csv_careful, _parse_csv_fast
from nfs.io.measurement import FORMAT, find_runs, read_run, read_runs, write_run
from nfs.io.measurement_checks import check_columns
from nfs.run import REQUIRED_COLUMNS, Run, RunMeta

# ---------------------------------------------------------------------------------------------
# helpers


def make_run(name="run_a", n=600, seed=0, step_s=1.0, start_temperature_c=-32.0):
    """A seeded synthetic run with NaN, -0.0, tiny and huge values in optional columns."""
    rng = np.random.default_rng(seed)
    time_s = np.arange(n) * step_s
    position = np.repeat([0.0, 90.0, 180.0, 270.0], n // 4 + 1)[:n]
    moving = (rng.random(n) < 0.1).astype(float)
    columns = {
        # deliberately not in REQUIRED_COLUMNS order: the writer must reorder
        "temp_fog_c": start_temperature_c + rng.normal(0, 0.01, n).cumsum(),
        "time_s": time_s,
        "position_deg": position,
        "moving": moving,
        # the horizontal Earth rate at the sidecar's latitude and heading (deg/h), as the
        # unit checks of the reader require (nfs.io.measurement.check_units)
        "gyro_dph": 15.041067 * np.cos(np.radians(30.26)) * np.cos(np.radians(212.7 + position))
        + rng.normal(0, 0.05, n),
        "acc_x_g": rng.normal(0, 1e-4, n),
        "acc_y_g": rng.normal(0, 1e-4, n),
        "temp_acc_x_c": start_temperature_c + rng.normal(0, 0.01, n),
        "temp_acc_y_c": start_temperature_c + rng.normal(0, 0.01, n),
        "temp_chamber_c": np.full(n, start_temperature_c),
        "aux_source_current_ma": rng.normal(100.0, 1.0, n),
    }
    columns["gyro_dph"][[3, 17]] = np.nan
    columns["temp_chamber_c"][5] = np.nan
    columns["aux_source_current_ma"][[0, 1, 2, 4]] = [-0.0, 1e-300, 1e300, np.nan]
    meta = RunMeta(latitude_deg=30.26, start_temperature_c=start_temperature_c,
                   true_heading_deg=212.7, sample_rate_hz=1.0 / step_s,
                   positions_deg=(0.0, 90.0, 180.0, 270.0), dwell_s=150.0, move_s=10.0,
                   instrument="unit-07", extra={"seed": seed})
    return Run(name=name, columns=columns, meta=meta)


def assert_same_run(read: Run, written: Run):
    expected_order = [c for c in REQUIRED_COLUMNS] + [
        c for c in written.columns if c not in REQUIRED_COLUMNS]
    assert list(read.columns) == expected_order
    for name, values in written.columns.items():
        got = read.columns[name]
        assert got.dtype == np.float64
        assert np.array_equal(got, values, equal_nan=True), name
        assert got.tobytes() == np.asarray(values, dtype=np.float64).tobytes(), name  # bitwise
    assert read.meta == written.meta


BASE_CSV = """\
time_s,position_deg,moving,gyro_dph,acc_x_g,acc_y_g,temp_fog_c,temp_acc_x_c,temp_acc_y_c
0,0,0,12.9,0.001,-0.002,-32.0,-32.0,-32.0
1,0,0,13.1,0.001,-0.002,-31.9,-31.9,-31.9
2,0,1,13.0,0.001,-0.002,-31.8,-31.8,-31.8
3,90,1,3.2,0.002,-0.001,-31.7,-31.7,-31.7
4,90,0,3.1,0.002,-0.001,-31.6,-31.6,-31.6
"""

BASE_TOML = f"""\
format = "{FORMAT}"
latitude_deg = 30.26
start_temperature_c = -32.0
sample_rate_hz = 1.0
"""


def write_pair(folder, csv_text=BASE_CSV, toml_text=BASE_TOML, name="run", newline="\n"):
    csv_path = folder / f"{name}.csv"
    csv_path.write_bytes(csv_text.replace("\n", newline).encode("utf-8"))
    if toml_text is not None:
        (folder / f"{name}.toml").write_text(toml_text, encoding="utf-8")
    return csv_path


def replace_line(text, line, new):
    """*text* with its 1-based *line* replaced by *new* (None deletes it)."""
    lines = text.splitlines()
    if new is None:
        del lines[line - 1]
    else:
        lines[line - 1] = new
    return "\n".join(lines) + "\n"


def replace_field(text, line, column, value):
    lines = text.splitlines()
    header = lines[0].split(",")
    fields = lines[line - 1].split(",")
    fields[header.index(column)] = value
    lines[line - 1] = ",".join(fields)
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# round trip


@pytest.mark.parametrize("step_s", [1.0, 0.1])  # whole seconds (written as integers) or not
def test_round_trip_is_bitwise(tmp_path, step_s):
    run = make_run(step_s=step_s)
    csv_path = write_run(run, tmp_path)
    assert csv_path == tmp_path / "run_a.csv"
    back = read_run(csv_path, allow_nan=True)
    assert back.name == "run_a"
    assert back.path == csv_path
    assert back.n_samples == run.n_samples
    assert_same_run(back, run)


def test_written_text_layout(tmp_path):
    csv_path = write_run(make_run(), tmp_path)
    lines = csv_path.read_bytes().decode("utf-8").split("\n")
    assert lines[0] == ",".join(REQUIRED_COLUMNS) + ",temp_chamber_c,aux_source_current_ma"
    first = lines[1].split(",")
    assert first[:3] == ["0", "0", first[2]] and first[2] in ("0", "1")  # integers
    assert lines[-1] == ""  # final newline, no CR
    assert b"\r" not in csv_path.read_bytes()
    moving = {line.split(",")[2] for line in lines[1:-1]}
    assert moving == {"0", "1"}
    # NaN written as an empty field
    gyro_line_4 = lines[4].split(",")  # sample 3 is on line 5 of the file (index 4)
    assert gyro_line_4[REQUIRED_COLUMNS.index("gyro_dph")] == ""


def test_writing_is_deterministic(tmp_path):
    run = make_run()
    a = write_run(run, tmp_path / "a")
    b = write_run(run, tmp_path / "b")
    # what was read writes the same bytes again
    c = write_run(read_run(a, allow_nan=True), tmp_path / "c")
    for suffix in (".csv", ".toml"):
        assert a.with_suffix(suffix).read_bytes() == b.with_suffix(suffix).read_bytes()
        assert a.with_suffix(suffix).read_bytes() == c.with_suffix(suffix).read_bytes()


def test_metadata_round_trip_with_extra_keys(tmp_path):
    extra = {
        "operator": 'A "quoted"\tname\\ with µ and \x01',
        "n_cycles": 3,
        "calibrated": True,
        "gains": [1.5, 2, -7],
        "labels": ["a", "b"],
        "chamber": {"model": "VT 4002", "volume_l": 200.0},
        "measured": dt.datetime(2024, 5, 1, 10, 0, tzinfo=dt.timezone.utc),
        "day": dt.date(2024, 5, 1),
        "odd key.with dots": 1e-05,
        "huge": 1e300,
    }
    run = make_run(start_temperature_c=17.0)
    run = Run(run.name, run.columns, RunMeta(latitude_deg=-45, start_temperature_c=17,
                                             positions_deg=(0, 180), extra=extra))
    back = read_run(write_run(run, tmp_path), allow_nan=True)
    assert back.meta == run.meta
    assert back.meta.extra == extra
    assert list(back.meta.extra) == list(extra)
    assert back.meta.latitude_deg == -45.0 and isinstance(back.meta.latitude_deg, float)
    assert back.meta.positions_deg == (0.0, 180.0)
    assert back.meta.true_heading_deg is None and back.meta.instrument is None


def test_write_to_stem_path_and_read_by_any_name(tmp_path):
    run = make_run(name="ignored")
    csv_path = write_run(run, tmp_path / "new" / "chamber_m32.toml")
    assert csv_path == tmp_path / "new" / "chamber_m32.csv"
    assert (tmp_path / "new" / "chamber_m32.toml").is_file()
    for given in (csv_path, csv_path.with_suffix(".toml"), csv_path.with_suffix(""),
                  str(csv_path)):
        back = read_run(given, allow_nan=True)
        assert back.name == "chamber_m32"
        assert_same_run(back, run)


def test_write_accepts_int_and_bool_arrays(tmp_path):
    run = make_run(n=20)
    columns = dict(run.columns)
    columns["time_s"] = np.arange(20)  # int
    columns["moving"] = np.zeros(20, dtype=bool)
    csv_path = write_run(Run("r", columns, run.meta), tmp_path)
    back = read_run(csv_path, allow_nan=True)
    assert back["time_s"].dtype == np.float64
    assert np.array_equal(back["time_s"], np.arange(20.0))
    assert np.array_equal(back["moving"], np.zeros(20))


# ---------------------------------------------------------------------------------------------
# files from another tool

OTHER_TOOL_CSV = (
    "aux_source_current_ma,temp_fog_c,time_s,moving,position_deg,gyro_dph,acc_y_g,acc_x_g,"
    "temp_chamber_c,temp_acc_y_c,temp_acc_x_c,aux_supply_v\r\n"
    "101.5,-32,0,0,0,12.875,-0.002,0.001,-32,-32.1,-31.9,28\r\n"
    "101.25,-31.9,1,0,0,,-0.002,0.001,nan,-32.0,-31.8,28.0\r\n"
    ",-31.8,2,1,0,NaN,-0.002,0.001,-32,-31.9, -31.7 ,\r\n"
    "1e2,-31.7,3,1,90,3.5,-0.001,2E-3,-32,-31.8,-31.6,27.5\r\n"
    "\r\n"
)
OTHER_TOOL_EXPECTED = {
    "aux_source_current_ma": [101.5, 101.25, np.nan, 100.0],
    "temp_fog_c": [-32.0, -31.9, -31.8, -31.7],
    "time_s": [0.0, 1.0, 2.0, 3.0],
    "moving": [0.0, 0.0, 1.0, 1.0],
    "position_deg": [0.0, 0.0, 0.0, 90.0],
    "gyro_dph": [12.875, np.nan, np.nan, 3.5],
    "acc_y_g": [-0.002, -0.002, -0.002, -0.001],
    "acc_x_g": [0.001, 0.001, 0.001, 0.002],
    "temp_chamber_c": [-32.0, np.nan, -32.0, -32.0],
    "temp_acc_y_c": [-32.1, -32.0, -31.9, -31.8],
    "temp_acc_x_c": [-31.9, -31.8, -31.7, -31.6],
    "aux_supply_v": [28.0, 28.0, np.nan, 27.5],
}
OTHER_TOOL_TOML = """\
# written by a chamber logger
format = "nfs-measurement/1"
latitude_deg = 30
start_temperature_c = -32
positions_deg = [0, 90, 180, 270]
operator = "kim"
[chamber]
model = "VT 4002"
"""


def _assert_columns(columns, expected):
    assert list(columns) == list(expected)
    for name, values in expected.items():
        assert np.array_equal(columns[name], np.array(values), equal_nan=True), name


def test_other_tool_file_loads(tmp_path):
    csv_path = tmp_path / "logger_m32.csv"
    csv_path.write_bytes(OTHER_TOOL_CSV.encode("utf-8"))
    (tmp_path / "logger_m32.toml").write_text(OTHER_TOOL_TOML, encoding="utf-8")
    run = read_run(csv_path, allow_nan=True)
    _assert_columns(run.columns, OTHER_TOOL_EXPECTED)  # file order, unknown columns kept
    assert run.meta.latitude_deg == 30.0
    assert run.meta.start_temperature_c == -32.0
    assert run.meta.positions_deg == (0.0, 90.0, 180.0, 270.0)
    assert run.meta.extra == {"operator": "kim", "chamber": {"model": "VT 4002"}}
    # and it writes and reads back unchanged
    assert_same_run(read_run(write_run(run, tmp_path / "copy"), allow_nan=True), run)


def test_spreadsheet_export_loads(tmp_path):
    # BOM, quoted header and values, a blank line inside, bare-CR-free CRLF, and a
    # trailing all-empty row as spreadsheets leave them: the careful (csv module) path
    text = ("\ufeff" + OTHER_TOOL_CSV.replace("aux_supply_v", '"aux_supply_v"')
            .replace("101.25,", '"101.25",').replace("\r\n\r\n", "\r\n")
            .replace("1e2,", "\r\n1e2,", 1) + ",,,,,,,,,,,\r\n\r\n")
    csv_path = tmp_path / "sheet.csv"
    csv_path.write_bytes(text.encode("utf-8"))
    (tmp_path / "sheet.toml").write_text(OTHER_TOOL_TOML, encoding="utf-8")
    _assert_columns(read_run(csv_path, allow_nan=True).columns, OTHER_TOOL_EXPECTED)


def test_fast_and_careful_parsers_agree(tmp_path):
    # invariant: the numpy fast path and the csv-module path read the same numbers
    written = write_run(make_run(), tmp_path).read_text(encoding="utf-8")
    for text in (OTHER_TOOL_CSV, BASE_CSV, written):
        names_fast, data = _parse_csv_fast(text)
        names, columns, lines, cut = _parse_csv_careful(text, tmp_path / "x.csv")
        assert names_fast == names
        assert lines == list(range(2, len(lines) + 2))
        for fast, careful in zip(data, columns):
            assert fast.tobytes() == careful.tobytes()


def test_single_sample_and_no_sample_rate(tmp_path):
    csv_path = write_pair(tmp_path, "\n".join(BASE_CSV.splitlines()[:2]) + "\n",
                          BASE_TOML.replace("sample_rate_hz = 1.0\n", ""))
    run = read_run(csv_path)
    assert run.n_samples == 1
    assert run.meta.sample_rate_hz is None


# ---------------------------------------------------------------------------------------------
# faults: every one names the file and the column/line or key


def _csv(edit):
    return lambda: (edit(BASE_CSV), BASE_TOML)


def _toml(edit):
    return lambda: (BASE_CSV, edit(BASE_TOML))


CSV_FAULTS = {
    # id: (make (csv, toml), file suffix, column, row, key, words in the message)
    "required column absent": (
        _csv(lambda t: t.replace(",moving,", ",turning,")),
        ".csv", "moving", 1, None, ["missing: moving"]),
    "two required columns absent": (
        _csv(lambda t: t.replace(",moving,", ",turning,").replace("acc_y_g", "acc_z_g")),
        ".csv", None, 1, None, ["missing: moving, acc_y_g", "acc_z_g"]),
    "value does not parse": (
        _csv(lambda t: replace_field(t, 4, "gyro_dph", "13,0".replace(",", ";"))),
        ".csv", "gyro_dph", 4, None, ["'13;0'", "number"]),
    "text in an unknown column": (
        _csv(lambda t: replace_line(t.replace("temp_acc_y_c\n", "temp_acc_y_c,aux_x_v\n"),
                                    2, BASE_CSV.splitlines()[1] + ",1.0")
             .replace("-31.9\n", "-31.9,OK\n").replace("-31.8\n", "-31.8,1\n")
             .replace("-31.7\n", "-31.7,1\n").replace("-31.6\n", "-31.6,1\n")),
        ".csv", "aux_x_v", 3, None, ["'OK'"]),
    "digit separator": (
        _csv(lambda t: replace_field(t, 3, "gyro_dph", "1_3")),
        ".csv", "gyro_dph", 3, None, ["'1_3'"]),
    "non-ASCII digit": (
        _csv(lambda t: replace_field(t, 3, "acc_y_g", "\uff11")),
        ".csv", "acc_y_g", 3, None, ["number"]),
    "bare CR line ends": (
        _csv(lambda t: replace_field(t, 6, "temp_fog_c", "-1e3").replace("\n", "\r")),
        ".csv", "temp_fog_c", 6, None, ["absolute zero"]),
    "earliest bad line is reported": (
        _csv(lambda t: replace_field(replace_field(t, 5, "time_s", "x"), 3, "acc_x_g", "y")),
        ".csv", "acc_x_g", 3, None, ["'y'"]),
    "time does not increase": (
        _csv(lambda t: replace_field(t, 5, "time_s", "1.5")),
        ".csv", "time_s", 5, None, ["does not increase", "1.5 after 2.0"]),
    "time repeats": (
        _csv(lambda t: replace_field(t, 3, "time_s", "0")),
        ".csv", "time_s", 3, None, ["does not increase"]),
    "time missing": (
        _csv(lambda t: replace_field(t, 4, "time_s", "")),
        ".csv", "time_s", 4, None, ["missing value"]),
    "position missing": (
        _csv(lambda t: replace_field(t, 6, "position_deg", "nan")),
        ".csv", "position_deg", 6, None, ["missing value"]),
    "moving missing": (
        _csv(lambda t: replace_field(t, 2, "moving", "")),
        ".csv", "moving", 2, None, ["missing value"]),
    "moving not 0/1": (
        _csv(lambda t: replace_field(t, 4, "moving", "0.5")),
        ".csv", "moving", 4, None, ["must be 0 or 1", "0.5"]),
    "moving 2": (
        _csv(lambda t: replace_field(t, 6, "moving", "2")),
        ".csv", "moving", 6, None, ["must be 0 or 1"]),
    "temperature below absolute zero": (
        _csv(lambda t: replace_field(t, 5, "temp_acc_y_c", "-300")),
        ".csv", "temp_acc_y_c", 5, None, ["-300.0", "absolute zero"]),
    "chamber temperature below absolute zero": (
        _csv(lambda t: t.replace("temp_acc_y_c\n", "temp_acc_y_c,temp_chamber_c\n")
             .replace("-31.9\n", "-31.9,-274\n").replace("-32.0\n", "-32.0,-32\n")
             .replace("-31.8\n", "-31.8,-31\n").replace("-31.7\n", "-31.7,-31\n")
             .replace("-31.6\n", "-31.6,-31\n")),
        ".csv", "temp_chamber_c", 3, None, ["absolute zero"]),
    "acceleration above 2 g": (
        _csv(lambda t: replace_field(t, 6, "acc_y_g", "-2.5")),
        ".csv", "acc_y_g", 6, None, ["2.5", "2.0 g"]),
    "infinite value": (
        _csv(lambda t: replace_field(t, 3, "gyro_dph", "inf")),
        ".csv", "gyro_dph", 3, None, ["not finite"]),
    "too few fields": (
        _csv(lambda t: replace_line(t, 4, "2,0,1,13.0,0.001,-0.002,-31.8,-31.8")),
        ".csv", None, 4, None, ["8 fields", "header has 9"]),
    "too many fields": (
        _csv(lambda t: replace_line(t, 6, "4,90,0,3.1,0.002,-0.001,-31.6,-31.6,-31.6,7")),
        ".csv", None, 6, None, ["10 fields"]),
    "line numbers count blank lines": (
        _csv(lambda t: replace_field(t.replace("\n1,", "\n\n1,"), 5, "gyro_dph", "?")),
        ".csv", "gyro_dph", 5, None, ["'?'"]),
    "line numbers with quoted fields": (
        _csv(lambda t: replace_field(t.replace("\n1,", '\n"1",'), 5, "gyro_dph", "?")),
        ".csv", "gyro_dph", 5, None, ["'?'"]),
    "duplicate column": (
        _csv(lambda t: t.replace("temp_acc_y_c\n", "temp_acc_y_c,gyro_dph\n")),
        ".csv", "gyro_dph", 1, None, ["twice"]),
    "empty column name": (
        _csv(lambda t: t.replace("temp_acc_y_c\n", "temp_acc_y_c,\n")),
        ".csv", None, 1, None, ["field 10", "empty"]),
    "empty file": (lambda: ("", BASE_TOML), ".csv", None, None, None, ["empty file"]),
    "blank file": (lambda: ("\n \n", BASE_TOML), ".csv", None, None, None, ["empty file"]),
    "header only": (
        lambda: (BASE_CSV.splitlines()[0] + "\n", BASE_TOML),
        ".csv", None, 1, None, ["no data rows"]),
    "sample rate inconsistent with time": (
        _toml(lambda t: t.replace("sample_rate_hz = 1.0", "sample_rate_hz = 1.02")),
        ".toml", None, None, "sample_rate_hz", ["median step", "run.csv", "1.02"]),
    "TOML syntax error": (
        _toml(lambda t: t + "dwell_s = = 150\n"),
        ".toml", None, None, None, ["TOML syntax error", "line 5"]),
    "format missing": (
        _toml(lambda t: t.replace(f'format = "{FORMAT}"\n', "")),
        ".toml", None, None, "format", [FORMAT]),
    "format wrong": (
        _toml(lambda t: t.replace(FORMAT, "nfs-measurement/2")),
        ".toml", None, None, "format", ["nfs-measurement/2"]),
    "latitude missing": (
        _toml(lambda t: t.replace("latitude_deg = 30.26\n", "")),
        ".toml", None, None, "latitude_deg", ["required"]),
    "start temperature missing": (
        _toml(lambda t: t.replace("start_temperature_c = -32.0\n", "")),
        ".toml", None, None, "start_temperature_c", ["required"]),
    "latitude is text": (
        _toml(lambda t: t.replace("30.26", '"30.26 N"')),
        ".toml", None, None, "latitude_deg", ["number", "str"]),
    "latitude is a bool": (
        _toml(lambda t: t.replace("30.26", "true")),
        ".toml", None, None, "latitude_deg", ["number", "bool"]),
    "latitude out of range": (
        _toml(lambda t: t.replace("30.26", "95.0")),
        ".toml", None, None, "latitude_deg", ["<= 90"]),
    "latitude nan": (
        _toml(lambda t: t.replace("30.26", "nan")),
        ".toml", None, None, "latitude_deg", ["finite"]),
    "start temperature below absolute zero": (
        _toml(lambda t: t.replace("-32.0", "-280.0")),
        ".toml", None, None, "start_temperature_c", [">= -273.15"]),
    "sample rate zero": (
        _toml(lambda t: t.replace("sample_rate_hz = 1.0", "sample_rate_hz = 0")),
        ".toml", None, None, "sample_rate_hz", ["> 0.0"]),
    "positions not a list": (
        _toml(lambda t: t + "positions_deg = 90\n"),
        ".toml", None, None, "positions_deg", ["list"]),
    "position element not a number": (
        _toml(lambda t: t + 'positions_deg = [0, "east"]\n'),
        ".toml", None, None, "positions_deg[1]", ["'east'"]),
    "instrument not text": (
        _toml(lambda t: t + "instrument = 7\n"),
        ".toml", None, None, "instrument", ["string"]),
    "dwell negative": (
        _toml(lambda t: t + "dwell_s = -1\n"),
        ".toml", None, None, "dwell_s", ["> 0.0"]),
}


@pytest.mark.parametrize("case", list(CSV_FAULTS), ids=list(CSV_FAULTS))
def test_fault_is_located(tmp_path, case):
    make, suffix, column, row, key, words = CSV_FAULTS[case]
    csv_text, toml_text = make()
    write_pair(tmp_path, csv_text, toml_text)
    with pytest.raises(MeasurementError) as info:
        read_run(tmp_path / "run.csv")
    err = info.value
    message = str(err)
    assert err.file == str(tmp_path / f"run{suffix}")
    assert message.startswith(str(tmp_path / f"run{suffix}"))
    assert (err.column, err.row, err.key) == (column, row, key)
    if column is not None:
        assert f"column '{column}'" in message
    if row is not None:
        assert f"row {row}" in message
    if key is not None:
        assert f"key '{key}'" in message
    for word in words:
        assert word in message
    assert "\n" not in message


def test_fault_with_crlf_is_located(tmp_path):
    write_pair(tmp_path, replace_field(BASE_CSV, 4, "acc_x_g", "3"), newline="\r\n")
    with pytest.raises(MeasurementError, match=r"run\.csv, column 'acc_x_g', row 4: "):
        read_run(tmp_path / "run.csv")


def test_not_utf8(tmp_path):
    csv_path = tmp_path / "run.csv"
    csv_path.write_bytes(BASE_CSV.encode("utf-8") + b"5,90,0,3\xff,0,0,1,1,1\n")
    (tmp_path / "run.toml").write_text(BASE_TOML)
    with pytest.raises(MeasurementError, match=r"run\.csv, row 7: not UTF-8"):
        read_run(csv_path)


def test_sidecar_missing_names_both_files(tmp_path):
    csv_path = write_pair(tmp_path, toml_text=None)
    with pytest.raises(MeasurementError) as info:
        read_run(csv_path)
    assert info.value.file == str(csv_path)
    assert "run.toml" in str(info.value)


def test_csv_missing_next_to_toml(tmp_path):
    (tmp_path / "run.toml").write_text(BASE_TOML)
    with pytest.raises(MeasurementError, match=r"run\.csv: run has no sample file run\.csv"):
        read_run(tmp_path / "run.toml")


def test_no_such_run(tmp_path):
    with pytest.raises(MeasurementError, match=r"nothing\.csv: no such file"):
        read_run(tmp_path / "nothing")


# ---------------------------------------------------------------------------------------------
# sets of runs


def test_read_runs_from_folders_and_files(tmp_path):
    folder = tmp_path / "set"
    for name, t in [("p54", 54.0), ("m32", -32.0), ("p17", 17.0)]:
        write_run(make_run(name=name, n=40, start_temperature_c=t), folder)
    (folder / "notes.txt").write_text("not a run")
    runs = read_runs(folder, allow_nan=True)
    assert [r.name for r in runs] == ["m32", "p17", "p54"]  # sorted by name
    assert [r.meta.start_temperature_c for r in runs] == [-32.0, 17.0, 54.0]
    # a file, a stem and a folder together; a run named twice is read once
    other = write_run(make_run(name="extra", n=40), tmp_path / "other")
    runs = read_runs([other.with_suffix(".toml"), folder, str(folder / "p17")],
                     allow_nan=True)
    assert [r.name for r in runs] == ["extra", "m32", "p17", "p54"]
    assert find_runs(str(other)) == [other]


def test_read_runs_faults(tmp_path):
    with pytest.raises(MeasurementError, match=r"nope: no such file or folder"):
        read_runs([tmp_path / "nope"])
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "run.toml").write_text(BASE_TOML)
    with pytest.raises(MeasurementError, match=r"empty: folder holds no runs"):
        read_runs(empty)
    with pytest.raises(MeasurementError, match="no measurement files"):
        read_runs([])
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(MeasurementError, match=r"notes\.txt: not a measurement file"):
        read_runs(tmp_path / "notes.txt")
    lonely = tmp_path / "lonely"
    lonely.mkdir()
    write_pair(lonely, name="a")
    write_pair(lonely, name="b", toml_text=None)
    with pytest.raises(MeasurementError) as info:
        read_runs(lonely)
    assert info.value.file == str(lonely / "b.csv")
    assert "b.toml" in str(info.value)


# ---------------------------------------------------------------------------------------------
# writing refuses what would not read back, and then writes nothing


def _assert_nothing_written(folder):
    assert not folder.exists() or list(folder.iterdir()) == []


def test_write_refuses_bad_columns(tmp_path):
    run = make_run(n=20)
    columns = dict(run.columns)
    columns["time_s"] = columns["time_s"].copy()
    columns["time_s"][7] = 3.0
    with pytest.raises(MeasurementError, match=r"run_a\.csv, column 'time_s', row 9: "
                                               r"time does not increase"):
        write_run(Run("run_a", columns, run.meta), tmp_path / "out")
    _assert_nothing_written(tmp_path / "out")
    columns = {k: v for k, v in run.columns.items() if k != "acc_y_g"}
    with pytest.raises(MeasurementError, match="missing: acc_y_g"):
        write_run(Run("run_a", columns, run.meta), tmp_path / "out")
    columns = dict(run.columns, aux_short_v=np.ones(5))
    with pytest.raises(MeasurementError, match="column 'aux_short_v': has 5 samples"):
        write_run(Run("run_a", columns, run.meta), tmp_path / "out")
    columns = dict(run.columns, **{"bad,name": np.ones(20)})
    with pytest.raises(MeasurementError, match="column 'bad,name'"):
        write_run(Run("run_a", columns, run.meta), tmp_path / "out")
    _assert_nothing_written(tmp_path / "out")


def test_write_refuses_bad_metadata(tmp_path):
    run = make_run(n=20)
    cases = [
        (RunMeta("north", -32.0), "key 'latitude_deg'"),
        (RunMeta(30.0, -32.0, sample_rate_hz=2.0), "key 'sample_rate_hz'"),
        (RunMeta(30.0, -32.0, extra={"dwell_s": 1.0}), "key 'dwell_s': extra key clashes"),
        (RunMeta(30.0, -32.0, extra={"x": None}), "key 'x'"),
        (RunMeta(30.0, -32.0, extra={"x": object()}), "key 'x': cannot write"),
        (RunMeta(30.0, -32.0, instrument=7), "key 'instrument'"),
    ]
    for meta, where in cases:
        with pytest.raises(MeasurementError, match=where):
            write_run(Run("run_a", run.columns, meta), tmp_path / "out")
    _assert_nothing_written(tmp_path / "out")


def test_failed_write_keeps_previous_files(tmp_path):
    good = make_run(n=20)
    csv_path = write_run(good, tmp_path)
    before = (csv_path.read_bytes(), csv_path.with_suffix(".toml").read_bytes())
    bad = Run("run_a", good.columns, RunMeta(30.0, -32.0, extra={"x": object()}))
    with pytest.raises(MeasurementError):
        write_run(bad, tmp_path)
    assert (csv_path.read_bytes(), csv_path.with_suffix(".toml").read_bytes()) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run_a.csv", "run_a.toml"]


# ---------------------------------------------------------------------------------------------
# speed (the budget of the brief: 9000 rows x 12 columns; 7 runs written)


@pytest.mark.slow


def test_check_columns_alone():
    run = make_run(n=20)
    check_columns(run.columns)  # a valid run passes
    columns = dict(run.columns, acc_z_g=np.full(20, 0.5))
    columns["acc_z_g"][4] = 2.5  # any acc_*_g column is bounded
    with pytest.raises(MeasurementError, match=r"^column 'acc_z_g', row 6: "):
        check_columns(columns)
    with pytest.raises(MeasurementError, match=r"^x\.csv, column 'acc_z_g', row 40: "):
        check_columns(columns, file="x.csv", line_of=lambda i: 10 * i)
    columns = {k: v for k, v in run.columns.items() if k != "moving"}
    with pytest.raises(MeasurementError, match="missing: moving"):
        check_columns(columns)
