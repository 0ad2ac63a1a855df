"""Exact piecewise solution of the thermal network: inputs held, or the chamber linear, over
each sample interval.

Over an interval [t_k, t_k + h) with the input u_k = [T_amb, P_1, ..., P_n] held constant
(zero-order hold), dT/dt = A T + B u_k (network.py, equation (2)) has the exact solution

    T(t_k + s) = Phi(s) T_k + Gamma(s) u_k,
    Phi(s) = expm(A s),   Gamma(s) = int_0^s expm(A r) dr B,                          (3)

and its time integral over the interval, needed for the heat lost to the chamber, is

    int_0^h T(t_k + s) ds = Psi(h) T_k + Upsilon(h) u_k,
    Psi(h) = int_0^h expm(A s) ds,   Upsilon(h) = int_0^h Gamma(s) ds.                (4)

All four come from one matrix exponential of the augmented (Van Loan) block matrix

         [0  I  0]                    [I  Psi  Upsilon]
    F =  [0  A  B],    expm(F h)  =   [0  Phi  Gamma  ]                                (5)
         [0  0  0]                    [0  0    I      ]

(Van Loan, "Computing integrals involving the matrix exponential", IEEE TAC 23(3), 1978,
theorem 1), computed once per distinct step h.  No ODE stepper is involved: the only
approximation is the hold of the inputs, which is exact for inputs that are constant over
each interval.

First-order hold of the chamber.  A chamber program ramps T_amb linearly, which a held value
follows only with a lag of h/2.  With ``ambient_hold="first-order"`` the chamber temperature
is linear between samples, T_amb(t_k + s) = T_amb,k + v_k s with v_k = (T_amb,k+1 -
T_amb,k) / h (the powers stay held), and (3)-(4) gain one exact term each:

    T(t_k + h) = Phi T_k + Gamma u_k + Lambda v_k,
    int_0^h T ds = Psi T_k + Upsilon u_k + Omega v_k,
    Lambda(h) = int_0^h expm(A (h - s)) b_amb s ds,   Omega(h) = int_0^h Lambda(s) ds,   (7)

b_amb the chamber column of B, from the same Van Loan exponential with one more block
(the slope v integrating into T_amb):

         [0  I  0  0    ]                  [I  Psi  Upsilon  Omega ]
    F =  [0  A  B  0    ],   expm(F h)  =  [0  Phi  Gamma    Lambda]                     (8)
         [0  0  0  e_amb]                  [0  0    I        e_amb h]
         [0  0  0  0    ]                  [0  0    0        1     ]

The solution is then exact for any chamber temperature that is piecewise linear with its
corners on the samples (a chamber program whose steps last whole sample intervals).

Energy bookkeeping.  Summing equation (1) over the nodes, the internal conductances cancel:

    d/dt sum_j C_j T_j = sum_j P_j - sum_j G_j,amb (T_j - T_amb),                      (6)

so heat_in = stored + lost, with heat_in = sum_k h_k sum_j P_j,k, lost = sum_k sum_j G_j,amb
(int T_j ds - h_k T_amb,k) from (4) or (7), and stored = sum_j C_j (T_j(t) - T_j(t_0)).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.linalg import expm, eigh
from scipy.signal import lfilter

from thermal.errors import ThermalError
from thermal.inputs import as_ambient, as_initial, as_time, step_classes
from thermal.march import heated_rows, march, step_maps
from thermal.network import Network, index_of

__all__ = ["ThermalResult", "simulate", "step_matrices", "StepMatrices", "AMBIENT_HOLDS",
           "thermal_result"]

#: How the chamber temperature is taken between samples: held (zero-order) or linear
#: (first-order, equations (7)-(8)).
AMBIENT_HOLDS = ("zero-order", "first-order")

#: A heat source P(t_s, temperature_c) -> extra power per node [W], shape (n_nodes,).
PowerLaw = Callable[[float, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class ThermalResult:
    """Node temperatures and energy bookkeeping of one :func:`simulate` run.

    Every array is read-only; rows are samples (the times ``time_s``), columns are nodes in
    the order ``node_names``.
    """

    time_s: np.ndarray
    """Sample times t_k [s], shape (n_t,)."""

    node_names: tuple[str, ...]
    """Node names, the column order of the node arrays."""

    capacity_j_per_k: np.ndarray
    """Node heat capacities C_j [J/K], shape (n_nodes,)."""

    temperature_c: np.ndarray
    """Node temperatures T_j(t_k) [degC], shape (n_t, n_nodes)."""

    rate_c_per_s: np.ndarray
    """dT_j/dt at t_k [K/s] = A T_k + B u_k, exact for the input held from t_k on."""

    power_w: np.ndarray
    """Total node power P_j,k [W] held over [t_k, t_k+1) (constants plus extra sources)."""

    ambient_c: np.ndarray
    """Chamber temperature T_amb,k [degC] at t_k, shape (n_t,): held over [t_k, t_k+1), or
    linear to T_amb,k+1 (:attr:`ambient_hold`)."""

    ambient_hold: str = "zero-order"
    """How T_amb went between samples: "zero-order" (held) or "first-order" (linear)."""

    _ledger: tuple = field(default=(), repr=False, compare=False)
    """(network, step matrices, steps, step classes, first-order hold?) of the solve: what
    the heat bookkeeping is computed from when first read (a sweep reads none of it)."""

    @cached_property
    def _heat(self) -> tuple[np.ndarray, np.ndarray]:
        return _heat_ledger(self)

    @property
    def heat_in_j(self) -> np.ndarray:
        """Cumulative energy injected by all node powers from t_0 to t_k [J], shape (n_t,)."""
        return self._heat[0]

    @property
    def heat_lost_j(self) -> np.ndarray:
        """Cumulative energy lost to the chamber from t_0 to t_k [J], shape (n_t,), exact
        (4) or (7)."""
        return self._heat[1]

    @property
    def stored_j(self) -> np.ndarray:
        """Energy stored since t_0 [J]: sum_j C_j (T_j(t_k) - T_j(t_0)), shape (n_t,)."""
        return (self.temperature_c - self.temperature_c[0]) @ self.capacity_j_per_k

    def node(self, name: str) -> np.ndarray:
        """Temperature of node ``name`` [degC], shape (n_t,)."""
        return self.temperature_c[:, index_of(self.node_names, name)]

    def rate(self, name: str) -> np.ndarray:
        """Temperature rate of node ``name`` [K/s], shape (n_t,)."""
        return self.rate_c_per_s[:, index_of(self.node_names, name)]


@dataclass(frozen=True)
class StepMatrices:
    """The blocks of expm(F h), equation (5), for one step h [s]."""

    phi: np.ndarray
    """Phi(h) = expm(A h) [1], shape (n, n)."""

    gamma: np.ndarray
    """Gamma(h) = int_0^h expm(A s) ds B, shape (n, 1 + n) (units of B times s)."""

    psi: np.ndarray
    """Psi(h) = int_0^h expm(A s) ds [s], shape (n, n)."""

    upsilon: np.ndarray
    """Upsilon(h) = int_0^h Gamma(s) ds, shape (n, 1 + n) (units of B times s^2)."""

    phi_minus_i: np.ndarray
    """Phi(h) - I = A Psi(h) [1], shape (n, n), free of the cancellation of Phi - I."""

    lam: np.ndarray | None = None
    """Lambda(h) of (7), the response to a unit chamber slope [K per K/s], shape (n,); None
    unless asked for (``slope=True``)."""

    omega: np.ndarray | None = None
    """Omega(h) = int_0^h Lambda(s) ds of (7) [K s per K/s], shape (n,); None unless asked
    for."""


def step_matrices(a: np.ndarray, b: np.ndarray, h_s: float, *,
                  slope: bool = False) -> StepMatrices:
    """Phi, Gamma, Psi and Upsilon of equations (3)-(4) for the step ``h_s`` [s], by (5);
    with ``slope``, also Lambda and Omega of the chamber's slope (7), by (8).

    ``a`` (n, n) and ``b`` (n, m) are the matrices of dT/dt = A T + B u
    (:meth:`thermal.Network.matrices`); column 0 of ``b`` is the chamber's.
    """
    n, m = b.shape
    size = 2 * n + m + (1 if slope else 0)
    f = np.zeros((size, size))
    f[:n, n:2 * n] = np.eye(n)
    f[n:2 * n, n:2 * n] = a
    f[n:2 * n, 2 * n:2 * n + m] = b
    if slope:
        f[2 * n, 2 * n + m] = 1.0        # d T_amb / dt = v
    e = expm(f * h_s)
    psi = e[:n, n:2 * n]
    lam = omega = None
    if slope:
        lam, omega = e[n:2 * n, 2 * n + m].copy(), e[:n, 2 * n + m].copy()
    return StepMatrices(phi=e[n:2 * n, n:2 * n], gamma=e[n:2 * n, 2 * n:2 * n + m], psi=psi,
                         upsilon=e[:n, 2 * n:2 * n + m], phi_minus_i=a @ psi, lam=lam,
                         omega=omega)


def _per_interval(mats: list[np.ndarray], cls: np.ndarray, x: np.ndarray,
                  n_out: int) -> np.ndarray:
    """Rows mats[cls[k]] @ x[k] (n_out,) for every interval k, vectorised per step class."""
    out = np.empty((cls.size, n_out))
    if len(mats) == 1:
        return np.matmul(x, mats[0].T, out=out)
    for c, mat in enumerate(mats):
        rows = cls == c
        out[rows] = x[rows] @ mat.T
    return out


def modal_form(phi_minus_i: np.ndarray, capacity: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(d, mu, Q) of one step: d = sqrt(C) [sqrt(J/K)], and D (Phi - I) D^-1 (D = diag(d),
    symmetric: network.py) = Q diag(mu) Q^T, mu = lambda - 1 clipped to [-1, 0] (see
    :func:`_modal_recursion`); a function of the step matrices alone, so it can be kept
    beside them (thermal/final.py)."""
    d = np.sqrt(capacity)
    sym = d[:, None] * phi_minus_i / d[None, :]
    mu, q = eigh(0.5 * (sym + sym.T))
    # lambda = exp(eigenvalue of A times h) lies in (0, 1]: a step long against a fast mode
    # gives lambda = 0 to rounding, and mu a hair below -1 would make log1p(mu) NaN.
    return d, np.clip(mu, -1.0, 0.0), q


