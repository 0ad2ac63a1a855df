"""Sweeps end to end: the smallest sweep as written, executors giving the same bytes,
resuming an interrupted sweep, closed forms of the white-noise floor across axes."""

import csv
import json
import math
import warnings

import numpy as np
import pytest

from nfs.cli import main
from nfs.sweep import (LocalExecutor, cell_batches, cell_tasks, load_sweep, run_cell, run_cells,
                       run_sweep)



def write_sweep(folder, text, name="sweep.toml"):
    """Write a sweep file into ``folder``; its path."""
    p = folder / name
    p.write_text(text, encoding="utf-8")
    return p

SMALLEST = """\
scenario = "default"
seeds = [1, 2]
[axes]
latitude_deg = [30.0, 60.0]
"""


def _rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_smallest_sweep_as_written(tmp_path, capsys):
    sweep = write_sweep(tmp_path, SMALLEST)
    out = tmp_path / "out"
    assert main(["sweep", str(sweep), "-o", str(out), "-q", "--jobs", "1"]) == 0
    rows = _rows(out / "results.csv")
    for col in ("latitude_deg", "seed", "start_temperature_c", "stage", "heading_rmse_deg"):
        assert col in rows[0]
    # 2 latitudes x 2 seeds x 7 start temperatures x 2 stages
    assert len(rows) == 2 * 2 * 7 * 2
    assert {r["seed"] for r in rows} == {"1", "2"}
    assert {r["stage"] for r in rows} == {"startup", "stable"}
    assert all(math.isfinite(float(r["heading_rmse_deg"])) for r in rows)
    # the floor sqrt(2/N) (ARW/sqrt(dwell)) / (Omega_ie cos L) grows as 1 / cos L
    f30 = {float(r["floor_deg"]) for r in rows if r["latitude_deg"] == "30.0"}
    f60 = {float(r["floor_deg"]) for r in rows if r["latitude_deg"] == "60.0"}
    assert len(f30) == len(f60) == 1
    assert f60.pop() / f30.pop() == pytest.approx(math.cos(math.radians(30)) / 0.5, rel=1e-12)
    assert (out / "heading_rmse_vs_latitude_deg.png").stat().st_size > 10000
    assert "4 cells (4 computed, 0 from the store), 56 rows" in capsys.readouterr().out


def _short_sweep(tmp_path, short_scenario, extra="", seeds="[5, 6]"):
    return load_sweep(write_sweep(tmp_path, f"""\
scenario = "{short_scenario.name}"
seeds = {seeds}
spec_deg = 0.03
{extra}
[axes]
latitude_deg = [20.0, 45.0]
"gyro.arw_deg_per_rth_h" = [0.0005, 0.001]
"""))


def test_one_and_two_jobs_give_the_same_bytes(tmp_path, short_scenario):
    spec = _short_sweep(tmp_path, short_scenario)
    a = run_sweep(spec, tmp_path / "a", executor=LocalExecutor(1), quiet=True, figures=False)
    b = run_sweep(spec, tmp_path / "b", executor=LocalExecutor(2), quiet=True, figures=False)
    assert a.n_computed == b.n_computed == spec.n_cells == 8
    assert (tmp_path / "a" / "results.csv").read_bytes() == \
        (tmp_path / "b" / "results.csv").read_bytes()
    rows = _rows(tmp_path / "a" / "results.csv")
    # rows in cell order: the first grid axis slowest, then the second, then the seed
    order = [(r["latitude_deg"], r["gyro.arw_deg_per_rth_h"], r["seed"]) for r in rows]
    assert order == sorted(order, key=lambda k: (float(k[0]), float(k[1]), int(k[2])))
    # an instrument axis reaches the simulation: the floor is proportional to the ARW
    f = {(r["latitude_deg"], r["gyro.arw_deg_per_rth_h"]): float(r["floor_deg"]) for r in rows}
    assert f[("20.0", "0.001")] / f[("20.0", "0.0005")] == pytest.approx(2.0, rel=1e-12)
    assert {"time_to_spec_s", "time_to_spec_rmse_s"} <= set(rows[0])


