"""The compensation study on a reduced budget has the shape the FOG start-up paper's Table 3 leads
us to
expect (by regime, not digits: the simulated instrument is not the paper's).

Oracle: the FOG start-up paper, Table 3 (../shared/reference/seed004_table3_heading_rmse_deg.csv):
SSA-SVR 0.0101 deg vs 0.0209 before (ratio 0.48), every SVR variant ahead of BP.  Checked:
SSA-SVR mean <= 0.6 x before, and below it beyond the table's uncertainty (paired bootstrap
over the test start-ups, Holm); BP better than none of the SVR family beyond the uncertainty
(means crossing inside the noise are a tie); every compensated mean above the white-noise floor; every
interval holds its estimate.  Reduced: 3 test start-ups per temperature instead of 5, 6 of
the 11 methods; the default budget (30 evaluations) and 3 tuner seeds.

The paper trains and tests on one unit, and its comparison is a bench analysis of recorded
runs: the check runs in the default scenario's world without variability
(:meth:`~nfs.scenario.Scenario.nominal`: one unit, every start-up soaked exactly at T0;
training and test start-ups differ by their seeds) on the offline features (the centred rate
window).  The slow tests check SSA-SVR against no compensation with the features an
instrument computes (cycle mode), on that unit and on the fleet scenario, where the
compensator trained on two units is scored on a third.
"""


from pathlib import Path

import numpy as np
import pytest

from nfs.studies.startup_study import run_study
from nfs.compensate.settings import CompensationSettings
from nfs.config.scenario import load_scenario
from nfs.report.compensation import SVR_FAMILY, shape_checks

FLEET = Path(__file__).resolve().parents[2] / "scenarios" / "startup_7temps_fleet.toml"


# The study of 6 methods with their tuners (about 20 s on two cores) is a benchmark-like
# check: its tests are the middle tier's (-m integration); tests/compensate has quick ones
# of each step in the default run.
@pytest.fixture(scope="module")
def study():
    settings = CompensationSettings(methods=("ls", "bp", "svr-grid", "pso-svr", "gwo-svr",
                                             "ssa-svr"), budget=30, test_repeats=3, n_jobs=2,
                                    features_mode="offline", tuner_seeds=3)
    return run_study(load_scenario().nominal(), settings)


@pytest.fixture(scope="module")
def table(study):
    return study.heading_table()


@pytest.mark.integration
def test_expected_shape(table):
    checks = {c.name: c for c in shape_checks(table)}
    for name in ("SSA-SVR mean <= 0.6 x before", "SVR family ahead of BP",
                 "every compensated mean above the floor"):
        assert checks[name].passed, checks[name].detail


@pytest.mark.integration
def test_expected_shape_beyond_the_uncertainty(table):
    ssa = table.comparison("SSA-SVR", "before")
    assert ssa.distinguishable and ssa.ci_high_deg < 0, ssa.sentence()
    # the table compares every row with SSA-SVR and with the best row
    compared = [c for c in (table.comparison("BP", n) for n in SVR_FAMILY) if c is not None]
    assert "SSA-SVR" in [c.method_b for c in compared]
    for c in compared:
        assert not (c.distinguishable and c.difference_deg < 0), c.sentence()
    for r in table.rows:
        if r.method != "floor":
            assert r.ci_low_deg <= r.mean_deg <= r.ci_high_deg, r.method
            lo_hi = np.asarray(r.cell_ci_deg)
            assert np.all(lo_hi[:, 0] <= np.asarray(r.rmse_deg) + 1e-12), r.method
            assert np.all(np.asarray(r.rmse_deg) <= lo_hi[:, 1] + 1e-12), r.method


@pytest.mark.integration
def test_tuned_rows_show_their_median_seed(study, table):
    for name in ("PSO-SVR", "GWO-SVR", "SSA-SVR"):
        means = [r.mean_deg for r in study.results[name].seeds]
        assert len(means) == 3
        assert table.row(name).mean_deg == pytest.approx(float(np.median(means)))
    assert table.row("SVR (grid)").seed_means_deg == ()


