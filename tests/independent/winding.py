"""The wound fibre coil of the independent generator: Shupe weights from the winding itself.

A time-varying temperature along the fibre reaches the two counter-propagating waves at
different times, except at the coil's midpoint (Shupe 1980, Appl. Opt. 19(5) 654, eq. (5));
divided by the Sagnac scale factor 2 pi L D / (lambda c) the equivalent rate is

    Omega = K int_0^L dT/dt(z, t) (2z - L) dz,   K = n (dn/dT + n alpha) / (L D)   [rad/s]

(Lefevre, The Fiber-Optic Gyroscope, 2nd ed., 2014, sec. 3.3.3).  The fibre lies in N optical
layers, each at one radius, so the integral is a sum over layers, Omega = K sum_j W_j
dT_j/dt with W_j = int over layer j's fibre of (2z - L) dz [m^2]; the winding pattern decides
which stretch of fibre each layer holds (:func:`layer_weights_m2`).

The thermal model knows the temperature at a few radii only (its thermal layers' nodes and
the coil's two faces); the rate at each optical layer's radius is interpolated across the
radius through those points (:func:`interpolation_matrix`), so the weight each thermal point
carries is sum_j W_j M_jk, the optical weights it holds shared by the interpolation.  A cubic
spline, not straight lines: a quadrupole's residual is a sum of second differences weighted
by the layer's distance from the fibre's midpoint, so the kinks of a piecewise-linear field
alias into it according to where they fall in an ABBA block (one physical coil, a quadrupole
of 48 layers, RMS of its 160 s means over the first hour after a power-on at -32 C: 8
against 16 cosine-graded thermal layers differ by 35-37 % with straight lines).  Thermal
layers graded toward both faces (:func:`thermal_layer_edges_m`, ``cosine``) put points where
the field bends, at the faces where heat enters and leaves and the fibre's ends lie.  The
gyro's sample is the interval mean of this rate (:func:`generator.interval_mean_rate`), not
its value at an instant: at power-on the heat flux through the outer face steps, and the
face layers answer within their time constants (below a second when fine), so a rate taken
at the instants depended on the grid through where that spike fell between samples.  With
both, measured on drawn units' coils (``test_winding.py``; seeds 1, 3, 5, 7, starts at -32
and +54 C): 8 against 16 layers -0.25 to +0.01 % (quadrupole), +0.9 to +1.7 % (dipole);
16 against 32 +0.7 to +1.0 % and +0.24 to +0.47 %.  An octupole's residual, a third
difference of the profile, needs 16 layers: 8 against 16 -22 %, 16 against 32 +2.4 %.

Imports nothing from ``nfs`` or ``thermal`` (NumPy and SciPy only).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

__all__ = ["PATTERNS", "PERIOD", "SPACINGS", "pattern_sequence", "layer_weights_m2",
           "thermal_layer_edges_m", "interpolation_matrix", "Winding", "RAD_S_TO_DPH"]

#: Winding patterns: wound from one end (helical) or from the fibre's midpoint, its halves A
#: and B laid on the layers in the pattern's order.
PATTERNS = ("helical", "dipole", "quadrupole", "octupole")
#: The midpoint patterns' repeating blocks (Frigo 1983, Proc. SPIE 412 268; Mohr 1996,
#: J. Lightwave Technol. 14(1) 27): AB, ABBA, ABBABAAB.
_BLOCK = {"dipole": "AB", "quadrupole": "ABBA", "octupole": "ABBABAAB"}
#: Layers in one repeating block of each pattern (a whole coil is a number of blocks).
PERIOD = {"helical": 1, "dipole": 2, "quadrupole": 4, "octupole": 8}
#: Radial spacings of the thermal layers.
SPACINGS = ("equal", "cosine")
#: 1 rad/s in deg/h.
RAD_S_TO_DPH = 180.0 / math.pi * 3600.0


def pattern_sequence(pattern: str, n_layers: int) -> str:
    """The half (A or B) each layer holds, spool side first, e.g. ``ABBAABBA`` for a
    quadrupole of 8 layers; a helical coil (one fibre end to the other) is ``H`` * N."""
    if pattern not in PATTERNS:
        raise ValueError(f"unknown winding pattern {pattern!r}; valid: {', '.join(PATTERNS)}")
    if n_layers < 1:
        raise ValueError(f"a winding needs at least one layer, got {n_layers}")
    if pattern == "helical":
        return "H" * n_layers
    block = _BLOCK[pattern]
    return (block * (n_layers // len(block) + 1))[:n_layers]


def layer_weights_m2(pattern: str, layer_lengths_m) -> np.ndarray:
    """W_j = int over layer j's fibre of (2z - L) dz [m^2], spool side first.

    A stretch [z1, z2] of fibre weighs int (2z - L) dz = (z2 - z1)(z2 + z1 - L).  Helical:
    layer j holds the next stretch from z = 0.  Midpoint patterns: half A occupies
    [0, L_A], wound from its end at the midpoint z = L_A toward z = 0, half B [L_A, L] from
    the midpoint toward z = L, each layer taking the next stretch of its half in the order of
    :func:`pattern_sequence` (L_A the total length of the A layers).  With equal layers of l
    the m-th layer of A weighs -(2m - 1) l^2, of B +(2m - 1) l^2, a helical layer j
    (2j - 1 - N) l^2; sum_j W_j = 0 for every pattern (the whole integral of 2z - L).
    ``layer_lengths_m``: fibre length of each layer [m].
    """
    length = np.asarray(layer_lengths_m, dtype=float)
    seq = pattern_sequence(pattern, length.size)
    total = float(length.sum())

    def stretch(z1, z2):
        return (z2 - z1) * (z2 + z1 - total)

    w = np.empty(length.size)
    if pattern == "helical":
        z = np.concatenate([[0.0], np.cumsum(length)])
        return stretch(z[:-1], z[1:])
    mid = float(sum(lj for lj, s in zip(length, seq) if s == "A"))
    used = {"A": 0.0, "B": 0.0}
    for j, (lj, s) in enumerate(zip(length, seq)):
        if s == "A":
            w[j] = stretch(mid - used["A"] - lj, mid - used["A"])
        else:
            w[j] = stretch(mid + used["B"], mid + used["B"] + lj)
        used[s] += lj
    return w


def thermal_layer_edges_m(r_in_m: float, r_out_m: float, n_layers: int,
                          spacing: str = "equal") -> np.ndarray:
    """The n + 1 radii between the coil's thermal layers, r_in first [m].

    ``equal``: r_k = r_in + (r_out - r_in) k / n.  ``cosine``: graded toward both faces,
    r_k = r_in + (r_out - r_in) (1 - cos(pi k / n)) / 2 (the Chebyshev-Lobatto points: thin
    shells where heat enters and leaves, so few nodes resolve the faces' gradients; Trefethen,
    Spectral Methods in MATLAB, 2000, ch. 5).
    """
    if spacing not in SPACINGS:
        raise ValueError(f"unknown layer spacing {spacing!r}; valid: {', '.join(SPACINGS)}")
    k = np.arange(n_layers + 1) / n_layers
    frac = k if spacing == "equal" else 0.5 * (1.0 - np.cos(np.pi * k))
    return r_in_m + (r_out_m - r_in_m) * frac


def interpolation_matrix(x_points, x_at, kind: str = "spline") -> np.ndarray:
    """M (len(x_at), len(x_points)): f(x_at) = M f(x_points) (``x_points`` increasing).

    ``spline``: the not-a-knot cubic spline through the points (de Boor, A Practical Guide to
    Splines, 1978, ch. IV; scipy's CubicSpline), straight lines for fewer than four points;
    ``linear``: straight lines between neighbours.  Both are linear in the values, so M is
    the interpolant of each unit vector.
    """
    xp = np.asarray(x_points, dtype=float)
    eye = np.eye(xp.size)
    if kind == "linear" or xp.size < 4:
        return np.column_stack([np.interp(x_at, xp, eye[:, k]) for k in range(xp.size)])
    if kind != "spline":
        raise ValueError(f"unknown interpolation {kind!r}; valid: spline, linear")
    return CubicSpline(xp, eye)(np.asarray(x_at, dtype=float))


@dataclass(frozen=True)
class Winding:
    """How the fibre lies in the coil: pattern, optical layers, fibre and its glass.

    The optical layers fill the winding's radial thickness evenly, layer j at
    r_in + (j + 1/2) (r_out - r_in) / N, each with the same number of turns, so its fibre
    length is proportional to its radius (they add up to ``fibre_length_m``).
    """

    pattern: str = "quadrupole"
    """One of :data:`PATTERNS`, wound from the spool."""
    n_layers: int = 48
    """N, optical layers (a whole number of the pattern's blocks, :data:`PERIOD`)."""
    fibre_length_m: float = 1000.0
    """L [m]."""
    index: float = 1.45
    """n, the fibre's effective index (fused silica at 1550 nm; Malitson 1965)."""
    dn_dt_per_k: float = 1.0e-5
    """dn/dT of fused silica [1/K] (Leviton and Frey 2006)."""
    expansion_per_k: float = 5.5e-7
    """alpha, thermal expansion of fused silica [1/K]."""

    def radii_m(self, r_in_m: float, r_out_m: float) -> np.ndarray:
        """Radius of each optical layer, spool side first [m]."""
        return r_in_m + (np.arange(self.n_layers) + 0.5) * (r_out_m - r_in_m) / self.n_layers

    def lengths_m(self, r_in_m: float, r_out_m: float) -> np.ndarray:
        """Fibre length of each optical layer [m] (equal turns: proportional to radius)."""
        r = self.radii_m(r_in_m, r_out_m)
        return self.fibre_length_m * r / r.sum()

    def weights_m2(self, r_in_m: float, r_out_m: float) -> np.ndarray:
        """W_j of each optical layer [m^2] (:func:`layer_weights_m2`)."""
        return layer_weights_m2(self.pattern, self.lengths_m(r_in_m, r_out_m))

    def k_dph(self, r_in_m: float, r_out_m: float) -> float:
        """K = n (dn/dT + n alpha) / (L D) with D = r_in + r_out, the mean diameter, in
        deg/h per (K/s m^2): Omega [deg/h] = K sum_j W_j [m^2] dT_j/dt [K/s]."""
        d_m = r_in_m + r_out_m
        k = self.index * (self.dn_dt_per_k + self.index * self.expansion_per_k) / (
            self.fibre_length_m * d_m)
        return k * RAD_S_TO_DPH

    def point_weights_m2(self, r_in_m: float, r_out_m: float, radii_points_m,
                         kind: str = "spline") -> np.ndarray:
        """The weight each thermal point carries [m^2]: sum_j W_j M_jk with M the
        interpolation (:func:`interpolation_matrix`) from the points (``radii_points_m``,
        increasing: the spool face, the thermal layers' nodes, the outer face) to the
        optical layers' radii."""
        m = interpolation_matrix(radii_points_m, self.radii_m(r_in_m, r_out_m), kind)
        return self.weights_m2(r_in_m, r_out_m) @ m
