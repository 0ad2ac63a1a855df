"""The default list of structural alternatives a model's thermal structure is checked against.

The generic changes of :mod:`nfs.fit.structure` (a split node, an inserted node, a free
link, a thermometer that sits elsewhere, the TEC's set point) and, for a lumped two-node
coil, the coil wound in N_th layers (:mod:`nfs.fit.wound_alternative`).  Scored on held-out
thermometers by :mod:`nfs.fit.adequacy`; adopted in a chain by :mod:`nfs.fit.refine`.
"""

from __future__ import annotations

from ..instrument import Instrument
from .structure import (StructuralAlternative, free_link, housing_node, insert_node,
                        neighbours, split_node, tec_set_point, thermometer_weight)
from .wound_alternative import can_wind, wound_coil

__all__ = ["structural_alternatives"]


def structural_alternatives(inst: Instrument) -> list[StructuralAlternative]:
    """The small default list of generic alternatives of ``inst``'s thermal structure.

    Core nodes: the coil nodes, the source (electronics), every other powered node that
    carries no accelerometer (the board) and the housing (largest conductance to the
    chamber).  Splits: each coil node, the housing and the powered non-source nodes.
    Inserts: between each node of the FOG thermometer and the housing.  Links: every pair of
    core nodes not yet linked.  Thermometer: the FOG thermometer's share of each neighbour
    of its nodes, and of its first node; each accelerometer thermometer's share of each
    neighbour of its nodes (the mount it sits on).  The TEC law's set point, when the model
    has one.  A lumped coil whose two nodes are linked: the coil wound in 8 layers
    (:func:`~nfs.fit.wound_alternative.wound_coil`).  For the lumped preset: 4 splits,
    2 inserts, 4 links, 5 thermometer shares, the TEC set point and the wound coil.
    """
    net = inst.network
    g = inst.gyro
    housing = housing_node(inst)
    acc = set(inst.accelerometers.nodes.values())
    coil = [n for n in (g.coil_outer, g.coil_inner) if n]
    # a wound coil's layers are resolved already and their links are its own numbers
    # (nfs.coil): they are linked to, not split or cut
    layers = set(inst.coil.layer_names) if inst.coil is not None else set()
    powered = [n.name for n in net.nodes
               if n.power_w > 0 and n.name not in acc and n.name != g.source]
    shell = [housing] if housing else []
    core = list(dict.fromkeys(coil + [g.source] + powered + shell))
    out = [split_node(inst, n) for n in dict.fromkeys(coil + shell + powered)
           if n not in layers]
    fog_nodes = list(inst.thermometers["fog"].nodes)
    if housing:
        out += [insert_node(inst, n, housing) for n in fog_nodes
                if n != housing and n not in layers
                and any({l.a, l.b} == {n, housing} for l in inst.own_parts[1])]
    linked = {frozenset((l.a, l.b)) for l in net.links}
    for i, a in enumerate(core):
        for b in core[i + 1:]:
            if frozenset((a, b)) not in linked and not {a, b} <= layers:
                out.append(free_link(inst, a, b))
    # a thermometer sits on a face of a wound coil, never inside the winding
    inside = set(inst.coil.layer_names[1:-1]) if inst.coil is not None else set()
    near = [m for n in fog_nodes for m in neighbours(net, n)
            if m not in fog_nodes and m not in inside]
    out += [thermometer_weight(inst, "fog", m) for m in dict.fromkeys(near)]
    if len(fog_nodes) > 1:
        out.append(thermometer_weight(inst, "fog", fog_nodes[0]))
    for name, model in inst.thermometers.items():   # an accelerometer's on its mount
        if name == "fog":
            continue
        own = list(model.nodes)
        out += [thermometer_weight(inst, name, m) for m in dict.fromkeys(
            m for n in own for m in neighbours(net, n) if m not in own and m not in inside)]
    if any(e.name == "tec_power" for e in inst.effects):
        out.append(tec_set_point(inst))
    if can_wind(inst):
        out.append(wound_coil(inst))
    return out