def _modal_recursion(phi_minus_i: np.ndarray, capacity: np.ndarray, t0: np.ndarray,
                     drive: np.ndarray, modes=None) -> np.ndarray:
    """T_{k+1} = T_k + (Phi - I) T_k + drive_k for one step size, vectorised over k.

    D (Phi - I) D^-1 with D = diag(sqrt(C)) is symmetric (network.py), = Q diag(mu) Q^T with
    orthogonal Q and mu = lambda - 1 in (-1, 0].  Each mode z = Q^T D T obeys z_{k+1} =
    lambda z_k + w_k; splitting w_k = w_0 + (w_k - w_0),

        z_k = lambda^k z_0 + (lambda^k - 1) / mu w_0 + y_k,   y_{k+1} = lambda y_k + w_k - w_0,

    the held-input part in closed form with lambda^k = exp(k log1p(mu)) (no accumulated
    rounding; (lambda^k - 1)/mu -> k for a mode with no path to the chamber), and y, zero
    for constant inputs, by :func:`scipy.signal.lfilter`.  ``modes``: :func:`modal_form`
    of the step when already known.
    """
    d, mu, q = modal_form(phi_minus_i, capacity) if modes is None else modes
    n_t = drive.shape[0] + 1
    w = (drive * d) @ q                                  # (n_t - 1, n)
    w0 = w[0] if n_t > 1 else np.zeros(mu.size)
    k = np.arange(n_t)[:, None]
    # log lambda, clipped at -700 (lambda = 0, mu = -1, underflows to e^-700), without an
    # errstate context (a context variable set and reset at every call)
    log_lam = np.full(mu.shape, -700.0)
    live = mu > -1.0
    log_lam[live] = np.maximum(np.log1p(mu[live]), -700.0)
    k_log_lam = k * log_lam
    floating = mu == 0.0
    geometric = np.where(floating, k, np.expm1(k_log_lam) / np.where(floating, 1.0, mu))
    z = np.exp(k_log_lam) * (q.T @ (d * t0)) + geometric * w0
    if n_t <= 2:
        # one step: w - w0 is zero, and the filter of zeros gives +0.0 at every sample
        z += 0.0
    else:
        varying = np.zeros((n_t, mu.size))
        varying[1:] = w - w0
        for i, mu_i in enumerate(mu):
            z[:, i] += lfilter([1.0], [1.0, -(1.0 + mu_i)], varying[:, i])
    return (z @ q.T) / d


