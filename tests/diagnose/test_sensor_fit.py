"""Turntable tilt and accelerometer biases from the means at rest (nfs.fit.sensor_fit),
and the drift stage's sensor parameters on simulated runs.

Oracles: (1) noise-free window means made from known tilts and biases with the exact sin(e)
of nfs.sensors.axis_elevation_deg come back to float precision (closed form); (2) runs
simulated from an instrument with QFA biases of a few mg and a 0.3 deg tilt, far from the
preset (hidden truth): after the drift stage the biases and tilts are within 3 standard errors
of the truth and the accelerometer window-mean residuals are at their noise floor, the white
noise 20 ug/sqrt(Hz) (one-sided: 14.1 ug per sample at 1 Hz) over 10-sample windows,
4.47 ug; (3) the gyro noise the fit reads from the drift residual at rest is the simulator's,
N = 0.0003 deg/sqrt(h) and B = 0.002 deg/h, within 20 %.
"""

import math

import numpy as np
import pytest

from nfs.fit.calibration import fit_model
from nfs.fit.params import get_param, set_params
from nfs.fit.sensor_fit import LEVEL_PATHS, LevelData, level_from_means
from nfs.experiment import simulate_run
from nfs.config.scenario import load_scenario
from nfs.sensors import axis_elevation_deg

TRUTH = {"turntable.tilt_north_deg": 0.3, "turntable.tilt_east_deg": -0.2,
         "accelerometers.bias_x_g": 3e-3, "accelerometers.bias_y_g": -2e-3,
         "effects.shupe_winding.k_m": 1.5e-5}

#: Standard error of a 10 s window mean of the QFA white noise [g].
WINDOW_FLOOR_G = 20e-6 * math.sqrt(0.5) / math.sqrt(10.0)


def test_level_closed_form():
    a = np.radians(np.repeat([12.7, 102.7, 192.7, 282.7], 5) + np.linspace(0, 0.1, 20))
    az = np.degrees(a)
    tn, te, bx, by = 0.4, -0.7, 2e-3, -1e-3
    fx = np.sin(np.radians(axis_elevation_deg(az, tn, te))) + bx
    fy = np.sin(np.radians(axis_elevation_deg(az + 90.0, tn, te))) + by
    data = [LevelData(np.cos(a), np.sin(a), fx, fy)]
    start = dict.fromkeys(LEVEL_PATHS, 0.0)
    got = level_from_means(data, start, LEVEL_PATHS)
    np.testing.assert_allclose([got[p] for p in LEVEL_PATHS], [tn, te, bx, by], rtol=1e-9)
    # a held parameter stays out of the answer and the others still come back
    held = level_from_means(data, {**start, "turntable.tilt_east_deg": te},
                            LEVEL_PATHS[:1] + LEVEL_PATHS[2:])
    assert set(held) == {LEVEL_PATHS[0], *LEVEL_PATHS[2:]}
    assert held["turntable.tilt_north_deg"] == pytest.approx(tn, rel=1e-9)


@pytest.fixture(scope="module")
def drift_fit():
    sc = load_scenario().nominal()
    truth = set_params(sc.instrument, TRUTH)
    runs = [simulate_run(truth, c).run for c in sc.conditions()]
    return truth, fit_model(sc.instrument, runs, stages=("drift",))


def test_biases_and_tilts_recovered(drift_fit):
    truth, res = drift_fit
    for p in LEVEL_PATHS:
        want = get_param(truth, p)
        assert abs(res.params[p] - want) <= 3 * res.stderr[p], (p, res.params[p], want)
    for ch in ("acc_x_g", "acc_y_g"):
        assert res.rms_before[ch] > 100 * WINDOW_FLOOR_G
        assert res.rms_after[ch] == pytest.approx(WINDOW_FLOOR_G, rel=0.1), ch


def test_gyro_noise_from_drift_residual(drift_fit):
    truth, res = drift_fit
    assert res.noise is not None
    assert res.noise.arw_deg_per_rth_h == pytest.approx(truth.gyro.arw_deg_per_rth_h, rel=0.2)
    assert res.noise.bias_instability_dph == pytest.approx(truth.gyro.bias_instability_dph,
                                                           rel=0.2)
    assert res.instrument.gyro.arw_deg_per_rth_h == res.noise.arw_deg_per_rth_h
    assert res.instrument.gyro.bias_instability_dph == res.noise.bias_instability_dph
