"""Run-to-run and unit-to-unit variability of the simulated start-up world.

A real start-up experiment is never the same twice, and no two units are the same.  Each
start-up draws its own *conditions* (how it was soaked, how the chamber wandered); each unit
draws once its own *parameters* (thermal network, thermometer offsets, drift coefficients).
All values below are standard deviations (absolute [K], [s], or relative [1]).

Per start-up (run-to-run)
-------------------------
Chamber air temperature, on top of the scenario's own profile (``[chamber]``):

    T_amb(t) = T0 [+ ripple] + w(t) + a_c s(2 pi t / P + phi)                          [degC]

w is an Ornstein-Uhlenbeck wander of standard deviation ``chamber_wander_c`` and correlation
time tau_w = ``chamber_wander_tau_s``, sampled exactly on the run's time grid:
w_{k+1} = w_k exp(-h/tau_w) + sigma sqrt(1 - exp(-2h/tau_w)) z_k, w_0 ~ N(0, sigma^2)
(Gillespie, Phys. Rev. E 54, 2084 (1996), eq. (1.3)).  a_c s(.) is the controller's cycling:
``cycling_shape`` sine (a proportional controller's wobble) or triangle (a bang-bang
controller heating and cooling at constant rates between its thresholds, s = (2/pi)
arcsin(sin)), amplitude a_c = ``cycling_c``, phase phi uniform in [0, 2 pi) (power-on is not
synchronised with the controller) and period P = ``cycling_period_s`` scattered log-normally
by ``cycling_period_rel_std``.

Initial node temperatures at power-on (the soak), node j:

    T_j(0) = S_j + d_soak + e_j,      d_soak ~ N(0, soak_offset_c^2),
    e = sum_i s_i z_i v_i,  z_i ~ N(0, 1),  s_i^2 = soak_node_c^2 tau_i / tau_1          [degC]

S is the soak, solved exactly (:func:`thermal.final_temperature`): the unpowered network, from
``soak_from_c`` (an unfinished soak: the unit brought from the laboratory) or from T0, left
for t_soak (``soak_h``, scattered log-normally by ``soak_h_rel_std``, rounded up to the soak
grid's :data:`SOAK_STEP_S`: every step of every soak the same, whose step matrices are
computed once) in the chamber air
T0 + w(t) + cycling(t) for -t_soak <= t < 0, the same wander and cycling that go on after
power-on.  In still air S - T0 = expm(A t_soak) (T_from - T0) 1: the slowest mode (the
housing's global time constant) remains, so the residual grows with |T_from - T0|; the
wander and the cycling add what the network's low-pass lets through, the housing lagging the
air and the coil lagging the housing (gradients of a few thousandths of a kelvin, where
independent draws e_j of the same size per node would be tenths).  d_soak and e stand for
what a lumped chamber misses (the door opened to cable the unit, unevenly stirred air): e
lies along the network's free modes v_i (time constants tau_i, :meth:`thermal.Network.modes`,
each scaled to max |v_i| = 1), mode i with a standard deviation s_i, s_i^2 proportional to
tau_i (a mode driven by the air's white fluctuations holds a variance proportional to its
time constant), the slowest soak_node_c.  Parts that equalise within seconds (a wound coil's
layers, its outer face and the shield) then start together, as no soak leaves them apart,
and the estimators' start model (:mod:`nfs.fit.start_state`, the smoother's prior)
describes what the world draws.

Per unit (unit-to-unit, drawn once per unit)
--------------------------------------------
Every parameter path (:mod:`nfs.parameters`) of a family gets a factor or an offset:

- relative: p_u = p exp(s z - s^2/2), s^2 = ln(1 + rel^2), z ~ N(0, 1): mean p, standard
  deviation rel |p|, never a change of sign (a log-normal factor): node capacities and a
  wound coil's volumetric heat capacity (``capacity_rel_std``), link conductances, a wound
  coil's conductivity and its faces' contacts (``conductance_rel_std``; its radii and
  height are its drawing's, kept), node powers and the
  thermal effects' powers and power slopes [W], [W/K] (``power_rel_std``), the gyro and
  accelerometer effects' coefficients (``effect_rel_std``; reference temperatures [degC],
  angles [deg] and phases [rad] are set points, not coefficients, and are kept, as are the
  constants of a design a data sheet gives, registered ``constant``: a coil's fibre length
  and diameter, the fibre's index and dn/dT);
- absolute: p_u = p + std z: the thermometer offsets (``thermometer_offset_c``);
- ``parameters``: a scatter of one's own per path or glob pattern (relative, or absolute with
  ``{ std = ... }``), which overrides the families for the paths it names.

Seeds.  Every draw comes from a :class:`numpy.random.SeedSequence`.  A start-up's draws are
children of its own entropy (the noise seed of :class:`~nfs.experiment.RunConditions`, which
holds the scenario seed, the start temperature, the repeat and the unit), with spawn keys
after the sensor-noise streams; a unit's draws come from (``unit_seed``, unit) with the
parameter path's CRC-32 as spawn key: adding a unit or an effect leaves every other draw
unchanged (a node changes the network's modes, so the soak scatter's too).  The same seed
gives the same bytes.
"""

