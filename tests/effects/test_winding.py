"""The Shupe integral over a wound coil (nfs/effects/winding.py, ``shupe_winding``).

Oracles:

- the layer weights' closed forms: sum_j W_j = 0 for every pattern, and for a rate profile
  linear in the layer index (step g) sum_j W_j j g = N (N^2 - 1)/6, N^2/4, -N/2, 0 in units
  of l^2 g for helical, dipole, quadrupole, octupole (Frigo 1983; Lefevre 2014 sec. 3.3.3);
- the continuum limit of the quadrupole, -(l^2/2) d(dT/dt)/dx at the outer face (x = 1);
- a slab coil ramped at its outer face (Carslaw & Jaeger sec. 3.3: the surface gradient's
  series), its quadrupole residual -K l^2 v sum_n exp(-(2n+1)^2 t / tau_1), its integral
  -K l^2 v d^2 / (2 a), the quadrupole / dipole ratio of the integrals 3/N;
- the magnitude of a navigation coil (L = 1 km, D = 90 mm) per K/min of rate across it;
- heat at the hub of a quadrupole wound from the spool against heat at its outer face;
- the two lumped coil nodes: shupe_winding is shupe_gradient + shupe_stress (1e-9);
- grid convergence of one physical coil (8 and 16 thermal layers) and its energy balance.
"""

import dataclasses
import math

import numpy as np
import pytest

import thermal
from nfs.effects import CoilLayout, EffectContext, make_effect
from nfs.effects.winding import DPH_PER_RAD_PER_S, layer_sequence, layer_weights
from nfs.errors import EffectError
from thermal import Annulus, Link, Network, Node

PATTERNS = ("helical", "dipole", "quadrupole", "octupole")
#: sum_j W_j j in units of l^2, for a rate j g in layer j
LINEAR = {"helical": lambda n: n * (n * n - 1) / 6, "dipole": lambda n: n * n / 4,
          "quadrupole": lambda n: -n / 2, "octupole": lambda n: 0.0}
#: n (dn/dT + n alpha) of the effect's defaults [1/K]
THERMO = 1.46 * (1.0e-5 + 1.46 * 5.5e-7)


@pytest.mark.parametrize("n", [8, 16, 32, 64])
@pytest.mark.parametrize("pattern", PATTERNS)
def test_layer_weights_closed_forms(pattern, n):
    w = layer_weights(pattern, n, float(n))             # l = 1
    assert w.sum() == 0.0
    assert (w * np.arange(1, n + 1)).sum() == pytest.approx(LINEAR[pattern](n), abs=1e-9)
    # the weights are the integrals of (2z - L) over each layer's stretch of fibre: the
    # stretches tile [0, L], each weight's size is (2|m| - 1) l^2 for a distance m from the
    # midpoint (helical: from an end)
    assert sorted(np.abs(w)) == sorted(np.abs(layer_weights("helical", n, float(n))))


@pytest.mark.parametrize("profile, slope_at_1", [(lambda x: x ** 2, 2.0),
                                                 (lambda x: x ** 3, 3.0)])
def test_quadrupole_continuum_limit(profile, slope_at_1):
    n = 64
    w = layer_weights("quadrupole", n, float(n))        # l = 1
    x = (np.arange(n) + 0.5) / n
    assert (w * profile(x)).sum() == pytest.approx(-0.5 * slope_at_1, rel=5e-3)


def _context(res, layout):
    zero = np.zeros(res.time_s.size)
    return EffectContext(
        time_s=res.time_s, node_names=res.node_names, temperature_c=res.temperature_c,
        rate_c_per_s=res.rate_c_per_s, coil_outer=layout.layers[-1],
        coil_inner=layout.layers[0], source=layout.layers[0], axis_azimuth_deg=zero,
        earth_rate_dph=zero, moving=zero.astype(bool), coil_layout=layout)


def _shupe(ctx, **params):
    e = make_effect("shupe_winding", params)
    return e.spec.function(ctx, **e.params)


def _layout(ann):
    return CoilLayout(ann.layer_names, tuple(ann.centres), ann.face_weights("inner"),
                      ann.face_weights("outer"))


@pytest.fixture(scope="module")
def ramped_slab():
    """A slab coil (d = 16 mm, k = 0.25 W/(m K), rho c = 1.7e6 J/(m^3 K)) on an adiabatic
    spool, its outer face on a skin that follows the chamber (time constant 1e-5 s), the
    chamber ramped at 1 K/min from t = 0; 32 thermal layers (r_i = 100 m: flat to 2e-4)."""
    d, k, rho_c = 0.016, 0.25, 1.7e6
    ann = Annulus("coil", 100.0, 100.0 + d, 1e-3, k, rho_c, 32, {}, {"skin": 1e6})
    net = Network(ann.nodes() + (Node("skin", 100.0),),
                  ann.links() + (Link("skin", "chamber", 1e7),))
    t = np.arange(0.0, 4 * 3600.0 + 1.0, 1.0)
    v = 1.0 / 60.0
    res = thermal.simulate(net, t, ambient_c=v * t, initial_c=0.0,
                           ambient_hold="first-order")
    return _context(res, _layout(ann)), d * d * rho_c / k, v


