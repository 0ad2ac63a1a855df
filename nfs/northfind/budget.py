"""Heading error budget of multiposition north finding (physics.md section 5).

Closed forms that the tests hold the solver to, and that reports quote as the floor.
Angles in deg at the boundary; each formula is first order in the error source.
"""

from __future__ import annotations

import math

import numpy as np

from nfs.errors import NfsError
from nfs.northfind.solve import _omega_h

__all__ = [
    "white_noise_floor_deg",
    "rate_error_heading_deg",
    "linear_drift_error_deg",
    "east_tilt_error_deg",
]


def white_noise_floor_deg(arw_deg_per_rth_h: float, dwell_s: float, n_positions: int,
                          latitude_deg: float) -> float:
    """Standard deviation of psi from white rate noise (physics.md section 5).

        sigma_psi = sqrt(2 / N) (ARW / sqrt(tau)) / (Omega_ie cos L)   [rad]

    ARW / sqrt(tau) is the standard deviation of the mean rate over one dwell; least squares
    over N equally spaced positions gives var(X) = var(Y) = 2 sigma_w^2 / N, and
    sigma_psi = sigma_X / Omega_h.

    Parameters
    ----------
    arw_deg_per_rth_h : float
        Angle random walk N [deg/sqrt(h)].
    dwell_s : float
        Time tau averaged at each position [s].
    n_positions : int
        Number of positions N per cycle (equally spaced over 360 deg).
    latitude_deg : float
        Latitude L [deg].

    Returns
    -------
    float
        sigma_psi [deg].
    """
    if dwell_s <= 0 or n_positions < 3:
        raise NfsError("white_noise_floor_deg needs dwell_s > 0 and n_positions >= 3")
    tau_h = dwell_s / 3600.0
    sigma_w = arw_deg_per_rth_h / math.sqrt(tau_h)
    return math.degrees(math.sqrt(2.0 / n_positions) * sigma_w / _omega_h(latitude_deg))


def rate_error_heading_deg(rate_error_dph: float, latitude_deg: float) -> float:
    """Heading error of an uncancelled rate error: delta_psi = delta_b / (Omega_ie cos L) [deg]."""
    return math.degrees(rate_error_dph / _omega_h(latitude_deg))


def linear_drift_error_deg(drift_dph_per_s: float, step_s: float, n_positions: int,
                           heading_deg, latitude_deg: float):
    """Heading error of a linear drift with sequential positions (physics.md section 5).

        delta_psi = (k Delta / Omega_h) (cot(pi / N) cos psi + sin psi)   [rad]

    Assumes N >= 3 positions theta_j = 360 j / N visited in increasing order, one dwell each,
    the mean rate of dwell j taken at times t_0 + j Delta (equal dwells, equal moves), a
    drift b(t) = b_0 + k t, no tilt, and k Delta << Omega_h. Derivation: least squares over
    equally spaced angles is X = (2/N) sum w_j cos theta_j, Y = -(2/N) sum w_j sin theta_j;
    with sum_j j exp(i theta_j) = -N/2 - i (N/2) cot(pi/N) the drift adds dX = -k Delta and
    dY = k Delta cot(pi/N), and to first order delta_psi = (cos psi dY - sin psi dX) / Omega_h.
    The exact error is atan2(Omega_h sin psi + dY, Omega_h cos psi + dX) - psi.

    Parameters
    ----------
    drift_dph_per_s : float
        Drift slope k [deg/h per s].
    step_s : float
        Time Delta between the centres of consecutive dwells (dwell + move) [s].
    n_positions : int
        N.
    heading_deg : float or array_like
        True heading psi [deg].
    latitude_deg : float
        Latitude L [deg].

    Returns
    -------
    float or numpy.ndarray
        delta_psi = estimated - true heading [deg].
    """
    if n_positions < 3:
        raise NfsError("linear_drift_error_deg needs n_positions >= 3")
    psi = np.radians(heading_deg)
    k_delta = drift_dph_per_s * step_s
    out = np.degrees(k_delta / _omega_h(latitude_deg)
                     * (np.cos(psi) / math.tan(math.pi / n_positions) + np.sin(psi)))
    return out if np.ndim(out) else float(out)


def east_tilt_error_deg(tilt_east_deg: float, latitude_deg: float) -> float:
    """Heading error of an uncorrected east-west tilt: delta_psi = -alpha_E tan L [deg].

    physics.md section 4 gives the size, alpha_E tan L. Sign: with e_k = alpha_N cos A_k +
    alpha_E sin A_k, alpha_E > 0 lifts the x axis when it points east (east side of the
    turntable high). The vertical Earth rate then adds Omega_v alpha_E sin A_k to w_k, which
    turns the fitted cosine by -alpha_E Omega_v / Omega_h: the estimated heading is too small,
    delta_psi = estimated - true = -alpha_E tan L. First order in alpha_E; alpha_N only
    rescales Omega_h.
    """
    return -tilt_east_deg * math.tan(math.radians(latitude_deg))
