"""The Shupe integral over a wound coil: winding patterns, layer weights, ``shupe_winding``.

A light wave and its counter-propagating twin cross the point z of a fibre of length L at
times that differ by (2z - L) n / c, so a temperature that changes along the fibre leaves a
non-reciprocal phase, and the gyro reads the rate (Shupe 1980, Appl. Opt. 19(5) 654, eq. (5);
Lefevre, The Fiber-Optic Gyroscope, 2nd ed. 2014, sec. 3.3.3)

    Omega_e(t) = n (dn/dT + n alpha) / (L D) int_0^L dT/dt(z, t) (2z - L) dz      [rad/s]  (1)

(n the fibre's index, dn/dT its thermo-optic coefficient, alpha its expansion, D the coil's
mean diameter; the Sagnac phase 2 pi L D Omega / (lambda c) turns the phase into a rate).
A coil is wound in N layers; the fibre of layer j is at one radius, so (1) is a sum over
layers with the weight of each,

    Omega_e = K sum_j W_j dT_j/dt,    K = n (dn/dT + n alpha) / (L D),
    W_j = int over layer j's fibre of (2z - L) dz  [m^2],                                (2)

and the winding pattern decides which stretch of fibre each layer holds.  Wound from the
spool, the fibre's midpoint z = L/2 lies on the first layer and its two halves, A (towards
z = 0) and B (towards z = L), are laid on the layers in the pattern's order: AB.. (dipole),
ABBA.. (quadrupole), ABBABAAB.. (octupole, a quadrupole followed by its reverse), or a
user's own sequence; helical winds the fibre from z = 0 at the spool to z = L outside.  With
equal layers of fibre l = L / N, the m-th layer of half A holds z - L/2 in [-m l, -(m-1) l]
and weighs -(2m - 1) l^2, the m-th of half B +(2m - 1) l^2, and a helical layer j weighs
(2j - 1 - N) l^2.  Every pattern has sum_j W_j = 0 (a uniform heating rate cancels); for a
rate that grows by g per layer, dT_j/dt = j g, the residual sum_j W_j j g is N (N^2 - 1)/6,
N^2/4, -N/2 and 0 l^2 g (helical, dipole, quadrupole, octupole: Frigo 1983, Proc. SPIE 412,
268; Lefevre 2014 sec. 3.3.3); for a smooth rate field over x = (r - r_i)/(r_o - r_i) the
quadrupole's residual tends to -(l^2 / 2) d(dT/dt)/dx at the outer face x = 1, where the
fibre's ends are: a quadrupole answers to the rate of the radial gradient at its outer face.

The elasto-optic term.  A coil potted in a compound that strains the fibre as it heats adds
to dn/dT an effective stress-optic coefficient k_m with the same weighting (Mohr 1996,
J. Lightwave Technol. 14(1) 27), whose size follows the potting's modulus, which changes with
temperature (stiffer when cold): k_m (1 + c_m (T_coil - T_ref)), T_coil the fibre's mean
temperature.  The asymmetry.  A winding whose midpoint lies L_a / 2 of fibre away from its
place (an effective asymmetric length L_a [m], the difference between the halves' lengths)
shifts every weight by L_a l_j: W'_j = W_j + L_a l_j, sum_j W'_j = L_a L, so a uniform rate
no longer cancels.  Together:

    Omega_e = n [dn/dT + n alpha + k_m (1 + c_m (T_coil - T_ref))] / (L D)
              sum_j W'_j dT(x_j)/dt                                              [rad/s]  (3)

The coil's thermal layers (N_th, a few nodes of the network, :class:`thermal.Annulus`) are
not its optical layers (N_opt, dozens): the rate field of the thermal layers is interpolated
onto the optical layers' mid-radii x_j = (j - 1/2)/N_opt by a cubic spline through the
layers' temperatures at their mid-radii and the two face temperatures, whose slope at each
face is the heat flux the network carries through it (Fourier's law: the face's half shell,
:class:`CoilLayout`).  A spline, not straight lines: the quadrupole's residual is a sum of
second differences weighted by the distance from the fibre's midpoint, so the kinks of a
piecewise-linear field alias into it (a ramped slab coil in 8 layers gives half the
integrated error with straight lines, the right one within 0.1 % with the spline).  Two
lumped coil nodes ("outer layers", "inner layers", no faces) are the line through their
rates at x = 3/4 and 1/4, on which (3) is exactly ``shupe_gradient`` plus ``shupe_stress``
with k_r = n (dn/dT + n alpha) sum_j W_j x_j / (L D (x_o - x_i)) and k_m alike (the
two-layer case, checked to 1e-9 by the tests).

Each optical layer is taken to hold the same length of fibre, L / N_opt (the closed forms'
idealisation; a real layer's length grows with its radius, by r_o / r_i across the coil),
and only radial gradients are seen (the thermal layers have no axial split).
"""

