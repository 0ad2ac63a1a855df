"""Simulate start-up runs: from the thermal network to the measurement of one run.

    thermal network -> node temperatures -> thermometers, aux channels
                    -> turntable motion -> Earth-rate projection
                    -> named gyro / accelerometer effects + noise -> measurement (Run)

Every intermediate lands in a :class:`SimulationResult`: node temperatures, each effect's
contribution separately, the noise, and the measurement as it would be written to file.
The whole experiment (simulate -> north-find -> compensate -> table) is :class:`nfs.ModelChain`.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, replace
from typing import Any, Callable, Collection, Iterator

import numpy as np

import thermal

from .docfields import document_fields
from .effects import EffectContext, Geometry, apply_geometry, check_geometry
from .effects.thermometer import THERMOMETERS
from .errors import EffectError
from .heat import HeatLaw, thermal_power
from .instrument import Instrument
from .power import POWERED_COLUMN, since_power_on_s
from .run import Run, RunMeta
from .noise import gyro_noise_dph, white_noise
from .sensors import earth_rate_along_axis_dph, thermometer_reading
from .conditions import RunConditions
from .variability import drawn_soak, start_up_state, unit_instrument, unpowered_network

__all__ = ["SimulationResult", "simulate_run", "simulate_runs", "iter_simulate_runs",
           "effect_context", "OPTIONAL_COLUMNS"]

_UG = 1e-6

#: The columns of a simulated run beyond time, turntable, gyro and accelerometers (and the
#: power state of a run with power cycles): the thermometers, the chamber, and the
#: instrument's aux channels (by their names); ``channels`` of :func:`iter_simulate_runs`
#: chooses among them.
OPTIONAL_COLUMNS = (*THERMOMETERS.values(), "temp_chamber_c")


@document_fields
@dataclass(frozen=True)
class SimulationResult:
    """Everything one simulated run computed, stage by stage."""

    conditions: RunConditions
    """The conditions the run was made under."""
    thermal: thermal.ThermalResult
    """Node temperatures, rates, powers and the energy bookkeeping."""
    context: EffectContext
    """The state the effects were evaluated on."""
    thermal_terms_w: dict[str, np.ndarray]
    """Extra power of each thermal effect, by label [W]."""
    gyro_terms_dph: dict[str, np.ndarray]
    """Rate error of each gyro effect, by label [deg/h]."""
    acc_terms_g: dict[str, np.ndarray]
    """Error of each accelerometer effect, by label [g]."""
    gyro_noise_dph: np.ndarray
    """ARW + bias instability + rate random walk [deg/h]."""
    run: Run
    """The measurement, as written to file."""
    instrument: Instrument | None = None
    """The instrument simulated: the unit's draw of the instrument given to
    :func:`simulate_run` (that instrument itself without variability)."""
    geometry: Geometry | None = None
    """Where the sensors pointed: the table's true angle, the tilt, the gyro axis (after
    the geometry effects)."""

    @property
    def drift_dph(self) -> np.ndarray:
        """The thermal drift: sum of the gyro effect terms [deg/h] (no noise, no bias)."""
        total = np.zeros_like(self.context.time_s)
        for v in self.gyro_terms_dph.values():
            total = total + v
        return total


def _streams(seed) -> dict[str, np.random.Generator]:
    """Independent random streams per sensor, so switching one effect or sensor off leaves
    the others' draws unchanged."""
    names = ("gyro", "acc_x", "acc_y", "fog_thermometer", "acc_x_thermometer",
             "acc_y_thermometer", "aux", "turntable")  # new streams go last: the others keep
    seq = np.random.SeedSequence(seed)
    return {n: np.random.default_rng(s) for n, s in zip(names, seq.spawn(len(names)))}