@pytest.mark.integration
def test_drift_table_regime(study):
    rows = {r.method: r for r in study.drift_rows()}
    # the FOG start-up paper Table 2: denoised drift STD 0.0134 deg/h; SSA-SVR residual STD 0.0031.
    assert 0.008 <= rows["denoised (no compensation)"].std_dph <= 0.02
    assert rows["SSA-SVR"].std_dph < 0.5 * rows["denoised (no compensation)"].std_dph


@pytest.mark.integration
def test_tuned_parameters_inside_the_box(study):
    p = study.tuned_parameters()["SSA-SVR"]
    assert 0.1 <= p["C"] <= 100 and 0.5 <= p["sigma"] <= 30 and 0.02 <= p["epsilon"] <= 0.5


@pytest.mark.integration
def test_same_seed_same_model(study):
    """Determinism: retraining SSA-SVR with the same random_state gives the same drift."""
    from nfs.compensate import train_compensator
    data = study.dataset
    a = train_compensator("ssa-svr", data, budget=6, random_state=3, n_jobs=1)
    b = train_compensator("ssa-svr", data, budget=6, random_state=3, n_jobs=2)
    run = study.test.simulations[0].run
    np.testing.assert_array_equal(a.predict_drift(run), b.predict_drift(run))
    assert a.estimator.best_params_ == b.estimator.best_params_


@pytest.mark.slow
def test_cycle_mode_ssa_svr_within_the_paper_ratio():
    # The FOG start-up paper's ratio (SSA-SVR 0.48x before) with the features an instrument
    # computes, on
    # one unit: at most 0.6x, and below before beyond the uncertainty.
    settings = CompensationSettings(methods=("ssa-svr",), budget=30, test_repeats=3, n_jobs=2)
    table = run_study(load_scenario().nominal(), settings).heading_table()
    assert table.features_mode == "cycle"
    ssa, before = table.row("SSA-SVR"), table.row("before")
    assert ssa.mean_deg <= 0.6 * before.mean_deg
    c = table.comparison("SSA-SVR", "before")
    assert c.distinguishable and c.difference_deg < 0, c.sentence()


@pytest.mark.slow
def test_cycle_mode_ssa_svr_on_another_unit():
    # scenarios/startup_7temps_fleet.toml: trained on two units, scored on a third.  The
    # unit-to-unit scatter of the drift coefficients is not in the training units' data, so
    # the paper's ratio is not expected; the compensation must still help beyond the
    # uncertainty.
    settings = CompensationSettings(methods=("ssa-svr",), budget=30, test_repeats=3, n_jobs=2,
                                    train_units=(0, 1), test_units=(2,))
    table = run_study(load_scenario(FLEET), settings).heading_table()
    c = table.comparison("SSA-SVR", "before")
    assert c.distinguishable and c.difference_deg < 0, c.sentence()


@pytest.mark.integration
def test_the_study_keeps_what_it_scored(study):
    """The separation of every test run and each row's predicted drift are kept (the report
    draws them instead of computing them again): the drift row's MAE recomputed from them
    is the stored one, to rounding."""
    runs = study.test.simulations
    assert len(study.test_separations) == len(runs)
    end = study.test.scenario.northfind.startup_end_s
    for name, res in study.results.items():
        assert len(res.predicted_drift_dph) == len(runs)
        parts = []
        for sim, sep, pred in zip(runs, study.test_separations, res.predicted_drift_dph):
            t = np.asarray(sim.run.columns["time_s"])
            mask = (t < end) & ~np.asarray(sep.moving, dtype=bool)
            parts.append((np.asarray(sep.drift_dph) - pred)[mask])
        r = np.concatenate(parts)
        r = r[np.isfinite(r)]
        assert np.mean(np.abs(r)) == pytest.approx(res.drift.mae_dph, rel=1e-12), name
