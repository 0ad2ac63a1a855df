"""What an effect function sees: the simulated (or measured) state of the instrument."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..constants import T_REF_C
from ..errors import EffectError

__all__ = ["EffectContext", "CoilLayout"]


@dataclass(frozen=True)
class CoilLayout:
    """Where the coil's thermal layers sit across the winding: what ``shupe_winding``
    interpolates the rate field from (:mod:`nfs.effects.winding`, eq. (3))."""

    layers: tuple[str, ...]
    """The nodes of the thermal layers, spool (inner face) first."""
    centres: tuple[float, ...]
    """Their mid-radii across the winding, x = (r - r_i) / (r_o - r_i), increasing in (0, 1)."""
    inner_face: tuple[tuple[str, float], ...] | None = None
    """The inner face's temperature as (node, weight) pairs, weights summing to 1
    (:meth:`thermal.Annulus.face_weights`; a mapping is taken too), or None when the layers
    are lumped nodes with no face (the field is then extrapolated)."""
    outer_face: tuple[tuple[str, float], ...] | None = None
    """The outer face's, likewise."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "layers", tuple(self.layers))
        object.__setattr__(self, "centres", tuple(float(c) for c in self.centres))
        c = np.asarray(self.centres)
        if len(self.layers) != c.size or c.size < 2 and (
                self.inner_face is None or self.outer_face is None):
            raise EffectError("a coil layout needs one centre per layer, and two layers "
                              "or two faces")
        if c.size and (c[0] <= 0.0 or c[-1] >= 1.0 or np.any(np.diff(c) <= 0.0)):
            raise EffectError(f"coil layer centres must increase inside (0, 1), got "
                              f"{list(self.centres)}")
        for face in ("inner_face", "outer_face"):
            value = getattr(self, face)
            if value is not None:
                pairs = tuple((str(k), float(v)) for k, v in (
                    value.items() if isinstance(value, Mapping) else value))
                if abs(sum(v for _, v in pairs) - 1.0) > 1e-9:
                    raise EffectError(f"coil layout: the {face.replace('_', ' ')}'s weights "
                                      f"must sum to 1, got {pairs}")
                object.__setattr__(self, face, pairs)

    @functools.cached_property
    def nodes(self) -> tuple[str, ...]:
        """Every node the interpolated field depends on: the layers, then the faces'
        other neighbours."""
        out = list(self.layers)
        for face in (self.inner_face, self.outer_face):
            for name, _ in face or ():
                if name not in out:
                    out.append(name)
        return tuple(out)


@dataclass(frozen=True)
class EffectContext:
    """The state of one run that the gyro and accelerometer effects are evaluated on.

    All arrays have one entry per sample.  Temperatures are model states of the lumped
    thermal network (no thermometer sees the coil); rates are exact derivatives of the
    network solution.
    """

    time_s: np.ndarray
    """t, time since power-on [s]."""
    node_names: tuple[str, ...]
    """Names of the thermal nodes, in column order."""
    temperature_c: np.ndarray
    """T_j(t), node temperatures [degC], shape (n_samples, n_nodes)."""
    rate_c_per_s: np.ndarray
    """dT_j/dt [K/s], shape (n_samples, n_nodes)."""
    coil_outer: str
    """Node holding the coil's outer layers."""
    coil_inner: str
    """Node holding the coil's inner layers with the spool."""
    source: str
    """Node holding the light source (TEC-controlled) and the FOG electronics."""
    axis_azimuth_deg: np.ndarray
    """A(t) = psi + theta(t), azimuth of the FOG sensitive axis [deg], clockwise from north."""
    earth_rate_dph: np.ndarray
    """The true rate along the FOG axis (Earth-rate projection) [deg/h]."""
    moving: np.ndarray
    """True while the turntable moves."""
    acc_nodes: dict[str, str] = field(default_factory=dict)
    """Accelerometer axis (``x``/``y``) -> node carrying that QFA."""
    aux: dict[str, np.ndarray] = field(default_factory=dict)
    """Auxiliary channels ``aux_*`` by column name."""
    t_ref_c: float = T_REF_C
    """T_ref, the reference temperature of the effect library [degC]."""
    since_power_on_s: np.ndarray | None = None
    """t_on, time since the latest power-on [s] (:mod:`nfs.power`); None: ``time_s`` (no
    power cycle)."""
    coil_layout: CoilLayout | None = None
    """The coil's thermal layers across its winding (an instrument with a wound coil);
    None: the two lumped nodes ``coil_inner`` and ``coil_outer`` (:attr:`coil`)."""

    @property
    def coil(self) -> CoilLayout:
        """The coil's layout: :attr:`coil_layout`, or the lumped coil, its inner and outer
        nodes holding the inner and outer halves of the winding (mid-radii x = 1/4, 3/4, no
        faces)."""
        if self.coil_layout is not None:
            return self.coil_layout
        return _lumped_layout(self.coil_inner, self.coil_outer)

    @property
    def on_time_s(self) -> np.ndarray:
        """t_on [s]: time since the latest power-on, what turn-on effects are functions of
        (equal to ``time_s`` in a run without power cycles)."""
        return self.time_s if self.since_power_on_s is None else self.since_power_on_s

    def _index(self, node: str) -> int:
        try:
            return self.node_names.index(node)
        except ValueError:
            raise EffectError(f"unknown node '{node}'; nodes: {', '.join(self.node_names)}") \
                from None

    def node(self, name: str) -> np.ndarray:
        """T(t) of a node [degC]."""
        return self.temperature_c[:, self._index(name)]

    def rate(self, name: str) -> np.ndarray:
        """dT/dt of a node [K/s]."""
        return self.rate_c_per_s[:, self._index(name)]

    @property
    def coil_c(self) -> np.ndarray:
        """T_coil, the mean coil temperature [degC]: (T_coil_outer + T_coil_inner) / 2 of the
        lumped coil, the mean of the layers of a wound one."""
        if self.coil_layout is None:
            return 0.5 * (self.node(self.coil_outer) + self.node(self.coil_inner))
        return self.temperature_c @ self._layer_mean

    @property
    def coil_rate_c_per_s(self) -> np.ndarray:
        """dT_coil/dt [K/s]."""
        if self.coil_layout is None:
            return 0.5 * (self.rate(self.coil_outer) + self.rate(self.coil_inner))
        return self.rate_c_per_s @ self._layer_mean

    @property
    def _layer_mean(self) -> np.ndarray:
        """Weights 1/N on the N layers of a wound coil (0 elsewhere), by node."""
        w = np.zeros(len(self.node_names))
        w[[self._index(name) for name in self.coil_layout.layers]] = 1.0 / len(
            self.coil_layout.layers)
        return w

    def temperature(self, node: str | None) -> np.ndarray:
        """T of ``node``, or T_coil when ``node`` is None [degC]."""
        return self.coil_c if node is None else self.node(node)

    def temperature_rate(self, node: str | None) -> np.ndarray:
        """dT/dt of ``node``, or of T_coil when ``node`` is None [K/s]."""
        return self.coil_rate_c_per_s if node is None else self.rate(node)


@functools.lru_cache(maxsize=16)
def _lumped_layout(inner: str, outer: str) -> CoilLayout:
    return CoilLayout(layers=(inner, outer), centres=(0.25, 0.75))
