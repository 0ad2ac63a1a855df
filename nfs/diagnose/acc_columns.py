"""Design matrices of the accelerometer channels: the window means of acc_x_g and acc_y_g.

An accelerometer effect (``acc_bias_temperature`` on an axis) shows first in its own
accelerometer, not in the gyro: the x axis's error enters the drift only through the
vertical-rate removal of the north finder, Omega_ie sin L b_x (1.1e-5 deg/h per ug at 45 deg),
while the accelerometer itself reads it directly against a white-noise floor of a few ug per
10 s window.  So an accelerometer candidate is scored on its axis's readings at rest.

At rest, the axis of azimuth A on a turntable tilted by alpha_N (north edge up) and alpha_E
reads (docs/physics.md section 4; :mod:`nfs.fit.sensor_fit`)

    f = sin(e) + b + sum_j c_j g_j(T) + n,    e = alpha_N cos A + alpha_E sin A     [g]

with A the x axis's azimuth, or A + 90 deg for the y axis, b the axis bias, g_j the model's
accelerometer effects on that axis with coefficients c_j (evaluated on the same node
temperatures as the drift candidates).  Averaged over a window of ``decimate_s`` at rest,
this is linear in (alpha_N, alpha_E, b, c_j) once sin(e) - e is taken at the model's tilts
(below 1e-6 g for a table levelled within 1 deg): the model's columns are
(pi/180 <cos A>, pi/180 <sin A>, 1, <g_j>), the candidate's <g> of its effect with unit
coefficient.  The statistics are those of the drift channel (:mod:`nfs.scoring.run_stats`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..effects.registry import EffectInstance
from ..instrument import Instrument
from ..run import Run
from ..sensors import axis_elevation_deg
from .candidates import Candidate, effect_of, shape_grid, split_parameters
from ..fit.drift_residual import prepare_drift, window_means

__all__ = ["ACC_AXES", "AccRun", "acc_channel", "model_acc_paths", "prepare_acc",
           "acc_candidate_columns", "acc_grid_columns"]

#: The accelerometer axes and the offset of each from the x axis's azimuth [deg].
ACC_AXES = {"x": 0.0, "y": 90.0}

_DEG = np.pi / 180.0


@dataclass(frozen=True)
class AccRun:
    """One run on one accelerometer channel."""

    rd: Any
    """Its preparation with the accelerometer channels
    (:func:`nfs.fit.drift_residual.prepare_drift`)."""
    ctx: Any
    """Effect context of the run (the drift candidates' node temperatures)."""
    y: np.ndarray
    """Measured window means minus sin(e) - e at the model's tilts [g]."""
    X: np.ndarray
    """Model columns per window: tilt north [deg], tilt east [deg], bias [g], the model's
    accelerometer effect coefficients on the axis."""


def acc_channel(axis: str) -> str:
    """The measurement column of an accelerometer axis, ``acc_<axis>_g``."""
    return f"acc_{axis}_g"


def _axis_effects(inst: Instrument, axis: str) -> list[tuple[EffectInstance, str]]:
    """(effect, coefficient) of every coefficient of the model's effects on ``axis``."""
    out = []
    for e in inst.effects:
        if e.spec.kind == "accelerometer" and e.params.get("axis") == axis:
            coefs, _, _ = split_parameters(e.spec)
            out += [(e, c) for c in coefs if e.params.get(c) is not None]
    return out


def model_acc_paths(inst: Instrument, axis: str) -> list[str]:
    """The parameters of the model's columns on ``axis`` (tilts, bias, effect coefficients)."""
    return (["turntable.tilt_north_deg", "turntable.tilt_east_deg",
             f"accelerometers.bias_{axis}_g"]
            + [f"effects.{e.label}.{c}" for e, c in _axis_effects(inst, axis)])


def _unit_term(e: EffectInstance, coef: str, coefs: Sequence[str], ctx) -> np.ndarray:
    """Effect ``e`` with ``coef`` = 1 and its other coefficients 0, on ``ctx`` [g]."""
    params = {**e.params, **{c: (1.0 if c == coef else 0.0) for c in coefs}}
    return np.asarray(e.spec.function(ctx, **params), dtype=float) * np.ones(
        ctx.earth_rate_dph.size)


def prepare_acc(inst: Instrument, runs: Sequence[Run], contexts: Sequence[Any],
                decimate_s: float, axis: str) -> list[AccRun] | None:
    """Every run on the ``axis`` accelerometer channel (module docstring); None when a run
    lacks the column.  ``contexts``: the effect context of each run (the drift preparation's,
    :func:`nfs.diagnose.columns.prepare_runs`)."""
    col = acc_channel(axis)
    if not all(col in r.columns for r in runs):
        return None
    tt = inst.turntable
    effects = _axis_effects(inst, axis)
    out = []
    for run, ctx in zip(runs, contexts):
        rd = prepare_drift(run, decimate_s, True, "raw")
        a = rd.azimuth + ACC_AXES[axis]
        e = np.radians(axis_elevation_deg(a, tt.tilt_north_deg, tt.tilt_east_deg))
        cols = [_DEG * window_means(rd, np.cos(np.radians(a))),
                _DEG * window_means(rd, np.sin(np.radians(a)))]
        cols.append(np.ones_like(cols[0]))
        for eff, c in effects:
            coefs, _, _ = split_parameters(eff.spec)
            cols.append(window_means(rd, _unit_term(eff, c, coefs, ctx)))
        y = rd.measured[col] - window_means(rd, np.sin(e) - e)
        out.append(AccRun(rd, ctx, y, np.column_stack(cols)))
    return out


def acc_candidate_columns(c: Candidate, shapes: dict[str, float], acc: list[AccRun]
                          ) -> list[np.ndarray]:
    """The candidate's window-mean columns on its accelerometer channel, one per coefficient
    (that coefficient 1, the others 0, shapes fixed), per run."""
    e = effect_of(c, {**{k: 0.0 for k in c.coefficients}, **shapes})
    return [np.column_stack([window_means(a.rd, _unit_term(e, k, c.coefficients, a.ctx))
                             for k in c.coefficients]) for a in acc]


def acc_grid_columns(c: Candidate, acc: list[AccRun]
                     ) -> list[tuple[dict[str, float], list[np.ndarray]]]:
    """(shape values, columns per run) at every grid point of the candidate's shapes."""
    return [(g, acc_candidate_columns(c, g, acc)) for g in shape_grid(c)]
