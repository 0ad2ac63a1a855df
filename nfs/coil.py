"""The FOG's coil as it is wound: N_th radial layers of potted fibre between spool and outer face.

An instrument's ``[coil]`` table describes the winding as a body (docs/physics.md, "the
wound coil"): its inner and outer winding radii and height [m], the potted winding's
effective conductivity [W/(m K)] and volumetric heat capacity [J/(m^3 K)], how many thermal
layers it is cut into, and the contact conductances [W/K] of its two faces to the nodes of
the ``[thermal]`` network (the spool or hub inside, a shield, the electronics or the housing
outside).  :class:`WoundCoil` turns these into the layers' nodes ``coil_1`` (spool) ..
``coil_N`` (outer face) and their links (:class:`thermal.Annulus`: capacities of the shells'
volumes, conduction through cylindrical shells, the faces reduced exactly), and tells
``shupe_winding`` where the layers sit (:class:`~nfs.effects.CoilLayout`).

::

    [coil]
    layers = 8                          # N_th thermal layers
    inner_radius_m = 0.0423             # winding radii and height
    outer_radius_m = 0.0477
    height_m = 0.02
    conductivity_w_per_m_k = 0.25       # fibre, acrylate and potting, across the layers
    heat_capacity_j_per_m3_k = 1.7e6
    inner_contacts = { spool = 3.0 }    # W/K from the winding's inner face
    outer_contacts = { electronics = 0.3, housing = 0.4 }

The layers are nodes of the instrument's network like any other (node temperatures, rates,
heat sources), but their numbers are not the instrument's own: a fit, a unit's scatter and a
parameter path change the coil's few numbers (``coil.conductivity_w_per_m_k``,
``coil.outer_contacts.housing``, ...) and the layers follow.  An instrument without
``[coil]`` keeps its two lumped coil nodes (``[gyro] coil_outer``, ``coil_inner``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

from thermal import Annulus, Link, Network, Node

from .docfields import document_fields
from .effects import CoilLayout
from .errors import ScenarioError, ThermalError
from .io.tomlio import check_keys, integer, number, table

__all__ = ["WoundCoil", "COIL_PREFIX", "coil_from_dict", "with_coil", "own_parts"]

#: The layers' nodes are ``coil_1`` (spool) .. ``coil_N`` (outer face).
COIL_PREFIX = "coil"

#: The numbers of a coil that are parameter paths ``coil.<name>`` (the layer count is not).
COIL_NUMBERS = ("inner_radius_m", "outer_radius_m", "height_m", "conductivity_w_per_m_k",
                "heat_capacity_j_per_m3_k")
#: Its faces' contact tables, paths ``coil.<face>.<node>`` [W/K].
COIL_FACES = ("inner_contacts", "outer_contacts")


@document_fields
@dataclass(frozen=True)
class WoundCoil:
    """The coil's winding as a layered body of the thermal network (module docstring)."""

    inner_radius_m: float
    """r_i, the winding's inner radius (on the spool) [m]."""
    outer_radius_m: float
    """r_o, its outer radius [m]; D = r_i + r_o is its mean diameter."""
    height_m: float
    """h, the winding's height along the coil axis [m]."""
    conductivity_w_per_m_k: float
    """k, the potted winding's effective radial conductivity [W/(m K)]."""
    heat_capacity_j_per_m3_k: float
    """rho c, its volumetric heat capacity [J/(m^3 K)]."""
    inner_contacts: tuple[tuple[str, float], ...]
    """(node, conductance [W/K]) from the inner face (the spool side); none: adiabatic."""
    outer_contacts: tuple[tuple[str, float], ...]
    """(node, conductance [W/K]) from the outer face; none: adiabatic."""
    layers: int = 8
    """N_th, the thermal layers the winding is cut into, graded toward both faces (cosine
    spacing, :class:`thermal.Annulus`): the Shupe bias of one coil over each dwell changes
    by under 2 % from 8 to 16 layers (by 3.7 % with shells of equal thickness)."""

    def __post_init__(self) -> None:
        for face in COIL_FACES:
            value = getattr(self, face)
            pairs = value.items() if isinstance(value, dict) else value
            object.__setattr__(self, face, tuple((str(k), float(v)) for k, v in pairs))
        self.annulus  # noqa: B018  (checks the geometry now: ThermalError)

    @functools.cached_property
    def annulus(self) -> Annulus:
        """The body (:class:`thermal.Annulus`) whose shells are the layers."""
        return Annulus(COIL_PREFIX, self.inner_radius_m, self.outer_radius_m, self.height_m,
                       self.conductivity_w_per_m_k, self.heat_capacity_j_per_m3_k,
                       self.layers, dict(self.inner_contacts), dict(self.outer_contacts),
                       spacing="cosine")

    @property
    def layer_names(self) -> tuple[str, ...]:
        """``coil_1`` (spool) .. ``coil_N`` (outer face)."""
        return self.annulus.layer_names

    @property
    def mean_diameter_m(self) -> float:
        """D = r_i + r_o [m]."""
        return self.inner_radius_m + self.outer_radius_m

    @property
    def capacity_j_per_k(self) -> float:
        """The winding's heat capacity [J/K]."""
        return self.annulus.capacity_j_per_k

    @property
    def radial_conductance_w_per_k(self) -> float:
        """2 pi k h / ln(r_o / r_i): its steady conductance face to face [W/K]."""
        return self.annulus.wall_conductance_w_per_k

    @property
    def radial_time_constant_s(self) -> float:
        """The slowest radial mode of the winding alone with its outer face held and its
        inner face adiabatic, 4 d^2 / (pi^2 a) [s] (a flat wall; Carslaw and Jaeger (1959),
        sec. 3.3): the scale on which heat arriving at one face reaches the other."""
        return 4.0 * self.annulus.diffusion_time_s / math.pi ** 2

    @functools.cached_property
    def layout(self) -> CoilLayout:
        """Where the layers sit across the winding, with the faces' temperatures."""
        ann = self.annulus
        return CoilLayout(layers=ann.layer_names, centres=tuple(ann.centres),
                          inner_face=ann.face_weights("inner"),
                          outer_face=ann.face_weights("outer"))

    def number(self, name: str) -> float:
        """``coil.<name>``: one of :data:`COIL_NUMBERS` or ``<face>.<node>``."""
        face, _, node = name.partition(".")
        if face in COIL_FACES:
            return dict(getattr(self, face))[node]
        return float(getattr(self, name))

    def with_numbers(self, values: dict[str, float]) -> "WoundCoil":
        """A copy with ``coil.<name>`` numbers changed (``values`` keyed by ``<name>``)."""
        kw: dict[str, Any] = {}
        faces = {face: dict(getattr(self, face)) for face in COIL_FACES}
        for name, value in values.items():
            face, _, node = name.partition(".")
            if face in COIL_FACES:
                faces[face][node] = float(value)
            else:
                kw[name] = float(value)
        return WoundCoil(**{**{f: getattr(self, f) for f in (*COIL_NUMBERS, "layers")},
                            **faces, **kw})

    def paths(self) -> list[str]:
        """The parameter paths ``coil.*`` of its numbers, in TOML order."""
        return ([f"coil.{n}" for n in COIL_NUMBERS]
                + [f"coil.{face}.{node}" for face in COIL_FACES
                   for node, _ in getattr(self, face)])

    def to_dict(self) -> dict[str, Any]:
        """The ``[coil]`` table."""
        out: dict[str, Any] = {"layers": self.layers}
        out.update({n: getattr(self, n) for n in COIL_NUMBERS})
        for face in COIL_FACES:
            out[face] = dict(getattr(self, face))
        return out


