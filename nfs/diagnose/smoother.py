"""Node temperatures of measured runs, consistent with their thermometers (Kalman smoother).

The drift candidates of the diagnosis (a Shupe term k_r d(T_outer - T_inner)/dt, a bias
b_1 (T_coil - 25)) are evaluated on node temperatures.  Simulated open-loop from the chamber
temperature, a network that is not exact for the unit gives wrong node temperatures, and the
drift misfit is then blamed on a thermal candidate instead of on the gyro effect that is
missing.  Here the node temperatures are estimated from the measured thermometers through
the model's network by :mod:`thermal.estimate` (Kalman filter and Rauch-Tung-Striebel
smoother; the network's error is an unmodelled random-walk heat per node whose scale q is
the maximum-likelihood estimate over all runs).

Each thermometer of the instrument is a :class:`thermal.sensors.LinearSensor`: its node
weights normalised (:meth:`nfs.sensors.ThermometerModel.sensed`), its lag followed by the
``thermometer_lag`` effects on it (lags in series, as :func:`nfs.sensors.thermometer_reading`
applies them), its offset, and a white error of variance noise_c^2 + quantum_c^2 / 12 (the
variance of a uniform rounding error, Bennett 1948, Bell Syst. Tech. J. 27(3), 446; white
only while the reading moves by a quantum or more between knots: on a flat stretch the
rounding error is correlated and the innovations show it).

The estimation runs at decimated knots (every ``decimate_s``, plus the last sample), with the
chamber temperature, the turntable's moving fraction and the state-free thermal-effect
powers averaged over each knot interval and held, and the state-dependent thermal effects
(the TEC law) evaluated at the filtered estimate and held over the interval (its slope left
out of the covariance; thermal/estimate.py).  Temperatures come back to the run's own time
base as the model's own solution at every sample (open loop from the run's start, the
recorded chamber and the heat law at full rate, as the drift stage replays it) plus the
smoother's correction of it, the difference at the knots of the smoothed values and rates
from that solution's, carried between the knots by cubic Hermite interpolation; the rates
are the derivative of those temperatures (at the knots: the model rate A T + B u + C^-1 d
at the smoothed state).  The network's fast answers to known inputs (a wound coil's outer
layers to the electronics' heat after power-on, within seconds) come from the solution at
full rate, what the thermometers correct varies over the knots: interpolating the whole
state instead loses what happens within a knot interval, and a drift effect on a wound
coil's face then leaves a residual that is not noise on the model's own runs.

What the thermometers cannot tell: no thermometer sees the coil's inner layers, and the FOG
thermometer reads a weighted mean of the electronics and coil_outer, so how the unmodelled
heat splits among those nodes comes from the network's dynamics and the prior, not from a
reading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

import thermal
from thermal import (LinearSensor, NodeEstimate, ProcessNoiseFit, ThermalRecord,
                     estimate_states)
from thermal.network import index_of

from ..docfields import document_fields
from ..effects.thermometer import THERMOMETERS
from ..errors import InputError, NfsError, ThermalError
from ..conditions import conditions_from_run
from ..heat import fixed_thermal_power, thermal_power
from ..instrument import Instrument
from ..run import Run

__all__ = ["SmoothedThermal", "RunSmoothing", "smooth_runs", "thermometer_sensors",
           "DEFAULT_DECIMATE_S"]

#: Default spacing of the estimation knots [s].
DEFAULT_DECIMATE_S = 10.0

#: Lags shorter than this fraction of the knot interval are left out of the sensors
#: (:func:`thermometer_sensors`).
_MIN_LAG_FRACTION = 0.1

#: Floor of a thermometer's error standard deviation [degC] when its noise and quantum are 0:
#: the filter needs a positive measurement variance.
_MIN_NOISE_C = 1e-3


@dataclass(frozen=True)
class SmoothedThermal:
    """Smoothed node temperatures of one run on its own time base.

    Has the fields of :class:`thermal.ThermalResult` that the effects read (``time_s``,
    ``node_names``, ``temperature_c``, ``rate_c_per_s``), so
    :func:`nfs.experiment.effect_context` accepts it.  Every array is read-only.
    """

    name: str
    """The run's name."""

    time_s: np.ndarray
    """Sample times t [s] of the run, shape (n_t,)."""

    node_names: tuple[str, ...]
    """Node names, the column order of the node arrays."""

    temperature_c: np.ndarray
    """Smoothed node temperatures [degC], shape (n_t, n_nodes): cubic Hermite interpolation
    of the knot estimates."""

    rate_c_per_s: np.ndarray
    """dT/dt [K/s], shape (n_t, n_nodes): the derivative of ``temperature_c`` (the model rate
    at the smoothed state at every knot)."""

    temperature_std_c: np.ndarray
    """Standard deviation of the temperatures [K], linear between the knots."""

    knots: NodeEstimate
    """The estimate at the knots: rates with their errors, the unmodelled heat per node,
    standardised innovations and the thermometer residual."""

    def node(self, name: str) -> np.ndarray:
        """Temperature of node ``name`` [degC], shape (n_t,)."""
        return self.temperature_c[:, index_of(self.node_names, name)]

    def rate(self, name: str) -> np.ndarray:
        """Rate of node ``name`` [K/s], shape (n_t,)."""
        return self.rate_c_per_s[:, index_of(self.node_names, name)]


