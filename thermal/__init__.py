"""Lumped thermal network of the north finder, independent of gyros (docs/physics.md section 2).

Build a :class:`Network` of :class:`Node` and :class:`Link` objects, then :func:`simulate`
it exactly over sample intervals of held input (or of a chamber linear between samples),
many runs of one network together with :func:`simulate_many`;
the :class:`ThermalResult` labels every node and carries the energy bookkeeping.
:func:`estimate_states` estimates the node temperatures from :class:`LinearSensor` readings
through the network (Kalman filter and smoother, thermal/estimate.py).
"""

from thermal.errors import ThermalError
from thermal.network import CHAMBER, Link, Network, Node
from thermal.solve import ThermalResult, simulate
from thermal.batch import simulate_many
from thermal.estimate import (LinearSensor, NodeEstimate, ProcessNoiseFit, StateEstimate,
                              StatePower, ThermalRecord, estimate_states,
                              fit_process_noise, kalman_smooth)

__all__ = ["ThermalError", "CHAMBER", "Node", "Link", "Network", "simulate", "simulate_many", "ThermalResult",
           "LinearSensor", "ThermalRecord", "StatePower", "NodeEstimate", "ProcessNoiseFit",
           "StateEstimate", "kalman_smooth", "fit_process_noise", "estimate_states"]