def test_ramp_closed_form(ramped_slab):
    ctx, d2_over_a, v = ramped_slab
    n_opt, length, diameter = 64, 1000.0, 0.09
    quad = _shupe(ctx, L=length, D=diameter, N_opt=n_opt)
    dip = _shupe(ctx, L=length, D=diameter, N_opt=n_opt, pattern="dipole")
    k_l2 = THERMO / (length * diameter) * DPH_PER_RAD_PER_S * (length / n_opt) ** 2
    tau_1 = 4.0 * d2_over_a / math.pi ** 2
    t = ctx.time_s
    modes = (2 * np.arange(400) + 1) ** 2
    closed = -k_l2 * v * np.exp(-np.outer(t, modes) / tau_1).sum(axis=1)
    late = t >= tau_1 / 10                      # the series' first tenth is a boundary layer
    assert np.max(np.abs(quad[late] - closed[late])) <= 0.01 * k_l2 * v
    integral = np.trapezoid(quad, t)
    assert integral == pytest.approx(-k_l2 * v * d2_over_a / 2, rel=0.02)
    assert abs(integral / np.trapezoid(dip, t)) == pytest.approx(3.0 / n_opt, rel=0.02)


@pytest.mark.parametrize("n_opt, quad, dip", [(32, 0.294, 4.71), (64, 0.0735, 2.35)])
def test_navigation_coil_magnitude(n_opt, quad, dip):
    # L = 1 km, D = 90 mm: the rate across the winding grows linearly from the spool to the
    # outer face, 1 K/min between the faces; deg/h per K/min (0.07-0.29 for a quadrupole of
    # 32-64 layers, 2.4-4.7 for a dipole)
    x = (np.arange(n_opt) + 0.5) / n_opt
    per = THERMO / (1000.0 * 0.09) * DPH_PER_RAD_PER_S / 60.0
    q = abs(per * (layer_weights("quadrupole", n_opt, 1000.0) * x).sum())
    d = abs(per * (layer_weights("dipole", n_opt, 1000.0) * x).sum())
    assert q == pytest.approx(quad, rel=2e-3) and 0.07 <= round(q, 2) <= 0.29
    assert d == pytest.approx(dip, rel=2e-3) and 2.4 <= round(d, 1) <= 4.7


@pytest.mark.parametrize("n_th", [8, 16])
def test_heat_at_the_hub_is_almost_invisible_to_a_quadrupole(n_th):
    # the default coil's winding (N_opt = 64), 1 W stepped on at a 100 J/K mount (0.5 W/K to
    # the chamber) touching either its spool face or its outer face (3 W/K), the other face
    # free: a quadrupole wound from the spool answers to the gradient at its outer face
    def peak(face):
        contacts = {"mount": 3.0}
        ann = Annulus("coil", 0.03955, 0.05045, 0.0094, 0.25, 1.7e6, n_th,
                      contacts if face == "inner" else {}, contacts if face == "outer" else {})
        net = Network(ann.nodes() + (Node("mount", 100.0, power_w=1.0),),
                      ann.links() + (Link("mount", "chamber", 0.5),))
        res = thermal.simulate(net, np.arange(0.0, 7200.0), ambient_c=0.0, initial_c=0.0)
        out = _shupe(_context(res, _layout(ann)), N_opt=64)
        return np.max(np.abs(out)), abs(out.sum())
    (hub, hub_sum), (outer, outer_sum) = peak("inner"), peak("outer")
    assert hub < 0.01 * outer and hub_sum < 0.01 * outer_sum


