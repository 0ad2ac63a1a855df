"""Tests of the error-budget closed forms (nfs.northfind.budget) not covered elsewhere.

white_noise_floor_deg, linear_drift_error_deg and east_tilt_error_deg are held to simulated
runs in test_north_find.py; this file checks the remaining formula and the figures that
docs/physics.md section 5 quotes.
"""

import math

import numpy as np
import pytest

from nfs.constants import OMEGA_IE_DPH
from nfs.errors import NfsError
from nfs.northfind import rate_error_heading_deg, solve_heading, white_noise_floor_deg


def test_rate_error_figure_quoted_by_physics_md():
    # Oracle: docs/physics.md section 5, "0.001 deg/h is about 0.0044 deg at L = 30 deg".
    assert rate_error_heading_deg(0.001, 30.0) == pytest.approx(0.0044, abs=5e-5)


@pytest.mark.parametrize("psi", [0.0, 75.0, 250.0])
def test_rate_error_in_quadrature_turns_the_heading_by_delta_over_omega_h(psi):
    # Oracle: a rate error delta sin(A_k) (in quadrature with the Earth-rate cosine) gives
    # Omega_h cos A + delta sin A = R cos(A - delta / Omega_h): the heading moves by
    # -delta / Omega_h, first order (delta = 0.01 deg/h here, remainder ~ 1e-6 relative).
    lat, delta = 30.0, 0.01
    theta = np.array([0.0, 90.0, 180.0, 270.0])
    a = np.radians(psi + theta)
    w = OMEGA_IE_DPH * math.cos(math.radians(lat)) * np.cos(a) + delta * np.sin(a)
    err = solve_heading(theta, w).psi_deg - psi
    err = (err + 180.0) % 360.0 - 180.0
    assert err == pytest.approx(-rate_error_heading_deg(delta, lat), rel=1e-5)


def test_floor_rejects_what_it_cannot_describe():
    with pytest.raises(NfsError, match="depends on the heading"):
        white_noise_floor_deg(0.0005, 150.0, 2, 30.0)   # two positions need the heading
    with pytest.raises(NfsError, match="dwell_s > 0"):
        white_noise_floor_deg(0.0005, 0.0, 4, 30.0)
    with pytest.raises(NfsError, match="horizontal Earth rate"):
        rate_error_heading_deg(0.001, 90.0)
