"""Lumped thermal network of the north finder, independent of gyros (physics.md section 2).

Build a :class:`Network` of :class:`Node` and :class:`Link` objects, then :func:`simulate`
it exactly over sample intervals of held input; the :class:`ThermalResult` labels every
node and carries the energy bookkeeping.
"""

from thermal.network import CHAMBER, Link, Network, Node
from thermal.solve import ThermalResult, simulate

__all__ = ["CHAMBER", "Node", "Link", "Network", "simulate", "ThermalResult"]
