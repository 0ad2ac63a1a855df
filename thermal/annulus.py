"""A thick-walled cylinder conducting radially, in N shells: a layered body of the network.

A body between radii r_i and r_o [m], of height h [m], conductivity k [W/(m K)] and
volumetric heat capacity rho c [J/(m^3 K)], heated or cooled through its two faces, is cut
into N coaxial shells, shell k (k = 1 .. N, from the inner face out) between r_(k-1) and
r_k: of equal thickness, r_k = r_i + (r_o - r_i) k / N (``spacing="uniform"``), or graded
toward both faces, r_k = r_i + (r_o - r_i) (1 - cos(pi k / N)) / 2 (``"cosine"``, the
Chebyshev-Lobatto points: heat enters and leaves through the faces, where the gradients are
steepest, so thinner shells there resolve them with fewer nodes).  Shell k is one node at
its mid-radius rho_k = (r_(k-1) + r_k) / 2 with the heat capacity of its volume,

    C_k = rho c pi (r_k^2 - r_(k-1)^2) h,                                               (1)

and two neighbouring nodes are joined by the conductance of the cylindrical shell between
their radii (steady radial conduction; Incropera and DeWitt (2007), Fundamentals of Heat and
Mass Transfer, 6th ed., eq. (3.33): R = ln(r_2 / r_1) / (2 pi k h)),

    G_k,k+1 = 2 pi k h / ln(rho_(k+1) / rho_k).                                        (2)

A face is the half shell between a face radius and the nearest node, G_face = 2 pi k h /
ln(rho_1 / r_i) (inner) or 2 pi k h / ln(r_o / rho_N) (outer), in series with the contacts
of that face to the nodes outside it (a hub, a housing, the chamber) [W/K].  The face itself
holds no heat, so it is eliminated exactly (a star of conductances to its mesh, Kron
reduction): with G_f the half shell and G_1 .. G_m the face's contacts, S = G_f + sum G_i,

    G(shell, node_i) = G_f G_i / S,     G(node_i, node_j) = G_i G_j / S,               (3)

(Doerfler and Bullo (2013)) and the face temperature is the mean of its neighbours
weighted by their conductances,

    T_face = (G_f T_shell + sum_i G_i T_i) / S                                          (4)

(:meth:`Annulus.face_weights`).  A face without contacts is adiabatic (T_face = T_shell).
The series of (2) and the half shells telescopes: the steady conductance of the whole wall
from face to face is 2 pi k h / ln(r_o / r_i) at every N, the exact one of a thick-walled
cylinder (eq. (3.33)); the capacities (1) add up to the whole volume's.

Only radial conduction is modelled: the body is one temperature over its height in each
shell (no axial split; an axial gradient needs an N x M grid of nodes).  A slab is the limit
r_i >> r_o - r_i.  The module knows nothing of what the body is (a fibre coil, a potted
winding): it makes :class:`~thermal.network.Node` and :class:`~thermal.network.Link`
objects for a :class:`~thermal.network.Network`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from thermal.errors import ThermalError
from thermal.network import Link, Node, finite_number

__all__ = ["Annulus", "SPACINGS"]

#: How the shells' boundaries are spaced across the wall (module docstring).
SPACINGS = ("uniform", "cosine")


def _contacts(value: Mapping[str, float], what: str) -> dict[str, float]:
    """A face's contacts {node: conductance [W/K]}, checked."""
    if not isinstance(value, Mapping):
        raise ThermalError(f"{what} must map node names to conductances [W/K], got {value!r}")
    out = {}
    for name, g in value.items():
        if not isinstance(name, str) or not name:
            raise ThermalError(f"{what}: node names must be non-empty strings, got {name!r}")
        g = finite_number(g, f"{what}.{name}")
        if g < 0.0:
            raise ThermalError(f"{what}.{name} must be >= 0 W/K, got {g}")
        out[name] = g
    return out


