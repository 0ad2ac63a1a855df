"""Tests of the independent run generator (tests/independent/generator.py).

The generator imports nothing from nfs; these tests may, to read what it writes.  Each test
states its oracle.  Runs are short (a few hundred to 3000 s) except where a time constant
needs the length.
"""

from __future__ import annotations

import ast
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

from nfs.io.measurement import read_runs

from nfs.run import REQUIRED_COLUMNS

from . import generator as g
from . import winding as wd

TEMPS = (-32.0, 17.0, 54.0)


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("module", ["generator.py", "family.py", "winding.py"])
def test_imports_nothing_from_nfs(module):
    """Oracle: the generator's own source; its imports are the standard library, NumPy
    and SciPy only, and each other (an independent truth must not share code with the
    model)."""
    tree = ast.parse((Path(g.__file__).parent / module).read_text(encoding="utf-8"))
    roots = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            roots |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level:    # from . import sibling
            assert {a.name for a in node.names} <= {"generator", "family", "winding"}
        elif isinstance(node, ast.ImportFrom):
            roots.add((node.module or "").split(".")[0])
    assert not roots & {"nfs", "thermal"}
    assert roots <= {"__future__", "argparse", "json", "math", "sys", "zlib", "dataclasses",
                     "pathlib", "typing", "numpy", "scipy", "generator", "family",
                     "winding"}


def test_files_load_and_pass_the_readers_checks(tmp_path):
    """Oracle: the format spec (nfs-measurement/1): nfs.io.measurement.read_runs loads every
    run with its checks (required columns, increasing time, moving 0/1, sample rate against
    time_s) and gives back the metadata that was asked for."""
    truth = g.generate_set(tmp_path, start_temperatures_c=TEMPS, duration_s=700.0,
                           latitude_deg=31.0, true_heading_deg=100.0)
    assert truth == {"hidden": None, "target": None, "channel": None, "params": {}}
    runs = read_runs(tmp_path)
    assert [r.meta.start_temperature_c for r in runs] == list(TEMPS)
    for r in runs:
        assert r.n_samples == 700
        assert set(REQUIRED_COLUMNS) <= set(r.columns)
        assert {"temp_chamber_c", "aux_source_current_ma", "aux_osc_v"} <= set(r.columns)
        assert r.meta.latitude_deg == 31.0 and r.meta.true_heading_deg == 100.0
        assert r.meta.positions_deg == (0.0, 90.0, 180.0, 270.0)
        assert r.meta.dwell_s == 150.0 and r.meta.move_s == 10.0
        # Soaked at T0: every thermometer starts within its offset, noise and quantum.
        for c in ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c", "temp_chamber_c"):
            assert abs(r[c][0] - r.meta.start_temperature_c) < 0.15
        # One move every 160 s, 10 samples each.
        assert r["moving"].sum() == 40


def test_same_seed_same_bytes_other_seed_differs(tmp_path):
    """Oracle: determinism (every draw from default_rng(seed)); another seed draws other
    noise, so the gyro column differs while the time base does not."""
    kw = dict(start_temperatures_c=(-5.0, 43.0), duration_s=400.0, hidden="magnetic")
    g.generate_set(tmp_path / "a", seed=4, **kw)
    g.generate_set(tmp_path / "b", seed=4, **kw)
    g.generate_set(tmp_path / "c", seed=5, **kw)
    a, b, c = (_files(tmp_path / x) for x in "abc")
    assert a == b
    assert a.keys() == c.keys() and a != c
    ra, rc = read_runs(tmp_path / "a"), read_runs(tmp_path / "c")
    assert np.array_equal(ra[0]["time_s"], rc[0]["time_s"])
    assert not np.array_equal(ra[0]["gyro_dph"], rc[0]["gyro_dph"])


def test_single_layer_coil_is_an_exact_exponential():
    """Oracle: one layer between two held faces is an RC circuit: T(t) = T_inf + (T0 -
    T_inf) exp(-t (G_a + G_b)/C), with G_a, G_b each face contact in series with the half
    layer 2 pi k h / ln(rho / r_face) and T_inf their weighted mean."""
    geom = g.CoilGeometry(n_layers=1)
    net = g.coil_network(geom, 0.6, 0.3)
    k2 = 2 * math.pi * geom.conductivity_w_per_m_k * geom.height_m
    rho = math.sqrt(geom.inner_radius_m * geom.outer_radius_m)
    ga = 1 / (1 / 0.6 + math.log(rho / geom.inner_radius_m) / k2)
    gb = 1 / (1 / 0.3 + math.log(geom.outer_radius_m / rho) / k2)
    cap = geom.heat_j_per_m3_k * math.pi * (geom.outer_radius_m ** 2
                                            - geom.inner_radius_m ** 2) * geom.height_m
    np.testing.assert_allclose(net.boundary_w_per_k, [[ga, gb]], rtol=1e-12)
    st = g.Stepper(net, 7.0)
    tb = np.array([30.0, 10.0])
    x = np.array([0.0])
    drive = st.boundary_terms(np.vstack([tb, tb]))[0]
    t_inf = (ga * 30.0 + gb * 10.0) / (ga + gb)
    for k in range(1, 60):
        x = st.phi @ x + drive
        exact = t_inf - t_inf * math.exp(-7.0 * k * (ga + gb) / cap)
        assert abs(x[0] - exact) < 1e-10


