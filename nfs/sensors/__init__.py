"""Sensors and turntable: FOG, quartz accelerometers, thermometers, indexing schedule."""

from .fog import earth_rate_along_axis_dph
from .thermometer import ThermometerModel, quantize, thermometer_reading
from .turntable import ORDERS, Schedule, axis_elevation_deg, turntable_motion

__all__ = [
    "earth_rate_along_axis_dph", "ThermometerModel", "quantize", "thermometer_reading",
    "ORDERS", "Schedule", "axis_elevation_deg", "turntable_motion",
]
