"""FOG rate effects [deg/h] (docs/effects.md, "Gyro rate effects"; docs/physics.md section 3).

Each function returns the equivalent rate error it adds to the FOG output, one value per
sample, from an :class:`~nfs.effects.context.EffectContext`.  Temperature rates enter the
Shupe family per minute, as the literature quotes k_r and k_s in deg/h per K/min.
"""

from __future__ import annotations

import numpy as np

from ..constants import T_REF_C
from ..errors import EffectError
from .context import EffectContext
from .registry import Parameter, register_effect

__all__ = [
    "bias_temperature", "shupe_gradient", "shupe_rate", "shupe_product", "shupe_stress",
    "stress_factor_bounds", "STRESS_RANGE_C", "STRESS_GRID", "turn_on_transient", "aux_linear", "scale_factor_temperature", "magnetic",
    "polarization_ripple",
]

_S_PER_MIN = 60.0

_NODE = Parameter("node", "", "thermal node whose temperature drives the effect "
                  "(default: the coil, T_coil = (T_outer + T_inner)/2)", type=str, optional=True)


@register_effect("bias_temperature", kind="gyro", target="node", parameters=[
    Parameter("b1", "deg/h/K", "linear temperature coefficient of the bias"),
    Parameter("b2", "deg/h/K^2", "quadratic temperature coefficient of the bias", default=0.0),
    _NODE])
def bias_temperature(ctx: EffectContext, *, b1: float, b2: float = 0.0,
                     node: str | None = None) -> np.ndarray:
    """Static bias vs temperature: b1 (T_coil - T_ref) + b2 (T_coil - T_ref)^2 [deg/h].

    Parameters: b1 [deg/h/K], b2 [deg/h/K^2], node (default the coil mean).
    Reference: docs/physics.md section 3 (static bias, b1 0.0005-0.003 deg/h/K); the polynomial
    temperature model of IEEE Std 952-2020 Annex B (temperature sensitivity of bias).
    """
    dT = ctx.temperature(node) - ctx.t_ref_c
    return b1 * dT + b2 * dT * dT


@register_effect("shupe_gradient", kind="gyro", parameters=[
    Parameter("k_r", "deg/h per K/min", "Shupe coefficient of the radial gradient rate")])
def shupe_gradient(ctx: EffectContext, *, k_r: float) -> np.ndarray:
    """Shupe radial term: k_r d(T_coil_outer - T_coil_inner)/dt [deg/h], rate in K/min.

    The Shupe phase is proportional to the integral over the fibre of dT/dt(z, t) (2z - L)
    (Shupe 1980, Appl. Opt. 19(5) 654, eq. (5)); a quadrupole coil cancels a uniform heating
    rate, and the lumped remainder is the rate of the radial gradient between the outer and
    inner layers.  k_r [deg/h per K/min], 0.1-1 (docs/physics.md section 3, est.).
    """
    d_grad = ctx.rate(ctx.coil_outer) - ctx.rate(ctx.coil_inner)
    return k_r * _S_PER_MIN * d_grad


@register_effect("shupe_rate", kind="gyro", target="node", parameters=[
    Parameter("k_s", "deg/h per K/min", "effective Shupe coefficient of winding imperfection"),
    _NODE])
def shupe_rate(ctx: EffectContext, *, k_s: float, node: str | None = None) -> np.ndarray:
    """Shupe winding-imperfection term: k_s dT_coil/dt [deg/h], rate in K/min.

    An imperfect (asymmetric) winding leaves a residue of the Shupe integral proportional to
    the mean heating rate (Shupe 1980, eq. (5); Mohr 1996, J. Lightwave Technol. 14(1) 27).
    k_s [deg/h per K/min]; node defaults to the coil mean.
    """
    return k_s * _S_PER_MIN * ctx.temperature_rate(node)


@register_effect("shupe_product", kind="gyro", target="node", parameters=[
    Parameter("k_p", "deg/h per K*K/min", "temperature dependence of the Shupe coefficient"),
    _NODE])
def shupe_product(ctx: EffectContext, *, k_p: float, node: str | None = None) -> np.ndarray:
    """Shupe-Mohr thermal stress: k_p (T_coil - T_ref) dT_coil/dt [deg/h], rate in K/min.

    The thermal-stress (elasto-optic) Shupe term scales with the potting modulus, which
    changes with temperature; to first order this gives the T x dT/dt interaction that Cheng
    et al. (Sensors 2015, 15, 11189, eq. (6)-(8), "temperature product term") uses as an input.
    Mohr 1996 (J. Lightwave Technol. 14(1) 27) for the stress-induced term.
    k_p [deg/h per K*K/min]; node defaults to the coil mean.
    """
    return k_p * (ctx.temperature(node) - ctx.t_ref_c) * _S_PER_MIN * ctx.temperature_rate(node)


