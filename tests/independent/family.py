"""A family of independent units: one seed draws a whole unit, its chamber and its soak.

:mod:`generator` simulates one fixed unit.  A rule tuned to that one structure can pass on it
and fail on any other; here every set gets a unit of its own, drawn from a seed within the
physical ranges of the physics reference (``README.md`` next to this file: every range and
why):

Thermal structure
    the coil's thermal layers (16-24, graded toward both faces) and geometry, its spool hub
    and face contacts; its winding (pattern, optical layers, fibre length: the Shupe bias
    is the integral over it, ``winding.py``); the lumped capacities, powers
    and links scattered log-normally; optional extra paths (electronics-plate, board-plate,
    the board radiating onto the coil's outer face, the housing split into a shell and a
    base); where each thermometer sits (Dirichlet weights over candidate nodes), its lag,
    offset, noise and quantum.  Draws whose slowest time constant or 2.5 h coil rise falls
    outside the reference's range are drawn again.
TEC law
    quadratic, piecewise linear with a dead band, or quadratic clipped at the driver's limit
    (:func:`generator.tec_power_w`), set point 18-28 C.
Gyro noise
    angle random walk plus a Gauss-Markov bias, flicker, or a rate random walk.
Chamber and start
    an unfinished soak: the unpowered network brought from the laboratory and left 2-8 h in
    the chamber, whose air wanders (random walk or Ornstein-Uhlenbeck) and cycles (sine or
    triangle) through the soak and the run; a common offset of the unit from its air at
    power-on; the sidecar records the soak history with probability 1/2.
Hidden effect
    its amplitude scaled so that its excess over the channel's noise floor (the part a
    fitted model cannot take up, :func:`generator.unabsorbed_ratio_key`) is a drawn target,
    log-uniform over 1-3.

Seeds: every concern draws from its own stream, ``SeedSequence(seed, spawn_key=(crc32 of
the concern's name, ...))``, so adding a draw to one concern leaves the others unchanged;
the same seed gives the same bytes.  Imports nothing from ``nfs`` or ``thermal``.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Sequence

import numpy as np
from scipy.linalg import expm

if __package__:
    from . import generator as g
else:  # the folder on sys.path (benchmarks, examples, the command line)
    import generator as g
if __package__:
    from . import winding as wd
else:
    import winding as wd

__all__ = ["RANGES", "PATH_PROBABILITY", "SIDECAR_PROBABILITY", "AMPLITUDE",
           "START_TEMPERATURES_C", "HEAT_PLACES", "WINDING_PATTERNS", "ChamberDraw", "RunDraw", "FamilyDraw", "draw_unit",
           "chamber_air", "start_state", "simulate_family_run", "scale_to_strength",
           "generate_family_set"]

#: The seven start temperatures of a set [degC].
START_TEMPERATURES_C = (-32.0, -16.0, -5.0, 17.0, 28.0, 43.0, 54.0)
#: Probability that each optional thermal path is present.
PATH_PROBABILITY = 0.5
#: Probability that a set's sidecars record the soak history.
SIDECAR_PROBABILITY = 0.5
#: Relative scatter (log-normal sigma) of the lumped capacities, powers and links [1].
SCATTER = 0.3
#: Soak steps are at most this long [s] (the soak's chamber air is linear between them).
SOAK_STEP_S = 10.0
#: Attempts at a thermal structure inside the time-constant and rise ranges.
MAX_ATTEMPTS = 200

#: (lo, hi) of every drawn value, by name (units in the name's last part; README: why).
RANGES: dict[str, tuple[float, float]] = {
    # coil geometry (rejection on the derived capacity and radial conductance)
    "coil.n_layers": (16, 24),
    "coil.inner_radius_m": (0.030, 0.050),
    "coil.radius_ratio": (1.2, 1.6),
    "coil.height_m": (0.015, 0.045),
    "coil.conductivity_w_per_m_k": (0.15, 0.45),
    "coil.heat_j_per_m3_k": (1.4e6, 2.0e6),
    "coil.capacity_j_per_k": (120.0, 300.0),
    "coil.radial_w_per_k": (0.1, 0.4),
    "contact.spool_plate_w_per_k": (0.3, 1.2),
    "contact.outer_housing_w_per_k": (0.15, 0.6),
    # the source board over the coil's magnetic shield, through air and by radiation (not
    # a bonded contact): (k_air / gap + 4 eps sigma T^3) A, README: the Shupe bias's size
    "contact.outer_electronics_w_per_k": (0.01, 0.06),
    "contact.spool_bond_w_per_k": (1.0, 5.0),
    "capacity.spool_j_per_k": (50.0, 200.0),
    # the winding (Shupe weights from its pattern)
    "winding.n_layers": (24, 64),
    "winding.fibre_length_m": (500.0, 2000.0),
    # lumped nodes: nominal x log-normal(SCATTER), clipped
    "capacity.housing_j_per_k": (2000.0, 4500.0),
    "capacity.plate_j_per_k": (500.0, 1500.0),
    "capacity.electronics_j_per_k": (100.0, 300.0),
    "capacity.board_j_per_k": (150.0, 400.0),
    "capacity.qfa_j_per_k": (30.0, 60.0),
    "power.electronics_w": (2.0, 4.0),
    "power.board_w": (3.0, 8.0),
    "power.qfa_w": (0.3, 0.6),
    "link.housing_chamber_w_per_k": (1.0, 5.0),
    "link.plate_housing_w_per_k": (1.2, 5.0),
    "link.component_housing_w_per_k": (0.3, 2.0),
    "link.qfa_plate_w_per_k": (0.3, 1.0),
    # optional paths
    "path.electronics_plate_w_per_k": (0.1, 0.6),
    "path.board_plate_w_per_k": (0.1, 0.6),
    # radiation onto the shield's bare metal: 4 eps_eff sigma T^3 A, eps_eff 0.1-0.3
    "path.board_coil_radiation_w_per_k": (0.005, 0.03),
    "path.base_capacity_share": (0.3, 0.6),
    "path.base_chamber_share": (0.2, 0.5),
    "path.shell_base_w_per_k": (2.0, 8.0),
    # acceptance of the whole network
    "network.tau1_min": (20.0, 60.0),
    "network.coil_rise_k": (5.0, 15.0),
    # thermometers
    "thermometer.weight": (0.0, 1.0),
    "thermometer.lag_s": (10.0, 60.0),
    "thermometer.offset_c": (-0.1, 0.1),
    "thermometer.noise_c": (0.005, 0.02),
    "thermometer.quantum_c": (0.01, 0.0625),
    # TEC
    "tec.set_c": (18.0, 28.0),
    "tec.slope_below_w_per_k": (0.02, 0.04),
    "tec.slope_above_w_per_k": (0.05, 0.1),
    "tec.minimum_below_set_k": (3.0, 20.0),
    "tec.minimum_w": (0.05, 0.4),
    "tec.idle_w": (0.1, 0.4),
    "tec.dead_band_k": (0.5, 4.0),
    "tec.max_w": (0.8, 1.6),
    # gyro
    "gyro.arw_deg_per_rth_h": (0.0003, 0.001),
    "gyro.gm_sigma_dph": (0.002, 0.005),
    "gyro.gm_tau_s": (200.0, 1000.0),
    "gyro.flicker_b_dph": (0.002, 0.005),
    "gyro.rrw_dph_per_rth_h": (0.001, 0.004),
    "gyro.b0_dph": (-0.02, 0.02),
    "gyro.b1_dph_per_k": (0.0005, 0.003),
    "gyro.b2_dph_per_k2": (2.0e-5, 1.5e-4),
    "gyro.mean_rate_dph_per_k_per_min": (0.01, 0.04),
    # other sensors
    "tilt.deg": (-0.05, 0.05),
    "acc.bias_g": (-1.0e-4, 1.0e-4),
    "acc.noise_g_per_rth_hz": (15.0e-6, 30.0e-6),
    "osc.gain_v_per_k": (0.002, 0.006),
    "osc.walk_v_per_rth_s": (0.5e-4, 2.5e-4),
    # chamber
    "chamber.walk_k_per_rth_s": (2.0e-4, 1.0e-3),
    "chamber.ou_sigma_k": (0.02, 0.1),
    "chamber.ou_tau_s": (600.0, 3600.0),
    "chamber.cycle_k": (0.03, 0.15),
    "chamber.period_s": (300.0, 900.0),
    "chamber.logger_noise_c": (0.002, 0.01),
    # soak, per run
    "soak.from_c": (18.0, 28.0),
    "soak.h": (2.0, 8.0),
    "soak.offset_k": (-0.4, 0.4),
    # strength of the hidden effect
    "strength.target": (1.0, 3.0),
}

#: Hidden effect -> its amplitude parameter (the one scaled to the strength target).
AMPLITUDE = {"shupe_product": "k_p", "magnetic": "m", "scale_factor_temperature": "s1",
             "turn_on_transient": "a", "aux_linear": "k", "acc_bias_temperature": "b_q1",
             "heat_source": "power", "thermometer_lag": "tau", "outside": "c"}
#: Effects whose strength is not linear in the amplitude, and the search bounds [unit of
#: the amplitude]: a heat source moves the TEC's working point, a lag is no factor at all.
_NONLINEAR = {"heat_source": (0.01, 6.0), "thermometer_lag": (1.0, 3000.0)}
#: Where a hidden heat source can sit and the extra power it can dissipate there [W] (the
#: README's table: a heater on the spool hub or the housing, a driver in the FOG electronics,
#: the turntable's motor driver on the main board); never inside the passive winding.
HEAT_PLACES = {"spool": (0.05, 1.0), "electronics": (0.05, 1.5), "board": (0.1, 2.0),
               "housing": (0.1, 2.0)}
#: Winding patterns and their probabilities (quadrupole mostly; no dipole: its Shupe bias is
#: N/3 times a quadrupole's, far beyond a north finder's start-up drift, README).
WINDING_PATTERNS = {"quadrupole": 0.8, "octupole": 0.2}
#: Relative tolerance of the achieved strength on the target for the nonlinear effects.
STRENGTH_RTOL = 0.02
_THERMOMETER_CHOICES = (0.01, 0.015625, 0.03125, 0.0625)


# ---------------------------------------------------------------------------------------------
# Draws

def _key(part) -> int:
    return int(part) if isinstance(part, (int, np.integer)) else zlib.crc32(str(part).encode())


def _rng(seed: int, *concern) -> np.random.Generator:
    """The stream of one concern: SeedSequence(seed, spawn_key=(crc32(name), ...))."""
    return np.random.default_rng(np.random.SeedSequence(
        int(seed), spawn_key=tuple(_key(c) for c in concern)))


class _Record:
    """Draws within :data:`RANGES`, each recorded as (range name, value)."""

    def __init__(self):
        self.values: list[tuple[str, float]] = []

    def put(self, name: str, value: float) -> float:
        self.values.append((name, float(value)))
        return float(value)

    def uniform(self, rng, name: str) -> float:
        lo, hi = RANGES[name]
        return self.put(name, rng.uniform(lo, hi))

    def log_uniform(self, rng, name: str) -> float:
        lo, hi = RANGES[name]
        return self.put(name, math.exp(rng.uniform(math.log(lo), math.log(hi))))

    def scatter(self, rng, name: str, nominal: float) -> float:
        """nominal exp(SCATTER z), z ~ N(0, 1), clipped to the range."""
        lo, hi = RANGES[name]
        return self.put(name, float(np.clip(nominal * math.exp(SCATTER * rng.standard_normal()),
                                             lo, hi)))


@dataclass(frozen=True)
class ChamberDraw:
    """The chamber's air around the unit, the same through the soak and the run."""

    wander: str
    """``walk`` (random walk from the soak's start) or ``ou`` (Ornstein-Uhlenbeck)."""
    walk_k_per_rth_s: float
    """q of the random walk [K/sqrt(s)]."""
    ou_sigma_k: float
    """Standard deviation of the Ornstein-Uhlenbeck wander [K]."""
    ou_tau_s: float
    """Its correlation time [s]."""
    cycle_shape: str
    """``sine`` (a proportional controller's wobble) or ``triangle`` (bang-bang)."""
    cycle_k: float
    """Amplitude of the controller's cycling [K]."""
    period_s: float
    """Its period [s]."""