def test_coil_steady_state_is_the_cylinder_log_profile():
    """Oracle: steady radial conduction through a cylindrical shell, T(r) = T_a - Q (1/g_a
    + ln(r / r_in) / (2 pi k h)), Q = (T_a - T_b) / (1/g_a + ln(r_out/r_in)/(2 pi k h) +
    1/g_b) (Incropera & DeWitt, 6th ed., sec. 3.3.1); the log-conductance finite
    differences are exact at the node radii for any number of layers."""
    geom = g.CoilGeometry(n_layers=6)
    net = g.coil_network(geom, 0.6, 0.3)
    tb = np.array([30.0, 10.0])
    t_ss = np.linalg.solve(net.laplacian_w_per_k, net.boundary_w_per_k @ tb)
    k2 = 2 * math.pi * geom.conductivity_w_per_m_k * geom.height_m
    r = np.linspace(geom.inner_radius_m, geom.outer_radius_m, 7)
    rho = np.sqrt(r[:-1] * r[1:])
    q = 20.0 / (1 / 0.6 + math.log(geom.outer_radius_m / geom.inner_radius_m) / k2 + 1 / 0.3)
    np.testing.assert_allclose(t_ss, 30.0 - q * (1 / 0.6 + np.log(rho / r[0]) / k2),
                               rtol=1e-12)


def test_energy_balance_of_the_whole_unit():
    """Oracle: energy conservation.  Heat stored, sum_j C_j (T_j(t) - T0), equals the
    electrical energy in minus the heat lost to the chamber, sum_j G_j,amb (T_j - T_amb),
    integrated by the trapezoid rule (error O(h^2) on 1 s steps: < 1e-4 relative)."""
    run = g.simulate_run(-16.0, duration_s=3000.0, noise=False)
    net = g.unit_network(g.Unit())
    stored = (run.temperature_c - run.temperature_c[0]) @ net.capacity_j_per_k
    loss = (run.temperature_c - run.chamber_c[:, None]) @ net.boundary_w_per_k[:, 0]
    net_in = run.power_w.sum(axis=1) - loss
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (net_in[1:] + net_in[:-1]))])
    assert abs(stored[-1] - integral[-1]) < 1e-4 * stored[-1]
    # And the rate returned is the network's own right-hand side: C dT/dt sums to net_in.
    np.testing.assert_allclose(run.rate_c_per_s @ net.capacity_j_per_k, net_in, rtol=1e-9)


def test_time_constants_and_rise_in_range():
    """Oracle: docs/physics.md section 2: one global time constant of 20-60 min, component
    constants of minutes, an internal rise of 5-15 K after 2.5 h; the TEC law makes the rise
    depend on T0 (more power away from the set point)."""
    taus = g.unit_network(g.Unit()).time_constants_s() / 60.0
    assert 20.0 < taus[0] < 60.0 and taus[1] < 10.0
    rises = {}
    for t0 in (-32.0, 17.0, 54.0):
        run = g.simulate_run(t0, noise=False)
        coil = np.mean([run.node(f"coil_{i}")[-1] for i in range(8)]) - t0
        board = run.node("board")[-1] - t0
        assert 5.0 < coil < 15.0 and 5.0 < board < 15.0
        rises[t0] = coil
    assert rises[54.0] > rises[-32.0] > rises[17.0]


def test_dwell_mean_minus_projection_is_the_drift():
    """Oracle: the Earth-rate projection w = Omega_ie (cos L cos A cos e + sin L sin e) with
    A = heading + position and e = alpha_N cos A + alpha_E sin A, computed here from the
    unit's tilt: without noise the gyro minus it is exactly the drift terms (bias, Shupe,
    mean rate); with noise the dwell means differ from the drift by the noise of a 150 s
    mean (ARW N 60 / sqrt(150) deg/h plus the Gauss-Markov bias), within 5 sigma."""
    unit = g.Unit()
    lat, heading = 30.26, 212.7

    def projection(run):
        a = np.radians(heading + run.columns["position_deg"])
        e = np.radians(unit.tilt_north_deg * np.cos(a) + unit.tilt_east_deg * np.sin(a))
        L = math.radians(lat)
        return g.OMEGA_IE_DPH * (math.cos(L) * np.cos(a) * np.cos(e) + math.sin(L) * np.sin(e))

    clean = g.simulate_run(-5.0, duration_s=1300.0, noise=False)
    terms = clean.gyro_terms_dph
    drift = terms["bias"] + terms["shupe_layers"] + terms["mean_rate"]
    np.testing.assert_allclose(clean.columns["gyro_dph"] - projection(clean), drift,
                               atol=1e-12)
    noisy = g.simulate_run(-5.0, duration_s=1300.0, seed=2)
    sigma = math.hypot(unit.arw_deg_per_rth_h * 60.0 / math.sqrt(150.0), unit.gm_sigma_dph)
    resid = noisy.columns["gyro_dph"] - projection(noisy) - drift
    still = noisy.columns["moving"] < 0.5
    dwell = np.floor(noisy.columns["time_s"] / 160.0)
    means = [resid[still & (dwell == k)].mean() for k in range(8)]
    assert np.max(np.abs(means)) < 5 * sigma