def _closed_form(mats: list[StepMatrices], cls: np.ndarray, capacity: np.ndarray,
                 t0: np.ndarray, inputs: np.ndarray, slope: np.ndarray,
                 linear: bool, modes=None) -> np.ndarray:
    """T_k at every sample for inputs known in advance: each stretch of equal steps (one
    step class) by :func:`_modal_recursion` from the temperatures where the previous
    stretch ended, so a grid of a few step sizes (a soak on a coarse grid, then one step to
    the record) costs a few closed forms, not a loop over the samples.  ``modes``: per step
    class, its :func:`modal_form` when known (None: computed here)."""
    temp = np.empty((cls.size + 1, t0.size))
    temp[0] = t0
    edges = np.flatnonzero(np.diff(cls)) + 1
    for a, b in zip(np.concatenate([[0], edges]), np.concatenate([edges, [cls.size]])):
        m = mats[cls[a]]
        drive = inputs[a:b] @ m.gamma.T
        if linear:
            drive += slope[a:b, None] * m.lam
        temp[a:b + 1] = _modal_recursion(m.phi_minus_i, capacity, temp[a], drive,
                                         None if modes is None else modes[cls[a]])
    return temp


def _check_power_array(power: np.ndarray, time_s: np.ndarray, names: tuple[str, ...],
                       source: str) -> None:
    """A :class:`ThermalError` locating the first non-finite power (time and node)."""
    finite = np.isfinite(power)
    if not np.all(finite):
        k, j = (int(i) for i in np.argwhere(~finite)[0])
        raise ThermalError(f"{source} is not finite at t = {time_s[k]} s, node {names[j]!r}")