from __future__ import annotations

import functools
import zlib
from dataclasses import dataclass, fields, replace
from typing import Sequence

import numpy as np
from scipy.signal import lfilter

import thermal

from .docfields import document_fields
from .instrument import Instrument
from .parameters import ParameterError, expand_paths, get_param, param_paths, set_params

__all__ = ["Variability", "NO_VARIABILITY", "REALISTIC", "VARIABILITY_PRESETS",
           "VARIABILITY_KEYS", "CYCLING_SHAPES", "SOAK_STEP_S", "unit_scatter",
           "unit_instrument", "start_up_state", "drawn_soak", "chamber_terms",
           "lognormal_factor",
           "describe_units", "unpowered_network"]

#: Shapes of the chamber controller's cycling.
CYCLING_SHAPES = ("sine", "triangle")

#: Spawn keys of a start-up's variability streams (after the sensor-noise streams 0-6 of
#: :func:`nfs.experiment.simulate_run`, which keep their keys).
_SOAK_KEY, _NODE_KEY, _WANDER_KEY, _CYCLING_KEY = 16, 17, 18, 19
#: Word mixed into a unit's entropy so its streams never meet a start-up's.
_UNIT_TAG = 0x756E6974

#: Effect parameter units that are set points or angles, not coefficients of a drift.
_REFERENCE_UNITS = ("degC", "deg", "rad", "channel unit")


