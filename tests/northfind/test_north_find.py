"""Tests of north-finding whole runs (nfs.northfind.heading) against docs/physics.md section 5.

Runs come from nfs.northfind.synthetic_run, which evaluates the section 5 rate model
(Earth-rate projection with turntable tilt, bias, drift, white noise) sample by sample.
"""

import dataclasses
import math

import numpy as np
import pytest

from nfs.constants import OMEGA_IE_DPH
from nfs.errors import MeasurementError, NfsError
import nfs.northfind.heading as heading
from nfs.run import Run
from nfs.northfind import (east_tilt_error_deg, heading_rmse, linear_drift_error_deg,
                           north_find, synthetic_run, white_noise_floor_deg, wrap_deg_180)

FWD_REV = (0.0, 90.0, 180.0, 270.0, 270.0, 180.0, 90.0, 0.0)


def _with_meta(run: Run, **changes) -> Run:
    return dataclasses.replace(run, meta=dataclasses.replace(run.meta, **changes))


@pytest.mark.parametrize("n_positions", [3, 4, 6, 8, 12])
def test_noiseless_tilted_runs_give_the_true_heading(n_positions):
    # Oracle: noiseless data from the exact model -> psi exactly (style.md, practice 9),
    # for random headings, tilts, latitudes 0-70 deg and biases; tilt correction on.
    rng = np.random.default_rng(100 + n_positions)
    sched = tuple(360.0 * np.arange(n_positions) / n_positions)
    for _ in range(6):
        psi = rng.uniform(0, 360)
        run = synthetic_run(heading_deg=psi, latitude_deg=rng.uniform(0, 70),
                            positions_deg=sched, dwell_s=60.0, move_s=5.0, n_cycles=2,
                            tilt_north_deg=rng.uniform(-0.5, 0.5),
                            tilt_east_deg=rng.uniform(-0.5, 0.5), bias_dph=rng.normal(0, 3))
        res = north_find(run)
        assert res.n_cycles == 2
        assert np.all(np.abs(res.error_deg) < 1e-9), res.error_deg
        assert np.all(np.abs(wrap_deg_180(res.heading_deg - psi)) < 1e-9)
        omega_h = OMEGA_IE_DPH * math.cos(math.radians(run.meta.latitude_deg))
        np.testing.assert_allclose(res.horizontal_rate_dph, omega_h, rtol=1e-12)


def test_noiseless_run_without_schedule_metadata():
    # Oracle: as above; the schedule (forward-then-reverse) is recovered from the samples.
    run = synthetic_run(heading_deg=301.0, latitude_deg=45.0, positions_deg=FWD_REV,
                        n_cycles=3, tilt_north_deg=0.2, tilt_east_deg=-0.3, bias_dph=1.0)
    res = north_find(_with_meta(run, positions_deg=None, dwell_s=None))
    assert res.n_cycles == 3 and res.theta_deg.shape == (3, 8)
    assert np.all(np.abs(res.error_deg) < 1e-9)


def test_forward_reverse_cancels_linear_drift_sequential_does_not():
    # Oracle: docs/physics.md section 5. A linear drift b(t) = k t:
    # - forward-then-reverse: each angle's two dwells have the same mean time, so the drift
    #   is the same at every angle and goes into b: zero heading error (exactly);
    # - sequential, N equally spaced positions, dwell centres Delta = dwell + move apart:
    #   dX = -k Delta, dY = k Delta cot(pi/N) exactly, psi_hat = atan2(Y + dY, X + dX);
    #   to first order (k Delta / Omega_h)(cot(pi/N) cos psi + sin psi)
    #   (budget.linear_drift_error_deg), the rest bounded by |u|^2 / (2 (1 - |u|)) with
    #   |u| = (k Delta / Omega_h) / sin(pi/N) (remainder of log(1 + u)).
    lat, k = 30.0, 8e-5  # k [deg/h per s]: k Delta / Omega_h ~ 1e-3 rad
    omega_h = OMEGA_IE_DPH * math.cos(math.radians(lat))

    def drift(t):
        return k * t

    for psi in (0.0, 37.0, 212.7, 300.0):
        fr = north_find(synthetic_run(heading_deg=psi, latitude_deg=lat, positions_deg=FWD_REV,
                                      n_cycles=3, drift_dph=drift, bias_dph=0.4))
        assert np.all(np.abs(fr.error_deg) < 1e-9), fr.error_deg
        for n in (3, 4, 6, 8):
            sched = tuple(360.0 * np.arange(n) / n)
            run = synthetic_run(heading_deg=psi, latitude_deg=lat, positions_deg=sched,
                                dwell_s=150.0, move_s=10.0, n_cycles=3, drift_dph=drift)
            err = north_find(run).error_deg
            step = 160.0
            c = 1.0 / math.tan(math.pi / n)
            p = math.radians(psi)
            exact = wrap_deg_180(math.degrees(math.atan2(omega_h * math.sin(p) + k * step * c,
                                                         omega_h * math.cos(p) - k * step) - p))
            np.testing.assert_allclose(err, exact, rtol=0, atol=1e-9)
            linear = linear_drift_error_deg(k, step, n, psi, lat)
            u = k * step / omega_h / math.sin(math.pi / n)
            bound = math.degrees(u * u / (2 * (1 - u)))
            assert abs(exact - linear) <= bound
            assert bound < 2e-4  # vs errors of 0.02-0.14 deg here: a tight check


