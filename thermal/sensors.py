"""What the state estimator reads: linear sensors of the node temperatures and the records
of held inputs and readings (equations (3)-(4) of thermal/estimate.py's module docstring).

The inputs of :mod:`thermal.estimate` and of the recursions in :mod:`thermal.kalman`, in a
module below both so that neither imports the other's names.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from thermal.errors import ThermalError

__all__ = ["LinearSensor", "ThermalRecord", "StatePower"]

#: A held state-dependent heat source of one record: ``law(k, temperature_c)`` at sample k
#: from the node temperatures (n,) [degC] -> extra power per node (n,) [W].
StatePower = Callable[[int, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class LinearSensor:
    """A sensor that reads a weighted sum of node temperatures through lags in series, (3)-(4)."""

    name: str
    """Sensor name, e.g. ``"fog"``."""

    weights: Mapping[str, float]
    """Node -> h_mj [1]: the sensed temperature is sum_j h_mj T_j (not normalised here)."""

    noise_std_c: float
    """sigma_m, standard deviation of the white measurement error per sample [degC], > 0."""

    lags_s: tuple[float, ...] = ()
    """Time constants tau_m,i [s] of first-order lags in series (empty: no lag), each > 0."""

    offset_c: float = 0.0
    """o_m, constant offset of the reading [degC]."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "lags_s", tuple(float(t) for t in self.lags_s))
        if not self.weights:
            raise ThermalError(f"sensor {self.name!r} has no node weights")
        if not (math.isfinite(self.noise_std_c) and self.noise_std_c > 0.0):
            raise ThermalError(f"sensor {self.name!r}: noise_std_c must be > 0, got "
                               f"{self.noise_std_c}")
        for tau in self.lags_s:
            if not (math.isfinite(tau) and tau > 0.0):
                raise ThermalError(f"sensor {self.name!r}: lags_s must be > 0, got {tau}")


@dataclass(frozen=True)
class ThermalRecord:
    """One record: held inputs and sensor readings at the estimation times t_k."""

    time_s: np.ndarray
    """t_k [s], shape (n_k,), strictly increasing."""

    readings_c: np.ndarray
    """z_m(t_k) [degC], shape (n_k, n_sensors), columns in sensor order; NaN: missing."""

    ambient_c: np.ndarray
    """T_amb held over [t_k, t_k+1) [degC], shape (n_k,)."""

    initial_c: float | np.ndarray
    """Node temperatures at t_0 [degC], scalar or (n,); the lag states start in equilibrium
    with them (as :func:`nfs.signal.first_order_lag` does)."""

    power_w: np.ndarray | None = None
    """Extra power per node held over [t_k, t_k+1) [W], shape (n_k, n), on top of the
    constant node powers; None for none."""

    power_law: StatePower | None = None
    """A held state-dependent extra power (e.g. a TEC law), or None."""
