"""Tests of the single-cycle solvers (nfs.northfind.solve), each with its oracle."""

import math

import numpy as np
import pytest

from nfs.constants import OMEGA_IE_DPH
from nfs.errors import NfsError
from nfs.northfind import solve_heading, tilt_correct, wrap_deg_180, wrap_deg_360


def _rates(psi_deg, theta_deg, lat_deg, bias):
    """Oracle: level-axis Earth-rate projection w_k = Omega_h cos(psi + theta_k) + b."""
    a = np.radians(psi_deg + np.asarray(theta_deg, dtype=float))
    return OMEGA_IE_DPH * math.cos(math.radians(lat_deg)) * np.cos(a) + bias


def test_four_position_closed_form_equals_least_squares():
    # Oracle: docs/physics.md section 5, psi = atan2(w_270 - w_90, w_0 - w_180), exact for
    # arbitrary rates because the 4-position design is orthogonal.
    rng = np.random.default_rng(1)
    for _ in range(200):
        w0, w90, w180, w270 = rng.normal(0.0, 20.0, 4)
        sol = solve_heading([0, 90, 180, 270], [w0, w90, w180, w270])
        closed = math.degrees(math.atan2(w270 - w90, w0 - w180)) % 360.0
        assert abs(wrap_deg_180(sol.psi_deg - closed)) < 1e-10
        assert sol.X_dph == pytest.approx((w0 - w180) / 2, abs=1e-12)
        assert sol.Y_dph == pytest.approx((w270 - w90) / 2, abs=1e-12)
        assert sol.bias_dph == pytest.approx((w0 + w90 + w180 + w270) / 4, abs=1e-12)


@pytest.mark.parametrize("n", [3, 4, 5, 8, 12])
def test_noiseless_rates_give_exact_heading(n):
    # Oracle: the rates are the model itself, so psi, b and Omega_h come back exactly.
    rng = np.random.default_rng(n)
    for _ in range(20):
        psi, lat, b = rng.uniform(0, 360), rng.uniform(0, 70), rng.normal(0, 5)
        theta = rng.uniform(0, 30) + 360.0 * np.arange(n) / n
        sol = solve_heading(theta, _rates(psi, theta, lat, b))
        assert abs(wrap_deg_180(sol.psi_deg - psi)) < 1e-9
        assert sol.bias_dph == pytest.approx(b, abs=1e-10)
        assert sol.horizontal_rate_dph == pytest.approx(
            OMEGA_IE_DPH * math.cos(math.radians(lat)), abs=1e-10)
        assert sol.residual_dph < 1e-10
        assert 0.0 <= sol.psi_deg < 360.0


def test_rotating_the_positions_rotates_the_heading():
    # Oracle (invariant): A_k = psi + theta_k, so adding delta to every theta_k with the same
    # rates means psi - delta.
    rng = np.random.default_rng(3)
    theta = np.array([0.0, 60.0, 150.0, 200.0, 310.0])
    w = rng.normal(0, 10, theta.size)
    base = solve_heading(theta, w).psi_deg
    for delta in (17.0, -123.0, 400.0):
        assert wrap_deg_180(solve_heading(theta + delta, w).psi_deg - (base - delta)) == \
            pytest.approx(0.0, abs=1e-9)


def test_zero_weight_drops_a_position():
    # Oracle (invariant): weight 0 is the same as leaving the rate out.
    theta = np.array([0.0, 72.0, 144.0, 216.0, 288.0])
    w = np.array([3.0, -7.0, 1.0, 11.0, -2.0])
    sol_w = solve_heading(theta, w, weights=[1, 1, 0, 1, 1])
    sol = solve_heading(np.delete(theta, 2), np.delete(w, 2))
    assert sol_w.psi_deg == pytest.approx(sol.psi_deg, abs=1e-10)
    assert sol_w.bias_dph == pytest.approx(sol.bias_dph, abs=1e-10)


