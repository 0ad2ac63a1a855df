"""Turntable and geometry effects: where the sensors point (docs/effects.md, "Turntable and
geometry effects", and ``axis_misalignment``; docs/physics.md sections 4 and 5).

A geometry effect does not add an error to a sensor's output: it changes the directions
the sensors point in, before the Earth rate and gravity are projected on them.  The state it
acts on is a :class:`Geometry`: the turntable's true angle, the platform tilt and the gyro's
input axis in the body frame.  The simulator builds one per run, lets each geometry effect
return a changed copy, and projects:

    gyro  = Omega . u_g          (Omega_ie cos L cos A cos e + Omega_ie sin L sin e)
    acc_x = -g_D . u_x = sin e_x,   acc_y = sin e_y

for the unit vectors u of the gyro axis and the two accelerometer axes (A, e: azimuth and
elevation of u).

Frames: the local level frame is north-east-down (NED).  The body frame on the turntable
is x (the x accelerometer and the nominal gyro axis), y (the y accelerometer, 90 deg
clockwise of x seen from above), z (the turntable axis, down).  Angles in deg at the
boundary, rad inside.

Without a geometry effect the axes follow the first-order tilt model of docs/physics.md
section 4 (azimuth A = psi + theta, elevation e = alpha_N cos A + alpha_E sin A), the model
every run of the package used before this module; with ``tilt_exact`` the platform is
rotated exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import EffectError
from ..sensors.turntable import axis_elevation_deg
from .registry import EffectInstance, Parameter, register_effect

__all__ = ["Geometry", "tilt_matrix", "table_axes_ned", "azimuth_elevation_deg",
           "apply_geometry", "check_geometry", "indexing_error", "axis_misalignment",
           "tilt_exact", "MAX_TILT_DEG"]

#: Largest platform tilt [deg] for which ``tilt_exact`` is offered (docs/effects.md).
MAX_TILT_DEG = 5.0

#: A commanded angle within this of a schedule position [deg] is a visit of that position.
_MATCH_TOL_DEG = 0.5


def tilt_matrix(pitch_deg: float, roll_deg: float) -> np.ndarray:
    """C, the rotation from the levelled table frame to the tilted one, in NED.

        C = R_y(p) R_x(-r)

    R_y(p) turns about the east axis and lifts the north edge of the table by the pitch p;
    R_x(-r) turns about the north axis and lifts the east edge by the roll r (taken first,
    so the table's north line keeps the elevation p exactly).  The Euler-angle direction
    cosine matrix of Titterton & Weston, "Strapdown Inertial Navigation Technology" (2004),
    section 3.6, with yaw 0, pitch p and roll -r (equation number not checked).  To first
    order C tilts an axis of azimuth A by e = p cos A + r sin A, the model of docs/physics.md
    section 4 with alpha_N = p, alpha_E = r.
    """
    p, r = math.radians(pitch_deg), math.radians(roll_deg)
    cp, sp, cr, sr = math.cos(p), math.sin(p), math.cos(r), math.sin(r)
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, sr], [0.0, -sr, cr]])
    return ry @ rx


def table_axes_ned(heading_deg: float, theta_deg: np.ndarray, pitch_deg: float,
                   roll_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (NED) of the body axes x, y, z on an exactly tilted turntable.

    The table normal (down) is n = C e_D (:func:`tilt_matrix`).  x_T, the x axis at
    theta = 0, is the unit vector of the table plane whose horizontal projection has the
    azimuth psi (the heading the package reports is the azimuth of that projection);
    y_T = n x x_T.  At table angle theta: x = cos theta x_T + sin theta y_T,
    y = -sin theta x_T + cos theta y_T, z = n.  Shapes (n_samples, 3).
    """
    n = tilt_matrix(pitch_deg, roll_deg)[:, 2]
    psi = math.radians(heading_deg)
    h = np.array([math.cos(psi), math.sin(psi), 0.0])
    v = h - (h @ n) / n[2] * np.array([0.0, 0.0, 1.0])   # in the table plane, over h
    x_t = v / np.linalg.norm(v)
    y_t = np.cross(n, x_t)
    th = np.radians(np.asarray(theta_deg, dtype=float))[:, None]
    c, s = np.cos(th), np.sin(th)
    x = c * x_t + s * y_t
    y = -s * x_t + c * y_t
    z = np.broadcast_to(n, x.shape)
    return x, y, z


def azimuth_elevation_deg(u_ned: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Azimuth A in [0, 360) (clockwise from north) and elevation e of vectors u (NED) [deg]."""
    u = u_ned / np.linalg.norm(u_ned, axis=-1, keepdims=True)
    az = np.mod(np.degrees(np.arctan2(u[..., 1], u[..., 0])), 360.0)
    el = np.degrees(np.arcsin(np.clip(-u[..., 2], -1.0, 1.0)))
    return az, el


def _first_order_axis(azimuth_deg, tilt_north_deg, tilt_east_deg):
    """Azimuth and the first-order elevation of :func:`~nfs.sensors.axis_elevation_deg` [deg]."""
    return azimuth_deg, axis_elevation_deg(azimuth_deg, tilt_north_deg, tilt_east_deg)


def _unit_ned(azimuth_deg, elevation_deg) -> np.ndarray:
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    return np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), -np.sin(e)], axis=-1)


@dataclass(frozen=True)
class Geometry:
    """Where the sensors of one run point: the state the geometry effects change."""

    time_s: np.ndarray
    """t, time since power-on [s]."""
    position_deg: np.ndarray
    """theta_cmd(t), the commanded turntable angle the run records [deg]."""
    moving: np.ndarray
    """True while the turntable moves."""
    positions_deg: tuple[float, ...]
    """theta_k, the schedule's positions (one pass) [deg]."""
    heading_deg: float
    """psi, azimuth of the x axis at theta = 0 [deg] (of its horizontal projection)."""
    rng: np.random.Generator
    """The run's seeded stream for the turntable's random draws."""
    theta_deg: np.ndarray
    """theta(t), the angle the table actually stands at [deg] (theta_cmd unless an effect
    says otherwise)."""
    tilt_north_deg: float = 0.0
    """alpha_N (first order) or the pitch p (exact) of the platform [deg]."""
    tilt_east_deg: float = 0.0
    """alpha_E (first order) or the roll r (exact) of the platform [deg]."""
    exact_tilt: bool = False
    """True: the tilt is the exact rotation of :func:`tilt_matrix`; False: docs/physics.md's
    first-order model."""
    gyro_axis_body: tuple[float, float, float] = (1.0, 0.0, 0.0)
    """Unit vector of the gyro's input axis in the body frame (x, y, z down)."""

    def axes_ned(self) -> dict[str, np.ndarray]:
        """Unit vectors (NED) of ``x``, ``y`` and ``gyro``, each (n_samples, 3)."""
        if self.exact_tilt:
            x, y, z = table_axes_ned(self.heading_deg, self.theta_deg, self.tilt_north_deg,
                                     self.tilt_east_deg)
        else:
            az = self.heading_deg + self.theta_deg
            x = _unit_ned(*_first_order_axis(az, self.tilt_north_deg, self.tilt_east_deg))
            y = _unit_ned(*_first_order_axis(az + 90.0, self.tilt_north_deg,
                                             self.tilt_east_deg))
            z = np.cross(x, y)
            z = z / np.linalg.norm(z, axis=-1, keepdims=True)
        gx, gy, gz = self.gyro_axis_body
        return {"x": x, "y": y, "gyro": gx * x + gy * y + gz * z}

    def azimuth_elevation(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """(azimuth, elevation) [deg] of the ``x``, ``y`` and ``gyro`` axes per sample.

        Without an exact tilt or a gyro misalignment these are docs/physics.md's first-order
        values A = psi + theta (wrapped to [0, 360)), e = alpha_N cos A + alpha_E sin A,
        computed exactly as before this module existed.
        """
        if not self.exact_tilt and self.gyro_axis_body == (1.0, 0.0, 0.0):
            az = np.mod(self.heading_deg + self.theta_deg, 360.0)
            x = _first_order_axis(az, self.tilt_north_deg, self.tilt_east_deg)
            _, el_y = _first_order_axis(az + 90.0, self.tilt_north_deg, self.tilt_east_deg)
            return {"x": x, "y": (np.mod(az + 90.0, 360.0), el_y), "gyro": x}
        return {k: azimuth_elevation_deg(u) for k, u in self.axes_ned().items()}


def apply_geometry(geom: Geometry, effects) -> Geometry:
    """``geom`` changed by each geometry effect of ``effects`` in turn (others ignored).

    Each effect sets its own part of the state (the table angle, the tilt, the gyro axis),
    so the order of the effects does not matter.
    """
    for e in effects:
        if e.spec.kind == "geometry":
            geom = e.spec.function(geom, **e.params)
    return geom


def check_geometry(effects, positions_deg, tilt_north_deg: float,
                   tilt_east_deg: float) -> None:
    """The checks of the geometry effects that need the schedule or the turntable, before
    any work: EffectError with a one-line message naming the effect.  ``positions_deg``
    None: no schedule to check against yet (an instrument file alone)."""
    for e in effects:
        if not isinstance(e, EffectInstance) or e.spec.kind != "geometry":
            continue
        if (e.name == "indexing_error" and positions_deg is not None
                and len(e.params["offsets_deg"]) != len(positions_deg)):
            raise EffectError(
                f"effect 'indexing_error': offsets_deg has {len(e.params['offsets_deg'])} "
                f"value(s), the schedule has {len(positions_deg)} position(s) "
                f"{list(positions_deg)}: give one offset per position")
        if e.name == "tilt_exact" and (tilt_north_deg != 0.0 or tilt_east_deg != 0.0):
            raise EffectError(_TWO_TILTS.format(tilt_north_deg, tilt_east_deg))


_TWO_TILTS = ("effect 'tilt_exact': the platform tilt is given twice ([turntable] "
              "tilt_north_deg = {:g}, tilt_east_deg = {:g}); set those to 0 or drop tilt_exact")


# --------------------------------------------------------------------------------------------
# The effects

def _visits(moving: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(index of the first sample of each visit, visit number of each sample at rest)."""
    rest = ~np.asarray(moving, dtype=bool)
    start = rest & np.concatenate(([True], ~rest[:-1]))
    return np.flatnonzero(start), np.cumsum(start) - 1


@register_effect("indexing_error", kind="geometry", parameters=[
    Parameter("offsets_deg", "deg", "fixed offset of each schedule position, in the order of "
              "positions_deg", type=tuple, bounds=(-MAX_TILT_DEG, MAX_TILT_DEG)),
    Parameter("sigma_deg", "deg", "repeatability: standard deviation of the scatter drawn "
              "at every visit", default=0.0, bounds=(0.0, 1.0))])
def indexing_error(geom: Geometry, *, offsets_deg: tuple[float, ...],
                   sigma_deg: float = 0.0) -> Geometry:
    """Turntable indexing error: theta_true = theta_cmd + d_k + s_v [deg].

    d_k [deg] is the fixed offset of schedule position k (one per entry of positions_deg;
    both visits of one angle in a forward-then-reverse cycle share it); s_v ~ N(0,
    sigma_deg^2) [deg] is drawn once per visit v (a dwell between two moves) from the run's
    seeded turntable stream.  During a move the error goes linearly in time from the last
    visit's to the next one's.  The run records theta_cmd (the indexer reports where it was
    told to go); the gyro and both accelerometers point at theta_true.

    Heading error (derived here, first order in d; no published figure checked): an axis
    off by d_k at position k reads Omega_h cos(A_k + d_k) ~ Omega_h (cos A_k - d_k sin A_k);
    least squares over N >= 3 equally spaced positions (X = (2/N) sum w_k cos theta_k,
    Y = -(2/N) sum w_k sin theta_k) turns the heading by

        delta_psi = (2/N) sum_k d_k sin^2(psi + theta_k),

    so a common offset d turns it by d, and the repeatability scatter gives a heading
    standard deviation sigma sqrt(3 / (2N)) (sum_k sin^4 = 3N/8).  The positional errors of
    an indexing table are treated the same way in the multiposition north-finding
    literature; see also Titterton & Weston (2004), ch. 8 (gyrocompassing).
    """
    visit_start, visit_of = _visits(geom.moving)
    if visit_start.size == 0:
        return geom
    pos = np.asarray(geom.positions_deg, dtype=float)
    cmd = np.asarray(geom.position_deg, dtype=float)[visit_start]
    dist = np.abs(np.mod(cmd[:, None] - pos[None, :] + 180.0, 360.0) - 180.0)
    k = np.argmin(dist, axis=1)
    bad = np.flatnonzero(dist[np.arange(k.size), k] > _MATCH_TOL_DEG)
    if bad.size:
        i = visit_start[bad[0]]
        raise EffectError(f"effect 'indexing_error': the table rests at {cmd[bad[0]]:g} deg "
                          f"at t = {geom.time_s[i]:g} s, which is no position of the schedule "
                          f"{list(geom.positions_deg)}")
    per_visit = np.asarray(offsets_deg, dtype=float)[k]
    per_visit = per_visit + geom.rng.normal(0.0, 1.0, k.size) * sigma_deg
    rest = ~np.asarray(geom.moving, dtype=bool)
    t = np.asarray(geom.time_s, dtype=float)
    err = np.interp(t, t[rest], per_visit[visit_of[rest]])
    return replace(geom, theta_deg=np.asarray(geom.theta_deg, dtype=float) + err)


@register_effect("axis_misalignment", kind="geometry", parameters=[
    Parameter("delta_deg", "deg", "in-plane angle of the gyro input axis from x (towards y)",
              bounds=(-180.0, 180.0)),
    Parameter("gamma_deg", "deg", "elevation of the gyro input axis above the table plane",
              default=0.0, bounds=(-MAX_TILT_DEG, MAX_TILT_DEG))])
def axis_misalignment(geom: Geometry, *, delta_deg: float, gamma_deg: float = 0.0) -> Geometry:
    """Gyro input axis out of line with x: u_g = cos g cos d x + cos g sin d y - sin g z.

    x, y, z (down) are the body axes that the heading and the x accelerometer refer to;
    d = delta_deg [deg] turns the gyro axis in the table plane towards y, g = gamma_deg [deg]
    lifts it out of the plane.  The gyro reads Omega . u_g: on a level table

        w = Omega_ie cos L cos g cos(A + d) + Omega_ie sin L sin g   [deg/h],

    so every north-found heading is the gyro axis's, psi + d (d is a mounting constant that
    north finding cannot see: calibration finds it), and g adds Omega_ie sin L sin g, which
    a multiposition fit takes into its bias.  On a tilted table g also brings cross terms of
    tilt and g (e.g. -Omega_ie cos L cos A sin e sin g) that the x accelerometer, which sees
    e and not e + g, does not correct.  The misalignment terms of a gyro's error model,
    Titterton & Weston (2004), ch. 4 (mounting misalignment; equation number not checked).
    """
    d, g = math.radians(delta_deg), math.radians(gamma_deg)
    return replace(geom, gyro_axis_body=(math.cos(g) * math.cos(d), math.cos(g) * math.sin(d),
                                         -math.sin(g)))


def _total_tilt_deg(pitch_deg: float, roll_deg: float) -> float:
    """Angle between the table axis and the vertical, acos(cos p cos r) [deg]."""
    c = math.cos(math.radians(pitch_deg)) * math.cos(math.radians(roll_deg))
    return math.degrees(math.acos(min(1.0, c)))


def _check_tilt(params: dict) -> None:
    tilt = _total_tilt_deg(params["pitch_deg"], params["roll_deg"])
    if tilt > MAX_TILT_DEG:
        raise EffectError(f"the platform tilt acos(cos pitch cos roll) = {tilt:.3g} deg exceeds "
                          f"{MAX_TILT_DEG:g} deg (the range the model is offered for)")


@register_effect("tilt_exact", kind="geometry", check=_check_tilt, parameters=[
    Parameter("pitch_deg", "deg", "platform pitch: the table's north edge up",
              bounds=(-MAX_TILT_DEG, MAX_TILT_DEG)),
    Parameter("roll_deg", "deg", "platform roll: the table's east edge up",
              bounds=(-MAX_TILT_DEG, MAX_TILT_DEG))])
def tilt_exact(geom: Geometry, *, pitch_deg: float, roll_deg: float) -> Geometry:
    """Platform tilt as an exact rotation C = R_y(p) R_x(-r) [deg] (:func:`tilt_matrix`).

    The turntable turns about its own axis n = C e_D; the x axis at table angle theta is
    u = cos theta x_T + sin theta y_T (:func:`table_axes_ned`, x_T in the table plane over
    the heading psi), and gravity and the Earth rate are projected on these exact unit
    vectors: acc_x = sin e = -u_D, gyro = Omega_ie (cos L u_N - sin L u_D).  p = pitch_deg [deg], r
    = roll_deg [deg], each and the
    total tilt acos(cos p cos r) at most 5 deg.  The first-order model of docs/physics.md section
    4 (e = alpha_N cos A + alpha_E sin A, azimuth psi + theta) agrees to first order; at
    p = 2 deg, r = 1 deg the two put the north-found heading 6.6e-3 deg apart at psi =
    212.7 deg (:func:`nfs.northfind.budget.tilt_model_error_deg`).  Replaces the
    [turntable] tilt, which must then be 0.  Titterton & Weston (2004), section 3.6 (Euler
    angles; equation number not checked).
    """
    if geom.tilt_north_deg != 0.0 or geom.tilt_east_deg != 0.0:
        raise EffectError(_TWO_TILTS.format(geom.tilt_north_deg, geom.tilt_east_deg))
    return replace(geom, tilt_north_deg=float(pitch_deg), tilt_east_deg=float(roll_deg),
                   exact_tilt=True)
