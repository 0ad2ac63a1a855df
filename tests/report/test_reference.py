"""The package's copy of the FOG start-up paper's tables equals ../shared/reference (skips without it)."""

import csv
from pathlib import Path

import pytest

from nfs.report.reference import (SEED004_TABLE1_SVR, SEED004_TABLE2_DRIFT_DPH,
                                  SEED004_TABLE3_HEADING_RMSE_DEG, SEED004_TEMPERATURES_C)
from nfs.report.compensation import shape_checks
from nfs.scoring.heading_table import HeadingTable, TableRow

REF = Path(__file__).resolve().parents[2].parent / "shared" / "reference"


def rows(name):
    path = REF / name
    if not path.exists():
        pytest.skip(f"{path} absent (../shared not beside the repo)")
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def test_table3_copy():
    r = rows("seed004_table3_heading_rmse_deg.csv")
    assert tuple(float(t) for t in r[0][1:-1]) == SEED004_TEMPERATURES_C
    assert {row[0]: tuple(float(v) for v in row[1:]) for row in r[1:]} == \
        SEED004_TABLE3_HEADING_RMSE_DEG


def test_table1_and_table2_copies():
    t1 = {row[0]: float(row[1]) for row in rows("seed004_table1_svr_params.csv")[1:]}
    assert t1 == {"C_best": SEED004_TABLE1_SVR["C"], "sigma_best": SEED004_TABLE1_SVR["sigma"]}
    t2 = {row[0]: (float(row[1]) if row[1] else None, float(row[2]))
          for row in rows("seed004_table2_drift_residual_dph.csv")[1:]}
    assert t2 == SEED004_TABLE2_DRIFT_DPH


def test_shape_checks_on_the_papers_own_table():
    """Oracle: the FOG start-up paper's Table 3 itself passes the SSA-SVR and SVR-vs-BP checks
    (ratio 0.48)
    (the 1.3x-of-stable check needs a stable row, which the paper's Table 3 lacks)."""
    t = HeadingTable(SEED004_TEMPERATURES_C, tuple(
        TableRow(m, v[:-1]) for m, v in SEED004_TABLE3_HEADING_RMSE_DEG.items()))
    checks = {c.name: c.passed for c in shape_checks(t)}
    assert checks["SSA-SVR mean <= 0.6 x before"] and checks["SVR family ahead of BP"]
