"""The fibre-optic gyroscope: Earth-rate projection, effects and noise (docs/physics.md 3, 5)."""

from __future__ import annotations

import numpy as np

from ..constants import OMEGA_IE_DPH

__all__ = ["earth_rate_along_axis_dph"]


def earth_rate_along_axis_dph(azimuth_deg: np.ndarray, elevation_deg: np.ndarray,
                              latitude_deg: float) -> np.ndarray:
    """Omega_ie cos L cos A cos e + Omega_ie sin L sin e [deg/h] (docs/physics.md section 5).

    The Earth rate sensed by an axis of azimuth A (clockwise from north) and elevation e at
    latitude L; a north-pointing level axis reads +Omega_ie cos L.
    """
    lat = np.radians(latitude_deg)
    a = np.radians(azimuth_deg)
    e = np.radians(elevation_deg)
    return OMEGA_IE_DPH * (np.cos(lat) * np.cos(a) * np.cos(e) + np.sin(lat) * np.sin(e))