def effect_context(inst: Instrument, th: thermal.ThermalResult, azimuth_deg: np.ndarray,
                   earth_rate_dph: np.ndarray, moving: np.ndarray,
                   aux: dict[str, np.ndarray], powered: np.ndarray | None = None
                   ) -> EffectContext:
    """The :class:`EffectContext` of a run from its thermal solution and turntable motion
    (``powered``: its power state, :mod:`nfs.power`; None: on throughout)."""
    return EffectContext(
        time_s=th.time_s, node_names=tuple(th.node_names), temperature_c=th.temperature_c,
        rate_c_per_s=th.rate_c_per_s, coil_outer=inst.gyro.coil_outer,
        coil_inner=inst.gyro.coil_inner, source=inst.gyro.source,
        axis_azimuth_deg=azimuth_deg, earth_rate_dph=earth_rate_dph, moving=moving,
        acc_nodes=inst.accelerometers.nodes, aux=aux, t_ref_c=inst.t_ref_c,
        since_power_on_s=None if powered is None else since_power_on_s(th.time_s, powered),
        coil_layout=inst.coil_layout)


def _aux_channels(inst: Instrument, th: thermal.ThermalResult, fs: float,
                  rng: np.random.Generator) -> dict[str, np.ndarray]:
    out = {}
    n = len(th.time_s)
    for ch in inst.aux:
        j = list(th.node_names).index(ch.node)
        src = th.power_w[:, j] if ch.kind == "power" else th.temperature_c[:, j]
        value = ch.offset + ch.gain * src
        white = rng.standard_normal(n)
        walk = np.cumsum(rng.standard_normal(n)) * np.sqrt(1.0 / fs)
        value = value + ch.noise * white + ch.walk_per_rth_s * walk
        out[ch.name] = value
    return out


def _channels_read(inst: Instrument) -> dict[str, str]:
    """{effect label: the aux ``channel`` it reads} of every effect of ``inst`` that reads one."""
    return {e.label: e.params["channel"] for e in inst.effects
            if isinstance(e.params.get("channel"), str)}


def _check_simulated_channels(inst: Instrument) -> None:
    """Every ``channel`` an effect reads must be one of the instrument's [[aux]] channels.

    An instrument may name a measured ``aux_*`` column it does not simulate (a model fitted
    to runs that recorded it); it cannot be simulated, since nothing produces the channel.
    """
    declared = {a.name for a in inst.aux}
    for label, channel in _channels_read(inst).items():
        if channel not in declared:
            raise EffectError(
                f"effect '{label}' reads channel '{channel}', which instrument "
                f"'{inst.name}' does not simulate; declare it under [[aux]] to simulate it "
                f"(declared: {', '.join(sorted(declared)) or '(none)'})")


@dataclass
class _Prepared:
    """One run up to its thermal solve (:func:`simulate_run`, :func:`simulate_runs`)."""

    inst: Instrument
    cond: RunConditions
    rngs: dict
    theta: np.ndarray
    moving: np.ndarray
    geom: Any
    axes: dict
    power: Any              # array (n_t, n) or a law for thermal.simulate
    thermal_terms: dict
    stateful: list
    initial: Any            # node temperatures at power-on
    ambient: np.ndarray     # chamber at the run's samples
    soak: tuple[float, float] | None = None   # (soak_from_c, soak_h) of an unfinished soak
    powered: np.ndarray | None = None         # power state at the samples (None: always on)
    earth: np.ndarray | None = None           # Earth rate along the gyro axis [deg/h]
    gravity: dict | None = None               # sin(elevation) of the x and y axes [g]


