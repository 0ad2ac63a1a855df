"""Sweeps stream their runs: a cell's record does not depend on how many start-ups are
marched beside it or where the memory bound cuts the chunks, and a fully stored rerun keeps
its figures when what they show has not changed."""

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest

import nfs.experiment
from nfs.experiment import iter_simulate_runs, simulate_run
from nfs.config.scenario import load_scenario
from nfs.sweep import LocalExecutor, cell_batches, cell_tasks, load_sweep, run_cell, run_cells, \
    run_sweep
from nfs.sweep import cells
from nfs.sweep.run import FIGURES_RECORD


def _sweep(tmp_path, short_scenario, seeds):
    p = tmp_path / "sweep.toml"
    p.write_text(f'scenario = "{short_scenario.name}"\nseeds = {seeds}\nspec_deg = 0.03\n'
                 "[axes]\nlatitude_deg = [20.0]\n", encoding="utf-8")
    return load_sweep(p)


def test_a_cell_has_its_record_beside_many_start_ups(tmp_path, short_scenario):
    # Oracle: run_cell, the cell alone (its two start-ups marched together); a batch of nine
    # cells marches eighteen start-ups at once, and a memory bound of three start-ups cuts
    # the chunks inside cells.
    spec = _sweep(tmp_path, short_scenario, list(range(9)))
    tasks = list(cell_tasks(spec))
    assert 2 * len(tasks) == 18
    alone = [json.dumps(run_cell(t), sort_keys=True) for t in tasks]
    (batch,) = list(cell_batches(tasks))
    assert [json.dumps(r, sort_keys=True) for r in run_cells(batch)] == alone
    per_run = 8 * (7 + 1) * 2400           # 7 temperatures and the TEC's node's power
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(nfs.experiment, "STACK_BYTES", 3 * per_run)
        assert [json.dumps(r, sort_keys=True) for r in run_cells(batch)] == alone


def test_streamed_runs_are_the_single_runs(short_scenario):
    # Oracle: simulate_run of each start-up alone, bit for bit, for the streamed runs of
    # three seeds whose chunks (a bound of two start-ups) split the seeds' runs.
    base = load_scenario(str(short_scenario))
    conds = [c for seed in (1, 2, 3) for c in
             dataclasses.replace(base, seed=seed).conditions()]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(nfs.experiment, "STACK_BYTES", 2 * 8 * (7 + 1) * 2400)
        streamed = list(iter_simulate_runs(base.instrument, conds))
    for cond, sim in zip(conds, streamed, strict=True):
        one = simulate_run(base.instrument, cond)
        assert np.array_equal(one.thermal.temperature_c, sim.thermal.temperature_c)
        for col, v in one.run.columns.items():
            assert np.array_equal(v, sim.run.columns[col], equal_nan=True), col


def test_runs_without_the_optional_columns_keep_every_other_bit(short_scenario):
    # Oracle: the runs with every column (simulate_run alone): with channels=() (what a
    # sweep's record reads) the gyro, accelerometers, turntable and drift terms are the same
    # bits, and no thermometer, chamber or aux column is made; with one thermometer asked
    # for, that column is the full run's.
    base = load_scenario(str(short_scenario))
    conds = dataclasses.replace(base, seed=4).conditions()[:3]
    full = [simulate_run(base.instrument, c) for c in conds]
    bare = list(iter_simulate_runs(base.instrument, conds, channels=()))
    one = list(iter_simulate_runs(base.instrument, conds, channels=("temp_fog_c",)))
    optional = set(nfs.experiment.OPTIONAL_COLUMNS) | {a.name for a in base.instrument.aux}
    for f, b, o in zip(full, bare, one, strict=True):
        assert set(b.run.columns) == set(f.run.columns) - optional
        for col, v in b.run.columns.items():
            assert np.array_equal(v, f.run.columns[col], equal_nan=True), col
        for label, v in f.gyro_terms_dph.items():
            assert np.array_equal(v, b.gyro_terms_dph[label]), label
        assert set(o.run.columns) == set(b.run.columns) | {"temp_fog_c"}
        assert np.array_equal(o.run.columns["temp_fog_c"], f.run.columns["temp_fog_c"])