def simulate(network: Network, time_s: np.ndarray, *,
             ambient_c: float | np.ndarray | Callable[[float], float],
             initial_c: float | np.ndarray,
             power_w: PowerLaw | np.ndarray | None = None,
             ambient_hold: str = "zero-order", heated_nodes=None) -> ThermalResult:
    """Node temperatures of ``network`` at the sample times, exact for held inputs (3)-(5).

    Parameters
    ----------
    network : Network
        The thermal network.
    time_s : array_like (n_t,)
        Strictly increasing sample times [s]; any spacing.  One matrix exponential per
        distinct step (a fraction of a millisecond each), so a uniform grid costs one;
        steps equal to within the float resolution of the time stamps count as one.
    ambient_c : float, array_like (n_t,) or callable(t_s) -> float
        Chamber temperature T_amb [degC] at the samples, taken between them as
        ``ambient_hold`` says.
    ambient_hold : {"zero-order", "first-order"}
        "zero-order": the value at t_k is held over [t_k, t_k+1), exact for a chamber that
        steps on the samples; "first-order": linear from T_amb,k to T_amb,k+1, exact for a
        piecewise-linear chamber (ramps) with its corners on the samples, equations (7)-(8).
        Both cost the same per sample.
    initial_c : float or array_like (n_nodes,)
        Node temperatures at time_s[0] [degC].
    power_w : callable(t_s, temperature_c) -> array (n_nodes,), array (n_t, n_nodes), optional
        Extra power per node [W] on top of the constant ``Node.power_w``.  A callable is
        evaluated at each sample t_k from the node temperatures T_k (a read-only array) and
        held over [t_k, t_k+1): this is how temperature-dependent sources (a TEC law) and
        pulses enter.  An array gives the held value per sample.  Holding a
        temperature-dependent law over a step h errs by O(h) against the same law applied
        continuously (3e-4 K for the TEC of benchmarks/bench_thermal.py at h = 1 s); the
        value at the last sample is reported (``power_w``, ``rate_c_per_s``) but not held.
        With a callable the march (thermal/march.py, equation (9)) is a Python loop over
        the samples, a few microseconds per step plus the callable, in the same arithmetic
        as a run of :func:`thermal.simulate_many`; without one it is vectorised.
    heated_nodes : sequence of int, optional
        With a callable ``power_w``: the indices of the nodes whose extra power it can make
        non-zero (its other entries are 0 at every sample, which the caller guarantees); the
        march then carries only these (thermal/march.py: the same bits, less work).  None:
        every node.

    Returns
    -------
    ThermalResult
        Temperatures, exact rates, the powers and ambient used, and the energy bookkeeping
        heat_in_j = stored_j + heat_lost_j (equation (6)).
    """
    t = as_time(time_s)
    n_t = t.size
    names = network.node_names
    n = len(names)
    amb = as_ambient(ambient_c, t)
    t0 = as_initial(initial_c, names)

    if ambient_hold not in AMBIENT_HOLDS:
        raise ThermalError(f"ambient_hold must be one of {', '.join(AMBIENT_HOLDS)}, got "
                           f"{ambient_hold!r}")
    linear = ambient_hold == "first-order"
    a, b = network.matrices()
    steps, cls = step_classes(t)
    mats = [step_matrices(a, b, h, slope=linear) for h in steps]
    slope = np.zeros(n_t)               # v_k of (7), the chamber's slope over [t_k, t_k+1)
    if linear and n_t > 1:
        slope[:-1] = np.diff(amb) / np.diff(t)

    law = power_w if callable(power_w) else None
    extra = None
    if law is None and power_w is not None:
        extra = np.asarray(power_w, dtype=float)
        if extra.shape != (n_t, n):
            raise ThermalError(f"power_w must be a callable or an array of shape ({n_t}, {n}), "
                               f"got shape {extra.shape}")
        _check_power_array(extra, t, names, "power_w")

    inputs = np.empty((n_t, 1 + n))     # u_k = [T_amb,k, P_1,k, ..., P_n,k], equation (2)
    inputs[:, 0] = amb
    if law is None:
        inputs[:, 1:] = network.node_power_w + (0.0 if extra is None else extra)
        temp = (_closed_form(mats, cls, network.capacity_j_per_k, t0, inputs, slope, linear)
                if n_t > 1 else t0[None, :].copy())
    else:
        # the march of thermal/march.py with one run: a run's bits are those it gets in a
        # batch of any size (thermal.simulate_many)
        temps, powers = march(step_maps(mats, network.node_power_w), cls, t, t0[:, None],
                              amb[:, None], slope[:, None] if linear else None, None, law,
                              stacked=False, heated=heated_nodes)
        temp = temps[0]
        fill_inputs(inputs, network.node_power_w, heated_rows(n, heated_nodes), powers[0],
                    t, names)

    return thermal_result(network, a, b, mats, steps, cls, t, amb, linear, temp, inputs,
                          ambient_hold)