@document_fields
@dataclass(frozen=True)
class RunSmoothing:
    """Smoothed node temperatures of every run and the process noise they share."""

    runs: tuple[SmoothedThermal, ...]
    """One per run, in order."""

    q_w2_per_s: float
    """Process-noise scale q [W^2/s] of the unmodelled heat (thermal/estimate.py, (2))."""

    fit: ProcessNoiseFit | None
    """The maximum-likelihood search of q (None when q was given)."""

    log_likelihood: float
    """Innovation log-likelihood of all runs at q [1]."""

    thermometer_rms_c: dict[str, float]
    """RMS of measured minus smoothed reading at the knots, per thermometer column [K]."""


def _norm_weights(model) -> dict[str, float]:
    total = sum(model.nodes.values())
    return {node: w / total for node, w in model.nodes.items()}


def thermometer_sensors(inst: Instrument, min_lag_s: float = 0.0) -> list[LinearSensor]:
    """The instrument's thermometers as linear sensors, in the order of ``THERMOMETERS``.

    A lag shorter than ``min_lag_s`` [s] is left out: its reading follows the sensed
    temperature within tau dT/dt (5e-4 K for 1 s at 0.03 K/min), below the thermometer's
    noise, and a state that relaxes in a fraction of a knot interval makes the filter's
    covariance recursion ill-conditioned (a fitted lag that ran towards 0 s did).

    Raises
    ------
    NfsError
        A thermometer effect other than ``thermometer_lag`` (not a linear lag).
    """
    extra: dict[str, list[float]] = {name: [] for name in THERMOMETERS}
    for e in inst.effects:
        if e.spec.kind != "thermometer":
            continue
        if e.name != "thermometer_lag":
            raise NfsError(f"effect '{e.label}' changes a thermometer reading in a way the "
                           "smoother cannot model (only thermometer_lag is a linear lag)")
        extra[e.params["thermometer"]].append(float(e.params["tau"]))
    out = []
    for name in THERMOMETERS:
        model = inst.thermometers[name]
        lags = [t for t in [model.lag_s, *extra[name]] if t > 0 and t >= min_lag_s]
        std = math.sqrt(model.noise_c ** 2 + model.quantum_c ** 2 / 12.0)
        out.append(LinearSensor(name=name, weights=_norm_weights(model),
                                noise_std_c=max(std, _MIN_NOISE_C), lags_s=tuple(lags),
                                offset_c=model.offset_c))
    return out


@dataclass(frozen=True)
class _Prepared:
    record: ThermalRecord
    time_s: np.ndarray
    knots: np.ndarray
    open_loop: thermal.ThermalResult
    """The model's solution at every sample, from the run's start (what the smoother
    corrects)."""


def _window_mean(x: np.ndarray, knots: np.ndarray) -> np.ndarray:
    """Mean of x over [knots[i], knots[i+1]) (the last knot: its own sample)."""
    counts = np.diff(np.append(knots, x.shape[0]))
    sums = np.add.reduceat(x, knots, axis=0)
    return sums / (counts if x.ndim == 1 else counts[:, None])


