"""Turntable schedule, tilt geometry, Earth-rate projection and thermometer model."""

import numpy as np
import pytest

from nfs.constants import OMEGA_IE_DPH
from nfs.errors import NfsError
from nfs.sensors import (Schedule, ThermometerModel, axis_elevation_deg,
                         earth_rate_along_axis_dph, quantize, thermometer_reading,
                         turntable_motion)


def test_sequential_schedule():
    s = Schedule((0.0, 90.0, 180.0, 270.0), dwell_s=150.0, move_s=10.0)
    t = np.arange(0.0, 2 * s.cycle_s)
    theta, moving = turntable_motion(s, t)
    assert s.cycle_s == 640.0
    # Oracle: by construction, dwell k occupies [160 k, 160 k + 150).
    for k in range(8):
        sl = slice(160 * k, 160 * k + 150)
        assert not moving[sl].any()
        np.testing.assert_array_equal(theta[sl], [0, 90, 180, 270][k % 4])
        assert moving[160 * k + 150: 160 * k + 160].all()
    # the move 0 -> 90 passes through 45 at its middle
    assert theta[155] == pytest.approx(45.0)


def test_forward_reverse_schedule():
    s = Schedule((0.0, 90.0, 180.0, 270.0), dwell_s=100.0, move_s=5.0, order="forward-reverse")
    assert s.cycle_positions_deg == (0, 90, 180, 270, 270, 180, 90, 0)
    t = np.arange(0.0, s.cycle_s)
    theta, moving = turntable_motion(s, t)
    centres = [theta[int(105 * k + 50)] for k in range(8)]
    assert centres == [0, 90, 180, 270, 270, 180, 90, 0]
    # between two dwells at 270 the table holds still but the flag is set (settling)
    np.testing.assert_array_equal(theta[3 * 105 + 100: 4 * 105], 270.0)
    assert moving[3 * 105 + 100: 4 * 105].all()


@pytest.mark.parametrize("kw, msg", [
    (dict(positions_deg=()), "empty"),
    (dict(order="zigzag"), "zigzag"),
    (dict(dwell_s=0.0), "dwell_s"),
])
def test_schedule_errors(kw, msg):
    base = dict(positions_deg=(0.0, 180.0), dwell_s=10.0, move_s=1.0)
    base.update(kw)
    with pytest.raises(NfsError, match=msg):
        Schedule(**base)


def test_earth_rate_projection():
    # Oracle: docs/physics.md section 5; north level axis reads Omega cos L, east reads 0.
    lat = 30.0
    w = earth_rate_along_axis_dph(np.array([0.0, 90.0, 180.0]), np.zeros(3), lat)
    np.testing.assert_allclose(w, OMEGA_IE_DPH * np.cos(np.radians(lat)) * np.array([1, 0, -1]),
                               atol=1e-12)
    # an axis pointing straight up reads Omega sin L
    assert earth_rate_along_axis_dph(0.0, 90.0, lat) == pytest.approx(
        OMEGA_IE_DPH * np.sin(np.radians(lat)))


def test_tilt_geometry():
    assert axis_elevation_deg(0.0, 0.1, 0.05) == pytest.approx(0.1)
    assert axis_elevation_deg(90.0, 0.1, 0.05) == pytest.approx(0.05)
    assert axis_elevation_deg(180.0, 0.1, 0.05) == pytest.approx(-0.1)


def test_thermometer_model():
    m = ThermometerModel(nodes={"a": 1.0, "b": 3.0}, lag_s=0.0, offset_c=0.5, noise_c=0.0,
                         quantum_c=0.25)
    temp = np.array([[10.0, 20.0], [12.0, 22.0]])
    sensed = m.sensed(temp, ("a", "b"))
    np.testing.assert_allclose(sensed, [17.5, 19.5])
    r = thermometer_reading(sensed, np.array([0.0, 1.0]), m, np.random.default_rng(0))
    np.testing.assert_allclose(r, [18.0, 20.0])
    assert quantize(np.array([0.03, 0.07]), 0.0625).tolist() == [0.0, 0.0625]
