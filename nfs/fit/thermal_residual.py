"""The thermal stage's residual: the network solved on a run's knots, the thermometers read.

:func:`prepare_thermal` puts a run on the decimated grid (knots every ``decimate_s``, the
chamber temperature and the turntable's moving fraction averaged over each step, the measured
readings at the knots); :func:`simulate_knots` solves the network at the knots with the exact
step of :func:`thermal.simulate` (zero-order hold over each knot interval) and
:func:`readings` brings the sensed node temperatures back to the run's own time base by cubic
Hermite interpolation (values and the solver's exact rates at the knots) and runs the
thermometer chain of the simulator (:func:`nfs.sensors.thermometer_reading`: lag,
thermometer effects, offset) with noise and quantisation off.

Every function takes a *sequence* of instruments that share a network's structure (the same
nodes and effects, other parameter values) and solves them together: all runs of all
instruments march over the knots as one stack, each instrument with its own step matrices.
A least-squares fit evaluates its residual at n + 1 parameter vectors for one forward-
difference Jacobian; stacked, the Python loop over the knots runs once instead of n + 1 times
(:func:`nfs.fit.stage.solve_stage`, ``batch``).  One instrument gives the same numbers
as a stack of many (tested).
"""

# About 530 lines, one concept: the grid, the stacked network solve, the readings and the
# residual share the stacking convention (instrument, run, knot) and the ThermalRun and Knots
# types; split, each part would need the others' internals.

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Iterable, Sequence

import numpy as np
from scipy.signal import lfilter

import thermal
from thermal.solve import step_matrices

from ..effects.thermometer import THERMOMETERS
from ..errors import InputError, NfsError
from ..conditions import conditions_from_run
from ..heat import thermal_effects, thermal_power
from ..instrument import Instrument
from ..power import POWERED_COLUMN
from ..run import Run
from ..sensors import thermometer_reading
from ..signal import uniform_steps
from .start_state import StartModel, solve_amplitudes, start_basis, soak_history, start_prior

__all__ = ["MAX_STACK", "THERMAL_COLUMNS", "DEFAULT_START", "ThermalRun", "Knots", "StatefulLaw",
           "ThermalResidual", "prepare_thermal", "simulate_knots", "readings",
           "thermometer_floors", "thermal_residual", "thermal_residual_parts", "start_states",
           "require_columns", "decimation_step", "window_mean"]

_ZERO_RNG = np.random.default_rng(0)   # never drawn from: the readings are noise-free

#: Instruments solved in one stack by :func:`thermal_residual_parts` (more go in turns): the
#: stack holds node temperatures, drives and rates of every knot, run and instrument, 3 x 8 B
#: x knots x runs x nodes per instrument, 1.1 MB for 7 runs of 2.5 h at 10 s knots and 7 nodes.
MAX_STACK = 32

THERMAL_COLUMNS = ("time_s", "position_deg", "moving") + tuple(THERMOMETERS.values())


def require_columns(run: Run, columns: Iterable[str], stage: str) -> None:
    for c in columns:
        if c not in run.columns:
            raise InputError(f"run '{run.name}' has no column '{c}', which the {stage} stage "
                             "of the fit needs", file=run.path, column=c)


def decimation_step(t: np.ndarray, decimate_s: float) -> int:
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    return max(1, int(round(decimate_s / dt)))


def window_mean(x: np.ndarray, k: int) -> np.ndarray:
    """Mean of x over consecutive windows of k samples (the last one may be shorter)."""
    n = x.size
    w = np.arange(n) // k
    return np.bincount(w, weights=x) / np.bincount(w)