@pytest.mark.requires("dask", "distributed")
def test_dask_local_cluster_gives_the_same_bytes(tmp_path, short_scenario):
    from nfs.sweep import DaskExecutor
    spec = _short_sweep(tmp_path, short_scenario)
    run_sweep(spec, tmp_path / "local", executor=LocalExecutor(1), quiet=True, figures=False)
    ex = DaskExecutor(workers=2)
    try:
        res = run_sweep(spec, tmp_path / "dask", executor=ex, quiet=True, figures=False)
    finally:
        ex.close()
    assert res.n_computed == spec.n_cells
    assert (tmp_path / "local" / "results.csv").read_bytes() == \
        (tmp_path / "dask" / "results.csv").read_bytes()


class _Stop(Exception):
    pass


@pytest.mark.parametrize("jobs", [1, 2])
def test_interrupted_sweep_resumes_with_the_missing_cells_only(tmp_path, short_scenario, jobs):
    spec = _short_sweep(tmp_path, short_scenario)
    k = 3

    def stop_after_k(record, seen=[]):
        seen.append(record["key"])
        if len(seen) == k:
            raise _Stop

    with warnings.catch_warnings(record=True) as caught, pytest.raises(_Stop):
        warnings.simplefilter("always")
        run_sweep(spec, tmp_path / "out", executor=LocalExecutor(jobs), quiet=True,
                  on_cell=stop_after_k)
    # the batches in flight are cancelled quietly: the user reads the error, not joblib
    assert not [w for w in caught if "cancelled" in str(w.message)]
    # a batch's records are stored together, before their callbacks: the k seen and the
    # rest of their batch are stored, and only they
    stored = len(list((tmp_path / "out" / "cells").glob("*.json")))
    assert k <= stored < spec.n_cells
    assert not (tmp_path / "out" / "results.csv").exists()
    again = run_sweep(spec, tmp_path / "out", executor=LocalExecutor(jobs), quiet=True,
                      figures=False)
    assert again.n_computed == spec.n_cells - stored
    whole = run_sweep(spec, tmp_path / "whole", executor=LocalExecutor(1), quiet=True,
                      figures=False)
    assert (tmp_path / "out" / "results.csv").read_bytes() == \
        (tmp_path / "whole" / "results.csv").read_bytes()
    assert whole.n_computed == spec.n_cells
    # a third run computes nothing
    assert run_sweep(spec, tmp_path / "out", executor=LocalExecutor(jobs), quiet=True,
                     figures=False).n_computed == 0


def test_more_seeds_compute_only_the_new_cells(tmp_path, short_scenario):
    spec = _short_sweep(tmp_path, short_scenario)
    run_sweep(spec, tmp_path / "out", executor=LocalExecutor(1), quiet=True, figures=False)
    more = load_sweep(write_sweep(tmp_path, (tmp_path / "sweep.toml").read_text().replace(
        "seeds = [5, 6]", "seeds = [5, 6, 7]"), "more.toml"))
    res = run_sweep(more, tmp_path / "out", executor=LocalExecutor(1), quiet=True,
                    figures=False)
    assert (more.n_cells, res.n_computed) == (12, 4)


def test_a_moved_scenario_keeps_its_cells_and_a_changed_one_does_not(tmp_path, short_scenario):
    from nfs.sweep import cell_tasks
    spec = _short_sweep(tmp_path, short_scenario)
    sub = tmp_path / "moved"
    sub.mkdir()
    (sub / short_scenario.name).write_text(short_scenario.read_text())
    moved = load_sweep(write_sweep(sub, (tmp_path / "sweep.toml").read_text()))
    assert [t.key for t in cell_tasks(spec)] == [t.key for t in cell_tasks(moved)]
    (sub / short_scenario.name).write_text(
        short_scenario.read_text().replace("move_s = 10.0", "move_s = 12.0"))
    changed = load_sweep(sub / "sweep.toml")
    assert not {t.key for t in cell_tasks(spec)} & {t.key for t in cell_tasks(changed)}


