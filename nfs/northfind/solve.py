"""Multiposition heading solvers (docs/physics.md section 5).

Symbols (docs/physics.md section 5):

- ``psi``: azimuth of the gyro's sensitive axis x at turntable angle theta = 0 [deg],
  clockwise from north;
- ``theta_k``: turntable angle of position k [deg]; the axis azimuth is A_k = psi + theta_k;
- ``e_k``: elevation of the x axis at position k; the x accelerometer reads f_x = sin e_k;
- ``Omega_ie``: the Earth's rotation rate, ``Omega_h = Omega_ie cos L`` its horizontal and
  ``Omega_v = Omega_ie sin L`` its vertical component at latitude L;
- ``X = Omega_h cos psi``, ``Y = Omega_h sin psi``, ``b`` the gyro bias [deg/h].

The mean rate over the dwell at position k is modelled as

    w_k = Omega_h cos A_k cos e_k + Omega_v sin e_k + b
        = cos e_k (X cos theta_k - Y sin theta_k) + Omega_v sin e_k + b,

which is linear in (X, Y, b). Inside this module angles are in rad; the public functions
take and return deg, except :func:`solve_xyb_stack` and :func:`distinct_angles`, shared with
the run's north finding (:mod:`nfs.northfind.heading`), which take rad as their names say.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nfs.constants import earth_rate_components_dph
from nfs.errors import NfsError

__all__ = [
    "HeadingSolution",
    "solve_heading",
    "tilt_correct",
    "wrap_deg_360",
    "wrap_deg_180",
    "distinct_angles",
    "horizontal_earth_rate_dph",
    "remove_vertical_rate",
    "solve_xyb_stack",
]

#: Two turntable angles closer than this [deg] (modulo 360) count as the same position.
ANGLE_TOL_DEG = 1e-6

#: Smallest ratio of singular values of the design matrix accepted by the solver.
_RCOND = 1e-9


def wrap_deg_360(angle_deg):
    """Wrap angles to [0, 360) [deg]."""
    out = np.mod(np.asarray(angle_deg, dtype=float), 360.0)
    out = np.where(out >= 360.0, 0.0, out)  # np.mod(-1e-17, 360.0) == 360.0
    return out if np.ndim(out) else float(out)


def wrap_deg_180(angle_deg):
    """Wrap angles to [-180, 180) [deg]."""
    out = np.mod(np.asarray(angle_deg, dtype=float) + 180.0, 360.0) - 180.0
    out = np.where(out >= 180.0, -180.0, out)
    return out if np.ndim(out) else float(out)


def horizontal_earth_rate_dph(latitude_deg: float) -> float:
    """Omega_h = Omega_ie cos L [deg/h], the horizontal Earth rate at latitude L [deg] that
    every heading solver divides by; NfsError at a pole, where psi is undefined."""
    omega_h, _ = earth_rate_components_dph(latitude_deg)
    if not omega_h > 1e-9:
        raise NfsError(f"no horizontal Earth rate at latitude {latitude_deg} deg: "
                       "the heading is undefined")
    return omega_h


def remove_vertical_rate(rate_dph, acc_x_g, latitude_deg: float):
    """The mean rates w_k [deg/h] without the vertical Earth rate that an axis lifted by e_k
    sees, and cos e_k [1]: (w_k - Omega_ie sin L sin e_k, cos e_k), sin e_k = f_x,k, from the
    x accelerometer's mean f_x,k [g] and the latitude L [deg] (NaN passes through).

    The first step of :func:`tilt_correct`; the run's north finding stops here and levels
    with both accelerometers (:mod:`nfs.northfind.level`).  NfsError when |f_x,k| > 1 g.
    """
    sin_e = np.asarray(acc_x_g, dtype=float)
    if np.any(np.abs(sin_e) > 1.0):
        raise NfsError(f"|acc_x_g| must not exceed 1 g to give an elevation; got "
                       f"{np.nanmax(np.abs(sin_e)):.6g} g")
    _, omega_v = earth_rate_components_dph(latitude_deg)
    return np.asarray(rate_dph, dtype=float) - omega_v * sin_e, np.sqrt(1.0 - sin_e * sin_e)


def tilt_correct(rate_dph, acc_x_g, latitude_deg: float):
    """Tilt-correct the mean rate of each position (docs/physics.md sections 4 and 5).

        w_k' = (w_k - Omega_ie sin L sin e_k) / cos e_k,   sin e_k = f_x,k

    removes the vertical Earth rate seen by an axis lifted by e_k and rescales the
    horizontal part to a level axis.

    Parameters
    ----------
    rate_dph : array_like
        Mean gyro rate w_k of each position [deg/h].
    acc_x_g : array_like
        Mean x accelerometer reading f_x,k = sin e_k over the same dwells [g].
    latitude_deg : float
        Latitude L [deg].

    Returns
    -------
    numpy.ndarray
        w_k' [deg/h]. A gyro bias b becomes b / cos e_k here (the first-order tilt model
        of :func:`solve_heading`); :func:`north_find` levels exactly with both
        accelerometers instead (:mod:`nfs.northfind.level`).
    """
    rate_v, cos_e = remove_vertical_rate(rate_dph, acc_x_g, latitude_deg)
    return rate_v / cos_e


@dataclass(frozen=True)
class HeadingSolution:
    """Result of :func:`solve_heading` for one north-finding cycle."""

    psi_deg: float
    """Heading psi: azimuth of the x axis at theta = 0, clockwise from north, in [0, 360) [deg]."""
    X_dph: float
    """X = Omega_h cos psi, the north component of the horizontal Earth rate [deg/h]."""
    Y_dph: float
    """Y = Omega_h sin psi [deg/h]."""
    bias_dph: float
    """Gyro bias b over the cycle [deg/h]."""
    horizontal_rate_dph: float
    """Horizontal Earth rate sqrt(X^2 + Y^2) as fitted (assumed Omega_ie cos L for two
    positions) [deg/h]."""
    residual_dph: float
    """Root mean square of the fit residuals over the positions [deg/h] (0 when the
    positions leave no degree of freedom)."""
    n_positions: int
    """Number of rates given."""
    ambiguous: bool = False
    """True for a two-position solution whose sign of (psi + theta_a) was not resolved by a
    heading hint; psi is then the branch with sin(psi + theta_a) >= 0."""


def distinct_angles(theta_rad: np.ndarray, tol_rad: float) -> np.ndarray:
    """Distinct angles (modulo 2 pi) of a 1-D array, as a sorted array in [0, 2 pi)."""
    t = np.sort(np.mod(theta_rad, 2.0 * np.pi))
    keep = np.concatenate(([True], np.diff(t) > tol_rad))
    out = t[keep]
    if len(out) > 1 and (out[0] + 2.0 * np.pi - out[-1]) <= tol_rad:
        out = out[:-1]
    return out


def solve_xyb_stack(theta_rad, rate_dph, cos_e=None, weights=None):
    """Least squares of w_k = cos e_k (X cos theta_k - Y sin theta_k) + b for a stack of
    cycles, all solved in one batched SVD (the linear model of this module's docstring).

    Parameters
    ----------
    theta_rad : array_like
        Turntable angles theta_k [rad] (rad, unlike the public functions in deg: the caller
        has them in rad already), (n_cycles, n_positions).
    rate_dph : array_like
        Mean rates w_k [deg/h] with the vertical Earth rate removed
        (:func:`remove_vertical_rate`), same shape.
    cos_e : array_like, optional
        cos e_k [1], same shape (None: level, 1 everywhere).
    weights : array_like, optional
        Non-negative weights of the positions [1], same shape or (n_positions,).

    Returns
    -------
    tuple of numpy.ndarray
        X, Y, b and the residual RMS [deg/h], each (n_cycles,).  NfsError when a cycle's
        design [cos theta, -sin theta, 1] is rank deficient.
    """
    theta_rad = np.asarray(theta_rad, dtype=float)
    rate = np.asarray(rate_dph, dtype=float)
    c = np.ones_like(theta_rad) if cos_e is None else np.asarray(cos_e, dtype=float)
    design = np.stack([c * np.cos(theta_rad), -c * np.sin(theta_rad),
                       np.ones_like(theta_rad)], axis=-1)
    if weights is None:
        sw = np.ones_like(theta_rad)
    else:
        w = np.broadcast_to(np.asarray(weights, dtype=float), theta_rad.shape)
        if np.any(~np.isfinite(w)) or np.any(w < 0):
            raise NfsError("weights must be finite and non-negative")
        sw = np.sqrt(w)
    a = design * sw[..., None]
    y = rate * sw
    u, s, vt = np.linalg.svd(a, full_matrices=False)
    if np.any(s[..., -1] <= _RCOND * s[..., 0]):
        raise NfsError("the positions cannot determine psi: the design [cos theta, -sin theta, 1] "
                       "is rank deficient (need at least 3 distinct angles with non-zero weight)")
    coef = np.einsum("...ji,...j->...i", u, y) / s
    coef = np.einsum("...ij,...i->...j", vt, coef)
    resid = y - np.einsum("...ij,...j->...i", a, coef)
    rms = np.sqrt(np.mean(resid * resid, axis=-1))
    return coef[..., 0], coef[..., 1], coef[..., 2], rms


def _solve_two_position(theta_a, theta_rad, rate, cos_e, weights, latitude_deg,
                        heading_hint_deg):
    """Classic two-position method: angles theta_a and theta_a + 180 deg only.

    With s_k = +1 at theta_a and -1 at theta_a + 180, w_k = cos e_k s_k u + b where
    u = Omega_h cos(psi + theta_a): least squares in (u, b), then
    psi + theta_a = +-arccos(u / Omega_h).
    """
    if latitude_deg is None:
        raise NfsError("two positions 180 deg apart observe only Omega_h cos(psi + theta_a): "
                       "pass latitude_deg (for the known Omega_h) or use at least 3 distinct "
                       "positions")
    omega_h = horizontal_earth_rate_dph(latitude_deg)
    sgn = np.where(np.abs(np.angle(np.exp(1j * (theta_rad - theta_a)))) < np.pi / 2, 1.0, -1.0)
    c = np.ones_like(theta_rad) if cos_e is None else cos_e
    sw = np.ones_like(theta_rad) if weights is None else np.sqrt(np.asarray(weights, float))
    a = np.stack([c * sgn, np.ones_like(theta_rad)], axis=-1) * sw[:, None]
    coef, *_ = np.linalg.lstsq(a, rate * sw, rcond=None)
    u, b = coef
    resid = rate * sw - a @ coef
    phi = math.acos(min(1.0, max(-1.0, u / omega_h)))  # psi + theta_a, branch [0, pi]
    ambiguous = True
    if heading_hint_deg is not None:
        hint = math.radians(heading_hint_deg)
        cands = [phi - theta_a, -phi - theta_a]
        psi = min(cands, key=lambda p: abs(math.remainder(p - hint, 2.0 * math.pi)))
        ambiguous = False
    else:
        psi = phi - theta_a
    return psi, omega_h, b, float(np.sqrt(np.mean(resid * resid))), ambiguous


def solve_heading(theta_deg, rate_dph, *, weights=None, cos_elevation=None,
                  latitude_deg: float | None = None, heading_hint_deg: float | None = None,
                  angle_tol_deg: float = ANGLE_TOL_DEG) -> HeadingSolution:
    """Heading psi from the mean rates of one multiposition cycle (docs/physics.md section 5).

    Least squares of ``w_k = c_k (X cos theta_k - Y sin theta_k) + b`` with c_k = cos e_k
    (1 when ``cos_elevation`` is None, i.e. rates already tilt-corrected or a level axis);
    psi = atan2(Y, X). For four positions 0, 90, 180, 270 this is the closed form
    psi = atan2(w_270 - w_90, w_0 - w_180).

    Two positions: when every angle is theta_a or theta_a + 180 deg, only
    u = Omega_h cos(psi + theta_a) is observable (together with b). Given ``latitude_deg``
    the classic two-position method returns psi = +-arccos(u / Omega_h) - theta_a, with the
    known Omega_h = Omega_ie cos L. The sign is not observable from these rates: the branch
    nearest ``heading_hint_deg`` is returned (e.g. from a magnetic compass or a previous
    fix); without a hint the branch with sin(psi + theta_a) >= 0 is returned and the
    solution is marked ``ambiguous``. A second pair of positions 90 deg away (0, 90, 180,
    270) removes the ambiguity and the need for the latitude.

    Parameters
    ----------
    theta_deg : array_like
        Turntable angle theta_k of each rate [deg].
    rate_dph : array_like
        Mean gyro rate w_k at each position [deg/h] (tilt-corrected, or with the vertical
        Earth rate removed when ``cos_elevation`` is given).
    weights : array_like, optional
        Non-negative weight of each rate (e.g. 1 / variance); equal weights by default.
    cos_elevation : array_like, optional
        cos e_k of the x axis at each position; scales the Earth-rate regressors but not
        the bias.
    latitude_deg : float, optional
        Latitude L [deg]; needed only by the two-position method.
    heading_hint_deg : float, optional
        Approximate psi [deg] that picks the two-position branch.
    angle_tol_deg : float
        Angles closer than this (modulo 360) count as one position, and two positions this
        close to 180 deg apart as a two-position pair [deg].

    Returns
    -------
    HeadingSolution

    Raises
    ------
    NfsError
        When the positions cannot determine psi (one angle, two angles not 180 deg apart,
        two positions without ``latitude_deg``, nearly coincident angles), or the arrays
        do not match.
    """
    theta = np.radians(np.asarray(theta_deg, dtype=float)).ravel()
    rate = np.asarray(rate_dph, dtype=float).ravel()
    if theta.shape != rate.shape:
        raise NfsError(f"theta_deg has {theta.size} values but rate_dph has {rate.size}")
    c = None if cos_elevation is None else np.asarray(cos_elevation, dtype=float).ravel()
    if c is not None and c.shape != theta.shape:
        raise NfsError(f"cos_elevation has {c.size} values, expected {theta.size}")
    w = None if weights is None else np.asarray(weights, dtype=float).ravel()
    if w is not None and w.shape != theta.shape:
        raise NfsError(f"weights has {w.size} values, expected {theta.size}")
    if not (np.all(np.isfinite(theta)) and np.all(np.isfinite(rate))):
        raise NfsError("theta_deg and rate_dph must be finite")
    used = theta if w is None else theta[w > 0]
    distinct = distinct_angles(used, math.radians(angle_tol_deg))
    n = theta.size
    if len(distinct) >= 3:
        x, y, b, rms = (float(v[0]) for v in solve_xyb_stack(theta[None], rate[None],
                                                           None if c is None else c[None],
                                                           None if w is None else w[None]))
        psi = math.atan2(y, x)
        return HeadingSolution(float(wrap_deg_360(math.degrees(psi))), x, y, b,
                               math.hypot(x, y), rms, n)
    if len(distinct) == 2 and abs(abs(math.remainder(distinct[1] - distinct[0], 2 * math.pi))
                                  - math.pi) <= math.radians(angle_tol_deg):
        psi, omega_h, b, rms, amb = _solve_two_position(distinct[0], theta, rate, c, w,
                                                        latitude_deg, heading_hint_deg)
        return HeadingSolution(float(wrap_deg_360(math.degrees(psi))), omega_h * math.cos(psi),
                               omega_h * math.sin(psi), float(b), omega_h, rms, n, amb)
    angles = ", ".join(f"{math.degrees(a):g}" for a in distinct)
    raise NfsError(f"the positions cannot determine psi: distinct angles [{angles}] deg; need "
                   "at least 3 distinct angles, or two angles 180 deg apart with latitude_deg")
