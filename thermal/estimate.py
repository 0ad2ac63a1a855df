"""Node temperatures estimated from linear sensors through the network (Kalman filter, smoother).

The network of network.py, equation (1), is never exact for a real unit.  Its error is
modelled as an unmodelled heat input d_j(t) [W] at every node, a random walk, and the nodes
are read by linear sensors through first-order lags:

    C_j dT_j/dt = sum_k G_jk (T_k - T_j) + G_j,amb (T_amb - T_j) + P_j(t, T) + d_j        (1)
    dd_j/dt = w_j,       E[w_j(t) w_l(s)] = q r_j delta_jl delta(t - s)   [W^2/s]           (2)
    tau_m,i dy_m,i/dt = y_m,i-1 - y_m,i,   y_m,0 = sum_j h_mj T_j          [degC]           (3)
    z_m(t_k) = y_m,last(t_k) + o_m + v_m,k,   v_m,k ~ N(0, sigma_m^2)      [degC]           (4)

(3) is the first-order lag of nfs/signal.py, one state per lag of a sensor's chain (none:
the sensor reads h_m . T directly).  The state is x = [T (n), d (n), y (lag states)] and
(1)-(3) are dx/dt = A x + B u + G w with u = [T_amb, P_1, ..., P_n] held over each interval,
as in solve.py.  q is the process-noise scale [W^2/s] (estimated by maximum likelihood,
:func:`fit_process_noise`) and r_j >= 0 fixed relative weights (default 1 at every node).

Why a random-walk heat and not white noise on the temperatures: the error of a wrong network
(a capacity, a conductance, a missing source) is a persistent, smooth heat flow.  A random-
walk d makes the temperature corrections smooth and the rate dT/dt = A T + B u + C^-1 d a
function of the state, so the rates come from the model dynamics at the smoothed state
(white noise on T gives the smoothed temperatures a kink at every sample and no rate), and
the smoothed d_j says where, and how much, heat the network lacks.

Discretisation, exact for held inputs over a step h (solve.py, equation (5) for Phi and
Gamma; Van Loan 1978, IEEE TAC 23(3), theorem 1, for the process noise):

    x_k+1 = x_k + (Phi - I) x_k + Gamma u_k + w_k,
    E[w_k w_k'] = Q_d = int_0^h e^{As} G Q G' e^{A's} ds,   Q = q diag(r_j)
    expm([[-A, G Q G'], [0, A']] h) = [[., Phi^-1 Q_d], [0, Phi']]                          (5)

A state-dependent power p(T_k) (a TEC law), held over the step as the simulator holds it,
enters the mean exactly: it is evaluated at the filtered (smoothed, for the rates) estimate
and held, x_k+1 = ... + Gamma_P p(T_k^+).  Its slope dp/dT is left out of the covariance,
which propagates with the network's Phi alone (an extended Kalman filter would use
F_k = Phi + Gamma_P dp/dT; Simon 2006, Optimal State Estimation, section 13.2).  For the
TEC the slope is 0.02-0.1 W/K against the electronics' 1.1 W/K of conductances, a few per
cent of one entry of A; leaving it out makes the covariance, the gains and the smoother's
Lam independent of the readings, so they are computed once for all records that share
their time steps and missing readings, which is what makes the filter fast.

Filter (Simon 2006, equations 5.19):

    v_k = z_k - H x_k^- - o,   S_k = H P_k^- H' + R,   K_k = P_k^- H' S_k^-1
    x_k^+ = x_k^- + K_k v_k,   P_k^+ = (I - K_k H) P_k^-                                 (6)

A missing reading (NaN) zeroes its row of H at that step.

Log-likelihood by the prediction-error decomposition (Harvey 1989, Forecasting, Structural
Time Series Models and the Kalman Filter, section 3.4; Shumway & Stoffer 2017, Time
Series Analysis and Its Applications, section 6.3; equation numbers not checked):

    log L(q) = -1/2 sum_k [log det S_k + v_k' S_k^-1 v_k + m_k log 2 pi]                  (7)

Smoother: the modified Bryson-Frazier form of the Rauch-Tung-Striebel fixed-interval
smoother (Bierman 1973, "Fixed interval smoothing with discrete measurements", Int. J.
Control 18(1), 65-75), which needs no inverse of P_k^- (singular when q = 0):

    lam~_N = 0, Lam~_N = 0;   C_k = I - K_k H
    lam^_k = -H' S_k^-1 v_k + C_k' lam~_k,     Lam^_k = H' S_k^-1 H + C_k' Lam~_k C_k
    lam~_k-1 = F_k-1' lam^_k,                  Lam~_k-1 = F_k-1' Lam^_k F_k-1
    x_k|N = x_k^+ - P_k^+ lam~_k,              P_k|N = P_k^+ - P_k^+ Lam~_k P_k^+           (8)

The recursions are written here rather than taken from filterpy or pykalman: neither
discretises a continuous model exactly with Van Loan's process noise, neither is a
dependency of the package, and running all records at once as stacked NumPy arrays (one
Python loop over the steps, not one per record, and one covariance for all) is what makes
seven 2.5 h runs smooth in a fraction of a second.  They live in :mod:`thermal.kalman`; the
inputs (:class:`LinearSensor`, :class:`ThermalRecord`, the power law :data:`StatePower`) in
:mod:`thermal.sensors`, below both; this module holds the results and the functions to call.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize, minimize_scalar

from thermal import kalman
from thermal.errors import ThermalError
from thermal.network import Network, index_of
from thermal.sensors import LinearSensor, ThermalRecord

__all__ = ["NodeEstimate", "ProcessNoiseFit", "StateEstimate", "kalman_smooth",
           "fit_process_noise", "estimate_states"]

#: 5 % critical value of the boundary likelihood-ratio test, 1/2 chi^2_0 + 1/2 chi^2_1
#: (the 90 % point of chi^2_1).
_LR_CRITICAL = 2.706


@dataclass(frozen=True)
class NodeEstimate:
    """Smoothed node temperatures of one record at its times t_k."""

    time_s: np.ndarray
    """t_k [s], shape (n_k,)."""

    node_names: tuple[str, ...]
    """Node names, the column order of the node arrays."""

    sensor_names: tuple[str, ...]
    """Sensor names, the column order of the sensor arrays."""

    temperature_c: np.ndarray
    """Smoothed T_j(t_k) = E[T | all readings] [degC], shape (n_k, n)."""

    temperature_std_c: np.ndarray
    """Its standard deviation [K], shape (n_k, n)."""

    rate_c_per_s: np.ndarray
    """dT_j/dt at t_k [K/s] = A T + B u_k + C^-1 d from (1) at the smoothed state."""

    rate_std_c_per_s: np.ndarray
    """Standard deviation of the rate [K/s], shape (n_k, n) (the power law's slope left
    out, as in the covariance)."""

    heat_w: np.ndarray
    """Smoothed unmodelled heat input d_j(t_k) [W], shape (n_k, n)."""

    heat_std_w: np.ndarray
    """Its standard deviation [W], shape (n_k, n)."""

    filtered_temperature_c: np.ndarray
    """Filtered T_j(t_k) = E[T | readings up to t_k] [degC], shape (n_k, n)."""

    innovation: np.ndarray
    """Standardised innovations v_m,k / sqrt(S_mm,k) [1], shape (n_k, n_sensors); N(0, 1)
    and white when the model and its noise are right; NaN where the reading is missing."""

    residual_c: np.ndarray
    """Reading minus the smoothed reading z - H x_k|N - o [degC], (n_k, n_sensors)."""

    log_likelihood: float
    """This record's share of (7) [1]."""

    def node(self, name: str) -> np.ndarray:
        """Smoothed temperature of node ``name`` [degC], shape (n_k,)."""
        return self.temperature_c[:, index_of(self.node_names, name)]

    def rate(self, name: str) -> np.ndarray:
        """Smoothed rate of node ``name`` [K/s], shape (n_k,)."""
        return self.rate_c_per_s[:, index_of(self.node_names, name)]