def _pair(hidden, **kw):
    kw.setdefault("duration_s", 1500.0)
    return (g.simulate_run(-16.0, seed=7, **kw),
            g.simulate_run(-16.0, seed=7, hidden=hidden, **kw))


_GYRO = ("gyro_dph",)
_THERMO = ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c")


@pytest.mark.parametrize("hidden, changed", [
    ("magnetic", _GYRO), ("shupe_product", _GYRO), ("scale_factor_temperature", _GYRO),
    ("turn_on_transient", _GYRO), ("aux_linear", _GYRO), ("outside", _GYRO),
    ("acc_bias_temperature", ("acc_x_g",)),
    ("thermometer_lag", ("temp_fog_c",)),
    ("heat_source", _GYRO + _THERMO + ("aux_source_current_ma", "aux_osc_v")),
])
def test_hidden_effect_changes_its_channels_only(hidden, changed):
    """Oracle: the effect's definition (docs/effects.md) and the generator's independent random
    streams: with the same seed only the channels the effect acts on change (a gyro effect
    leaves the thermometers, accelerometers and aux bit-identical; a heat source warms the
    unit, so the thermometers, the TEC and through them the gyro change)."""
    base, hid = _pair(hidden)
    for col, values in base.columns.items():
        same = np.array_equal(values, hid.columns[col])
        assert same != (col in changed), col


def test_magnetic_and_quadrantal_follow_the_azimuth():
    """Oracle: the closed forms m cos(A - D_mag) and c cos(2 (A - D2)), A = heading +
    position: the gyro difference with and without the effect is exactly that."""
    for hidden, f in (("magnetic", lambda a, p: p["m"] * np.cos(np.radians(a - p["D_mag"]))),
                      ("outside", lambda a, p: p["c"] * np.cos(2 * np.radians(a - p["D2_deg"])))):
        base, hid = _pair(hidden, duration_s=700.0)
        a = 212.7 + base.columns["position_deg"]
        np.testing.assert_allclose(hid.columns["gyro_dph"] - base.columns["gyro_dph"],
                                   f(a, g.HIDDEN_EFFECTS[hidden]), atol=1e-12)


def test_heat_source_warms_the_fog_thermometer():
    """Oracle: an extra constant power P at the spool side raises every temperature (a
    network of positive conductances is monotone in its sources), and its steady share at
    the FOG thermometer is bounded by P over the housing's conductance to the chamber plus
    the rest of the path (here checked loosely: warmer by 0.05-1 K after 1500 s)."""
    base, hid = _pair("heat_source")
    assert np.all(hid.temperature_c >= base.temperature_c - 1e-12)
    d = hid.clean["temp_fog_c"][-1] - base.clean["temp_fog_c"][-1]
    assert 0.05 < d < 1.0


def test_truth_and_bad_input(tmp_path):
    """Oracle: the API: the truth names the hidden effect, its target and parameters
    (defaults overridden by ``params``); unknown names raise ValueError listing valid ones."""
    truth = g.generate_set(tmp_path, hidden="heat_source", params={"power": 0.5},
                           start_temperatures_c=(10.0,), duration_s=300.0)
    assert truth == {"hidden": "heat_source", "target": "coil_spool",
                     "channel": "temp_fog_c", "params": {"node": "coil_spool", "power": 0.5}}
    with pytest.raises(ValueError, match="valid: .*magnetic"):
        g.generate_set(tmp_path, hidden="nonsense")
    with pytest.raises(ValueError, match="no parameter"):
        g.generate_set(tmp_path, hidden="magnetic", params={"q": 1.0})


def test_command_line(tmp_path, capsys):
    """Oracle: the documented command line writes the runs and prints the truth as JSON."""
    assert g.main([str(tmp_path), "--hidden", "magnetic", "--seed", "3",
                   "--temperatures", "0", "--duration", "320"]) == 0
    out = capsys.readouterr().out
    assert '"hidden": "magnetic"' in out
    assert len(read_runs(tmp_path)) == 1
    with pytest.raises(SystemExit):
        g.main(["--help"])


# ---------------------------------------------------------------------------------------------
# The family (family.py)

from . import family as fam  # noqa: E402

SHORT = dict(start_temperatures_c=(-16.0, 43.0), duration_s=900.0)


def _allan(y, h_s, m):
    """Overlapping Allan deviation of rate samples y at tau = m h (NIST SP 1065, eq. (14)),
    from the integrated rate theta_k = h sum y."""
    th = np.concatenate([[0.0], np.cumsum(y) * h_s])
    d = th[2 * m:] - 2.0 * th[m:-m] + th[:-2 * m]
    return math.sqrt(np.mean(d ** 2) / (2.0 * (m * h_s) ** 2))