def _prepare(inst: Instrument, run: Run, decimate_s: float,
             start_c: np.ndarray | None = None) -> _Prepared:
    for col in ("time_s", "position_deg", "moving", *THERMOMETERS.values()):
        if col not in run.columns:
            raise InputError(f"run '{run.name}' has no column '{col}', which the thermal "
                             "smoother needs", file=run.path, column=col)
    cond = conditions_from_run(run)
    t = np.asarray(run["time_s"], dtype=float)
    if t.size < 3:
        raise InputError(f"run '{run.name}' has {t.size} samples; the smoother needs a record",
                         file=run.path)
    dt = float(np.median(np.diff(t)))
    step = max(1, int(round(decimate_s / dt)))
    knots = np.arange(0, t.size, step)
    if knots[-1] != t.size - 1:
        knots = np.append(knots, t.size - 1)
    moving = np.asarray(run["moving"], dtype=float)
    amb = (np.full(t.size, cond.start_temperature_c) if cond.chamber_c is None
           else np.asarray(run["temp_chamber_c"], dtype=float))
    names = inst.network.node_names
    n = len(names)
    t_knot, moving_knot = t[knots], _window_mean(moving, knots)
    # the heat of the thermal effects; while the unit is off (power cycles, nfs.power)
    # none, and the network's constant node powers cancelled
    powered = cond.powered(t)
    fixed, _, stateful_effects = fixed_thermal_power(inst, t, moving, powered)
    stateful = [(e.spec.function, j, params) for e, j, params in stateful_effects]
    law = None
    if stateful:
        times, moves = t_knot.tolist(), moving_knot.tolist()
        on_knot = ([True] * len(times) if powered is None
                   else (_window_mean(powered.astype(float), knots) > 0.5).tolist())

        def law(k: int, temperature_c: np.ndarray) -> np.ndarray:
            """Held power of the state-dependent effects at knot k [W] (none while off)."""
            p = np.zeros(n)
            if not on_knot[k]:
                return p
            for f, j, params in stateful:
                p[j] += f(times[k], float(temperature_c[j]), moves[k], **params)
            return p

    readings = np.column_stack([np.asarray(run[col], dtype=float)[knots]
                                for col in THERMOMETERS.values()])
    initial = cond.start_temperature_c if start_c is None else start_c
    record = ThermalRecord(time_s=t_knot, readings_c=readings,
                           ambient_c=_window_mean(amb, knots), initial_c=initial,
                           power_w=_window_mean(fixed, knots), power_law=law)
    power, _, _ = thermal_power(inst, t, moving, powered)
    open_loop = thermal.simulate(inst.network, t, ambient_c=amb, initial_c=initial,
                                 power_w=power, ambient_hold="first-order")
    return _Prepared(record=record, time_s=t, knots=knots, open_loop=open_loop)