def _pointing(inst: Instrument, cond: RunConditions, t: np.ndarray, rng, shared: dict):
    """(theta, moving, geometry, axes, earth rate [deg/h], {axis: sin elevation [g]}) of a
    run: the turntable's motion, where the sensors point, and what Earth rate and gravity
    they sense.

    Without a geometry effect and a replayed motion these depend only on the schedule, the
    time grid, the heading, the tilt and the latitude, so the runs of one call that share
    them share one computation (``shared``), each with its own turntable stream in its
    :class:`Geometry` (which no effect then draws from).
    """
    tilt = inst.turntable
    key = None
    if cond.motion is None and not any(e.spec.kind == "geometry" for e in inst.effects):
        # the whole grid by its digest (16 bytes of BLAKE2b, ~20 us for a 2.5 h run at 1 Hz):
        # two grids of one size and the same ends may still differ inside
        key = ("pointing", cond.schedule, hashlib.blake2b(t.tobytes(), digest_size=16).digest(),
               cond.true_heading_deg, tilt.tilt_north_deg, tilt.tilt_east_deg,
               cond.latitude_deg)
        if key in shared:
            theta, moving, geom, axes, earth, gravity = shared[key]
            return theta, moving, replace(geom, rng=rng), axes, earth, gravity
    theta, moving = cond.turntable(t)
    geom = apply_geometry(Geometry(
        time_s=t, position_deg=theta, moving=moving, positions_deg=cond.schedule.positions_deg,
        heading_deg=cond.true_heading_deg, rng=rng, theta_deg=theta,
        tilt_north_deg=tilt.tilt_north_deg, tilt_east_deg=tilt.tilt_east_deg), inst.effects)
    axes = geom.azimuth_elevation()
    azimuth, elev_gyro = axes["gyro"]
    earth = earth_rate_along_axis_dph(azimuth, elev_gyro, cond.latitude_deg)
    gravity = {axis: np.sin(np.radians(axes[axis][1])) for axis in ("x", "y")}
    if key is not None:
        for a in (theta, moving, earth, *gravity.values(),
                  *(v for pair in axes.values() for v in pair)):
            a.flags.writeable = False       # shared by the runs: read-only
        shared[key] = (theta, moving, geom, axes, earth, gravity)
    return theta, moving, geom, axes, earth, gravity


def _prepare(inst: Instrument, cond: RunConditions, shared: dict | None = None) -> _Prepared:
    """Everything of one run before its thermal solve, the unpowered soak included.

    ``shared``: a dict kept across the runs of one call (:func:`simulate_runs`) that holds
    what runs have in common (a unit's drawn instrument, the heat input of one unit, grid
    and schedule), built once for all of them; None: built for this run.
    """
    shared = {} if shared is None else shared
    _check_simulated_channels(inst)
    tilt = inst.turntable
    check_geometry(inst.effects, cond.schedule.positions_deg, tilt.tilt_north_deg,
                   tilt.tilt_east_deg)
    t = cond.time_s
    fs = cond.sample_rate_hz
    rngs = _streams(cond.seed)
    var = cond.variability
    if var is not None and var.per_unit:
        key = ("unit", id(var), cond.unit)
        if key not in shared:
            shared[key] = unit_instrument(inst, var, cond.unit)
        inst = shared[key]
    theta, moving, geom, axes, earth, gravity = _pointing(inst, cond, t, rngs["turntable"],
                                                          shared)

    # 1. thermal network: the unpowered soak of a chamber program, then the run
    powered = cond.powered(t)
    key = ("power", id(inst), t.size, float(t[0]), float(t[-1]), moving.tobytes(),
           None if powered is None else powered.tobytes())
    if key not in shared:
        shared[key] = thermal_power(inst, t, moving, powered)
    power, thermal_terms, stateful = shared[key]
    thermal_terms = dict(thermal_terms)     # _finish adds the run's own state-dependent terms
    n_pre = int(np.ceil(cond.soak_s * fs - 1e-9)) if cond.soak_s > 0.0 else 0
    t_all = np.concatenate([-cond.soak_s + np.arange(n_pre) / fs, t]) if n_pre else t
    ambient = (np.full(t_all.shape, cond.start_temperature_c) if cond.chamber_c is None
               else np.asarray(cond.chamber_c(t_all), dtype=float))
    initial = cond.start_temperature_c if cond.initial_c is None else cond.initial_c
    if var is not None and var.per_start_up and cond.initial_c is None:
        initial, terms = start_up_state(inst, var, cond.start_temperature_c, t_all,
                                        cond.seed)
        ambient = ambient + terms
    if n_pre:
        soak = thermal.simulate(unpowered_network(inst.network), t_all[:n_pre + 1],
                                ambient_c=ambient[:n_pre + 1], initial_c=initial,
                                ambient_hold="first-order")
        initial, ambient = soak.temperature_c[-1], ambient[n_pre:]
    soak = (drawn_soak(var, cond.seed) if var is not None and cond.initial_c is None
            and not n_pre else None)
    return _Prepared(inst, cond, rngs, theta, moving, geom, axes, power, thermal_terms,
                     stateful, initial, np.asarray(ambient, dtype=float), soak, powered,
                     earth, gravity)