def test_quadratic_drift_is_not_cancelled_by_forward_reverse():
    # Oracle: docs/physics.md section 5 ("cancels linear drift exactly, not quadratic drift");
    # a test that the exact cancellation above is specific to linear drift.
    res = north_find(synthetic_run(heading_deg=50.0, positions_deg=FWD_REV, n_cycles=2,
                                   drift_dph=lambda t: 1e-8 * t ** 2))
    assert np.all(np.abs(res.error_deg) > 1e-4)


def test_white_noise_rmse_matches_the_floor():
    # Oracle: docs/physics.md section 5, sigma_psi = sqrt(2/N)(ARW/sqrt(tau))/(Omega_ie cos L).
    # 1500 cycles: the sample RMSE has a relative standard deviation of about
    # 1/sqrt(2 * 1500) = 1.8 %, so 10 % is more than 5 sigma.
    arw, dwell, lat = 0.0005, 150.0, 30.0
    run = synthetic_run(heading_deg=212.7, latitude_deg=lat, dwell_s=dwell, move_s=10.0,
                        n_cycles=1500, arw_deg_per_rth_h=arw, tilt_north_deg=0.1,
                        tilt_east_deg=0.1, bias_dph=0.5, random_state=20240601)
    res = north_find(run)
    assert res.n_cycles == 1500
    rmse = float(np.sqrt(np.mean(res.error_deg ** 2)))
    floor = white_noise_floor_deg(arw, dwell, 4, lat)
    assert floor == pytest.approx(0.00757, rel=1e-2)  # hand value: 0.0076 deg
    assert rmse == pytest.approx(floor, rel=0.10)


@pytest.mark.parametrize("lat", [10.0, 30.0, 60.0])
@pytest.mark.parametrize("psi", [20.0, 200.0])
def test_uncorrected_east_tilt_error_is_minus_alpha_e_tan_l(lat, psi):
    # Oracle: docs/physics.md section 4, |error| = alpha_E tan L; sign derived in
    # budget.east_tilt_error_deg (estimated - true = -alpha_E tan L). First order in the
    # tilt: with alpha = 0.1 deg = 1.7 mrad the second-order remainder is ~ alpha relative,
    # so 1 % tolerance. North tilt alone only rescales Omega_h (error second order).
    alpha_e = 0.1
    run = synthetic_run(heading_deg=psi, latitude_deg=lat, n_cycles=2, tilt_east_deg=alpha_e)
    err = north_find(run, tilt_correction=False).error_deg
    expected = east_tilt_error_deg(alpha_e, lat)
    assert expected == pytest.approx(-alpha_e * math.tan(math.radians(lat)))
    np.testing.assert_allclose(err, expected, rtol=1e-2)
    assert np.all(np.abs(north_find(run).error_deg) < 1e-9)  # corrected
    north = synthetic_run(heading_deg=psi, latitude_deg=lat, n_cycles=2, tilt_north_deg=alpha_e)
    assert np.all(np.abs(north_find(north, tilt_correction=False).error_deg)
                  < 1e-2 * abs(expected))


def test_error_wraps_to_plus_minus_180():
    # Oracle: definition; a heading of 0.02 against a true heading of 359.98 is +0.04 deg,
    # not -359.96.
    run = synthetic_run(heading_deg=0.02, n_cycles=2)
    res = north_find(_with_meta(run, true_heading_deg=359.98))
    np.testing.assert_allclose(res.error_deg, 0.04, atol=1e-9)
    res = north_find(_with_meta(run, true_heading_deg=180.02))
    np.testing.assert_allclose(res.error_deg, -180.0, atol=1e-9)
    res = north_find(_with_meta(run, true_heading_deg=None))
    assert np.all(np.isnan(res.error_deg))
    with pytest.raises(NfsError, match="true_heading_deg"):
        heading_rmse(res)


def test_stage_rmse_selects_cycles_by_time():
    # Oracle: 4 x (150 s dwell + 10 s move) cycles over 9000 s start at 640 c and end at
    # 640 c + 629 (c = 0..13). Start-up (end <= 3600): c = 0..4; stable (start >= 5400):
    # c = 9..13. With error c + 1 the RMSEs are sqrt(mean(1..5)^2) and sqrt(mean(10..14)^2).
    res = north_find(synthetic_run(heading_deg=10.0, duration_s=9000.0))
    assert res.n_cycles == 14
    res = dataclasses.replace(res, error_deg=np.arange(1.0, 15.0))
    s = heading_rmse(res)
    assert (s.n_startup, s.n_stable) == (5, 5)
    assert s.startup_deg == pytest.approx(math.sqrt(np.mean(np.arange(1, 6) ** 2)))
    assert s.stable_deg == pytest.approx(math.sqrt(np.mean(np.arange(10, 15) ** 2)))
    s = heading_rmse(res, startup_end_s=629.0, stable_start_s=8320.0)
    assert (s.n_startup, s.n_stable, s.startup_deg, s.stable_deg) == (1, 1, 1.0, 14.0)
    s = heading_rmse(res, startup_end_s=100.0, stable_start_s=9000.0)
    assert (s.n_startup, s.n_stable) == (0, 0) and math.isnan(s.startup_deg)


