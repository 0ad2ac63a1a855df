"""A regression test of an instrument's heading table: copy this file into your own tests.

Question it answers on every run: is the heading-RMSE table of my scenario still as good as
the one I accepted (no cell worse beyond its noise and 5 %), and does my drift compensator
still do no harm?

First run: the table is computed and written beside this file as
``my_instrument_baseline.json`` (the test is skipped: commit that file). Every later run
recomputes the table and compares it cell by cell with the baseline, paired over the same
test start-ups (``nfs table --baseline`` does the same on the command line). After a change
you mean to keep, delete the baseline and run again.

    pytest examples/test_my_instrument.py      # about 15 s

Point ``SCENARIO`` at your own scenario file (``nfs init DIR`` writes a starter).
"""

import dataclasses
import shutil
from pathlib import Path

import pytest

import nfs
from nfs.testing import assert_compensator_no_worse, assert_table_within

#: The baseline, kept beside this file and committed with it.
BASELINE = Path(__file__).with_name("my_instrument_baseline.json")

#: A small, fast experiment: three start temperatures, one 65-min start-up each, the
#: default instrument; compensated by least squares (trained on start-ups of another seed).
SCENARIO = """
name = "my_instrument"
seed = 5
start_temperatures_c = [-20.0, 10.0, 40.0]
duration_s = 3900.0
latitude_deg = 30.0
true_heading_deg = 40.0
[schedule]
positions_deg = [0.0, 90.0, 180.0, 270.0]
dwell_s = 150.0
move_s = 10.0
[compensation]
methods = ["ls"]
train_seed = 9
test_repeats = 1
n_jobs = 1
"""


def my_scenario(folder: Path) -> nfs.Scenario:
    """The scenario above, as a file in ``folder`` and loaded (point this at your own file)."""
    path = folder / "scenario.toml"
    path.write_text(SCENARIO)
    return nfs.load_scenario(path)


def simulated_runs(scenario: nfs.Scenario, seed: int) -> list[nfs.Run]:
    """The scenario's start-ups simulated with their own seed (as ``nfs simulate --seed``)."""
    scenario = dataclasses.replace(scenario, seed=seed)
    return [nfs.simulate_run(scenario.instrument, cond).run for cond in scenario.conditions()]


def test_table_no_worse_than_baseline(tmp_path):
    result = nfs.ModelChain(my_scenario(tmp_path)).run_model()
    table = tmp_path / "table.json"
    result.write(tmp_path / "out", json_path=table)
    if not BASELINE.exists():
        shutil.copyfile(table, BASELINE)
        pytest.skip(f"baseline written to {BASELINE}: commit it")
    assert_table_within(table, BASELINE, tolerance=0.05)


def test_compensator_no_worse_than_none(tmp_path):
    scenario = my_scenario(tmp_path)
    # training start-ups and test start-ups of other seeds: no test noise seen in training
    train, test = simulated_runs(scenario, 1), simulated_runs(scenario, 2)
    compensator = nfs.train_compensator("ls", train)
    assert_compensator_no_worse(compensator, test)
