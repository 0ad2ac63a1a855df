"""Thermal networks shared by the thermal solver tests."""

from thermal import CHAMBER, Link, Network, Node


def seven_nodes() -> Network:
    """The representative north finder of benchmarks/bench_thermal.py."""
    nodes = (Node("housing", 3500.0), Node("electronics", 200.0, 3.0),
             Node("board", 250.0, 5.0), Node("coil_outer", 70.0), Node("coil_inner", 140.0),
             Node("qfa_x", 45.0, 0.45), Node("qfa_y", 45.0, 0.45))
    links = (Link("housing", CHAMBER, 2.2), Link("electronics", "housing", 1.0),
             Link("board", "housing", 1.5), Link("coil_outer", "housing", 0.8),
             Link("coil_outer", "coil_inner", 0.25), Link("electronics", "coil_outer", 0.3),
             Link("qfa_x", "housing", 0.5), Link("qfa_y", "housing", 0.5))
    return Network(nodes, links)
