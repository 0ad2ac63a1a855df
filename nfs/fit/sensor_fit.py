"""Accelerometer biases and turntable tilt by linear least squares from the means at rest.

On a turntable tilted by alpha_N toward north and alpha_E toward east, the x and y
accelerometers at axis azimuth A read (docs/physics.md section 4)

    f_x = sin(alpha_N cos A + alpha_E sin A) + b_x + e_x(T)                         [g]
    f_y = sin(-alpha_N sin A + alpha_E cos A) + b_y + e_y(T)                        [g]

(the y axis points at A + 90 deg; :func:`nfs.sensors.axis_elevation_deg`), e_x, e_y the
accelerometer effects of the model.  With sin(e) ~ e for the tilts of a levelled table
(e <= 1 deg: the cubic term e^3/6 is 1e-6 g or less) this is linear in (alpha_N, alpha_E,
b_x, b_y): averaged over a window, cos A and sin A become their window means, and one
linear least-squares solve (:func:`numpy.linalg.lstsq`) gives them directly, whatever the
start.  Two more solves with the cubic term moved to the left-hand side make it exact to
float precision.  :func:`nfs.fit.calibration.fit_model` starts its drift stage there and then
refines them jointly with the other drift parameters.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ..errors import NfsError

__all__ = ["LEVEL_PATHS", "LevelData", "level_from_means"]

#: The parameters the linear solve finds, in the order of its unknowns.
LEVEL_PATHS = ("turntable.tilt_north_deg", "turntable.tilt_east_deg",
               "accelerometers.bias_x_g", "accelerometers.bias_y_g")

_DEG = math.pi / 180.0


@dataclass(frozen=True)
class LevelData:
    """Window means of one run at rest (the rows of the linear solve)."""

    cos_a: np.ndarray
    """Mean of cos A over each window [-] (A the x axis azimuth)."""
    sin_a: np.ndarray
    """Mean of sin A over each window [-]."""
    acc_x_g: np.ndarray
    """Measured f_x minus the model's x accelerometer effects, window means [g]."""
    acc_y_g: np.ndarray
    """Measured f_y minus the model's y accelerometer effects, window means [g]."""


def level_from_means(data: Sequence[LevelData], start: Mapping[str, float],
                     free: Sequence[str], *, scale_x_g: float = 1.0,
                     scale_y_g: float = 1.0, n_iterations: int = 3) -> dict[str, float]:
    """Tilts and accelerometer biases from window means at rest (module docstring).

    Parameters
    ----------
    data : sequence of LevelData
        The windows of every run.
    start : mapping
        Value of each of :data:`LEVEL_PATHS` [deg, g]; those not in ``free`` are held.
    free : sequence of str
        Which of :data:`LEVEL_PATHS` to solve for (others are ignored).
    scale_x_g, scale_y_g : float
        Noise level of a window mean of each axis [g] (weights of the two axes).
    n_iterations : int
        Linear solves; the first neglects sin(e) - e, each next one subtracts it at the
        previous solution.

    Returns
    -------
    dict
        {path: value} of the free ones among :data:`LEVEL_PATHS`.
    """
    idx = [i for i, p in enumerate(LEVEL_PATHS) if p in free]
    if not idx or not data:
        return {}
    c = np.concatenate([d.cos_a for d in data])
    s = np.concatenate([d.sin_a for d in data])
    fx = np.concatenate([d.acc_x_g for d in data])
    fy = np.concatenate([d.acc_y_g for d in data])
    one, zero = np.ones_like(c), np.zeros_like(c)
    # columns: d f / d (alpha_N [deg], alpha_E [deg], b_x [g], b_y [g]), with sin(e) ~ e
    design = np.vstack([np.column_stack([_DEG * c, _DEG * s, one, zero]) / scale_x_g,
                        np.column_stack([-_DEG * s, _DEG * c, zero, one]) / scale_y_g])
    if not np.all(np.isfinite(design)):
        raise NfsError("level_from_means: non-finite window means")
    x = np.array([float(start[p]) for p in LEVEL_PATHS])
    fixed = [i for i in range(4) if i not in idx]
    for _ in range(max(1, n_iterations)):
        ex = _DEG * (x[0] * c + x[1] * s)
        ey = _DEG * (-x[0] * s + x[1] * c)
        # the part of sin(e) the linear columns miss, at the current solution
        lhs = np.concatenate([(fx - (np.sin(ex) - ex)) / scale_x_g,
                              (fy - (np.sin(ey) - ey)) / scale_y_g])
        lhs = lhs - design[:, fixed] @ x[fixed]
        sol, *_ = np.linalg.lstsq(design[:, idx], lhs, rcond=None)
        x[idx] = sol
    return {LEVEL_PATHS[i]: float(x[i]) for i in idx}