@document_fields
@dataclass(frozen=True)
class Variability:
    """How start-ups and units differ (``[variability]`` of a scenario); zero: no scatter.

    Standard deviations; ``*_rel_std`` are relative (0.05 = 5 %).  The field comments of
    :data:`REALISTIC` give the value and its source.
    """

    preset: str = "none"
    """The preset the values started from (``none``, ``custom``: zero, or ``realistic``),
    for the table notes."""
    soak_offset_c: float = 0.0
    """Common offset of every node from the chamber at power-on, per start-up [K]."""
    soak_node_c: float = 0.0
    """Scatter of each node about that, per start-up [K]."""
    unfinished_soak: bool = False
    """True: the unit came from ``soak_from_c`` and soaked only ``soak_h`` at T0."""
    soak_from_c: float = 23.0
    """Temperature the unit is brought from into the chamber (the laboratory) [degC]."""
    soak_h: float = 4.0
    """Mean duration of the soak at T0 before power-on [h]."""
    soak_h_rel_std: float = 0.0
    """Relative scatter of the soak duration, per start-up [1]."""
    chamber_wander_c: float = 0.0
    """Standard deviation of the chamber's slow wander (Ornstein-Uhlenbeck) [K]."""
    chamber_wander_tau_s: float = 600.0
    """Correlation time of the wander [s]."""
    cycling_c: float = 0.0
    """Amplitude of the chamber controller's cycling [K] (random phase per start-up)."""
    cycling_period_s: float = 600.0
    """Mean period of the cycling [s]."""
    cycling_period_rel_std: float = 0.0
    """Relative scatter of the cycling period, per start-up [1]."""
    cycling_shape: str = "sine"
    """``sine`` or ``triangle`` (bang-bang)."""
    thermometer_offset_c: float = 0.0
    """Scatter of each thermometer's offset, per unit [K]."""
    capacity_rel_std: float = 0.0
    """Relative scatter of each node's heat capacity, per unit [1]."""
    conductance_rel_std: float = 0.0
    """Relative scatter of each link's conductance, per unit [1]."""
    power_rel_std: float = 0.0
    """Relative scatter of each node power and thermal-effect power or slope, per unit [1]."""
    effect_rel_std: float = 0.0
    """Relative scatter of each gyro and accelerometer effect coefficient, per unit [1]."""
    parameters: tuple[tuple[str, float, bool], ...] = ()
    """(path or glob pattern, standard deviation, relative?) of one's own, per unit; they
    override the families above for the paths they match."""
    unit_seed: int = 0
    """Root of the unit draws (a scenario sets it to its own seed unless told otherwise, so
    training and test start-ups drawn with other seeds are made by the same units)."""

    @property
    def per_start_up(self) -> bool:
        """True when a start-up's soak or chamber varies."""
        return bool(self.soak_offset_c or self.soak_node_c or self.unfinished_soak
                    or self.chamber_wander_c or self.cycling_c)

    @property
    def per_unit(self) -> bool:
        """True when a unit's parameters vary."""
        return bool(self.thermometer_offset_c or self.capacity_rel_std
                    or self.conductance_rel_std or self.power_rel_std or self.effect_rel_std
                    or any(std for _, std, _ in self.parameters))

    @property
    def active(self) -> bool:
        """True when anything varies (False: every start-up at T0 soaked exactly at T0, the
        chamber as the scenario says, every unit the nominal instrument)."""
        return self.per_start_up or self.per_unit

    def describe(self) -> str:
        """One line: what varies and by how much."""
        if not self.active:
            return "none (every start-up soaked at T0, every unit the nominal instrument)"
        run, unit = [], []
        if self.soak_offset_c or self.soak_node_c:
            run.append(f"soak offset {self.soak_offset_c:g} K and node scatter "
                       f"{self.soak_node_c:g} K")
        if self.unfinished_soak:
            run.append(f"soak from {self.soak_from_c:g} C for {self.soak_h:g} h "
                       f"(+-{100 * self.soak_h_rel_std:g} %)")
        if self.chamber_wander_c:
            run.append(f"chamber wander {self.chamber_wander_c:g} K "
                       f"({self.chamber_wander_tau_s:g} s)")
        if self.cycling_c:
            run.append(f"{self.cycling_shape} cycling {self.cycling_c:g} K, "
                       f"{self.cycling_period_s:g} s (+-{100 * self.cycling_period_rel_std:g} %)")
        for name, v, what in (("thermometer_offset_c", self.thermometer_offset_c,
                               "thermometer offsets {} K"),
                              ("capacity_rel_std", self.capacity_rel_std, "capacities {} %"),
                              ("conductance_rel_std", self.conductance_rel_std,
                               "conductances {} %"),
                              ("power_rel_std", self.power_rel_std, "powers {} %"),
                              ("effect_rel_std", self.effect_rel_std,
                               "drift coefficients {} %")):
            if v:
                unit.append(what.format(f"{v if name.endswith('_c') else 100 * v:g}"))
        if self.parameters:
            unit.append(f"{len(self.parameters)} parameter(s) of their own")
        return (f"{self.preset}: per start-up " + (", ".join(run) or "nothing")
                + "; per unit (standard deviations) " + (", ".join(unit) or "nothing"))


#: Today's world: no variability.
NO_VARIABILITY = Variability()

