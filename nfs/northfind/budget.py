"""Heading error budget of multiposition north finding (docs/physics.md section 5).

Closed forms that the tests hold the solver to, and that reports quote as the floor.
Angles in deg at the boundary; each formula is first order in the error source.
"""

from __future__ import annotations

import math

import numpy as np

from nfs.errors import NfsError
from nfs.northfind.solve import horizontal_earth_rate_dph

__all__ = [
    "white_noise_floor_deg",
    "rate_error_heading_deg",
    "linear_drift_error_deg",
    "east_tilt_error_deg",
    "indexing_error_deg",
    "tilt_model_error_deg",
]


def white_noise_floor_deg(arw_deg_per_rth_h: float, dwell_s: float, n_positions: int,
                          latitude_deg: float, *, heading_deg: float | None = None,
                          first_position_deg: float = 0.0, visits: int = 1) -> float:
    """Standard deviation of psi from white rate noise (docs/physics.md section 5).

    N >= 3 positions equally spaced over 360 deg:

        sigma_psi = sqrt(2 / (N v)) (ARW / sqrt(tau)) / (Omega_ie cos L)   [rad]

    ARW / sqrt(tau) = sigma_w is the standard deviation of the mean rate over one dwell;
    least squares over the N v dwells of a cycle gives var(X) = var(Y) = 2 sigma_w^2 / (N v),
    and sigma_psi = sigma_X / Omega_h.

    N = 2 (angles theta_a and theta_a + 180 deg, the two-position method):

        ``sigma_psi = (ARW / sqrt(tau)) / (sqrt(2 v) Omega_ie cos L |sin(psi + theta_a)|)``   [rad]

    Derivation: u = Omega_h cos(psi + theta_a) is half the difference of the two angles'
    mean rates, var(u) = sigma_w^2 / (2 v); psi + theta_a = arccos(u / Omega_h), so
    d psi = -du / (Omega_h sin(psi + theta_a)).  Assumptions: Omega_h = Omega_ie cos L is
    known (the latitude) and not fitted, the bias is constant over the cycle, the right
    branch is chosen (a heading hint), and first order in the noise, i.e. sigma_w <<
    ``Omega_h |sin(psi + theta_a)|``: near the axis pointing north or south at theta_a the
    arccos flattens, the floor grows without bound (inf at sin = 0) and the formula stops
    describing the scatter.  It depends on the heading, which N >= 3 does not.

    Parameters
    ----------
    arw_deg_per_rth_h : float
        Angle random walk N [deg/sqrt(h)].
    dwell_s : float
        Time tau averaged at each position [s].
    n_positions : int
        Number N of distinct positions per cycle (equally spaced over 360 deg; 2: 180 deg
        apart).
    latitude_deg : float
        Latitude L [deg].
    heading_deg : float, optional
        psi [deg]; needed for N = 2.
    first_position_deg : float
        theta_a, the first of the two positions of N = 2 [deg].
    visits : int
        v, dwells at each position per cycle (2 for a forward-then-reverse order).

    Returns
    -------
    float
        sigma_psi [deg].
    """
    if not dwell_s > 0 or n_positions < 2 or visits < 1:
        raise NfsError(f"white_noise_floor_deg needs dwell_s > 0, n_positions >= 2 and "
                       f"visits >= 1, got {dwell_s:g}, {n_positions}, {visits}")
    tau_h = dwell_s / 3600.0
    sigma_w = arw_deg_per_rth_h / math.sqrt(tau_h)
    omega_h = horizontal_earth_rate_dph(latitude_deg)
    if n_positions >= 3:
        return math.degrees(math.sqrt(2.0 / (n_positions * visits)) * sigma_w / omega_h)
    if heading_deg is None:
        raise NfsError("white_noise_floor_deg: the two-position floor depends on the heading; "
                       "pass heading_deg")
    s = abs(math.sin(math.radians(heading_deg + first_position_deg)))
    if s == 0.0:
        return math.inf
    return math.degrees(sigma_w / (math.sqrt(2.0 * visits) * omega_h * s))