def simulate_run(inst: Instrument, cond: RunConditions) -> SimulationResult:
    """Simulate one start-up run of ``inst`` under ``cond``.

    The unpowered instrument is soaked at T0 (every node at T0), follows the chamber
    unpowered for ``cond.soak_s`` (a program's soak), is powered on at t = 0 and stays in the
    chamber at T_amb(t) (T0 unless ``cond.chamber_c``).  With ``cond.variability`` the
    instrument is unit ``cond.unit``'s draw of ``inst``, its nodes start from the start-up's
    soak and the chamber wanders and cycles (:mod:`nfs.variability`).  The chamber is linear
    between samples (first-order hold, exact for a program's ramps).  The run records as its
    ``start_temperature_c`` the chamber's temperature at power-on, where it was soaked.
    """
    prep = _prepare(inst, cond)
    th = thermal.simulate(prep.inst.network, cond.time_s, ambient_c=prep.ambient,
                          initial_c=prep.initial, power_w=prep.power,
                          ambient_hold="first-order", heated_nodes=_heated(prep))
    return _finish(prep, th)


def _heated(prep: _Prepared) -> tuple[int, ...] | None:
    """The nodes the run's heat law can heat (None: no law, the power is an array)."""
    return prep.power.heated_nodes if isinstance(prep.power, HeatLaw) else None


#: Memory the stacked thermal march of :func:`iter_simulate_runs` may take [bytes]: the
#: marched states of 262 start-ups of 2.5 h at 1 Hz on 14 nodes with one node heated (the
#: default instrument, its coil wound: 15 rows of 9000 samples, 1.08 MB each), so that a
#: sweep's batch of :data:`nfs.sweep.BATCH_CELLS` = 256 single start-ups is one march (the
#: march's cost per sample is partly fixed: 128 runs at once cost 15 % more per run than
#: 256); 140 with every node heated, 491 of the two-node coil's 8 rows.
STACK_BYTES = 270 * 2 ** 20


def _state_bytes(prep: _Prepared) -> int:
    """Bytes of the run's marched states: 8 x (n_nodes + heated nodes) x n_samples
    (thermal/march.py)."""
    n = len(prep.inst.network.node_names)
    heated = _heated(prep)
    return 8 * (n + (n if heated is None else len(heated))) * prep.cond.time_s.size


def _stack_key(prep: _Prepared):
    """Runs with equal keys share the network, the time grid and the power law."""
    c = prep.cond
    unit = c.unit if c.variability is not None and c.variability.per_unit else None
    t = c.time_s
    return (unit, t.size, float(t[0]), float(t[-1]), prep.moving.tobytes(),
            None if prep.powered is None else prep.powered.tobytes())


def simulate_runs(inst: Instrument, conds, *,
                  progress: Callable[[int, int, str], None] | None = None,
                  channels: Collection[str] | None = None) -> list[SimulationResult]:
    """:func:`simulate_run` for many runs of ``inst``, their thermal states stacked
    (:func:`iter_simulate_runs`, every result kept).  Each result is :func:`simulate_run`'s,
    bit for bit, whatever else is simulated beside it."""
    return list(iter_simulate_runs(inst, conds, progress=progress, channels=channels))