def test_sobol_draws_are_seeded_and_inside_their_ranges(tmp_path, short_scenario):
    text = f"""\
scenario = "{short_scenario.name}"
seeds = [1]
[axes]
"effects.shupe_winding.k_m" = {{ low = 1e-6, high = 1e-5, log = true }}
schedule.dwell_s = {{ low = 60.0, high = 180.0 }}
[draws]
sampler = "sobol"
count = 4
seed = 3
"""
    spec = load_sweep(write_sweep(tmp_path, text))
    pts = list(spec.points())
    assert spec.n_cells == len(pts) == 4
    again = list(load_sweep(write_sweep(tmp_path, text, "again.toml")).points())
    assert pts == again
    k = np.array([p["effects.shupe_winding.k_m"] for p in pts]) * 1e5  # in 1e-5 /K
    d = np.array([p["schedule.dwell_s"] for p in pts])
    assert np.all((k >= 0.1) & (k <= 1.0)) and np.all((d >= 60.0) & (d <= 180.0))
    # a scrambled Sobol set of 4 puts one point in each quarter of each (log) range
    assert sorted(np.floor(4 * (d - 60.0) / 120.0).astype(int)) == [0, 1, 2, 3]
    assert sorted(np.floor(4 * np.log(k / 0.1) / np.log(10.0)).astype(int)) == [0, 1, 2, 3]


def test_compensated_sweep_has_both_methods(tmp_path, short_scenario):
    spec = _short_sweep(tmp_path, short_scenario, 'method = "ls"')
    spec = type(spec)(**{**spec.__dict__, "axes": spec.axes[:1], "seeds": (5,)})
    run_sweep(spec, tmp_path / "out", executor=LocalExecutor(1), quiet=True, figures=False)
    rows = _rows(tmp_path / "out" / "results.csv")
    assert [r["method"] for r in rows[:4]] == ["none", "none", "ls", "ls"]
    assert len(rows) == 2 * 2 * 2 * 2            # latitudes x T0 x methods x stages
    # the uncompensated rows are those of the same sweep without a method (same start-ups)
    plain = type(spec)(**{**spec.__dict__, "method": None})
    run_sweep(plain, tmp_path / "plain", executor=LocalExecutor(1), quiet=True, figures=False)
    none = [(r["run"], r["stage"], r["heading_rmse_deg"]) for r in rows if r["method"] == "none"]
    assert none == [(r["run"], r["stage"], r["heading_rmse_deg"])
                    for r in _rows(tmp_path / "plain" / "results.csv")]


@pytest.mark.requires("pyarrow")
def test_parquet_holds_the_csv_table(tmp_path, short_scenario):
    import pyarrow.parquet as pq
    spec = _short_sweep(tmp_path, short_scenario)
    res = run_sweep(spec, tmp_path / "out", executor=LocalExecutor(1), quiet=True,
                    figures=False)
    table = pq.read_table(tmp_path / "out" / "results.parquet").to_pylist()
    rows = _rows(tmp_path / "out" / "results.csv")
    assert len(table) == len(rows) == res.n_rows
    for t, r in zip(table, rows):
        assert repr(t["heading_rmse_deg"]) == r["heading_rmse_deg"]
        assert str(t["seed"]) == r["seed"] and t["stage"] == r["stage"]


def test_canonical_form_is_exact_and_leaves_paths_out():
    import dataclasses
    from pathlib import Path

    from nfs.sweep import canonical, digest

    @dataclasses.dataclass(frozen=True)
    class Thing:
        x: float
        path: Path | None = None

    one = Thing(0.1, Path("/a"))
    assert canonical(one)["x"] == "0.1" and "path" not in canonical(one)
    assert digest(one) == digest(Thing(0.1, Path("/elsewhere")))
    assert digest(one) != digest(Thing(np.nextafter(0.1, 1.0)))


def test_a_cell_has_the_same_record_alone_and_in_any_batch(tmp_path, short_scenario):
    # Oracle: the record of run_cell (the cell's runs stacked alone); a batch of a point's
    # three seeds stacks six start-ups (beyond the law's row-by-row limit of four), a batch
    # of two stacks four: neither may change a bit.
    spec = _short_sweep(tmp_path, short_scenario, seeds="[5, 6, 7]")
    tasks = list(cell_tasks(spec))
    alone = [json.dumps(run_cell(t), sort_keys=True) for t in tasks]
    for size in (2, 3):
        batches = list(cell_batches(tasks, size))
        assert max(len(b) for b in batches) == size
        batched = [json.dumps(r, sort_keys=True) for b in batches for r in run_cells(b)]
        assert batched == alone
