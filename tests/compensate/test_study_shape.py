"""The compensation study on a reduced budget has the shape seed 004's Table 3 leads us to
expect (by regime, not digits: the simulated instrument is not the paper's).

Oracle: seed 004, Table 3 (../shared/reference/seed004_table3_heading_rmse_deg.csv):
SSA-SVR 0.0101 deg vs 0.0209 before (ratio 0.48), every SVR variant ahead of BP.  Checked:
SSA-SVR mean <= 0.6 x before; each SVR-family mean below BP's; every compensated mean above
the white-noise floor.  Reduced: 3 test start-ups per temperature instead of 5, 6 of the 11
methods (about 30 s); the tuners keep the default budget of 30 evaluations (at 12 or 20 the
tuned SVR rows scatter between 0.008 and 0.018 deg).

The paper's comparison is a bench analysis of recorded runs, so it is reproduced with the
offline features (the centred rate window).  With the features an instrument computes
(cycle mode, the default) the SVR rows and BP trade places from one training draw to the
next (over five training seeds BP's mean scatters from 0.008 to 0.016 deg); the slow test
below checks the cycle-mode figure that matters, SSA-SVR against no compensation.
"""


import numpy as np
import pytest

from nfs.compensate.study import CompensationSettings, run_study
from nfs.io.scenario import load_scenario
from nfs.report.compensation import shape_checks


@pytest.fixture(scope="module")
def study():
    settings = CompensationSettings(methods=("ls", "bp", "svr-grid", "pso-svr", "gwo-svr",
                                             "ssa-svr"), budget=30, test_repeats=3, n_jobs=2,
                                    features_mode="offline")
    return run_study(load_scenario().nominal(), settings)


def test_expected_shape(study):
    table = study.heading_table()
    checks = {c.name: c for c in shape_checks(table)}
    for name in ("SSA-SVR mean <= 0.6 x before", "SVR family ahead of BP",
                 "every compensated mean above the floor"):
        assert checks[name].passed, checks[name].detail


def test_drift_table_regime(study):
    rows = {r.method: r for r in study.drift_rows()}
    # seed 004 Table 2: denoised drift STD 0.0134 deg/h; SSA-SVR residual STD 0.0031.
    assert 0.008 <= rows["denoised (no compensation)"].std_dph <= 0.02
    assert rows["SSA-SVR"].std_dph < 0.5 * rows["denoised (no compensation)"].std_dph


def test_tuned_parameters_inside_the_box(study):
    p = study.tuned_parameters()["SSA-SVR"]
    assert 0.1 <= p["C"] <= 100 and 0.5 <= p["sigma"] <= 30 and 0.02 <= p["epsilon"] <= 0.5


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
    # Seed 004's ratio (SSA-SVR 0.48x before) with the features an instrument computes:
    # at most 0.6x, and below before at every start temperature but the 28 C one, where the
    # uncompensated start-up is already at the stable stage's level (0.0082 deg).
    settings = CompensationSettings(methods=("ssa-svr",), budget=30, test_repeats=3, n_jobs=2)
    table = run_study(load_scenario().nominal(), settings).heading_table()
    assert table.features_mode == "cycle"
    ssa, before = table.row("SSA-SVR"), table.row("before")
    assert ssa.mean_deg <= 0.6 * before.mean_deg
    for t0, a, b in zip(table.temperatures_c, ssa.rmse_deg, before.rmse_deg):
        if t0 != 28.0:
            assert a < b, (t0, a, b)