def coil_from_dict(tbl: dict[str, Any], file: Any, nodes: tuple[str, ...]) -> WoundCoil:
    """A :class:`WoundCoil` from an instrument's ``[coil]`` table, its contacts naming the
    ``[thermal]`` network's ``nodes`` or ``chamber``."""
    check_keys(tbl, ("layers", *COIL_NUMBERS, *COIL_FACES), "coil", file,
               required=(*COIL_NUMBERS, "outer_contacts"))
    kw: dict[str, Any] = {n: number(tbl, n, "coil", file, positive=True) for n in COIL_NUMBERS}
    kw["layers"] = integer(tbl, "layers", "coil", file, 8, minimum=1)
    for face in COIL_FACES:
        contacts = table(tbl, face, "coil", file, {})
        for node in contacts:
            if node != "chamber" and node not in nodes:
                raise ScenarioError(f"unknown node '{node}'; nodes of [thermal]: "
                                    f"{', '.join(nodes)}, or 'chamber'", file=file,
                                    key=f"coil.{face}.{node}")
            number(contacts, node, f"coil.{face}", file, minimum=0.0)
        kw[face] = tuple((k, float(v)) for k, v in contacts.items())
    try:
        return WoundCoil(**kw)
    except ThermalError as exc:
        raise ScenarioError(str(exc).replace(f"annulus '{COIL_PREFIX}': ", ""), file=file,
                            key="coil") from None


def with_coil(nodes: tuple[Node, ...], links: tuple[Link, ...], coil: WoundCoil) -> Network:
    """The network of the ``[thermal]`` ``nodes`` and ``links`` (which may link to the
    coil's layers) with the coil's layers and their links added after them."""
    ann = coil.annulus
    taken = {n.name for n in nodes} & set(ann.layer_names)
    if taken:
        raise ThermalError(f"node '{sorted(taken)[0]}' is a layer of the wound coil; "
                           f"[thermal] cannot define it")
    return Network(nodes=tuple(nodes) + ann.nodes(), links=tuple(links) + ann.links())


def own_parts(network: Network, coil: WoundCoil) -> tuple[tuple[Node, ...], tuple[Link, ...]]:
    """(nodes, links) of ``network`` that are not the coil's: the ``[thermal]`` parts
    :func:`with_coil` was given.  The links the coil made (its layers' own and each face's
    reduced contacts) are removed one occurrence each, from the end where :func:`with_coil`
    put them, so a link of ``[thermal]`` equal to one of them is kept."""
    layers = set(coil.layer_names)
    made = list(coil.annulus.links())
    kept: list[Link] = []
    for link in reversed(network.links):
        if link in made:
            made.remove(link)
        else:
            kept.append(link)
    if made:
        raise ThermalError("the network does not hold the wound coil's links")
    return (tuple(n for n in network.nodes if n.name not in layers), tuple(reversed(kept)))
