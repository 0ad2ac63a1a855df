"""The recursions behind thermal/estimate.py: the augmented model, its exact discretisation,
records grouped to share one covariance, and the filter-smoother pass.

Equations (1)-(8) are those of thermal/estimate.py's module docstring; this module holds no
public API of the package (:mod:`thermal.estimate` is it).  It reads the inputs of
:mod:`thermal.sensors` and knows nothing of :mod:`thermal.estimate`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import expm

from thermal.errors import ThermalError
from thermal.network import Network, index_of
from thermal.sensors import LinearSensor, StatePower, ThermalRecord
from thermal.solve import step_matrices

__all__ = ["Model", "Step", "Group", "build_model", "discretise", "group_records",
           "initial_cov", "run_group", "loglik"]

_LOG_2PI = math.log(2.0 * math.pi)


# ---------------------------------------------------------------------------------------------
# The augmented model

@dataclass(frozen=True)
class Model:
    """Matrices of (1)-(4) for x = [T, d, y]."""

    n: int
    a: np.ndarray           # (N, N)
    b: np.ndarray           # (N, 1 + n)
    g_noise: np.ndarray     # (N, n): w enters the d rows, scaled by sqrt(r_j)
    h: np.ndarray           # (m, N)
    offset: np.ndarray      # (m,)
    r: np.ndarray           # (m,) measurement variances [K^2]
    lag_from_t: np.ndarray  # (N - 2n, n): equilibrium lag states = lag_from_t @ T
    inv_c: np.ndarray       # (n,)
    p_const: np.ndarray     # (n,)
    names: tuple[str, ...]
    sensors: tuple[str, ...]
    rates: np.ndarray = field(repr=False, default=None)  # (n, N): dT/dt = rates @ x + B u


def build_model(network: Network, sensors: Sequence[LinearSensor],
                noise_weights: Mapping[str, float] | None) -> Model:
    """The matrices of (1)-(4) for the network, the sensors and the noise weights r_j."""
    names = network.node_names
    n = len(names)
    if not sensors:
        raise ThermalError("state estimation needs at least one sensor")
    n_lag = sum(len(s.lags_s) for s in sensors)
    big = 2 * n + n_lag
    a_t, b_t = network.matrices()
    inv_c = 1.0 / network.capacity_j_per_k
    a = np.zeros((big, big))
    a[:n, :n] = a_t
    a[:n, n:2 * n] = np.diag(inv_c)
    b = np.zeros((big, 1 + n))
    b[:n] = b_t
    h = np.zeros((len(sensors), big))
    lag_from_t = np.zeros((n_lag, n))
    row = 2 * n
    for m, s in enumerate(sensors):
        w = np.zeros(n)
        for node, weight in s.weights.items():
            w[index_of(names, node)] += float(weight)
        src = None                      # the state the next lag reads; None: h_m . T
        for tau in s.lags_s:
            if src is None:
                a[row, :n] = w / tau
            else:
                a[row, src] = 1.0 / tau
            a[row, row] = -1.0 / tau
            lag_from_t[row - 2 * n] = w
            src = row
            row += 1
        if src is None:
            h[m, :n] = w
        else:
            h[m, src] = 1.0
    weights = np.ones(n)
    if noise_weights is not None:
        weights = np.zeros(n)
        for node, r_j in noise_weights.items():
            r_j = float(r_j)
            if not (math.isfinite(r_j) and r_j >= 0.0):
                raise ThermalError(f"noise weight of node {node!r} must be >= 0, got {r_j}")
            weights[index_of(names, node)] = r_j
    g_noise = np.zeros((big, n))
    g_noise[n:2 * n] = np.diag(np.sqrt(weights))
    return Model(n=n, a=a, b=b, g_noise=g_noise, h=h,
                  offset=np.array([s.offset_c for s in sensors]),
                  r=np.array([s.noise_std_c ** 2 for s in sensors]), lag_from_t=lag_from_t,
                  inv_c=inv_c, p_const=network.node_power_w, names=names,
                  sensors=tuple(s.name for s in sensors), rates=a[:n].copy())


@dataclass(frozen=True)
class Step:
    """Discrete matrices for one step h."""

    phi: np.ndarray
    phi_minus_i: np.ndarray
    gamma: np.ndarray
    q_unit: np.ndarray       # Q_d for q = 1 [W^2/s]


def discretise(model: Model, h_s: float) -> Step:
    """Phi, Gamma by solve.py's (5) and Q_d by Van Loan's (5) of thermal/estimate.py."""
    mats = step_matrices(model.a, model.b, h_s)
    big = model.a.shape[0]
    van_loan = np.zeros((2 * big, 2 * big))
    van_loan[:big, :big] = -model.a
    van_loan[:big, big:] = model.g_noise @ model.g_noise.T
    van_loan[big:, big:] = model.a.T
    e = expm(van_loan * h_s)
    q_d = e[big:, big:].T @ e[:big, big:]
    return Step(phi=mats.phi, phi_minus_i=mats.phi_minus_i, gamma=mats.gamma,
                 q_unit=0.5 * (q_d + q_d.T))


# ---------------------------------------------------------------------------------------------
# Records, stacked

@dataclass
class Group:
    """Records that share their length, steps and missing readings, so one covariance,
    one gain sequence and one smoother covariance serve them all: (r, n_k, ...) arrays."""

    members: list[int]
    cls: np.ndarray          # (n_k - 1,) step class of each interval
    seen: np.ndarray         # (n_k, m) True where the readings exist
    z: np.ndarray            # (r, n_k, m), 0 where missing
    u: np.ndarray            # (r, n_k, 1 + n) without the state-dependent power
    x0: np.ndarray           # (r, N)
    laws: list[StatePower | None]


def _check_record(rec: ThermalRecord, i: int, n: int, m: int) -> tuple[np.ndarray, ...]:
    t = np.asarray(rec.time_s, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ThermalError(f"record {i}: time_s must be 1-D with at least 2 samples, got "
                           f"shape {t.shape}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0.0):
        raise ThermalError(f"record {i}: time_s must be finite and strictly increasing")
    z = np.asarray(rec.readings_c, dtype=float)
    if z.shape != (t.size, m):
        raise ThermalError(f"record {i}: readings_c must have shape ({t.size}, {m}), got "
                           f"{z.shape}")
    amb = np.broadcast_to(np.asarray(rec.ambient_c, dtype=float), t.shape)
    if not np.all(np.isfinite(amb)):
        raise ThermalError(f"record {i}: ambient_c is not finite")
    power = np.zeros((t.size, n)) if rec.power_w is None else np.asarray(rec.power_w, float)
    if power.shape != (t.size, n) or not np.all(np.isfinite(power)):
        raise ThermalError(f"record {i}: power_w must be finite with shape ({t.size}, {n}), "
                           f"got shape {power.shape}")
    try:
        t0 = np.broadcast_to(np.asarray(rec.initial_c, dtype=float), (n,))
    except ValueError:
        raise ThermalError(f"record {i}: initial_c must be a scalar or have shape ({n},)") \
            from None
    if not np.all(np.isfinite(t0)):
        raise ThermalError(f"record {i}: initial_c is not finite")
    return t, z, amb, power, t0


def group_records(model: Model, records: Sequence[ThermalRecord]
                  ) -> tuple[list[Step], list[Group]]:
    """The discrete matrices of every distinct step and the records grouped by (length,
    steps, missing readings)."""
    if not records:
        raise ThermalError("state estimation needs at least one record")
    n, m = model.n, model.h.shape[0]
    checked = [_check_record(rec, i, n, m) for i, rec in enumerate(records)]
    keys = np.unique(np.round(np.concatenate([np.diff(c[0]) for c in checked]), 9))
    steps = [discretise(model, float(h)) for h in keys]
    by_key: dict[tuple, list[int]] = {}
    classes = []
    for q, (t, zq, *_rest) in enumerate(checked):
        cls = np.searchsorted(keys, np.round(np.diff(t), 9))
        classes.append(cls)
        key = (t.size, cls.tobytes(), np.isfinite(zq).tobytes())
        by_key.setdefault(key, []).append(q)
    groups = []
    for members in by_key.values():
        first = checked[members[0]]
        seen = np.isfinite(first[1])
        z = np.stack([np.where(seen, checked[q][1], 0.0) for q in members])
        u = np.stack([np.column_stack([checked[q][2], model.p_const + checked[q][3]])
                      for q in members])
        x0 = np.stack([np.concatenate([checked[q][4], np.zeros(n),
                                       model.lag_from_t @ checked[q][4]]) for q in members])
        groups.append(Group(members=members, cls=classes[members[0]], seen=seen, z=z, u=u,
                             x0=x0, laws=[records[q].power_law for q in members]))
    return steps, groups


def initial_cov(model: Model, initial_std_c: float, initial_power_std_w: float) -> np.ndarray:
    """P_0: T along the network's free modes, d_j independent with initial_std_c, lags in
    equilibrium with T (y = L T, so their covariance follows from T's).

    A soaked unit deviates from its start by what the chamber's fluctuations leave after
    the network filtered them: a first-order mode driven by white noise has a variance
    proportional to its time constant, so mode i (shape v_i with max |v_i| = 1, time
    constant tau_i: :meth:`thermal.Network.modes`) gets the variance
    initial_std_c^2 tau_i / tau_1, the slowest mode (the whole unit against the chamber)
    initial_std_c^2.  Nodes coupled within seconds (a wound coil's layers) then start
    together, where independent deviations of initial_std_c would start the filter with
    gradients no soak leaves.
    """
    n = model.n
    big = model.a.shape[0]
    jac = np.zeros((big, 2 * n))
    jac[:n, :n] = np.eye(n)
    jac[n:2 * n, n:] = np.eye(n)
    jac[2 * n:, :n] = model.lag_from_t
    d = 1.0 / np.sqrt(model.inv_c)                         # sqrt(C)
    a = model.a[:n, :n]
    sym = d[:, None] * a / d[None, :]                      # C^1/2 A C^-1/2, symmetric
    rates, u = np.linalg.eigh(-0.5 * (sym + sym.T))
    v = u / d[:, None]                                     # mode shapes C^-1/2 u_i
    v = v / np.max(np.abs(v), axis=0)
    live = rates > 1e3 * np.finfo(float).eps * max(rates.max(), 0.0)
    share = np.ones(n) if not live.all() else rates.min() / rates
    share[~live] = 1.0
    cov_t = (v * (initial_std_c ** 2 * share)) @ v.T
    base = np.zeros((2 * n, 2 * n))
    base[:n, :n] = cov_t
    base[n:, n:] = np.diag(np.full(n, initial_power_std_w ** 2))
    return jac @ base @ jac.T


def law_at(group: Group, k: int, temps: np.ndarray, n: int) -> np.ndarray:
    """Held extra power (r, n) [W] of the group's state-dependent laws at step k."""
    p = np.zeros((temps.shape[0], n))
    try:
        for q, law in enumerate(group.laws):
            if law is not None:
                p[q] = law(k, temps[q])
    except (TypeError, ValueError):
        raise ThermalError(f"power_law must return an array of shape ({n},) of numbers, got "
                           f"{np.shape(law(k, temps[q]))} at sample {k}") from None
    if k == 0 and not np.isfinite(p).all():
        raise ThermalError(f"power_law is not finite at sample {k}")
    return p


def run_group(model: Model, steps: list[Step], group: Group, q_scale: float, p0: np.ndarray,
              smooth: bool):
    """Filter (6) with the likelihood (7) and, when ``smooth``, the smoother (8), for a group.

    The covariance recursion does not depend on the readings, so it runs once for the
    group (N x N arrays) while the means run for all its records at once (r x N).  A
    missing reading zeroes its row of H and gets S_mm = 1, v_m = 0: it then adds nothing to
    the update, to (7) or to (8).  Returns the per-record log-likelihoods (r,) and, with
    ``smooth``, a dict of smoothed arrays.
    """
    n = model.n
    m, big = model.h.shape
    r, n_k = group.z.shape[:2]
    cls = group.cls.tolist()
    seen = group.seen
    phis = [s.phi for s in steps]
    phis_t = [s.phi.T.copy() for s in steps]
    phims_t = [s.phi_minus_i.T.copy() for s in steps]
    gammas_t = [s.gamma.T.copy() for s in steps]
    qds = [q_scale * s.q_unit for s in steps]
    has_law = any(law is not None for law in group.laws)
    patterns: dict[bytes, np.ndarray] = {}
    hks = [patterns.setdefault(row.tobytes(), model.h * row[:, None]) for row in seen]
    r_diag = np.where(seen, model.r, 1.0)
    offset = model.offset * seen                # (n_k, m)
    diag = np.arange(m)

    logdet = 0.0
    quad = np.zeros(r)
    v_all = np.zeros((r, n_k, m))               # innovations v (0 where unseen)
    s_diag = np.ones((n_k, m))                  # diagonal of S (1 where unseen)
    x = group.x0.copy()
    p = p0.copy()
    if smooth:
        xf_all = np.empty((r, n_k, big))
        pf_all = np.empty((n_k, big, big))
        gain_all = np.empty((n_k, big, m))
        sinv_all = np.empty((n_k, m, m))
    for k in range(n_k):
        hk = hks[k]
        pht = p @ hk.T
        s = hk @ pht
        s[diag, diag] += r_diag[k]
        s_inv = np.linalg.inv(s)
        gain = pht @ s_inv
        v = group.z[:, k] - x @ hk.T - offset[k]
        sv = v @ s_inv
        quad += np.sum(sv * v, axis=1)
        sign, ld = np.linalg.slogdet(s)
        if sign <= 0:  # the innovation covariance lost its definiteness: no likelihood
            raise ThermalError("innovation covariance is not positive definite (process "
                               "noise scale out of range)")
        logdet += ld
        x += v @ gain.T
        # Joseph's form (P = (I - K H) P (I - K H)^T + K R K^T; Bucy & Joseph 1968, ch. 4;
        # Grewal & Andrews, Kalman Filtering, 4th ed., sec. 4.2): the covariance stays
        # symmetric positive semi-definite in floating point, which the short form
        # P - K H P does not guarantee over hundreds of steps with a large process noise.
        ikh = -gain @ hk
        ikh[np.diag_indices_from(ikh)] += 1.0
        p = ikh @ p @ ikh.T + (gain * r_diag[k]) @ gain.T
        p = 0.5 * (p + p.T)
        v_all[:, k] = v
        s_diag[k] = s[diag, diag]
        if smooth:
            xf_all[:, k] = x
            pf_all[k] = p
            gain_all[k] = gain
            sinv_all[k] = s_inv
        if k == n_k - 1:
            break
        c = cls[k]
        uk = group.u[:, k]
        if has_law:
            uk = uk.copy()
            uk[:, 1:] += law_at(group, k, x[:, :n], n)
        x = x + x @ phims_t[c] + uk @ gammas_t[c]
        p = phis[c] @ p @ phis_t[c] + qds[c]
    log_l = -0.5 * (quad + logdet + seen.sum() * _LOG_2PI)
    if not np.all(np.isfinite(log_l)):
        raise ThermalError("the filter diverged (a power law or an input is not finite)")
    if not smooth:
        return log_l, None

    # modified Bryson-Frazier backward pass (8)
    lam = np.zeros((r, big))                    # one adjoint per record
    lam_m = np.zeros((big, big))                # shared: it does not depend on readings
    xs = np.empty((r, n_k, big))
    ps_diag = np.empty((n_k, big))
    rate_var = np.empty((n_k, n))
    rates = model.rates
    eye = np.eye(big)
    for k in range(n_k - 1, -1, -1):
        pf = pf_all[k]
        xs[:, k] = xf_all[:, k] - lam @ pf
        ps_diag[k] = np.diagonal(pf) - np.sum((pf @ lam_m) * pf, axis=1)
        mp = rates @ pf
        rate_var[k] = np.sum(mp * rates, axis=1) - np.sum((mp @ lam_m) * mp, axis=1)
        if k == 0:
            break
        hk, gain, s_inv = hks[k], gain_all[k], sinv_all[k]
        lam = lam - (lam @ gain + v_all[:, k] @ s_inv) @ hk
        c_k = eye - gain @ hk
        lam_m = c_k.T @ lam_m @ c_k + hk.T @ s_inv @ hk
        c = cls[k - 1]
        lam = lam @ phis[c]
        lam_m = phis_t[c] @ lam_m @ phis[c]
    law_s = np.zeros((r, n_k, n))
    if has_law:
        for k in range(n_k):
            law_s[:, k] = law_at(group, k, xs[:, k, :n], n)
    rate = (xs @ rates.T + group.u[..., :1] * model.b[:n, 0]
            + (group.u[..., 1:] + law_s) * model.inv_c)
    pred = xs @ model.h.T + model.offset
    innov = np.where(seen, v_all / np.sqrt(s_diag), np.nan)
    out = dict(x=xs, x_filtered=xf_all, var=np.broadcast_to(ps_diag, (r, n_k, big)),
               rate=rate, rate_var=np.broadcast_to(rate_var, (r, n_k, n)),
               innovation=innov, residual=np.where(seen, group.z - pred, np.nan))
    return log_l, out


def loglik(model: Model, steps: list[Step], groups: list[Group], q_scale: float,
           p0: np.ndarray) -> float:
    """log L(q), equation (7), over every group (-inf where the filter's innovation
    covariance is not positive definite: such a q cannot be the maximum)."""
    try:
        return _loglik(model, steps, groups, q_scale, p0)
    except ThermalError:
        return -math.inf


def _loglik(model: Model, steps: list[Step], groups: list[Group], q_scale: float,
            p0: np.ndarray) -> float:
    return float(sum(run_group(model, steps, g, q_scale, p0, smooth=False)[0].sum()
                     for g in groups))