@dataclass
class ThermalRun:
    """A run prepared for the thermal stage: decimated grid, measured readings."""

    run: Run
    t0_c: float
    time_s: np.ndarray          # full time base (up to the last knot)
    knots: np.ndarray           # indices of the knots into time_s
    t_knot: np.ndarray
    moving_knot: np.ndarray     # moving fraction over each decimated step
    ambient_knot: np.ndarray    # chamber temperature averaged over each step
    measured: dict[str, np.ndarray]
    mask: dict[str, np.ndarray]
    interval: np.ndarray        # Hermite interpolation: knot interval of every sample
    basis: tuple[np.ndarray, ...]
    per_knot: int = 0           # samples per knot interval when every interval has the same
    """offsets (uniform sampling, knots every ``per_knot`` samples): the lag can then be
    stepped knot to knot (:func:`readings`); 0 otherwise."""
    history: tuple[float, float] | None = None
    """The soak history of the sidecar (soak_from_c [degC], soak_h [h]), if given
    (:func:`nfs.fit.start_state.soak_history`)."""
    powered_knot: np.ndarray | None = None
    """Fraction of each decimated step the unit was on (a run with power cycles,
    :mod:`nfs.power`): the heat released inside the unit is scaled by it; None: on
    throughout."""


def prepare_thermal(run: Run, decimate_s: float) -> ThermalRun:
    require_columns(run, THERMAL_COLUMNS, "thermal")
    cond = conditions_from_run(run)
    t_all = np.asarray(run["time_s"], dtype=float)
    if t_all.size < 3:
        raise InputError(f"run '{run.name}' has {t_all.size} samples; the fit needs a record",
                         file=run.path)
    k = decimation_step(t_all, decimate_s)
    knots = np.arange(0, t_all.size, k)
    t = t_all[: knots[-1] + 1]
    moving = np.asarray(run["moving"], dtype=float)[: t.size]
    if cond.chamber_c is None:
        amb = np.full(t.size, cond.start_temperature_c)
    else:
        amb = np.asarray(run["temp_chamber_c"], dtype=float)[: t.size]
    t_knot = t[knots]
    interval = np.minimum(np.searchsorted(t_knot, t, side="right") - 1, knots.size - 2)
    h = np.diff(t_knot)[interval]
    s = (t - t_knot[interval]) / h
    basis = (2 * s**3 - 3 * s**2 + 1, (s**3 - 2 * s**2 + s) * h, -2 * s**3 + 3 * s**2,
             (s**3 - s**2) * h)
    measured, mask = {}, {}
    for col in THERMOMETERS.values():
        y = np.asarray(run[col], dtype=float)[knots]
        measured[col] = y
        mask[col] = np.isfinite(y)
    dt = np.diff(t)
    uniform = knots.size > 2 and uniform_steps(dt)
    powered = run.columns.get(POWERED_COLUMN)
    powered_knot = (None if powered is None or np.all(np.asarray(powered) > 0.5) else
                    window_mean((np.asarray(powered, dtype=float) > 0.5).astype(float)[: t.size],
                                k))
    return ThermalRun(run=run, t0_c=cond.start_temperature_c, time_s=t, knots=knots,
                       t_knot=t_knot, moving_knot=window_mean(moving, k),
                       ambient_knot=window_mean(amb, k), measured=measured, mask=mask,
                       interval=interval, basis=basis, per_knot=k if uniform else 0,
                       history=soak_history(run), powered_knot=powered_knot)


@dataclass
class Knots:
    """Node temperatures and exact rates at the knots of one run (what _readings needs)."""

    node_names: tuple[str, ...]
    temperature_c: np.ndarray
    rate_c_per_s: np.ndarray


