"""Physical constants and the unit conversions of the package (one module, poliastro style).

Inside the package: time in s, temperature in degC, rates in deg/h, angles in deg at the
boundaries and rad inside the solvers, specific force in g.
"""

from __future__ import annotations

import math

__all__ = [
    "OMEGA_IE_DPH",
    "STANDARD_GRAVITY_M_S2",
    "T_REF_C",
    "ABSOLUTE_ZERO_C",
    "POSITION_TOL_DEG",
    "earth_rate_components_dph",
]

#: Omega_ie, the Earth's sidereal rotation rate [deg/h] (docs/physics.md section 5).
OMEGA_IE_DPH: float = 15.041067

#: Standard gravity g_n [m/s^2] (CGPM 1901), to convert m/s^2 to g.
STANDARD_GRAVITY_M_S2: float = 9.80665

#: Reference temperature of the effect library [degC] (docs/effects.md).
T_REF_C: float = 25.0

#: Absolute zero [degC]; a temperature below it is physically impossible.
ABSOLUTE_ZERO_C: float = -273.15


#: Turntable positions closer than this (modulo 360 deg) are one position [deg]: the
#: tolerance of the recorded ``position_deg`` when dwells are grouped and segmented, and of
#: the positions a scenario writes.
POSITION_TOL_DEG: float = 0.5


def earth_rate_components_dph(latitude_deg: float) -> tuple[float, float]:
    """Horizontal and vertical Earth rate: (Omega_ie cos L, Omega_ie sin L) [deg/h]."""
    lat = math.radians(latitude_deg)
    return OMEGA_IE_DPH * math.cos(lat), OMEGA_IE_DPH * math.sin(lat)