@dataclass(frozen=True)
class RunDraw:
    """The conditions of one run of a set."""

    soak_from_c: float
    """Laboratory temperature the unit was brought from [degC]."""
    soak_h: float
    """Time it soaked, unpowered, in the chamber before power-on [h]."""
    offset_k: float
    """Common offset of every node from the soak's end at power-on [K]."""
    cycle_phase: float
    """Phase of the chamber's cycling at the soak's start [cycles, 0-1]."""


@dataclass(frozen=True)
class FamilyDraw:
    """One unit of the family and its run conditions, drawn from ``seed``."""

    seed: int
    """The seed everything was drawn from."""
    unit: g.Unit
    """The drawn unit (thermal structure, TEC law, thermometers, gyro noise, sensors)."""
    paths: tuple
    """Names of the optional thermal paths present (``electronics-plate``, ``board-plate``,
    ``board-coil radiation``, ``shell/base``)."""
    chamber: ChamberDraw
    """The chamber's wander and cycling."""
    runs: tuple
    """:class:`RunDraw` of the seven runs of a set (:meth:`run_draw` for any index)."""
    sidecar: bool
    """True: the sidecars record ``soak_from_c`` and ``soak_h``."""
    strength_target: float
    """Target of a hidden effect's unabsorbed excess over its floor [1]."""
    noise_seed: int
    """Seed of the sensors' noise streams (:func:`generator.simulate_run`)."""
    attempts: int
    """Thermal structures drawn until one fell inside the time-constant and rise ranges."""
    drawn: tuple
    """Every drawn value as (name in :data:`RANGES`, value)."""

    def run_draw(self, run_index: int) -> RunDraw:
        """The conditions of run ``run_index``."""
        if 0 <= run_index < len(self.runs):
            return self.runs[run_index]
        return _draw_run(self.seed, run_index, _Record())

    def describe(self) -> str:
        """The unit and its world in one line."""
        u = self.unit
        c = u.coil
        tau1 = g.unit_network(u).time_constants_s()[0] / 60.0
        fog = " + ".join(f"{w:.2f} {n}" for n, w in
                         sorted(u.fog_thermometer.items(), key=lambda kv: -kv[1]))
        noise = {"gauss_markov": f"GM {u.gm_sigma_dph:.4f} deg/h {u.gm_tau_s:.0f} s",
                 "flicker": f"flicker B {u.flicker_b_dph:.4f} deg/h",
                 "rate_random_walk": f"RRW {u.rrw_dph_per_rth_h:.4f} deg/h/rt-h"}[u.bias_noise]
        ch = self.chamber
        wander = (f"walk {ch.walk_k_per_rth_s:.1e} K/rt-s" if ch.wander == "walk"
                  else f"OU {ch.ou_sigma_k:.3f} K/{ch.ou_tau_s / 60:.0f} min")
        soak = [r.soak_h for r in self.runs]
        w = u.winding
        return (f"seed {self.seed}: coil {c.n_layers} layers r {1e3 * c.inner_radius_m:.0f}-"
                f"{1e3 * c.outer_radius_m:.0f} mm, {w.pattern} {w.n_layers} layers "
                f"{w.fibre_length_m:.0f} m, paths "
                f"{'+'.join(self.paths) if self.paths else 'none'}, tau1 {tau1:.0f} min; "
                f"FOG thermometer {fog}; TEC {u.tec_law} at {u.tec_set_c:.1f} C; gyro ARW "
                f"{u.arw_deg_per_rth_h:.5f} + {noise}; chamber {wander} + {ch.cycle_shape} "
                f"{ch.cycle_k:.2f} K/{ch.period_s / 60:.1f} min; soak {min(soak):.1f}-"
                f"{max(soak):.1f} h (sidecar {'yes' if self.sidecar else 'no'}); strength "
                f"target {self.strength_target:.2f}x")