#: A realistic set.  Engineering estimates (est.), each with its reason:
REALISTIC = Variability(
    preset="realistic",
    # A climatic chamber holds its set point to +-0.3-0.5 K (temperature fluctuation and
    # deviation in IEC 60068-3-5 terms) and the door is opened to cable the unit before
    # power-on: the unit sits a few tenths of a kelvin off the air it is then held in.
    soak_offset_c=0.2,
    # What the soak under the wandering chamber does not give: a steady spatial spread of the
    # air (+-0.5-1 K over the workspace, IEC 60068-3-5) sets a steady gradient that persists
    # after power-on and drives no rate; only its unsteady part, a few hundredths of a kelvin
    # between parts coupled within minutes, relaxes after power-on.
    soak_node_c=0.02,
    # Soaks end when the thermometers look steady (about 0.01 K/min), which leaves about
    # 0.5 K behind a 48 min global time constant (the default network's): 4 h +-15 % from a
    # 23 C laboratory leaves 0.2-0.8 K at -32 C, 0.1-0.4 K at 54 C (about twice as much in a
    # unit whose housing couples 15 % less to the air).
    unfinished_soak=True, soak_from_c=23.0, soak_h=4.0, soak_h_rel_std=0.15,
    # The same fluctuation band as a slow wander: 0.1 K, correlated over 10 min (the
    # chamber's outer control loop and its refrigeration duty cycle).
    chamber_wander_c=0.1, chamber_wander_tau_s=600.0,
    # Controller cycling of the air, 0.1 K amplitude, 5-15 min period.
    cycling_c=0.1, cycling_period_s=600.0, cycling_period_rel_std=0.1, cycling_shape="sine",
    # Platinum sensors of IEC 60751 class A: +-(0.15 + 0.002 |T|) K, read as a 1.5-sigma band.
    thermometer_offset_c=0.1,
    # Mass and specific heat of machined parts, boards and potting: a few percent.
    capacity_rel_std=0.05,
    # Bolted-joint contact conductance varies with torque, flatness and interface material by
    # tens of percent (Madhusudana, Thermal Contact Conductance, Springer 1996, ch. 1).
    conductance_rel_std=0.15,
    # Power draw of electronics boards and TECs of one design: component tolerances, 5 %.
    power_rel_std=0.05,
    # FOG thermal drift coefficients differ between coils of one design (winding symmetry,
    # fibre tension, potting), which is why each unit is compensated on its own: 20 %.
    effect_rel_std=0.2,
)

#: Presets by name.
VARIABILITY_PRESETS = {"none": NO_VARIABILITY, "custom": Variability(preset="custom"),
                       "realistic": REALISTIC}

#: Field names a scenario's ``[variability]`` table may set (besides ``preset`` and
#: ``parameters``).
VARIABILITY_KEYS = tuple(f.name for f in fields(Variability)
                         if f.name not in ("preset", "parameters"))


def lognormal_factor(z: float | np.ndarray, rel_std: float) -> float | np.ndarray:
    """exp(s z - s^2/2), s^2 = ln(1 + rel_std^2): a positive factor of mean 1 and standard
    deviation ``rel_std`` for z ~ N(0, 1)."""
    s2 = np.log1p(rel_std ** 2)
    return np.exp(np.sqrt(s2) * z - 0.5 * s2)


def _crc(text: str) -> int:
    return zlib.crc32(text.encode("utf-8"))


def _unit_normal(unit_seed: int, unit: int, path: str) -> float:
    """The standard normal draw of parameter ``path`` of unit ``unit``."""
    seq = np.random.SeedSequence([unit_seed, _UNIT_TAG, unit], spawn_key=(_crc(path),))
    return float(np.random.default_rng(seq).standard_normal())


def _run_rng(entropy, *key: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(entropy, spawn_key=key))


# ---------------------------------------------------------------------------------------------
# Per unit

def unit_scatter(inst: Instrument, var: Variability) -> dict[str, tuple[float, bool]]:
    """{path: (standard deviation, relative?)} of every parameter of ``inst`` that scatters.

    A pattern of ``var.parameters`` that matches nothing in ``inst`` is skipped (the scenario
    checks its patterns against its own instrument when it is read).
    """
    out: dict[str, tuple[float, bool]] = {}
    for path, kind in param_paths(inst):
        leaf = path.rsplit(".", 1)[-1]
        std, rel = 0.0, True
        if path.startswith("thermal.nodes."):
            std = var.capacity_rel_std if leaf == "capacity_j_per_k" else var.power_rel_std
        elif path.startswith("thermal.links."):
            std = var.conductance_rel_std
        elif path.startswith("coil."):      # a wound coil: its potting and its contacts
            std = {"heat_capacity_j_per_m3_k": var.capacity_rel_std,
                   "conductivity_w_per_m_k": var.conductance_rel_std}.get(
                leaf, var.conductance_rel_std if "_contacts." in path else 0.0)
        elif path.startswith("thermometers.") and leaf == "offset_c":
            std, rel = var.thermometer_offset_c, False
        elif path.startswith("effects."):
            label = path[len("effects."):].rsplit(".", 1)[0]
            par = inst.effect(label).spec.parameter(leaf)
            unit = par.unit
            if par.constant:        # a data sheet's constant: every unit of a design has it
                pass
            elif kind == "thermal" and unit in ("W", "W/K"):
                std = var.power_rel_std
            elif kind in ("drift", "accelerometer") and unit not in _REFERENCE_UNITS:
                std = var.effect_rel_std
        if std:
            out[path] = (std, rel)
    for pattern, std, rel in var.parameters:
        try:
            paths = expand_paths(inst, pattern)
        except ParameterError:      # a path this instrument does not have
            continue
        for p in paths:
            out[p] = (std, rel)
    return {p: v for p, v in out.items() if v[0] > 0.0}


