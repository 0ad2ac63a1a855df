"""The coil in N_th layers: a lumped two-node coil replaced by its wound form, as an alternative.

A lumped coil (``coil_outer``: the outer layers; ``coil_inner``: the inner layers with the
spool; one radial link between them) is the two-layer case of the wound coil
(:mod:`nfs.coil`, docs/physics.md "the wound coil").  On a unit whose start-up moves the
coil's radial field faster than two nodes can follow, the lumped network misses the
thermometers by a time constant and its Shupe terms (the rate of a two-node gradient) read
the wrong field.  :func:`wound_coil` builds the same instrument with its coil wound:

- the winding becomes N_th graded layers ``coil_1`` (spool) .. ``coil_N`` (outer face)
  between the radii of a navigation coil (the default preset's drawing), its height such
  that the winding holds C_w = C_outer [J/K] at the preset's rho c (1.7e6 J/(m^3 K));
- ``coil_inner`` becomes the hub ``spool`` (its capacity, its power and its links but the
  radial one), bonded to the winding's inner face as the preset's (3 W/K of epoxy);
- ``coil_outer``'s links but the radial one become the outer face's contacts (same
  conductances), and the radial link G_r [W/K] sets the winding's conductivity,
  k = G_r ln(r_o / r_i) / (2 pi h), so the face-to-face conductance starts where the model
  had it;
- thermometer weights on ``coil_outer`` move to the outer layer ``coil_N``, on
  ``coil_inner`` to the hub; an effect targeted at ``coil_outer`` moves to ``coil_N``, at
  ``coil_inner`` to the hub (a thermal effect) or to ``coil_1`` (a gyro effect);
- the lumped Shupe terms (``shupe_gradient``, ``shupe_rate``, ``shupe_stress``) become the
  Shupe integral over the winding, ``shupe_winding``: a 1 km quadrupole at the coil's mean
  diameter in the default preset's 64 optical layers, silica's dn/dT and expansion fixed by
  physics, the potting's stress term k_m and the halves' asymmetry L_asym free in the drift
  stage.

Its free numbers are the winding's height (its capacity, rho c of the potted fibre being a
material constant), its conductivity (its radial conductance, so its time constant), the
hub's capacity (the number the lumped inner node had), the hub's bond and each outer
contact, each in the box a fit gives it (:func:`nfs.fit.params.fit_bounds`: inside its hard
range in the table of ranges, :mod:`nfs.ranges`).  It is scored on
held-out thermometers as every structural alternative is (:mod:`nfs.fit.adequacy`);
:func:`nfs.fit.refine.fit_unit` keeps it only where the drift agrees
(:data:`DRIFT_KEEP`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import replace

from thermal import Link, Node

from ..coil import WoundCoil
from ..effects import get_effect, make_effect
from ..errors import NfsError
from ..instrument import Instrument, load_instrument
from .params import fit_bounds, get_param
from .structure import StructuralAlternative, new_node_name

__all__ = ["WOUND_KIND", "LUMPED_SHUPE", "DEFAULT_THERMAL_LAYERS", "can_wind", "wound_coil",
           "wound_name"]

#: The kind of the alternative (:attr:`StructuralAlternative.kind`).
WOUND_KIND = "wound"
#: The lumped Shupe terms :func:`wound_coil` replaces by ``shupe_winding``.
LUMPED_SHUPE = ("shupe_gradient", "shupe_rate", "shupe_stress")
#: Thermal layers of the wound coil: the default preset's, where one coil's Shupe bias over
#: each dwell changes by under 2 % from 8 to 16 layers (:class:`nfs.coil.WoundCoil`).
DEFAULT_THERMAL_LAYERS = 8


def wound_name(layers: int = DEFAULT_THERMAL_LAYERS) -> str:
    """The alternative's name, ``the coil in N layers``."""
    return f"the coil in {layers} layers"


