"""Stage rows of the heading table under a chamber program, and what a table prints where
nothing applies.

Oracles: the chamber program's corners in closed form (a hold of 1800 s, a ramp of 10 K at
1 C/min over the next 600 s, a hold): a cycle is ``ramping`` exactly when it overlaps the
ramp; the rows' RMSEs recomputed from the cycles' times; the FOG start-up paper's Table 2
prints "-" where a figure does not apply (the denoised row's MAE).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from nfs.config.scenario import load_scenario
from nfs.report.compensation import drift_table_markdown
from nfs.scoring.heading_table import HeadingTable, TableRow
from nfs.studies.scenario_runs import chamber_moves, run_scenario, stage_names, uncompensated_table

PROGRAM = """name = "held_then_ramp"
start_temperatures_c = [20.0]
repeats = 2
[chamber]
program = [
  { hold_s = 600.0 },
  { power_on = true },
  { hold_s = 1800.0 },
  { ramp_to_c = 30.0, rate_c_per_min = 1.0 },
  { hold_s = 4000.0 },
]
[northfind]
startup_end_s = 1800.0
stable_start_s = 3000.0
"""
RAMP_S = (1800.0, 2400.0)     # from power-on: after the 1800 s hold, 10 K at 1 K/min


@pytest.fixture(scope="module")
def program(tmp_path_factory):
    p = tmp_path_factory.mktemp("stages") / "program.toml"
    p.write_text(PROGRAM)
    return load_scenario(p)


def test_a_cycle_is_ramping_exactly_when_it_overlaps_the_ramp(program):
    a = np.array([0.0, 1000.0, 1700.0, 2300.0, 2400.0, 1000.0, 5000.0])
    b = np.array([1800.0, 1790.0, 1900.0, 2500.0, 3000.0, 3000.0, 6000.0])
    moves = chamber_moves(program, 20.0, a, b)
    assert moves.tolist() == [False, False, True, True, False, True, False]
    # the soak before power-on is not recorded: t = 0 is power-on, not the program's start
    assert not chamber_moves(program, 20.0, -600.0, 0.0)[0]
    plain = load_scenario(None, {"start_temperatures_c": [20.0]})
    assert stage_names(plain) == ("before", "stable")
    assert not chamber_moves(plain, 20.0, a, b).any()
    assert stage_names(program) == ("before", "held", "ramping")


def test_program_rows_are_named_for_what_the_chamber_does(program):
    res = run_scenario(program)
    table = uncompensated_table(res)
    assert [r.method for r in table.rows] == ["before", "held", "ramping", "floor"]
    pooled = {"before": [], "held": [], "ramping": []}
    for nf in res.northfind:
        t0, t1, e = (np.asarray(v) for v in (nf.t_start_s, nf.t_end_s, nf.error_deg))
        ramp = (t1 > RAMP_S[0]) & (t0 < RAMP_S[1])
        pooled["before"] += list(e[(t1 <= 1800.0) & ~ramp])
        pooled["held"] += list(e[(t0 >= 3000.0) & ~ramp])
        pooled["ramping"] += list(e[ramp])
    for name, errs in pooled.items():
        assert len(errs) > 0
        assert table.row(name).rmse_deg[0] == pytest.approx(
            math.sqrt(np.mean(np.square(errs))), rel=1e-12), name
    text = table.to_markdown()
    assert "stable" not in text and "ramps of 1 C/min" in text


def test_not_applicable_is_a_dash_in_markdown_and_csv_and_null_in_json():
    table = HeadingTable((-20.0, 40.0), (TableRow("before", (0.02, math.nan)),
                                         TableRow("floor", (0.005, 0.005))))
    md = table.to_markdown()
    assert "| before | 0.0200 | - | 0.0200 |" in md and "nan" not in md
    csv = table.to_csv()
    assert "before,0.020000,-,0.020000" in csv and "nan" not in csv
    assert json.loads(table.to_json())["rows"][0]["rmse_deg"] == [0.02, None]


def test_the_drift_table_prints_a_dash_and_says_why_as_the_paper():
    class Row:
        def __init__(self, method, mae, std):
            self.method, self.mae_dph, self.std_dph = method, mae, std
    md = drift_table_markdown([Row("denoised (no compensation)", math.nan, 0.0134),
                               Row("BP", 0.0056, 0.0073)])
    assert "| denoised (no compensation) | - | 0.0134 |" in md and "nan" not in md
    assert "MAE -, as in the FOG start-up paper" in md