def unit_instrument(inst: Instrument, var: Variability, unit: int) -> Instrument:
    """Unit ``unit`` of ``inst``: every parameter of :func:`unit_scatter` drawn once.

    The draw of a path depends only on (``var.unit_seed``, ``unit``, the path), so the same
    unit has the same parameters in every start-up, training or test.
    """
    values = {}
    for path, (std, rel) in unit_scatter(inst, var).items():
        z = _unit_normal(var.unit_seed, unit, path)
        v = get_param(inst, path)
        values[path] = v * float(lognormal_factor(z, std)) if rel else v + std * z
    return set_params(inst, values) if values else inst


# ---------------------------------------------------------------------------------------------
# Per start-up

@functools.lru_cache(maxsize=16)
def unpowered_network(network: thermal.Network) -> thermal.Network:
    """``network`` with every node's constant power set to zero (the unit switched off);
    made once per network (frozen: the start-ups of a unit share it)."""
    return thermal.Network(nodes=tuple(replace(n, power_w=0.0) for n in network.nodes),
                           links=network.links)


def _ou(t: np.ndarray, sigma: float, tau_s: float, z: np.ndarray) -> np.ndarray:
    """Ornstein-Uhlenbeck samples on the grid t from standard normals z, started stationary:
    w_0 = sigma z_0, w_{k+1} = a_k w_k + sigma sqrt(1 - a_k^2) z_{k+1}, a_k = exp(-h_k / tau);
    one linear filter per run of equal steps (equal to 1e-12: a grid k / fs has steps that
    differ in their last bits)."""
    a = np.exp(-np.diff(t) / tau_s)
    x = sigma * np.concatenate([z[:1], np.sqrt(1.0 - a ** 2) * z[1:]])
    w = np.empty_like(x)
    w[0] = x[0]
    k = 0                                           # w[k] known; fill the run of equal steps
    while k < a.size:
        j = _run_end(a, k)
        w[k + 1:j + 1] = lfilter([1.0], [1.0, -a[k]], x[k + 1:j + 1], zi=[a[k] * w[k]])[0]
        k = j
    return w


def _run_end(a: np.ndarray, k: int) -> int:
    """The first j > k with |a[j] - a[k]| > 1e-12 (a.size if none), searched in windows
    that double: a grid of equal steps costs a few array comparisons, not a Python loop
    over its samples."""
    j, width = k + 1, 64
    while j < a.size:
        far = np.flatnonzero(np.abs(a[j:j + width] - a[k]) > 1e-12)
        if far.size:
            return j + int(far[0])
        j, width = j + width, 2 * width
    return a.size


def chamber_terms(var: Variability, time_s: np.ndarray, entropy) -> np.ndarray:
    """The chamber's wander plus its controller cycling w(t) + a_c s(2 pi t / P + phi) [K],
    shape (n_t,), added to the scenario's chamber profile (module docstring)."""
    t = np.asarray(time_s, dtype=float)
    out = np.zeros(t.shape)
    if var.chamber_wander_c and t.size:
        z = _run_rng(entropy, _WANDER_KEY).standard_normal(t.size)
        out += _ou(t, var.chamber_wander_c, var.chamber_wander_tau_s, z)
    if var.cycling_c:
        rng = _run_rng(entropy, _CYCLING_KEY)
        phase = rng.uniform(0.0, 2.0 * np.pi)
        period = var.cycling_period_s * float(
            lognormal_factor(rng.standard_normal(), var.cycling_period_rel_std))
        arg = 2.0 * np.pi * t / period + phase
        wave = np.sin(arg) if var.cycling_shape == "sine" else \
            (2.0 / np.pi) * np.arcsin(np.sin(arg))
        out += var.cycling_c * wave
    return out


