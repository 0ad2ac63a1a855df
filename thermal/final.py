"""Where a solve with every input known in advance ends: the node temperatures at the last
sample, for a soak that needs nothing else (:func:`final_temperature`).

The soak before a start-up (the unpowered network left in the chamber for a few hours on a
coarse grid, nfs/variability.py) is read only at its end, and the start-ups of a sweep soak
the same network on grids of the same step: the step matrices of a step, equation (5) of
thermal/solve.py, and the modal form of its recursion (:func:`thermal.solve.modal_form`)
are kept for the next soak (:data:`KEPT_STEPS` at most, keyed by the network, a frozen
value, and the step's exact value), and the rates, powers and heat bookkeeping of a
:class:`~thermal.solve.ThermalResult` are not made.  The arithmetic is that of
:func:`~thermal.solve.simulate` (the same closed form, operation for operation), so the end
has the bits of ``simulate(...).temperature_c[-1]``.
"""

from __future__ import annotations

import functools

import numpy as np

from thermal.network import Network
from thermal.solve import (StepMatrices, _as_ambient, _as_initial, _as_time, _closed_form,
                           _step_classes, modal_form, step_matrices)

__all__ = ["final_temperature", "KEPT_STEPS"]

#: Steps whose matrices and modal form are kept (the soaks of a sweep's start-ups share the
#: grid's step up to a few distinct roundings of it; the last, partial step of each soak is
#: its own).
KEPT_STEPS = 64


@functools.lru_cache(maxsize=KEPT_STEPS)
def _step(network: Network, h_s: float) -> tuple[StepMatrices, tuple]:
    """The step matrices of ``h_s`` [s] (zero-order hold) of ``network`` and their modal
    form, the :data:`KEPT_STEPS` most recently used kept (the network is frozen: equal
    networks share them)."""
    a, b = network.matrices()
    mats = step_matrices(a, b, h_s)
    return mats, modal_form(mats.phi_minus_i, network.capacity_j_per_k)


def final_temperature(network: Network, time_s: np.ndarray, *, ambient_c,
                      initial_c: float | np.ndarray) -> np.ndarray:
    """Node temperatures [degC] (n_nodes,) at ``time_s[-1]`` of ``network`` from
    ``initial_c`` at ``time_s[0]``, the chamber ``ambient_c`` (scalar or (n_t,) [degC])
    held over each interval and the constant node powers only: the bits of
    :func:`thermal.simulate` (``ambient_hold="zero-order"``, no ``power_w``)
    ``.temperature_c[-1]``, equations (3) and (5) of thermal/solve.py."""
    t = _as_time(time_s)
    amb = _as_ambient(ambient_c, t)
    n = len(network.node_names)
    t0 = _as_initial(initial_c, network.node_names)
    if t.size == 1:
        return t0
    capacity = network.capacity_j_per_k
    steps, cls = _step_classes(t)
    kept = [_step(network, float(h)) for h in steps]
    inputs = np.empty((t.size, 1 + n))  # u_k = [T_amb,k, P_1, ..., P_n], equation (2)
    inputs[:, 0] = amb
    inputs[:, 1:] = network.node_power_w + 0.0
    temp = _closed_form([m for m, _ in kept], cls, capacity, t0, inputs, np.zeros(t.size),
                        False, [modes for _, modes in kept])
    return temp[-1].copy()
