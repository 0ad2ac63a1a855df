"""Exact levelling: the heading from the Earth rate and the gravity direction in the table frame.

The gyro and both accelerometers turn with the table, so over one cycle they sample fixed
vectors of the table frame (x_T, y_T: the body axes at theta = 0; z_T: the table axis,
down) along the directions u_k = (cos theta_k, sin theta_k, 0).  The x accelerometer reads
f_x,k = U_T . u_k (+ its bias), U_T the unit up vector (the specific force of gravity,
1 g) in the table frame, and with Omega = Omega_ie (cos L N + sin L U) the gyro reads
w_k = Omega_T . u_k + b, so that

    y_k = w_k - Omega_ie sin L f_x,k = Omega_ie cos L N_T . u_k + b
        = X cos theta_k - Y sin theta_k + b,   (X, -Y) = Omega_ie cos L (N_x, N_y)

exactly, for any tilt (a constant accelerometer bias b_x goes into b as -Omega_ie sin L
b_x, which is also what a gyro sees of an x axis raised out of the table plane: the bias
reported keeps it).  Least squares gives X, Y, b.  The up vector U_T comes from both
accelerometers, f_x,k = U_x cos theta_k + U_y sin theta_k + b_x and f_y,k = -U_x sin
theta_k + U_y cos theta_k + b_y, with U_z = -sqrt(1 - U_x^2 - U_y^2).  The north vector is
horizontal (N . U = 0), which gives n = (X, -Y, n_z) with n_z = -(X U_x - Y U_y) / U_z, and
the heading, the azimuth of the horizontal projection of x_T, is

    psi = atan2(E_x, N_x),   E = N x U   (north x up = east in NED).

A noiseless run of an exactly tilted table gives psi to rounding (the Earth-rate and
gravity vectors resolved in the body frame, as in the analytic alignment of Titterton &
Weston, "Strapdown Inertial Navigation Technology", 2004, section 10.2; equation numbers
not checked).  U_T enters only through n_z and E, at second order in the tilt; a level
table (U_T = (0, 0, -1)) gives psi = atan2(Y, X).  Angles in rad inside.
"""

from __future__ import annotations

import math

import numpy as np

from nfs.errors import NfsError
from nfs.northfind.solve import horizontal_earth_rate_dph

__all__ = ["LEVEL_UP", "gravity_and_biases", "level_heading",
           "level_two_position", "branch_heading"]

#: U_T of a level table (z_T down): the up vector when tilt correction is off.
LEVEL_UP = np.array([0.0, 0.0, -1.0])


def gravity_and_biases(theta_rad, acc_x_g, acc_y_g, *, biases_known: bool = False):
    """U_T, the up unit vector in the table frame, and the accelerometer biases b_x, b_y [g],
    per cycle, from both accelerometers.

    ``theta_rad``, ``acc_x_g``, ``acc_y_g``: (n_cycles, n_positions) dwell means.  Least
    squares of the module's f_x, f_y model in (U_x, U_y, b_x, b_y) per cycle; U_z =
    -sqrt(1 - U_x^2 - U_y^2); a cycle with a non-finite reading gives NaN; NfsError when the
    fitted tilt reaches 90 deg.  With ``biases_known`` the readings are taken as bias-free
    (already corrected) and only (U_x, U_y) are fitted, which one position determines; the
    biases returned are then 0.  Otherwise the positions must determine all four (two
    distinct angles at least).
    Returns (U_T (n_cycles, 3), b_x (n_cycles,), b_y (n_cycles,)).
    """
    th = np.asarray(theta_rad, dtype=float)
    fx = np.asarray(acc_x_g, dtype=float)
    fy = np.asarray(acc_y_g, dtype=float)
    c, s = np.cos(th), np.sin(th)
    one, zero = np.ones_like(th), np.zeros_like(th)
    cols_x, cols_y = [c, s], [-s, c]
    if not biases_known:
        cols_x += [one, zero]
        cols_y += [zero, one]
    design = np.concatenate([np.stack(cols_x, axis=-1), np.stack(cols_y, axis=-1)], axis=-2)
    y = np.concatenate([fx, fy], axis=-1)
    out = np.full(th.shape[:-1] + (3,), np.nan)
    bias = np.zeros(th.shape[:-1] + (2,))
    ok = np.all(np.isfinite(y), axis=-1)
    bias[~ok] = np.nan
    if np.any(ok):
        coef = np.einsum("cij,cj->ci", np.linalg.pinv(design[ok]), y[ok])
        horiz = coef[:, 0] ** 2 + coef[:, 1] ** 2
        if np.any(horiz >= 1.0):
            raise NfsError(f"the accelerometers give a tilt of 90 deg or more "
                           f"(|U_xy| = {math.sqrt(float(np.max(horiz))):.6g} g)")
        out[ok] = np.column_stack([coef[:, 0], coef[:, 1], -np.sqrt(1.0 - horiz)])
        if not biases_known:
            bias[ok] = coef[:, 2:4]
    return out, bias[..., 0], bias[..., 1]


def _heading(n: np.ndarray, up: np.ndarray) -> np.ndarray:
    """psi = atan2(E_x, N_x) with E = N x U [rad]; n, up (..., 3)."""
    east_x = n[..., 1] * up[..., 2] - n[..., 2] * up[..., 1]
    return np.arctan2(east_x, n[..., 0])


