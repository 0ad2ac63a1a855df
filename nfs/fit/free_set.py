"""The stages of the fit and the parameters each frees by default.

:func:`nfs.fit.calibration.fit_model` runs a thermal stage (thermal and thermometer parameters
against the thermometers) and a drift stage (gyro, accelerometer and turntable parameters
against the drift and accelerometer window means).  :func:`default_free` is the set a fit
frees when the caller names none; :func:`stage_of` says which stage fits a parameter.
"""

from __future__ import annotations

from typing import Sequence

from ..instrument import Instrument
from .params import get_param, param_paths

__all__ = ["FIT_STAGES", "THERMAL_KINDS", "default_free", "stage_of"]

#: The stages of :func:`nfs.fit.calibration.fit_model`, in order.
FIT_STAGES = ("thermal", "drift")

#: Parameter kinds the thermal stage fits.
THERMAL_KINDS = ("thermal", "thermometer")

_NOT_FREE_UNITS = ("s", "K", "degC", "channel unit")
"""Effect parameters left out of the default free set: time constants [s], temperature
periods [K], set points [degC] and channel references (collinear with the bias)."""


def default_free(inst: Instrument, stages: Sequence[str] = FIT_STAGES) -> list[str]:
    """The default free set.

    thermal stage: every node capacity (a wound coil's: its volumetric heat capacity), every
    conductance to the chamber, every non-zero node power, every thermometer lag and offset, the coefficients of the thermal effects
    (TEC slopes c_h, c_c; heat powers).  drift stage: ``gyro.bias_dph``, every coefficient of
    the gyro and accelerometer effects, the accelerometer biases and the turntable tilts.
    Effect time constants [s], temperature periods [K], set points [degC], channel
    references and parameters registered as shapes (shupe_stress's c_m) are left out (list
    them to free them).
    """
    out = []
    for path, kind in param_paths(inst):
        leaf = path.rsplit(".", 1)[-1]
        if path.startswith("effects."):
            label = path[len("effects."):].rsplit(".", 1)[0]
            par = inst.effect(label).spec.parameter(leaf)
            take = par.unit not in _NOT_FREE_UNITS and not par.shape
        elif path.startswith("coil."):     # a wound coil: its capacity (nfs.coil)
            take = leaf == "heat_capacity_j_per_m3_k"
        elif kind == "thermal":
            take = (leaf == "capacity_j_per_k"
                    or (leaf == "power_w" and get_param(inst, path) != 0.0)
                    or (leaf == "conductance_w_per_k"
                        and "chamber" in path.split(".")[2].split("-")))
        elif kind == "thermometer":
            take = leaf in ("lag_s", "offset_c")
        elif kind == "drift":
            take = leaf == "bias_dph"
        elif kind == "accelerometer":
            take = leaf in ("bias_x_g", "bias_y_g")
        else:  # turntable
            take = leaf.startswith("tilt_")
        stage = "thermal" if kind in THERMAL_KINDS else "drift"
        if take and stage in stages:
            out.append(path)
    return out


def stage_of(kind: str, stages: Sequence[str]) -> str:
    """The stage of :func:`nfs.fit.calibration.fit_model` that fits a parameter of ``kind``
    (:data:`nfs.parameters.PARAM_KINDS`) when ``stages`` run: thermal and thermometer
    parameters the thermal stage when it runs, everything else the drift stage."""
    if kind in THERMAL_KINDS and "thermal" in stages:
        return "thermal"
    return "drift"