@functools.lru_cache(maxsize=1)
def _navigation_coil():
    """The default preset's wound coil and its ``shupe_winding`` (1 km of fibre, a
    quadrupole of 64 optical layers, potted at 1.7e6 J/(m^3 K), bonded to its hub by 3 W/K of
    epoxy): a lumped
    model says neither its drawing nor its fibre, so the wound coil starts from these."""
    inst = load_instrument("default")
    return inst.coil, inst.effect("shupe_winding").params


def _coil_links(inst: Instrument):
    """(radial links, the outer node's other links) of a lumped coil."""
    outer, inner = inst.gyro.coil_outer, inst.gyro.coil_inner
    pair = {outer, inner}
    links = inst.own_parts[1]
    return ([l for l in links if {l.a, l.b} == pair],
            [l for l in links if outer in (l.a, l.b) and {l.a, l.b} != pair])


def can_wind(inst: Instrument) -> bool:
    """Whether ``inst``'s coil is lumped in two linked nodes, the outer one linked to
    something else too (what :func:`wound_coil` winds)."""
    if inst.coil is not None or inst.gyro.coil_outer == inst.gyro.coil_inner:
        return False
    radial, face = _coil_links(inst)
    return bool(radial and face)


def wound_coil(inst: Instrument, layers: int = DEFAULT_THERMAL_LAYERS
               ) -> StructuralAlternative:
    """``inst``'s lumped coil wound into ``layers`` thermal layers, as a structural
    alternative.

    The winding holds the lumped outer node's capacity between the radii of a navigation
    coil; the inner node becomes its hub (``spool``), bonded to the winding's inner face; the
    outer node's other links become the outer face's contacts and the radial link sets the
    winding's conductivity; thermometers and effects follow their nodes, and the lumped
    Shupe terms become ``shupe_winding`` (:mod:`nfs.fit.wound_alternative`).

    Returns
    -------
    StructuralAlternative
        ``.instrument`` the wound instrument at the start values; ``.free``, ``.start`` and
        ``.bounds`` its fitted numbers (the winding's height and conductivity, the hub's
        capacity, the hub's bond, each outer contact); ``.build(values)`` the instrument
        with them set.  ``nfs.fit.fit_unit`` tries it on a lumped model and keeps it where
        the held-out thermometers and the drift say so.

    Examples
    --------
    >>> import nfs
    >>> from nfs.fit import wound_coil
    >>> alt = wound_coil(nfs.load_instrument("lumped"))
    >>> alt.instrument.coil.layers, alt.instrument.gyro.coil_outer
    (8, 'coil_8')

    Raises
    ------
    NfsError
        ``inst``'s coil is wound already, or its two coil nodes are not linked.
    """
    if inst.coil is not None:
        raise NfsError("wound_coil: the coil is wound already ([coil])")
    outer, inner = inst.gyro.coil_outer, inst.gyro.coil_inner
    own_nodes, own_links = inst.own_parts
    by_name = {n.name: n for n in own_nodes}
    radial, face = _coil_links(inst)
    if not radial or outer == inner:
        raise NfsError(f"wound_coil: the coil nodes '{outer}' and '{inner}' are not linked "
                       "(no radial conductance to start the winding from)")
    if not face:
        raise NfsError(f"wound_coil: '{outer}' has no link but the radial one (its outer face "
                       "would be adiabatic)")
    g_r = sum(l.conductance_w_per_k for l in radial)
    c_w = by_name[outer].capacity_j_per_k
    nav, _ = _navigation_coil()
    r_i, r_o, rho_c = nav.inner_radius_m, nav.outer_radius_m, nav.heat_capacity_j_per_m3_k
    bond = sum(g for _, g in nav.inner_contacts)        # the winding's epoxy bond to its hub
    area = math.pi * (r_o ** 2 - r_i ** 2)
    h = min(max(c_w / (rho_c * area), 0.005), 0.05)    # inside the table's typical height
    k = g_r * math.log(r_o / r_i) / (2.0 * math.pi * h)

    hub = new_node_name(inst.network, "spool")
    outer_contacts: dict[str, float] = {}
    links = []
    for l in own_links:
        if l in radial:
            continue
        if outer in (l.a, l.b):
            other = l.b if l.a == outer else l.a
            other = hub if other == inner else other
            outer_contacts[other] = outer_contacts.get(other, 0.0) + l.conductance_w_per_k
        elif inner in (l.a, l.b):
            a, b = (hub if x == inner else x for x in (l.a, l.b))
            links.append(Link(a, b, l.conductance_w_per_k))
        else:
            links.append(l)
    coil = WoundCoil(inner_radius_m=r_i, outer_radius_m=r_o, height_m=h,
                     conductivity_w_per_m_k=k, heat_capacity_j_per_m3_k=rho_c,
                     inner_contacts=((hub, bond),),
                     outer_contacts=tuple(outer_contacts.items()), layers=layers)
    first, last = coil.layer_names[0], coil.layer_names[-1]
    nodes = []
    for n in own_nodes:
        if n.name == outer:
            continue
        if n.name == inner:
            n = Node(hub, n.capacity_j_per_k, n.power_w + by_name[outer].power_w)
        nodes.append(n)

    thermal_map = {outer: last, inner: hub}
    thermos = {}
    for name, th in inst.thermometers.items():
        w: dict[str, float] = {}
        for node, wt in th.nodes.items():
            node = thermal_map.get(node, node)
            w[node] = w.get(node, 0.0) + wt
        thermos[name] = replace(th, nodes=w)
    effects = _wound_effects(inst, coil, {outer: last, inner: first}, thermal_map)
    gyro = replace(inst.gyro, coil_outer=last, coil_inner=first)
    base = replace(inst, coil=coil, gyro=gyro, thermometers=thermos)
    new = base.with_own_parts(nodes, links).with_effects(effects)

    free = (["coil.height_m", "coil.conductivity_w_per_m_k",
             f"thermal.nodes.{hub}.capacity_j_per_k", f"coil.inner_contacts.{hub}"]
            + [f"coil.outer_contacts.{n}" for n in outer_contacts])
    start = [get_param(new, p) for p in free]
    bounds = [fit_bounds(new, p) for p in free]
    return StructuralAlternative(
        name=wound_name(layers), kind=WOUND_KIND,
        description=(f"winds the coil: {outer} and {inner} become {layers} graded layers "
                     f"of a winding ({c_w:.4g} J/K, {g_r:.3g} W/K face to face) on a hub "
                     f"'{hub}', its Shupe terms the integral over the winding; capacity, "
                     "radial conductance and face contacts to fit"),
        instrument=new, free=tuple(free), start=tuple(start), bounds=tuple(bounds))


def _wound_effects(inst: Instrument, coil: WoundCoil, gyro_map: dict[str, str],
                   thermal_map: dict[str, str]) -> list:
    """The effects of ``inst`` on the wound coil: targets moved, the lumped Shupe terms
    replaced by one ``shupe_winding`` where the model had any."""
    out, shupe = [], False
    for e in inst.effects:
        if e.name in LUMPED_SHUPE:
            shupe = True
            continue
        spec = get_effect(e.name)
        mapping = thermal_map if spec.kind == "thermal" else gyro_map
        params = dict(e.params)
        for key, value in params.items():
            if isinstance(value, str) and value in mapping:
                params[key] = mapping[value]
        out.append(make_effect(e.name, params) if params != dict(e.params) else e)
    if shupe and not any(e.name == "shupe_winding" for e in out):
        # the navigation coil's fibre, pattern and optical layers at this coil's diameter;
        # the potting's stress term and the halves' asymmetry start at 0 (the drift fits them)
        fibre = _navigation_coil()[1]
        out.append(make_effect("shupe_winding", {
            "L": fibre["L"], "D": coil.mean_diameter_m, "pattern": fibre["pattern"],
            "N_opt": fibre["N_opt"], "k_m": 0.0, "L_asym": 0.0}))
    return out