class StatefulLaw:
    """A state-dependent thermal law (the TEC) of every instrument, for all runs at once.

    Called with the node temperature of every (instrument, run) row; the parameters may
    differ between instruments (a fit perturbs the TEC slopes).  Tried as one vector call
    with array-valued parameters; a law written for scalars (a user's) is called per
    instrument, and per run when it takes scalars only.
    """

    def __init__(self, f, params: Sequence[dict], r: int):
        self.f = f
        self.params = list(params)
        self.mode = "joint"
        self.joint: dict = {}
        for key in params[0]:
            vals = [p[key] for p in params]
            if all(v == vals[0] for v in vals[1:]):
                self.joint[key] = vals[0]
                continue
            try:
                self.joint[key] = np.repeat(np.asarray(vals, dtype=float), r)
            except (TypeError, ValueError):  # a parameter that is no number differs
                self.mode = "per instrument"

    def __call__(self, t_s: float, temp: np.ndarray, moving: np.ndarray,
                 moving_rows: np.ndarray) -> np.ndarray:
        """Power [W] at every row of ``temp`` (n_instruments, n_runs); ``moving`` (n_runs,),
        ``moving_rows`` the same for every row (n_instruments * n_runs,)."""
        s, r = temp.shape
        if self.mode == "joint":
            try:
                p = np.asarray(self.f(t_s, temp.reshape(-1), moving_rows, **self.joint),
                               dtype=float)
                if p.shape == (s * r,):
                    return p.reshape(s, r)
            except Exception:  # a user's law written for scalar parameters or temperatures
                pass
            self.mode = "per instrument"
        if self.mode == "per instrument":
            try:
                out = np.empty((s, r))
                for i, params in enumerate(self.params):
                    p = np.asarray(self.f(t_s, temp[i], moving, **params), dtype=float)
                    if p.shape != (r,):
                        raise ValueError
                    out[i] = p
                return out
            except Exception:
                self.mode = "per run"
        return np.array([[float(self.f(t_s, float(x), float(m), **params))
                          for x, m in zip(temp[i], moving)]
                         for i, params in enumerate(self.params)])


def _each(x: np.ndarray, mats: np.ndarray) -> np.ndarray:
    """x[:, s] @ mats[s] for every instrument s of a (knot, instrument, run, node) array,
    as one large product per instrument (broadcasting would make one tiny product per knot).
    """
    n_k, n_s, r, n = x.shape
    xs = x.transpose(1, 0, 2, 3).reshape(n_s, n_k * r, n)
    return (xs @ mats).reshape(n_s, n_k, r, -1).transpose(1, 0, 2, 3)