def iter_simulate_runs(inst: Instrument, conds, *,
                       progress: Callable[[int, int, str], None] | None = None,
                       channels: Collection[str] | None = None
                       ) -> Iterator[SimulationResult]:
    """:func:`simulate_run` for many runs of ``inst``, yielded one at a time, in order.

    The runs are taken in consecutive chunks whose marched thermal states fit in
    :data:`STACK_BYTES` (8 bytes x (n_nodes + heated nodes) x n_samples per run, [T_k, p_k]
    of each sample):
    a chunk is prepared, the runs of one unit on one time grid and schedule share the network
    and the heat input law and are solved together (:func:`thermal.iter_simulate_many`, one
    array operation per term of the step for all of them), and each run is finished
    (effects, sensors, noise) only when it is yielded.  So at most one chunk of runs is held,
    whatever the number of runs.  Each result is :func:`simulate_run`'s, bit for bit,
    whatever else is simulated beside it.  ``progress(i, n, name)`` is called before each
    run's preparation.

    ``channels``: the columns of :data:`OPTIONAL_COLUMNS` and aux channels to make (None:
    every one, a run that can be written to file; ``()``: none, what north-finding and the
    drift need, as a sweep's record).  The aux channels are made all together, when one is
    asked for or an effect reads one (their draws share one stream).  Every sensor draws
    from its own stream, so a column left out changes no bit of the others.
    """
    conds = list(conds)
    shared: dict = {}
    carried = None                      # a prepared run that did not fit in the last chunk
    i = 0
    while i < len(conds) or carried is not None:
        preps, used = [], 0
        if carried is not None:
            preps, used, carried = [carried], _state_bytes(carried), None
        while i < len(conds):
            if progress is not None:
                progress(i, len(conds), conds[i].name)
            prep = _prepare(inst, conds[i], shared)
            i += 1
            if preps and used + _state_bytes(prep) > STACK_BYTES:
                carried = prep
                break
            preps.append(prep)
            used += _state_bytes(prep)
        yield from _solve_chunk(preps, channels)
        shared = {k: v for k, v in shared.items() if k[0] == "unit"}


def _solve_chunk(preps: list[_Prepared], channels: Collection[str] | None = None
                 ) -> Iterator[SimulationResult]:
    """The prepared runs solved (stacked by :func:`_stack_key`) and finished, in order."""
    groups: dict = {}
    for k, p in enumerate(preps):
        groups.setdefault(_stack_key(p), []).append(k)
    solutions: dict = {}
    streams = {}                        # run -> its group's (run, solution) stream
    for idx in groups.values():
        first = preps[idx[0]]
        n = len(first.inst.network.node_names)
        initial = np.array([np.broadcast_to(np.asarray(preps[k].initial, dtype=float), (n,))
                            for k in idx])
        stream = zip(idx, thermal.iter_simulate_many(
            first.inst.network, first.cond.time_s,
            ambient_c=np.array([preps[k].ambient for k in idx]), initial_c=initial,
            power_w=first.power, ambient_hold="first-order", heated_nodes=_heated(first)))
        streams.update((k, stream) for k in idx)
    for k, p in enumerate(preps):
        for m, th in streams.pop(k) if k not in solutions else ():
            solutions[m] = th           # the group's solutions, in order, up to run k
            if m == k:
                break
        yield _finish(p, solutions.pop(k), channels)
        preps[k] = None