@dataclass(frozen=True)
class Annulus:
    """A thick-walled cylinder in ``n_layers`` radial shells (module docstring, (1)-(4))."""

    prefix: str
    """Node names are ``<prefix>_1`` (inner face) .. ``<prefix>_N`` (outer face)."""
    inner_radius_m: float
    """r_i, radius of the inner face [m], > 0."""
    outer_radius_m: float
    """r_o, radius of the outer face [m], > r_i."""
    height_m: float
    """h, height of the cylinder [m], > 0."""
    conductivity_w_per_m_k: float
    """k, radial thermal conductivity [W/(m K)], > 0."""
    heat_capacity_j_per_m3_k: float
    """rho c, volumetric heat capacity [J/(m^3 K)], > 0."""
    n_layers: int
    """N, the number of shells, >= 1."""
    inner_contacts: Mapping[str, float] = field(default_factory=dict)
    """Conductances [W/K] from the inner face to nodes outside the body (``chamber`` is one);
    none: the face is adiabatic."""
    outer_contacts: Mapping[str, float] = field(default_factory=dict)
    """Conductances [W/K] from the outer face to nodes outside the body."""
    spacing: str = "uniform"
    """``"uniform"`` (shells of equal thickness) or ``"cosine"`` (graded toward both faces)."""

    def __post_init__(self) -> None:
        if not isinstance(self.prefix, str) or not self.prefix:
            raise ThermalError(f"annulus prefix must be a non-empty string, got {self.prefix!r}")
        where = f"annulus {self.prefix!r}"
        for name in ("inner_radius_m", "outer_radius_m", "height_m",
                     "conductivity_w_per_m_k", "heat_capacity_j_per_m3_k"):
            value = finite_number(getattr(self, name), f"{where}: {name}")
            if value <= 0.0:
                raise ThermalError(f"{where}: {name} must be > 0, got {value}")
            object.__setattr__(self, name, value)
        if self.outer_radius_m <= self.inner_radius_m:
            raise ThermalError(f"{where}: outer_radius_m ({self.outer_radius_m}) must exceed "
                               f"inner_radius_m ({self.inner_radius_m})")
        if (isinstance(self.n_layers, bool) or not isinstance(self.n_layers, (int, np.integer))
                or self.n_layers < 1):
            raise ThermalError(f"{where}: n_layers must be an integer >= 1, "
                               f"got {self.n_layers!r}")
        object.__setattr__(self, "n_layers", int(self.n_layers))
        if self.spacing not in SPACINGS:
            raise ThermalError(f"{where}: spacing must be one of {', '.join(SPACINGS)}, got "
                               f"{self.spacing!r}")
        inner = _contacts(self.inner_contacts, f"{where}: inner_contacts")
        outer = _contacts(self.outer_contacts, f"{where}: outer_contacts")
        own = set(self.layer_names)
        for name in (*inner, *outer):
            if name in own:
                raise ThermalError(f"{where}: a face cannot touch its own shell {name!r}")
        object.__setattr__(self, "inner_contacts", inner)
        object.__setattr__(self, "outer_contacts", outer)

    # -- geometry

    @property
    def layer_names(self) -> tuple[str, ...]:
        """Node names of the shells, inner face first."""
        return tuple(f"{self.prefix}_{k}" for k in range(1, self.n_layers + 1))

    @property
    def edges_m(self) -> np.ndarray:
        """Shell boundaries r_0 = r_i, ..., r_N = r_o [m], shape (N + 1,)."""
        if self.spacing == "cosine":
            u = 0.5 * (1.0 - np.cos(np.pi * np.arange(self.n_layers + 1) / self.n_layers))
            u[[0, -1]] = 0.0, 1.0
            return self.inner_radius_m + (self.outer_radius_m - self.inner_radius_m) * u
        return np.linspace(self.inner_radius_m, self.outer_radius_m, self.n_layers + 1)

    @property
    def centres_m(self) -> np.ndarray:
        """Node radii rho_k, the shells' mid-radii [m], shape (N,)."""
        edges = self.edges_m
        return 0.5 * (edges[:-1] + edges[1:])

    @property
    def centres(self) -> np.ndarray:
        """Node positions across the wall, x_k = (rho_k - r_i) / (r_o - r_i) ((k - 1/2) / N
        for equal shells)."""
        return (self.centres_m - self.inner_radius_m) / (self.outer_radius_m - self.inner_radius_m)

    @property
    def capacities_j_per_k(self) -> np.ndarray:
        """C_k of (1) [J/K], shape (N,)."""
        edges = self.edges_m
        return (self.heat_capacity_j_per_m3_k * math.pi * self.height_m
                * (edges[1:] ** 2 - edges[:-1] ** 2))

    @property
    def capacity_j_per_k(self) -> float:
        """The whole body's heat capacity rho c pi (r_o^2 - r_i^2) h [J/K]."""
        return float(self.heat_capacity_j_per_m3_k * math.pi * self.height_m
                     * (self.outer_radius_m ** 2 - self.inner_radius_m ** 2))

    def _shell(self, r1: float, r2: float) -> float:
        """The conductance of the cylindrical shell between r1 < r2 [W/K], (2)."""
        return 2.0 * math.pi * self.conductivity_w_per_m_k * self.height_m / math.log(r2 / r1)

    @property
    def wall_conductance_w_per_k(self) -> float:
        """2 pi k h / ln(r_o / r_i): the steady conductance face to face [W/K]."""
        return self._shell(self.inner_radius_m, self.outer_radius_m)

    @property
    def half_shells_w_per_k(self) -> tuple[float, float]:
        """(G_face inner, G_face outer): the half shells between each face and its node."""
        rho = self.centres_m
        return (self._shell(self.inner_radius_m, rho[0]),
                self._shell(rho[-1], self.outer_radius_m))

    @property
    def diffusion_time_s(self) -> float:
        """(r_o - r_i)^2 rho c / k [s]: the wall's diffusion time d^2 / a.  The slowest
        radial mode of a flat wall with one face held and the other adiabatic decays with
        4 / pi^2 of it, with both faces held with 1 / pi^2 (Carslaw and Jaeger (1959),
        Conduction of Heat in Solids, sec. 3.3)."""
        d = self.outer_radius_m - self.inner_radius_m
        return d * d * self.heat_capacity_j_per_m3_k / self.conductivity_w_per_m_k

    # -- the network's parts

    def nodes(self) -> tuple[Node, ...]:
        """One passive node per shell, capacities (1)."""
        return tuple(Node(name, float(c))
                     for name, c in zip(self.layer_names, self.capacities_j_per_k))

    def links(self) -> tuple[Link, ...]:
        """The shells' conductances (2), then each face's contacts reduced by (3)."""
        names, rho = self.layer_names, self.centres_m
        out = [Link(names[k], names[k + 1], self._shell(rho[k], rho[k + 1]))
               for k in range(self.n_layers - 1)]
        g_in, g_out = self.half_shells_w_per_k
        out += _star_to_mesh(names[0], g_in, self.inner_contacts)
        out += _star_to_mesh(names[-1], g_out, self.outer_contacts)
        return tuple(out)

    def face_weights(self, face: str) -> dict[str, float]:
        """{node: weight} of the face temperature (4): T_face = sum weight T_node, weights
        summing to 1 (``face`` is ``"inner"`` or ``"outer"``); an adiabatic face is its
        shell's temperature."""
        if face not in ("inner", "outer"):
            raise ThermalError(f"face must be 'inner' or 'outer', got {face!r}")
        g_in, g_out = self.half_shells_w_per_k
        shell, g_f, contacts = ((self.layer_names[0], g_in, self.inner_contacts)
                                if face == "inner" else
                                (self.layer_names[-1], g_out, self.outer_contacts))
        total = g_f + sum(contacts.values())
        out = {shell: g_f / total}
        for name, g in contacts.items():
            out[name] = out.get(name, 0.0) + g / total
        return out


def _star_to_mesh(shell: str, g_face: float, contacts: Mapping[str, float]) -> list[Link]:
    """The links (3) that replace a massless face joined to ``shell`` by ``g_face`` and to
    each contact node by its conductance; no contacts: none (an adiabatic face)."""
    live = {name: g for name, g in contacts.items() if g > 0.0}
    if not live:
        return []
    total = g_face + sum(live.values())
    out = [Link(shell, name, g_face * g / total) for name, g in live.items()]
    names = list(live)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            out.append(Link(a, b, live[a] * live[b] / total))
    return out