def level_heading(x_dph, y_dph, up):
    """Heading psi [rad] and horizontal Earth rate [deg/h] from the fitted X, Y and U_T.

    n = (X, -Y, n_z) = Omega_ie cos L N_T with n_z = -(n_x U_x + n_y U_y) / U_z (the north
    vector is horizontal); psi = atan2(E_x, n_x), the horizontal rate is |n|.  X, Y from
    rates with the vertical Earth rate removed (module docstring).  Arrays of cycles;
    ``up`` is (n_cycles, 3) or (3,).
    """
    up = np.broadcast_to(np.asarray(up, dtype=float), np.shape(x_dph) + (3,))
    nx = np.asarray(x_dph, dtype=float)
    ny = -np.asarray(y_dph, dtype=float)
    nz = -(nx * up[..., 0] + ny * up[..., 1]) / up[..., 2]
    n = np.stack([nx, ny, nz], axis=-1)
    return _heading(n, up), np.linalg.norm(n, axis=-1)


def level_two_position(theta_rad, rate_dph, up, latitude_deg: float,
                       heading_hint_deg: float | None = None):
    """Two positions theta_a and theta_a + 180 deg, levelled exactly (per cycle).

    Least squares of y_k = s_k a + b (s_k = +1 at theta_a, -1 opposite; y_k the rates with
    the vertical Earth rate removed, module docstring) gives a = n . d for the table
    direction d = (cos theta_a, sin theta_a, 0) and the north vector n = Omega_h N_T, which
    lies in the horizontal plane: with h1 the
    unit horizontal projection of d and h2 = U x h1, n = n_1 h1 + n_2 h2, n_1 = (n . d) /
    |d_h|, n_2 = +-sqrt(Omega_h^2 - n_1^2).  The sign is not observable (on a level table
    n_2 = Omega_h sin(psi + theta_a)): the branch nearest ``heading_hint_deg`` is taken, or
    without a hint n_2 >= 0 and the cycle is marked ambiguous.  Omega_h = Omega_ie cos L
    is the known horizontal rate.

    Returns (psi [rad], Omega_h, bias [deg/h], residual RMS [deg/h], ambiguous), arrays
    over the cycles (ambiguous a bool).
    """
    th = np.asarray(theta_rad, dtype=float)
    w = np.asarray(rate_dph, dtype=float)
    up = np.broadcast_to(np.asarray(up, dtype=float), th.shape[:-1] + (3,))
    omega_h = horizontal_earth_rate_dph(latitude_deg)
    theta_a = th[:, :1]
    sgn = np.where(np.abs(np.angle(np.exp(1j * (th - theta_a)))) < np.pi / 2, 1.0, -1.0)
    design = np.stack([sgn, np.ones_like(th)], axis=-1)
    coef = np.einsum("cij,cj->ci", np.linalg.pinv(design), w)
    resid = w - np.einsum("cij,cj->ci", design, coef)
    a, b = coef[:, 0], coef[:, 1]
    psi, ambiguous = branch_heading(a, theta_a[:, 0], up, omega_h, heading_hint_deg)
    rms = np.sqrt(np.mean(resid * resid, axis=-1))
    return psi, np.full(len(th), omega_h), b, rms, ambiguous


def branch_heading(a, theta_a, up, omega_h: float, heading_hint_deg: float | None = None):
    """Heading [rad] from the Earth rate a = n . d seen along one table direction, per cycle.

    d = (cos theta_a, sin theta_a, 0) in the table frame, n = Omega_h N_T horizontal.  With
    h1 the unit horizontal projection of d and h2 = U x h1, n = n_1 h1 + n_2 h2,
    n_1 = a / |d_h|, n_2 = +-sqrt(Omega_h^2 - n_1^2): the sign is not observable (on a level
    table n_2 = Omega_h sin(psi + theta_a)), so the branch nearest ``heading_hint_deg`` is
    taken, or without a hint n_2 >= 0 and the result is marked ambiguous.  ``a``,
    ``theta_a``: (n_cycles,); ``up``: (n_cycles, 3).  Returns (psi, ambiguous).
    """
    a = np.asarray(a, dtype=float)
    theta_a = np.asarray(theta_a, dtype=float)
    up = np.broadcast_to(np.asarray(up, dtype=float), a.shape + (3,))
    d = np.stack([np.cos(theta_a), np.sin(theta_a), np.zeros_like(theta_a)], axis=-1)
    du = np.sum(d * up, axis=-1)
    d_h = d - du[:, None] * up
    norm_h = np.linalg.norm(d_h, axis=-1)
    h1 = d_h / norm_h[:, None]
    h2 = np.cross(up, h1)
    n1 = a / norm_h
    n2 = np.sqrt(np.maximum(omega_h * omega_h - n1 * n1, 0.0))
    psi_pos = _heading(n1[:, None] * h1 + n2[:, None] * h2, up)
    psi_neg = _heading(n1[:, None] * h1 - n2[:, None] * h2, up)
    if heading_hint_deg is None:
        return psi_pos, True
    hint = math.radians(heading_hint_deg)

    def dist(p):
        return np.abs(np.angle(np.exp(1j * (p - hint))))

    return np.where(dist(psi_neg) < dist(psi_pos), psi_neg, psi_pos), False