@dataclass(frozen=True)
class ProcessNoiseFit:
    """Maximum-likelihood estimate of the process-noise scale q of (2)."""

    q_w2_per_s: float
    """q-hat [W^2/s], the argmax of (7) over the bounds."""

    log10_stderr: float
    """Standard error of log10 q-hat from the curvature of (7) [decades] (inf when the
    likelihood is flat there or q-hat sits on a bound)."""

    log_likelihood: float
    """log L(q-hat) [1]."""

    log_likelihood_zero: float
    """log L at the lower bound (the network taken as exact) [1]."""

    bounds_w2_per_s: tuple[float, float]
    """The search interval of q [W^2/s]."""

    at_lower_bound: bool
    """True when q-hat is the lower bound: the readings show no network error."""

    at_upper_bound: bool
    """True when q-hat is the upper bound."""

    significant: bool
    """True when the likelihood-ratio statistic 2 (log L(q-hat) - log L(lower bound))
    exceeds 2.706, the 5 % point of its null distribution 1/2 chi^2_0 + 1/2 chi^2_1 for a
    variance on the boundary (Self & Liang 1987, JASA 82(398), 605-610): the readings show a
    network error."""

    initial_power_std_w: float
    """Standard deviation of the unmodelled heat at t_0 [W] the likelihood was maximised
    with: the one given, or its estimate when ``initial_power_bounds_w`` was given."""

    n_evaluations: int
    """Filter runs of the search."""


