"""Tests of thermal.solve.simulate; each test names its oracle.

Oracles: the closed-form RC step of one node, the hand eigen-decomposition of a two-node
network, the linear solve of Network.steady_state, the energy balance (equation (6) of
thermal/solve.py), the per-interval closed form of one node under a held power law, and
invariants (grid independence for constant input, finite differences of the solution).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from thermal import ThermalError
from thermal import CHAMBER, Link, Network, Node, ThermalResult, simulate
from thermal_networks import seven_nodes

C, G = 200.0, 0.8            # one node: capacity [J/K], conductance to the chamber [W/K]
TAU = C / G                  # its time constant [s]


def one_node(power_w: float = 0.0) -> Network:
    return Network((Node("coil", C, power_w),), (Link("coil", CHAMBER, G),))


def two_nodes() -> Network:
    """a (C 100, 1 W) to chamber 0.5 W/K, a to b (C 50, 0.3 W) 0.2 W/K."""
    return Network((Node("a", 100.0, 1.0), Node("b", 50.0, 0.3)),
                   (Link("a", CHAMBER, 0.5), Link("a", "b", 0.2)))


def tec_law(network: Network):
    """TEC of the light source, set point 25 C: 0.03 W/K below it, 0.07 W/K above it."""
    j, n = network.index("electronics"), len(network.nodes)

    def power(t_s: float, temperature_c: np.ndarray) -> np.ndarray:
        p = np.zeros(n)
        te = temperature_c[j]
        p[j] = 0.03 * max(0.0, 25.0 - te) + 0.07 * max(0.0, te - 25.0)
        return p
    return power


# --- closed forms ------------------------------------------------------------------------

def test_one_node_ambient_step():
    """RC step: T(t) = T_amb + (T0 - T_amb) exp(-t G/C)."""
    t = np.linspace(0.0, 5 * TAU, 1001)
    res = simulate(one_node(), t, ambient_c=20.0, initial_c=-30.0)
    expected = 20.0 + (-30.0 - 20.0) * np.exp(-t / TAU)
    np.testing.assert_allclose(res.node("coil"), expected, rtol=1e-9)


def test_one_node_constant_power():
    """T(t) = T_amb + P/G (1 - exp(-t G/C)), for a node constant and for an extra power."""
    t = np.arange(0.0, 3000.0, 1.0)
    expected = 10.0 + 3.0 / G * (1.0 - np.exp(-t / TAU))
    constant = simulate(one_node(3.0), t, ambient_c=10.0, initial_c=10.0)
    extra = simulate(one_node(), t, ambient_c=10.0, initial_c=10.0,
                     power_w=np.full((t.size, 1), 3.0))
    for res in (constant, extra):
        np.testing.assert_allclose(res.node("coil"), expected, rtol=1e-9)
        np.testing.assert_allclose(res.power_w, 3.0, rtol=0)


def test_two_nodes_closed_form():
    """T(t) = T_ss + c1 v1 exp(l1 t) + c2 v2 exp(l2 t), the 2x2 eigen-decomposition by hand.

    A = [[-0.7/100, 0.2/100], [0.2/50, -0.2/50]]; l = (tr -+ sqrt(tr^2 - 4 det)) / 2,
    v_i = (a12, l_i - a11); at steady state all 1.3 W leave through a-chamber and Pb = 0.3 W
    crosses a-b, so Ta = T_amb + 1.3/0.5 and Tb = Ta + 0.3/0.2.
    """
    a11, a12, a21, a22 = -0.7 / 100, 0.2 / 100, 0.2 / 50, -0.2 / 50
    tr, det = a11 + a22, a11 * a22 - a12 * a21
    disc = math.sqrt(tr * tr - 4 * det)
    l1, l2 = (tr - disc) / 2, (tr + disc) / 2
    v1, v2 = (a12, l1 - a11), (a12, l2 - a11)
    t_amb, t0 = -5.0, (30.0, -40.0)
    t_ss = np.array([t_amb + 1.3 / 0.5, t_amb + 1.3 / 0.5 + 0.3 / 0.2])
    x0 = (t0[0] - t_ss[0], t0[1] - t_ss[1])
    det_v = v1[0] * v2[1] - v2[0] * v1[1]
    c1 = (x0[0] * v2[1] - v2[0] * x0[1]) / det_v
    c2 = (v1[0] * x0[1] - x0[0] * v1[1]) / det_v
    t = np.arange(0.0, 2000.0, 1.0)
    expected = t_ss + (c1 * np.outer(np.exp(l1 * t), v1) + c2 * np.outer(np.exp(l2 * t), v2))
    res = simulate(two_nodes(), t, ambient_c=t_amb, initial_c=t0)
    np.testing.assert_allclose(res.temperature_c, expected, rtol=1e-9)


def test_long_run_reaches_network_steady_state():
    """After 50 of the longest time constants, T equals the linear solve L T = g T_amb + P."""
    net = seven_nodes()
    t = np.linspace(0.0, 50 * net.time_constants_s()[0], 2001)
    res = simulate(net, t, ambient_c=-16.0, initial_c=-16.0)
    np.testing.assert_allclose(res.temperature_c[-1], net.steady_state(-16.0), rtol=1e-9)


def test_held_power_law_matches_per_interval_closed_form():
    """One node, P_k = k_f (T_set - T_k) held over each step, so per interval the RC closed
    form applies: T_{k+1} = T_amb + (T_k - T_amb) e^{-h/tau} + P_k/G (1 - e^{-h/tau})."""
    k_f, t_set, t_amb, h = 0.5, 25.0, -32.0, 2.0
    t = np.arange(0.0, 1200.0, h)
    res = simulate(one_node(), t, ambient_c=t_amb, initial_c=t_amb,
                   power_w=lambda t_s, temp: k_f * (t_set - temp))
    decay = math.exp(-h / TAU)
    expected = [t_amb]
    for _ in t[1:]:
        p = k_f * (t_set - expected[-1])
        expected.append(t_amb + (expected[-1] - t_amb) * decay + p / G * (1 - decay))
    np.testing.assert_allclose(res.node("coil"), expected, rtol=1e-9)
    np.testing.assert_allclose(res.power_w[:, 0], k_f * (t_set - np.array(expected)), rtol=1e-9)


@pytest.mark.parametrize("grid", ["uniform", "non-uniform"])
def test_ambient_is_held_over_each_interval(grid):
    """Zero-order hold: an ambient sample at t_k acts over [t_k, t_k+1); RC closed form per
    interval with the held value (the uniform grid takes the vectorised modal path)."""
    if grid == "uniform":
        t = np.arange(0.0, 600.0, 2.0)
        amb = np.repeat([10.0, 30.0, -5.0, 0.0, 12.0, 99.0], 50)
    else:
        t = np.array([0.0, 50.0, 80.0, 200.0, 201.0, 400.0])
        amb = np.array([10.0, 30.0, -5.0, 0.0, 12.0, 99.0])
    res = simulate(one_node(), t, ambient_c=amb, initial_c=0.0)
    expected = [0.0]
    for k in range(t.size - 1):
        decay = math.exp(-(t[k + 1] - t[k]) / TAU)
        expected.append(amb[k] + (expected[-1] - amb[k]) * decay)
    np.testing.assert_allclose(res.node("coil"), expected, rtol=1e-12)
    np.testing.assert_array_equal(res.ambient_c, amb)


@pytest.mark.parametrize("path", ["vectorised", "march"])
def test_floating_pair_closed_form(path):
    """Two nodes with no path to the chamber, 1 W into a: the mean (C-weighted) temperature
    rises at P / (C_a + C_b); x = Ta - Tb obeys dx/dt = -G (1/C_a + 1/C_b) x + P / C_a."""
    net = Network((Node("a", 1.0, 1.0), Node("b", 2.0)), (Link("a", "b", 1.0),))
    t = np.arange(0.0, 50.0, 0.5)
    law = (lambda t_s, temp: np.zeros(2)) if path == "march" else None
    res = simulate(net, t, ambient_c=5.0, initial_c=[0.0, 1.0], power_w=law)
    rate, x_ss = 1.0 + 1.0 / 2.0, 1.0 / 1.5
    x = x_ss + (0.0 - 1.0 - x_ss) * np.exp(-rate * t)
    mean = (0.0 * 1.0 + 1.0 * 2.0 + 1.0 * t) / 3.0
    np.testing.assert_allclose(res.node("a"), mean + 2.0 / 3.0 * x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.node("b"), mean - 1.0 / 3.0 * x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.heat_lost_j, 0.0, atol=0)


# --- invariants --------------------------------------------------------------------------

@pytest.mark.parametrize("grid", ["uniform", "non-uniform"])
def test_energy_balance(grid):
    """heat_in = stored + lost (equation (6)), with a sinusoidal chamber and the TEC law."""
    net = seven_nodes()
    t = np.arange(0.0, 9000.0, 1.0)
    if grid == "non-uniform":
        # a few distinct steps (one matrix exponential each), in random order
        t = np.cumsum(np.random.default_rng(1).choice([0.25, 1.0, 2.5, 7.0], 3000))
    res = simulate(net, t, ambient_c=lambda t_s: -5.0 + 3.0 * math.sin(t_s / 700.0),
                   initial_c=-5.0, power_w=tec_law(net))
    assert res.heat_in_j[-1] > 1e4
    scale = np.max(np.abs(res.heat_in_j))
    np.testing.assert_allclose(res.heat_in_j, res.stored_j + res.heat_lost_j, rtol=0,
                               atol=1e-9 * scale)


def test_non_uniform_grid_agrees_with_uniform_grid():
    """For constant input the solution does not depend on the sampling."""
    net = seven_nodes()
    uniform = np.arange(0.0, 3001.0, 1.0)
    # every third uniform sample plus random half-second points: steps of 0.5 s to 3 s
    halves = np.cumsum(np.random.default_rng(0).choice([0.5, 1.0, 2.5], 2000))
    mixed = np.union1d(uniform[::3], halves[halves < 3000.0])
    a = simulate(net, uniform, ambient_c=17.0, initial_c=17.0)
    b = simulate(net, mixed, ambient_c=17.0, initial_c=17.0)
    common = np.isin(mixed, uniform)
    at = mixed[common].astype(int)              # uniform[i] == i
    assert at.size > 1000
    np.testing.assert_allclose(b.temperature_c[common], a.temperature_c[at], rtol=1e-11)
    np.testing.assert_allclose(b.heat_lost_j[common], a.heat_lost_j[at], rtol=1e-9, atol=1e-9)


def test_power_law_and_power_array_agree():
    """A law that returns a constant and the same array give one answer (two code paths)."""
    net = seven_nodes()
    t = np.arange(0.0, 2000.0, 1.0)
    p = np.linspace(0.1, 0.7, len(net.nodes))
    by_law = simulate(net, t, ambient_c=28.0, initial_c=28.0, power_w=lambda t_s, temp: p)
    by_array = simulate(net, t, ambient_c=28.0, initial_c=28.0,
                        power_w=np.tile(p, (t.size, 1)))
    np.testing.assert_allclose(by_law.temperature_c, by_array.temperature_c, rtol=1e-12)
    np.testing.assert_allclose(by_law.power_w, by_array.power_w, rtol=0)


def test_rate_matches_finite_difference():
    """rate_c_per_s = A T + B u is the derivative: central differences on a 0.01 s grid
    (error h^2/6 |T'''|) agree to 1e-6 of the largest rate."""
    net = seven_nodes()
    t = np.arange(0.0, 60.0, 0.01)
    res = simulate(net, t, ambient_c=-32.0, initial_c=np.linspace(-40.0, 10.0, 7))
    central = (res.temperature_c[2:] - res.temperature_c[:-2]) / (t[2:] - t[:-2])[:, None]
    scale = np.max(np.abs(res.rate_c_per_s))
    np.testing.assert_allclose(res.rate_c_per_s[1:-1], central, rtol=0, atol=1e-6 * scale)
    np.testing.assert_array_equal(res.rate("coil_inner"), res.rate_c_per_s[:, 4])


# --- result and input checking -----------------------------------------------------------

def test_result_is_labelled_and_read_only():
    net = two_nodes()
    res = simulate(net, np.arange(5.0), ambient_c=0.0, initial_c=[1.0, 2.0])
    assert isinstance(res, ThermalResult) and res.node_names == ("a", "b")
    np.testing.assert_array_equal(res.node("b"), res.temperature_c[:, 1])
    with pytest.raises(ValueError):
        res.temperature_c[0, 0] = 3.0
    with pytest.raises(ThermalError, match="unknown node 'c'; valid nodes: 'a', 'b'"):
        res.node("c")


def test_single_sample():
    res = simulate(two_nodes(), [0.0], ambient_c=3.0, initial_c=[1.0, 2.0])
    np.testing.assert_array_equal(res.temperature_c, [[1.0, 2.0]])
    np.testing.assert_array_equal(res.heat_in_j, [0.0])


@pytest.mark.parametrize("kwargs, message", [
    (dict(time_s=[0.0, 1.0, 1.0]), r"strictly increasing: time_s\[2\]"),
    (dict(time_s=[[0.0, 1.0]]), "1-D"),
    (dict(ambient_c=[1.0, 2.0]), "ambient_c must be"),
    (dict(ambient_c=lambda t: math.nan), "ambient_c is not finite at t = 0.0 s"),
    (dict(initial_c=[1.0, 2.0, 3.0]), "initial_c must be"),
    (dict(power_w=np.zeros((3, 3))), r"power_w must be a callable or an array of shape \(3, 2\)"),
    (dict(power_w=lambda t, temp: 1.0), r"must return shape \(2,\)"),
    (dict(power_w=lambda t, temp: [0.0, math.inf if t > 0 else 0.0]),
     "not finite at t = 1.0 s, node 'b'"),
])
def test_bad_input_raises_thermal_exception(kwargs, message):
    args = dict(time_s=[0.0, 1.0, 2.0], ambient_c=0.0, initial_c=0.0)
    args.update(kwargs)
    time_s = args.pop("time_s")
    with pytest.raises(ThermalError, match=message):
        simulate(two_nodes(), time_s, **args)


def test_power_law_cannot_change_the_state():
    def meddling(t_s, temp):
        temp[0] = 1e6
        return np.zeros(2)
    with pytest.raises(ValueError):
        simulate(two_nodes(), [0.0, 1.0], ambient_c=0.0, initial_c=0.0, power_w=meddling)


def test_linspace_grid_counts_as_uniform():
    """np.linspace steps differ in the last bits; the answer equals that of np.arange."""
    net = seven_nodes()
    a = simulate(net, np.arange(0.0, 9001.0), ambient_c=43.0, initial_c=43.0)
    b = simulate(net, np.linspace(0.0, 9000.0, 9001), ambient_c=43.0, initial_c=43.0)
    np.testing.assert_allclose(b.temperature_c, a.temperature_c, rtol=1e-12)


def test_a_step_long_against_a_fast_mode_stays_finite():
    # Closed form: the unpowered two-node network relaxing from 10 C to a chamber at 0 C over
    # one step of 4 h, T(h) = expm(A h) T(0); its fast mode (a few seconds) has decayed to
    # exactly zero in floating point, where the modal march once took log1p(-1 - eps) = NaN.
    net = Network((Node("a", 10.0), Node("b", 1000.0)),
                  (Link("a", CHAMBER, 5.0), Link("a", "b", 0.5), Link("b", CHAMBER, 1.0)))
    from scipy.linalg import expm
    a, _ = net.matrices()
    with np.errstate(all="raise"):
        res = simulate(net, np.array([0.0, 14400.0]), ambient_c=0.0, initial_c=10.0)
    np.testing.assert_allclose(res.temperature_c[-1], expm(a * 14400.0) @ [10.0, 10.0],
                               rtol=0.0, atol=1e-11)     # 1e-12 of the initial 10 K
