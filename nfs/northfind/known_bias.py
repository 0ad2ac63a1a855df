"""North finding with the sensor biases known: any schedule, down to one position.

A multiposition cycle fits the gyro bias b with the heading (docs/physics.md section 5):
it needs three distinct positions, or two 180 deg apart and a hint for the sign.  When the
biases are known instead (predicted from the temperatures by a parameter-level model,
:mod:`nfs.studies.parameter_study`, or calibrated), fewer positions do (Titterton and Weston,
"Strapdown Inertial Navigation Technology", 2004, section 10.2: gyrocompassing with the
instrument errors calibrated):

- accelerometers: f_x,k - b_x = U_x cos theta_k + U_y sin theta_k and f_y,k - b_y =
  -U_x sin theta_k + U_y cos theta_k (:mod:`nfs.northfind.level`), least squares in
  (U_x, U_y), which one position determines;
- gyro: y_k = (w_k - b) / (1 + k) - Omega_ie sin L (f_x,k - b_x) = X cos theta_k - Y sin theta_k
  with k the scale-factor error [-];
- two distinct positions not 180 deg apart (e.g. 0 and 90 deg) and more: least squares in
  (X, Y) and the exact levelling of :func:`~nfs.northfind.level.level_heading`;
- one position, or only positions 180 deg apart: a = mean of s_k y_k = n . d with the known
  Omega_h = Omega_ie cos L, and the sign of psi + theta_a from a hint
  (:func:`~nfs.northfind.level.branch_heading`).

The error of the bias goes straight into the heading: db / (Omega_h |sin(psi + theta)|) rad
for one position, where a multiposition cycle cancels it.  That is what a parameter-level
model buys on schedules that do not cancel the bias.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nfs.constants import earth_rate_components_dph
from nfs.errors import NfsError
from nfs.northfind.heading import NorthFindResult
from nfs.northfind.level import branch_heading, gravity_and_biases, level_heading
from nfs.northfind.solve import (distinct_angles, horizontal_earth_rate_dph, wrap_deg_180,
                                 wrap_deg_360)

__all__ = ["KnownBiasHeading", "level_known_bias", "north_find_known_bias"]


@dataclass(frozen=True)
class KnownBiasHeading:
    """Headings of a run's cycles solved with the biases known (arrays over the cycles)."""

    positions_deg: tuple[float, ...]
    """The turntable angles used in each cycle [deg]."""
    heading_deg: np.ndarray
    """Heading psi of each cycle, in [0, 360) [deg]."""
    error_deg: np.ndarray
    """heading_deg - true heading, wrapped to [-180, 180) [deg] (NaN when unknown)."""
    ambiguous: bool
    """True when the sign of psi + theta_a was taken without a hint (one position, or only
    positions 180 deg apart)."""


def _per_cycle(value, n: int, name: str) -> np.ndarray:
    v = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    if v.shape != (n,):
        raise NfsError(f"{name} must be a number or one value per cycle ({n})")
    return v


