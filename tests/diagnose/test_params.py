"""Parameter paths into an instrument (nfs.fit.params).

Oracles: invariants (get after set returns what was set; the original instrument is
unchanged; a TOML round trip keeps the set value), the instrument's own TOML form (the path
names the same number as the TOML key), and the error contract (a bad path names itself
and lists close valid ones).  Both coils: the default's wound coil (its layers follow the
coil's numbers ``coil.*``) and the lumped preset's two nodes.
"""

import math

import pytest

from nfs.fit.params import (ParameterError, default_bounds, expand_paths, fit_bounds,
                                 get_param, list_params, set_params)
from nfs.errors import NfsError
from nfs.instrument import instrument_from_dict, load_instrument


@pytest.fixture(scope="module")
def inst():
    return load_instrument("default")


@pytest.fixture(scope="module")
def lumped():
    return load_instrument("lumped")


@pytest.mark.parametrize("preset", ["default", "lumped"])
def test_round_trip_every_path(preset):
    inst = load_instrument(preset)
    paths = list_params(inst)
    assert len(paths) == len(set(paths)) > 40
    for p in paths:
        v = get_param(inst, p)
        # a coil's radii and height by 10 % (its winding stays between them)
        new = v * 1.1 if p.startswith("coil.") else v * 1.25 + 0.5
        out = set_params(inst, {p: new})
        assert get_param(out, p) == pytest.approx(new, rel=1e-15), p
        # the original is unchanged
        assert get_param(inst, p) == v, p
        # every other parameter unchanged
        for q in paths:
            if q != p:
                assert get_param(out, q) == get_param(inst, q), (p, q)


def test_set_many_and_toml_round_trip(lumped):
    inst = lumped
    values = {"thermal.nodes.coil_inner.capacity_j_per_k": 170.0,
              "thermal.links.chamber-housing.conductance_w_per_k": 1.9,   # reversed order
              "thermometers.fog.lag_s": 36.0, "gyro.bias_dph": 0.03,
              "effects.shupe_gradient.k_r": 0.12,
              "effects.acc_bias_temperature:x.b_q1": 3e-5,
              "effects.tec_power.c_h": 0.04}
    out = set_params(inst, values)
    back = instrument_from_dict(out.to_dict())
    for p, v in values.items():
        assert get_param(back, p) == v
    # the other axis's effect with the same name is untouched
    assert get_param(out, "effects.acc_bias_temperature:y.b_q1") == -1.5e-5
    # node powers and the original network untouched
    assert inst.network.nodes[4].capacity_j_per_k == 190.0


def test_a_wound_coils_layers_follow_its_numbers(inst):
    # the layers are not paths: the coil's numbers are, and setting one rebuilds them
    paths = list_params(inst)
    assert not any(".coil_3." in p or "coil_3-" in p for p in paths)
    assert {"coil.conductivity_w_per_m_k", "coil.heat_capacity_j_per_m3_k",
            "coil.inner_contacts.spool", "coil.outer_contacts.housing"} <= set(paths)
    out = set_params(inst, {"coil.heat_capacity_j_per_m3_k": 2.0e6,
                            "coil.outer_contacts.housing": 0.6,
                            "thermal.nodes.spool.capacity_j_per_k": 90.0})
    caps = {n.name: n.capacity_j_per_k for n in out.network.nodes}
    old = {n.name: n.capacity_j_per_k for n in inst.network.nodes}
    assert caps["coil_5"] == pytest.approx(old["coil_5"] * 2.0 / 1.7, rel=1e-12)
    assert caps["spool"] == 90.0
    assert sum(caps[f"coil_{k}"] for k in range(1, 9)) == pytest.approx(
        out.coil.capacity_j_per_k, rel=1e-12)
    back = instrument_from_dict(out.to_dict())
    assert back.network == out.network and back.coil == out.coil
    with pytest.raises(ParameterError, match="coil_3"):
        get_param(inst, "thermal.nodes.coil_3.capacity_j_per_k")


def test_kinds(inst, lumped):
    thermal = list_params(inst, "thermal")
    assert "thermal.nodes.housing.capacity_j_per_k" in thermal
    assert "effects.tec_power.c_h" in thermal
    assert "coil.conductivity_w_per_m_k" in thermal
    assert "effects.shupe_winding.k_m" in list_params(inst, "drift")
    assert "effects.shupe_gradient.k_r" in list_params(lumped, "drift")
    assert "gyro.bias_dph" in list_params(inst, "drift")
    assert "effects.acc_bias_temperature:x.b_q1" in list_params(inst, "accelerometer")
    assert set(list_params(inst, "thermometer")) >= {"thermometers.fog.lag_s",
                                                     "thermometers.acc_y.offset_c"}
    with pytest.raises(NfsError, match="kinds"):
        list_params(inst, "gyros")


