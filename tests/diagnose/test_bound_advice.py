"""What a parameter at a bound says (nfs.fit.departures.bound_advice), and the extra starts.

Oracles: the message of each kind of parameter names the physical fix its side of the box
points at (a power at 0: a missing heat path; a lag at 300 s: a larger mass); the extra starts
are exactly the preset with capacities x1.3 and conductances x0.7 and the reverse, clipped
into the box.
"""

import numpy as np

from nfs.fit.departures import bound_advice
from nfs.fit.stage import perturbed_starts


def test_messages_by_kind():
    assert "heat path" in bound_advice("thermal.nodes.board.power_w", 0.0, (0.0, 70.0))
    assert "heat source is missing" in bound_advice("thermal.nodes.board.power_w", 70.0,
                                                    (0.0, 70.0))
    low = bound_advice("thermal.nodes.coil_outer.capacity_j_per_k", 9.5, (9.5, 950.0))
    assert "presses on its floor 9.5" in low and "layers" in low
    assert "presses on its ceiling 950" in bound_advice(
        "thermal.nodes.coil_outer.capacity_j_per_k", 950.0, (9.5, 950.0))
    assert "larger mass" in bound_advice("thermometers.acc_x.lag_s", 300.0, (0.0, 300.0))
    assert "not soaked" in bound_advice("thermometers.fog.offset_c", 2.0, (-2.0, 2.0))
    assert "levelled" in bound_advice("turntable.tilt_east_deg", -1.0, (-1.0, 1.0))
    assert "TEC law" in bound_advice("effects.tec_power.c_h", 0.0, (0.0, 1.0))
    assert "housing-chamber" in bound_advice(
        "thermal.links.housing-chamber.conductance_w_per_k", 0.16, (0.16, 16.0))


def test_perturbed_starts():
    paths = ["thermal.nodes.a.capacity_j_per_k", "thermal.links.a-b.conductance_w_per_k",
             "thermometers.fog.lag_s"]
    x0 = np.array([100.0, 1.0, 30.0])
    lb, ub = np.array([10.0, 0.1, 0.0]), np.array([120.0, 10.0, 300.0])
    up, down = perturbed_starts(paths, x0, lb, ub)
    np.testing.assert_allclose(up, [120.0, 0.7, 30.0])      # 130 clipped to 120
    np.testing.assert_allclose(down, [70.0, 1.3, 30.0])
    assert perturbed_starts(paths[2:], x0[2:], lb[2:], ub[2:]) == []