from __future__ import annotations

import functools
import math
import numpy as np
from scipy.interpolate import CubicSpline

from ..errors import EffectError
from .context import CoilLayout, EffectContext
from .gyro import STRESS_GRID, stress_factor_bounds
from .registry import Parameter, register_effect

__all__ = ["PATTERNS", "CoilLayout", "layer_sequence", "layer_weights", "optical_layer_map",
           "winding_node_weights", "shupe_winding", "DPH_PER_RAD_PER_S"]

#: The named winding patterns (module docstring); a string of ``A`` and ``B`` is a user's own.
PATTERNS = ("helical", "dipole", "quadrupole", "octupole")

#: The repeating unit of each pattern wound from the midpoint (helical has none).
_UNITS = {"dipole": "AB", "quadrupole": "ABBA", "octupole": "ABBABAAB"}

#: 1 rad/s in deg/h: (180 / pi) * 3600.
DPH_PER_RAD_PER_S = 180.0 / math.pi * 3600.0


def layer_sequence(pattern: str, n_layers: int) -> str | None:
    """Which half of the fibre (``A`` or ``B``) each layer holds, spool first; None for
    ``helical`` (wound from one end).

    A named pattern repeats its unit (``AB``, ``ABBA``, ``ABBABAAB``) and needs a multiple
    of its length; a user's sequence of ``A`` and ``B`` repeats too (its length must divide
    ``n_layers``).  Both halves must hold the same number of layers (equal halves, L / 2).
    """
    n = _count(n_layers)
    if pattern == "helical":
        return None
    unit = _UNITS.get(pattern, pattern)
    if not isinstance(unit, str) or not unit or set(unit) - {"A", "B"}:
        raise EffectError(f"winding pattern {pattern!r} is none of {', '.join(PATTERNS)} "
                          "and not a sequence of A and B (e.g. 'ABBA')")
    if n % len(unit):
        raise EffectError(f"winding pattern {pattern!r} repeats every {len(unit)} layers; "
                          f"{n} layers is not a multiple")
    seq = unit * (n // len(unit))
    if seq.count("A") != seq.count("B"):
        raise EffectError(f"winding pattern {pattern!r} puts {seq.count('A')} layers on half "
                          f"A and {seq.count('B')} on half B over {n} layers: the halves of a "
                          "fibre wound from its midpoint have equal lengths")
    return seq


def _count(n_layers) -> int:
    if isinstance(n_layers, bool) or not float(n_layers).is_integer() or n_layers < 1:
        raise EffectError(f"a coil needs a whole number of layers >= 1, got {n_layers!r}")
    return int(n_layers)


@functools.lru_cache(maxsize=64)
def layer_weights(pattern: str, n_layers: int, length_m: float = 1.0) -> np.ndarray:
    """W_j of (2) [m^2], spool first, for ``n_layers`` equal layers of a fibre of
    ``length_m`` wound in ``pattern`` (read-only; module docstring for the closed forms)."""
    n = _count(n_layers)
    l2 = (float(length_m) / n) ** 2
    seq = layer_sequence(pattern, n)
    if seq is None:
        j = np.arange(1, n + 1)
        w = l2 * (2 * j - 1 - n)
    else:
        halves = np.frombuffer(seq.encode(), dtype=np.uint8) == ord("B")
        w = np.empty(n)
        for is_b in (False, True):
            rows = np.flatnonzero(halves == is_b)
            m = np.arange(1, rows.size + 1)
            w[rows] = (1.0 if is_b else -1.0) * (2 * m - 1) * l2
    w = w.astype(float)
    w.flags.writeable = False
    return w


@functools.lru_cache(maxsize=32)
def optical_layer_map(layout: CoilLayout, n_optical: int) -> np.ndarray:
    """P, shape (n_optical, len(layout.nodes)): T(x_j) = sum_i P[j, i] T_i, the field at the
    optical layers' mid-radii x_j = (j - 1/2) / n_optical as weights on the layout's nodes
    (module docstring: a cubic spline through the layers and faces, its end slopes the
    faces' fluxes; without faces the not-a-knot spline through the layers).  Read-only."""
    n_opt = _count(n_optical)
    x_opt = (np.arange(n_opt) + 0.5) / n_opt
    index = {name: i for i, name in enumerate(layout.nodes)}
    m = len(layout.nodes)
    # the knots' values as rows of node weights
    knots_x, knots = [], []
    if layout.inner_face is not None:
        knots_x.append(0.0)
        knots.append(_weights_row(layout.inner_face, index, m))
    for name, x in zip(layout.layers, layout.centres):
        knots_x.append(x)
        row = np.zeros(m)
        row[index[name]] = 1.0
        knots.append(row)
    if layout.outer_face is not None:
        knots_x.append(1.0)
        knots.append(_weights_row(layout.outer_face, index, m))
    xk, values = np.asarray(knots_x), np.asarray(knots)         # (n_k,), (n_k, m)
    if len(xk) == 2:                      # two knots: the line through them (extrapolated)
        slope = (values[1] - values[0]) / (xk[1] - xk[0])
        out = values[0] + np.outer(x_opt - xk[0], slope)
    else:
        bc: list = ["not-a-knot", "not-a-knot"]
        if layout.inner_face is not None:   # the face's flux: slope between face and layer
            bc[0] = (1, (values[1] - values[0]) / (xk[1] - xk[0]))
        if layout.outer_face is not None:
            bc[1] = (1, (values[-1] - values[-2]) / (xk[-1] - xk[-2]))
        # the spline is linear in its values and end slopes, so splining the node-weight
        # columns at once gives the weights of the field on the nodes
        out = CubicSpline(xk, values, axis=0, bc_type=tuple(bc))(x_opt)
    out = np.ascontiguousarray(out)
    out.flags.writeable = False
    return out


def _weights_row(weights, index: dict[str, int], m: int) -> np.ndarray:
    row = np.zeros(m)
    for name, w in weights:
        row[index[name]] += w
    return row


def winding_node_weights(layout: CoilLayout, pattern: str, n_optical: int, length_m: float,
                         asymmetric_length_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(w, t) on ``layout.nodes``: sum_j W'_j dT(x_j)/dt = sum_i w_i dT_i/dt [m^2 K/s] and
    the fibre's mean temperature T_coil = sum_i t_i T_i (equal layers: the mean over j of
    T(x_j)); W'_j = W_j + L_a l_j of (3)."""
    p = optical_layer_map(layout, n_optical)
    w = layer_weights(pattern, n_optical, length_m) + asymmetric_length_m * length_m / n_optical
    return w @ p, p.mean(axis=0)


def _check_shupe_winding(params: dict) -> None:
    layer_sequence(params["pattern"], params["N_opt"])


@register_effect("shupe_winding", kind="gyro", check=_check_shupe_winding, parameters=[
    Parameter("L", "m", "fibre length", default=1000.0, shape=True, bounds=(1.0, 1e5),
              constant=True),
    Parameter("D", "m", "mean diameter of the winding", default=0.09, shape=True,
              bounds=(0.005, 2.0), constant=True),
    Parameter("pattern", "", "winding pattern: helical, dipole, quadrupole, octupole, or a "
              "sequence of A and B wound from the spool", type=str, default="quadrupole"),
    Parameter("N_opt", "", "optical layers of the winding", type=int, default=32,
              bounds=(1, 10000)),
    Parameter("n", "", "effective index of the fibre's mode", default=1.46, shape=True,
              bounds=(1.0, 2.0), constant=True),
    Parameter("dn_dT", "1/K", "thermo-optic coefficient dn/dT of the fibre", default=1.0e-5,
              shape=True, constant=True),
    Parameter("alpha", "1/K", "thermal expansion coefficient of the fibre", default=5.5e-7,
              shape=True, constant=True),
    Parameter("k_m", "1/K", "effective stress-optic coefficient of the potted winding at "
              "T_ref (Shupe-Mohr), added to dn/dT", default=0.0),
    Parameter("c_m", "1/K", "temperature coefficient of the stress term (potting modulus)",
              default=0.0, shape=True, bounds=stress_factor_bounds(), grid=STRESS_GRID),
    Parameter("L_asym", "m", "effective asymmetric length: half B's fibre minus half A's",
              default=0.0)])
def shupe_winding(ctx: EffectContext, *, L: float = 1000.0, D: float = 0.09,
                  pattern: str = "quadrupole", N_opt: int = 32, n: float = 1.46,
                  dn_dT: float = 1.0e-5, alpha: float = 5.5e-7, k_m: float = 0.0,
                  c_m: float = 0.0, L_asym: float = 0.0) -> np.ndarray:
    """The Shupe integral over the winding, eq. (3) of :mod:`nfs.effects.winding` [deg/h].

    Omega_e = n [dn/dT + n alpha + k_m (1 + c_m (T_coil - T_ref))] / (L D)
    sum_j (W_j + L_asym L / N_opt) dT(x_j)/dt, the rate field of the coil's thermal layers
    (:attr:`EffectContext.coil`) interpolated onto the N_opt optical layers.

    Parameters: L [m] fibre length (0.5-2 km in north finders), D [m] mean diameter
    (60-120 mm), pattern (helical, dipole, quadrupole, octupole or A/B), N_opt optical layers,
    n the mode's effective index (1.46), dn_dT [1/K] (fused silica 0.95-1.1e-5 /K at
    1550 nm: Leviton & Frey 2006, Proc. SPIE 6273, 62732K), alpha [1/K] (fused silica
    5.5e-7 /K), k_m [1/K] the potting's stress-optic coefficient at T_ref (Mohr 1996,
    J. Lightwave Technol. 14(1) 27), c_m [1/K] its temperature coefficient, L_asym [m].
    Sources: Shupe 1980 (Appl. Opt. 19(5) 654, eq. (5)); Frigo 1983 (Proc. SPIE 412, 268);
    Lefevre 2014 (The Fiber-Optic Gyroscope, 2nd ed., sec. 3.3.3).  Equal optical layers and
    radial gradients only (module docstring).
    """
    layout = ctx.coil
    lo, hi = stress_factor_bounds(ctx.t_ref_c)
    if not lo <= c_m <= hi:
        raise EffectError(f"shupe_winding: c_m = {c_m:g} 1/K flips the sign of 1 + c_m "
                          f"(T_coil - T_ref) inside the operating range at T_ref = "
                          f"{ctx.t_ref_c:g} C (allowed {lo:.6g}..{hi:.6g})")
    w, t = winding_node_weights(layout, pattern, N_opt, L, L_asym)
    index = {name: i for i, name in enumerate(ctx.node_names)}
    w_all, t_all = np.zeros(len(index)), np.zeros(len(index))
    for name, wi, ti in zip(layout.nodes, w, t):
        if name not in index:
            _missing(name, ctx)
        w_all[index[name]], t_all[index[name]] = wi, ti
    rate = ctx.rate_c_per_s @ w_all                    # sum_j W'_j dT_j/dt [m^2 K/s]
    coef = dn_dT + n * alpha
    if k_m != 0.0:
        coef = coef + k_m * (1.0 + c_m * (ctx.temperature_c @ t_all - ctx.t_ref_c))
    return (n / (L * D) * DPH_PER_RAD_PER_S) * coef * rate


def _missing(name: str, ctx: EffectContext) -> int:
    raise EffectError(f"shupe_winding: the coil's node '{name}' is not in the network; "
                      f"nodes: {', '.join(ctx.node_names)}")