def test_a_stored_rerun_keeps_its_figures(tmp_path, short_scenario):
    # Oracle: the figures' files are not rewritten when the sweep and its table are the
    # same (their modification times stay), and are drawn again when one is missing.
    spec = _sweep(tmp_path, short_scenario, [1])
    out = tmp_path / "out"
    first = run_sweep(spec, out, executor=LocalExecutor(1), quiet=True)
    figures = [p for p in first.paths if p.suffix == ".png"]
    assert figures and (out / FIGURES_RECORD).is_file()
    stamps = [p.stat().st_mtime_ns for p in figures]
    again = run_sweep(spec, out, executor=LocalExecutor(1), quiet=True)
    assert again.n_computed == 0
    assert [p for p in again.paths if p.suffix == ".png"] == figures
    assert [p.stat().st_mtime_ns for p in figures] == stamps
    figures[0].unlink()
    run_sweep(spec, out, executor=LocalExecutor(1), quiet=True)
    assert figures[0].is_file()


def test_a_fully_stored_rerun_computes_and_draws_nothing(tmp_path, short_scenario):
    # Oracle: what a process imports.  `nfs sweep` rerun on a sweep whose every cell is
    # stored and whose figures are current reads the store and writes the table: it loads
    # neither the cells' computation, the executors nor matplotlib (a fresh interpreter,
    # so nothing was imported before), and it names the same files as the first run.
    _sweep(tmp_path, short_scenario, [1])
    out = tmp_path / "out"
    argv = ["sweep", str(tmp_path / "sweep.toml"), "-o", str(out), "--jobs", "1", "-q"]
    probe = ("import sys\nfrom nfs.cli import main\nassert main(sys.argv[1:]) == 0\n"
             "print(sorted(m for m in sys.modules if m.startswith(('matplotlib', "
             "'nfs.sweep.cells', 'nfs.sweep.executors', 'nfs.sweep.figures', 'dask'))))\n")
    first = subprocess.run([sys.executable, "-c", probe, *argv], check=True,
                           capture_output=True, text=True).stdout.splitlines()
    again = subprocess.run([sys.executable, "-c", probe, *argv], check=True,
                           capture_output=True, text=True).stdout.splitlines()
    assert first[0].startswith("1 cells (1 computed") and "matplotlib" in first[-1]
    assert again[0].startswith("1 cells (0 computed, 1 from the store)")
    assert again[1:-1] == first[1:-1]                  # results.csv and the figures
    assert again[-1] == "[]"


def test_batches_of_a_list_valued_point_share_its_scenario(tmp_path, short_scenario):
    # Oracle: run_cell of each cell alone, with the worker's kept point cleared.  A point may
    # hold a list (an axis over start_temperatures_c); a worker's consecutive batches of that
    # point reuse the scenario it loaded, and give the records of the cells computed alone.
    p = tmp_path / "sweep.toml"
    p.write_text(f'scenario = "{short_scenario.name}"\nseeds = [0, 1, 2]\nspec_deg = 0.03\n'
                 "[axes]\nstart_temperatures_c = [[-20.0], [30.0]]\n", encoding="utf-8")
    tasks = list(cell_tasks(load_sweep(p)))
    assert all(t.base_digest for t in tasks)
    alone = []
    for t in tasks:
        cells._LAST_POINT[0] = None
        alone.append(json.dumps(run_cell(t), sort_keys=True))
    cells._LAST_POINT[0] = None
    got = [json.dumps(r, sort_keys=True)
           for batch in cell_batches(tasks, size=2) for r in run_cells(batch)]
    assert got == alone
    kept = cells._LAST_POINT[0][1]
    assert cells._point_scenario(tasks[-1]) is kept        # the last point, not loaded again