def _finish(prep: _Prepared, th, channels: Collection[str] | None = None
            ) -> SimulationResult:
    """The run from its thermal solution: effects, sensors, noise, the measurement file
    (its optional columns those of ``channels``, :func:`iter_simulate_runs`)."""
    inst, cond, rngs, moving = prep.inst, prep.cond, prep.rngs, prep.moving
    t, fs, theta, geom = cond.time_s, cond.sample_rate_hz, prep.theta, prep.geom
    ambient, thermal_terms = prep.ambient, prep.thermal_terms
    azimuth = prep.axes["gyro"][0]
    for e, j, params in prep.stateful:
        p = np.array(e.spec.function(t, th.temperature_c[:, j], moving, **params),
                     dtype=float)
        if prep.powered is not None:
            p[~prep.powered] = 0.0
        thermal_terms[e.label] = p

    # 2. aux channels (when asked for, or read by an effect) and the effect context
    wanted = (lambda column: True) if channels is None else channels.__contains__
    aux = (_aux_channels(inst, th, fs, rngs["aux"])
           if any(wanted(a.name) for a in inst.aux)
           or _channels_read(inst) else {})
    earth = prep.earth
    ctx = effect_context(inst, th, azimuth, earth, moving, aux, prep.powered)

    # 3. gyro: K0 * Earth rate + bias + effects + noise
    gyro_terms: dict[str, np.ndarray] = {}
    acc_terms: dict[str, np.ndarray] = {}
    for e in inst.effects:
        if e.spec.kind == "gyro":
            gyro_terms[e.label] = np.broadcast_to(
                np.asarray(e.spec.function(ctx, **e.params), dtype=float), t.shape).copy()
        elif e.spec.kind == "accelerometer":
            acc_terms[e.label] = np.broadcast_to(
                np.asarray(e.spec.function(ctx, **e.params), dtype=float), t.shape).copy()
    g = inst.gyro
    noise = gyro_noise_dph(len(t), fs, arw_deg_per_rth_h=g.arw_deg_per_rth_h,
                           bias_instability_dph=g.bias_instability_dph,
                           rrw_deg_per_h_per_rth_h=g.rrw_deg_per_h_per_rth_h, rng=rngs["gyro"])
    gyro = g.scale_factor * earth + g.bias_dph + noise
    for v in gyro_terms.values():
        gyro = gyro + v

    # 4. accelerometers: sin(elevation) + bias + effects + noise
    a = inst.accelerometers
    acc = {}
    for axis, bias in (("x", a.bias_x_g), ("y", a.bias_y_g)):
        f = prep.gravity[axis] + bias
        for e in inst.effects:
            if e.spec.kind == "accelerometer" and e.params.get("axis") == axis:
                f = f + acc_terms[e.label]
        f = f + white_noise(len(t), fs, a.noise_ug_per_rth_hz * _UG, rng=rngs[f"acc_{axis}"])
        acc[axis] = f

    # 5. thermometers (with any thermometer effects applied after the built-in lag)
    temps = {}
    for name, column in THERMOMETERS.items():
        if not wanted(column):
            continue
        model = inst.thermometers[name]
        transforms = [
            (lambda y, e=e: e.spec.function(y, t, **e.params))
            for e in inst.effects
            if e.spec.kind == "thermometer" and e.params.get("thermometer") == name]
        sensed = model.sensed(th.temperature_c, tuple(th.node_names))
        temps[column] = thermometer_reading(sensed, t, model, rngs[f"{name}_thermometer"],
                                            transforms)

    columns = {
        "time_s": t, "position_deg": theta, "moving": moving.astype(float),
        "gyro_dph": gyro, "acc_x_g": acc["x"], "acc_y_g": acc["y"], **temps,
    }
    if wanted("temp_chamber_c"):
        columns["temp_chamber_c"] = np.broadcast_to(np.asarray(ambient, dtype=float),
                                                    t.shape).copy()
    columns.update(aux)
    if prep.powered is not None:
        # switched off, the unit records nothing but its power state (the chamber's own
        # thermometer and the table's encoder keep recording)
        off = ~prep.powered
        for name in ("gyro_dph", "acc_x_g", "acc_y_g", *temps, *aux):
            columns[name] = np.where(off, np.nan, columns[name])
        columns[POWERED_COLUMN] = prep.powered.astype(float)
    sched = cond.schedule
    soaked_c = (cond.start_temperature_c if cond.soak_s == 0.0 or cond.chamber_c is None
                else float(cond.chamber_c(0.0)))
    meta = RunMeta(latitude_deg=cond.latitude_deg, start_temperature_c=soaked_c,
                   true_heading_deg=cond.true_heading_deg, sample_rate_hz=fs,
                   positions_deg=sched.cycle_positions_deg, dwell_s=sched.dwell_s,
                   move_s=sched.move_s, duration_s=cond.duration_s or None,
                   instrument=inst.name,
                   extra={} if prep.soak is None else
                   {"soak_from_c": prep.soak[0], "soak_h": round(prep.soak[1], 4)})
    run = Run(name=cond.name, columns=columns, meta=meta)
    return SimulationResult(conditions=cond, thermal=th, context=ctx,
                            thermal_terms_w=thermal_terms, gyro_terms_dph=gyro_terms,
                            acc_terms_g=acc_terms, gyro_noise_dph=noise, run=run,
                            instrument=inst, geometry=geom)
