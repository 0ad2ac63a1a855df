"""The experiment chain: decomposition into named terms, ablation, determinism, physics."""


import numpy as np
import pytest

from nfs.effects import available_effects, make_effect
from nfs.errors import ScenarioError
from nfs.conditions import RunConditions
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.io.measurement import read_run, write_run
from nfs.config.scenario import TRUST_EFFECTS_ENV, load_scenario
from nfs.sensors import Schedule

SCHED = Schedule((0.0, 90.0, 180.0, 270.0), dwell_s=150.0, move_s=10.0)


@pytest.fixture(scope="module")
def inst():
    return load_instrument("default")


def cond(t0=-16.0, seed=(1, 2), duration=3200.0):
    return RunConditions(name="t", start_temperature_c=t0, latitude_deg=30.0,
                         true_heading_deg=123.4, schedule=SCHED, duration_s=duration, seed=seed)


def test_output_is_the_sum_of_its_named_terms(inst):
    # Invariant: gyro = K0 * Earth rate + bias + noise + sum of the effect terms.
    r = simulate_run(inst, cond())
    g = inst.gyro
    expected = g.scale_factor * r.context.earth_rate_dph + g.bias_dph + r.gyro_noise_dph
    for v in r.gyro_terms_dph.values():
        expected = expected + v
    np.testing.assert_allclose(r.run["gyro_dph"], expected, rtol=0, atol=1e-12)
    assert set(r.gyro_terms_dph) == {e.label for e in inst.effects if e.spec.kind == "gyro"}
    assert set(r.thermal_terms_w) == {"tec_power"}
    assert set(r.acc_terms_g) == {"acc_bias_temperature:x", "acc_bias_temperature:y"}


def test_ablation_changes_only_that_term(inst):
    # Switching one effect to the null effect removes its term and nothing else.
    r0 = simulate_run(inst, cond())
    effects = [make_effect("null") if e.name == "shupe_winding" else e for e in inst.effects]
    r1 = simulate_run(inst.with_effects(effects), cond())
    diff = r0.run["gyro_dph"] - r1.run["gyro_dph"]
    np.testing.assert_allclose(diff, r0.gyro_terms_dph["shupe_winding"], atol=1e-12)
    np.testing.assert_array_equal(r0.gyro_noise_dph, r1.gyro_noise_dph)
    np.testing.assert_array_equal(r0.run["temp_fog_c"], r1.run["temp_fog_c"])


def test_energy_balance_of_the_default_instrument(inst):
    # Invariant: heat in = heat stored + heat lost to the chamber (thermal/solve.py eq. (6)).
    th = simulate_run(inst, cond()).thermal
    np.testing.assert_allclose(th.heat_in_j, th.stored_j + th.heat_lost_j, rtol=1e-9,
                               atol=1e-9 * th.heat_in_j[-1])


def test_start_temperature_matters_through_the_tec(inst):
    # The TEC law draws more power away from its 25 C set point: a cold start heats faster.
    rise = {}
    for t0 in (-32.0, 25.0, 54.0):
        th = simulate_run(inst, cond(t0)).thermal
        rise[t0] = th.node("electronics")[-1] - t0
    assert rise[-32.0] > rise[25.0] + 1.0 and rise[54.0] > rise[25.0] + 1.0


def test_soaked_start(inst):
    # Before power-on the unit is soaked: every node and thermometer starts at T0.
    r = simulate_run(inst, cond(-5.0))
    np.testing.assert_allclose(r.thermal.temperature_c[0], -5.0)
    for c in ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c"):
        assert abs(r.run[c][0] + 5.0) < 0.1


def test_same_seed_same_bytes(tmp_path, inst):
    a = write_run(simulate_run(inst, cond()).run, tmp_path / "a")
    b = write_run(simulate_run(inst, cond()).run, tmp_path / "b")
    c = write_run(simulate_run(inst, cond(seed=(1, 3))).run, tmp_path / "c")
    assert a.read_bytes() == b.read_bytes()
    assert a.with_suffix(".toml").read_bytes() == b.with_suffix(".toml").read_bytes()
    assert a.read_bytes() != c.read_bytes()
    run = read_run(a)
    assert run.meta.true_heading_deg == 123.4 and run.meta.positions_deg == (0, 90, 180, 270)


def test_scenario_with_user_effect(tmp_path, monkeypatch):
    (tmp_path / "fx.py").write_text(
        "from nfs.effects import register_effect, Parameter\n"
        "@register_effect('test_step_bias', kind='gyro',\n"
        "                 parameters=[Parameter('step', 'deg/h', 'size'),\n"
        "                             Parameter('at', 's', 'time')])\n"
        "def test_step_bias(ctx, *, step, at):\n"
        "    '''step * (t >= at) [deg/h].'''\n"
        "    return step * (ctx.time_s >= at)\n")
    (tmp_path / "s.toml").write_text(
        'effects_files = ["fx.py"]\n'
        "start_temperatures_c = [20.0]\nduration_s = 700.0\n"
        "[schedule]\npositions_deg = [0, 90, 180, 270]\ndwell_s = 150.0\n"
        "[[effects]]\nname = 'test_step_bias'\nstep = 0.5\nat = 100.0\n")
    # a scenario does not run code because it was loaded: refused until the user trusts it
    with pytest.raises(ScenarioError, match="does not run code"):
        load_scenario(tmp_path / "s.toml")
    assert "test_step_bias" not in available_effects()
    monkeypatch.setenv(TRUST_EFFECTS_ENV, "1")
    sc = load_scenario(tmp_path / "s.toml")
    assert [e.name for e in sc.instrument.effects] == ["test_step_bias"]
    r = simulate_run(sc.instrument, sc.conditions()[0])
    np.testing.assert_array_equal(r.gyro_terms_dph["test_step_bias"][99:101], [0.0, 0.5])


def test_chamber_ripple(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text("start_temperatures_c = [20.0]\nduration_s = 1300.0\n"
                 "[schedule]\npositions_deg = [0, 180]\ndwell_s = 100.0\n"
                 "[chamber]\nripple_c = 0.5\nripple_period_s = 400.0\n")
    sc = load_scenario(p)
    r = simulate_run(sc.instrument, sc.conditions()[0])
    amb = r.run["temp_chamber_c"]
    assert amb.max() == pytest.approx(20.5, abs=1e-3) and amb.min() == pytest.approx(19.5, abs=1e-3)


def test_replaying_a_runs_own_conditions_reproduces_it(tmp_path, inst):
    """Invariant: a run simulated again from its own file (time base, turntable motion, T0,
    latitude, heading, chamber; same seed) is the same run - the basis of putting a model
    beside a measurement."""
    from nfs.conditions import conditions_from_run
    r0 = simulate_run(inst, cond(seed=(4, 4)))
    run = read_run(write_run(r0.run, tmp_path))
    r1 = simulate_run(inst, conditions_from_run(run, seed=(4, 4)))
    for c in ("gyro_dph", "acc_x_g", "temp_fog_c", "temp_acc_y_c", "position_deg"):
        np.testing.assert_allclose(r1.run[c], run[c], rtol=0, atol=1e-9, err_msg=c)
