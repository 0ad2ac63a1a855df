"""Which parameters of an instrument a fit frees, and the box it keeps each one in.

The parameter paths themselves (``thermal.nodes.<node>.capacity_j_per_k``,
``effects.<label>.<param>``, ...), :func:`get_param`, :func:`set_params`,
:func:`list_params` and :func:`expand_paths` live in :mod:`nfs.parameters` (the simulator
draws a unit's parameters through them too) and are re-exported here; this module adds
:func:`default_bounds`, :func:`effect_unit` and :func:`fit_bounds`.
"""

from __future__ import annotations

import math

from .. import ranges
from ..parameters import (PARAM_KINDS, ParameterError, canonical_path, expand_paths,
                          get_param, list_params, param_kind, param_paths, set_params)

__all__ = ["ParameterError", "PARAM_KINDS", "get_param", "set_params", "list_params",
           "expand_paths", "param_kind", "param_paths", "default_bounds", "canonical_path",
           "effect_unit", "fit_bounds"]

_INF = math.inf

#: A wound coil's numbers whose box is relative to the value, as a capacity's or a link's
#: (:mod:`nfs.coil`): its material and its faces' contacts.
_COIL_RELATIVE = ("coil.conductivity_w_per_m_k", "coil.heat_capacity_j_per_m3_k",
                  "coil.inner_contacts.", "coil.outer_contacts.")


# ---------------------------------------------------------------------------------------------
# Bounds

#: How far beyond the typical range of :mod:`nfs.ranges` a box relative to the value (a
#: tenth to ten times it) may reach [factor]: a decade each way.
TYPICAL_REACH = 10.0


def default_bounds(path: str, value: float, unit: str | None = None) -> tuple[float, float]:
    """The box (lower, upper) a fit keeps parameter ``path`` (now at ``value``) in.

    ======================================  =====================================================
    parameter                               bounds
    ======================================  =====================================================
    capacities, conductances                value/10 .. value*10 (> 0: a network stays physical),
                                            anchored (below); a zero conductance 0 .. 10 W/K
    a wound coil's conductivity, heat       value/10 .. value*10, anchored (below), as
    capacity and face contacts              capacities and conductances
    a wound coil's radii and height         value/2 .. value*2 (its drawing: rarely freed)
    node powers                             0 .. max(10 value, 1 W) (negative: 10 value .. 0)
    thermometer lag_s                       0 .. 300 s, anchored (below) when > 0
    thermometer offset_c                    -2 .. +2 K
    noise, quantum, ARW, BI, RRW fields     0 .. inf
    tilts                                   -1 .. +1 deg
    effect time constants (unit ``s``),     value/10 .. value*10, anchored (below)
    temperature periods (unit ``K``)
    effect temperatures (unit ``degC``)     value - 20 .. value + 20 K
    TEC slopes (unit ``W/K``)               0 .. max(10 value, 1 W/K)
    effect powers (unit ``W``)              -10 .. +10 W
    angles (unit ``deg``)                   value - 360 .. value + 360
    other coefficients, biases              unbounded
    ======================================  =====================================================

    :func:`fit_bounds` cuts every box to the parameter's hard range in the table of ranges.

    ``unit`` is the effect parameter's unit (looked up by :func:`fit_bounds`); without it
    an effect parameter is unbounded.  Anchored: a box relative to the value stops a decade
    (:data:`TYPICAL_REACH`) beyond the parameter's typical range in :mod:`nfs.ranges`, the
    value itself kept inside (:func:`_anchored`).
    """
    v = float(value)
    leaf = path.rsplit(".", 1)[-1]
    if leaf in ("capacity_j_per_k", "conductance_w_per_k") or path.startswith(_COIL_RELATIVE):
        return _anchored(path, v, v / 10.0, v * 10.0) if v > 0 else (0.0, 10.0)
    if path.startswith("coil."):                                   # radii and height
        return (v / 2.0, v * 2.0)
    if leaf == "power_w" and path.startswith("thermal."):
        return (0.0, max(10.0 * v, 1.0)) if v >= 0 else (10.0 * v, 0.0)
    if path.startswith("thermometers."):
        if leaf == "lag_s":
            return _anchored(path, v, 0.0, 300.0) if v > 0 else (0.0, 300.0)
        if leaf == "offset_c":
            return (-2.0, 2.0)
        return (0.0, _INF)
    if leaf.startswith(("arw", "bias_instability", "rrw", "noise")):
        return (0.0, _INF)
    if leaf.startswith("tilt_"):
        return (-1.0, 1.0)
    if path.startswith("effects.") and unit is not None:
        if unit in ("s", "K"):
            return _anchored(path, v, v / 10.0, v * 10.0) if v > 0 else (0.0, _INF)
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
    return _within_hard(path, lo, hi)


def _within_hard(path: str, lo: float, hi: float) -> tuple[float, float]:
    """The box (lo, hi) cut to the hard range of ``path`` in the table of ranges
    (:func:`nfs.ranges.find`): a fitted model never holds a value the table calls impossible.
    A magnitude's hard range bounds |value|; an open low end of 0 is kept just above 0."""
    found = ranges.find(path)
    if found is None:
        return lo, hi
    h_lo, h_hi = found.hard
    if found.magnitude:
        h_lo = -h_hi
    elif found.low_open:
        h_lo = h_lo + max(abs(h_lo), 1.0) * 1e-12 if h_lo == 0 else h_lo
    new_lo, new_hi = max(lo, h_lo), min(hi, h_hi)
    return (new_lo, new_hi) if new_lo < new_hi else (lo, hi)


def _anchored(path: str, value: float, lo: float, hi: float) -> tuple[float, float]:
    """The relative box (lo, hi) of ``value`` cut to the typical range of ``path``
    (:func:`nfs.ranges.find`) widened by :data:`TYPICAL_REACH` each way, the value itself
    always kept inside.

    A box relative to the value moves with it: a fit that starts from another fit's result
    (a model file that is itself a fit, then the structure's refinement, then a candidate's
    refit) can take a capacity a decade further down at every link of the chain, to a coil
    of 0.1 J/K (three fits) that no winding has.  Anchored to the one table of ranges, a
    chain stops a decade beyond what real units have; a fit from a value inside the typical
    range keeps its box as it was (value/10 >= typical low/10, value*10 <= typical high*10),
    and a value already beyond the reach (a unit the table does not know) is not pushed
    back, only kept from going further.
    """
    found = ranges.find(path)
    if found is None:
        return lo, hi
    typ_lo, typ_hi = found.typical
    if typ_lo > 0:
        lo = max(lo, min(value, typ_lo / TYPICAL_REACH))
    if typ_hi > 0:
        hi = min(hi, max(value, typ_hi * TYPICAL_REACH))
    return lo, hi