@dataclass(frozen=True)
class StateEstimate:
    """The smoothed records and the process noise they were smoothed with."""

    records: tuple[NodeEstimate, ...]
    """One per input record, in order."""

    q_w2_per_s: float
    """Process-noise scale q used [W^2/s]."""

    log_likelihood: float
    """log L(q), equation (7), over all records [1]."""

    fit: ProcessNoiseFit | None = None
    """The maximum-likelihood search, when q was estimated."""


# ---------------------------------------------------------------------------------------------
# Public functions

def _check_scale(q_w2_per_s: float) -> float:
    q = float(q_w2_per_s)
    if not (math.isfinite(q) and q >= 0.0):
        raise ThermalError(f"process noise q must be a finite number >= 0 W^2/s, got {q}")
    return q


def kalman_smooth(network: Network, sensors: Sequence[LinearSensor],
                  records: Sequence[ThermalRecord], *, q_w2_per_s: float,
                  noise_weights: Mapping[str, float] | None = None,
                  initial_std_c: float = 0.05, initial_power_std_w: float = 0.0
                  ) -> StateEstimate:
    """Smoothed node temperatures of every record for a given process noise q, (1)-(8).

    Parameters
    ----------
    network : Network
        The thermal network (the model, possibly wrong).
    sensors : sequence of LinearSensor
        The sensors; the columns of every record's ``readings_c`` in this order.
    records : sequence of ThermalRecord
        Held inputs and readings; all are filtered together (one loop over the steps).
    q_w2_per_s : float
        Process-noise scale q of (2) [W^2/s], >= 0 (0: the network taken as exact).
    noise_weights : mapping node -> r_j, optional
        Relative spectral densities of the unmodelled heat per node (default 1 everywhere;
        0 switches a node's unmodelled heat off).
    initial_std_c : float
        Standard deviation of every node temperature at t_0 about ``initial_c`` [K].
    initial_power_std_w : float
        Standard deviation of the unmodelled heat d_j at t_0 [W] (0: none before t_0).

    Returns
    -------
    StateEstimate
    """
    q = _check_scale(q_w2_per_s)
    for what, value in (("initial_std_c", initial_std_c),
                        ("initial_power_std_w", initial_power_std_w)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ThermalError(f"{what} must be >= 0, got {value}")
    model = kalman.build_model(network, sensors, noise_weights)
    steps, groups = kalman.group_records(model, records)
    p0 = kalman.initial_cov(model, initial_std_c, initial_power_std_w)
    results: list[NodeEstimate | None] = [None] * len(records)
    total = 0.0
    for group in groups:
        per_record, out = kalman.run_group(model, steps, group, q, p0, smooth=True)
        total += float(per_record.sum())
        for g, i in enumerate(group.members):
            results[i] = _node_estimate(model, records[i], out, g, float(per_record[g]))
    return StateEstimate(records=tuple(results), q_w2_per_s=q, log_likelihood=total)


def _node_estimate(model: kalman.Model, rec: ThermalRecord, out: dict, i: int,
                   log_likelihood: float) -> NodeEstimate:
    """Record i of a group's smoothed arrays as a read-only :class:`NodeEstimate`."""
    n = model.n
    k = out["x"].shape[1]
    arrays = dict(
        time_s=np.asarray(rec.time_s, dtype=float).copy(),
        temperature_c=out["x"][i, :k, :n].copy(),
        temperature_std_c=np.sqrt(np.maximum(out["var"][i, :k, :n], 0.0)),
        rate_c_per_s=out["rate"][i, :k].copy(),
        rate_std_c_per_s=np.sqrt(np.maximum(out["rate_var"][i, :k], 0.0)),
        heat_w=out["x"][i, :k, n:2 * n].copy(),
        heat_std_w=np.sqrt(np.maximum(out["var"][i, :k, n:2 * n], 0.0)),
        filtered_temperature_c=out["x_filtered"][i, :k, :n].copy(),
        innovation=out["innovation"][i, :k].copy(),
        residual_c=out["residual"][i, :k].copy())
    for value in arrays.values():
        value.flags.writeable = False
    return NodeEstimate(node_names=model.names, sensor_names=model.sensors,
                        log_likelihood=log_likelihood, **arrays)


def fit_process_noise(network: Network, sensors: Sequence[LinearSensor],
                      records: Sequence[ThermalRecord], *,
                      bounds_w2_per_s: tuple[float, float] = (1e-12, 1e-1),
                      noise_weights: Mapping[str, float] | None = None,
                      initial_std_c: float = 0.05, initial_power_std_w: float = 0.0,
                      initial_power_bounds_w: tuple[float, float] | None = None,
                      xatol_decades: float = 0.05) -> ProcessNoiseFit:
    """The q of (2) that maximises the innovation likelihood (7) over all records.

    A bounded 1-D search in log10 q (:func:`scipy.optimize.minimize_scalar`, method
    ``bounded``), then the lower bound is checked too (the likelihood of an exact network
    often peaks at q -> 0, which an interior search only approaches).  The standard error
    of log10 q-hat is 1 / sqrt(-d^2 log L / d(log10 q)^2), the curvature by central
    differences (the asymptotic variance of a maximum-likelihood estimate).

    With ``initial_power_bounds_w`` the standard deviation of the unmodelled heat at t_0 is
    estimated too: after the 1-D search, a bounded Nelder-Mead search over (log10 q,
    log10 of that standard deviation) (:func:`scipy.optimize.minimize`), about three times
    the filter runs.

    Parameters are those of :func:`kalman_smooth`; ``bounds_w2_per_s`` is the search
    interval of q [W^2/s] (both > 0) and ``xatol_decades`` the tolerance in log10.
    """
    lo, hi = _log_bounds(bounds_w2_per_s, "bounds_w2_per_s")
    model = kalman.build_model(network, sensors, noise_weights)
    steps, groups = kalman.group_records(model, records)
    covs: dict[float, np.ndarray] = {}
    count = [0]

    def loglik(log10_q: float, power_std_w: float) -> float:
        count[0] += 1
        if power_std_w not in covs:
            covs[power_std_w] = kalman.initial_cov(model, initial_std_c, power_std_w)
        return kalman.loglik(model, steps, groups, 10.0 ** log10_q, covs[power_std_w])

    def best_q(power_std_w: float) -> tuple[float, float]:
        res = minimize_scalar(lambda e: -loglik(e, power_std_w), bounds=(lo, hi),
                              method="bounded", options={"xatol": xatol_decades})
        return float(res.x), float(-res.fun)

    power_std = float(initial_power_std_w)
    best, best_ll = best_q(power_std)
    if initial_power_bounds_w is not None:
        p_lo, p_hi = _log_bounds(initial_power_bounds_w, "initial_power_bounds_w")
        start = np.array([min(max(best, lo + 1.0), hi - 1.0), 0.5 * (p_lo + p_hi)])
        simplex = np.array([start, start + [1.0, 0.0], start + [0.0, 1.0]])
        res = minimize(lambda e: -loglik(e[0], 10.0 ** e[1]), start, method="Nelder-Mead",
                       bounds=[(lo, hi), (p_lo, p_hi)],
                       options={"xatol": xatol_decades, "fatol": 0.1,
                                "initial_simplex": simplex})
        best, power_std, best_ll = float(res.x[0]), 10.0 ** float(res.x[1]), float(-res.fun)
    ll_lo = loglik(lo, power_std)
    if ll_lo >= best_ll:
        best, best_ll = lo, ll_lo
    at_lo = best - lo < 2.0 * xatol_decades
    at_hi = hi - best < 2.0 * xatol_decades
    stderr = math.inf
    if not (at_lo or at_hi):
        step = 0.1
        curv = (loglik(best + step, power_std) - 2.0 * best_ll
                + loglik(best - step, power_std)) / step ** 2
        if curv < 0.0:
            stderr = 1.0 / math.sqrt(-curv)
    return ProcessNoiseFit(q_w2_per_s=10.0 ** best, log10_stderr=stderr, log_likelihood=best_ll,
                           log_likelihood_zero=ll_lo, bounds_w2_per_s=(10.0 ** lo, 10.0 ** hi),
                           at_lower_bound=bool(at_lo), at_upper_bound=bool(at_hi),
                           significant=bool(2.0 * (best_ll - ll_lo) > _LR_CRITICAL),
                           initial_power_std_w=power_std, n_evaluations=count[0])


def _log_bounds(bounds: tuple[float, float], what: str) -> tuple[float, float]:
    """log10 of a search interval 0 < low < high, or a ThermalError naming it."""
    lo, hi = (float(b) for b in bounds)
    if not (0.0 < lo < hi and math.isfinite(hi)):
        raise ThermalError(f"{what} must satisfy 0 < low < high, got {bounds}")
    return math.log10(lo), math.log10(hi)


def estimate_states(network: Network, sensors: Sequence[LinearSensor],
                    records: Sequence[ThermalRecord], *,
                    q_w2_per_s: float | None = None,
                    bounds_w2_per_s: tuple[float, float] = (1e-12, 1e-1),
                    noise_weights: Mapping[str, float] | None = None,
                    initial_std_c: float = 0.05, initial_power_std_w: float = 0.0,
                    initial_power_bounds_w: tuple[float, float] | None = None
                    ) -> StateEstimate:
    """:func:`fit_process_noise` (unless ``q_w2_per_s`` is given), then :func:`kalman_smooth`.

    The records share one q: the network's error is a property of the unit, not of a run.
    ``initial_power_bounds_w`` (with q estimated) estimates the initial heat's standard
    deviation too, and the smoother uses the estimate.
    """
    fit = None
    if q_w2_per_s is None:
        fit = fit_process_noise(network, sensors, records, bounds_w2_per_s=bounds_w2_per_s,
                                noise_weights=noise_weights, initial_std_c=initial_std_c,
                                initial_power_std_w=initial_power_std_w,
                                initial_power_bounds_w=initial_power_bounds_w)
        q_w2_per_s = fit.q_w2_per_s
        initial_power_std_w = fit.initial_power_std_w
    out = kalman_smooth(network, sensors, records, q_w2_per_s=q_w2_per_s,
                        noise_weights=noise_weights, initial_std_c=initial_std_c,
                        initial_power_std_w=initial_power_std_w)
    return StateEstimate(records=out.records, q_w2_per_s=out.q_w2_per_s,
                         log_likelihood=out.log_likelihood, fit=fit)