def test_patterns(lumped):
    inst = lumped
    caps = expand_paths(inst, "thermal.nodes.*.capacity_j_per_k")
    assert len(caps) == len(inst.network.nodes)
    got = expand_paths(inst, ["thermometers.*.lag_s", "effects.shupe_*.*",
                              "thermal.links.chamber-housing.conductance_w_per_k"])
    assert got == ["thermal.links.housing-chamber.conductance_w_per_k",
                   "thermometers.fog.lag_s", "thermometers.acc_x.lag_s",
                   "thermometers.acc_y.lag_s", "effects.shupe_gradient.k_r",
                   "effects.shupe_rate.k_s", "effects.shupe_stress.k_m",
                   "effects.shupe_stress.c_m"]
    with pytest.raises(ParameterError, match="matches no parameter"):
        expand_paths(inst, "thermal.nodes.*.capacity_w")


@pytest.mark.parametrize("bad, close", [
    ("effects.shupe_gradiant.k_r", "effects.shupe_gradient.k_r"),
    ("thermal.links.coil_outer-board.conductance_w_per_k", "thermal.links."),
    ("thermometers.fog.lag", "thermometers.fog.lag_s"),
    ("gyro.bias", "gyro.bias_dph"),
])
def test_bad_path(lumped, bad, close):
    inst = lumped
    with pytest.raises(NfsError) as err:
        get_param(inst, bad)
    msg = str(err.value)
    assert bad in msg and close in msg and "\n" not in msg
    with pytest.raises(ParameterError):
        set_params(inst, {bad: 1.0})


def test_default_bounds(inst):
    assert default_bounds("thermal.nodes.housing.capacity_j_per_k", 3500.0) == (350.0, 35000.0)
    assert default_bounds("thermal.links.a-b.conductance_w_per_k", 1.6) == (0.16, 16.0)
    # anchored: a decade below the typical 10-60 s, never 0 (a log prior's row)
    assert default_bounds("thermometers.fog.lag_s", 30.0) == (1.0, 300.0)
    assert default_bounds("thermometers.fog.lag_s", 0.0) == (0.0, 300.0)
    assert default_bounds("thermometers.fog.offset_c", 0.0) == (-2.0, 2.0)
    assert default_bounds("effects.shupe_gradient.k_r", 0.1) == (-math.inf, math.inf)
    assert fit_bounds(inst, "effects.tec_power.c_h") == (0.0, 1.0)
    assert fit_bounds(inst, "effects.turn_on_transient.tau") == (12.0, 1200.0)
    for p in list_params(inst):
        lo, hi = fit_bounds(inst, p)
        assert lo <= get_param(inst, p) <= hi, p


def test_relative_boxes_of_a_typical_unit_are_a_decade_each_way(inst):
    # every value of the default instrument is typical: the anchoring leaves its boxes alone
    for p in list_params(inst):
        if p.endswith(("capacity_j_per_k", "conductance_w_per_k")):
            v = get_param(inst, p)
            assert fit_bounds(inst, p) == (v / 10.0, v * 10.0), p


def test_chained_fits_cannot_walk_a_capacity_out_of_its_range(lumped):
    """A fit started from another fit's result gets a box relative to that result; chained,
    the boxes would let a capacity fall a decade per fit.  Anchored to the typical range of
    nfs.ranges (coil_outer 40-100 J/K), the box stops a decade below it, however many fits
    come before."""
    inst = lumped
    path = "thermal.nodes.coil_outer.capacity_j_per_k"
    floor = 40.0 / 10.0
    walked = inst
    for _ in range(4):                     # each fit ends on the floor of its box
        lo, hi = fit_bounds(walked, path)
        assert lo >= floor * (1 - 1e-12)
        walked = set_params(walked, {path: lo})
    assert get_param(walked, path) == pytest.approx(floor)
    # a value between the floor and the typical range: the floor, not value / 10
    mid = set_params(inst, {path: 20.0})
    assert fit_bounds(mid, path) == (floor, 200.0)
    # a value already below the floor (a unit the table does not know) is kept, not raised
    low = set_params(inst, {path: 0.2})
    assert fit_bounds(low, path) == (0.2, 2.0)
    # the top side: a decade above the typical high (qfa_x 30-60 J/K -> 600 J/K)
    high = set_params(inst, {"thermal.nodes.qfa_x.capacity_j_per_k": 100.0})
    assert fit_bounds(high, "thermal.nodes.qfa_x.capacity_j_per_k") == (10.0, 600.0)