#: Step of the soak's grid [s]: resolves the chamber's wander and cycling (minutes).
SOAK_STEP_S = 10.0


def drawn_soak(var: Variability, entropy) -> tuple[float, float] | None:
    """(the temperature the unit came from [degC], the soak's drawn duration [h]) of an
    unfinished soak, as a laboratory log would give them (the measurement sidecar's
    ``soak_from_c`` and ``soak_h``); None without an unfinished soak."""
    if not var.unfinished_soak:
        return None
    _, z_soak = _run_rng(entropy, _SOAK_KEY).standard_normal(2)
    return var.soak_from_c, var.soak_h * float(lognormal_factor(z_soak, var.soak_h_rel_std))


def start_up_state(inst: Instrument, var: Variability, start_temperature_c: float,
                   time_s: np.ndarray, entropy) -> tuple[np.ndarray, np.ndarray]:
    """(T_j(0) [degC], shape (n_nodes,); the chamber's terms over the run [K], shape (n_t,)).

    The soak: the unpowered network from ``soak_from_c`` (an unfinished soak) or from T0,
    for t_soak before power-on, in the chamber air T0 + w(t) + cycling(t) (the same wander
    and cycling that go on over the run, so the unit enters the run in step with its
    chamber), solved exactly on a :data:`SOAK_STEP_S` grid held over each step; then the
    common offset and each node's scatter (module docstring).  Without an unfinished soak,
    a wander or a cycling, no soak is solved: T_j(0) = T0 + offsets.

    ``entropy`` is the start-up's seed (a :class:`numpy.random.SeedSequence` entropy).
    """
    net = inst.network
    t0 = float(start_temperature_c)
    t = np.asarray(time_s, dtype=float)
    rng = _run_rng(entropy, _SOAK_KEY)
    common, z_soak = rng.standard_normal(2)
    chamber = bool(var.chamber_wander_c or var.cycling_c)
    out = np.full(len(net.node_names), t0)
    terms = np.zeros(t.shape)
    if var.unfinished_soak or chamber:
        soak_s = 3600.0 * var.soak_h * float(lognormal_factor(z_soak, var.soak_h_rel_std))
        # whole steps only (t_soak rounded up to the grid, under SOAK_STEP_S longer than
        # drawn): a partial last step would be a step of its own, whose exponentials every
        # start-up would compute anew
        n = max(int(np.ceil(soak_s / SOAK_STEP_S)), 1)
        soak_t = t[0] - SOAK_STEP_S * np.arange(n, 0, -1)
        both = chamber_terms(var, np.concatenate([soak_t, t]), entropy)
        terms = both[n:]
        out = thermal.final_temperature(unpowered_network(net), np.append(soak_t, t[0]),
                                        ambient_c=t0 + both[:n + 1],
                                        initial_c=var.soak_from_c if var.unfinished_soak
                                        else t0)
    out += var.soak_offset_c * common
    if var.soak_node_c:
        share, shapes = _modes(net)
        z = _run_rng(entropy, _NODE_KEY).standard_normal(share.size)
        out += shapes @ (var.soak_node_c * np.sqrt(share) * z)
    return out, terms


@functools.lru_cache(maxsize=16)
def _modes(network: thermal.Network) -> tuple[np.ndarray, np.ndarray]:
    """(tau_i / tau_1, v_i) of the network's free modes, longest first (a mode with no path
    to the chamber: 1), kept per network (a sweep's start-ups of one unit share them)."""
    taus, shapes = network.modes()
    finite = np.isfinite(taus)
    share = np.ones(taus.size)
    if finite.any():
        share[finite] = taus[finite] / taus[finite].max()
    return share, shapes


def describe_units(units: int, run_units: Sequence[int]) -> str:
    """'unit 2 of 3' / 'units 0, 1 of 3'."""
    ids = ", ".join(str(u) for u in run_units)
    return f"unit{'s' if len(run_units) > 1 else ''} {ids} of {units}"
