"""Thermometer effects (docs/effects.md, "Thermal effects": ``thermometer_lag``)."""

from __future__ import annotations

import numpy as np

from ..signal import first_order_lag
from .registry import Parameter, register_effect

__all__ = ["thermometer_lag", "THERMOMETERS"]

#: The three built-in thermometers and the columns they are written to.
THERMOMETERS = {"fog": "temp_fog_c", "acc_x": "temp_acc_x_c", "acc_y": "temp_acc_y_c"}


@register_effect("thermometer_lag", kind="thermometer", target="thermometer", parameters=[
    Parameter("thermometer", "", "which thermometer: fog, acc_x or acc_y", type=str),
    # the diagnosis linearises a thermometer effect at tau = 0 (tau a coefficient there):
    # this grid marks tau as one it can start, and fixes no value of its scores
    Parameter("tau", "s", "time constant of the extra lag",
              grid=(60.0, 150.0, 300.0, 600.0, 1200.0))])
def thermometer_lag(reading_c: np.ndarray, time_s: np.ndarray, *, thermometer: str,
                    tau: float) -> np.ndarray:
    """An extra first-order lag on one thermometer: tau dy/dt = T_read - y [degC].

    A thermometer bonded through a thermal resistance reads its node late; tau [s]
    10-60 (docs/physics.md section 2, est.).  Applied before offset, noise and quantisation.
    """
    return first_order_lag(reading_c, time_s, tau)
