"""Tests of thermal.network: validation, the matrices of equation (1), steady state, time constants.

Oracles: equation (1) of docs/physics.md section 2 written out by hand for one and two nodes, and
the closed-form eigenvalues of a 2x2 matrix.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from thermal import ThermalError
from thermal import CHAMBER, Link, Network, Node


def two_nodes() -> Network:
    """a (C 100, 1 W) to chamber 0.5 W/K, a to b (C 50) 0.2 W/K."""
    return Network((Node("a", 100.0, 1.0), Node("b", 50.0)),
                   (Link("a", CHAMBER, 0.5), Link("a", "b", 0.2)))


# --- validation: a non-physical network raises ThermalError naming the culprit -------------

@pytest.mark.parametrize("capacity", [-1.0, 0.0, math.nan, math.inf])
def test_bad_capacity_names_node(capacity):
    with pytest.raises(ThermalError, match="'coil_inner'.*capacity_j_per_k"):
        Node("coil_inner", capacity)


def test_bad_power_names_node():
    with pytest.raises(ThermalError, match="'board'.*power_w"):
        Node("board", 250.0, math.nan)


@pytest.mark.parametrize("conductance", [-0.1, math.nan, math.inf])
def test_bad_conductance_names_link(conductance):
    with pytest.raises(ThermalError, match="'coil_outer'-'coil_inner'.*conductance_w_per_k"):
        Link("coil_outer", "coil_inner", conductance)


def test_unknown_node_in_link_names_it_and_lists_valid_nodes():
    with pytest.raises(ThermalError, match="unknown node 'qfa_z'; valid nodes: 'a', 'b'"):
        Network((Node("a", 1.0), Node("b", 1.0)), (Link("a", "qfa_z", 1.0),))


def test_duplicate_node_name():
    with pytest.raises(ThermalError, match="duplicate node name 'housing'"):
        Network((Node("housing", 1.0), Node("housing", 2.0)), ())


@pytest.mark.parametrize("end", ["a", CHAMBER])
def test_link_to_itself(end):
    with pytest.raises(ThermalError, match=f"'{end}' to itself"):
        Link(end, end, 1.0)


def test_chamber_is_reserved():
    with pytest.raises(ThermalError, match="reserved"):
        Node(CHAMBER, 1.0)


def test_empty_network():
    with pytest.raises(ThermalError, match="no nodes"):
        Network((), ())


def test_index_of_unknown_node_lists_valid_names():
    net = two_nodes()
    assert net.index("b") == 1
    with pytest.raises(ThermalError, match="unknown node 'c'; valid nodes: 'a', 'b'"):
        net.index("c")


def test_lists_become_tuples():
    net = Network([Node("a", 1.0)], [Link("a", CHAMBER, 1.0)])
    assert isinstance(net.nodes, tuple) and isinstance(net.links, tuple)


# --- matrices: equation (1) by hand ------------------------------------------------------

def test_matrices_two_nodes_by_hand():
    """100 dTa/dt = 0.5 (Tamb - Ta) + 0.2 (Tb - Ta) + Pa;  50 dTb/dt = 0.2 (Ta - Tb) + Pb."""
    a, b = two_nodes().matrices()
    np.testing.assert_allclose(a, [[-0.7 / 100, 0.2 / 100], [0.2 / 50, -0.2 / 50]], rtol=1e-15)
    np.testing.assert_allclose(b, [[0.5 / 100, 1 / 100, 0.0], [0.0, 0.0, 1 / 50]], rtol=1e-15)


def test_kept_matrices_are_handed_out_as_copies():
    # Invariant: the network keeps its matrices once made; what a caller does to the arrays
    # it was given does not reach the network (a frozen value) or the next caller.
    net = two_nodes()
    a0, b0 = net.matrices()
    l0, g0 = net.conductances()
    for m in (*net.matrices(), *net.conductances()):
        m *= 2.0
    np.testing.assert_array_equal(net.matrices()[0], a0)
    np.testing.assert_array_equal(net.matrices()[1], b0)
    np.testing.assert_array_equal(net.conductances()[0], l0)
    np.testing.assert_array_equal(net.conductances()[1], g0)
    assert net.matrices()[0] is not net.matrices()[0]


def test_parallel_links_add():
    one = Network((Node("a", 3.0),), (Link("a", CHAMBER, 0.75),))
    two = Network((Node("a", 3.0),), (Link("a", CHAMBER, 0.5), Link(CHAMBER, "a", 0.25)))
    np.testing.assert_allclose(two.matrices()[0], one.matrices()[0], rtol=1e-15)


# --- steady state and time constants -----------------------------------------------------

def test_steady_state_two_nodes_by_hand():
    """All power leaves through a-chamber, Pb through a-b: Ta = Tamb + (Pa + Pb) / 0.5,
    Tb = Ta + Pb / 0.2."""
    net = two_nodes()
    np.testing.assert_allclose(net.steady_state(20.0), [22.0, 22.0], rtol=1e-14)
    np.testing.assert_allclose(net.steady_state(20.0, [0.0, 0.5]), [23.0, 25.5], rtol=1e-14)


def test_steady_state_of_floating_node_raises():
    net = Network((Node("a", 1.0), Node("b", 1.0)),
                  (Link("a", CHAMBER, 1.0), Link("a", "b", 0.0)))
    with pytest.raises(ThermalError, match="'b'"):
        net.steady_state(20.0)


def test_time_constant_one_node_is_c_over_g():
    net = Network((Node("a", 3500.0),), (Link("a", CHAMBER, 2.2),))
    np.testing.assert_allclose(net.time_constants_s(), [3500.0 / 2.2], rtol=1e-14)


def test_time_constants_two_nodes_closed_form():
    """Eigenvalues of the 2x2 A: (tr -+ sqrt(tr^2 - 4 det)) / 2; tau = -1/lambda."""
    a = [[-0.7 / 100, 0.2 / 100], [0.2 / 50, -0.2 / 50]]
    tr, det = a[0][0] + a[1][1], a[0][0] * a[1][1] - a[0][1] * a[1][0]
    disc = math.sqrt(tr * tr - 4 * det)
    expected = [-2 / (tr + disc), -2 / (tr - disc)]          # longest first
    np.testing.assert_allclose(two_nodes().time_constants_s(), expected, rtol=1e-12)


def test_floating_node_has_infinite_time_constant():
    net = Network((Node("a", 1.0), Node("b", 2.0)), (Link("a", "b", 1.0),))
    taus = net.time_constants_s()
    assert math.isinf(taus[0])
    np.testing.assert_allclose(taus[1], 1 / (1.0 / 1 + 1.0 / 2), rtol=1e-12)
