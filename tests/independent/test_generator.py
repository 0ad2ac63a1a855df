"""Tests of the independent run generator (tests/independent/generator.py).

The generator imports nothing from nfs; these tests may, to read what it writes.  Each test
states its oracle.  Runs are short (a few hundred to 3000 s) except where a time constant
needs the length.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from nfs.io.measurement import REQUIRED_COLUMNS, read_runs

from . import generator as g

TEMPS = (-32.0, 17.0, 54.0)


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_imports_nothing_from_nfs():
    """Oracle: the generator's own source; its imports are the standard library, NumPy
    and SciPy only (an independent truth must not share code with the model)."""
    tree = ast.parse(Path(g.__file__).read_text(encoding="utf-8"))
    roots = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            roots |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            roots.add((node.module or "").split(".")[0])
    assert not roots & {"nfs", "thermal"}
    assert roots <= {"__future__", "argparse", "json", "math", "sys", "dataclasses",
                     "pathlib", "numpy", "scipy"}


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