#: Coil temperatures over which the stress factor 1 + c_m (T_coil - T_ref) of
#: :func:`shupe_stress` must keep its sign [degC] (docs/effects.md: -40..60 C, the operating range).
STRESS_RANGE_C = (-40.0, 60.0)


#: The c_m [1/K] the diagnosis tries for the stress term's temperature coefficient, inside
#: the sign-keeping bounds (-1/35, 1/65 at T_ref = 25 C); 0 would repeat the plain gradient
#: term (shupe_gradient, shupe_winding's k_m alone).
STRESS_GRID = (-0.02, -0.01, 0.01)


def stress_factor_bounds(t_ref_c: float = T_REF_C) -> tuple[float, float]:
    """The c_m [1/K] for which 1 + c_m (T - T_ref) >= 0 over :data:`STRESS_RANGE_C`.

    The factor is linear in T, so it keeps its sign over the range when it does at both
    ends: -1 / (T_max - T_ref) <= c_m <= 1 / (T_ref - T_min); (-1/35, 1/65) 1/K at
    T_ref = 25 C.
    """
    t_min, t_max = STRESS_RANGE_C
    if not t_min < t_ref_c < t_max:
        raise EffectError(f"shupe_stress: T_ref {t_ref_c:g} C must lie inside the operating "
                          f"range {t_min:g}..{t_max:g} C")
    return -1.0 / (t_max - t_ref_c), 1.0 / (t_ref_c - t_min)


@register_effect("shupe_stress", kind="gyro", parameters=[
    Parameter("k_m", "deg/h per K/min",
              "Shupe-Mohr stress coefficient of the radial gradient rate at T_ref"),
    Parameter("c_m", "1/K",
              "temperature coefficient of the stress term (potting modulus); "
              "1 + c_m (T_coil - T_ref) must keep its sign over -40..60 C",
              shape=True, bounds=stress_factor_bounds(), grid=STRESS_GRID)])
def shupe_stress(ctx: EffectContext, *, k_m: float, c_m: float) -> np.ndarray:
    """Shupe-Mohr thermal stress: k_m d(T_out - T_in)/dt (1 + c_m (T_coil - T_ref)) [deg/h].

    A radial temperature gradient across the potted coil strains the fibre; through the
    elasto-optic effect the strain rate adds a non-reciprocal phase with the same weighting
    along the fibre as Shupe's thermal phase (Shupe 1980, Appl. Opt. 19(5) 654, eq. (5)),
    so it is lumped on the rate of the radial gradient, here in K/min (Mohr 1996,
    "Thermooptically induced bias drift in fiber optical Sagnac interferometers",
    J. Lightwave Technol. 14(1) 27: the thermally induced stress term beside the dn/dT term).
    Its coefficient follows the elastic modulus of the potting compound, which changes with
    temperature (stiffer when cold, c_m < 0); to first order
    k_m(T) = k_m (1 + c_m (T_coil - T_ref)), which gives the T x dT/dt interaction that
    Cheng et al. (2015) feeds its network.

    Parameters: k_m [deg/h per K/min] at T_ref; c_m [1/K], bounded so that the factor keeps
    its sign over -40..60 C (:func:`stress_factor_bounds`: c_m in [-1/35, 1/65] at
    T_ref = 25 C; checked on construction, and against the instrument's own T_ref here).
    T_coil = (T_outer + T_inner)/2.  Magnitudes are engineering estimates (docs/physics.md
    section 3); not checked against a measured potting modulus.
    """
    lo, hi = stress_factor_bounds(ctx.t_ref_c)
    if not lo <= c_m <= hi:
        raise EffectError(f"shupe_stress: c_m = {c_m:g} 1/K flips the sign of "
                          f"1 + c_m (T_coil - T_ref) inside {STRESS_RANGE_C[0]:g}.."
                          f"{STRESS_RANGE_C[1]:g} C at T_ref = {ctx.t_ref_c:g} C "
                          f"(allowed {lo:.6g}..{hi:.6g})")
    d_grad = ctx.rate(ctx.coil_outer) - ctx.rate(ctx.coil_inner)
    factor = 1.0 + c_m * (ctx.coil_c - ctx.t_ref_c)
    return k_m * _S_PER_MIN * d_grad * factor


@register_effect("turn_on_transient", kind="gyro", parameters=[
    Parameter("a", "deg/h", "amplitude at power-on"),
    Parameter("tau", "s", "time constant", grid=(60.0, 150.0, 300.0, 600.0, 1200.0))])
