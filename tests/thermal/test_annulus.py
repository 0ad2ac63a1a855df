"""A thick-walled cylinder in radial shells (thermal/annulus.py).

Oracles: the volume of the shells (their capacities add up to rho c pi (r_o^2 - r_i^2) h);
steady radial conduction through a thick-walled cylinder, G = 2 pi k h / ln(r_o / r_i)
(Incropera & DeWitt eq. (3.33)), which the shells and the half shells at the faces must give
at every N (the series telescopes); the Kron reduction of a massless face (the network with
the face as a node of vanishing capacity has the same steady state and, to the face's own
time constant, the same response); the energy balance of the solved network.
"""

import math

import numpy as np
import pytest

import thermal
from thermal import Annulus, Link, Network, Node, ThermalError


def _wall(n, **kw):
    args = dict(prefix="w", inner_radius_m=0.04, outer_radius_m=0.05, height_m=0.01,
                conductivity_w_per_m_k=0.25, heat_capacity_j_per_m3_k=1.7e6, n_layers=n)
    args.update(kw)
    return Annulus(**args)


@pytest.mark.parametrize("spacing", thermal.annulus.SPACINGS)
@pytest.mark.parametrize("n", [1, 2, 8, 33])
def test_capacities_add_up_to_the_volume(n, spacing):
    wall = _wall(n, spacing=spacing)
    volume = math.pi * (0.05 ** 2 - 0.04 ** 2) * 0.01
    assert wall.capacities_j_per_k.sum() == pytest.approx(1.7e6 * volume, rel=1e-12)
    assert wall.capacity_j_per_k == pytest.approx(1.7e6 * volume, rel=1e-12)
    edges = wall.edges_m
    assert edges[0] == 0.04 and edges[-1] == 0.05 and np.all(np.diff(edges) > 0)
    if spacing == "uniform":
        # outer shells hold more (their volume grows with the radius)
        assert np.all(np.diff(wall.capacities_j_per_k) > 0)
        assert np.allclose(wall.centres, (np.arange(n) + 0.5) / n, rtol=0, atol=1e-12)
    else:
        # graded toward both faces: symmetric thicknesses, thinnest at the faces
        thick = np.diff(edges)
        assert np.allclose(thick, thick[::-1], rtol=1e-12)
        if n > 2:
            assert thick[0] < thick[n // 2]


def test_unknown_spacing_is_refused():
    with pytest.raises(ThermalError, match="spacing"):
        _wall(4, spacing="log")


@pytest.mark.parametrize("spacing", thermal.annulus.SPACINGS)
@pytest.mark.parametrize("n", [1, 3, 8, 16])
def test_steady_conduction_is_the_thick_walled_cylinder(n, spacing):
    # inner face held at the chamber by a huge contact, outer face fed 1 W: the steady rise
    # of the outer face over the inner one is 1 W / (2 pi k h / ln(r_o/r_i)) + 1 W / G_c
    g_c = 50.0
    wall = _wall(n, inner_contacts={"chamber": g_c}, outer_contacts={"heater": g_c},
                 spacing=spacing)
    net = Network(wall.nodes() + (Node("heater", 1.0, power_w=1.0),), wall.links())
    steady = net.steady_state(0.0)
    expected = 1.0 / wall.wall_conductance_w_per_k + 2.0 / g_c
    assert steady[net.index("heater")] == pytest.approx(expected, rel=1e-12)
    exact = 2 * math.pi * 0.25 * 0.01 / math.log(0.05 / 0.04)
    assert wall.wall_conductance_w_per_k == pytest.approx(exact, rel=1e-14)
    # the outer face's temperature (4): the heater's minus 1 W over its contact
    face = sum(w * steady[net.index(k)] if k != "chamber" else 0.0
               for k, w in wall.face_weights("outer").items())
    assert face == pytest.approx(steady[net.index("heater")] - 1.0 / g_c, rel=1e-12)


def test_massless_face_is_reduced_exactly():
    # the outer face touching two nodes: as an explicit node of tiny capacity it gives the
    # same steady state as the reduced links (3) and the same response to within what the
    # face's own capacity stores (C_face / sum G ~ 1e-6 s here: microkelvins)
    contacts = {"a": 0.3, "b": 0.7}
    wall = _wall(6, inner_contacts={"chamber": 2.0}, outer_contacts=contacts)
    others = (Node("a", 50.0, power_w=2.0), Node("b", 80.0))
    links = (Link("a", "chamber", 0.5), Link("b", "chamber", 0.4))
    reduced = Network(wall.nodes() + others, wall.links() + links)
    g_half = wall.half_shells_w_per_k[1]
    explicit_links = tuple(l for l in wall.links() if "a" not in (l.a, l.b)
                           and "b" not in (l.a, l.b))
    explicit = Network(
        wall.nodes() + others + (Node("face", 1e-6),),
        explicit_links + links + (Link("w_6", "face", g_half), Link("face", "a", 0.3),
                                  Link("face", "b", 0.7)))
    s1, s2 = reduced.steady_state(-10.0), explicit.steady_state(-10.0)
    for name in reduced.node_names:
        assert s1[reduced.index(name)] == pytest.approx(s2[explicit.index(name)], abs=1e-9)
    t = np.arange(0.0, 3600.0, 10.0)
    r1 = thermal.simulate(reduced, t, ambient_c=-10.0, initial_c=-10.0)
    r2 = thermal.simulate(explicit, t, ambient_c=-10.0, initial_c=-10.0)
    for name in reduced.node_names:
        np.testing.assert_allclose(r1.node(name), r2.node(name), atol=1e-5)
    face = sum(w * r1.node(k) for k, w in wall.face_weights("outer").items())
    np.testing.assert_allclose(face, r2.node("face"), atol=1e-5)


def test_adiabatic_face_and_energy_balance():
    wall = _wall(8, outer_contacts={"chamber": 1.0})
    assert wall.face_weights("inner") == {"w_1": 1.0}
    net = Network(wall.nodes(), wall.links())
    t = np.arange(0.0, 7200.0, 1.0)
    res = thermal.simulate(net, t, ambient_c=np.where(t < 600, 20.0, 30.0), initial_c=20.0)
    ledger = res.heat_in_j - res.stored_j - res.heat_lost_j
    assert np.max(np.abs(ledger)) <= 1e-9 * np.max(np.abs(res.stored_j))
    # the inner shell lags the outer one after the step (heat enters from outside)
    k = np.searchsorted(t, 700.0)
    assert res.node("w_8")[k] > res.node("w_1")[k]


def test_bad_geometry_is_refused():
    with pytest.raises(ThermalError, match="outer_radius_m .* must exceed"):
        _wall(4, outer_radius_m=0.03)
    with pytest.raises(ThermalError, match="n_layers must be an integer"):
        _wall(0)
    with pytest.raises(ThermalError, match="conductivity_w_per_m_k must be > 0"):
        _wall(4, conductivity_w_per_m_k=0.0)
    with pytest.raises(ThermalError, match="its own shell"):
        _wall(4, outer_contacts={"w_2": 1.0})
