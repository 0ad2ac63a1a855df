"""Geometry effects (indexing_error, axis_misalignment, tilt_exact) held to closed forms.

Runs come from the simulator with a noiseless instrument (no gyro or accelerometer noise,
no drift effects, a constant gyro bias), so north finding sees only the geometry: every
oracle below is a closed form of nfs.northfind.budget or of the effect's own equation.
"""

import math

import numpy as np
import pytest

from nfs.constants import OMEGA_IE_DPH
from nfs.effects import Geometry, make_effect
from nfs.effects.geometry import azimuth_elevation_deg, table_axes_ned, tilt_matrix
from nfs.errors import EffectError
from nfs.conditions import RunConditions
from nfs.experiment import _pointing, simulate_run, simulate_runs
from nfs.instrument import load_instrument
from nfs.northfind import (indexing_error_deg, north_find, tilt_model_error_deg,
                           wrap_deg_180)
from nfs.parameters import set_params
from nfs.sensors import Schedule, axis_elevation_deg

LAT = 30.26
FOUR = (0.0, 90.0, 180.0, 270.0)


@pytest.fixture(scope="module")
def quiet():
    """The default instrument without noise, drift effects or tilt (bias 0.02 deg/h kept)."""
    inst = set_params(load_instrument("default"), {
        "gyro.arw_deg_per_rth_h": 0.0, "gyro.bias_instability_dph": 0.0,
        "accelerometers.noise_ug_per_rth_hz": 0.0, "turntable.tilt_north_deg": 0.0,
        "turntable.tilt_east_deg": 0.0})
    return inst.with_effects([])


def run(inst, effects, heading, positions=FOUR, cycles=2, seed=0, tilt=(0.0, 0.0)):
    sched = Schedule(positions, dwell_s=60.0, move_s=5.0)
    inst = set_params(inst, {"turntable.tilt_north_deg": tilt[0],
                             "turntable.tilt_east_deg": tilt[1]})
    cond = RunConditions(name="g", start_temperature_c=20.0, latitude_deg=LAT,
                         true_heading_deg=heading, schedule=sched,
                         duration_s=cycles * sched.cycle_s, seed=seed)
    return simulate_run(inst.with_effects([make_effect(n, p) for n, p in effects]), cond)


HEADINGS = np.arange(0.0, 360.0, 15.0)


# ---------------------------------------------------------------- registry and validation

def test_registered_as_geometry_with_units():
    for name, params in [("indexing_error", {"offsets_deg", "sigma_deg"}),
                         ("axis_misalignment", {"delta_deg", "gamma_deg"}),
                         ("tilt_exact", {"pitch_deg", "roll_deg"})]:
        e = make_effect(name, {"offsets_deg": [0.0]} if name == "indexing_error" else
                        {"delta_deg": 0.0} if name == "axis_misalignment" else
                        {"pitch_deg": 0.0, "roll_deg": 0.0})
        assert e.spec.kind == "geometry"
        assert {p.name for p in e.spec.parameters} == params
        assert all(p.unit == "deg" for p in e.spec.parameters)


@pytest.mark.parametrize("name, params, message", [
    ("tilt_exact", {"pitch_deg": 6.0, "roll_deg": 0.0}, "'pitch_deg' = 6 [deg] is outside"),
    ("tilt_exact", {"pitch_deg": 4.0, "roll_deg": 4.0}, "tilt acos(cos pitch cos roll) = 5.65"),
    ("indexing_error", {"offsets_deg": 0.1}, "must be a list of numbers"),
    ("indexing_error", {"offsets_deg": [0.0, True]}, "must be a list of numbers"),
    ("indexing_error", {"offsets_deg": [0.0, 9.0]}, "'offsets_deg[1]' = 9 [deg] is outside"),
    ("indexing_error", {"offsets_deg": [0.0], "sigma_deg": -1.0}, "'sigma_deg' = -1"),
    ("axis_misalignment", {"delta_deg": 0.0, "gamma_deg": 7.0}, "'gamma_deg' = 7"),
])
def test_bad_parameters_give_one_line_errors(name, params, message):
    with pytest.raises(EffectError) as exc:
        make_effect(name, params)
    assert message in str(exc.value) and "\n" not in str(exc.value)


def test_offsets_must_match_the_schedule_and_the_tilt_is_given_once(quiet):
    with pytest.raises(EffectError, match=r"offsets_deg has 3 value\(s\), the schedule has 4"):
        run(quiet, [("indexing_error", {"offsets_deg": [0.0, 0.1, 0.2]})], 10.0)
    with pytest.raises(EffectError, match="tilt is given twice"):
        run(quiet, [("tilt_exact", {"pitch_deg": 1.0, "roll_deg": 0.0})], 10.0,
            tilt=(0.02, 0.0))


