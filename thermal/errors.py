"""The thermal package's one error: a network that is not physical."""

__all__ = ["ThermalError"]


class ThermalError(ValueError):
    """A thermal network that is not physical (a negative capacity, an unknown node, an
    input of the wrong shape); the message names the node, link or argument."""