def _draw_coil(rng, rec: _Record) -> g.CoilGeometry:
    """Geometry drawn until the coil's capacity and radial conductance lie in their ranges.

    C = rho c pi (r_out^2 - r_in^2) h and G = 2 pi k h / ln(r_out / r_in) (Incropera &
    DeWitt, 6th ed., eq. (3.27)).
    """
    lo_c, hi_c = RANGES["coil.capacity_j_per_k"]
    lo_g, hi_g = RANGES["coil.radial_w_per_k"]
    for _ in range(MAX_ATTEMPTS):
        trial = _Record()
        n = int(rng.integers(RANGES["coil.n_layers"][0], RANGES["coil.n_layers"][1] + 1))
        r_in = trial.uniform(rng, "coil.inner_radius_m")
        ratio = trial.uniform(rng, "coil.radius_ratio")
        h = trial.uniform(rng, "coil.height_m")
        k = trial.uniform(rng, "coil.conductivity_w_per_m_k")
        rho_c = trial.uniform(rng, "coil.heat_j_per_m3_k")
        cap = rho_c * math.pi * r_in ** 2 * (ratio ** 2 - 1.0) * h
        g_rad = 2.0 * math.pi * k * h / math.log(ratio)
        if lo_c <= cap <= hi_c and lo_g <= g_rad <= hi_g:
            rec.put("coil.n_layers", n)
            rec.values += trial.values
            rec.put("coil.capacity_j_per_k", cap)
            rec.put("coil.radial_w_per_k", g_rad)
            return g.CoilGeometry(inner_radius_m=r_in, outer_radius_m=r_in * ratio,
                                  height_m=h, n_layers=n, conductivity_w_per_m_k=k,
                                  heat_j_per_m3_k=rho_c, spacing="cosine")
    raise RuntimeError("no coil geometry inside the capacity and conductance ranges")