def test_without_geometry_effects_the_first_order_model_is_unchanged():
    # Oracle: docs/physics.md section 4 as axis_elevation_deg computes it, bit for bit.
    theta = np.linspace(0.0, 350.0, 36)
    g = Geometry(time_s=theta, position_deg=theta, moving=np.zeros(36, bool),
                 positions_deg=FOUR, heading_deg=212.7, rng=np.random.default_rng(0),
                 theta_deg=theta, tilt_north_deg=0.02, tilt_east_deg=-0.015)
    axes = g.azimuth_elevation()
    az = np.mod(212.7 + theta, 360.0)
    np.testing.assert_array_equal(axes["x"][0], az)
    np.testing.assert_array_equal(axes["x"][1], axis_elevation_deg(az, 0.02, -0.015))
    np.testing.assert_array_equal(axes["y"][1], axis_elevation_deg(az + 90.0, 0.02, -0.015))
    np.testing.assert_array_equal(axes["gyro"][1], axes["x"][1])


# ---------------------------------------------------------------- tilt_exact

def test_tilt_matrix_is_a_rotation_with_the_named_edges_up():
    # Oracle: C orthonormal, det +1; the table's north line rises by exactly the pitch.
    c = tilt_matrix(2.0, 1.0)
    np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(c) == pytest.approx(1.0, abs=1e-15)
    north_line = c @ np.array([1.0, 0.0, 0.0])
    assert math.degrees(math.asin(-north_line[2])) == pytest.approx(2.0, abs=1e-12)
    x, y, z = table_axes_ned(212.7, np.array([0.0, 90.0]), 2.0, 1.0)
    az, _ = azimuth_elevation_deg(x)
    assert az[0] == pytest.approx(212.7, abs=1e-12)   # psi is the projection's azimuth
    np.testing.assert_allclose(np.cross(x, y), z, atol=1e-15)
    np.testing.assert_allclose(x[1], y[0], atol=1e-15)  # x at 90 deg is y at 0


@pytest.mark.parametrize("heading", HEADINGS)
def test_exact_levelling_returns_the_true_heading_of_an_exactly_tilted_table(quiet, heading):
    # Oracle: a noiseless run, exact geometry and exact levelling: psi to rounding.
    res = north_find(run(quiet, [("tilt_exact", {"pitch_deg": 2.0, "roll_deg": 1.0})],
                         heading).run)
    assert np.all(np.abs(res.error_deg) < 1e-9), res.error_deg


@pytest.mark.parametrize("positions", [FOUR, (0.0, 120.0, 240.0),
                                       tuple(45.0 * np.arange(8))], ids=["N4", "N3", "N8"])
def test_first_order_and_exact_tilt_differ_by_the_second_order_formula(quiet, positions):
    # Oracle: budget.tilt_model_error_deg (second order; the third-order remainder is about
    # the tilt in rad relative, 3.5 % at 2 deg). At psi = 212.7, N = 4 it is the 6.6e-3 deg
    # the first-order tilt model errs by at 2 deg / 1 deg.
    found = {}
    for heading in (0.0, 45.0, 300.0, 212.7):
        exact = north_find(run(quiet, [("tilt_exact", {"pitch_deg": 2.0, "roll_deg": 1.0})],
                               heading, positions).run)
        first = north_find(run(quiet, [], heading, positions, tilt=(2.0, 1.0)).run)
        diff = wrap_deg_180(first.heading_deg - exact.heading_deg)
        expected = tilt_model_error_deg(2.0, 1.0, heading, len(positions))
        np.testing.assert_allclose(diff, expected, rtol=0.04, atol=2e-5)
        found[heading] = (float(diff[0]), expected)
    if len(positions) == 4:
        diff, expected = found[212.7]
        assert f"{expected:.1e}" == "6.6e-03" and f"{diff:.1e}" == "6.6e-03"


# ---------------------------------------------------------------- axis_misalignment

@pytest.mark.parametrize("heading", HEADINGS)
def test_delta_shifts_every_heading_by_delta(quiet, heading):
    # Oracle: the gyro axis stands at psi + delta; north finding finds the gyro axis.
    res = north_find(run(quiet, [("axis_misalignment", {"delta_deg": 0.37})], heading).run)
    np.testing.assert_allclose(res.error_deg, 0.37, atol=1e-9)