def fill_inputs(inputs: np.ndarray, node_power_w: np.ndarray, nodes: np.ndarray,
                power_w: np.ndarray, time_s: np.ndarray, names: tuple[str, ...]) -> None:
    """inputs[:, 1:] = P_const + p_k [W]: the constant node powers plus the law's powers
    ``power_w`` (n_t, m) of the heated ``nodes`` (the other nodes' are zero), after a
    :class:`ThermalError` locating the first non-finite power."""
    if not np.all(np.isfinite(power_w)):
        full = np.zeros((time_s.size, node_power_w.size))
        full[:, nodes] = power_w
        _check_power_array(full, time_s, names, "power_w(t_s, temperature_c)")
    inputs[:, 1:] = node_power_w
    if nodes.size == node_power_w.size:
        inputs[:, 1:] += power_w
    else:
        inputs[:, 1 + nodes] += power_w


def thermal_result(network: Network, a: np.ndarray, b: np.ndarray,
                   mats: list[StepMatrices], steps: np.ndarray, cls: np.ndarray, time_s: np.ndarray,
                   ambient_c: np.ndarray, linear: bool, temperature_c: np.ndarray,
                   inputs: np.ndarray, ambient_hold: str) -> ThermalResult:
    """The read-only :class:`ThermalResult` of one solved run, shared by :func:`simulate`
    and :func:`thermal.simulate_many`: its rates dT/dt = A T + B u [K/s] now, its heat
    bookkeeping (6) when first read (:func:`_heat_ledger`; the chamber's slope is recomputed
    then from the chamber, as it was made).

    ``a``, ``b`` are the network's matrices of equation (2) (:meth:`Network.matrices`),
    ``mats`` the step matrices of the distinct ``steps`` h [s] and ``cls`` the class of each
    interval (:func:`thermal.inputs.step_classes`), ``linear`` True under a first-order
    chamber hold; ``time_s`` (n_t,) [s], ``ambient_c`` (n_t,) [degC], ``temperature_c``
    (n_t, n) [degC] and ``inputs`` (n_t, 1 + n) = [T_amb,k [degC], P_1,k ... P_n,k [W]]
    become the result's arrays (not copied: the caller hands them over).
    """
    rate = temperature_c @ a.T + inputs @ b.T
    arrays = dict(time_s=time_s, capacity_j_per_k=network.capacity_j_per_k,
                  temperature_c=np.ascontiguousarray(temperature_c), rate_c_per_s=rate,
                  power_w=inputs[:, 1:].copy(), ambient_c=ambient_c)
    for value in arrays.values():
        value.flags.writeable = False
    return ThermalResult(node_names=network.node_names, ambient_hold=ambient_hold,
                         _ledger=(network, mats, steps, cls, linear), **arrays)