def test_family_same_seed_same_bytes_other_seed_other_unit(tmp_path):
    """Oracle: determinism (every draw from a SeedSequence of the seed): the same seed writes
    the same bytes and the same truth; other seeds draw other structures (of 10 seeds, the
    coil's layers, the TEC law, the noise law and the FOG thermometer's nodes are not all
    one value)."""
    t_a = fam.generate_family_set(tmp_path / "a", seed=11, hidden="magnetic", **SHORT)
    t_b = fam.generate_family_set(tmp_path / "b", seed=11, hidden="magnetic", **SHORT)
    fam.generate_family_set(tmp_path / "c", seed=12, hidden="magnetic", **SHORT)
    a, b, c = (_files(tmp_path / x) for x in "abc")
    assert a == b and t_a == t_b
    assert a.keys() == c.keys() and a != c
    draws = [fam.draw_unit(s) for s in range(10)]
    assert fam.draw_unit(11) == fam.draw_unit(11)
    assert len({d.unit.coil.n_layers for d in draws}) > 3
    assert len({d.unit.tec_law for d in draws}) > 1
    assert len({d.unit.bias_noise for d in draws}) > 1
    assert len({tuple(d.unit.fog_thermometer) for d in draws}) > 1
    assert len({d.paths for d in draws}) > 1
    # the public names are reached from generator.py too
    assert g.draw_unit is fam.draw_unit and g.generate_family_set is fam.generate_family_set


def test_family_draws_lie_in_their_ranges():
    """Oracle: the ranges of the README's table (fam.RANGES): over 200 seeds every recorded
    draw lies in its range, and the drawn unit itself agrees (the network's slowest time
    constant, the thermometer weights summing to 1, capacities and links positive, the laws
    from their lists); every law, path and sidecar choice occurs."""
    laws, noise, paths, sidecar, walls, patterns = set(), set(), set(), set(), set(), set()
    for seed in range(200):
        d = fam.draw_unit(seed)
        for name, value in d.drawn:
            lo, hi = fam.RANGES[name]
            assert lo <= value <= hi, (seed, name, value)
        u = d.unit
        names = {n for n, _ in d.drawn}
        assert {"coil.n_layers", "network.tau1_min", "tec.set_c", "gyro.arw_deg_per_rth_h",
                "strength.target", "soak.h", "thermometer.lag_s"} <= names
        assert 16 <= u.coil.n_layers <= 24 and u.coil.spacing == "cosine"
        assert u.winding.n_layers % wd.PERIOD[u.winding.pattern] == 0
        patterns.add(u.winding.pattern)
        tau1 = g.unit_network(u).time_constants_s()[0] / 60.0
        assert 20.0 <= tau1 <= 60.0
        housing = u.capacity_j_per_k["housing"] + u.capacity_j_per_k.get("base", 0.0)
        assert 2000.0 <= housing <= 4500.0
        assert all(c > 0 for c in u.capacity_j_per_k.values())
        assert all(gk > 0 for *_, gk in u.links_w_per_k)
        for weights in (u.fog_thermometer, *u.acc_thermometers.values()):
            assert abs(sum(weights.values()) - 1.0) < 1e-12
            assert all(0.0 <= w <= 1.0 for w in weights.values())
        assert all(10.0 <= v <= 60.0 for v in u.thermometer_lag_s.values())
        assert 18.0 <= u.tec_set_c <= 28.0
        assert len(d.runs) == 7 and all(2.0 <= r.soak_h <= 8.0 for r in d.runs)
        assert 1.0 <= d.strength_target <= 3.0
        laws.add(u.tec_law)
        noise.add(u.bias_noise)
        paths |= set(d.paths)
        sidecar.add(d.sidecar)
        walls.add((d.chamber.wander, d.chamber.cycle_shape))
    assert laws == set(g.TEC_LAWS) and noise == set(g.BIAS_NOISE_LAWS)
    assert paths == {"electronics-plate", "board-plate", "board-coil", "shell/base"}
    assert sidecar == {True, False} and len(walls) == 4
    assert patterns == set(fam.WINDING_PATTERNS)


def test_tec_laws_meet_their_closed_forms():
    """Oracle: each law's equation.  Piecewise: p0 inside the dead band, p0 + c_h (T_set -
    w/2 - T) below it, p0 + c_c (T - T_set - w/2) above.  Saturating: min(quadratic, P_max).
    Quadratic as drawn: its slope is -s_b at 45 K below the set point and +s_a at 40 K above
    (within the reference's 0.02-0.04 and 0.05-0.1 W/K), its minimum 3-20 K below."""
    u = g.Unit(tec_law="piecewise", tec_set_c=24.0, tec_p0_w=0.2, tec_heat_w_per_k=0.03,
               tec_cool_w_per_k=0.08, tec_dead_band_k=2.0)
    t = np.array([10.0, 23.0, 24.5, 25.0, 40.0])
    np.testing.assert_allclose(g.tec_power_w(u, t),
                               [0.2 + 0.03 * 13.0, 0.2, 0.2, 0.2, 0.2 + 0.08 * 15.0])
    q = g.Unit()
    s = replace(q, tec_law="saturating", tec_max_w=0.9)
    t = np.linspace(-40.0, 70.0, 23)
    np.testing.assert_allclose(g.tec_power_w(s, t), np.minimum(g.tec_power_w(q, t), 0.9))
    with pytest.raises(ValueError, match="valid: quadratic"):
        g.tec_power_w(replace(q, tec_law="linear"), 0.0)
    seen = 0
    for seed in range(60):
        u = fam.draw_unit(seed).unit
        if u.tec_law == "piecewise":
            continue
        seen += 1
        quad = replace(u, tec_law="quadratic")
        d = 1e-3
        slope = [(g.tec_power_w(quad, u.tec_set_c + x + d) - g.tec_power_w(quad, u.tec_set_c + x
                                                                         - d)) / (2 * d)
                 for x in (-45.0, 40.0)]
        assert 0.02 - 1e-9 <= -slope[0] <= 0.04 + 1e-9 and 0.05 - 1e-9 <= slope[1] <= 0.1 + 1e-9
        t_min = u.tec_set_c - u.tec_a_w_per_k / (2 * u.tec_c_w_per_k2)
        assert 3.0 - 1e-9 <= u.tec_set_c - t_min <= 20.0 + 1e-9
        assert 0.05 - 1e-9 <= g.tec_power_w(quad, t_min) <= 0.4 + 1e-9
    assert seen > 20


