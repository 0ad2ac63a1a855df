"""Many runs of one network solved together (thermal.simulate_many) against one at a time."""

import numpy as np
import pytest

from thermal import ThermalError
from thermal import simulate, simulate_many
from thermal_networks import seven_nodes


def _tec(index_of_electronics):
    """A TEC-like law on the electronics node, for one run (n,) or many (R, n)."""
    def law(t_s, temperature_c):
        p = np.zeros(np.shape(temperature_c))
        dT = np.asarray(temperature_c)[..., index_of_electronics] - 25.0
        p[..., index_of_electronics] = np.where(dT < 0, -0.03 * dT, 0.08 * dT)
        return p
    return law


@pytest.mark.parametrize("hold", ["zero-order", "first-order"])
def test_stacked_runs_match_single_runs(hold):
    # Oracle: simulate() run by run, bit for bit (the same elementwise products and sums, in
    # the same order, per run).
    net = seven_nodes()
    t = np.arange(0.0, 3600.0, 1.0)
    starts = np.array([-32.0, 5.0, 54.0])
    ambient = starts[:, None] + 0.5 * np.sin(2 * np.pi * t / 600.0)[None, :] \
        + np.array([0.0, 1.0, -1.0])[:, None] * t / 3600.0
    law = _tec(net.node_names.index("electronics"))
    many = simulate_many(net, t, ambient_c=ambient, initial_c=starts, power_w=law,
                         ambient_hold=hold)
    assert len(many) == 3
    for i, res in enumerate(many):
        one = simulate(net, t, ambient_c=ambient[i], initial_c=starts[i], power_w=law,
                       ambient_hold=hold)
        np.testing.assert_array_equal(res.temperature_c, one.temperature_c)
        np.testing.assert_array_equal(res.power_w, one.power_w)
        np.testing.assert_array_equal(res.heat_lost_j, one.heat_lost_j)
        assert res.temperature_c.flags.writeable is False


def test_a_run_has_the_same_bits_in_any_batch():
    # Oracle: each run's arithmetic is its own (thermal/march.py: elementwise, fixed order);
    # max_bytes splits the runs into batches of one here.
    net = seven_nodes()
    t = np.arange(0.0, 900.0, 1.0)
    starts = np.array([-32.0, 0.0, 17.0, 40.0, 54.0, 60.0])
    ambient = np.repeat(starts[:, None], t.size, axis=1)
    law = _tec(net.node_names.index("electronics"))
    together = simulate_many(net, t, ambient_c=ambient, initial_c=starts, power_w=law)
    apart = simulate_many(net, t, ambient_c=ambient, initial_c=starts, power_w=law,
                          max_bytes=1)
    three = simulate_many(net, t, ambient_c=ambient[:3], initial_c=starts[:3], power_w=law)
    for a, b in zip(together, apart):
        assert np.array_equal(a.temperature_c, b.temperature_c)
    for a, b in zip(together, three):
        assert np.array_equal(a.temperature_c, b.temperature_c)


def test_without_a_law_each_run_is_the_closed_form_bit_for_bit():
    net = seven_nodes()
    t = np.arange(0.0, 1800.0, 2.0)
    ambient = np.vstack([np.full(t.size, 10.0), np.linspace(20.0, 30.0, t.size)])
    many = simulate_many(net, t, ambient_c=ambient, initial_c=[10.0, 20.0])
    for i, res in enumerate(many):
        one = simulate(net, t, ambient_c=ambient[i], initial_c=[10.0, 20.0][i])
        assert np.array_equal(res.temperature_c, one.temperature_c)


def test_shapes_are_checked():
    net = seven_nodes()
    t = np.arange(0.0, 10.0)
    with pytest.raises(ThermalError, match="ambient_c must have shape"):
        simulate_many(net, t, ambient_c=np.zeros(10), initial_c=[0.0])
    with pytest.raises(ThermalError, match="initial_c must have shape"):
        simulate_many(net, t, ambient_c=np.zeros((2, 10)), initial_c=[0.0, 1.0, 2.0])


def test_the_tec_law_gives_the_same_bits_for_floats_and_arrays():
    # Oracle: the registry's contract for state-dependent effects (simulate_runs evaluates
    # a few stacked runs row by row and many at once).
    from nfs.effects.thermal import tec_power
    rng = np.random.default_rng(3)
    temps = 25.0 + 40.0 * rng.standard_normal(2000)
    arr = tec_power(0.0, temps, 0, T_set=25.0, c_h=0.031, c_c=0.077)
    one = np.array([tec_power(0.0, float(v), 0, T_set=25.0, c_h=0.031, c_c=0.077)
                    for v in temps])
    assert np.array_equal(arr, one)
