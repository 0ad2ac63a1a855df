"""First-order hold of the chamber temperature in thermal.simulate (equations (7)-(8) of
thermal/solve.py); each test names its oracle.

Oracles: the closed form of one RC node under a chamber ramp, grid independence of an exact
solution (a piecewise-linear chamber with corners on both grids), the energy balance
(equation (6)), and the zero-order hold for a constant chamber.
"""

from __future__ import annotations

import numpy as np
import pytest

from thermal import ThermalError
from thermal import CHAMBER, Link, Network, Node, simulate
from thermal_networks import seven_nodes

C, G = 200.0, 0.8            # one node: capacity [J/K], conductance to the chamber [W/K]
TAU = C / G                  # its time constant [s]


def one_node(power_w: float = 0.0) -> Network:
    return Network((Node("coil", C, power_w),), (Link("coil", CHAMBER, G),))


def ramp_closed_form(t, t0_c, amb0_c, rate_c_per_s):
    """dT/dt = (T_amb - T) / tau with T_amb = amb0 + r t:
    T(t) = T_amb(t) - r tau (1 - exp(-t/tau)) + (T0 - amb0) exp(-t/tau)."""
    e = np.exp(-t / TAU)
    return amb0_c + rate_c_per_s * t - rate_c_per_s * TAU * (1.0 - e) + (t0_c - amb0_c) * e


@pytest.mark.parametrize("grid", ["uniform", "two steps", "power law"])
def test_one_node_under_a_ramp_is_the_closed_form(grid):
    # Oracle: the closed form above, to 1e-9 K, on the vectorised path (uniform grid), the
    # per-step march (two step sizes) and the march with a power law (returning zero).
    r = -1.0 / 60.0                                  # -1 C/min
    if grid == "two steps":
        t = np.concatenate([np.arange(0.0, 1800.0, 1.0), np.arange(1800.0, 5400.0, 2.5)])
    else:
        t = np.arange(0.0, 5400.0, 1.0)
    law = (lambda ts, temp: np.zeros(1)) if grid == "power law" else None
    th = simulate(one_node(), t, ambient_c=25.0 + r * t, initial_c=30.0, power_w=law,
                  ambient_hold="first-order")
    np.testing.assert_allclose(th.node("coil"), ramp_closed_form(t, 30.0, 25.0, r),
                               rtol=0, atol=1e-9)
    assert th.ambient_hold == "first-order"
    # and the exact rate dT/dt = (T_amb - T) / tau at every sample
    np.testing.assert_allclose(th.rate("coil"), (th.ambient_c - th.node("coil")) / TAU,
                               rtol=0, atol=1e-12)


def test_a_held_chamber_lags_a_ramp_by_half_a_step():
    # Oracle: the held ramp's steady lag.  The zero-order hold steps T_k+1 = lambda T_k +
    # (1 - lambda) r k h (lambda = exp(-h/tau)), whose steady solution lags the ramp by
    # r h / (1 - lambda) = r (tau + h/2 + h^2 / (12 tau) + ...); the first-order hold lags
    # by r tau, the closed form of the previous test (both transients gone to e^-20).
    r, h = 1.0 / 60.0, 10.0
    t = np.arange(0.0, 20 * TAU, h)
    zoh = simulate(one_node(), t, ambient_c=r * t, initial_c=0.0).node("coil")
    foh = simulate(one_node(), t, ambient_c=r * t, initial_c=0.0,
                   ambient_hold="first-order").node("coil")
    assert foh[-1] - zoh[-1] == pytest.approx(r * (h / -np.expm1(-h / TAU) - TAU), rel=1e-7)


def test_piecewise_linear_chamber_is_grid_independent():
    # Oracle: the solution is exact for a chamber linear between samples, so grids of 1 s
    # and 60 s (every corner of the program on both) agree at their common times; the
    # seven-node network with its powers.
    knots_t = np.array([0.0, 1800.0, 2700.0, 4500.0, 6300.0, 8100.0])
    knots_c = np.array([25.0, 25.0, 10.0, 10.0, 25.0, 25.0])
    net = seven_nodes()
    fine = np.arange(0.0, 8101.0, 1.0)
    coarse = np.arange(0.0, 8101.0, 60.0)
    a = simulate(net, fine, ambient_c=np.interp(fine, knots_t, knots_c), initial_c=25.0,
                 ambient_hold="first-order")
    b = simulate(net, coarse, ambient_c=np.interp(coarse, knots_t, knots_c), initial_c=25.0,
                 ambient_hold="first-order")
    np.testing.assert_allclose(a.temperature_c[::60], b.temperature_c, rtol=0, atol=1e-9)
    np.testing.assert_allclose(a.heat_lost_j[::60], b.heat_lost_j, rtol=1e-9, atol=1e-6)


def test_energy_balance_under_a_ramp():
    # Oracle: equation (6), heat in = stored + lost, with the lost heat integrated exactly
    # under the linear chamber (Omega of (7) and the trapezoid of T_amb).
    net = seven_nodes()
    t = np.arange(0.0, 7200.0, 1.0)
    amb = 20.0 + 0.5 / 60.0 * t
    th = simulate(net, t, ambient_c=amb, initial_c=20.0, ambient_hold="first-order")
    scale = np.max(np.abs(th.heat_in_j))
    np.testing.assert_allclose(th.heat_in_j, th.stored_j + th.heat_lost_j, rtol=0,
                               atol=1e-9 * scale)


def test_constant_chamber_first_order_is_zero_order():
    # Oracle: with no slope the two holds are the same equations.
    net = seven_nodes()
    t = np.arange(0.0, 3000.0, 1.0)
    a = simulate(net, t, ambient_c=-10.0, initial_c=-10.0)
    b = simulate(net, t, ambient_c=-10.0, initial_c=-10.0, ambient_hold="first-order")
    np.testing.assert_allclose(a.temperature_c, b.temperature_c, rtol=0, atol=1e-12)


def test_unknown_hold_is_refused():
    with pytest.raises(ThermalError, match="ambient_hold must be one of"):
        simulate(one_node(), np.arange(3.0), ambient_c=0.0, initial_c=0.0,
                 ambient_hold="linear")