def test_bias_noise_laws_meet_their_allan_deviations():
    """Oracle: IEEE Std 952-1997 annex C, table C.1, on 10^6 samples at 1 Hz.  Flicker of
    bias instability B (a sum of Gauss-Markov processes with correlation times 2-20000 s):
    the Allan deviation is flat at 0.664 B from 30 to 3000 s (within 10 %: the sum's ripple
    and the estimate's scatter).  Rate random walk K: K sqrt(tau/3), tau in hours (within
    10 % at 10-1000 s).  Gauss-Markov sigma, T: sigma T/tau sqrt(2 tau/T - 3 + 4 exp(-tau/T)
    - exp(-2 tau/T)) (within 10 %), standard deviation sigma (within 5 %)."""
    rng = np.random.default_rng(20)
    n = 10 ** 6
    b = 0.003
    y = g.flicker_sum(rng, n, 1.0, b, g.Unit().flicker_taus_s)
    for m in (30, 100, 300, 1000, 3000):
        assert abs(_allan(y, 1.0, m) / (math.sqrt(2 * math.log(2) / math.pi) * b) - 1) < 0.1, m
    k = 0.002
    y = g.rate_random_walk(rng, n, 1.0, k)
    for m in (10, 100, 1000):
        assert abs(_allan(y, 1.0, m) / (k * math.sqrt(m / 3600.0 / 3.0)) - 1) < 0.1, m
    sigma, tc = 0.003, 400.0
    y = g.gauss_markov(rng, n, 1.0, sigma, tc)
    for m in (10, 100, 1000):
        x = m / tc
        want = sigma / x * math.sqrt(2 * x - 3 + 4 * math.exp(-x) - math.exp(-2 * x))
        assert abs(_allan(y, 1.0, m) / want - 1) < 0.1, m
    assert abs(np.std(y) / sigma - 1) < 0.05


@pytest.mark.parametrize("law", g.BIAS_NOISE_LAWS)
def test_each_noise_law_is_the_gyro_noise_floor(law):
    """Oracle: the run's gyro is the sum of its terms, the bias noise under its law's name;
    measure_strength's floor uses exactly ARW plus that term (no other noise term)."""
    run = g.simulate_run(17.0, duration_s=400.0, unit=replace(g.Unit(), bias_noise=law))
    terms = run.gyro_terms_dph
    assert law in terms and not set(g.BIAS_NOISE_LAWS) - {law} & set(terms)
    np.testing.assert_allclose(sum(terms.values()), run.columns["gyro_dph"], atol=1e-12)


def test_soak_start_is_the_unpowered_network_in_still_air():
    """Oracle: the unpowered linear network from a uniform T_from, left t_soak in still air at
    T0: T(0) = T0 + expm(A t_soak) (T_from - T0) 1 (the homogeneous solution), plus the run's
    common offset; the run's air is T0 throughout.  In a wandering chamber the run's air
    starts where the soak's ended and the start differs from the still one by less than the
    wander's and the cycling's size."""
    d = fam.draw_unit(5)
    still = replace(d, chamber=replace(d.chamber, wander="walk", walk_k_per_rth_s=0.0,
                                       cycle_k=0.0))
    net = g.unit_network(d.unit)
    for i, t0 in ((0, -32.0), (6, 54.0)):
        rd = d.run_draw(i)
        x0, air = fam.start_state(still, i, t0, duration_s=300.0)
        want = t0 + expm(net.a_per_s * 3600.0 * rd.soak_h) @ np.full(len(net.names),
                                                                      rd.soak_from_c - t0)
        np.testing.assert_allclose(x0, want + rd.offset_k, atol=1e-9)
        assert np.all(air == t0)
        x1, air1 = fam.start_state(d, i, t0, duration_s=300.0)
        assert np.max(np.abs(x1 - x0)) < 1.0 and np.max(np.abs(air1 - t0)) < 1.0
    # the start passes into the run: its first node temperatures are the start state
    run = fam.simulate_family_run(still, 0, -32.0, duration_s=300.0)
    np.testing.assert_allclose(run.temperature_c[0], fam.start_state(
        still, 0, -32.0, duration_s=300.0)[0], atol=0)