def level_known_bias(theta_rad, rate_dph, acc_x_g, acc_y_g, latitude_deg: float, *,
                     gyro_bias_dph=0.0, acc_x_bias_g=0.0, acc_y_bias_g=0.0,
                     scale_factor=0.0, heading_hint_deg: float | None = None,
                     angle_tol_deg: float = 0.5):
    """Heading [rad] per cycle with the biases known (module docstring).

    ``theta_rad``, ``rate_dph``, ``acc_x_g``, ``acc_y_g``: dwell means, (n_cycles,
    n_positions), the same angles in every cycle.  Biases and the scale-factor error k [-]:
    a number or one per cycle.  Returns (psi [rad], ambiguous).
    """
    th = np.asarray(theta_rad, dtype=float)
    if th.ndim != 2 or th.shape[0] == 0:
        raise NfsError("level_known_bias needs dwell means of shape (n_cycles, n_positions)")
    n = th.shape[0]
    bg = _per_cycle(gyro_bias_dph, n, "gyro_bias_dph")[:, None]
    bx = _per_cycle(acc_x_bias_g, n, "acc_x_bias_g")[:, None]
    by = _per_cycle(acc_y_bias_g, n, "acc_y_bias_g")[:, None]
    k = _per_cycle(scale_factor, n, "scale_factor")[:, None]
    fx = np.asarray(acc_x_g, dtype=float) - bx
    fy = np.asarray(acc_y_g, dtype=float) - by
    up = gravity_and_biases(th, fx, fy, biases_known=True)[0]
    omega_v = earth_rate_components_dph(latitude_deg)[1]
    y = (np.asarray(rate_dph, dtype=float) - bg) / (1.0 + k) - omega_v * fx
    distinct = distinct_angles(th[0], math.radians(angle_tol_deg))
    opposite = len(distinct) == 2 and abs(abs(math.remainder(
        distinct[1] - distinct[0], 2 * math.pi)) - math.pi) <= math.radians(angle_tol_deg)
    if len(distinct) >= 2 and not opposite:
        design = np.stack([np.cos(th), -np.sin(th)], axis=-1)
        coef = np.einsum("cij,cj->ci", np.linalg.pinv(design), y)
        return level_heading(coef[:, 0], coef[:, 1], up)[0], False
    theta_a = th[:, :1]
    sgn = np.where(np.abs(np.angle(np.exp(1j * (th - theta_a)))) < np.pi / 2, 1.0, -1.0)
    a = np.mean(sgn * y, axis=1)
    return branch_heading(a, theta_a[:, 0], up, horizontal_earth_rate_dph(latitude_deg),
                          heading_hint_deg)


def north_find_known_bias(result: NorthFindResult, *, positions_deg=None,
                          gyro_bias_dph=0.0, acc_x_bias_g=0.0, acc_y_bias_g=0.0,
                          scale_factor=0.0, heading_hint_deg: float | None = None,
                          angle_tol_deg: float = 0.5) -> KnownBiasHeading:
    """Heading of every cycle of ``result`` (a :func:`~nfs.northfind.north_find`, whose dwell
    means of the gyro and both accelerometers it uses) with the biases known, using only the
    dwells at ``positions_deg`` (default: all).

    Using a subset of a multiposition run's dwells (0 and 90 deg of a four-position cycle,
    or 0 deg alone) solves the two-position and one-position schedules on the same samples,
    so schedules are compared on the same runs.  Biases as in :func:`level_known_bias`.
    """
    theta = np.asarray(result.theta_deg, dtype=float)
    cols = np.arange(theta.shape[1])
    if positions_deg is not None:
        want = [float(p) for p in positions_deg]
        cols = np.array([j for j in range(theta.shape[1])
                         if any(abs(wrap_deg_180(theta[0, j] - p)) <= angle_tol_deg
                                for p in want)], dtype=int)
        if len(cols) != len(want):
            raise NfsError(f"run '{result.run_name}': positions {want} deg are not all dwells "
                           f"of its cycles ({', '.join(f'{v:g}' for v in theta[0])} deg)")
    if result.acc_y_g is None:
        raise NfsError(f"run '{result.run_name}': the north-finding result holds no y "
                       "accelerometer means; north-find it again with this version")
    rate = np.asarray(result.rate_dph)[:, cols]
    fx = np.asarray(result.acc_x_g)[:, cols]
    fy = np.asarray(result.acc_y_g)[:, cols]
    psi, amb = level_known_bias(np.radians(theta[:, cols]), rate, fx, fy, result.latitude_deg,
                                gyro_bias_dph=gyro_bias_dph, acc_x_bias_g=acc_x_bias_g,
                                acc_y_bias_g=acc_y_bias_g, scale_factor=scale_factor,
                                heading_hint_deg=heading_hint_deg, angle_tol_deg=angle_tol_deg)
    heading = np.asarray(wrap_deg_360(np.degrees(psi)), dtype=float)
    true = result.true_heading_deg
    error = (np.full(heading.shape, np.nan) if true is None
             else np.asarray(wrap_deg_180(heading - true), dtype=float))
    return KnownBiasHeading(tuple(float(v) for v in theta[0, cols]), heading, error,
                            bool(amb))