def test_two_lumped_nodes_are_shupe_gradient_and_stress():
    # the lumped coil's nodes hold the inner and outer halves (x = 1/4, 3/4): shupe_winding
    # is the line through their rates, i.e. k_r = n (dn/dT + n alpha) sum_j W_j x_j /
    # (L D (x_o - x_i)) per K/s, and k_m alike
    from nfs.config.scenario import load_scenario
    from nfs.comparison.compare_runs import noise_free
    from nfs.experiment import simulate_run
    from nfs.instrument import load_instrument
    inst = noise_free(load_instrument("lumped"))
    cond = load_scenario().nominal().conditions()[0]
    length, diam, n_opt, k_m, c_m = 1000.0, 0.09, 32, 1.2e-5, -0.012
    x = (np.arange(n_opt) + 0.5) / n_opt
    s = (layer_weights("quadrupole", n_opt, length) * x).sum() / 0.5
    per = 1.46 / (length * diam) * s * DPH_PER_RAD_PER_S / 60.0
    thermal_fx = [e for e in inst.effects if e.spec.kind == "thermal"]
    wound = simulate_run(inst.with_effects(thermal_fx + [make_effect("shupe_winding", dict(
        L=length, D=diam, N_opt=n_opt, k_m=k_m, c_m=c_m))]), cond).drift_dph
    lumped = simulate_run(inst.with_effects(thermal_fx + [
        make_effect("shupe_gradient", {"k_r": per * (1.0e-5 + 1.46 * 5.5e-7)}),
        make_effect("shupe_stress", {"k_m": per * k_m, "c_m": c_m})]), cond).drift_dph
    assert np.max(np.abs(wound - lumped)) <= 1e-9 * np.max(np.abs(lumped))


def test_asymmetric_length_reads_the_mean_rate():
    # W'_j = W_j + L_a l_j: a uniform rate dT/dt leaves K L L_a dT/dt
    layout = CoilLayout(("a", "b"), (0.25, 0.75))
    t = np.arange(100.0)
    temp = np.column_stack([0.01 * t, 0.01 * t])
    rate = np.full_like(temp, 0.01)
    zero = np.zeros(t.size)
    ctx = EffectContext(time_s=t, node_names=("a", "b"), temperature_c=temp,
                        rate_c_per_s=rate, coil_outer="b", coil_inner="a", source="a",
                        axis_azimuth_deg=zero, earth_rate_dph=zero,
                        moving=zero.astype(bool), coil_layout=layout)
    assert np.allclose(_shupe(ctx, L_asym=0.0), 0.0, atol=1e-15)
    out = _shupe(ctx, L_asym=0.05)
    expected = THERMO / 0.09 * 0.05 * 0.01 * DPH_PER_RAD_PER_S
    np.testing.assert_allclose(out, expected, rtol=1e-12)


def test_bad_windings_are_refused():
    with pytest.raises(EffectError, match="none of helical"):
        layer_sequence("quadrupol", 8)
    with pytest.raises(EffectError, match="not a multiple"):
        layer_sequence("quadrupole", 6)
    with pytest.raises(EffectError, match="equal lengths"):
        layer_sequence("AAB", 6)
    assert layer_sequence("BAAB", 8) == "BAABBAAB"
    with pytest.raises(EffectError, match="N_opt.*whole number"):
        make_effect("shupe_winding", {"N_opt": 31.5})
    with pytest.raises(EffectError, match="not a multiple"):
        make_effect("shupe_winding", {"N_opt": 30})




def test_one_physical_coil_converges_between_8_and_16_layers():
    # the default coil cut into 8 and into 16 thermal layers, the nominal start-up at -32 C:
    # the Shupe bias over every 150 s dwell (what the north finder reads) agrees within 2 %
    # (RMS of the difference against the bias's), and so does the bias at every sample after
    # the first minute (the first seconds after power-on are a boundary layer at the outer
    # face, thinner than a layer); the layered network keeps its energy balance to 1e-9
    from nfs.coil import with_coil
    from nfs.config.scenario import load_scenario
    from nfs.comparison.compare_runs import noise_free
    from nfs.experiment import simulate_run
    from nfs.instrument import load_instrument
    inst = noise_free(load_instrument("default"))
    cond = load_scenario().nominal().conditions()[0]
    out = {}
    for n_th in (8, 16):
        coil = dataclasses.replace(inst.coil, layers=n_th)
        nodes, links = inst.own_parts
        unit = dataclasses.replace(inst, coil=coil, network=with_coil(nodes, links, coil),
                                   gyro=dataclasses.replace(inst.gyro,
                                                            coil_outer=coil.layer_names[-1],
                                                            coil_inner="coil_1"),
                                   thermometers={**inst.thermometers, "fog": dataclasses.replace(
                                       inst.thermometers["fog"],
                                       nodes={"electronics": 0.3, coil.layer_names[-1]: 0.7})})
        sim = simulate_run(unit, cond)
        th = sim.thermal
        ledger = th.heat_in_j - th.stored_j - th.heat_lost_j
        assert np.max(np.abs(ledger)) <= 1e-9 * np.max(np.abs(th.stored_j))
        out[n_th] = sim.gyro_terms_dph["shupe_winding"]
    dwell = [x[:9000].reshape(-1, 150).mean(axis=1) for x in (out[8], out[16])]

    def rel(a, b):
        return np.sqrt(np.mean((a - b) ** 2) / np.mean(b ** 2))
    assert rel(*dwell) < 0.02
    assert rel(out[8][60:], out[16][60:]) < 0.02
