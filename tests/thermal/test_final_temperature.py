"""thermal.final_temperature: where a soak ends.

Oracle: thermal.simulate's last row (every sample's closed form) to rounding, 1e-11 K (the
end alone is one weighted sum per mode: its rounding differs from the recursion's in the
last bits), on soak grids of a coarse step and a partial last step, repeated (the kept step
matrices and modal forms), on two networks, and from a scalar or a per-node start.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import thermal.final
from thermal import Network, ThermalError, final_temperature, simulate
from thermal_networks import seven_nodes


def _soak_grid(soak_s: float, step_s: float = 10.0) -> np.ndarray:
    n = int(np.ceil(soak_s / step_s))
    return np.append(-soak_s + step_s * np.arange(n), 0.0)


@pytest.mark.parametrize("soak_s", [14400.0, 12345.678, 9.5, 10.0])
def test_the_end_of_simulate(soak_s):
    net = seven_nodes()
    rng = np.random.default_rng(3)
    for start in (23.0, 23.0 + rng.standard_normal(len(net.nodes))):
        for _ in range(3):                  # the second and third use the kept steps
            t = _soak_grid(soak_s * float(np.exp(0.1 * rng.standard_normal())))
            amb = -32.0 + 0.1 * rng.standard_normal(t.size)
            want = simulate(net, t, ambient_c=amb, initial_c=start).temperature_c[-1]
            got = final_temperature(net, t, ambient_c=amb, initial_c=start)
            np.testing.assert_allclose(got, want, rtol=0.0, atol=1e-11)


def test_kept_steps_are_bounded_and_keyed_by_network():
    # Oracle: simulate, for a network whose matrices differ from the first's; the store of
    # kept steps never grows beyond KEPT_STEPS.
    t = _soak_grid(3600.0)
    first = seven_nodes()
    second = Network(tuple(replace(n, capacity_j_per_k=1.1 * n.capacity_j_per_k)
                           for n in first.nodes), first.links)
    for net in (first, second, first):
        want = simulate(net, t, ambient_c=5.0, initial_c=20.0).temperature_c[-1]
        np.testing.assert_allclose(final_temperature(net, t, ambient_c=5.0, initial_c=20.0),
                                   want, rtol=0.0, atol=1e-11)
    for k in range(thermal.final.KEPT_STEPS + 5):
        final_temperature(first, np.array([0.0, 1.0 + k / 100.0]), ambient_c=0.0,
                          initial_c=1.0)
    assert thermal.final._step.cache_info().currsize <= thermal.final.KEPT_STEPS


def test_one_sample_and_bad_start():
    net = seven_nodes()
    assert np.array_equal(final_temperature(net, [0.0], ambient_c=1.0, initial_c=2.0),
                          np.full(len(net.nodes), 2.0))
    with pytest.raises(ThermalError, match="initial_c"):
        final_temperature(net, [0.0, 1.0], ambient_c=1.0, initial_c=[1.0, 2.0])
