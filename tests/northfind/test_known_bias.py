"""North finding with known biases: closed forms on ideal runs, every schedule down to one
position (nfs.northfind.known_bias)."""

import dataclasses

import numpy as np
import pytest

from nfs.errors import NfsError
from nfs.northfind import north_find, synthetic_run
from nfs.northfind.known_bias import north_find_known_bias
from nfs.northfind.level import gravity_and_biases

HEADING = 212.7
LAT = 34.0
BIAS = 0.37          # deg/h
BX, BY = 2.0e-4, -1.5e-4   # g


def _run(tilt=(1.5, -2.0)):
    run = synthetic_run(heading_deg=HEADING, latitude_deg=LAT, n_cycles=3, bias_dph=BIAS,
                        tilt_north_deg=tilt[0], tilt_east_deg=tilt[1])
    cols = dict(run.columns)
    cols["acc_x_g"] = np.asarray(cols["acc_x_g"]) + BX
    cols["acc_y_g"] = np.asarray(cols["acc_y_g"]) + BY
    return dataclasses.replace(run, columns=cols)


@pytest.mark.parametrize("positions", [None, (0.0, 90.0), (90.0, 180.0), (0.0,), (270.0,),
                                       (0.0, 180.0)])
def test_noiseless_heading_with_the_true_biases_to_1e9_deg(positions):
    run = _run()
    nf = north_find(run)
    out = north_find_known_bias(nf, positions_deg=positions, gyro_bias_dph=BIAS,
                                acc_x_bias_g=BX, acc_y_bias_g=BY, heading_hint_deg=200.0)
    assert np.max(np.abs(out.error_deg)) < 1e-9
    assert not out.ambiguous


def test_one_position_without_a_hint_is_flagged_ambiguous():
    run = _run()
    out = north_find_known_bias(north_find(run), positions_deg=(0.0,), gyro_bias_dph=BIAS,
                                acc_x_bias_g=BX, acc_y_bias_g=BY)
    assert out.ambiguous


def test_a_bias_error_moves_a_one_position_heading_by_db_over_omega_h_sin():
    """d psi = -db / (Omega_h sin(psi + theta)) rad on a level table, one position at 0."""
    run = _run(tilt=(0.0, 0.0))
    nf = north_find(run)
    db = 0.01
    out = north_find_known_bias(nf, positions_deg=(0.0,), gyro_bias_dph=BIAS + db,
                                acc_x_bias_g=BX, acc_y_bias_g=BY, heading_hint_deg=200.0)
    omega_h = 15.041067 * np.cos(np.radians(LAT))
    want = np.degrees(db / (omega_h * np.sin(np.radians(HEADING))))
    np.testing.assert_allclose(out.error_deg, want, rtol=2e-3)


def test_a_four_position_cycle_is_insensitive_to_a_wrong_constant_bias_no_more_than_2_positions():
    run = _run()
    nf = north_find(run)
    full = north_find_known_bias(nf, gyro_bias_dph=BIAS + 0.01, acc_x_bias_g=BX,
                                 acc_y_bias_g=BY)
    two = north_find_known_bias(nf, positions_deg=(0.0, 90.0), gyro_bias_dph=BIAS + 0.01,
                                acc_x_bias_g=BX, acc_y_bias_g=BY)
    assert np.max(np.abs(full.error_deg)) < 1e-9          # the bias cancels over 0..270
    assert np.min(np.abs(two.error_deg)) > 1e-2           # and not over 0, 90


def test_the_accelerometer_biases_come_back_from_a_four_position_cycle():
    run = _run()
    nf = north_find(run)
    np.testing.assert_allclose(nf.acc_bias_g[:, 0], BX, atol=1e-12)
    np.testing.assert_allclose(nf.acc_bias_g[:, 1], BY, atol=1e-12)
    _, bx, by = gravity_and_biases(np.radians(nf.theta_deg), nf.acc_x_g, nf.acc_y_g)
    np.testing.assert_array_equal(bx, nf.acc_bias_g[:, 0])


def test_positions_not_in_the_schedule_are_refused():
    run = _run()
    with pytest.raises(NfsError, match="45"):
        north_find_known_bias(north_find(run), positions_deg=(45.0,))