def simulate_knots(insts: Sequence[Instrument], data: Sequence[ThermalRun],
                   initial_offset_c: np.ndarray | None = None) -> list[list[Knots]]:
    """Solve the network of every instrument on the knots of every run: ``out[s][i]``.

    Every node starts at the run's T0, plus ``initial_offset_c[s, i]`` [K] (shape
    (instruments, runs, nodes)) when given.

    The same exact step as :func:`thermal.simulate` (zero-order hold of the inputs over each
    knot interval, :func:`thermal.solve.step_matrices` once per instrument and step size),
    with the state-dependent thermal effects evaluated for all rows at each knot.  Runs
    whose knots are not uniform are solved one by one with :func:`thermal.simulate`.  The
    instruments must share node names and effects (other parameter values).
    """
    insts = list(insts)
    n_s = len(insts)
    names = insts[0].network.node_names
    n = len(names)
    if any(inst.network.node_names != names for inst in insts[1:]):
        raise NfsError("simulate_knots: the instruments must share their nodes")
    out: list[list[Knots | None]] = [[None] * len(data) for _ in insts]
    groups: dict[float, list[int]] = {}
    for i, rd in enumerate(data):
        dt = np.diff(rd.t_knot)
        h = float(dt[0])
        if uniform_steps(dt):
            groups.setdefault(round(h, 9), []).append(i)
            continue
        for s, inst in enumerate(insts):
            power, _, _ = thermal_power(
                inst, rd.t_knot, rd.moving_knot,
                None if rd.powered_knot is None else rd.powered_knot > 0.5)
            start = rd.t0_c if initial_offset_c is None else rd.t0_c + initial_offset_c[s, i]
            th = thermal.simulate(inst.network, rd.t_knot, ambient_c=rd.ambient_knot,
                                  initial_c=start, power_w=power)
            out[s][i] = Knots(names, th.temperature_c, th.rate_c_per_s)
    if not groups:
        return out  # type: ignore[return-value]
    ab = [inst.network.matrices() for inst in insts]
    a_t = np.stack([a.T for a, _ in ab])                         # (S, n, n)
    b_amb = np.stack([b[:, 0] for _, b in ab])                   # (S, n)
    b_pow_t = np.stack([b[:, 1:].T for _, b in ab])              # (S, n, n)
    p_const = np.stack([inst.network.node_power_w for inst in insts])
    effects = [thermal_effects(inst) for inst in insts]
    kinds = [[(e.name, j) for e, j, _ in eff] for eff in effects]
    if any(k != kinds[0] for k in kinds[1:]):
        raise NfsError("simulate_knots: the instruments must share their thermal effects, "
                       "each on the same node")
    for h, members in groups.items():
        mats = [step_matrices(a, b, h) for a, b in ab]
        step = np.stack([m.phi_minus_i.T for m in mats])         # (S, n, n)
        g_amb = np.stack([m.gamma[:, 0] for m in mats])          # (S, n)
        g_pow = np.stack([m.gamma[:, 1:].T for m in mats])       # (S, n, n)
        n_k = max(data[i].t_knot.size for i in members)
        r = len(members)
        # knot-major arrays (knot, instrument, run, node): each knot's slice is contiguous
        t_knot = np.zeros(n_k)
        amb = np.empty((n_k, r))
        moving = np.zeros((n_k, r))
        on = np.ones((n_k, r))     # fraction of each step the unit is on (power cycles)
        t0 = np.empty(r)
        for q, i in enumerate(members):
            rd = data[i]
            m = rd.t_knot.size
            if m == n_k:
                t_knot = rd.t_knot
            amb[:m, q], amb[m:, q] = rd.ambient_knot, rd.ambient_knot[-1]
            moving[:m, q], moving[m:, q] = rd.moving_knot, rd.moving_knot[-1]
            if rd.powered_knot is not None:
                on[:m, q], on[m:, q] = rd.powered_knot, rd.powered_knot[-1]
            t0[q] = rd.t0_c
        # powers: the nodes' constant ones, the time-varying ones of the state-independent
        # effects (``varying``, e.g. a motor's heat pulses) and those of the state-dependent
        # laws on their nodes ``cols`` (``law_p``), each put through the step matrices apart
        stateful, cols = [], []
        varying = None
        for k_e, (e, j, _) in enumerate(effects[0]):
            if e.spec.state_dependent:
                if j not in cols:
                    cols.append(j)
                stateful.append((StatefulLaw(e.spec.function, [eff[k_e][2] for eff in effects],
                                              r), j, cols.index(j)))
                continue
            if varying is None:
                varying = np.zeros((n_k, n_s, r, n))
            contrib: dict[str, np.ndarray] = {}   # parameters -> the effect's power (knot, run)
            for s in range(n_s):
                params = effects[s][k_e][2]
                key = repr(sorted(params.items()))
                if key not in contrib:   # (in a fit's stack: once, the same in every instrument)
                    c = np.empty((n_k, r))
                    for q, i in enumerate(members):
                        rd = data[i]
                        m = rd.t_knot.size
                        c[:m, q] = np.broadcast_to(np.asarray(e.spec.function(
                            rd.t_knot, None, rd.moving_knot, **params), dtype=float), (m,))
                        c[m:, q] = c[m - 1, q]
                    contrib[key] = c * on
                varying[:, s, :, j] += contrib[key]
        gated = not np.all(on == 1.0)
        # (on = 1 multiplies exactly: a run without power cycles keeps its bits)
        drive = (amb[:, None, :, None] * g_amb[None, :, None, :]
                 + on[:, None, :, None] * (p_const[:, None, :] @ g_pow)[None, :, :, :])
        if varying is not None:
            drive += _each(varying, g_pow)
        temp = np.empty((n_k, n_s, r, n))
        law_p = np.zeros((n_k, n_s, r, len(cols)))
        g_law = g_pow[:, cols, :]
        temp[0] = t0[None, :, None]
        if initial_offset_c is not None:
            temp[0] += initial_offset_c[:, members, :]
        times = t_knot.tolist()
        moving_rows = np.tile(moving, (1, n_s))
        for k in range(n_k):
            tk = temp[k]
            if stateful:
                pk = law_p[k]
                for law, j, c in stateful:
                    pk[:, :, c] += law(times[k], tk[:, :, j], moving[k], moving_rows[k])
                if gated:
                    pk *= on[k][None, :, None]
            if k + 1 < n_k:
                nxt = tk + tk @ step + drive[k]
                if stateful:
                    nxt += pk @ g_law
                temp[k + 1] = nxt
        rate = (_each(temp, a_t) + amb[:, None, :, None] * b_amb[None, :, None, :]
                + on[:, None, :, None] * (p_const[:, None, :] @ b_pow_t)[None, :, :, :])
        if varying is not None:
            rate += _each(varying, b_pow_t)
        if cols:
            rate += _each(law_p, b_pow_t[:, cols, :])
        for s in range(n_s):
            for q, i in enumerate(members):
                m = data[i].t_knot.size
                out[s][i] = Knots(names, temp[:m, s, q], rate[:m, s, q])
    return out  # type: ignore[return-value]