def turn_on_transient(ctx: EffectContext, *, a: float, tau: float) -> np.ndarray:
    """Electronics turn-on transient: a exp(-t_on / tau) [deg/h] from power-on.

    t_on is the time since the latest power-on (:attr:`EffectContext.on_time_s`): a warm
    restart (a power cycle, :mod:`nfs.power`) starts the transient again at full amplitude.

    a [deg/h] 0.005-0.05, tau [s] 60-300 (docs/physics.md section 3, est.); IEEE Std 952-2020
    defines turn-on behaviour as warm-up time (clause 9 in its test procedure list).
    """
    if tau <= 0:
        raise EffectError(f"turn_on_transient: tau must be > 0 s, got {tau}")
    return a * np.exp(-ctx.on_time_s / tau)


@register_effect("aux_linear", kind="gyro", target="channel", parameters=[
    Parameter("channel", "", "the aux_* column that drives the bias", type=str),
    Parameter("k", "deg/h per channel unit", "sensitivity"),
    Parameter("aux_ref", "channel unit", "reference value of the channel", default=0.0)])
def aux_linear(ctx: EffectContext, *, channel: str, k: float, aux_ref: float = 0.0) -> np.ndarray:
    """Auxiliary electrical driver of the bias: k (aux - aux_ref) [deg/h].

    Tao et al. (2019) (Sensors 2019, 19, 2986, section 2 and Table 5) shows the high-frequency
    oscillator voltage U_HFO tracks a laser gyro's bias better than temperature.
    channel: an ``aux_*`` column; k [deg/h per channel unit]; aux_ref [channel unit].
    """
    try:
        x = ctx.aux[channel]
    except KeyError:
        raise EffectError(f"aux_linear: no channel '{channel}'; aux channels: "
                          + (", ".join(sorted(ctx.aux)) or "(none)")) from None
    return k * (x - aux_ref)


@register_effect("scale_factor_temperature", kind="gyro", target="node", parameters=[
    Parameter("s1", "1/K", "scale-factor temperature coefficient"),
    Parameter("node", "", "node of the light source (default: the instrument's source node)",
              type=str, optional=True)])
def scale_factor_temperature(ctx: EffectContext, *, s1: float,
                             node: str | None = None) -> np.ndarray:
    """Scale factor vs source temperature: Omega_true s1 (T_source - T_ref) [deg/h].

    K(T) = K0 (1 + s1 (T - 25)): the source's mean wavelength moves with temperature and the
    Sagnac scale factor with it.  s1 [1/K], 17-800 ppm/K (docs/physics.md section 3, est.;
    IEEE Std 952-2020 scale-factor temperature sensitivity).
    """
    t_src = ctx.node(ctx.source if node is None else node)
    return ctx.earth_rate_dph * s1 * (t_src - ctx.t_ref_c)


@register_effect("magnetic", kind="gyro", parameters=[
    Parameter("m", "deg/h", "amplitude of the magnetic (Faraday) bias"),
    Parameter("D_mag", "deg", "azimuth of the axis that gives the largest positive bias",
              grid=(0.0, 45.0, 90.0, 135.0))])
def magnetic(ctx: EffectContext, *, m: float, D_mag: float) -> np.ndarray:
    """Position-dependent bias from the Earth's magnetic field: m cos(A - D_mag) [deg/h].

    Faraday non-reciprocity in a coil with residual twist and birefringence makes the bias
    depend on the field along the axis (Hotate & Tabe 1986, Appl. Opt. 25(7) 1086); on a
    turntable it follows the position.  m [deg/h], D_mag [deg]; A the axis azimuth.
    """
    return m * np.cos(np.radians(ctx.axis_azimuth_deg - D_mag))


@register_effect("polarization_ripple", kind="gyro", target="node", parameters=[
    Parameter("A_p", "deg/h", "ripple amplitude"),
    Parameter("T_p", "K", "temperature period of the ripple", grid=(2.0, 5.0, 10.0, 20.0)),
    Parameter("phi", "rad", "phase", default=0.0, grid=(0.0, np.pi / 2)),
    _NODE])
def polarization_ripple(ctx: EffectContext, *, A_p: float, T_p: float, phi: float = 0.0,
                        node: str | None = None) -> np.ndarray:
    """Polarization non-reciprocity ripple: A_p sin(2 pi T_coil / T_p + phi) [deg/h].

    Polarization cross-coupling gives a bias that oscillates with temperature as the
    birefringent phase of the coil changes (Kintner 1981, Opt. Lett. 6(3) 154).
    A_p [deg/h], T_p [K], phi [rad].  Not checked against a measured period.
    """
    return A_p * np.sin(2.0 * np.pi * ctx.temperature(node) / T_p + phi)


@register_effect("null", kind="null")
def null(ctx: EffectContext | None = None, **_: object) -> float:
    """The explicit null effect: contributes nothing (for ablation and as a placeholder)."""
    return 0.0
