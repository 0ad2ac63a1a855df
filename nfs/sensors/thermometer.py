"""Built-in thermometers of the FOG and the two QFAs (docs/physics.md section 2)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..signal import first_order_lag

__all__ = ["ThermometerModel", "thermometer_reading", "quantize"]


@dataclass(frozen=True)
class ThermometerModel:
    """A thermometer bonded to one node (or between nodes), read through a lag."""

    nodes: dict[str, float] = field(default_factory=dict)
    """Node -> weight: the sensed temperature is sum w_j T_j / sum w_j (a thermometer that
    sits between the electronics and the coil has two weights)."""
    lag_s: float = 20.0
    """tau, first-order lag [s] (10-60)."""
    offset_c: float = 0.0
    """Constant offset [degC]."""
    noise_c: float = 0.01
    """White noise standard deviation per sample [degC] (0.005-0.02)."""
    quantum_c: float = 0.0625
    """Quantisation step [degC] (0.01-0.0625); 0 for none."""

    def sensed(self, temperature_c: np.ndarray, node_names: tuple[str, ...]) -> np.ndarray:
        """sum_j w_j T_j / sum_j w_j from the node temperature matrix (n_samples, n_nodes)."""
        total = sum(self.nodes.values())
        out = np.zeros(temperature_c.shape[0])
        for node, w in self.nodes.items():
            out += (w / total) * temperature_c[:, node_names.index(node)]
        return out


def quantize(x: np.ndarray, quantum: float) -> np.ndarray:
    """Round to the nearest multiple of ``quantum`` (0: unchanged)."""
    return x if quantum <= 0 else quantum * np.round(x / quantum)


def thermometer_reading(sensed_c: np.ndarray, time_s: np.ndarray, model: ThermometerModel,
                        rng: np.random.Generator, transforms=()) -> np.ndarray:
    """Reading = Q(lag(T_sensed) [then extra transforms] + offset + noise) [degC].

    ``transforms`` are callables reading -> reading (thermometer effects such as
    ``thermometer_lag``), applied after the built-in lag.  Q rounds to ``quantum_c``.
    """
    y = first_order_lag(sensed_c, time_s, model.lag_s)
    for f in transforms:
        y = f(y)
    y = y + model.offset_c
    if model.noise_c:  # a noise-free reading (the fits' model readings) draws nothing
        y = y + model.noise_c * rng.standard_normal(y.shape)
    return quantize(y, model.quantum_c)
