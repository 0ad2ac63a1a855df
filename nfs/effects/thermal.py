"""Thermal effects: extra heat at a node [W] (docs/effects.md, "Thermal effects"; docs/physics.md
2).

Signature ``f(time_s, temperature_c, moving, **params) -> power [W]`` at the effect's node;
``temperature_c`` is that node's temperature.  Effects registered ``state_dependent`` are
evaluated per sample from the current state (the solver holds the power over each sample
interval); the others are evaluated once on whole arrays.
"""

from __future__ import annotations

import numpy as np

from .registry import Parameter, register_effect

__all__ = ["tec_power", "heat_source", "motor_heat"]


@register_effect("tec_power", kind="thermal", target="node", state_dependent=True, parameters=[
    Parameter("T_set", "degC", "TEC set point of the light source", default=25.0),
    Parameter("c_h", "W/K", "extra power per kelvin below the set point (heating)"),
    Parameter("c_c", "W/K", "extra power per kelvin above the set point (cooling)"),
    Parameter("node", "", "node of the light source (default: the instrument's source node)",
              type=str, optional=True)])
def tec_power(time_s, temperature_c, moving, *, T_set: float = 25.0, c_h: float, c_c: float,
              node: str | None = None):
    """TEC power law: P = c_h max(0, T_set - T_src) + c_c max(0, T_src - T_set) [W].

    The thermo-electric cooler that holds the source at its set point draws more power the
    further the source's surroundings sit from it; the extra power heats the electronics
    node, which is what makes start-up depend on T0.  c_h 0.02-0.04 W/K, c_c 0.05-0.1 W/K
    (docs/physics.md section 2, est.).  Evaluated per sample from the node temperature.
    """
    dT = temperature_c - T_set
    if isinstance(dT, float):
        # Per-sample call from the solver: plain float arithmetic is ~10x faster than NumPy's
        # ufuncs on scalars, and this runs once per sample of every run.
        return c_h * -dT if dT < 0.0 else c_c * dT
    return c_h * np.maximum(0.0, -dT) + c_c * np.maximum(0.0, dT)


@register_effect("heat_source", kind="thermal", target="node", parameters=[
    Parameter("node", "", "node that receives the power", type=str),
    Parameter("power", "W", "constant extra power")])
def heat_source(time_s, temperature_c, moving, *, node: str, power: float):
    """A constant extra power P at a named node [W] (docs/physics.md section 2)."""
    return power * np.ones_like(np.asarray(time_s, dtype=float))


@register_effect("motor_heat", kind="thermal", target="node", parameters=[
    Parameter("node", "", "node heated by the turntable motor", type=str),
    Parameter("power", "W", "power dissipated while the turntable moves")])
def motor_heat(time_s, temperature_c, moving, *, node: str, power: float):
    """Heat pulse from the turntable motor: P while moving, 0 at rest [W].

    docs/physics.md section 7 ("heat pulses from the turntable motor at each move").
    """
    return power * np.asarray(moving, dtype=float)