def test_missing_data_gives_nan_for_that_cycle_only():
    # Oracle: a dwell with no finite gyro sample cannot be averaged; the other cycles are
    # unaffected (exact heading).
    run = synthetic_run(heading_deg=75.0, n_cycles=3)
    gyro = run.columns["gyro_dph"].copy()
    d = north_find(run).cycles[1].dwells[2]
    gyro[d.index] = np.nan
    gyro[5] = np.nan  # one missing sample in cycle 0 is ignored
    res = north_find(dataclasses.replace(run, columns={**run.columns, "gyro_dph": gyro}))
    assert np.isnan(res.heading_deg[1])
    assert np.all(np.abs(res.error_deg[[0, 2]]) < 1e-9)
    # the missing samples counted are those inside the dwells, per column
    samples = np.arange(gyro.size)
    inside = np.concatenate([samples[dw.index] for c in res.cycles for dw in c.dwells])
    assert res.n_missing == {"gyro_dph": len(samples[d.index]) + int(5 in inside)}
    # the same for a dwell without accelerometer data, when tilt correction needs it
    acc = run.columns["acc_x_g"].copy()
    acc[north_find(run).cycles[2].dwells[0].index] = np.nan
    run_acc = dataclasses.replace(run, columns={**run.columns, "acc_x_g": acc})
    res = north_find(run_acc)
    assert np.isnan(res.heading_deg[2]) and np.all(np.abs(res.error_deg[:2]) < 1e-9)
    lost = len(acc[north_find(run).cycles[2].dwells[0].index])
    assert res.n_missing == {"acc_x_g": lost}
    level = north_find(run_acc, tilt_correction=False)
    assert np.all(np.abs(level.error_deg) < 1e-9) and level.n_missing == {"acc_x_g": lost}


def test_result_is_frozen_and_errors_locate_the_fault():
    run = synthetic_run(heading_deg=75.0, n_cycles=1)
    res = north_find(run)
    with pytest.raises(ValueError):
        res.heading_deg[0] = 1.0
    with pytest.raises(MeasurementError, match="no column 'gyro_comp_dph'"):
        north_find(run, gyro_column="gyro_comp_dph")
    with pytest.raises(MeasurementError, match="no complete north-finding cycle"):
        north_find(_with_meta(run, positions_deg=(0.0, 45.0, 90.0)))
    one_angle = synthetic_run(heading_deg=75.0, positions_deg=(0.0, 0.0, 0.0), n_cycles=2,
                              skip_null_moves=False)
    with pytest.raises(NfsError, match="cannot determine psi"):
        north_find(one_angle)


def test_two_position_run_uses_the_known_horizontal_rate():
    # Oracle: two-position method (solve_heading); the hint resolves the sign.
    run = synthetic_run(heading_deg=290.0, latitude_deg=35.0, positions_deg=(0.0, 180.0),
                        n_cycles=3, bias_dph=2.0)
    res = north_find(run, heading_hint_deg=280.0)
    assert not res.ambiguous and np.all(np.abs(res.error_deg) < 1e-9)
    res = north_find(run)
    assert res.ambiguous and np.allclose(res.heading_deg, 70.0)


def test_runs_that_share_their_motion_are_segmented_once_with_the_same_results():
    # Oracle: north_find of each run with its segmentation forgotten before (the runs alone),
    # field by field, for runs met in turn that share their motion (two headings: the same
    # time base and turntable angles), then a run of another schedule and one with a settle
    # time (segmented anew), then the first run again.
    sched4, sched3 = (0.0, 90.0, 180.0, 270.0), (0.0, 120.0, 240.0)
    runs = [synthetic_run(heading_deg=h, latitude_deg=40.0, positions_deg=sched4,
                          n_cycles=2, bias_dph=0.5) for h in (10.0, 200.0)]
    runs.append(synthetic_run(heading_deg=10.0, latitude_deg=40.0, positions_deg=sched3,
                              n_cycles=2))
    calls = [(r, 0.0) for r in runs] + [(runs[0], 5.0), (runs[1], 0.0)]
    fields = ("heading_deg", "error_deg", "rate_dph", "theta_deg", "t_start_s", "t_end_s")
    for run, settle in calls:
        met = north_find(run, settle_s=settle)
        heading._LAST_SEGMENTS[0] = None
        alone = north_find(run, settle_s=settle)
        assert met.cycles == alone.cycles
        for f in fields:
            assert np.array_equal(getattr(met, f), getattr(alone, f)), f
    assert north_find(runs[0], settle_s=5.0).t_start_s[0] > north_find(runs[0]).t_start_s[0]