def _lag_at_knots(y: np.ndarray, m: np.ndarray, rd: ThermalRun, tau_s: float) -> np.ndarray:
    """The lag of :func:`nfs.signal.first_order_lag` run over the Hermite interpolant of the
    knot values ``y`` and rates ``m`` (rows: records), read at the knots, stepped from knot
    to knot.

    With p samples per knot interval, every interval samples its cubic at the same offsets
    s_i = i / p, so sample K_k + i of the interpolant is b0_i y_k + b1_i m_k + b2_i y_k+1 +
    b3_i m_k+1 with the same weights in every interval, and the lag's recursion
    z[n+1] = a z[n] + (1 - a) x[n] (a = exp(-dt / tau)) summed over an interval gives

        z_k+1 = a^p z_k + c0 y_k + c1 m_k + c2 y_k+1 + c3 m_k+1,
        c_j = (1 - a) sum_i a^(p-1-i) b_j,i,                 z_0 = y_0,

    the same readings as lagging the full-rate record (to rounding) for a tenth of the work
    at 10 samples per knot.
    """
    if tau_s == 0:
        return y.copy()
    p = rd.per_knot
    a = math.exp(-(rd.time_s[1] - rd.time_s[0]) / tau_s)
    w = (1.0 - a) * a ** np.arange(p - 1, -1, -1)
    c0, c1, c2, c3 = (float(w @ b[:p]) for b in rd.basis)
    u = c0 * y[:, :-1] + c1 * m[:, :-1] + c2 * y[:, 1:] + c3 * m[:, 1:]
    big_a = a ** p
    z = np.empty_like(y)
    z[:, 0] = y[:, 0]
    z[:, 1:], _ = lfilter([1.0], [1.0, -big_a], u, axis=-1, zi=big_a * y[:, :1])
    return z


def _same_thermometer(insts: Sequence[Instrument]) -> dict[str, list[list[int]]]:
    """Per thermometer, the instruments whose thermometer (model and thermometer effects)
    is the same, as groups of indices."""
    out = {}
    for name in THERMOMETERS:
        same: dict[tuple, list[int]] = {}
        for s, inst in enumerate(insts):
            effects = tuple((e.name, tuple(sorted(e.params.items()))) for e in inst.effects
                            if e.spec.kind == "thermometer"
                            and e.params.get("thermometer") == name)
            # (a thermometer's node weights are a dict: its repr is the hashable key)
            same.setdefault((repr(inst.thermometers[name]), effects), []).append(s)
        out[name] = list(same.values())
    return out