def _heat_ledger(result: ThermalResult) -> tuple[np.ndarray, np.ndarray]:
    """(heat_in_j, heat_lost_j) of ``result`` by (4) or (7) and (6): the energy injected by
    the node powers and lost to the chamber from t_0 to each t_k [J]."""
    network, mats, steps, cls, linear = result._ledger
    t, amb, temp = result.time_s, result.ambient_c, result.temperature_c
    n = len(network.node_names)
    inputs = np.empty((t.size, 1 + n))  # u_k = [T_amb,k, P_1,k, ..., P_n,k], equation (2)
    inputs[:, 0] = amb
    inputs[:, 1:] = result.power_w
    _, to_chamber = network.conductances()
    integral = (_per_interval([m.psi for m in mats], cls, temp[:-1], n)
                + _per_interval([m.upsilon for m in mats], cls, inputs[:-1], n))
    h = steps[cls]
    amb_integral = h * amb[:-1]
    if linear:
        slope = np.zeros(t.size)
        slope[:-1] = np.diff(amb) / np.diff(t)
        integral += _per_interval([m.omega[:, None] for m in mats], cls,
                                  slope[:-1, None], n)
        amb_integral = h * 0.5 * (amb[:-1] + amb[1:])
    lost = (integral - amb_integral[:, None]) @ to_chamber
    gained = h * inputs[:-1, 1:].sum(axis=1)
    heat_in = np.concatenate([[0.0], np.cumsum(gained)])
    heat_lost = np.concatenate([[0.0], np.cumsum(lost)])
    heat_in.flags.writeable = heat_lost.flags.writeable = False
    return heat_in, heat_lost
