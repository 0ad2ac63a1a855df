"""Runs that are whole (nfs.io.completeness): a run shorter than its sidecar's duration_s, a
CSV cut while written and missing samples are refused with their counts and rows, and read
when asked (``partial``, ``allow_nan``; ``--partial``, ``--allow-nan``), the fact then stated
in every output.

Oracles: the runs are written by the test, so the rows found and expected, the cut line and
the rows of every missing sample are known exactly; a dwell mean that leaves a missing
sample out is the mean of the dwell without that row, so north finding a run with missing
samples gives the headings of the run with those rows deleted (an invariant).
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import nfs
from nfs.errors import MeasurementError
from nfs.fit.departures import fit_warnings
from nfs.io import read_run, read_runs, write_run
from nfs.io.provenance import runs_provenance
from nfs.northfind.synthetic import synthetic_run
from nfs.run import Run, run_caveats


def one_line_error(code, err):
    assert code == 2
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("nfs: error: "), err
    return lines[0]


def make_run(duration_s=1300.0, name="unit7", **meta):
    """A 1 Hz four-position run of 1300 s whose sidecar says ``duration_s``."""
    run = synthetic_run(heading_deg=40.0, duration_s=1300.0, arw_deg_per_rth_h=0.005,
                        random_state=7, name=name)
    return dataclasses.replace(run, meta=dataclasses.replace(run.meta, duration_s=duration_s,
                                                             **meta))


def with_rows(run, keep):
    return dataclasses.replace(run, columns={k: v[keep] for k, v in run.columns.items()})


# ---------------------------------------------------------------------------- partial runs

def test_a_run_shorter_than_its_duration_is_refused_with_the_row_counts(tmp_path):
    path = write_run(with_rows(make_run(), slice(0, 1000)), tmp_path)   # 1000 of 1300 s
    with pytest.raises(MeasurementError) as exc:
        read_run(path)
    assert str(exc.value) == (
        f"{path}: the run is partial: the rows cover 1000 s; 1000 rows found, 1300 expected "
        "(duration_s = 1300 s in unit7.toml); read the rows found with --partial "
        "(read_run(..., partial=True))")
    run = read_run(path, partial=True)
    assert run.n_samples == 1000
    assert run.caveats == ("partial, read with --partial: 1000 rows found, 1300 expected "
                           "(duration_s = 1300 s in unit7.toml)",)


def test_a_whole_run_reads_as_it_is(tmp_path):
    run = read_run(write_run(make_run(), tmp_path))
    assert run.n_samples == 1300 and run.caveats == ()
    # half a step short is still whole (a logger's last sample a little early)
    run = read_run(write_run(make_run(duration_s=1300.4), tmp_path / "b"))
    assert run.caveats == ()


def test_a_line_cut_while_written_is_refused_then_left_out(tmp_path):
    path = write_run(make_run(), tmp_path)
    text = path.read_text()
    path.write_text(text[: text.rstrip("\n").rindex(",") - 10])     # the last line cut
    with pytest.raises(MeasurementError, match=(
            r"unit7.csv, row 1301: the run is partial: its last line \(row 1301\) has \d of "
            r"9 fields: the file was cut while being written; the rows cover 1299 s; 1299 "
            r"rows found, 1300 expected")):
        read_run(path)
    run = read_run(path, partial=True)
    assert run.n_samples == 1299
    assert run.caveats[0].endswith("; the cut last line (row 1301) left out")
    # without a duration the cut line alone says the run is partial
    path.with_suffix(".toml").write_text(
        path.with_suffix(".toml").read_text().replace("duration_s = 1300.0\n", ""))
    with pytest.raises(MeasurementError, match=r"1299 complete rows found, at least 1300 "
                                               r"expected"):
        read_run(path)


def test_a_short_row_before_the_end_is_a_fault_not_a_cut(tmp_path):
    path = write_run(make_run(), tmp_path)
    lines = path.read_text().splitlines()
    lines[9] = ",".join(lines[9].split(",")[:5])
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(MeasurementError, match=r"unit7.csv, row 10: row has 5 fields, the "
                                               r"header has 9$"):
        read_run(path, partial=True)


# ---------------------------------------------------------------------------- missing samples

def test_missing_samples_are_refused_naming_columns_and_rows(tmp_path):
    run = make_run()
    gyro = run.columns["gyro_dph"].copy()
    gyro[[3, 17, 18, 19, 40, 41, 500]] = np.nan
    temp = run.columns["temp_fog_c"].copy()
    temp[7] = np.nan
    run = dataclasses.replace(run, columns={**run.columns, "gyro_dph": gyro,
                                            "temp_fog_c": temp})
    path = write_run(run, tmp_path)
    with pytest.raises(MeasurementError) as exc:
        read_run(path)
    assert str(exc.value) == (
        f"{path}, row 5: 8 missing samples (empty or nan) where a value is due: gyro_dph: 7 "
        "(rows 5, 19, 20, 21, 42, ...); temp_fog_c: 1 (row 9); read them as missing with "
        "--allow-nan (read_run(..., allow_nan=True))")
    back = read_run(path, allow_nan=True)
    assert np.array_equal(np.isnan(back["gyro_dph"]), np.isnan(gyro))
    assert back.caveats == (
        "8 missing samples read with --allow-nan (left out where they fall: a dwell mean, a "
        "fit window; a chamber record with a gap is set aside for T0): gyro_dph: 7 (rows 5, "
        "19, 20, 21, 42, ...); temp_fog_c: 1 (row 9)",)


def test_a_switched_off_unit_records_nothing_and_misses_nothing(tmp_path):
    run = make_run()
    powered = np.ones(run.n_samples)
    powered[600:700] = 0.0
    off = powered == 0.0
    cols = {k: (np.where(off, np.nan, v) if k.startswith(("gyro", "acc", "temp")) else v)
            for k, v in run.columns.items()}
    cols["powered"] = powered
    cols["temp_chamber_c"] = np.full(run.n_samples, 25.0)     # the chamber keeps recording
    path = write_run(dataclasses.replace(run, columns=cols), tmp_path)
    assert read_run(path).caveats == ()
    cols["temp_chamber_c"] = np.where(off, np.nan, 25.0)     # ... so its gap is missing
    path = write_run(dataclasses.replace(run, columns=cols), tmp_path / "b")
    with pytest.raises(MeasurementError, match=r"column 'temp_chamber_c', row 602: 100 "
                                               r"missing samples"):
        read_run(path)


def test_missing_samples_are_left_out_of_their_dwell_means(tmp_path):
    run = make_run()
    drop = np.array([20, 21, 22, 200, 201, 650])             # inside dwells
    assert not run.columns["moving"][drop].any()
    gyro = run.columns["gyro_dph"].copy()
    gyro[drop] = np.nan
    with_nan = read_run(write_run(dataclasses.replace(
        run, columns={**run.columns, "gyro_dph": gyro}), tmp_path), allow_nan=True)
    without = with_rows(run, np.setdiff1d(np.arange(run.n_samples), drop))
    a, b = nfs.north_find(with_nan), nfs.north_find(without)
    assert a.n_missing == {"gyro_dph": 6}
    np.testing.assert_allclose(a.heading_deg, b.heading_deg, rtol=0, atol=1e-9)


# ---------------------------------------------------------------------------- the outputs say it

def test_every_output_states_the_caveats(tmp_path):
    run = Run("r", make_run().columns, make_run().meta, caveats=("partial, read with x",))
    assert run_caveats([run, make_run(name="whole")]) == ["run 'r': partial, read with x"]
    assert runs_provenance([run])[0]["caveats"] == ["partial, read with x"]
    warnings = fit_warnings([run], [], {}, {}, {}, {}, {}, [], {}, {}, {}, None)
    assert "run 'r': partial, read with x" in warnings
    comparison = nfs.compare(nfs.load_instrument("default"), [run])
    assert "run 'r': partial, read with x" in comparison.assumptions


def test_commands_refuse_a_partial_run_and_read_it_with_partial(tmp_path, cli):
    write_run(with_rows(make_run(), slice(0, 1000)), tmp_path / "runs")
    line = one_line_error(*cli("northfind", tmp_path / "runs")[::2])
    assert "unit7.csv: the run is partial" in line and "--partial" in line
    code, out, err = cli("northfind", tmp_path / "runs", "--partial",
                         "--json", tmp_path / "nf.json")
    assert code == 0, err
    assert out.splitlines()[0] == ("note: run 'unit7': partial, read with --partial: 1000 "
                                   "rows found, 1300 expected (duration_s = 1300 s in "
                                   "unit7.toml)")
    doc = json.loads((tmp_path / "nf.json").read_text())
    assert doc["provenance"]["runs"][0]["caveats"][0].startswith("partial, read with")
    for command in ("fit", "compare", "diagnose", "design", "train", "compensate"):
        assert "--partial" in _help(command) and "--allow-nan" in _help(command)


def _help(command):
    from nfs.cli import build_parser
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return sub.choices[command].format_help()


def test_a_semicolon_or_decimal_comma_file_is_pointed_to_nfs_import(tmp_path):
    path = write_run(make_run(), tmp_path)
    text = path.read_text()
    path.write_text(text.replace(",", ";"))
    with pytest.raises(MeasurementError, match=r"unit7.csv, row 1: the header is separated "
                                               r"by ';', not ','; .*nfs import"):
        read_run(path)
    lines = text.splitlines()
    lines[3] = lines[3].replace("0.0,", "0,0,", 1)           # a decimal comma: one field more
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(MeasurementError, match=r"row 4: row has 10 fields, the header has 9; "
                                               r"a decimal comma .*nfs import"):
        read_run(path)
    lines[3] = lines[3].replace("0,0,", '"0,0",', 1)         # quoted by a spreadsheet
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(MeasurementError, match=r"row 4: cannot read '0,0' as a number; a "
                                               r"decimal comma\? .*nfs import"):
        read_run(path)


def test_read_runs_passes_the_options_on(tmp_path):
    write_run(with_rows(make_run(), slice(0, 1000)), tmp_path)
    with pytest.raises(MeasurementError, match="partial"):
        read_runs(tmp_path)
    assert read_runs(tmp_path, partial=True)[0].n_samples == 1000