def _draw_thermal(seed: int, attempt: int, rec: _Record):
    """One attempt at the thermal structure: Unit keyword arguments and the paths present."""
    coil = _draw_coil(_rng(seed, "coil", attempt), rec)
    rc = _rng(seed, "coil_contacts", attempt)
    spool = rec.log_uniform(rc, "contact.spool_plate_w_per_k")
    outer = [("housing", rec.log_uniform(rc, "contact.outer_housing_w_per_k")),
             ("electronics", rec.log_uniform(rc, "contact.outer_electronics_w_per_k"))]
    # the spool hub: an aluminium body between the mounting plate and the winding's spool
    # face, bonded to it with epoxy (drawn after the contacts: their values unchanged)
    bond = rec.log_uniform(rc, "contact.spool_bond_w_per_k")
    hub = rec.uniform(rc, "capacity.spool_j_per_k")
    nominal = g.Unit()
    rl = _rng(seed, "lumped", attempt)
    cap = {n: rec.scatter(rl, f"capacity.{'qfa' if n.startswith('qfa') else n}_j_per_k", c)
           for n, c in nominal.capacity_j_per_k.items()}
    cap["spool"] = hub
    power = {n: rec.scatter(rl, f"power.{'qfa' if n.startswith('qfa') else n}_w", p)
             for n, p in nominal.power_w.items()}
    link_range = {("housing", "chamber"): "link.housing_chamber_w_per_k",
                  ("plate", "housing"): "link.plate_housing_w_per_k",
                  ("qfa_x", "plate"): "link.qfa_plate_w_per_k",
                  ("qfa_y", "plate"): "link.qfa_plate_w_per_k"}
    links = [(a, b, rec.scatter(rl, link_range.get((a, b), "link.component_housing_w_per_k"),
                                gk)) for a, b, gk in nominal.links_w_per_k]
    # optional paths: every value drawn whether the path is present or not, so that one
    # path's presence never moves another's draw
    rp = _rng(seed, "paths", attempt)
    present = {name: bool(rp.uniform() < PATH_PROBABILITY)
               for name in ("electronics-plate", "board-plate", "board-coil", "shell/base")}
    opt = _Record()
    g_ep = opt.log_uniform(rp, "path.electronics_plate_w_per_k")
    g_bp = opt.log_uniform(rp, "path.board_plate_w_per_k")
    g_bc = opt.log_uniform(rp, "path.board_coil_radiation_w_per_k")
    share_c = opt.uniform(rp, "path.base_capacity_share")
    share_g = opt.uniform(rp, "path.base_chamber_share")
    g_sb = opt.log_uniform(rp, "path.shell_base_w_per_k")
    used = {"electronics-plate": ("path.electronics_plate_w_per_k",),
            "board-plate": ("path.board_plate_w_per_k",),
            "board-coil": ("path.board_coil_radiation_w_per_k",),
            "shell/base": ("path.base_capacity_share", "path.base_chamber_share",
                           "path.shell_base_w_per_k")}
    rec.values += [(k, v) for k, v in opt.values
                   if any(present[p] and k in used[p] for p in present)]
    if present["electronics-plate"]:
        links.append(("electronics", "plate", g_ep))
    if present["board-plate"]:
        links.append(("board", "plate", g_bp))
    if present["board-coil"]:
        # linearised radiation h_r A = 4 eps_eff sigma T^3 A between the board (eps 0.9)
        # and the bare metal of the coil's shield over its outer face (eps 0.1-0.3), eps_eff
        # = 1 / (1/eps_1 + 1/eps_2 - 1) (Incropera & DeWitt, 6th ed., eqs. (1.9), (13.19))
        outer.append(("board", g_bc))
    if present["shell/base"]:
        # "housing" becomes the shell (cover); the base takes a share of its capacity and of
        # its path to the chamber (the feet), and carries the plate
        cap["base"] = cap["housing"] * share_c
        cap["housing"] = cap["housing"] * (1.0 - share_c)
        new = []
        for a, b, gk in links:
            if (a, b) == ("housing", "chamber"):
                new += [("housing", "chamber", gk * (1.0 - share_g)), ("base", "chamber",
                                                                        gk * share_g)]
            elif (a, b) == ("plate", "housing"):
                new.append(("plate", "base", gk))
            else:
                new.append((a, b, gk))
        links = new + [("housing", "base", g_sb)]
    names = tuple(p for p in present if present[p])
    links.append(("spool", "plate", spool))
    kw = dict(capacity_j_per_k=cap, power_w=power, links_w_per_k=tuple(links), coil=coil,
              coil_spool_links_w_per_k=(("spool", bond),),
              coil_outer_links_w_per_k=tuple(outer))
    return kw, names


def _coil_rise_k(unit: g.Unit, duration_s: float) -> float:
    """Capacity-weighted coil rise after ``duration_s`` from uniform, still air, the TEC at
    its set-point power: T(t) - T0 = A^-1 (expm(A t) - I) C^-1 P (linear network) [K]."""
    net = g.unit_network(unit)
    a = net.a_per_s
    p = np.zeros(len(net.names))
    for n, pw in unit.power_w.items():
        p[net.names.index(n)] += pw
    p[net.names.index("electronics")] += float(g.tec_power_w(unit, unit.tec_set_c))
    growth = (expm(a * duration_s) - np.eye(len(p))) @ (p / net.capacity_j_per_k)
    rise = np.linalg.solve(a, growth)
    layers = [net.names.index(n) for n in g._layer_names(unit.coil.n_layers)]
    c = net.capacity_j_per_k[layers]
    return float(rise[layers] @ c / c.sum())


