"""Lumped thermal network of the north finder, independent of gyros (docs/physics.md section 2).

Build a :class:`Network` of :class:`Node` and :class:`Link` objects, then :func:`simulate`
it exactly over sample intervals of held input (or of a chamber linear between samples),
many runs of one network together with :func:`simulate_many` (or, streamed,
:func:`iter_simulate_many`), or only where a soak ends with :func:`final_temperature`;
the :class:`ThermalResult` labels every node and carries the energy bookkeeping.
:class:`Annulus` makes the nodes and links of a layered body (a thick-walled cylinder in
radial shells, conduction through cylindrical shells).
:func:`estimate_states` estimates the node temperatures from :class:`LinearSensor` readings
through the network (Kalman filter and smoother, thermal/estimate.py; the sensors and
records it reads in thermal/sensors.py).
"""

from importlib import import_module

from thermal.errors import ThermalError

#: Public name -> the module that defines it, loaded on first use (SPEC 1 lazy loading): the
#: error class alone (what nfs.errors needs) does not import SciPy.
_PUBLIC = {
    "CHAMBER": "thermal.network", "Node": "thermal.network", "Link": "thermal.network",
    "Network": "thermal.network", "simulate": "thermal.solve", "ThermalResult": "thermal.solve",
    "simulate_many": "thermal.batch", "iter_simulate_many": "thermal.batch",
    "final_temperature": "thermal.final", "Annulus": "thermal.annulus",
    **{name: "thermal.sensors" for name in ("LinearSensor", "ThermalRecord", "StatePower")},
    **{name: "thermal.estimate" for name in (
        "NodeEstimate", "ProcessNoiseFit", "StateEstimate", "kalman_smooth",
        "fit_process_noise", "estimate_states")},
}

__all__ = ["ThermalError", *_PUBLIC]


def __getattr__(name: str):
    """Load a public name from its module on first use (PEP 562)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'thermal' has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
