"""Which parameters of an instrument a fit frees, and the box it keeps each one in.

The parameter paths themselves (``thermal.nodes.<node>.capacity_j_per_k``,
``effects.<label>.<param>``, ...), :func:`get_param`, :func:`set_params`,
:func:`list_params` and :func:`expand_paths` live in :mod:`nfs.parameters` (the simulator
draws a unit's parameters through them too) and are re-exported here; this module adds
:func:`default_bounds`, :func:`effect_unit` and :func:`fit_bounds`.
"""

from __future__ import annotations

import math

from ..parameters import (PARAM_KINDS, ParameterError, canonical_path, expand_paths,
                          get_param, list_params, param_kind, param_paths, set_params)

__all__ = ["ParameterError", "PARAM_KINDS", "get_param", "set_params", "list_params",
           "expand_paths", "param_kind", "param_paths", "default_bounds", "canonical_path",
           "effect_unit", "fit_bounds"]

_INF = math.inf


# ---------------------------------------------------------------------------------------------
# Bounds

def default_bounds(path: str, value: float, unit: str | None = None) -> tuple[float, float]:
    """The box (lower, upper) a fit keeps parameter ``path`` (now at ``value``) in.

    ======================================  =====================================================
    parameter                               bounds
    ======================================  =====================================================
    capacities, conductances                value/10 .. value*10 (> 0: a network stays physical);
                                            a zero conductance 0 .. 10 W/K
    node powers                             0 .. max(10 value, 1 W) (negative: 10 value .. 0)
    thermometer lag_s                       0 .. 300 s
    thermometer offset_c                    -2 .. +2 K
    noise, quantum, ARW, BI, RRW fields     0 .. inf
    tilts                                   -1 .. +1 deg
    effect time constants (unit ``s``),     value/10 .. value*10
    temperature periods (unit ``K``)
    effect temperatures (unit ``degC``)     value - 20 .. value + 20 K
    TEC slopes (unit ``W/K``)               0 .. max(10 value, 1 W/K)
    effect powers (unit ``W``)              -10 .. +10 W
    angles (unit ``deg``)                   value - 360 .. value + 360
    other coefficients, biases              unbounded
    ======================================  =====================================================

    ``unit`` is the effect parameter's unit (looked up by :func:`fit_bounds`); without it
    an effect parameter is unbounded.
    """
    v = float(value)
    leaf = path.rsplit(".", 1)[-1]
    if leaf in ("capacity_j_per_k", "conductance_w_per_k"):
        return (v / 10.0, v * 10.0) if v > 0 else (0.0, 10.0)
    if leaf == "power_w" and path.startswith("thermal."):
        return (0.0, max(10.0 * v, 1.0)) if v >= 0 else (10.0 * v, 0.0)
    if path.startswith("thermometers."):
        if leaf == "lag_s":
            return (0.0, 300.0)
        if leaf == "offset_c":
            return (-2.0, 2.0)
        return (0.0, _INF)
    if leaf.startswith(("arw", "bias_instability", "rrw", "noise")):
        return (0.0, _INF)
    if leaf.startswith("tilt_"):
        return (-1.0, 1.0)
    if path.startswith("effects.") and unit is not None:
        if unit in ("s", "K"):
            return (v / 10.0, v * 10.0) if v > 0 else (0.0, _INF)
        if unit == "degC":
            return (v - 20.0, v + 20.0)
        if unit == "W/K":
            return (0.0, max(10.0 * v, 1.0))
        if unit == "W":
            return (-10.0, 10.0)
        if unit == "deg":
            return (v - 360.0, v + 360.0)
    return (-_INF, _INF)


def effect_unit(inst, path: str) -> str | None:
    """The unit of an effect parameter path (None for other paths)."""
    if not path.startswith("effects."):
        return None
    label, name = path[len("effects."):].rsplit(".", 1)
    return inst.effect(label).spec.parameter(name).unit


def fit_bounds(inst, path: str) -> tuple[float, float]:
    """:func:`default_bounds` of ``path`` at its value in ``inst``, effect units looked up,
    within the physical bounds an effect parameter is registered with (shupe_stress's c_m)."""
    path = canonical_path(inst, path)
    lo, hi = default_bounds(path, get_param(inst, path), effect_unit(inst, path))
    if path.startswith("effects."):
        label, name = path[len("effects."):].rsplit(".", 1)
        physical = inst.effect(label).spec.parameter(name).bounds
        if physical is not None:
            lo, hi = max(lo, physical[0]), min(hi, physical[1])
    return lo, hi