def _draw_tec(rng, rec: _Record) -> dict:
    """TEC law and its parameters (every parameter drawn whatever the law).

    Quadratic: p = p_min + c (d + d_min)^2 with d = T_src - T_set, its slope -s_b at 45 K
    below the set point and +s_a at 40 K above (the reference's TEC slopes): c = (s_a +
    s_b)/170, d_min = s_a/(2c) - 40, drawn again until the minimum lies 3-20 K below.
    """
    law = g.TEC_LAWS[int(rng.integers(len(g.TEC_LAWS)))]
    t_set = rec.uniform(rng, "tec.set_c")
    lo, hi = RANGES["tec.minimum_below_set_k"]
    for _ in range(MAX_ATTEMPTS):
        trial = _Record()
        s_b = trial.uniform(rng, "tec.slope_below_w_per_k")
        s_a = trial.uniform(rng, "tec.slope_above_w_per_k")
        c = (s_a + s_b) / 170.0
        d_min = s_a / (2.0 * c) - 40.0
        if lo <= d_min <= hi:
            break
    else:
        raise RuntimeError("no TEC slopes with the minimum 3-20 K below the set point")
    rec.values += trial.values
    rec.put("tec.minimum_below_set_k", d_min)
    p_min = rec.uniform(rng, "tec.minimum_w")
    idle = rec.uniform(rng, "tec.idle_w")
    band = rec.uniform(rng, "tec.dead_band_k")
    p_max = rec.uniform(rng, "tec.max_w")
    kw = dict(tec_law=law, tec_set_c=t_set, tec_max_w=p_max)
    if law == "piecewise":
        kw.update(tec_p0_w=idle, tec_heat_w_per_k=s_b, tec_cool_w_per_k=s_a,
                  tec_dead_band_k=band)
    else:   # p_min + c (d + d_min)^2 = p0 + a d + c d^2
        kw.update(tec_p0_w=p_min + c * d_min ** 2, tec_a_w_per_k=2.0 * c * d_min,
                  tec_c_w_per_k2=c)
    return kw


def _draw_thermometers(rng, n_layers: int, rec: _Record) -> dict:
    """Where each thermometer sits (Dirichlet weights over its candidate nodes), its lag,
    offset; noise and quantum (one sensor type for the three)."""
    fog_nodes = ["housing", "plate", "electronics", "coil_outer"]
    if n_layers >= 4:
        fog_nodes.append(f"coil_{n_layers - 2}")
    w = rng.dirichlet(np.ones(len(fog_nodes)))
    fog = {n: rec.put("thermometer.weight", x) for n, x in zip(fog_nodes, w)}
    acc = {}
    for ax in ("x", "y"):
        wb = rng.dirichlet([3.0, 1.0])
        acc[ax] = {f"qfa_{ax}": rec.put("thermometer.weight", wb[0]),
                   "plate": rec.put("thermometer.weight", wb[1])}
    lag = {k: rec.uniform(rng, "thermometer.lag_s") for k in ("fog", "x", "y")}
    off = {k: rec.uniform(rng, "thermometer.offset_c") for k in ("fog", "x", "y")}
    noise = rec.log_uniform(rng, "thermometer.noise_c")
    quantum = rec.put("thermometer.quantum_c",
                      _THERMOMETER_CHOICES[int(rng.integers(len(_THERMOMETER_CHOICES)))])
    return dict(fog_thermometer=fog, acc_thermometers=acc, thermometer_lag_s=lag,
                thermometer_offset_c=off, thermometer_noise_c=noise,
                thermometer_quantum_c=quantum)


def _draw_gyro(seed: int, rec: _Record) -> dict:
    """ARW and the bias noise's law (its parameters all drawn); the drift coefficients."""
    rn = _rng(seed, "gyro_noise")
    law = g.BIAS_NOISE_LAWS[int(rn.integers(len(g.BIAS_NOISE_LAWS)))]
    kw = dict(bias_noise=law, arw_deg_per_rth_h=rec.log_uniform(rn, "gyro.arw_deg_per_rth_h"))
    noise = _Record()
    law_kw = dict(gm_sigma_dph=noise.log_uniform(rn, "gyro.gm_sigma_dph"),
                  gm_tau_s=noise.log_uniform(rn, "gyro.gm_tau_s"),
                  flicker_b_dph=noise.log_uniform(rn, "gyro.flicker_b_dph"),
                  rrw_dph_per_rth_h=noise.log_uniform(rn, "gyro.rrw_dph_per_rth_h"))
    prefix = {"gauss_markov": "gyro.gm_", "flicker": "gyro.flicker_",
              "rate_random_walk": "gyro.rrw_"}[law]
    rec.values += [(k, v) for k, v in noise.values if k.startswith(prefix)]
    kw.update(law_kw)
    rd = _rng(seed, "gyro_drift")
    kw.update(b0_dph=rec.uniform(rd, "gyro.b0_dph"),
              b1_dph_per_k=rec.uniform(rd, "gyro.b1_dph_per_k"),
              b2_dph_per_k2=rec.log_uniform(rd, "gyro.b2_dph_per_k2"),
              # the cosine weight's k_sh: still drawn (the stream's order), no longer used
              shupe_dph_per_k_per_min=math.exp(rd.uniform(math.log(0.05), math.log(0.15))),
              mean_rate_dph_per_k_per_min=rec.log_uniform(
                  rd, "gyro.mean_rate_dph_per_k_per_min"))
    return kw


