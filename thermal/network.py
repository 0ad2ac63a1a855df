"""Lumped thermal network: nodes, links to each other and to the chamber (docs/physics.md section
2).

Node j has a heat capacity C_j [J/K], a constant heat input P_j [W] and conductances G_jk
[W/K] to other nodes and G_j,amb [W/K] to the chamber, the boundary at temperature
T_amb(t) [degC]:

    C_j dT_j/dt = sum_k G_jk (T_k - T_j) + G_j,amb (T_amb(t) - T_j) + P_j(t, T)        (1)

Written for all nodes at once, with the conductance Laplacian L (L_jj = sum_k G_jk +
G_j,amb, L_jk = -G_jk) and g = (G_1,amb, ..., G_n,amb):

    dT/dt = A T + B u,   A = -C^-1 L,   B = [C^-1 g | C^-1],   u = [T_amb, P_1, ..., P_n]   (2)

A is similar to the symmetric matrix -C^-1/2 L C^-1/2, so its eigenvalues are real and
non-positive; -1/lambda are the network's time constants.

The network knows nothing of gyros; :mod:`thermal.solve` integrates (2) exactly.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from thermal.errors import ThermalError

__all__ = ["CHAMBER", "Node", "Link", "Network"]

#: Reserved node name of the boundary (the climatic chamber) at temperature T_amb(t).
CHAMBER: str = "chamber"


def finite_number(value: object, what: str) -> float:
    """``value`` as a float, or a :class:`ThermalError` naming ``what``."""
    if isinstance(value, bool):
        raise ThermalError(f"{what} must be a number, got {value!r}")
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ThermalError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise ThermalError(f"{what} must be finite, got {number}")
    return number


def index_of(names: Sequence[str], name: str) -> int:
    """Position of ``name`` in ``names``; a :class:`ThermalError` listing the valid names."""
    try:
        return list(names).index(name)
    except ValueError:
        valid = ", ".join(repr(n) for n in names)
        raise ThermalError(f"unknown node {name!r}; valid nodes: {valid}") from None


@dataclass(frozen=True)
class Node:
    """A lumped body at one temperature."""

    name: str
    """Unique node name, e.g. ``"housing"`` (``"chamber"`` is reserved for the boundary)."""

    capacity_j_per_k: float
    """Heat capacity C_j [J/K], > 0."""

    power_w: float = 0.0
    """Constant heat input P_j [W] (negative for a constant heat sink)."""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ThermalError(f"node name must be a non-empty string, got {self.name!r}")
        if self.name == CHAMBER:
            raise ThermalError(f"node name {CHAMBER!r} is reserved for the boundary")
        capacity = finite_number(self.capacity_j_per_k,
                                  f"node {self.name!r}: capacity_j_per_k")
        if capacity <= 0.0:
            raise ThermalError(f"node {self.name!r}: capacity_j_per_k must be > 0, "
                               f"got {capacity}")
        power = finite_number(self.power_w, f"node {self.name!r}: power_w")
        object.__setattr__(self, "capacity_j_per_k", capacity)
        object.__setattr__(self, "power_w", power)


@dataclass(frozen=True)
class Link:
    """A thermal conductance between two nodes, or between a node and the chamber."""

    a: str
    """Name of one end: a node name or ``"chamber"``."""

    b: str
    """Name of the other end: a node name or ``"chamber"``."""

    conductance_w_per_k: float
    """Conductance G_ab [W/K], >= 0 (heat flow G_ab (T_a - T_b) from a to b)."""

    def __str__(self) -> str:
        return f"link {self.a!r}-{self.b!r}"

    def __post_init__(self) -> None:
        for end in (self.a, self.b):
            if not isinstance(end, str) or not end:
                raise ThermalError(f"link ends must be non-empty strings, got "
                                   f"{self.a!r}-{self.b!r}")
        if self.a == self.b:
            raise ThermalError(f"{self}: links {self.a!r} to itself")
        conductance = finite_number(self.conductance_w_per_k,
                                     f"{self}: conductance_w_per_k")
        if conductance < 0.0:
            raise ThermalError(f"{self}: conductance_w_per_k must be >= 0, got {conductance}")
        object.__setattr__(self, "conductance_w_per_k", conductance)


@dataclass(frozen=True)
class Network:
    """Nodes and the links between them; the linear system (2) of the module docstring.

    Parallel links between the same two ends add their conductances.
    """

    nodes: tuple[Node, ...]
    """The nodes; their order is the order of every state vector and result column."""

    links: tuple[Link, ...]
    """The conductances between nodes and to the chamber."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "nodes", tuple(self.nodes))
        object.__setattr__(self, "links", tuple(self.links))
        if not self.nodes:
            raise ThermalError("network has no nodes")
        seen: set[str] = set()
        for node in self.nodes:
            if not isinstance(node, Node):
                raise ThermalError(f"network nodes must be Node objects, got {node!r}")
            if node.name in seen:
                raise ThermalError(f"duplicate node name {node.name!r}")
            seen.add(node.name)
        valid = ", ".join(repr(n.name) for n in self.nodes)
        for link in self.links:
            if not isinstance(link, Link):
                raise ThermalError(f"network links must be Link objects, got {link!r}")
            for end in (link.a, link.b):
                if end != CHAMBER and end not in seen:
                    raise ThermalError(f"{link}: unknown node {end!r}; valid nodes: {valid}, "
                                       f"{CHAMBER!r}")

    @property
    def node_names(self) -> tuple[str, ...]:
        """Node names in state-vector order."""
        return tuple(node.name for node in self.nodes)

    def index(self, name: str) -> int:
        """Position of node ``name`` in the state vector."""
        return index_of(self.node_names, name)

    @property
    def capacity_j_per_k(self) -> np.ndarray:
        """C = (C_1, ..., C_n) [J/K]."""
        return np.array([node.capacity_j_per_k for node in self.nodes])

    @property
    def node_power_w(self) -> np.ndarray:
        """Constant node powers (P_1, ..., P_n) [W]."""
        return np.array([node.power_w for node in self.nodes])

    def conductances(self) -> tuple[np.ndarray, np.ndarray]:
        """(L, g): conductance Laplacian L [W/K] (n, n) and chamber conductances g [W/K] (n,).

        C dT/dt = -L T + g T_amb + P is equation (1) for all nodes.  New arrays at every
        call (of :attr:`_system`, which the network keeps).
        """
        laplacian, to_chamber, _, _ = self._system
        return laplacian.copy(), to_chamber.copy()

    def matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) of dT/dt = A T + B u with u = [T_amb, P_1, ..., P_n].

        A = -C^-1 L [1/s], shape (n, n); B = [C^-1 g | diag(C^-1)], shape (n, 1 + n), its
        first column in [1/s] (multiplies T_amb [degC]) and the others in [K/J] (multiply
        the total node powers P_j [W], constants included).  New arrays at every call (of
        :attr:`_system`, which the network keeps).
        """
        _, _, a, b = self._system
        return a.copy(), b.copy()

    @functools.cached_property
    def _system(self) -> tuple[np.ndarray, ...]:
        """(L, g, A, B) of :meth:`conductances` and :meth:`matrices`, read-only, made once
        per network (it is frozen): a solve asks for them once per run, and assembling
        them link by link costs more than the copies (0.36 ms against 2 us for the default
        instrument's network; a sweep's soaks ask for them at every start-up)."""
        n = len(self.nodes)
        where = {name: j for j, name in enumerate(self.node_names)}
        laplacian = np.zeros((n, n))
        to_chamber = np.zeros(n)
        for link in self.links:
            g = link.conductance_w_per_k
            if CHAMBER in (link.a, link.b):
                j = where[link.b if link.a == CHAMBER else link.a]
                to_chamber[j] += g
                laplacian[j, j] += g
            else:
                j, k = where[link.a], where[link.b]
                laplacian[j, j] += g
                laplacian[k, k] += g
                laplacian[j, k] -= g
                laplacian[k, j] -= g
        inv_c = 1.0 / self.capacity_j_per_k
        a = -inv_c[:, None] * laplacian
        b = np.column_stack([inv_c * to_chamber, np.diag(inv_c)])
        for m in (laplacian, to_chamber, a, b):
            m.flags.writeable = False
        return laplacian, to_chamber, a, b

    def floating_nodes(self) -> tuple[str, ...]:
        """Nodes with no path of positive conductance to the chamber (no steady state)."""
        reached = {CHAMBER}
        grew = True
        while grew:
            grew = False
            for link in self.links:
                if link.conductance_w_per_k > 0.0 and (link.a in reached) != (link.b in reached):
                    reached.update((link.a, link.b))
                    grew = True
        return tuple(name for name in self.node_names if name not in reached)

    def steady_state(self, ambient_c: float, power_w: Sequence[float] | np.ndarray | None = None
                     ) -> np.ndarray:
        """Steady temperatures [degC] (n,): the solution of L T = g T_amb + P.

        Parameters
        ----------
        ambient_c : float
            Chamber temperature T_amb [degC].
        power_w : array_like (n,), optional
            Extra power per node [W], added to the constant node powers.
        """
        floating = self.floating_nodes()
        if floating:
            raise ThermalError(f"no steady state: nodes {', '.join(map(repr, floating))} have "
                               f"no conducting path to {CHAMBER!r}")
        laplacian, to_chamber = self.conductances()
        power = self.node_power_w
        if power_w is not None:
            extra = np.asarray(power_w, dtype=float)
            if extra.shape != power.shape:
                raise ThermalError(f"steady_state: power_w must have shape {power.shape}, "
                                   f"got {extra.shape}")
            power = power + extra
        ambient = finite_number(ambient_c, "steady_state: ambient_c")
        return np.linalg.solve(laplacian, to_chamber * ambient + power)

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Free modes of (2): time constants tau_i [s], longest first, and shapes V (n, n).

        With no input, T(t) - T_amb = sum_i a_i v_i exp(-t / tau_i).  From the symmetric
        form S = C^-1/2 L C^-1/2 = U diag(mu) U^T, A = -C^-1/2 S C^1/2, so column i of V is
        v_i = C^-1/2 u_i and tau_i = 1 / mu_i (``inf`` for a node set with no path to the
        chamber).  Each column is scaled to ``max |v_i| = 1`` with its largest entry positive:
        a_i is then the kelvins the mode puts on the node it moves most.
        """
        laplacian, _ = self.conductances()
        scale = 1.0 / np.sqrt(self.capacity_j_per_k)
        rates, u = np.linalg.eigh(scale[:, None] * laplacian * scale[None, :])
        positive = rates > 1e3 * np.finfo(float).eps * max(rates.max(), 0.0)
        taus = np.full(rates.shape, np.inf)
        taus[positive] = 1.0 / rates[positive]
        v = scale[:, None] * u
        big = np.argmax(np.abs(v), axis=0)
        v = v / v[big, np.arange(v.shape[1])]
        order = np.argsort(-taus, kind="stable")
        return taus[order], v[:, order]

    def time_constants_s(self) -> np.ndarray:
        """Time constants -1/lambda_i [s] of the eigenvalues of A, longest first.

        Computed from the symmetric form -C^-1/2 L C^-1/2 (real spectrum); a node set with
        no path to the chamber has lambda = 0 and time constant ``inf``.
        """
        laplacian, _ = self.conductances()
        scale = 1.0 / np.sqrt(self.capacity_j_per_k)
        rates = np.linalg.eigvalsh(scale[:, None] * laplacian * scale[None, :])
        # a zero eigenvalue comes out as round-off of the size of eps * the largest one
        positive = rates > 1e3 * np.finfo(float).eps * max(rates.max(), 0.0)
        taus = np.full(rates.shape, np.inf)
        taus[positive] = 1.0 / rates[positive]
        return np.sort(taus)[::-1]