@pytest.mark.parametrize("heading", [0.0, 75.0, 212.7])
def test_gamma_adds_omega_sin_l_sin_gamma(quiet, heading):
    # Oracle: w = Omega_h cos(gamma) cos A + Omega_ie sin L sin(gamma) on a level table:
    # the rate along the gyro axis, the fitted bias (+ Omega_v sin gamma exactly, the
    # cos A terms cancel over the positions), the heading (unchanged) and the fitted
    # horizontal rate (Omega_h cos gamma).
    gamma = 0.5
    r0 = run(quiet, [], heading)
    r1 = run(quiet, [("axis_misalignment", {"delta_deg": 0.0, "gamma_deg": gamma})], heading)
    lat, g = math.radians(LAT), math.radians(gamma)
    a = np.radians(r0.context.axis_azimuth_deg)
    expected = OMEGA_IE_DPH * (math.cos(lat) * math.cos(g) * np.cos(a)
                               + math.sin(lat) * math.sin(g))
    np.testing.assert_allclose(r1.context.earth_rate_dph, expected, rtol=0, atol=1e-12)
    n0, n1 = north_find(r0.run), north_find(r1.run)
    np.testing.assert_allclose(n1.bias_dph - n0.bias_dph,
                               OMEGA_IE_DPH * math.sin(lat) * math.sin(g), rtol=1e-10)
    np.testing.assert_allclose(n1.error_deg, 0.0, atol=1e-9)
    np.testing.assert_allclose(n1.horizontal_rate_dph,
                               OMEGA_IE_DPH * math.cos(lat) * math.cos(g), rtol=1e-12)


# ---------------------------------------------------------------- indexing_error

@pytest.mark.parametrize("positions, offsets", [
    (FOUR, (0.02, -0.03, 0.01, 0.04)),
    (tuple(45.0 * np.arange(8)), (0.02, -0.03, 0.01, 0.04, 0.0, -0.01, 0.03, 0.02))],
    ids=["N4", "N8"])
def test_indexing_offsets_give_the_small_angle_heading_error(quiet, positions, offsets):
    # Oracle: delta_psi = (2/N) sum d_k sin^2(psi + theta_k), first order in d (d <= 0.04
    # deg = 0.7 mrad: the remainder is below 1e-3 relative, or 2e-6 deg).
    for heading in HEADINGS:
        res = north_find(run(quiet, [("indexing_error", {"offsets_deg": list(offsets)})],
                             heading, positions).run)
        expected = indexing_error_deg(offsets, heading, positions)
        np.testing.assert_allclose(res.error_deg, expected, rtol=1e-3, atol=2e-6)
    # a common offset turns the heading by itself, exactly in the first order
    assert indexing_error_deg((0.05,) * 4, 33.0, FOUR) == pytest.approx(0.05, rel=1e-12)


def test_indexing_scatter_is_drawn_per_visit_from_the_seeded_stream(quiet):
    # Oracle: theta_true - theta_cmd is constant over each visit, with standard deviation
    # sigma over the visits (600 visits: 2.9 % relative standard error, 15 % is 5 sigma);
    # the heading scatters by sigma sqrt(3 / (2N)) (sum sin^4 = 3N/8; 150 cycles: 5.8 %
    # relative standard error, 25 % is 4 sigma); same seed, same draws; the run records the
    # commanded angle, and the other streams (thermometer noise) are unchanged.
    sigma = 0.01
    eff = [("indexing_error", {"offsets_deg": [0.0] * 4, "sigma_deg": sigma})]
    a = run(quiet, eff, 212.7, cycles=150, seed=5)
    geom = a.geometry
    err = geom.theta_deg - geom.position_deg
    rest = ~geom.moving
    starts = np.flatnonzero(rest & np.concatenate(([True], ~rest[:-1])))
    per_visit = err[starts]
    assert per_visit.size == 600
    stops = np.flatnonzero(rest & np.concatenate((~rest[1:], [True])))
    np.testing.assert_array_equal(err[stops], per_visit)
    assert np.std(per_visit) == pytest.approx(sigma, rel=0.15)
    nf = north_find(a.run)
    assert np.std(nf.error_deg) == pytest.approx(sigma * math.sqrt(3 / 8), rel=0.25)
    b = run(quiet, eff, 212.7, cycles=150, seed=5)
    np.testing.assert_array_equal(b.geometry.theta_deg, geom.theta_deg)
    c = run(quiet, eff, 212.7, cycles=150, seed=6)
    assert not np.array_equal(c.geometry.theta_deg, geom.theta_deg)
    plain = run(quiet, [], 212.7, cycles=150, seed=5)
    np.testing.assert_array_equal(plain.run["temp_fog_c"], a.run["temp_fog_c"])
    np.testing.assert_array_equal(plain.run["position_deg"], a.run["position_deg"])


# ---------------------------------------------------------------- files and the command line

GEOMETRY_TOML = """
[[effects]]
name = "tilt_exact"
pitch_deg = 0.05
roll_deg = 0.03

[[effects]]
name = "indexing_error"
offsets_deg = [0.01, -0.02, 0.015, 0.0]
sigma_deg = 0.002

[[effects]]
name = "axis_misalignment"
delta_deg = 0.05
gamma_deg = 0.1
"""