def _draw_winding(seed: int, rec: _Record) -> wd.Winding:
    """Pattern (quadrupole mostly), optical layers (a whole number of the pattern's blocks)
    and fibre length, from the ``winding`` stream."""
    rw = _rng(seed, "winding")
    names = list(WINDING_PATTERNS)
    pattern = names[int(rw.choice(len(names), p=list(WINDING_PATTERNS.values())))]
    lo, hi = RANGES["winding.n_layers"]
    n = int(rw.integers(lo, hi + 1))
    period = wd.PERIOD[pattern]
    n = max(period * math.ceil(lo / period), period * (n // period))
    rec.put("winding.n_layers", n)
    length = rec.log_uniform(rw, "winding.fibre_length_m")
    return wd.Winding(pattern=pattern, n_layers=n, fibre_length_m=length)


def _draw_sensors(seed: int, rec: _Record) -> dict:
    """Tilt, accelerometer biases and noise, the oscillator's law."""
    rs = _rng(seed, "sensors")
    return dict(tilt_north_deg=rec.uniform(rs, "tilt.deg"),
                tilt_east_deg=rec.uniform(rs, "tilt.deg"),
                acc_bias_g=(rec.uniform(rs, "acc.bias_g"), rec.uniform(rs, "acc.bias_g")),
                acc_noise_g_per_rth_hz=rec.uniform(rs, "acc.noise_g_per_rth_hz"),
                osc_gain_v_per_k=rec.uniform(rs, "osc.gain_v_per_k"),
                osc_walk_v_per_rth_s=rec.log_uniform(rs, "osc.walk_v_per_rth_s"))


def _draw_chamber(seed: int, rec: _Record) -> tuple[ChamberDraw, float]:
    """The chamber's wander and cycling, and its logger's noise [degC]."""
    rc = _rng(seed, "chamber")
    wander = ("walk", "ou")[int(rc.integers(2))]
    shape = ("sine", "triangle")[int(rc.integers(2))]
    w = _Record()
    walk = w.log_uniform(rc, "chamber.walk_k_per_rth_s")
    sigma = w.uniform(rc, "chamber.ou_sigma_k")
    tau = w.log_uniform(rc, "chamber.ou_tau_s")
    rec.values += [(k, v) for k, v in w.values if k.startswith(
        "chamber.walk" if wander == "walk" else "chamber.ou")]
    ch = ChamberDraw(wander=wander, walk_k_per_rth_s=walk, ou_sigma_k=sigma, ou_tau_s=tau,
                     cycle_shape=shape, cycle_k=rec.uniform(rc, "chamber.cycle_k"),
                     period_s=rec.uniform(rc, "chamber.period_s"))
    return ch, rec.log_uniform(rc, "chamber.logger_noise_c")


def _draw_run(seed: int, run_index: int, rec: _Record) -> RunDraw:
    rr = _rng(seed, "soak", run_index)
    return RunDraw(soak_from_c=rec.uniform(rr, "soak.from_c"),
                   soak_h=rec.uniform(rr, "soak.h"), offset_k=rec.uniform(rr, "soak.offset_k"),
                   cycle_phase=float(rr.uniform()))


def draw_unit(seed: int) -> FamilyDraw:
    """Draw one unit of the family and its run conditions from ``seed`` (>= 0).

    Deterministic in ``seed``; each concern (coil, contacts, lumped nodes, paths,
    thermometers, TEC, gyro noise, gyro drift, other sensors, chamber, each run's soak,
    sidecar, strength, noise seed) from its own stream.  The thermal structure is drawn
    again (attempt 1, 2, ... as part of its streams' keys) until the network's slowest time
    constant and its 2.5 h coil rise lie in :data:`RANGES`.
    """
    if int(seed) < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    seed = int(seed)
    base = g.Unit()
    rec = _Record()
    tec = _draw_tec(_rng(seed, "tec"), rec)
    for attempt in range(MAX_ATTEMPTS):
        trial = _Record()
        kw, paths = _draw_thermal(seed, attempt, trial)
        unit = replace(base, **kw, **tec)
        tau1 = g.unit_network(unit).time_constants_s()[0] / 60.0
        rise = _coil_rise_k(unit, 9000.0)
        lo_t, hi_t = RANGES["network.tau1_min"]
        lo_r, hi_r = RANGES["network.coil_rise_k"]
        if lo_t <= tau1 <= hi_t and lo_r <= rise <= hi_r:
            rec.values += trial.values
            rec.put("network.tau1_min", tau1)
            rec.put("network.coil_rise_k", rise)
            break
    else:
        raise RuntimeError(f"seed {seed}: no thermal structure inside the ranges")
    therm = _draw_thermometers(_rng(seed, "thermometers"), unit.coil.n_layers, rec)
    chamber, logger = _draw_chamber(seed, rec)
    unit = replace(unit, **therm, **_draw_gyro(seed, rec), **_draw_sensors(seed, rec),
                   chamber_logger_noise_c=logger, winding=_draw_winding(seed, rec))
    runs = tuple(_draw_run(seed, i, rec) for i in range(len(START_TEMPERATURES_C)))
    sidecar = bool(_rng(seed, "sidecar").uniform() < SIDECAR_PROBABILITY)
    target = rec.log_uniform(_rng(seed, "strength"), "strength.target")
    noise_seed = int(_rng(seed, "noise_seed").integers(2 ** 62))
    return FamilyDraw(seed=seed, unit=unit, paths=paths, chamber=chamber, runs=runs,
                      sidecar=sidecar, strength_target=target, noise_seed=noise_seed,
                      attempts=attempt + 1, drawn=tuple(rec.values))


# ---------------------------------------------------------------------------------------------
# Chamber air and the unfinished soak

def chamber_air(chamber: ChamberDraw, t0_c: float, time_s: np.ndarray, phase: float,
                rng: np.random.Generator) -> np.ndarray:
    """T_amb(t) = T0 + a s(t / P + phase) + w(t) on the given (increasing) times [degC].

    Cycling s: ``sine`` sin(2 pi x) or ``triangle`` (2/pi) arcsin(sin(2 pi x)) (a
    bang-bang controller heating and cooling at constant rates), amplitude a [K], period P
    [s].  Wander w from the first time on: ``walk`` w_0 = 0, w_k+1 = w_k + q sqrt(dt_k)
    z_k [K/sqrt(s)]; ``ou`` w_0 ~ N(0, sigma^2), w_k+1 = w_k e_k + sigma sqrt(1 - e_k^2)
    z_k, e_k = exp(-dt_k / tau), the exact update of an Ornstein-Uhlenbeck process
    (Gillespie, Phys. Rev. E 54(2) 2084, 1996, eq. (1.3)).
    """
    t = np.asarray(time_s, dtype=float)
    x = 2.0 * np.pi * (t / chamber.period_s + phase)
    s = np.sin(x) if chamber.cycle_shape == "sine" else (2.0 / np.pi) * np.arcsin(np.sin(x))
    z = rng.standard_normal(t.size)
    dt = np.diff(t)
    if chamber.wander == "walk":
        w = np.concatenate([[0.0], np.cumsum(chamber.walk_k_per_rth_s * np.sqrt(dt) * z[1:])])
    else:
        e = np.exp(-dt / chamber.ou_tau_s)
        b = chamber.ou_sigma_k * np.sqrt(1.0 - e * e)
        w = np.empty(t.size)
        w[0] = chamber.ou_sigma_k * z[0]
        for k in range(t.size - 1):
            w[k + 1] = w[k] * e[k] + b[k] * z[k + 1]
    return t0_c + chamber.cycle_k * s + w


def start_state(draw: FamilyDraw, run_index: int, t0_c: float, *, duration_s: float = 9000.0,
                sample_rate_hz: float = 1.0, network: g.Network | None = None):
    """Node temperatures at power-on and the chamber air over the run.

    The unpowered network (C dT/dt = -L T + G_b T_amb), uniform at the laboratory's
    ``soak_from_c``, is left ``soak_h`` in the chamber air of :func:`chamber_air`, stepped
    exactly (:class:`generator.Stepper`, air linear between steps of at most
    :data:`SOAK_STEP_S`); the same air process goes on over the run's samples.  In still air
    the end is T0 + expm(A t_soak) (T_from - T0) 1.  Every node then gets the run's common
    offset (the unit a few tenths off its air: the door opened to cable it, unevenly stirred
    air).  Returns (initial node temperatures [degC], chamber air per sample [degC]).
    """
    rd = draw.run_draw(run_index)
    net = g.unit_network(draw.unit) if network is None else network
    h = 1.0 / sample_rate_hz
    n = int(round(duration_s * sample_rate_hz))
    t_soak = 3600.0 * rd.soak_h
    n_soak = max(1, math.ceil(t_soak / SOAK_STEP_S))
    h_soak = t_soak / n_soak
    times = np.concatenate([-t_soak + h_soak * np.arange(n_soak), h * np.arange(n)])
    air = chamber_air(draw.chamber, t0_c, times, rd.cycle_phase,
                      _rng(draw.seed, "chamber_path", run_index))
    st = g.Stepper(net, h_soak)
    drive = st.boundary_terms(air[:n_soak + 1, None])
    x = np.full(len(net.names), rd.soak_from_c)
    for k in range(n_soak):
        x = st.phi @ x + drive[k]
    return x + rd.offset_k, air[n_soak:]


def simulate_family_run(draw: FamilyDraw, run_index: int, t0_c: float, *,
                        hidden: str | None = None, params: dict | None = None,
                        duration_s: float = 9000.0, sample_rate_hz: float = 1.0,
                        latitude_deg: float = 30.26, true_heading_deg: float = 212.7,
                        start=None, power_off_s: Sequence[tuple[float, float]] = (),
                        chamber_offset_c=None, dwell_s: float = g._DWELL_S,
                        move_s: float = g._MOVE_S) -> g.RunData:
    """One run of the drawn unit: :func:`start_state` then :func:`generator.simulate_run`
    with the unit's own noise seed.  ``start``: a (initial, air) pair already computed.

    ``power_off_s``: power cycles, ``dwell_s`` and ``move_s`` the turntable's schedule,
    passed through (:func:`generator.simulate_run`).
    ``chamber_offset_c``: a chamber program's departure from T0 over the run, one value per
    sample [K] (a ramp: 0 until it starts, then the ramp, then the hold), added to the
    drawn air (the controller's cycling and wander go on about the new set point)."""
    initial, air = start if start is not None else start_state(
        draw, run_index, t0_c, duration_s=duration_s, sample_rate_hz=sample_rate_hz)
    if chamber_offset_c is not None:
        offset = np.asarray(chamber_offset_c, dtype=float)
        if offset.shape != air.shape:
            raise ValueError(f"chamber_offset_c needs {air.size} samples, got shape "
                             f"{offset.shape}")
        air = air + offset
    return g.simulate_run(t0_c, hidden=hidden, params=params, seed=draw.noise_seed,
                          run_index=run_index, duration_s=duration_s,
                          sample_rate_hz=sample_rate_hz, latitude_deg=latitude_deg,
                          true_heading_deg=true_heading_deg, unit=draw.unit,
                          chamber_c=air, initial_c=initial, power_off_s=power_off_s,
                          dwell_s=dwell_s, move_s=move_s)


# ---------------------------------------------------------------------------------------------
# Strength of the hidden effect

class _SetRuns:
    """The runs of one set of a drawn unit, the starts and the effect-free runs computed once."""

    def __init__(self, draw: FamilyDraw, temps, run_kw: dict):
        self.draw, self.temps, self.kw = draw, tuple(float(t) for t in temps), run_kw
        net = g.unit_network(draw.unit)
        self.starts = [start_state(draw, i, t0, duration_s=run_kw["duration_s"],
                                   sample_rate_hz=run_kw["sample_rate_hz"], network=net)
                       for i, t0 in enumerate(self.temps)]
        self._without = None

    def runs(self, hidden=None, params=None) -> list:
        return [simulate_family_run(self.draw, i, t0, hidden=hidden, params=params,
                                    start=self.starts[i], **self.kw)
                for i, t0 in enumerate(self.temps)]

    def without(self) -> list:
        if self._without is None:
            self._without = self.runs()
        return self._without

    def strength(self, hidden: str, params: dict) -> tuple[dict, list]:
        """:func:`generator.strength_of_runs` of the set with the effect; the runs."""
        with_ = self.runs(hidden, params)
        thermo = g._CHANNEL[hidden].startswith("temp_")
        pairs = zip(with_, self.without() if thermo else [None] * len(with_))
        return g.strength_of_runs(hidden, params, pairs, self.kw["sample_rate_hz"]), with_


def _lag_ratio(set_runs: _SetRuns, tau_s: float) -> float:
    """The after-rescale ratio of an extra FOG-thermometer lag tau, from the effect-free
    runs alone: lag(y + offset) = lag(y) + offset, so the effect is lag(clean) - clean."""
    h = 1.0 / set_runs.kw["sample_rate_hz"]
    ex, fl = [], []
    for run in set_runs.without():
        y = run.clean["temp_fog_c"]
        ex.append(g._after_rescale(g.first_order_lag(y, h, tau_s) - y, y - y[0]))
        fl.append(run.columns["temp_fog_c"] - y)
    return float(np.sqrt(np.mean(np.concatenate(ex) ** 2) / np.mean(np.concatenate(fl) ** 2)))


def scale_to_strength(draw: FamilyDraw, hidden: str, params: dict, target: float, *,
                      start_temperatures_c=START_TEMPERATURES_C, duration_s: float = 9000.0,
                      sample_rate_hz: float = 1.0, latitude_deg: float = 30.26,
                      true_heading_deg: float = 212.7, _set_runs=None):
    """Scale the hidden effect's amplitude so that its unabsorbed ratio is ``target``.

    Linear effects (every gyro and accelerometer effect here: the term is amplitude times a
    signal the amplitude does not change): one measurement at the given amplitude, a linear
    rescale.  A heat source changes the TEC's working point (not quite linear): secant steps
    until within :data:`STRENGTH_RTOL`.  A thermometer lag: bisection in log tau on the
    ratio computed from the effect-free runs (:func:`_lag_ratio`, monotone in tau).  The
    amplitude stays inside the bounds of ``_NONLINEAR`` (a heat source: its place's
    power range, :data:`HEAT_PLACES`; the achieved ratio then falls short).  Returns (params, the achieved strength dict, the runs with the effect).
    """
    sr = _set_runs or _SetRuns(draw, start_temperatures_c, dict(
        duration_s=duration_s, sample_rate_hz=sample_rate_hz, latitude_deg=latitude_deg,
        true_heading_deg=true_heading_deg))
    p = g._check_hidden(hidden, params)
    amp, key = AMPLITUDE[hidden], g.unabsorbed_ratio_key(hidden)
    lo, hi = _NONLINEAR.get(hidden, (0.0, math.inf))
    if hidden == "heat_source":
        if p["node"] not in HEAT_PLACES:
            raise ValueError(f"a drawn unit's heat source sits at one of "
                             f"{', '.join(HEAT_PLACES)}, not {p['node']!r} (a passive winding "
                             f"dissipates nothing)")
        lo, hi = HEAT_PLACES[p["node"]]
    if hidden == "thermometer_lag":
        a, b = math.log(lo), math.log(hi)
        if _lag_ratio(sr, hi) <= target:
            a = b
        for _ in range(40):
            mid = 0.5 * (a + b)
            if _lag_ratio(sr, math.exp(mid)) < target:
                a = mid
            else:
                b = mid
        p[amp] = math.exp(0.5 * (a + b))
    for _ in range(6):
        s, runs = sr.strength(hidden, p)
        ratio = s[key]
        if hidden == "thermometer_lag" or abs(ratio / target - 1.0) <= STRENGTH_RTOL \
                or ratio <= 0:
            break
        new = float(np.clip(p[amp] * target / ratio, lo, hi))
        if new == p[amp]:
            break
        p[amp] = new
        if hidden not in _NONLINEAR:     # linear: one rescale hits it; measure it once more
            s, runs = sr.strength(hidden, p)
            break
    return p, s, runs


# ---------------------------------------------------------------------------------------------
# A set

def _hidden_params(seed: int, hidden: str) -> dict:
    """The hidden effect's own draws (not its amplitude): the magnetic and quadrantal
    directions, the transient's time constant (1-5 min), the heat source's place (where heat
    can be dissipated: :data:`HEAT_PLACES`; the winding's faces get it through the hub's bond
    or the outer face's contacts)."""
    p = dict(g.HIDDEN_EFFECTS[hidden])
    rh = _rng(seed, "hidden", hidden)
    if hidden == "magnetic":
        p["D_mag"] = float(rh.uniform(0.0, 360.0))
    elif hidden == "outside":
        p["D2_deg"] = float(rh.uniform(0.0, 180.0))
    elif hidden == "turn_on_transient":
        p["tau"] = float(rh.uniform(60.0, 300.0))
    elif hidden == "heat_source":
        places = list(HEAT_PLACES)
        p["node"] = places[int(rh.integers(len(places)))]
        p["power"] = float(np.sqrt(np.prod(HEAT_PLACES[p["node"]])))  # a start for the secant
    return p


def generate_family_set(out_dir, *, seed: int, hidden: str | None = None,
                        params: dict | None = None,
                        start_temperatures_c=START_TEMPERATURES_C, duration_s: float = 9000.0,
                        sample_rate_hz: float = 1.0, latitude_deg: float = 30.26,
                        true_heading_deg: float = 212.7) -> dict:
    """Write one run per start temperature of the unit :func:`draw_unit` (``seed``) draws.

    The hidden effect's own parameters are drawn (:func:`_hidden_params`), then ``params``
    override them; its amplitude is scaled to the draw's strength target unless ``params``
    gives it.  Returns the truth of :func:`generator.generate_set` plus ``strength``
    (``ratio``: which ratio, ``target`` (None when the amplitude was given), ``achieved``,
    ``floor``), ``family`` (:meth:`FamilyDraw.describe`), ``seed`` and ``soak_sidecar``.
    Same arguments, same bytes.
    """
    draw = draw_unit(seed)
    if hidden is not None and hidden not in g.HIDDEN_EFFECTS:
        g._check_hidden(hidden, params)       # raises with the valid names
    run_kw = dict(duration_s=duration_s, sample_rate_hz=sample_rate_hz,
                  latitude_deg=latitude_deg, true_heading_deg=true_heading_deg)
    sr = _SetRuns(draw, start_temperatures_c, run_kw)
    strength = None
    if hidden is None:
        g._check_hidden(None, params)
        p, runs = {}, sr.runs()
    else:
        p = g._check_hidden(hidden, {**_hidden_params(seed, hidden), **(params or {})})
        key = g.unabsorbed_ratio_key(hidden)
        if AMPLITUDE[hidden] in (params or {}):
            s, runs = sr.strength(hidden, p)
            target = None
        else:
            target = draw.strength_target
            p, s, runs = scale_to_strength(draw, hidden, p, target, _set_runs=sr)
        strength = {"ratio": key, "target": target, "achieved": s[key], "floor": s["floor"]}
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for i, run in enumerate(runs):
        rd = draw.run_draw(i)
        extra = ({"soak_from_c": round(rd.soak_from_c, 1), "soak_h": round(rd.soak_h, 2)}
                 if draw.sidecar else None)
        g._write_run(run, out, latitude_deg=float(latitude_deg),
                     true_heading_deg=true_heading_deg, sample_rate_hz=sample_rate_hz,
                     extra=extra, instrument="independent generator family (tests/independent)")
    truth = g._truth(hidden, p)
    truth.update(strength=strength, family=draw.describe(), seed=int(seed),
                 soak_sidecar=draw.sidecar)
    return truth