def test_cos_elevation_model_is_exact_with_bias():
    # Oracle: rates built as cos e_k (X cos theta - Y sin theta) + b solve exactly with
    # cos_elevation (the bias is not rescaled), and tilt_correct is (w - Omega_v sin e)/cos e.
    rng = np.random.default_rng(4)
    theta = np.array([0.0, 90.0, 180.0, 270.0])
    psi, lat, b = 123.4, 40.0, 7.5
    e = rng.normal(0, 0.01, 4)
    omega_h = OMEGA_IE_DPH * math.cos(math.radians(lat))
    omega_v = OMEGA_IE_DPH * math.sin(math.radians(lat))
    w = omega_h * np.cos(np.radians(psi + theta)) * np.cos(e) + omega_v * np.sin(e) + b
    sol = solve_heading(theta, w - omega_v * np.sin(e), cos_elevation=np.cos(e))
    assert abs(wrap_deg_180(sol.psi_deg - psi)) < 1e-9
    assert sol.bias_dph == pytest.approx(b, abs=1e-10)
    np.testing.assert_allclose(tilt_correct(w, np.sin(e), lat),
                               omega_h * np.cos(np.radians(psi + theta)) + b / np.cos(e),
                               rtol=0, atol=1e-12)
    with pytest.raises(NfsError, match="acc_x_g"):
        tilt_correct([1.0], [1.5], lat)


def test_two_position_method_and_its_sign_ambiguity():
    # Oracle: w_0 - w_180 = 2 Omega_h cos psi, so arccos gives |psi| (mod 360) and the sign
    # comes from the hint (physics of the classic two-position method).
    lat = 30.0
    for psi in (40.0, 320.0, 100.0, 250.0):
        w = _rates(psi, [0, 180], lat, 2.0)
        sol = solve_heading([0, 180], w, latitude_deg=lat)
        assert sol.ambiguous
        assert 0.0 <= sol.psi_deg <= 180.0
        assert sol.psi_deg == pytest.approx(min(psi, 360 - psi), abs=1e-9)
        assert sol.bias_dph == pytest.approx(2.0, abs=1e-12)
        hinted = solve_heading([0, 180], w, latitude_deg=lat, heading_hint_deg=psi + 30)
        assert not hinted.ambiguous
        assert abs(wrap_deg_180(hinted.psi_deg - psi)) < 1e-9
    # the pair may sit anywhere (90, 270) and be visited several times
    w = _rates(200.0, [90, 270, 270, 90], lat, -1.0)
    sol = solve_heading([90, 270, 270, 90], w, latitude_deg=lat, heading_hint_deg=190)
    assert abs(wrap_deg_180(sol.psi_deg - 200.0)) < 1e-9


@pytest.mark.parametrize("theta, kwargs, match", [
    ([0, 0, 0], {}, "cannot determine psi"),
    ([0, 90], {"latitude_deg": 30}, "cannot determine psi"),
    ([0, 180], {}, "latitude_deg"),
    ([10, 10.0000000001, 190], {}, "latitude_deg"),   # coincident angles count once
])
def test_positions_that_cannot_determine_psi_raise(theta, kwargs, match):
    # Oracle: rank of [cos theta, -sin theta, 1] is below 3 for these angles.
    with pytest.raises(NfsError, match=match):
        solve_heading(theta, np.arange(len(theta), dtype=float), **kwargs)


def test_bad_shapes_raise():
    with pytest.raises(NfsError, match="rate_dph has 3"):
        solve_heading([0, 90, 180, 270], [1, 2, 3])
    with pytest.raises(NfsError, match="weights"):
        solve_heading([0, 90, 180, 270], [1, 2, 3, 4], weights=[1, 1])


def test_wrapping():
    # Oracle: definitions, [-180, 180) and [0, 360).
    np.testing.assert_array_equal(wrap_deg_180([180.0, -180.0, 540.0, 179.5, -0.5]),
                                  [-180.0, -180.0, -180.0, 179.5, -0.5])
    assert wrap_deg_360(-1e-17) == 0.0
    assert wrap_deg_360(-90.0) == 270.0
    assert wrap_deg_360(720.5) == pytest.approx(0.5)