@pytest.mark.parametrize("hidden, rtol", [("magnetic", 1e-9), ("turn_on_transient", 1e-9),
                                          ("heat_source", fam.STRENGTH_RTOL),
                                          ("thermometer_lag", 0.05)])
def test_strength_scaling_hits_its_target(hidden, rtol):
    """Oracle: the definition of the strength (measure_strength's unabsorbed ratio on the
    set's own runs): after scaling, the ratio measured afresh on the runs with the effect is
    the target; exactly for an effect linear in its amplitude, within the secant's tolerance
    for a heat source (the TEC's working point moves) unless its power is clipped at the top
    of its place's range (then short of it), within 5 % for a lag (bisected on the
    effect-free runs; the quantiser then sees other values)."""
    d = fam.draw_unit(7)
    # a heat source sits where a drawn unit dissipates heat (fam.HEAT_PLACES), not in the
    # winding: the family's own place for it (seed 7: the electronics, at most 1.5 W)
    p = g._check_hidden(hidden, fam._hidden_params(7, hidden) if hidden == "heat_source"
                        else None)
    for target in (1.0, 2.5):
        out, s, runs = fam.scale_to_strength(d, hidden, p, target,
                                             start_temperatures_c=(-16.0, 43.0),
                                             duration_s=2400.0)
        key = g.unabsorbed_ratio_key(hidden)
        if hidden == "heat_source" and out["power"] == fam.HEAT_PLACES[out["node"]][1]:
            assert s[key] < target     # clipped at the place's power: falls short, as documented
            continue
        assert abs(s[key] / target - 1) <= rtol, (target, s[key], out)
        assert len(runs) == 2 and out[fam.AMPLITUDE[hidden]] > 0


def test_family_files_and_truth(tmp_path):
    """Oracle: the format spec and the truth's definition: the family's files load with
    read_runs; a set whose draw records the soak gives soak_from_c and soak_h in every
    sidecar (the draw's values, rounded as a log book would), another gives neither; the
    truth says the hidden effect, its strength (target = the draw's, achieved near it), the
    draw's description; an amplitude given in params is kept (target None)."""
    with_sc = next(s for s in range(20) if fam.draw_unit(s).sidecar)
    without = next(s for s in range(20) if not fam.draw_unit(s).sidecar)
    t = fam.generate_family_set(tmp_path / "a", seed=with_sc, hidden="outside", **SHORT)
    runs = read_runs(tmp_path / "a")
    d = fam.draw_unit(with_sc)
    for i, r in enumerate(sorted(runs, key=lambda r: r.name)):
        assert r.meta.extra == {"soak_from_c": round(d.runs[i].soak_from_c, 1),
                                "soak_h": round(d.runs[i].soak_h, 2)}
    assert t["hidden"] == "outside" and t["seed"] == with_sc and t["soak_sidecar"]
    assert t["strength"]["target"] == d.strength_target
    assert abs(t["strength"]["achieved"] / d.strength_target - 1) < 1e-9
    assert t["family"] == d.describe() and t["family"].startswith(f"seed {with_sc}:")
    t = fam.generate_family_set(tmp_path / "b", seed=without, hidden="magnetic",
                                params={"m": 0.02}, **SHORT)
    assert all(r.meta.extra == {} for r in read_runs(tmp_path / "b"))
    assert t["params"]["m"] == 0.02 and t["strength"]["target"] is None
    t = fam.generate_family_set(tmp_path / "c", seed=without, **SHORT)
    assert t["hidden"] is None and t["strength"] is None


def test_family_command_line(tmp_path, capsys):
    """Oracle: the documented command line (--family) writes the drawn unit's runs and prints
    the truth with the draw's description."""
    assert g.main([str(tmp_path), "--family", "--hidden", "magnetic", "--seed", "3",
                   "--temperatures", "0", "--duration", "320"]) == 0
    out = capsys.readouterr().out
    assert '"family": "seed 3:' in out and '"ratio": "ratio_detrended"' in out
    assert len(read_runs(tmp_path)) == 1


# ---------------------------------------------------------------------------------------------
# Power cycles (warm restarts)

SPANS = ((2400.0, 3600.0),)


def test_no_power_cycle_is_the_previous_run_byte_for_byte(tmp_path):
    """Oracle: the behaviour before power cycles existed, i.e. the default call: with
    ``power_off_s=()`` every column, node temperature, power and gyro term is the same array
    bit for bit, no ``powered`` column appears and the written files are the same bytes (for
    the fixed unit with and without a hidden effect, and for a drawn unit)."""
    d = fam.draw_unit(4)
    pairs = [(g.simulate_run(-16.0, seed=3, duration_s=900.0),
              g.simulate_run(-16.0, seed=3, duration_s=900.0, power_off_s=())),
             (g.simulate_run(43.0, seed=3, duration_s=900.0, hidden="turn_on_transient"),
              g.simulate_run(43.0, seed=3, duration_s=900.0, hidden="turn_on_transient",
                             power_off_s=[])),
             (fam.simulate_family_run(d, 1, 17.0, duration_s=900.0, hidden="heat_source"),
              fam.simulate_family_run(d, 1, 17.0, duration_s=900.0, hidden="heat_source",
                                      power_off_s=()))]
    for k, (a, b) in enumerate(pairs):
        assert a.columns.keys() == b.columns.keys() and g.POWERED_COLUMN not in b.columns
        for c in a.columns:
            assert np.array_equal(a.columns[c], b.columns[c]), c
        for x, y in ((a.temperature_c, b.temperature_c), (a.power_w, b.power_w),
                     (a.rate_c_per_s, b.rate_c_per_s)):
            assert np.array_equal(x, y)
        for c in a.gyro_terms_dph:
            assert np.array_equal(a.gyro_terms_dph[c], b.gyro_terms_dph[c]), c
        for run, where in ((a, tmp_path / f"a{k}"), (b, tmp_path / f"b{k}")):
            where.mkdir()
            g._write_run(run, where, latitude_deg=30.26, true_heading_deg=212.7,
                         sample_rate_hz=1.0)
        assert _files(tmp_path / f"a{k}") == _files(tmp_path / f"b{k}")