def readings(insts: Sequence[Instrument], rd: ThermalRun, ths: Sequence[Knots],
             groups: dict[str, list[list[int]]] | None = None) -> list[dict[str, np.ndarray]]:
    """Noise-free thermometer readings at the knots of one run, per instrument.

    Instruments whose thermometer (model and thermometer effects) is the same are read
    together: one interpolation and one lag filter over a stack of rows (``groups``: those
    instruments per thermometer, when the caller has them for several runs).
    """
    out: list[dict[str, np.ndarray]] = [{} for _ in insts]
    names = tuple(ths[0].node_names)
    j, (b0, b1, b2, b3) = rd.interval, rd.basis
    groups = _same_thermometer(insts) if groups is None else groups
    for name, col in THERMOMETERS.items():
        for idx in groups[name]:
            inst = insts[idx[0]]
            model = inst.thermometers[name]
            y = np.stack([model.sensed(ths[s].temperature_c, names) for s in idx])
            m = np.stack([model.sensed(ths[s].rate_c_per_s, names) for s in idx])
            transforms = [(lambda v, e=e: e.spec.function(v, rd.time_s, **e.params))
                          for e in inst.effects
                          if e.spec.kind == "thermometer" and e.params.get("thermometer") == name]
            if rd.per_knot and not transforms:
                read = _lag_at_knots(y, m, rd, model.lag_s) + model.offset_c
            else:
                full = b0 * y[:, j] + b1 * m[:, j] + b2 * y[:, j + 1] + b3 * m[:, j + 1]
                quiet = replace(model, noise_c=0.0, quantum_c=0.0)
                if transforms:  # a thermometer effect (a user's) may take one record at a time
                    read = np.stack([thermometer_reading(row, rd.time_s, quiet, _ZERO_RNG,
                                                         transforms) for row in full])
                else:
                    read = thermometer_reading(full, rd.time_s, quiet, _ZERO_RNG)
                read = read[:, rd.knots]
            for row, s in enumerate(idx):
                out[s][col] = read[row]
    return out


#: The start of every run estimated with one slow mode and the fast remainder of a uniform
#: offset (:mod:`nfs.fit.start_state`).
DEFAULT_START = StartModel()


def thermometer_floors(inst: Instrument) -> dict[str, float]:
    """Each thermometer column's noise and rounding level sqrt(noise_c^2 + quantum_c^2 / 12)
    [K] (1 where both are zero): the scale its residual rows are divided by."""
    out = {}
    for name, col in THERMOMETERS.items():
        th = inst.thermometers[name]
        out[col] = math.hypot(th.noise_c, th.quantum_c / math.sqrt(12.0)) or 1.0
    return out


@dataclass
class ThermalResidual:
    """The thermometer residual of a stack of instruments, the start of every run profiled."""

    parts: list[dict[str, list[np.ndarray]]]
    """Model minus measured at the knots, NaN readings dropped: ``parts[s][column][run]`` [K]."""
    start_rows: list[np.ndarray]
    """Per instrument, the start amplitudes' prior rows (a - centre) / width of every run,
    concatenated (empty without a start model)."""
    start_c: list[np.ndarray]
    """Per instrument, every run's node temperatures at power-on, shape (runs, nodes) [degC]."""
    amplitudes_c: list[np.ndarray]
    """Per instrument, every run's start amplitudes a, shape (runs, k + 1) [K]."""


