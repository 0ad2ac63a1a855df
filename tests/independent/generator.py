"""An independent generator of north-finder start-up runs: a "truth" the nfs model is not.

It writes runs in ``nfs-measurement/1`` (``NAME.csv`` + ``NAME.toml``) made by physics built
here from NumPy and SciPy only, on purpose different in structure from the package's
simulator, so that ``nfs fit / compare / diagnose`` can be tried on runs their own model did
not make.  It hides one physical effect (or none) and returns the truth.

What it models (every value and its reason: ``README.md`` next to this file)

Thermal
    Housing/base, mounting plate, FOG electronics (light source with its TEC), main board,
    two QFA blocks, and the fibre coil as a finite-difference radial conduction model of
    ``n_layers`` cylindrical layers (spool side to outer side).  Heat enters the coil through
    both faces: the spool face from the plate, the outer face from the housing and the
    electronics, each through a contact conductance in series with the half layer.  Massless
    surface nodes are eliminated exactly (Kron reduction).  Solved exactly per sample step
    with the matrix exponential of the augmented matrix (powers held, chamber temperature
    linear over the step); the TEC's power, the only state-dependent input, is held over
    each step at its value at the step's start.
Sensors
    Thermometers on mixes of nodes (none on a single node) with first-order lag, offset,
    noise and quantisation; a FOG with the Earth-rate projection, a bias polynomial in the
    mean coil temperature, a Shupe term summed over the coil's layers with a
    quadrupole-like weight, a mean-rate term, angle random walk and a first-order
    Gauss-Markov bias; two accelerometers on a tilted table; a chamber that cycles and
    wanders; a TEC drive current and an oscillator voltage.
Power cycles
    ``power_off_s`` spans switch the unit off and on again (a warm restart): no heat inside
    while off, the unit's columns NaN and a ``powered`` column, the turn-on transient
    restarting at each switch-on (:func:`simulate_run`).

Family
    ``family.py`` next to this file draws a whole unit (structure, noise, chamber, soak and
    the hidden effect's strength) from one seed; its public names are also reached from here
    (:func:`draw_unit`, :func:`generate_family_set`, :class:`FamilyDraw`).

Run ``python tests/independent/generator.py --help``.  This module imports nothing from
``nfs`` or ``thermal``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Sequence

import numpy as np
from scipy.linalg import expm
from scipy.signal import lfilter

if __package__:
    from . import winding as wd
else:  # the folder on sys.path (benchmarks, examples, the command line)
    import winding as wd

__all__ = ["OMEGA_IE_DPH", "T_REF_C", "HIDDEN_EFFECTS", "TEC_LAWS", "BIAS_NOISE_LAWS",
           "CoilGeometry", "Unit", "Network", "RunData", "coil_network", "unit_network",
           "Stepper", "tec_power_w", "face_mixes", "shupe_node_weights", "interval_mean_rate",
           "gauss_markov", "flicker_sum", "rate_random_walk",
           "simulate_run", "generate_set", "measure_strength", "main", "POWERED_COLUMN",
           "check_power_spans", "powered_state", "time_since_switch_on_s",
           # from family.py (loaded on first use)
           "FamilyDraw", "draw_unit", "generate_family_set"]

#: Earth rotation rate Omega_ie [deg/h] (WGS-84: 7.292115e-5 rad/s).
OMEGA_IE_DPH = 15.041067
#: Reference temperature of every temperature law [degC].
T_REF_C = 25.0
_S_PER_MIN = 60.0
_POSITIONS_DEG = (0.0, 90.0, 180.0, 270.0)
_DWELL_S = 150.0
_MOVE_S = 10.0
#: The run's power-state column (1.0 on, 0.0 off), written only for runs with power cycles.
POWERED_COLUMN = "powered"
#: The unit's own columns: NaN while it is switched off (the laboratory's go on recording).
_UNIT_COLUMNS = ("gyro_dph", "acc_x_g", "acc_y_g", "temp_fog_c", "temp_acc_x_c",
                 "temp_acc_y_c", "aux_source_current_ma", "aux_osc_v")

#: hidden effect -> default parameters.  ``outside`` is the one outside the nfs library.
HIDDEN_EFFECTS: dict[str, dict] = {
    "shupe_product": {"k_p": 0.008},
    "magnetic": {"m": 0.012, "D_mag": 40.0},
    "scale_factor_temperature": {"s1": 4.0e-5},
    "turn_on_transient": {"a": 0.12, "tau": 150.0},
    "aux_linear": {"channel": "aux_osc_v", "k": 1.5, "aux_ref": 5.0},
    "acc_bias_temperature": {"axis": "x", "b_q1": 5.0e-6},
    "heat_source": {"node": "coil_spool", "power": 0.7},
    "thermometer_lag": {"thermometer": "fog", "tau": 90.0},
    "outside": {"effect": "quadrantal", "c": 0.012, "D2_deg": 15.0},
}

#: Forms of the TEC law (:func:`tec_power_w`).
TEC_LAWS = ("quadratic", "piecewise", "saturating")
#: Forms of the gyro's bias noise on top of the angle random walk (:func:`simulate_run`).
BIAS_NOISE_LAWS = ("gauss_markov", "flicker", "rate_random_walk")

#: hidden effect -> the measured column it acts on.
_CHANNEL = {"shupe_product": "gyro_dph", "magnetic": "gyro_dph",
            "scale_factor_temperature": "gyro_dph", "turn_on_transient": "gyro_dph",
            "aux_linear": "gyro_dph", "acc_bias_temperature": "acc_x_g",
            "heat_source": "temp_fog_c", "thermometer_lag": "temp_fog_c",
            "outside": "gyro_dph"}


# ---------------------------------------------------------------------------------------------
# The unit

@dataclass(frozen=True)
class CoilGeometry:
    """A potted fibre coil as a thick cylinder, cut into radial (thermal) layers."""

    inner_radius_m: float = 0.040
    """r_in, the spool side [m]."""
    outer_radius_m: float = 0.056
    """r_out [m]."""
    height_m: float = 0.028
    """h, the axial length of the winding [m]."""
    n_layers: int = 8
    """Number of finite-difference layers (>= 1)."""
    conductivity_w_per_m_k: float = 0.25
    """k, radial conductivity of fibre in potting compound [W/(m K)]."""
    heat_j_per_m3_k: float = 1.7e6
    """rho c, volumetric heat capacity of the winding [J/(m^3 K)]."""
    spacing: str = "equal"
    """Radial spacing of the thermal layers, ``equal`` or ``cosine`` (graded toward both
    faces; :func:`winding.thermal_layer_edges_m`)."""


@dataclass(frozen=True)
class Unit:
    """The instrument the generator simulates (README: every value and why)."""

    capacity_j_per_k: dict = field(default_factory=lambda: {
        "housing": 3200.0, "plate": 900.0, "electronics": 180.0, "board": 320.0,
        "qfa_x": 42.0, "qfa_y": 36.0})
    """C_j of the lumped nodes [J/K] (the coil's layers come from ``coil``)."""
    power_w: dict = field(default_factory=lambda: {
        "electronics": 2.8, "board": 6.5, "qfa_x": 0.4, "qfa_y": 0.45})
    """Constant electrical power dissipated in each node after power-on [W]."""
    links_w_per_k: tuple = (("housing", "chamber", 2.0), ("plate", "housing", 2.5),
                            ("electronics", "housing", 0.7), ("board", "housing", 0.9),
                            ("qfa_x", "plate", 0.55), ("qfa_y", "plate", 0.5))
    """(node, node, G [W/K]) between lumped nodes and the chamber."""
    coil: CoilGeometry = CoilGeometry()
    """The fibre coil."""
    winding: wd.Winding | None = None
    """How the fibre lies in the coil.  None (the fixed unit): the Shupe term is the assumed
    cosine weight over the thermal layers times ``shupe_dph_per_k_per_min``; a
    :class:`winding.Winding`: the Shupe integral over the winding (:func:`shupe_node_weights`)."""
    coil_spool_links_w_per_k: tuple = (("plate", 0.6),)
    """Contacts of the coil's spool face (through the spool hub) [W/K]."""
    coil_outer_links_w_per_k: tuple = (("housing", 0.3), ("electronics", 0.18))
    """Contacts of the coil's outer face (cover air and the electronics above it) [W/K]."""
    tec_set_c: float = 22.0
    """T_set, the TEC set point of the source assembly [degC]."""
    tec_p0_w: float = 0.3
    """p0 of the TEC law [W]."""
    tec_a_w_per_k: float = 0.012
    """a of the TEC law [W/K]."""
    tec_c_w_per_k2: float = 6.0e-4
    """c of the TEC law [W/K^2]."""
    tec_law: str = "quadratic"
    """Form of the TEC law, one of :data:`TEC_LAWS` (see :func:`tec_power_w`)."""
    tec_heat_w_per_k: float = 0.03
    """``piecewise``: c_h, the slope below the dead band (heating the source) [W/K]."""
    tec_cool_w_per_k: float = 0.07
    """``piecewise``: c_c, the slope above the dead band (cooling the source) [W/K]."""
    tec_dead_band_k: float = 1.0
    """``piecewise``: full width of the dead band about T_set [K]."""
    tec_max_w: float = 1.2
    """``saturating``: the driver's power limit P_max [W]."""
    tec_resistance_ohm: float = 2.2
    """Electrical resistance of the TEC, for its drive current [ohm]."""
    fog_thermometer: dict = field(default_factory=lambda: {
        "housing": 0.5, "plate": 0.3, "coil_outer": 0.2})
    """Weights of the FOG thermometer on the housing next to the coil mount."""
    acc_thermometers: dict = field(default_factory=lambda: {
        "x": {"qfa_x": 0.75, "plate": 0.25}, "y": {"qfa_y": 0.7, "plate": 0.3}})
    """Weights of the QFA thermometers on the QFA mounts."""
    thermometer_lag_s: dict = field(default_factory=lambda: {"fog": 25.0, "x": 18.0, "y": 20.0})
    """First-order lag of each thermometer [s]."""
    thermometer_offset_c: dict = field(default_factory=lambda: {"fog": 0.03, "x": -0.02,
                                                                "y": 0.04})
    """Constant offset of each thermometer [degC]."""
    thermometer_noise_c: float = 0.008
    """White noise of each thermometer [degC]."""
    thermometer_quantum_c: float = 0.0625
    """Quantum of each thermometer [degC]."""
    b0_dph: float = -0.012
    """FOG constant bias [deg/h]."""
    b1_dph_per_k: float = 0.0015
    """FOG bias, linear coefficient in the mean coil temperature [deg/h/K]."""
    b2_dph_per_k2: float = 8.0e-5
    """FOG bias, quadratic coefficient [deg/h/K^2]."""
    shupe_dph_per_k_per_min: float = 0.09
    """k_sh of the layer Shupe term, on the cosine weight (see :func:`shupe_weights`); unused
    when ``winding`` is given."""
    mean_rate_dph_per_k_per_min: float = 0.02
    """k_m of the mean-rate (winding imperfection) term [deg/h per K/min]."""
    arw_deg_per_rth_h: float = 0.00035
    """N, angle random walk [deg/sqrt(h)]."""
    gm_sigma_dph: float = 0.003
    """sigma of the first-order Gauss-Markov bias [deg/h]."""
    gm_tau_s: float = 400.0
    """Correlation time of the Gauss-Markov bias [s]."""
    bias_noise: str = "gauss_markov"
    """The gyro's bias noise besides ARW, one of :data:`BIAS_NOISE_LAWS`."""
    flicker_b_dph: float = 0.003
    """``flicker``: B, the bias instability coefficient of IEEE 952 [deg/h]."""
    flicker_taus_s: tuple = (2.0, 6.32, 20.0, 63.2, 200.0, 632.0, 2000.0, 6320.0, 20000.0)
    """``flicker``: correlation times of the Gauss-Markov processes summed [s], spaced by a
    constant ratio (see :func:`flicker_sum`)."""
    rrw_dph_per_rth_h: float = 0.002
    """``rate_random_walk``: K, the rate random walk [deg/h/sqrt(h)]."""
    tilt_north_deg: float = 0.025
    """alpha_N, turntable tilt towards north [deg]."""
    tilt_east_deg: float = 0.012
    """alpha_E, turntable tilt towards east [deg]."""
    acc_bias_g: tuple = (4.0e-5, -6.0e-5)
    """Constant biases of the x and y accelerometers [g]."""
    acc_noise_g_per_rth_hz: float = 20.0e-6
    """One-sided white-noise density of each accelerometer [g/sqrt(Hz)]."""
    chamber_cycle_k: float = 0.07
    """Half the peak-to-peak of the chamber controller's cycling [K]."""
    chamber_period_s: float = 840.0
    """Period of the chamber controller's cycling [s]."""
    chamber_walk_k_per_rth_s: float = 6.0e-4
    """Random walk of the chamber air temperature [K/sqrt(s)]."""
    chamber_logger_noise_c: float = 0.005
    """White noise of the chamber air thermometer [degC]; quantum 0.01 degC."""
    osc_v: float = 5.0
    """Oscillator voltage at T_ref [V]."""
    osc_gain_v_per_k: float = 0.004
    """Oscillator voltage per kelvin of the electronics [V/K]."""
    osc_walk_v_per_rth_s: float = 1.5e-4
    """Random walk of the oscillator voltage [V/sqrt(s)]."""
    osc_noise_v: float = 2.0e-4
    """White noise of the voltage measurement [V]."""
    current_noise_ma: float = 0.5
    """White noise of the TEC current measurement [mA]."""


# ---------------------------------------------------------------------------------------------
# Thermal network

@dataclass(frozen=True)
class Network:
    """A linear thermal network C dT/dt = -L T + G_b T_b + P after Kron reduction.

    ``laplacian`` is the conductance Laplacian among the nodes (including each node's links
    to the boundaries on its diagonal); ``boundary`` [W/K] holds the conductance of each node
    to each held boundary temperature (columns ``boundary_names``).
    """

    names: tuple
    """Node names."""
    capacity_j_per_k: np.ndarray
    """C_j [J/K]."""
    laplacian_w_per_k: np.ndarray
    """L [W/K], (n, n): L_jj = sum of node j's conductances, L_jk = -G_jk."""
    boundary_w_per_k: np.ndarray
    """G_jb [W/K], (n, n_boundaries)."""
    boundary_names: tuple
    """Names of the held boundary temperatures (e.g. ``chamber``)."""

    @property
    def a_per_s(self) -> np.ndarray:
        """A = -C^-1 L [1/s], the state matrix."""
        return -self.laplacian_w_per_k / self.capacity_j_per_k[:, None]

    def time_constants_s(self) -> np.ndarray:
        """-1/lambda of A's eigenvalues, longest first [s]."""
        lam = np.linalg.eigvals(self.a_per_s).real
        return np.sort(-1.0 / lam)[::-1]


def _kron_reduce(names, capacity, links, boundary_names):
    """Network from (a, b, G) links; nodes of zero capacity are eliminated exactly.

    Kron reduction (the Schur complement of the massless nodes' block of the Laplacian,
    Doerfler & Bullo 2013, IEEE TCAS-I 60(1) 150, eq. (2)): a massless node carries no heat
    of its own, so it only puts its links in series/parallel; this is the Y-Delta transform
    for a surface where several contacts meet.
    """
    every = list(names) + list(boundary_names)
    idx = {n: i for i, n in enumerate(every)}
    m = len(every)
    lap = np.zeros((m, m))
    for a, b, g in links:
        i, j = idx[a], idx[b]
        lap[i, i] += g
        lap[j, j] += g
        lap[i, j] -= g
        lap[j, i] -= g
    cap = np.asarray(capacity, dtype=float)
    keep = [i for i in range(len(names)) if cap[i] > 0] + list(range(len(names), m))
    drop = [i for i in range(len(names)) if cap[i] <= 0]
    if drop:
        lap = (lap[np.ix_(keep, keep)]
               - lap[np.ix_(keep, drop)] @ np.linalg.solve(lap[np.ix_(drop, drop)],
                                                         lap[np.ix_(drop, keep)]))
    nk = len(keep) - len(boundary_names)
    kept_names = tuple(every[i] for i in keep[:nk])
    return Network(names=kept_names, capacity_j_per_k=cap[keep[:nk]],
                   laplacian_w_per_k=lap[:nk, :nk], boundary_w_per_k=-lap[:nk, nk:],
                   boundary_names=tuple(boundary_names))


def _layer_names(n: int) -> list[str]:
    return [f"coil_{i}" for i in range(n)]


def _coil_radii(geom: CoilGeometry):
    """Edges r_0..r_n of the thermal layers and their nodes' log-mean radii [m]."""
    if geom.n_layers < 1:
        raise ValueError(f"coil n_layers must be >= 1, got {geom.n_layers}")
    if not 0 < geom.inner_radius_m < geom.outer_radius_m:
        raise ValueError("coil radii must satisfy 0 < inner_radius_m < outer_radius_m")
    r = wd.thermal_layer_edges_m(geom.inner_radius_m, geom.outer_radius_m, geom.n_layers,
                                 geom.spacing)
    return r, np.sqrt(r[:-1] * r[1:])


def _coil_parts(geom: CoilGeometry):
    """Layers of a thick cylinder: names, capacities [J/K] and conductances [W/K].

    Layer i spans [r_i, r_i+1] (``geom.spacing``: equal thickness, or graded toward both
    faces), its node sits at the log-mean radius rho_i = sqrt(r_i r_i+1);
    C_i = rho c pi (r_i+1^2 - r_i^2) h.  Between two radii the
    steady radial conductance of a cylinder is G = 2 pi k h / ln(r_b / r_a) (Incropera &
    DeWitt, Fundamentals of Heat and Mass Transfer, 6th ed., sec. 3.3.1), which makes the
    finite-difference steady state exact at the nodes.  The face nodes ``coil_in_face`` and
    ``coil_out_face`` are massless (eliminated by Kron reduction); the last two links are
    the faces' half layers.
    """
    r, rho = _coil_radii(geom)
    cap = geom.heat_j_per_m3_k * np.pi * (r[1:] ** 2 - r[:-1] ** 2) * geom.height_m
    two_pi_kh = 2.0 * np.pi * geom.conductivity_w_per_m_k * geom.height_m
    names = _layer_names(geom.n_layers)
    links = [(names[i], names[i + 1], two_pi_kh / math.log(rho[i + 1] / rho[i]))
             for i in range(geom.n_layers - 1)]
    links.append(("coil_in_face", names[0], two_pi_kh / math.log(rho[0] / r[0])))
    links.append((names[-1], "coil_out_face", two_pi_kh / math.log(r[-1] / rho[-1])))
    return names, cap, links


def face_mixes(geom: CoilGeometry, spool_links, outer_links) -> tuple[dict, dict]:
    """Each face's temperature as a mix of nodes {name: weight} (weights sum to 1).

    A massless face between its half layer G_f and its contacts G_i (S = G_f + sum G_i)
    sits at T_face = (G_f T_shell + sum_i G_i T_i) / S, the node it eliminates in the Kron
    reduction (Doerfler & Bullo 2013, eq. (2)).  ``spool_links``, ``outer_links``: the
    faces' (node, G [W/K]) contacts; the coil alone (:func:`coil_network`) names them
    ``spool`` and ``outer``.
    """
    names, _, links = _coil_parts(geom)
    out = []
    for (shell, g_f), contacts in (((names[0], links[-2][2]), spool_links),
                                   ((names[-1], links[-1][2]), outer_links)):
        s = g_f + sum(gk for _, gk in contacts)
        mix = {shell: g_f / s}
        for n, gk in contacts:
            mix[n] = mix.get(n, 0.0) + gk / s
        out.append(mix)
    return out[0], out[1]


def shupe_node_weights(geom: CoilGeometry, winding: wd.Winding, names, spool_links,
                       outer_links) -> tuple[np.ndarray, float]:
    """Weights w over the nodes ``names`` [m^2] and K [deg/h per (K/s m^2)]: the Shupe
    integral over the winding is Omega = K sum_k w_k dT_k/dt.

    The rate at each optical layer's radius is the cubic spline through the thermal points
    (the spool face, the layers' nodes at their log-mean radii, the outer face:
    :meth:`winding.Winding.point_weights_m2`); a face's rate is its mix of nodes
    (:func:`face_mixes`), so its weight goes to the nodes it is made of.
    """
    r, rho = _coil_radii(geom)
    pw = winding.point_weights_m2(r[0], r[-1], np.concatenate([[r[0]], rho, [r[-1]]]))
    idx = {n: i for i, n in enumerate(names)}
    w = np.zeros(len(names))
    for i, name in enumerate(_layer_names(geom.n_layers)):
        w[idx[name]] += pw[1 + i]
    for face_w, mix in zip((pw[0], pw[-1]), face_mixes(geom, spool_links, outer_links)):
        for n, share in mix.items():
            w[idx[n]] += face_w * share
    return w, winding.k_dph(r[0], r[-1])


def coil_network(geom: CoilGeometry, g_spool_w_per_k: float, g_outer_w_per_k: float
                 ) -> Network:
    """The coil alone, its faces linked to two held temperatures ``spool`` and ``outer``.

    For checking the finite-difference coil against closed forms (the tests).
    """
    names, cap, links = _coil_parts(geom)
    links = links + [("coil_in_face", "spool", g_spool_w_per_k),
                     ("coil_out_face", "outer", g_outer_w_per_k)]
    return _kron_reduce(names + ["coil_in_face", "coil_out_face"],
                        list(cap) + [0.0, 0.0], links, ("spool", "outer"))


def unit_network(unit: Unit) -> Network:
    """The whole unit: lumped nodes, the coil's layers, one boundary ``chamber``."""
    lumped = list(unit.capacity_j_per_k)
    names, cap, links = _coil_parts(unit.coil)
    links = list(links) + list(unit.links_w_per_k)
    links += [("coil_in_face", n, g) for n, g in unit.coil_spool_links_w_per_k]
    links += [("coil_out_face", n, g) for n, g in unit.coil_outer_links_w_per_k]
    return _kron_reduce(lumped + names + ["coil_in_face", "coil_out_face"],
                        [unit.capacity_j_per_k[n] for n in lumped] + list(cap) + [0.0, 0.0],
                        links, ("chamber",))


class Stepper:
    """Exact one-step map of C dT/dt = -L T + G_b T_b(t) + P over a step h.

    T_b linear over the step (first-order hold), P held (zero-order hold):

        T(t+h) = Phi T(t) + Gamma_b T_b(t) + Gamma_d (T_b(t+h) - T_b(t))/h + Gamma_p P(t)

    from one matrix exponential of the augmented matrix
    [[A, B_b, 0, C^-1], [0, 0, I, 0], [0, 0, 0, 0], [0, 0, 0, 0]] (Van Loan 1978, IEEE TAC
    23(3) 395, the block-triangular exponential; Franklin, Powell & Workman, Digital Control
    of Dynamic Systems, 3rd ed., ch. 6, for the zero- and first-order hold).  Computed once
    per step size.
    """

    def __init__(self, net: Network, h_s: float):
        n, nb = len(net.names), len(net.boundary_names)
        a = net.a_per_s
        bb = net.boundary_w_per_k / net.capacity_j_per_k[:, None]
        m = np.zeros((n + 2 * nb + n, n + 2 * nb + n))
        m[:n, :n] = a
        m[:n, n:n + nb] = bb
        m[n:n + nb, n + nb:n + 2 * nb] = np.eye(nb)
        m[:n, n + 2 * nb:] = np.diag(1.0 / net.capacity_j_per_k)
        e = expm(m * h_s)
        self.h_s = h_s
        self.phi = e[:n, :n]
        self.gamma_b = e[:n, n:n + nb]
        self.gamma_d = e[:n, n + nb:n + 2 * nb]
        self.gamma_p = e[:n, n + 2 * nb:]
        self.a, self.bb = a, bb
        self.inv_c = 1.0 / net.capacity_j_per_k

    def boundary_terms(self, boundary_c: np.ndarray) -> np.ndarray:
        """Gamma_b T_b,k + Gamma_d (T_b,k+1 - T_b,k)/h for every step, shape (n_steps, n)."""
        tb = np.atleast_2d(np.asarray(boundary_c, dtype=float).T).T
        slope = np.diff(tb, axis=0) / self.h_s
        return tb[:-1] @ self.gamma_b.T + slope @ self.gamma_d.T

    def rate(self, temp_c: np.ndarray, boundary_c: np.ndarray, power_w: np.ndarray
             ) -> np.ndarray:
        """dT/dt = A T + B_b T_b + C^-1 P at each sample [K/s] (rows are samples)."""
        tb = np.atleast_2d(np.asarray(boundary_c, dtype=float).T).T
        return temp_c @ self.a.T + tb @ self.bb.T + power_w * self.inv_c


def tec_power_w(unit: Unit, t_src_c):
    """TEC power P_tec = p0 + a (T_src - T_set) + c (T_src - T_set)^2 [W].

    A smooth law for a Peltier element holding the source at T_set against the temperature
    T_src of its heat sink (the source assembly): the Peltier term is linear in the
    temperature difference and the Joule term grows with its square, so a quadratic is the
    first-order shape of the input power; its minimum sits a little below the set point, at
    T_set - a/(2c), where the source's own heat leaks to the colder sink unaided.  The
    module equations (Q_c = alpha I T_c - I^2 R / 2 - K dT, P = alpha I dT + I^2 R; Rowe
    (ed.), CRC Handbook of Thermoelectrics, 1995) motivate the shape; the quadratic itself
    is an assumed smooth fit, not derived from a module.  p0 [W], a [W/K], c [W/K^2] (README).

    ``unit.tec_law`` selects the form (the quadratic above is ``quadratic``):

    ``piecewise``
        P_tec = p0 + c_h max(0, T_set - w/2 - T_src) + c_c max(0, T_src - T_set - w/2): a
        heater/cooler controller that idles at p0 inside a dead band of full width w and
        pumps heat with a slope of its own on each side (a Peltier element heats more
        efficiently than it cools, its Joule heat helping one way and opposing the other:
        Rowe (ed.), CRC Handbook of Thermoelectrics, 1995, ch. 54); c_h, c_c [W/K], w [K].
    ``saturating``
        P_tec = min(quadratic, P_max): the same law, clipped at the driver's current limit
        (P_max = I_max^2 R, the drive current cannot rise further) [W].
    """
    d = np.asarray(t_src_c, dtype=float) - unit.tec_set_c
    law = unit.tec_law
    if law == "piecewise":
        half = 0.5 * unit.tec_dead_band_k
        return (unit.tec_p0_w + unit.tec_heat_w_per_k * np.maximum(0.0, -d - half)
                + unit.tec_cool_w_per_k * np.maximum(0.0, d - half))
    if law not in ("quadratic", "saturating"):
        raise ValueError(f"unknown TEC law {law!r}; valid: {', '.join(TEC_LAWS)}")
    p = unit.tec_p0_w + unit.tec_a_w_per_k * d + unit.tec_c_w_per_k2 * d * d
    return np.minimum(p, unit.tec_max_w) if law == "saturating" else p


# ---------------------------------------------------------------------------------------------
# Sensors

def interval_mean_rate(y: np.ndarray, y_end: float, h_s: float) -> np.ndarray:
    """(y_k+1 - y_k) / h: the mean of dy/dt over each sample's interval [t_k, t_k + h).

    A FOG's sample is the phase it accumulated over its sample period, the mean rate over
    that interval, not the rate at an instant: IEEE Std 952-1997 (annex C) reduces the
    output as angle, theta(t) = int Omega dt, a rate sample being the increment over one
    period divided by it; a closed-loop FOG's digital ramp reads out that increment
    (Lefevre, The Fiber-Optic Gyroscope, 2nd ed., 2014, ch. 5; the section not checked).
    For a linear functional of the node temperatures the interval mean is exact from the
    stepped states.  It matters for the Shupe integral over a winding: at power-on the heat
    flux through a face steps, the gradient at the face follows within the thin face
    layers' time constants (under a second when fine, seconds when coarse), and a rate taken
    at the instants weighs that spike by where it falls between samples.  Measured
    (``test_winding.py``'s coils, with the electronics pressed on the outer face at 0.08-0.35
    W/K, before the contacts' calibration): the dwell means' RMS moved by 2.5-3.6 % between
    8 and 16 thermal layers with the instants, by -0.4 to -0.6 % with the interval means.
    ``y``: the values at the samples, ``y_end``: one step past the last [unit]; ``h_s``: the
    step [s].
    """
    return np.diff(np.append(np.asarray(y, dtype=float), y_end)) / h_s


def first_order_lag(x: np.ndarray, h_s: float, tau_s: float) -> np.ndarray:
    """tau dy/dt = x - y, exact for x linear between samples (first-order hold), y_0 = x_0.

    y_k+1 = a y_k + (1 - c) x_k+1 + (c - a) x_k with a = exp(-h/tau), c = tau (1 - a)/h
    (the first-order-hold equivalent, Franklin, Powell & Workman, ch. 6).
    """
    x = np.asarray(x, dtype=float)
    if tau_s <= 0:
        return x.copy()
    a = math.exp(-h_s / tau_s)
    c = tau_s * (1.0 - a) / h_s
    b = [1.0 - c, c - a]
    y, _ = lfilter(b, [1.0, -a], x[1:], zi=[a * x[0] + (c - a) * x[0]])
    return np.concatenate([x[:1], y])


def shupe_weights(n_layers: int) -> np.ndarray:
    """w_i = cos(pi (i + 1/2) / n): the layer weight of the Shupe term, spool side first.

    The Shupe phase is proportional to the integral over the fibre of dT/dt(z, t) (2z - L)
    (Shupe 1980, Appl. Opt. 19(5) 654, eq. (5)); a quadrupole winding pairs layers from the
    two halves so that a uniform heating rate cancels (sum w_i = 0 exactly) and what remains
    weights the inner layers against the outer ones (Mohr 1996, J. Lightwave Technol. 14(1)
    27, fig. 3).  The cosine profile is an assumed smooth shape, not derived from a winding.
    """
    return np.cos(np.pi * (np.arange(n_layers) + 0.5) / n_layers)


def gauss_markov(rng: np.random.Generator, n: int, h_s: float, sigma: float, tau_s: float
                 ) -> np.ndarray:
    """First-order Gauss-Markov process, stationary from the first sample [unit of sigma].

    b_k+1 = phi b_k + sigma sqrt(1 - phi^2) w_k, phi = exp(-h/tau), b_0 ~ N(0, sigma^2): the
    exact discretisation of db/dt = -b/tau + white noise, autocorrelation sigma^2
    exp(-|t|/tau) (Brown & Hwang, Introduction to Random Signals and Applied Kalman
    Filtering, 4th ed., sec. 2.9 and 3.9); sigma [deg/h], tau [s].
    """
    phi = math.exp(-h_s / tau_s)
    w = rng.standard_normal(n)
    w[0] /= math.sqrt(1.0 - phi ** 2)        # start in the stationary distribution
    return sigma * math.sqrt(1.0 - phi ** 2) * lfilter([1.0], [1.0, -phi], w)


def flicker_sum(rng: np.random.Generator, n: int, h_s: float, b_dph: float, taus_s
                ) -> np.ndarray:
    """Flicker (1/f) bias as a sum of Gauss-Markov processes with log-spaced times [deg/h].

    A process of variance sigma^2 and correlation time tau has the two-sided spectrum
    S(f) = 2 sigma^2 tau / (1 + (2 pi f tau)^2); summed over tau_i = tau_0 r^i with equal
    sigma^2 it is (2 sigma^2 / (2 pi f)) sum x_i / (1 + x_i^2), x_i = 2 pi f tau_i, which
    for a dense log grid is (2 sigma^2 / (2 pi f ln r)) int_0^inf dx / (1 + x^2) = sigma^2 /
    (2 f ln r) between 1/(2 pi tau_max) and 1/(2 pi tau_min) (Keshner, Proc. IEEE 70(3) 212,
    1982, sec. III: 1/f noise as a superposition of relaxation processes).  Flicker rate
    noise of bias instability B has S(f) = B^2 / (2 pi f) in the same two-sided convention
    as white rate noise S = N^2 (IEEE Std 952-1997, annex C, table C.1), so sigma^2 = B^2
    ln r / pi, and its Allan deviation is flat at B sqrt(2 ln 2 / pi) = 0.664 B for
    averaging times well inside [tau_min, tau_max] (tested).
    ``taus_s`` must be (nearly) geometric; r is taken from its first and last value.
    """
    taus = np.asarray(taus_s, dtype=float)
    if taus.size < 2 or np.any(np.diff(taus) <= 0):
        raise ValueError("flicker_sum needs at least two increasing correlation times")
    ln_r = math.log(taus[-1] / taus[0]) / (taus.size - 1)
    sigma = b_dph * math.sqrt(ln_r / math.pi)
    return sum(gauss_markov(rng, n, h_s, sigma, float(tau)) for tau in taus)


def rate_random_walk(rng: np.random.Generator, n: int, h_s: float, k_dph_per_rth_h: float
                     ) -> np.ndarray:
    """Rate random walk from b_0 = 0 [deg/h]: b_k+1 = b_k + K sqrt(h / 3600) w_k.

    Integrated white rate acceleration of density K [deg/h/sqrt(h)]; its Allan deviation is
    K sqrt(tau / 3) with tau in hours (IEEE Std 952-1997, annex C, table C.1).
    """
    step = k_dph_per_rth_h * math.sqrt(h_s / 3600.0)
    return step * np.concatenate([[0.0], np.cumsum(rng.standard_normal(n - 1))])


def _turntable(time_s: np.ndarray, dwell_s: float = _DWELL_S, move_s: float = _MOVE_S):
    """theta(t) [deg] and moving: 4 positions, dwell 150 s, move 10 s (rewinding 270 -> 0)
    unless told otherwise."""
    step = dwell_s + move_s
    k = np.floor(time_s / step).astype(np.int64)
    tau = time_s - k * step
    pos = np.asarray(_POSITIONS_DEG)
    start, end = pos[k % 4], pos[(k + 1) % 4]
    moving = tau >= dwell_s
    frac = np.where(moving, (tau - dwell_s) / (move_s if move_s > 0 else 1.0), 0.0)
    return start + frac * (end - start), moving


def _chamber(unit: Unit, t0_c: float, time_s: np.ndarray, rng: np.random.Generator):
    """T_amb(t) = T0 + A tri(t/P + phi) + W(t): controller cycling plus a slow random walk.

    A bang-bang chamber controller cycles in a triangle of half-amplitude A and period P;
    W is a random walk of increments N(0, q^2 h) from W(0) = 0 (unit: README).
    """
    h = time_s[1] - time_s[0] if time_s.size > 1 else 1.0
    phase = rng.uniform()
    x = np.mod(time_s / unit.chamber_period_s + phase, 1.0)
    tri = 4.0 * np.abs(x - 0.5) - 1.0
    walk = np.concatenate([[0.0], np.cumsum(rng.standard_normal(time_s.size - 1))])
    return t0_c + unit.chamber_cycle_k * tri + unit.chamber_walk_k_per_rth_s * math.sqrt(h) * walk


def _thermometer(true_c, h, tau, offset, unit: Unit, rng, extra_tau_s: float = 0.0):
    """Reading = Q(lag(lag_extra(x)) + offset + noise), Q rounds to the quantum [degC]."""
    y = first_order_lag(first_order_lag(true_c, h, tau), h, extra_tau_s)
    clean = y + offset
    y = clean + unit.thermometer_noise_c * rng.standard_normal(y.shape)
    q = unit.thermometer_quantum_c
    return q * np.round(y / q), clean


# ---------------------------------------------------------------------------------------------
# One run

@dataclass(frozen=True)
class RunData:
    """One generated run, with every intermediate."""

    name: str
    """Stem of the files."""
    start_temperature_c: float
    """T0 [degC]."""
    columns: dict
    """The measured columns, as written."""
    node_names: tuple
    """Names of the thermal nodes."""
    temperature_c: np.ndarray
    """Node temperatures (n_samples, n_nodes) [degC]."""
    rate_c_per_s: np.ndarray
    """Node temperature rates (n_samples, n_nodes) [K/s]."""
    power_w: np.ndarray
    """Node powers (n_samples, n_nodes) [W], TEC and hidden heat included."""
    chamber_c: np.ndarray
    """True chamber air temperature [degC]."""
    gyro_terms_dph: dict
    """Each part of the gyro output [deg/h]: earth, bias, shupe_layers, mean_rate, hidden,
    arw, and the bias noise under its law's name (gauss_markov, flicker or
    rate_random_walk; :data:`GYRO_NOISE_TERMS`)."""
    acc_terms_g: dict
    """Parts of each accelerometer output [g] (``x_hidden``, ``x_noise``, ...)."""
    clean: dict
    """Noise-free versions of the thermometers (before noise and quantum) and aux columns."""
    dwell_s: float = _DWELL_S
    """Time at each turntable position [s] (the sidecar's ``dwell_s``)."""
    move_s: float = _MOVE_S
    """Time of each move [s] (the sidecar's ``move_s``)."""

    def node(self, name: str) -> np.ndarray:
        """Temperature of one node [degC]."""
        return self.temperature_c[:, self.node_names.index(name)]


def _run_name(i: int, t0_c: float) -> str:
    sign = "m" if t0_c < 0 else "p"
    return f"indep_{i:02d}_{sign}{abs(t0_c):05.1f}C".replace(".", "d")


def _check_hidden(hidden: str | None, params: dict | None) -> dict:
    if hidden is None:
        if params:
            raise ValueError("params given without a hidden effect")
        return {}
    if hidden not in HIDDEN_EFFECTS:
        raise ValueError(f"unknown hidden effect {hidden!r}; valid: "
                         + ", ".join(sorted(HIDDEN_EFFECTS)) + " (or None)")
    p = dict(HIDDEN_EFFECTS[hidden])
    unknown = set(params or {}) - set(p)
    if unknown:
        raise ValueError(f"hidden effect {hidden!r} has no parameter(s) "
                         f"{', '.join(sorted(unknown))}; valid: {', '.join(sorted(p))}")
    p.update(params or {})
    return p


#: Names of the gyro's noise terms in :attr:`RunData.gyro_terms_dph`.
GYRO_NOISE_TERMS = ("arw",) + BIAS_NOISE_LAWS

_STREAMS = ("arw", "gauss_markov", "acc_x", "acc_y", "therm_fog", "therm_x", "therm_y",
            "chamber", "osc", "current")


def check_power_spans(spans) -> tuple[tuple[float, float], ...]:
    """The power cycles as a tuple of (switched off, switched on again) [s from power-on];
    ValueError unless each has 0 < t_off < t_on, finite, in time order, none overlapping."""
    out = []
    for span in spans:
        try:
            t_off, t_on = (float(v) for v in span)
        except (TypeError, ValueError):
            raise ValueError(f"power_off_s: each span is (switched off, switched on) in s, "
                             f"got {span!r}") from None
        if not (math.isfinite(t_off) and math.isfinite(t_on) and 0.0 < t_off < t_on):
            raise ValueError(f"power_off_s: a span needs 0 < switched off < switched on "
                             f"(finite, s from power-on), got {span!r}")
        if out and t_off < out[-1][1]:
            raise ValueError(f"power_off_s: spans must be in time order without overlap, "
                             f"got {out[-1]!r} then {span!r}")
        out.append((t_off, t_on))
    return tuple(out)


def powered_state(time_s: np.ndarray, spans) -> np.ndarray:
    """s(t_k) as floats: 0.0 where t_off <= t_k < t_on for a span, 1.0 elsewhere.

    The switch is seen on the sample grid: the heat of the step [t_k, t_k+1) is released
    when s(t_k) is 1 (held over the step, like every power here)."""
    t = np.asarray(time_s, dtype=float)
    s = np.ones(t.shape)
    for t_off, t_on in spans:
        s[(t >= t_off) & (t < t_on)] = 0.0
    return s


def time_since_switch_on_s(time_s: np.ndarray, spans) -> np.ndarray:
    """t - t_k with t_k the latest switch-on at or before t: 0 (power-on) or a span's end
    [s].  The physical clock of every turn-on effect: a warm restart starts it again.  A
    switch-on between two samples gives the first sample after it t - t_on in [0, h)."""
    t = np.asarray(time_s, dtype=float)
    last = np.zeros(t.shape)
    for _, t_on in spans:
        last = np.where(t >= t_on, t_on, last)
    return t - last


def simulate_run(start_temperature_c: float, *, hidden: str | None = None,
                 params: dict | None = None, seed: int = 0, run_index: int = 0,
                 duration_s: float = 9000.0, sample_rate_hz: float = 1.0,
                 latitude_deg: float = 30.26, true_heading_deg: float = 212.7,
                 unit: Unit | None = None, noise: bool = True,
                 chamber_c: np.ndarray | None = None, initial_c: np.ndarray | None = None,
                 power_off_s: Sequence[tuple[float, float]] = (),
                 dwell_s: float = _DWELL_S, move_s: float = _MOVE_S) -> RunData:
    """Generate one start-up run at T0 = ``start_temperature_c`` [degC].

    The unit is soaked at T0 (every node at T0) and powered on at t = 0.  Random streams:
    ``SeedSequence((seed, run_index))`` spawned per sensor, so a hidden effect never
    changes another sensor's draws.  ``noise=False`` zeroes every random draw (for checks).

    ``chamber_c`` (one value per sample [degC]) replaces the chamber air process (kept as
    given, noise or not), ``initial_c`` (one value per node of :func:`unit_network` [degC])
    the soaked start: the family's unfinished soak (``family.py``) passes both.  A chamber
    ramp (or any chamber program) is a ``chamber_c`` too.

    ``power_off_s``: power cycles (warm restarts), each a span (switched off, switched on
    again) [s from power-on], 0 < t_off < t_on, in time order (:func:`check_power_spans`).
    While off (:func:`powered_state`) nothing is released inside the unit: the node powers,
    a hidden heat source and the TEC law are zero, and the network relaxes towards the
    chamber air, which goes on driving it; the unit's own columns (gyro, accelerometers,
    the three thermometers, the aux columns) are NaN, the chamber, time and turntable go on,
    and the run gets the column ``powered`` (1.0 on, 0.0 off; only when spans are given, so
    a run without them is the same bytes as before).  Turn-on effects restart at every
    switch-on: the hidden ``turn_on_transient`` is a exp(-t_on / tau) in the time since the
    latest switch-on (:func:`time_since_switch_on_s`), and is zero while off.  The gyro's
    and the other sensors' noise processes, the oscillator's random walk and the
    thermometers' own lags go on through the off time (the sensing elements are bodies
    that follow their mounts whether read or not); :attr:`RunData.gyro_terms_dph` and
    ``clean`` hold the terms at every sample.

    ``dwell_s``, ``move_s``: the turntable's schedule (default 150 s at each position, 10 s
    to move), written to the sidecar.
    """
    unit = Unit() if unit is None else unit
    p = _check_hidden(hidden, params)
    if sample_rate_hz <= 0 or duration_s * sample_rate_hz < 2:
        raise ValueError("need sample_rate_hz > 0 and at least two samples")
    spans = check_power_spans(power_off_s)
    if not (dwell_s > 0 and move_s >= 0):
        raise ValueError(f"need dwell_s > 0 and move_s >= 0, got {dwell_s!r}, {move_s!r}")
    h = 1.0 / sample_rate_hz
    n = int(round(duration_s * sample_rate_hz))
    t = np.arange(n) * h
    on = powered_state(t, spans)         # all 1.0 without spans: every product below exact
    t_on = time_since_switch_on_s(t, spans)
    rngs = dict(zip(_STREAMS, (np.random.default_rng(s) for s in
                               np.random.SeedSequence([seed, run_index]).spawn(len(_STREAMS)))))
    gain = 1.0 if noise else 0.0

    # 1. thermal: exact steps, the TEC law held over each step
    net = unit_network(unit)
    names = net.names
    idx = {nm: i for i, nm in enumerate(names)}
    n_layers = unit.coil.n_layers
    layers = [idx[nm] for nm in _layer_names(n_layers)]
    node_alias = {"coil_spool": names[layers[0]], "coil_outer": names[layers[-1]]}
    base_p = np.zeros(len(names))
    for nm, pw in unit.power_w.items():
        base_p[idx[nm]] += pw
    if hidden == "heat_source":
        target = node_alias.get(p["node"], p["node"])
        if target not in idx:
            raise ValueError(f"heat_source node {p['node']!r} unknown; valid: "
                             + ", ".join(sorted(set(names) | set(node_alias))))
        base_p[idx[target]] += p["power"]
    if chamber_c is not None:
        chamber = np.asarray(chamber_c, dtype=float)
        if chamber.shape != (n,):
            raise ValueError(f"chamber_c needs {n} samples, got shape {chamber.shape}")
    else:
        chamber = _chamber(unit, start_temperature_c, t, rngs["chamber"])
        if not noise:
            chamber = np.full(n, float(start_temperature_c))
    st = Stepper(net, h)
    # the constant powers of the step [t_k, t_k+1) gated by s(t_k); the chamber goes on
    drive = st.boundary_terms(chamber[:, None]) + np.outer(on[:-1], st.gamma_p @ base_p)
    g_e = st.gamma_p[:, idx["electronics"]]
    phi = st.phi
    temp = np.empty((n, len(names)))
    if initial_c is None:
        x = np.full(len(names), float(start_temperature_c))
    else:
        x = np.array(initial_c, dtype=float)
        if x.shape != (len(names),):
            raise ValueError(f"initial_c needs {len(names)} node temperatures, got shape "
                             f"{x.shape}")
    p_tec = np.empty(n)
    ie = idx["electronics"]
    # A plain loop: the TEC power depends on the state, so the steps are sequential.
    for k in range(n):
        temp[k] = x
        p_tec[k] = tec_power_w(unit, x[ie]) * on[k]
        if k + 1 < n:
            x = phi @ x + drive[k] + g_e * p_tec[k]
    power = on[:, None] * base_p
    power[:, ie] += p_tec
    rate = st.rate(temp, chamber[:, None], power)
    # one step past the last sample (the air held, the last sample's powers): the end of
    # the last sample's interval, for the interval means of the Shupe integral below
    x_end = (phi @ x + st.gamma_b @ chamber[-1:] + on[-1] * (st.gamma_p @ base_p)
             + g_e * p_tec[-1])

    cap = net.capacity_j_per_k[layers]
    t_coil = temp[:, layers] @ cap / cap.sum()
    r_coil = rate[:, layers] @ cap / cap.sum()
    t_src = temp[:, ie]

    # 2. turntable and axis geometry
    theta, moving = _turntable(t, float(dwell_s), float(move_s))
    az = np.radians(true_heading_deg + theta)
    elev_x = unit.tilt_north_deg * np.cos(az) + unit.tilt_east_deg * np.sin(az)
    az_y = az + np.pi / 2
    elev_y = unit.tilt_north_deg * np.cos(az_y) + unit.tilt_east_deg * np.sin(az_y)
    lat = math.radians(latitude_deg)
    ex = np.radians(elev_x)
    earth = OMEGA_IE_DPH * (math.cos(lat) * np.cos(az) * np.cos(ex) + math.sin(lat) * np.sin(ex))

    # 3. aux channels
    osc_walk = gain * unit.osc_walk_v_per_rth_s * math.sqrt(h) * np.concatenate(
        [[0.0], np.cumsum(rngs["osc"].standard_normal(n - 1))])
    osc_true = unit.osc_v + unit.osc_gain_v_per_k * (t_src - T_REF_C) + osc_walk
    osc = osc_true + gain * unit.osc_noise_v * rngs["osc"].standard_normal(n)
    current_true = 1000.0 * np.sqrt(np.maximum(p_tec, 0.0) / unit.tec_resistance_ohm)
    current = current_true + gain * unit.current_noise_ma * rngs["current"].standard_normal(n)

    # 4. gyro
    dtc = t_coil - T_REF_C
    # the fixed unit's cosine weight on the rates at the instants (its bytes kept; its weights
    # do not single out a face); a winding's integral as the gyro's interval means
    if unit.winding is None:
        shupe = unit.shupe_dph_per_k_per_min * _S_PER_MIN * (rate[:, layers]
                                                            @ shupe_weights(n_layers))
    else:
        w_sh, k_sh = shupe_node_weights(unit.coil, unit.winding, names,
                                        unit.coil_spool_links_w_per_k,
                                        unit.coil_outer_links_w_per_k)
        shupe = k_sh * interval_mean_rate(temp @ w_sh, float(x_end @ w_sh), h)
    terms = {
        "earth": earth,
        "bias": unit.b0_dph + unit.b1_dph_per_k * dtc + unit.b2_dph_per_k2 * dtc * dtc,
        "shupe_layers": shupe,
        "mean_rate": unit.mean_rate_dph_per_k_per_min * _S_PER_MIN * r_coil,
    }
    a_deg = np.degrees(az)
    hid = np.zeros(n)
    if hidden == "shupe_product":
        hid = p["k_p"] * dtc * _S_PER_MIN * r_coil
    elif hidden == "magnetic":
        hid = p["m"] * np.cos(np.radians(a_deg - p["D_mag"]))
    elif hidden == "scale_factor_temperature":
        hid = earth * p["s1"] * (t_src - T_REF_C)
    elif hidden == "turn_on_transient":
        if p["tau"] <= 0:
            raise ValueError("turn_on_transient tau must be > 0 s")
        hid = p["a"] * np.exp(-t_on / p["tau"]) * on
    elif hidden == "aux_linear":
        if p["channel"] != "aux_osc_v":
            raise ValueError("aux_linear acts on aux_osc_v only in this generator")
        hid = p["k"] * (osc_true - p["aux_ref"])
    elif hidden == "outside":
        if p["effect"] != "quadrantal":
            raise ValueError("the outside effect is 'quadrantal'")
        hid = p["c"] * np.cos(2.0 * np.radians(a_deg - p["D2_deg"]))
    terms["hidden"] = hid
    terms["arw"] = gain * unit.arw_deg_per_rth_h * 60.0 * math.sqrt(sample_rate_hz) \
        * rngs["arw"].standard_normal(n)
    rng_b = rngs["gauss_markov"]              # the bias noise's stream, whatever its law
    if unit.bias_noise == "gauss_markov":
        terms["gauss_markov"] = gain * gauss_markov(rng_b, n, h, unit.gm_sigma_dph,
                                                    unit.gm_tau_s)
    elif unit.bias_noise == "flicker":
        terms["flicker"] = gain * flicker_sum(rng_b, n, h, unit.flicker_b_dph,
                                              unit.flicker_taus_s)
    elif unit.bias_noise == "rate_random_walk":
        terms["rate_random_walk"] = gain * rate_random_walk(rng_b, n, h, unit.rrw_dph_per_rth_h)
    else:
        raise ValueError(f"unknown bias noise {unit.bias_noise!r}; valid: "
                         + ", ".join(BIAS_NOISE_LAWS))
    gyro = sum(terms.values())

    # 5. accelerometers
    acc, acc_terms = {}, {}
    dens = unit.acc_noise_g_per_rth_hz * math.sqrt(sample_rate_hz / 2.0)
    for axis, elev, bias in (("x", elev_x, unit.acc_bias_g[0]), ("y", elev_y, unit.acc_bias_g[1])):
        hid_a = np.zeros(n)
        if hidden == "acc_bias_temperature" and p["axis"] == axis:
            hid_a = p["b_q1"] * (temp[:, idx[f"qfa_{axis}"]] - T_REF_C)
        elif hidden == "acc_bias_temperature" and p["axis"] not in ("x", "y"):
            raise ValueError("acc_bias_temperature axis must be 'x' or 'y'")
        nz = gain * dens * rngs[f"acc_{axis}"].standard_normal(n)
        acc_terms[f"{axis}_hidden"], acc_terms[f"{axis}_noise"] = hid_a, nz
        acc[axis] = np.sin(np.radians(elev)) + bias + hid_a + nz

    # 6. thermometers
    def mix(weights):
        col = {**idx, **{k: idx[v] for k, v in node_alias.items()}}
        return sum(wt * temp[:, col[nm]] for nm, wt in weights.items())

    extra = p["tau"] if hidden == "thermometer_lag" else 0.0
    if hidden == "thermometer_lag" and p["thermometer"] != "fog":
        raise ValueError("thermometer_lag acts on the 'fog' thermometer in this generator")
    u = replace(unit, thermometer_noise_c=unit.thermometer_noise_c * gain)
    fog, fog_clean = _thermometer(mix(unit.fog_thermometer), h, unit.thermometer_lag_s["fog"],
                                  unit.thermometer_offset_c["fog"], u, rngs["therm_fog"], extra)
    tq = {}
    clean = {"temp_fog_c": fog_clean, "aux_osc_v": osc_true, "aux_source_current_ma": current_true}
    for axis in ("x", "y"):
        tq[axis], clean[f"temp_acc_{axis}_c"] = _thermometer(
            mix(unit.acc_thermometers[axis]), h, unit.thermometer_lag_s[axis],
            unit.thermometer_offset_c[axis], u, rngs[f"therm_{axis}"])
    logged = chamber + gain * unit.chamber_logger_noise_c * rngs["chamber"].standard_normal(n)

    columns = {"time_s": t, "position_deg": theta, "moving": moving.astype(float),
               "gyro_dph": gyro, "acc_x_g": acc["x"], "acc_y_g": acc["y"],
               "temp_fog_c": fog, "temp_acc_x_c": tq["x"], "temp_acc_y_c": tq["y"],
               "temp_chamber_c": 0.01 * np.round(logged / 0.01),
               "aux_source_current_ma": current, "aux_osc_v": osc}
    if spans:
        off = on < 0.5
        for c in _UNIT_COLUMNS:
            columns[c] = np.where(off, np.nan, columns[c])
        columns[POWERED_COLUMN] = on.copy()
    return RunData(name=_run_name(run_index, start_temperature_c),
                   start_temperature_c=float(start_temperature_c), columns=columns,
                   node_names=names, temperature_c=temp, rate_c_per_s=rate, power_w=power,
                   chamber_c=chamber, gyro_terms_dph=terms, acc_terms_g=acc_terms, clean=clean,
                   dwell_s=float(dwell_s), move_s=float(move_s))


# ---------------------------------------------------------------------------------------------
# Files

_FORMATS = {"time_s": "%.10g", "position_deg": "%.10g", "moving": "%d", "gyro_dph": "%.9g",
            "acc_x_g": "%.9g", "acc_y_g": "%.9g", "temp_fog_c": "%.4f",
            "temp_acc_x_c": "%.4f", "temp_acc_y_c": "%.4f", "temp_chamber_c": "%.2f",
            "aux_source_current_ma": "%.6g", "aux_osc_v": "%.8g"}


def _write_run(run: RunData, out_dir: Path, *, latitude_deg: float, true_heading_deg: float,
               sample_rate_hz: float, extra: dict | None = None,
               instrument: str = "independent generator (tests/independent)") -> None:
    """NAME.csv (one header row, %-formatted rows) and NAME.toml, written by hand.

    ``extra``: further sidecar keys (numbers), e.g. the soak history ``soak_from_c`` [degC]
    and ``soak_h`` [h].  A run with power cycles also writes its ``powered`` column (last);
    the unit's columns hold ``nan`` while it is off (the format's missing sample)."""
    cols = list(_FORMATS)
    formats = dict(_FORMATS)
    if POWERED_COLUMN in run.columns:
        cols.append(POWERED_COLUMN)
        formats[POWERED_COLUMN] = "%d"
    data = np.column_stack([run.columns[c] for c in cols])
    fmt = ",".join(formats[c] for c in cols)
    # "%d" needs integers; moving and powered are 0.0/1.0, exact.
    lines = [",".join(cols)] + [fmt % tuple(row) for row in data.tolist()]
    (out_dir / f"{run.name}.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    toml = (
        'format = "nfs-measurement/1"\n'
        f"latitude_deg = {latitude_deg!r}\n"
        f"start_temperature_c = {run.start_temperature_c!r}\n"
        f"true_heading_deg = {float(true_heading_deg)!r}\n"
        f"sample_rate_hz = {float(sample_rate_hz)!r}\n"
        f"positions_deg = [{', '.join(repr(p) for p in _POSITIONS_DEG)}]\n"
        f"dwell_s = {float(run.dwell_s)!r}\n"
        f"move_s = {float(run.move_s)!r}\n"
        f'instrument = "{instrument}"\n'
        + "".join(f"{k} = {float(v)!r}\n" for k, v in (extra or {}).items()))
    (out_dir / f"{run.name}.toml").write_text(toml, encoding="utf-8")


def _truth(hidden: str | None, p: dict) -> dict:
    if hidden is None:
        return {"hidden": None, "target": None, "channel": None, "params": {}}
    target = {"aux_linear": p.get("channel"), "acc_bias_temperature": p.get("axis"),
              "heat_source": p.get("node"),
              "thermometer_lag": p.get("thermometer")}.get(hidden)
    return {"hidden": hidden, "target": target, "channel": _CHANNEL[hidden], "params": p}


def generate_set(out_dir, *, hidden: str | None = None, seed: int = 0,
                 start_temperatures_c=(-32.0, -16.0, -5.0, 17.0, 28.0, 43.0, 54.0),
                 duration_s=9000.0, sample_rate_hz=1.0, latitude_deg=30.26,
                 true_heading_deg=212.7, params: dict | None = None) -> dict:
    """Write one run per start temperature into out_dir; return the truth.

    Returns ``{"hidden": name or None, "target": node/axis/channel/thermometer or None,
    "channel": the measured column it acts on, "params": {...}}``.  Same arguments, same
    bytes.
    """
    p = _check_hidden(hidden, params)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for i, t0 in enumerate(start_temperatures_c):
        run = simulate_run(float(t0), hidden=hidden, params=params, seed=seed, run_index=i,
                           duration_s=duration_s, sample_rate_hz=sample_rate_hz,
                           latitude_deg=latitude_deg, true_heading_deg=true_heading_deg)
        _write_run(run, out, latitude_deg=float(latitude_deg),
                   true_heading_deg=true_heading_deg, sample_rate_hz=sample_rate_hz)
    return _truth(hidden, p)


# ---------------------------------------------------------------------------------------------
# Strength of a hidden effect against its channel's noise floor

def _window_means(x: np.ndarray, moving: np.ndarray, n_win: int) -> np.ndarray:
    """Means of consecutive windows of n_win samples that hold no moving sample."""
    m = (len(x) // n_win) * n_win
    xw = x[:m].reshape(-1, n_win)
    ok = ~moving[:m].reshape(-1, n_win).any(axis=1)
    return xw[ok].mean(axis=1)


def unabsorbed_ratio_key(hidden: str) -> str:
    """The ratio of :func:`measure_strength` that counts what a fitted model cannot take up:
    ``ratio_after_rescale`` on a thermometer, ``ratio_detrended`` on the gyro or an
    accelerometer."""
    return "ratio_after_rescale" if _CHANNEL[hidden].startswith("temp_") else "ratio_detrended"


def _after_rescale(d: np.ndarray, rise: np.ndarray) -> np.ndarray:
    """d minus its least-squares fit on [1, rise]: what another power or conductance cannot
    take up of a thermometer's change d."""
    basis = np.column_stack([np.ones_like(rise), rise])
    coef, *_ = np.linalg.lstsq(basis, d, rcond=None)
    return d - basis @ coef


def strength_of_runs(hidden: str, params: dict, pairs, sample_rate_hz: float = 1.0) -> dict:
    """:func:`measure_strength` of given runs: ``pairs`` yields (with the effect, without it)
    per run; ``without`` is used on a thermometer channel only (may be None otherwise).
    Samples of a run with power cycles taken while the unit was off do not count."""
    channel = _CHANNEL[hidden]
    n_win = max(1, int(round(10.0 * sample_rate_hz)))
    ex, ex_d, fl = [], [], []
    for with_, without in pairs:
        mv = with_.columns["moving"] > 0.5
        if POWERED_COLUMN in with_.columns:
            mv = mv | (with_.columns[POWERED_COLUMN] < 0.5)
        if channel == "gyro_dph":
            term = with_.gyro_terms_dph["hidden"]
            noise = sum(with_.gyro_terms_dph[k] for k in GYRO_NOISE_TERMS
                        if k in with_.gyro_terms_dph)
        elif channel.startswith("acc_"):
            ax = channel[4]
            term, noise = with_.acc_terms_g[f"{ax}_hidden"], with_.acc_terms_g[f"{ax}_noise"]
        else:
            ok = ~(with_.columns[POWERED_COLUMN] < 0.5) if POWERED_COLUMN in with_.columns \
                else slice(None)
            d = (with_.clean[channel] - without.clean[channel])[ok]
            ex.append(d)
            rise = (without.clean[channel] - without.clean[channel][0])[ok]
            ex_d.append(_after_rescale(d, rise))
            fl.append((with_.columns[channel] - with_.clean[channel])[ok])
            continue
        wm = _window_means(term, mv, n_win)
        ex.append(wm)
        ex_d.append(wm - wm.mean())
        fl.append(_window_means(noise, mv, n_win))

    def rms(parts):
        return float(np.sqrt(np.mean(np.concatenate(parts) ** 2)))

    floor, excess, excess_d = rms(fl), rms(ex), rms(ex_d)
    return {"hidden": hidden, "channel": channel, "params": params, "floor": floor,
            "excess": excess, "ratio": excess / floor,
            unabsorbed_ratio_key(hidden): excess_d / floor}


def measure_strength(hidden: str, *, params: dict | None = None, seed: int = 0,
                     start_temperatures_c=(-32.0, -16.0, -5.0, 17.0, 28.0, 43.0, 54.0),
                     duration_s: float = 9000.0, sample_rate_hz: float = 1.0) -> dict:
    """Excess RMS of a hidden effect over its channel's noise floor, pooled over the runs.

    Gyro and accelerometer: 10 s window means (dwell samples only) of the effect's term and
    of the channel's noise; ``ratio`` uses the raw term, ``ratio_detrended`` the term minus
    its mean in each run (what a per-run constant cannot take up).  Thermometers: the noise
    floor is the RMS of reading minus clean reading (noise and quantum); the excess is the
    clean reading with the effect minus without (same seed); ``ratio_after_rescale`` removes
    from that difference, per run, its least-squares fit on [1, the run's own rise]: the part
    a model with another power or conductance could take up.
    """
    p = _check_hidden(hidden, params)
    thermo = _CHANNEL[hidden].startswith("temp_")

    def pairs():
        for i, t0 in enumerate(start_temperatures_c):
            kw = dict(seed=seed, run_index=i, duration_s=duration_s,
                      sample_rate_hz=sample_rate_hz)
            yield (simulate_run(float(t0), hidden=hidden, params=p, **kw),
                   simulate_run(float(t0), **kw) if thermo else None)

    return strength_of_runs(hidden, p, pairs(), sample_rate_hz)


# ---------------------------------------------------------------------------------------------
# The family (family.py), reached from here too

_FAMILY_NAMES = ("FamilyDraw", "draw_unit", "generate_family_set")


def _family():
    """The family module, imported on first use (it imports this one)."""
    if __package__:
        from . import family
    else:
        import family
    return family


def __getattr__(name: str):
    if name in _FAMILY_NAMES:
        return getattr(_family(), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# ---------------------------------------------------------------------------------------------
# Command line

def main(argv: list[str] | None = None) -> int:
    """``generator.py OUT_DIR [--hidden NAME] [--seed N] ...``; prints the truth as JSON."""
    ap = argparse.ArgumentParser(
        prog="generator.py",
        description="Write independent north-finder start-up runs (nfs-measurement/1), one "
                    "per start temperature, with one hidden physical effect or none; print "
                    "the truth as JSON.")
    ap.add_argument("out_dir", nargs="?", help="folder to write NAME.csv + NAME.toml into")
    ap.add_argument("--hidden", choices=sorted(HIDDEN_EFFECTS), default=None,
                    help="the hidden effect (default: none)")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                    help="override a parameter of the hidden effect (repeatable)")
    ap.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    ap.add_argument("--temperatures", type=float, nargs="+",
                    default=[-32.0, -16.0, -5.0, 17.0, 28.0, 43.0, 54.0],
                    help="start temperatures [degC]")
    ap.add_argument("--duration", type=float, default=9000.0, help="run length [s]")
    ap.add_argument("--rate", type=float, default=1.0, help="sample rate [Hz]")
    ap.add_argument("--latitude", type=float, default=30.26, help="latitude [deg]")
    ap.add_argument("--heading", type=float, default=212.7, help="true heading [deg]")
    ap.add_argument("--truth", default=None, help="also write the truth JSON to this file")
    ap.add_argument("--family", action="store_true",
                    help="a unit of the family drawn from --seed (family.py: structure, "
                         "noise, chamber, soak and the hidden effect's strength); the truth "
                         "adds the strength and the draw's description")
    ap.add_argument("--strengths", action="store_true",
                    help="instead of writing runs, print every hidden effect's excess RMS "
                         "over its channel's noise floor")
    a = ap.parse_args(argv)
    params = {}
    for kv in a.param:
        key, sep, val = kv.partition("=")
        if not sep:
            ap.error(f"--param {kv!r}: expected KEY=VALUE")
        try:
            params[key] = float(val)
        except ValueError:
            params[key] = val
    try:
        if a.strengths:
            for name in HIDDEN_EFFECTS:
                s = measure_strength(name, params=params if name == a.hidden else None,
                                     seed=a.seed, start_temperatures_c=a.temperatures,
                                     duration_s=a.duration, sample_rate_hz=a.rate)
                extra = {k: v for k, v in s.items() if k.startswith("ratio_")}
                print(f"{name:26s} {s['channel']:12s} floor {s['floor']:.3g}  excess "
                      f"{s['excess']:.3g}  ratio {s['ratio']:.2f}  "
                      + "  ".join(f"{k} {v:.2f}" for k, v in extra.items()))
            return 0
        if a.out_dir is None:
            ap.error("OUT_DIR is required (unless --strengths)")
        make = _family().generate_family_set if a.family else generate_set
        truth = make(a.out_dir, hidden=a.hidden, seed=a.seed,
                     start_temperatures_c=tuple(a.temperatures), duration_s=a.duration,
                     sample_rate_hz=a.rate, latitude_deg=a.latitude,
                     true_heading_deg=a.heading, params=params or None)
    except ValueError as exc:
        print(f"generator.py: error: {exc}", file=sys.stderr)
        return 2
    text = json.dumps(truth, indent=2, sort_keys=True)
    print(text)
    if a.truth:
        Path(a.truth).write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
