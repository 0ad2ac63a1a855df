"""Is the model's thermal structure adequate?  Generic structural alternatives and a verdict.

A thermal candidate of the diagnosis (a heat source, a motor heat pulse, a TEC law on a node,
an extra thermometer lag) is a *named* change of a lumped network (docs/physics.md section 2,
equation C_j dT_j/dt = sum_k G_jk (T_k - T_j) + G_j,amb (T_amb - T_j) + P_j).  When the
network itself is wrong (a coil of several radial layers lumped into two nodes, a
thermometer that does not sit where the model puts it, another TEC law) some named
candidate still lowers the thermometer residual, with an unphysical value (a negative heat
source).  This module supplies the yardstick: *generic* structural alternatives of the
same network, each with one to three free numbers, and a verdict on the model's structure.

Alternatives (the list :func:`nfs.fit.adequacy.structural_alternatives` makes; each is a new
:class:`~nfs.instrument.Instrument` and its free parameter paths):

- ``split``: node X becomes X (half the capacity, every link, its power, the thermometer
  weights) and X_2 (the other half), linked by a conductance G [W/K] to fit: one more time
  constant C/(2G) inside X (the coil's radial layers, a housing of base and lid);
- ``insert``: the link X-housing (G_0) is replaced by X-X_mid-housing, a node of capacity
  C_mid [J/K] with two conductances (start 2 G_0 each: the same steady state);
- ``link``: a conductance G [W/K] >= 0 between two nodes of the coil, electronics, board
  and housing that the model does not link;
- ``thermometer``: the FOG thermometer reads a fraction f of another node (a neighbour of
  its nodes), or another mix of its own nodes; an accelerometer's thermometer reads a
  fraction of its mount;
- ``tec``: the TEC law's set point free (:func:`tec_set_point`).  Paths ``thermometers.<t>.nodes.<node>``
  (the fraction f in [0, 1] of that node in the sensed temperature; the other nodes keep
  their relative weights and share 1 - f) are not :mod:`nfs.fit.params` paths:
  :meth:`StructuralAlternative.build` sets them (:func:`set_thermometer_fraction`).

Scoring and the verdict on the structure: :mod:`nfs.fit.adequacy`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence


from thermal import CHAMBER, Link, Network, Node

from ..effects import get_effect, make_effect
from ..errors import NfsError, moved_names
from ..instrument import Instrument
from .params import set_params

__all__ = ["StructuralAlternative", "split_node", "insert_node", "free_link",
           "thermometer_weight", "tec_set_point", "effect_alternative",
           "set_thermometer_fraction", "physical_lower", "positive_parameter", "new_node_name", "housing_node", "neighbours"]

_WEIGHT = ".nodes."
_PHYSICAL_LOWER = {("heat_source", "power"): 0.0, ("motor_heat", "power"): 0.0,
                   ("tec_power", "c_h"): 0.0, ("tec_power", "c_c"): 0.0,
                   ("thermometer_lag", "tau"): 0.0}


# ---------------------------------------------------------------------------------------------
# Alternatives

def _is_weight(path: str) -> bool:
    return path.startswith("thermometers.") and _WEIGHT in path


def set_thermometer_fraction(inst: Instrument, thermometer: str, node: str,
                             fraction: float) -> Instrument:
    """``inst`` with ``node`` making up ``fraction`` of the sensed temperature of a thermometer.

    T_sensed = (1 - f) sum_j w_j T_j / sum_j w_j + f T_node over the thermometer's other
    nodes j (docs/physics.md section 2: a thermometer between nodes reads a weighted mean);
    f = 0 removes ``node`` from the thermometer.
    """
    if thermometer not in inst.thermometers:
        raise NfsError(f"no thermometer '{thermometer}'; thermometers: "
                       + ", ".join(inst.thermometers))
    if node not in inst.network.node_names:
        raise NfsError(f"thermometer '{thermometer}': unknown node '{node}'; nodes: "
                       + ", ".join(inst.network.node_names))
    f = float(fraction)
    if not 0.0 <= f <= 1.0:
        raise NfsError(f"thermometer '{thermometer}': fraction of '{node}' must be in [0, 1], "
                       f"got {f}")
    model = inst.thermometers[thermometer]
    others = {k: w for k, w in model.nodes.items() if k != node}
    total = sum(others.values())
    if total <= 0.0:
        f = 1.0
    weights = {k: (1.0 - f) * w / total for k, w in others.items() if f < 1.0}
    if f > 0.0:
        weights[node] = f
    thermos = dict(inst.thermometers)
    thermos[thermometer] = replace(model, nodes=weights)
    return replace(inst, thermometers=thermos)


@dataclass(frozen=True)
class StructuralAlternative:
    """One generic change of the thermal structure, with its free numbers."""

    name: str
    """Short name, e.g. ``link electronics-coil_inner``."""
    kind: str
    """``split``, ``insert``, ``link``, ``thermometer``, ``tec`` or ``effect`` (a named
    candidate)."""
    description: str
    """One sentence: what it changes."""
    instrument: Instrument
    """The changed instrument at the start values."""
    free: tuple[str, ...]
    """Paths of the new free numbers (:mod:`nfs.fit.params`; thermometer fractions are
    ``thermometers.<t>.nodes.<node>``, set by :func:`set_thermometer_fraction`)."""
    start: tuple[float, ...]
    """Start values, in the units of the paths."""
    bounds: tuple[tuple[float, float], ...]
    """(lower, upper) of each free number."""

    def build(self, values: Sequence[float]) -> Instrument:
        """The instrument with the free numbers set to ``values``."""
        out = self.instrument
        plain = {}
        for p, v in zip(self.free, values):
            if _is_weight(p):
                t, node = p[len("thermometers."):].split(_WEIGHT, 1)
                out = set_thermometer_fraction(out, t, node, min(max(float(v), 0.0), 1.0))
            else:
                plain[p] = float(v)
        return set_params(out, plain) if plain else out


def housing_node(inst: Instrument) -> str | None:
    """The node with the largest conductance to the chamber (the housing/base)."""
    best, g_best = None, 0.0
    for link in inst.network.links:
        if CHAMBER in (link.a, link.b) and link.conductance_w_per_k > g_best:
            best = link.b if link.a == CHAMBER else link.a
            g_best = link.conductance_w_per_k
    return best


def neighbours(net: Network, node: str) -> list[str]:
    out = []
    for link in net.links:
        if node in (link.a, link.b):
            other = link.b if link.a == node else link.a
            if other != CHAMBER:
                out.append(other)
    return list(dict.fromkeys(out))


def new_node_name(net: Network, base: str) -> str:
    """``base``, or ``base2``, ``base3`` ... the first that names no node of ``net``."""
    name, i = base, 2
    while name in net.node_names:
        name, i = f"{base}{i}", i + 1
    return name


def _link_path(a: str, b: str) -> str:
    return f"thermal.links.{a}-{b}.conductance_w_per_k"


def split_node(inst: Instrument, node: str) -> StructuralAlternative:
    """Node X -> X and X_2, half the capacity C/2 [J/K] each, linked by G [W/K] (to fit).

    X keeps every link, its power and the thermometer weights; X_2 is reached only through
    G: one more time constant C / (2 G) [s] inside X.  G starts at a quarter of X's total
    conductance to its neighbours (so that C/(2G) is a few minutes) and is kept within
    1/100..100 times that.
    """
    net = inst.network
    own_nodes, own_links = inst.own_parts
    j = [n.name for n in own_nodes].index(node)
    old = own_nodes[j]
    twin = new_node_name(net, f"{node}_2")
    half = 0.5 * old.capacity_j_per_k
    g_all = sum(l.conductance_w_per_k for l in net.links if node in (l.a, l.b))
    g0 = 0.25 * g_all if g_all > 0 else 0.1
    nodes = list(own_nodes)
    nodes[j] = replace(old, capacity_j_per_k=half)
    nodes.insert(j + 1, Node(twin, half))
    new = inst.with_own_parts(nodes, own_links + (Link(node, twin, g0),))
    return StructuralAlternative(
        name=f"split {node}", kind="split",
        description=(f"splits {node} into two halves of {half:.4g} J/K linked by a conductance "
                     f"to fit; {node} keeps its links, power and thermometer weights"),
        instrument=new, free=(_link_path(node, twin),), start=(g0,),
        bounds=((g0 / 100.0, g0 * 100.0),))


def insert_node(inst: Instrument, node: str, to: str | None = None) -> StructuralAlternative:
    """The link X-``to`` (G_0) becomes X - X_mid - ``to``: a node of capacity C_mid [J/K].

    C_mid starts at C_X / 3, the two conductances at 2 G_0 [W/K] each (the same series
    conductance, so the same steady state); all three are fitted within 1/100..100 times
    their start.  ``to`` defaults to the housing (the node with the largest conductance to
    the chamber).
    """
    net = inst.network
    own_nodes, own_links = inst.own_parts      # a wound coil's own links are not cut
    to = to or housing_node(inst)
    links = [l for l in own_links if {l.a, l.b} == {node, to}]
    if not links:
        raise NfsError(f"insert_node: no link {node}-{to} in instrument '{inst.name}'")
    g0 = sum(l.conductance_w_per_k for l in links)
    mid = new_node_name(net, f"{node}_mid")
    c0 = net.nodes[net.index(node)].capacity_j_per_k / 3.0
    kept = tuple(l for l in own_links if l not in links)
    new = inst.with_own_parts(own_nodes + (Node(mid, c0),),
                              kept + (Link(node, mid, 2 * g0), Link(mid, to, 2 * g0)))
    free = (f"thermal.nodes.{mid}.capacity_j_per_k", _link_path(node, mid), _link_path(mid, to))
    start = (c0, 2 * g0, 2 * g0)
    return StructuralAlternative(
        name=f"insert node {node}-{to}", kind="insert",
        description=(f"puts a node of fitted capacity between {node} and {to} (the "
                     f"{node}-{to} link becomes two links through it)"),
        instrument=new, free=free, start=start,
        bounds=tuple((v / 100.0, v * 100.0) for v in start))


def free_link(inst: Instrument, a: str, b: str) -> StructuralAlternative:
    """A new conductance G [W/K] between nodes a and b, from 0 (bounds 0..5 W/K)."""
    net = inst.network
    for n in (a, b):
        net.index(n)  # thermal.ThermalError (one of USER_ERRORS) listing the valid nodes
    if any({l.a, l.b} == {a, b} for l in net.links):
        raise NfsError(f"free_link: {a} and {b} are linked already in '{inst.name}'")
    own_nodes, own_links = inst.own_parts
    new = inst.with_own_parts(own_nodes, own_links + (Link(a, b, 0.0),))
    return StructuralAlternative(
        name=f"link {a}-{b}", kind="link",
        description=f"adds a conductance between {a} and {b}, which the model does not link",
        instrument=new, free=(_link_path(a, b),), start=(0.0,), bounds=((0.0, 5.0),))


def thermometer_weight(inst: Instrument, thermometer: str, node: str) -> StructuralAlternative:
    """The thermometer reads a fraction f in [0, 1] of ``node`` (a new or one of its own).

    For a node it does not read, f starts at 0 (the model); for one of its own nodes, f
    starts at that node's present share (the others keep their relative weights).
    """
    if thermometer not in inst.thermometers:
        raise NfsError(f"no thermometer '{thermometer}'; thermometers: "
                       + ", ".join(inst.thermometers))
    model = inst.thermometers[thermometer]
    f0 = model.nodes.get(node, 0.0) / sum(model.nodes.values())
    what = (f"lets the {thermometer} thermometer read another mix of its nodes (the share of "
            f"{node} fitted)" if node in model.nodes else
            f"lets the {thermometer} thermometer read a fitted share of {node} (it sits "
            "elsewhere than the model puts it)")
    return StructuralAlternative(
        name=f"{thermometer} thermometer share of {node}", kind="thermometer",
        description=what, instrument=inst, free=(f"thermometers.{thermometer}.nodes.{node}",),
        start=(f0,), bounds=((0.0, 1.0),))


def tec_set_point(inst: Instrument) -> StructuralAlternative:
    """The TEC law's set point T_set [degC] free (+-10 K about the model's): a source held at
    another temperature than the model says draws its heating and cooling power on other
    sides of another temperature, which shifts the warm-up by start temperature."""
    tec = next((e for e in inst.effects if e.name == "tec_power"), None)
    if tec is None:
        raise NfsError(f"tec_set_point: '{inst.name}' has no tec_power law")
    t_set = float(tec.params["T_set"])
    return StructuralAlternative(
        name="tec set point", kind="tec",
        description=f"frees the TEC law's set point (the model's {t_set:g} C)",
        instrument=inst, free=(f"effects.{tec.label}.T_set",), start=(t_set,),
        bounds=((t_set - 10.0, t_set + 10.0),))


def physical_lower(effect: str, parameter: str) -> float | None:
    """The physical lower bound of a thermal candidate's coefficient, or None.

    A heat source or a motor heat pulse dissipates power >= 0 W (a resistor does not cool);
    the TEC slopes c_h, c_c >= 0 W/K (docs/effects.md: the TEC draws *more* power away from its
    set point); a thermometer lag tau >= 0 s (causality).
    """
    return _PHYSICAL_LOWER.get((effect, parameter))


def positive_parameter(effect: str, parameter: str) -> bool:
    """Whether an effect's parameter is a positive quantity, whose interval is made on its
    log (:func:`nfs.scoring.intervals.positive_interval`): a coefficient whose physical lower
    bound is 0 (:func:`physical_lower`: a power, a TEC slope, a lag) or a shape measured in
    seconds or kelvin (a time constant, a temperature period)."""
    if physical_lower(effect, parameter) == 0.0:
        return True
    p = get_effect(effect).parameter(parameter)
    return p.nonlinear and p.unit in ("s", "K")


def effect_alternative(inst: Instrument, effect: str, target: str | None = None
                       ) -> StructuralAlternative:
    """A named thermal candidate (``heat_source`` on a node, ...) in the same machinery.

    Its coefficients start at 0 within their physical bounds (:func:`physical_lower`; upper
    10 W, 1 W/K or 300 s), so that its CV RMS is comparable with the structural
    alternatives'.  Kind ``effect``: scored, but never the best *structural* alternative.
    """
    spec = get_effect(effect)
    if spec.kind not in ("thermal", "thermometer"):
        raise NfsError(f"effect_alternative: '{effect}' is a {spec.kind} effect, not thermal")
    params: dict[str, Any] = {}
    if spec.target is not None and target is not None:
        params[spec.target] = target
    free, bounds = [], []
    upper = {"W": 10.0, "W/K": 1.0, "s": 300.0}
    for p in spec.parameters:
        if p.type is not float or p.name == spec.target:
            continue
        if p.unit == "degC":
            params[p.name] = p.default
            continue
        params[p.name] = 0.0
        lo = physical_lower(effect, p.name)
        hi = upper.get(p.unit, 10.0)
        free.append(p.name)
        bounds.append((-hi if lo is None else lo, hi))
    e = make_effect(effect, params)
    if any(x.label == e.label for x in inst.effects):
        raise NfsError(f"effect_alternative: instrument '{inst.name}' has {e.label} already")
    return StructuralAlternative(
        name=e.label, kind="effect", description=f"adds the effect {e.label}",
        instrument=inst.with_effects(list(inst.effects) + [e]),
        free=tuple(f"effects.{e.label}.{n}" for n in free), start=(0.0,) * len(free),
        bounds=tuple(bounds))


#: Names that lived here before, and where they are now.
_MOVED = {"structural_alternatives": "nfs.fit.adequacy"}
__getattr__ = moved_names("nfs.fit.structure", _MOVED)
