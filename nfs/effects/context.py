"""What an effect function sees: the simulated (or measured) state of the instrument."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..constants import T_REF_C
from ..errors import EffectError

__all__ = ["EffectContext"]


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
        """T_coil = (T_coil_outer + T_coil_inner) / 2, the mean coil temperature [degC]."""
        return 0.5 * (self.node(self.coil_outer) + self.node(self.coil_inner))

    @property
    def coil_rate_c_per_s(self) -> np.ndarray:
        """dT_coil/dt [K/s]."""
        return 0.5 * (self.rate(self.coil_outer) + self.rate(self.coil_inner))

    def temperature(self, node: str | None) -> np.ndarray:
        """T of ``node``, or T_coil when ``node`` is None [degC]."""
        return self.coil_c if node is None else self.node(node)

    def temperature_rate(self, node: str | None) -> np.ndarray:
        """dT/dt of ``node``, or of T_coil when ``node`` is None [K/s]."""
        return self.coil_rate_c_per_s if node is None else self.rate(node)