def test_power_cycle_columns_nan_while_off_and_powered_column(tmp_path):
    """Oracle: the power-cycle semantics (docs/power_cycles.md) and the format spec: while
    off (t_off <= t < t_on) the unit's own columns are NaN and ``powered`` is 0, elsewhere
    finite and 1; time, turntable and chamber record throughout; nfs reads the files, finds
    the span back from the ``powered`` column, and before the switch-off the run is the run
    without a power cycle (nothing acts before its cause); the node powers are zero while
    off and the TEC and constant powers back after."""
    base = g.simulate_run(17.0, seed=5, duration_s=6000.0)
    run = g.simulate_run(17.0, seed=5, duration_s=6000.0, power_off_s=SPANS)
    t = run.columns["time_s"]
    off = (t >= 2400.0) & (t < 3600.0)
    assert np.array_equal(run.columns[g.POWERED_COLUMN], np.where(off, 0.0, 1.0))
    for c in g._UNIT_COLUMNS:
        assert np.all(np.isnan(run.columns[c][off])), c
        assert np.all(np.isfinite(run.columns[c][~off])), c
    for c in ("time_s", "position_deg", "moving", "temp_chamber_c"):
        assert np.all(np.isfinite(run.columns[c])) and np.array_equal(run.columns[c],
                                                                      base.columns[c]), c
    before = t < 2400.0
    for c in g._UNIT_COLUMNS:
        assert np.array_equal(run.columns[c][before], base.columns[c][before]), c
    assert np.all(run.power_w[off] == 0.0) and np.all(run.power_w[~off].sum(axis=1) > 2.0)
    g._write_run(run, tmp_path, latitude_deg=30.26, true_heading_deg=212.7,
                 sample_rate_hz=1.0)
    header = next(tmp_path.glob("*.csv")).read_text().splitlines()[0]
    assert header.endswith(",powered")
    (r,) = read_runs(tmp_path)
    assert np.array_equal(r[g.POWERED_COLUMN], run.columns[g.POWERED_COLUMN])
    assert np.array_equal(np.isnan(r["gyro_dph"]), off)
    from nfs.power import off_spans_s
    assert off_spans_s(r["time_s"], r[g.POWERED_COLUMN]) == SPANS
    with pytest.raises(ValueError, match="0 < switched off"):
        g.simulate_run(17.0, duration_s=100.0, power_off_s=((0.0, 50.0),))
    with pytest.raises(ValueError, match="overlap"):
        g.simulate_run(17.0, duration_s=100.0, power_off_s=((10.0, 50.0), (40.0, 60.0)))


def test_nodes_relax_towards_the_chamber_while_off():
    """Oracle: with no heat released inside, a network of positive conductances to a held
    chamber at T0 relaxes towards T0: after 40 min on (every node above T0) the capacity-
    weighted mean node temperature falls at every step of the off span and stays above T0,
    and it rises again after the switch-on; energy balance over the whole run (stored =
    electrical in - lost to the chamber, trapezoid rule) holds with the gated powers."""
    run = g.simulate_run(28.0, duration_s=6000.0, noise=False, power_off_s=SPANS)
    net = g.unit_network(g.Unit())
    cap = net.capacity_j_per_k
    mean = run.temperature_c @ cap / cap.sum()
    t = run.columns["time_s"]
    off = (t >= 2400.0) & (t < 3600.0)
    assert np.all(run.temperature_c[2400] > 28.0)
    assert np.all(np.diff(mean[2400:3601]) < 0.0)
    assert mean[3600] > 28.0 and mean[3600] < mean[2400] - 1.0
    assert mean[4200] > mean[3600]
    # and a run left on is warmer at the switch-on time
    left_on = g.simulate_run(28.0, duration_s=6000.0, noise=False)
    assert np.all(left_on.temperature_c[3600] > run.temperature_c[3600])
    stored = (run.temperature_c - run.temperature_c[0]) @ cap
    loss = (run.temperature_c - run.chamber_c[:, None]) @ net.boundary_w_per_k[:, 0]
    net_in = run.power_w.sum(axis=1) - loss
    # powers are held over each 1 s step (gated at its start): integrate them as steps and
    # the smooth loss by the trapezoid rule (O(h^2) on it: 4e-9 relative here)
    integral = np.sum(run.power_w.sum(axis=1)[:-1]) - np.sum(0.5 * (loss[1:] + loss[:-1]))
    assert abs(stored[-1] - integral) < 1e-6 * abs(stored[-1]), (stored[-1], integral)
    np.testing.assert_allclose(run.rate_c_per_s @ cap, net_in, rtol=1e-9, atol=1e-9)
    assert np.all(run.power_w[off] == 0.0)


