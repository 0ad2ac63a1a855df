"""Beyond the paper: the best method's start-up heading RMSE within 1.3x of
the stable-stage RMSE at every one of the 7 start temperatures.

Measured on scenarios/startup_7temps_precise.toml (30 test and 3 training start-ups per
temperature): with the default file's 5 test start-ups the ratio of two stage RMSEs carries
+-20 % sampling error and even a perfect compensator (the simulator's true drift subtracted)
reaches 2.0x at 54 C, so the claim is only testable with more start-ups.  Oracle: the stable
stage of the same runs, and the check of nfs.report.shape_checks.
"""

from pathlib import Path

import dataclasses

import numpy as np
import pytest

from nfs.studies.startup_study import run_study
from nfs.config.scenario import load_scenario
from nfs.report.compensation import shape_checks

PRECISE = Path(__file__).resolve().parents[2] / "scenarios" / "startup_7temps_precise.toml"


def _ratios(table, method):
    return np.array(table.row(method).rmse_deg) / np.array(table.row("stable").rmse_deg)


def test_least_squares_within_1_3x_of_stable_at_every_temperature():
    # The cheapest of the compensators (cubic least squares, Tao et al. (2019)) on the precise
    # scenario.
    sc = load_scenario(PRECISE)
    st = run_study(sc, dataclasses.replace(sc.compensation, methods=("ls",)))
    table = st.heading_table()
    r = _ratios(table, "LS")
    assert np.all(r <= 1.3), r
    assert table.row("LS").mean_deg < 0.5 * table.row("before").mean_deg


def test_a_perfect_compensator_is_at_the_stable_stage():
    # Oracle: the simulator's own thermal drift (sum of the gyro effect terms) subtracted from
    # the rate of each of the 30 test start-ups per temperature: what is left is noise, so
    # the start-up RMSE equals the stable one up to sampling error (+-6 % per stage).
    from dataclasses import replace

    from nfs.studies.scenario_runs import run_scenario
    from nfs.northfind import heading_rmse, north_find
    sc = load_scenario(PRECISE)
    res = run_scenario(dataclasses.replace(sc, repeats=sc.compensation.test_repeats))
    per_t0 = {}
    for sim in res.simulations:
        run = sim.run
        cols = dict(run.columns)
        cols["perfect_dph"] = np.asarray(run["gyro_dph"], dtype=float) - sim.drift_dph
        st = heading_rmse(north_find(replace(run, columns=cols), gyro_column="perfect_dph"),
                          startup_end_s=sc.northfind.startup_end_s,
                          stable_start_s=sc.northfind.stable_start_s)
        acc = per_t0.setdefault(sim.conditions.start_temperature_c, [0.0, 0, 0.0, 0])
        acc[0] += st.startup_deg ** 2 * st.n_startup
        acc[1] += st.n_startup
        acc[2] += st.stable_deg ** 2 * st.n_stable
        acc[3] += st.n_stable
    ratios = [np.sqrt(a / n) / np.sqrt(b / m) for a, n, b, m in per_t0.values()]
    assert len(ratios) == 7 and 0.8 < min(ratios) and max(ratios) < 1.2, ratios


@pytest.mark.slow
def test_best_method_within_1_3x_of_stable_every_row():
    # Every row of the table (about 100 s on 2 cores).
    sc = load_scenario(PRECISE)
    table = run_study(sc).heading_table()
    check = [c for c in shape_checks(table) if "1.3x" in c.name]
    assert check and check[0].passed, check
