"""Where a solve with every input known in advance ends: the node temperatures at the last
sample, for a soak that needs nothing else (:func:`final_temperature`).

The soak before a start-up (the unpowered network left in the chamber for a few hours on a
coarse grid, nfs/variability.py) is read only at its end, and the start-ups of a sweep soak
the same network on grids of the same step: the step matrices of a step, equation (5) of
thermal/solve.py, and the modal form of its recursion (:func:`thermal.solve.modal_form`)
are kept for the next soak (:data:`KEPT_STEPS` at most, keyed by the network, a frozen
value, and the step's exact value), and the rates, powers and heat bookkeeping of a
:class:`~thermal.solve.ThermalResult` are not made.

Only the end is formed.  Each stretch of equal steps is the recursion T_(k+1) = T_k +
(Phi - I) T_k + d_k of thermal/solve.py, whose modes z = Q^T D T (D = diag(sqrt(C)),
:func:`thermal.solve.modal_form`) obey z_(k+1) = lambda z_k + w_k, w_k = Q^T D d_k; after
N steps

    z_N = lambda^N z_0 + sum_(k=0)^(N-1) lambda^(N-1-k) w_k,                          (1)

one weighted sum per mode with lambda^j = exp(j log lambda) (no accumulated rounding), in
place of :func:`~thermal.solve.simulate`'s every sample (a filter per mode): the same
temperatures to rounding (below 1e-12 K after a soak of hours), a fraction of the work.
"""

from __future__ import annotations

import functools

import numpy as np

from thermal.inputs import as_ambient, as_initial, as_time, step_classes
from thermal.network import Network
from thermal.solve import StepMatrices, modal_form, step_matrices

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
    held over each interval and the constant node powers only: :func:`thermal.simulate`'s
    (``ambient_hold="zero-order"``, no ``power_w``) ``.temperature_c[-1]`` to rounding, by
    (1) on the step matrices of equations (3) and (5) of thermal/solve.py."""
    t = as_time(time_s)
    amb = as_ambient(ambient_c, t)
    n = len(network.node_names)
    t0 = as_initial(initial_c, network.node_names)
    if t.size == 1:
        return t0
    steps, cls = step_classes(t)
    kept = [_step(network, float(h)) for h in steps]
    inputs = np.empty((t.size, 1 + n))  # u_k = [T_amb,k, P_1, ..., P_n], equation (2)
    inputs[:, 0] = amb
    inputs[:, 1:] = network.node_power_w + 0.0
    temp = t0.astype(float)
    edges = np.flatnonzero(np.diff(cls)) + 1
    for a, b in zip(np.concatenate([[0], edges]), np.concatenate([edges, [cls.size]])):
        mats, modes = kept[cls[a]]
        temp = _stretch_end(modes, temp, inputs[a:b] @ mats.gamma.T)
    return temp


def _stretch_end(modes, t0: np.ndarray, drive: np.ndarray) -> np.ndarray:
    """T_N of T_(k+1) = T_k + (Phi - I) T_k + drive_k (k = 0 .. N-1, ``drive`` (N, n)) from
    ``t0`` by (1); ``modes`` the step's :func:`~thermal.solve.modal_form`."""
    d, mu, q = modes
    n_steps = drive.shape[0]
    w = (drive * d) @ q                                  # (N, n)
    # log lambda, clipped at -700 (lambda = 0: a mode faster than the step)
    log_lam = np.full(mu.shape, -700.0)
    live = mu > -1.0
    log_lam[live] = np.maximum(np.log1p(mu[live]), -700.0)
    powers = np.exp(np.arange(n_steps - 1, -1, -1.0)[:, None] * log_lam)   # lambda^(N-1-k)
    z = np.exp(n_steps * log_lam) * (q.T @ (d * t0)) + (powers * w).sum(axis=0)
    return (q @ z) / d
