"""A unit's measured runs and a model, worked as a chain: fit -> compare -> diagnose ->
apply -> design (:class:`UnitChain`), every step a frozen result that saves itself as JSON.

- :mod:`~nfs.unit.chain`: :class:`UnitChain`;
- :mod:`~nfs.unit.applied`: what adding an effect did (:class:`Applied`).

The results of the other steps live where they are made: :class:`nfs.fit.FitResult`,
:class:`nfs.comparison.Comparison`, :class:`nfs.rivals.Finding` (the diagnosis with the
settlement of its tie), :class:`nfs.design.Design`.
"""

from .applied import Applied
from .chain import UnitChain

__all__ = ["UnitChain", "Applied"]