def test_instrument_and_scenario_files_with_geometry_effects_load(tmp_path):
    # Oracle: the files themselves; the instrument round-trips through its TOML form, and
    # a scenario naming it simulates with the effects in place.
    from nfs.instrument import preset_path
    from nfs.config.scenario import load_scenario
    from nfs.config.presets import default_scenario_path
    # a file of its own has a name of its own, and a levelled platform's tilt (0.05 and 0.03
    # deg, inside nfs.ranges' typical 0-0.1 deg): the files load without a RangeWarning
    text = preset_path("default").read_text().replace('name = "default"', 'name = "geom"', 1)
    text = text.replace("tilt_north_deg = 0.02", "tilt_north_deg = 0.0").replace(
        "tilt_east_deg = -0.015", "tilt_east_deg = 0.0")
    (tmp_path / "geom.toml").write_text(text + GEOMETRY_TOML)
    inst = load_instrument(tmp_path / "geom.toml")
    labels = [e.label for e in inst.effects]
    assert labels[-3:] == ["tilt_exact", "indexing_error", "axis_misalignment"]
    assert inst.effect("indexing_error").params["offsets_deg"] == (0.01, -0.02, 0.015, 0.0)
    (tmp_path / "again.toml").write_text(inst.to_toml())
    assert load_instrument(tmp_path / "again.toml").effects == inst.effects
    scen = default_scenario_path().read_text().replace(
        'instrument = "default"', 'instrument = "geom.toml"')
    (tmp_path / "s.toml").write_text(scen)
    sc = load_scenario(tmp_path / "s.toml")
    assert [e.name for e in sc.instrument.effects][-3:] == labels[-3:]
    sim = simulate_run(sc.instrument, sc.conditions()[0])
    assert sim.geometry.exact_tilt and sim.geometry.gyro_axis_body != (1.0, 0.0, 0.0)


def test_runs_stacked_share_their_pointing_only_without_a_geometry_effect(quiet):
    # Oracle: simulate_run of each run alone, bit for bit.  Without a geometry effect the
    # runs of one call with one schedule, heading and latitude share one turntable motion and
    # pointing (read-only arrays), each keeping its own turntable stream; an indexing
    # scatter draws from each run's stream, so there every run points its own way.
    sched = Schedule(FOUR, dwell_s=60.0, move_s=5.0)
    conds = [RunConditions(name=f"g{s}", start_temperature_c=20.0, latitude_deg=LAT,
                           true_heading_deg=100.0, schedule=sched, duration_s=2 * sched.cycle_s,
                           seed=s) for s in (1, 2, 3)]
    scatter = quiet.with_effects([make_effect("indexing_error", {
        "offsets_deg": [0.0] * 4, "sigma_deg": 0.01})])
    for inst, shared in ((quiet, True), (scatter, False)):
        sims = simulate_runs(inst, conds)
        for cond, sim in zip(conds, sims, strict=True):
            one = simulate_run(inst, cond)
            np.testing.assert_array_equal(sim.geometry.theta_deg, one.geometry.theta_deg)
            for col, v in one.run.columns.items():
                np.testing.assert_array_equal(sim.run.columns[col], v, err_msg=col)
        assert (sims[0].geometry.theta_deg is sims[1].geometry.theta_deg) == shared
        assert sims[0].geometry.rng is not sims[1].geometry.rng
        assert shared == (not sims[0].run.columns["position_deg"].flags.writeable)
        if not shared:
            assert not np.array_equal(sims[0].geometry.theta_deg, sims[1].geometry.theta_deg)


def test_shared_pointing_holds_the_whole_time_grid(quiet):
    # Oracle: two grids of one size and the same ends that differ inside are pointed each on
    # its own (the turntable's angle at an inner sample), not shared.
    sched = Schedule(FOUR, dwell_s=60.0, move_s=5.0)
    cond = RunConditions(name="g", start_temperature_c=20.0, latitude_deg=LAT,
                         true_heading_deg=100.0, schedule=sched, duration_s=2 * sched.cycle_s,
                         seed=1)
    even = cond.time_s
    uneven = even.copy()
    uneven[1:-1] += 0.4                         # the same size, first and last sample
    shared: dict = {}
    rng = np.random.default_rng(0)
    a = _pointing(quiet, cond, even, rng, shared)
    b = _pointing(quiet, cond, uneven, rng, shared)
    np.testing.assert_array_equal(b[0], cond.turntable(uneven)[0])
    assert not np.array_equal(a[0], b[0])
    assert _pointing(quiet, cond, even.copy(), rng, shared)[0] is a[0]     # shared again
