"""Each built-in effect against its equation in docs/effects.md on a hand-made state."""

import dataclasses

import numpy as np
import pytest

from nfs.effects import EffectContext, get_effect, make_effect
from nfs.effects.gyro import stress_factor_bounds
from nfs.errors import EffectError

T = np.linspace(0.0, 600.0, 61)


@pytest.fixture
def ctx():
    # Oracle state: linear ramps, so every derivative is known exactly.
    names = ("electronics", "coil_outer", "coil_inner", "qfa_x", "qfa_y")
    slopes = np.array([0.01, 0.004, 0.002, 0.003, 0.0025])           # K/s
    t0 = np.array([30.0, 20.0, 18.0, 10.0, 12.0])
    temp = t0 + np.outer(T, slopes)
    rate = np.broadcast_to(slopes, temp.shape).copy()
    az = np.mod(40.0 + 90.0 * (T // 150), 360.0)
    return EffectContext(time_s=T, node_names=names, temperature_c=temp, rate_c_per_s=rate,
                         coil_outer="coil_outer", coil_inner="coil_inner", source="electronics",
                         axis_azimuth_deg=az, earth_rate_dph=10.0 * np.cos(np.radians(az)),
                         moving=np.zeros_like(T, dtype=bool),
                         acc_nodes={"x": "qfa_x", "y": "qfa_y"},
                         aux={"aux_v": 5.0 + 0.01 * T})


def call(name, ctx, **p):
    return get_effect(name).function(ctx, **p)


def test_bias_temperature(ctx):
    tc = 0.5 * (ctx.node("coil_outer") + ctx.node("coil_inner"))
    np.testing.assert_allclose(call("bias_temperature", ctx, b1=0.002, b2=1e-4),
                               0.002 * (tc - 25) + 1e-4 * (tc - 25) ** 2, rtol=1e-12)
    np.testing.assert_allclose(call("bias_temperature", ctx, b1=0.002, node="qfa_x"),
                               0.002 * (ctx.node("qfa_x") - 25), rtol=1e-12)


def test_shupe_family(ctx):
    # d(T_out - T_in)/dt = 0.002 K/s = 0.12 K/min
    np.testing.assert_allclose(call("shupe_gradient", ctx, k_r=0.5), 0.5 * 0.12, rtol=1e-12)
    # dT_coil/dt = 0.003 K/s = 0.18 K/min
    np.testing.assert_allclose(call("shupe_rate", ctx, k_s=0.1), 0.1 * 0.18, rtol=1e-12)
    tc = 0.5 * (ctx.node("coil_outer") + ctx.node("coil_inner"))
    np.testing.assert_allclose(call("shupe_product", ctx, k_p=0.01),
                               0.01 * (tc - 25) * 0.18, rtol=1e-12)


def test_shupe_stress(ctx):
    # d(T_out - T_in)/dt = 0.002 K/s = 0.12 K/min; T_coil = 19 + 0.003 t [degC]
    tc = 19.0 + 0.003 * T
    np.testing.assert_allclose(call("shupe_stress", ctx, k_m=0.4, c_m=-0.02),
                               0.4 * 0.12 * (1.0 - 0.02 * (tc - 25.0)), rtol=1e-12)
    # c_m = 0: the stress term is the Shupe radial term with k_r = k_m
    np.testing.assert_allclose(call("shupe_stress", ctx, k_m=0.4, c_m=0.0),
                               call("shupe_gradient", ctx, k_r=0.4), rtol=1e-12)


def test_shupe_stress_factor_keeps_its_sign():
    # Oracle: 1 + c_m (T - 25) >= 0 at T = 60 C needs c_m >= -1/35, at T = -40 C c_m <= 1/65
    lo, hi = stress_factor_bounds(25.0)
    assert (lo, hi) == pytest.approx((-1 / 35, 1 / 65), rel=1e-12)
    make_effect("shupe_stress", {"k_m": 0.3, "c_m": -1 / 35})
    make_effect("shupe_stress", {"k_m": 0.3, "c_m": 1 / 65})
    for c_m in (-0.03, 0.016, -1.0):
        with pytest.raises(EffectError, match="c_m.*-40..60 C") as exc:
            make_effect("shupe_stress", {"k_m": 0.3, "c_m": c_m})
        assert "\n" not in str(exc.value)
    t = np.linspace(-40.0, 60.0, 101)
    for c_m in (lo, hi, -0.02, 0.01):
        assert np.all(1.0 + c_m * (t - 25.0) >= -1e-15)


def test_shupe_stress_checks_the_instruments_own_t_ref(ctx):
    # c_m = -0.02 keeps the sign at T_ref = 25 C (1 - 0.02 * 35 = 0.3 at 60 C), not at
    # T_ref = 0 C (1 - 0.02 * 60 = -0.2)
    cold = dataclasses.replace(ctx, t_ref_c=0.0)
    with pytest.raises(EffectError, match="flips the sign"):
        call("shupe_stress", cold, k_m=0.3, c_m=-0.02)


def test_turn_on_transient(ctx):
    np.testing.assert_allclose(call("turn_on_transient", ctx, a=0.02, tau=120.0),
                               0.02 * np.exp(-T / 120.0), rtol=1e-12)
    with pytest.raises(EffectError):
        call("turn_on_transient", ctx, a=0.02, tau=0.0)


def test_aux_linear(ctx):
    np.testing.assert_allclose(call("aux_linear", ctx, channel="aux_v", k=0.3, aux_ref=5.0),
                               0.3 * 0.01 * T, rtol=1e-12, atol=1e-15)
    with pytest.raises(EffectError, match="aux_v"):
        call("aux_linear", ctx, channel="aux_missing", k=1.0)


def test_scale_factor_temperature(ctx):
    np.testing.assert_allclose(call("scale_factor_temperature", ctx, s1=1e-4),
                               ctx.earth_rate_dph * 1e-4 * (ctx.node("electronics") - 25),
                               rtol=1e-12)


def test_magnetic_follows_position(ctx):
    out = call("magnetic", ctx, m=0.01, D_mag=40.0)
    np.testing.assert_allclose(out[:15], 0.01, rtol=1e-12)     # axis at 40 deg = D_mag
    np.testing.assert_allclose(out[30:45], -0.01, rtol=1e-12)  # axis at 220 deg


def test_polarization_ripple(ctx):
    tc = 0.5 * (ctx.node("coil_outer") + ctx.node("coil_inner"))
    np.testing.assert_allclose(call("polarization_ripple", ctx, A_p=0.003, T_p=2.0, phi=0.3),
                               0.003 * np.sin(np.pi * tc + 0.3), rtol=1e-12)


def test_acc_bias_temperature(ctx):
    np.testing.assert_allclose(call("acc_bias_temperature", ctx, axis="y", b_q1=2e-5),
                               2e-5 * (ctx.node("qfa_y") - 25), rtol=1e-12)
    with pytest.raises(EffectError, match="axis 'z'"):
        call("acc_bias_temperature", ctx, axis="z", b_q1=2e-5)


def test_thermal_effects():
    tec = get_effect("tec_power").function
    assert tec(0.0, 15.0, False, T_set=25.0, c_h=0.03, c_c=0.07) == pytest.approx(0.3)
    assert tec(0.0, 35.0, False, T_set=25.0, c_h=0.03, c_c=0.07) == pytest.approx(0.7)
    assert tec(0.0, 25.0, False, T_set=25.0, c_h=0.03, c_c=0.07) == 0.0
    assert get_effect("tec_power").state_dependent
    moving = np.array([0, 1, 1, 0], dtype=bool)
    np.testing.assert_array_equal(
        get_effect("motor_heat").function(np.arange(4.0), None, moving, node="board", power=2.0),
        [0.0, 2.0, 2.0, 0.0])
    np.testing.assert_array_equal(
        get_effect("heat_source").function(np.arange(3.0), None, None, node="board", power=0.5),
        [0.5, 0.5, 0.5])


def test_thermometer_lag_step():
    # Oracle: a first-order lag of a step held from t=0 is 1 - exp(-t/tau) at the samples.
    t = np.arange(0.0, 200.0)
    x = np.where(t >= 0, 1.0, 0.0)
    x[0] = 0.0                       # equilibrium at 0, then the step is held from t = 1
    y = get_effect("thermometer_lag").function(x, t, thermometer="fog", tau=30.0)
    np.testing.assert_allclose(y[1:], 1.0 - np.exp(-(t[1:] - 1.0) / 30.0), rtol=1e-12,
                               atol=1e-15)