def _hermite(t: np.ndarray, t_knot: np.ndarray, y: np.ndarray, m: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite interpolant of values y and slopes m at t_knot, and its derivative."""
    j = np.minimum(np.searchsorted(t_knot, t, side="right") - 1, t_knot.size - 2)
    h = np.diff(t_knot)[j][:, None]
    s = ((t - t_knot[j])[:, None]) / h
    s2, s3 = s * s, s * s * s
    value = ((2 * s3 - 3 * s2 + 1) * y[j] + (s3 - 2 * s2 + s) * h * m[j]
             + (-2 * s3 + 3 * s2) * y[j + 1] + (s3 - s2) * h * m[j + 1])
    slope = ((6 * s2 - 6 * s) / h * y[j] + (3 * s2 - 4 * s + 1) * m[j]
             + (-6 * s2 + 6 * s) / h * y[j + 1] + (3 * s2 - 2 * s) * m[j + 1])
    return value, slope


def smooth_runs(inst: Instrument, runs: Sequence[Run], *,
                decimate_s: float = DEFAULT_DECIMATE_S, q_w2_per_s: float | None = None,
                bounds_w2_per_s: tuple[float, float] = (1e-12, 1e-1),
                noise_weights: Mapping[str, float] | None = None,
                initial_std_c: float = 0.05, initial_power_std_w: float = 0.0,
                initial_power_bounds_w: tuple[float, float] | None = None,
                start_c: Mapping[str, np.ndarray] | None = None) -> RunSmoothing:
    """Node temperatures of ``runs`` estimated from their thermometers through ``inst``'s network.

    Parameters
    ----------
    inst : Instrument
        The model (network, thermometers, thermal and thermometer effects).
    runs : sequence of Run
        Measured runs with ``time_s``, ``position_deg``, ``moving`` and the three thermometer
        columns (and ``temp_chamber_c`` when the chamber was not held at T0); each starts
        soaked at its ``start_temperature_c``.
    decimate_s : float
        Spacing of the estimation knots [s].
    q_w2_per_s : float, optional
        Process-noise scale [W^2/s]; by default its maximum-likelihood estimate over all runs
        within ``bounds_w2_per_s``.
    bounds_w2_per_s : (float, float)
        Search interval of q [W^2/s].
    initial_std_c : float
        Standard deviation of every node temperature about its start at power-on [K].
    initial_power_std_w : float
        Standard deviation of the unmodelled heat of every node at power-on [W].  The
        default 0 lets the unmodelled heat grow from zero (a wrong capacity or conductance
        errs only once the unit warms); a heat source the model lacks is present from
        power-on and is found at the right node only with a prior here (e.g. 0.3 W, against
        node powers of 0.45-7 W).
    noise_weights : mapping node -> float, optional
        Relative spectral densities of the unmodelled heat (default 1 at every node).
    initial_power_bounds_w : (float, float), optional
        Estimate the unmodelled heat's standard deviation at power-on by maximum likelihood
        within these bounds [W] too (with q; about three times the filter runs).
    start_c : mapping {run name: node temperatures [degC]}, optional
        Each run's start (:func:`nfs.fit.thermal_residual.start_states`: an unfinished
        soak); a run not in it starts at its T0 everywhere.

    Returns
    -------
    RunSmoothing
        Per run a :class:`SmoothedThermal` for :func:`nfs.experiment.effect_context`.

    Raises
    ------
    NfsError
        No runs, a run without a column it needs, a bad decimation or noise setting.
    """
    runs = list(runs)
    if not runs:
        raise NfsError("smooth_runs: no runs")
    if not (math.isfinite(decimate_s) and decimate_s > 0):
        raise NfsError(f"smooth_runs: decimate_s must be > 0, got {decimate_s}")
    sensors = thermometer_sensors(inst, min_lag_s=_MIN_LAG_FRACTION * decimate_s)
    start_c = start_c or {}
    prepared = [_prepare(inst, run, decimate_s, start_c.get(run.name)) for run in runs]
    try:
        est = estimate_states(inst.network, sensors, [p.record for p in prepared],
                              q_w2_per_s=q_w2_per_s, bounds_w2_per_s=bounds_w2_per_s,
                              noise_weights=noise_weights, initial_std_c=initial_std_c,
                              initial_power_std_w=initial_power_std_w,
                              initial_power_bounds_w=initial_power_bounds_w)
    except ThermalError as exc:
        raise NfsError(f"smooth_runs: {exc}") from None
    out = []
    for run, prep, knot in zip(runs, prepared, est.records):
        ol = prep.open_loop
        temp, rate = _hermite(prep.time_s, knot.time_s,
                              knot.temperature_c - ol.temperature_c[prep.knots],
                              knot.rate_c_per_s - ol.rate_c_per_s[prep.knots])
        temp += ol.temperature_c
        rate += ol.rate_c_per_s
        std = np.column_stack([np.interp(prep.time_s, knot.time_s, s)
                               for s in knot.temperature_std_c.T])
        for a in (temp, rate, std):
            a.flags.writeable = False
        out.append(SmoothedThermal(name=run.name, time_s=prep.time_s,
                                   node_names=knot.node_names, temperature_c=temp,
                                   rate_c_per_s=rate, temperature_std_c=std, knots=knot))
    rms = {}
    for m, col in enumerate(THERMOMETERS.values()):
        res = np.concatenate([k.residual_c[:, m] for k in est.records])
        res = res[np.isfinite(res)]
        rms[col] = float(np.sqrt(np.mean(res * res))) if res.size else math.nan
    return RunSmoothing(runs=tuple(out), q_w2_per_s=est.q_w2_per_s, fit=est.fit,
                        log_likelihood=est.log_likelihood, thermometer_rms_c=rms)