def indexing_error_deg(offsets_deg, heading_deg: float, positions_deg) -> float:
    """Heading error of turntable indexing offsets: (2/N) sum_k d_k sin^2(psi + theta_k) [deg].

    First order in the offsets d_k [deg] of N >= 3 equally spaced positions theta_k [deg]
    (derivation in :func:`nfs.effects.geometry.indexing_error`); estimated - true heading.
    """
    d = np.asarray(offsets_deg, dtype=float)
    th = np.asarray(positions_deg, dtype=float)
    if d.shape != th.shape or th.size < 3:
        raise NfsError("indexing_error_deg needs one offset per position and >= 3 positions")
    return float(2.0 / th.size * np.sum(d * np.sin(np.radians(heading_deg + th)) ** 2))


def tilt_model_error_deg(pitch_deg: float, roll_deg: float, heading_deg,
                         n_positions: int):
    """Heading of a first-order-tilt run minus that of an exactly tilted one [deg].

    docs/physics.md section 4's model keeps the azimuth of the x axis at psi + theta_k and
    raises it by e_k = alpha_N cos A_k + alpha_E sin A_k; an exactly tilted table
    (:func:`nfs.effects.geometry.tilt_matrix`, pitch p = alpha_N, roll r = alpha_E [rad])
    turns the horizontal projection of the axis at in-plane angle beta to
    beta + g(beta), with, to second order in the tilt,

        g(beta) = ((p^2 - r^2) sin 2 beta + 2 p r (1 - cos 2 beta)) / 4.

    Levelled exactly (which returns an exactly tilted table's heading to rounding), the
    first-order run looks like an exact table whose positions are off by
    -(g(psi + theta_k) - g(psi)), and by the indexing formula
    (:func:`indexing_error_deg`) its heading is off by

        N = 4:        ((p^2 - r^2) sin 2 psi - 2 p r cos 2 psi) cos^2 psi / 2
        N >= 3, != 4: ((p^2 - r^2) sin 2 psi - 2 p r cos 2 psi - p r) / 4       [rad]

    (the fourth harmonic aliases into the fit for N = 4).  Independent of the latitude;
    the remainder is third order (relative ~ the tilt in rad).  At p = 2 deg, r = 1 deg,
    psi = 212.7 deg, N = 4: 6.6e-3 deg.  Derived here (no published figure).

    Parameters
    ----------
    pitch_deg, roll_deg : float
        Tilt alpha_N (pitch) and alpha_E (roll) [deg].
    heading_deg : float or array_like
        psi [deg].
    n_positions : int
        N >= 3 equally spaced positions.

    Returns
    -------
    float or numpy.ndarray
        First-order-run heading minus exact-run heading (= true heading) [deg].
    """
    if n_positions < 3:
        raise NfsError("tilt_model_error_deg needs n_positions >= 3")
    p, r = math.radians(pitch_deg), math.radians(roll_deg)
    psi = np.radians(heading_deg)
    core = (p * p - r * r) * np.sin(2 * psi) - 2 * p * r * np.cos(2 * psi)
    out = core * np.cos(psi) ** 2 / 2 if n_positions == 4 else (core - p * r) / 4
    out = np.degrees(out)
    return out if np.ndim(out) else float(out)


def rate_error_heading_deg(rate_error_dph: float, latitude_deg: float) -> float:
    """Heading error of an uncancelled rate error: delta_psi = delta_b / (Omega_ie cos L) [deg]."""
    return math.degrees(rate_error_dph / horizontal_earth_rate_dph(latitude_deg))


def linear_drift_error_deg(drift_dph_per_s: float, step_s: float, n_positions: int,
                           heading_deg, latitude_deg: float):
    """Heading error of a linear drift with sequential positions (docs/physics.md section 5).

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
    out = np.degrees(k_delta / horizontal_earth_rate_dph(latitude_deg)
                     * (np.cos(psi) / math.tan(math.pi / n_positions) + np.sin(psi)))
    return out if np.ndim(out) else float(out)


def east_tilt_error_deg(tilt_east_deg: float, latitude_deg: float) -> float:
    """Heading error of an uncorrected east-west tilt: delta_psi = -alpha_E tan L [deg].

    docs/physics.md section 4 gives the size, alpha_E tan L. Sign: with e_k = alpha_N cos A_k +
    alpha_E sin A_k, alpha_E > 0 lifts the x axis when it points east (east side of the
    turntable high). The vertical Earth rate then adds Omega_v alpha_E sin A_k to w_k, which
    turns the fitted cosine by -alpha_E Omega_v / Omega_h: the estimated heading is too small,
    delta_psi = estimated - true = -alpha_E tan L. First order in alpha_E; alpha_N only
    rescales Omega_h.
    """
    return -tilt_east_deg * math.tan(math.radians(latitude_deg))
