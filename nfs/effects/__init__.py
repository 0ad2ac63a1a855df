"""Named physical effects: the registry and the built-in library (docs/effects.md)."""

from .context import CoilLayout, EffectContext
from .registry import (KINDS, EffectInstance, EffectSpec, Parameter, available_effects,
                       get_effect, load_effects_file, make_effect, register_effect)
from . import accelerometer, gyro, thermal, thermometer, winding  # noqa: F401  (built-ins)
from .geometry import Geometry, apply_geometry, check_geometry

__all__ = [
    "KINDS", "CoilLayout", "EffectContext", "EffectInstance", "EffectSpec", "Parameter",
    "Geometry", "apply_geometry", "check_geometry", "available_effects", "get_effect", "load_effects_file", "make_effect", "register_effect",
]
