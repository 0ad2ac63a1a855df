"""Accelerometer effects [g] (docs/effects.md, "Accelerometer effects"; docs/physics.md section 4)."""

from __future__ import annotations

import numpy as np

from ..errors import EffectError
from .context import EffectContext
from .registry import Parameter, register_effect

__all__ = ["acc_bias_temperature"]

_AXIS = Parameter("axis", "", "accelerometer axis, 'x' or 'y'", type=str)


def acc_node(ctx: EffectContext, axis: str) -> str:
    """The thermal node of the QFA on ``axis`` (EffectError for an unknown axis)."""
    try:
        return ctx.acc_nodes[axis]
    except KeyError:
        raise EffectError(f"unknown accelerometer axis '{axis}'; axes: "
                          + ", ".join(sorted(ctx.acc_nodes))) from None


@register_effect("acc_bias_temperature", kind="accelerometer", target="axis", parameters=[
    _AXIS, Parameter("b_q1", "g/K", "bias temperature coefficient")])
def acc_bias_temperature(ctx: EffectContext, *, axis: str, b_q1: float) -> np.ndarray:
    """QFA bias vs temperature: b_q1 (T_acc - T_ref) [g] on one axis.

    b_q1 [g/K], 10-50 ug/K for quartz flexure accelerometers (docs/physics.md section 4, est.;
    IEEE Std 1293-2018 bias temperature sensitivity).  T_acc is the QFA's node.
    """
    return b_q1 * (ctx.node(acc_node(ctx, axis)) - ctx.t_ref_c)