def thermal_residual(insts: Sequence[Instrument], data: Sequence[ThermalRun],
                     start: StartModel | None = DEFAULT_START) -> ThermalResidual:
    """Model minus measured readings of every instrument and run, each run started where the
    readings and the start's prior put it (:mod:`nfs.fit.start_state`; ``start=None``:
    every node at T0).

    The readings' response to each start amplitude comes from the same march (the runs
    stacked once more per amplitude, started 1 K along its pattern), so the TEC law and the
    thermometers' lags are in it; the amplitudes are then solved per run and instrument by
    weighted linear least squares (rows divided by :func:`thermometer_floors`) with their
    prior.
    """
    insts = list(insts)
    if start is not None and start.n_amplitudes == 0:
        start = None
    r_n = len(data)
    cols = tuple(THERMOMETERS.values())
    parts = [{c: [] for c in cols} for _ in insts]
    rows: list[list[np.ndarray]] = [[] for _ in insts]
    start_c = [np.empty((r_n, len(inst.network.node_names))) for inst in insts]
    amps = [np.zeros((r_n, 0 if start is None else start.n_amplitudes)) for _ in insts]
    for lo in range(0, len(insts), MAX_STACK):
        chunk = insts[lo:lo + MAX_STACK]
        groups = _same_thermometer(chunk)
        if start is None:
            knots = simulate_knots(chunk, data)
            for i, rd in enumerate(data):
                for s, model in enumerate(readings(chunk, rd, [k[i] for k in knots], groups)):
                    for col, y in model.items():
                        parts[lo + s][col].append((y - rd.measured[col])[rd.mask[col]])
                    start_c[lo + s][i] = rd.t0_c
            continue
        modes = [inst.network.modes() for inst in chunk]
        bases = [start_basis(inst.network, start.n_slow, start.fast, m)
                 for inst, m in zip(chunk, modes)]
        k = bases[0].shape[1]
        n = bases[0].shape[0]
        offsets = np.zeros((len(chunk), r_n * (k + 1), n))
        for s, v in enumerate(bases):
            for m in range(k):
                offsets[s, (m + 1) * r_n:(m + 2) * r_n, :] = v[:, m]
        knots = simulate_knots(chunk, list(data) * (k + 1), offsets)
        floors = [thermometer_floors(inst) for inst in chunk]
        for i, rd in enumerate(data):
            base = readings(chunk, rd, [kn[i] for kn in knots], groups)
            moved = [readings(chunk, rd, [kn[i + (m + 1) * r_n] for kn in knots], groups)
                     for m in range(k)]
            for s, inst in enumerate(chunk):
                f = floors[s]
                r0 = {c: (base[s][c] - rd.measured[c])[rd.mask[c]] for c in cols}
                g = {c: np.column_stack([(mv[s][c] - base[s][c])[rd.mask[c]] for mv in moved])
                     for c in cols}
                centre, width = start_prior(inst.network, bases[s], rd.t0_c, rd.history, start,
                                            modes[s])
                a = solve_amplitudes(np.concatenate([r0[c] / f[c] for c in cols]),
                                     np.concatenate([g[c] / f[c] for c in cols]), centre, width)
                for c in cols:
                    parts[lo + s][c].append(r0[c] + g[c] @ a)
                rows[lo + s].append((a - centre) / width)
                amps[lo + s][i] = a
                start_c[lo + s][i] = rd.t0_c + bases[s] @ a
    return ThermalResidual(parts=parts,
                           start_rows=[np.concatenate(r) if r else np.empty(0) for r in rows],
                           start_c=start_c, amplitudes_c=amps)


def thermal_residual_parts(insts: Sequence[Instrument], data: Sequence[ThermalRun],
                           start: StartModel | None = DEFAULT_START
                           ) -> list[dict[str, list[np.ndarray]]]:
    """Model minus measured readings at the knots (NaN readings dropped), per instrument:
    ``out[s][column][run]`` [K] (:func:`thermal_residual`, its parts only)."""
    return thermal_residual(insts, data, start).parts


def start_states(inst: Instrument, runs: Sequence[Run], decimate_s: float = 10.0,
                 start: StartModel | None = DEFAULT_START) -> dict[str, np.ndarray]:
    """Each run's node temperatures at power-on [degC] {run name: (n_nodes,)}, estimated
    from its thermometers through ``inst`` (:func:`thermal_residual`; ``start=None``: T0)."""
    runs = list(runs)
    data = [prepare_thermal(r, decimate_s) for r in runs]
    res = thermal_residual([inst], data, start)
    return {r.name: res.start_c[0][i] for i, r in enumerate(runs)}