@pytest.mark.parametrize("spans", [SPANS, ((1000.0, 1030.0), (2500.0, 2560.5))])
def test_turn_on_transient_restarts_at_each_switch_on(spans):
    """Oracle: the transient's definition in the time since the latest switch-on, a
    exp(-t_on / tau): without noise, the gyro with the hidden transient minus the gyro
    without it is a at t = 0 and at the first sample of every restart on the grid (within
    1e-9), a exp(-(t - t_on)/tau) at every powered sample (a restart between samples gives
    the first sample after it its fraction of a second), NaN while off."""
    a, tau = 0.12, 150.0
    kw = dict(duration_s=4000.0, noise=False, power_off_s=spans)
    base = g.simulate_run(-5.0, **kw)
    hid = g.simulate_run(-5.0, hidden="turn_on_transient", params={"a": a, "tau": tau}, **kw)
    d = hid.columns["gyro_dph"] - base.columns["gyro_dph"]
    t = base.columns["time_s"]
    assert abs(d[0] - a) < 1e-9
    last = np.zeros_like(t)
    for t_off, t_on in spans:
        k = int(np.searchsorted(t, t_on))
        if t[k] == t_on:
            assert abs(d[k] - a) < 1e-9, t_on
        last[t >= t_on] = t_on
    on = base.columns[g.POWERED_COLUMN] > 0.5
    np.testing.assert_allclose(d[on], a * np.exp(-(t[on] - last[on]) / tau), atol=1e-9,
                               rtol=0)
    assert np.all(np.isnan(d[~on]))
    # everything else in the gyro is the same run: the thermal history does not see it
    assert np.array_equal(hid.temperature_c, base.temperature_c)


def test_family_run_passes_power_cycles_and_a_chamber_ramp_through():
    """Oracle: pass-through: a drawn unit's run with a power cycle is the generator's run of
    that unit with the same start, air and spans; a chamber offset (a ramp of +20 K at
    1 K/min from 1200 s) is added to the drawn air sample by sample, and the unit follows
    it (warmer than the run without it at the end)."""
    d = fam.draw_unit(9)
    start = fam.start_state(d, 7, -16.0, duration_s=4000.0)
    run = fam.simulate_family_run(d, 7, -16.0, duration_s=4000.0, power_off_s=SPANS,
                                  start=start)
    ref = g.simulate_run(-16.0, seed=d.noise_seed, run_index=7, duration_s=4000.0,
                         unit=d.unit, chamber_c=start[1], initial_c=start[0],
                         power_off_s=SPANS)
    for c in ref.columns:
        assert np.array_equal(run.columns[c], ref.columns[c], equal_nan=True), c
    t = np.arange(4000.0)
    ramp = np.clip((t - 1200.0) / 60.0, 0.0, 20.0)
    up = fam.simulate_family_run(d, 7, -16.0, duration_s=4000.0, start=start,
                                 chamber_offset_c=ramp)
    flat = fam.simulate_family_run(d, 7, -16.0, duration_s=4000.0, start=start)
    np.testing.assert_allclose(up.chamber_c - flat.chamber_c, ramp, atol=1e-12)
    assert np.all(up.temperature_c[-1] > flat.temperature_c[-1] + 5.0)
    with pytest.raises(ValueError, match="chamber_offset_c"):
        fam.simulate_family_run(d, 7, -16.0, duration_s=4000.0, start=start,
                                chamber_offset_c=ramp[:10])


def test_turntable_dwell_is_a_parameter(tmp_path):
    """Oracle: the schedule's definition (4 positions, a dwell then a move, back to back from
    power-on) and the format spec: with a 75 s dwell and 10 s moves a 1700 s run holds 20
    moves of 10 samples, the table leaves 0 deg at 75 s and dwells at 90 deg from 85 s, and the sidecar says dwell_s = 75,
    which nfs reads back; the family passes the dwell through."""
    run = g.simulate_run(17.0, duration_s=1700.0, dwell_s=75.0)
    assert run.columns["moving"].sum() == 200
    pos, mv = run.columns["position_deg"], run.columns["moving"]
    assert pos[74] == 0.0 and mv[74] == 0 and mv[75] == 1 and pos[85] == 90.0 and mv[85] == 0
    g._write_run(run, tmp_path, latitude_deg=30.26, true_heading_deg=212.7,
                 sample_rate_hz=1.0)
    (r,) = read_runs(tmp_path)
    assert r.meta.dwell_s == 75.0 and r.meta.move_s == 10.0
    d = fam.draw_unit(9)
    f = fam.simulate_family_run(d, 7, 17.0, duration_s=1700.0, dwell_s=75.0)
    assert np.array_equal(f.columns["moving"], run.columns["moving"]) and f.dwell_s == 75.0
    with pytest.raises(ValueError, match="dwell_s > 0"):
        g.simulate_run(17.0, duration_s=100.0, dwell_s=0.0)
