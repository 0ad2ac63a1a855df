"""Run-to-run and unit-to-unit variability (nfs/variability.py, ``units`` and ``[variability]``).

Oracles: the chain without variability (``preset = "none"`` must give the bytes of the
RunConditions every scenario made before units existed); determinism (same seed, same
bytes); the independence of the SeedSequence streams (adding a unit changes no other unit);
closed forms (a one-node soak decays as exp(-t G / C); a log-normal factor has mean 1 and the
stated standard deviation; an Ornstein-Uhlenbeck process has the stated variance and
correlation exp(-lag / tau)); and sample statistics over many draws, each with its tolerance.
"""

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import thermal
from nfs.errors import ScenarioError
from nfs.conditions import RunConditions
from nfs.experiment import simulate_run
from nfs.io.measurement import write_run
from nfs.config.scenario import load_scenario
from nfs.parameters import get_param
from nfs.variability import (NO_VARIABILITY, REALISTIC, Variability, chamber_terms,
                             lognormal_factor, start_up_state, unit_instrument, unit_scatter)

SHORT = 1300.0          # two 4-position cycles


def _write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _text(scenario_text, extra="", *, temps=(-20.0, 40.0), seed=7, duration=SHORT):
    """A small scenario; the top-level keys of ``extra`` (before its first table) go first."""
    lines = extra.splitlines(keepends=True)
    k = next((i for i, line in enumerate(lines) if line.startswith("[")), len(lines))
    return "".join(lines[:k]) + scenario_text("v", seed, temps, duration,
                                              extra="".join(lines[k:]))


def _scenario(tmp_path, scenario_text, extra="", *, temps=(-20.0, 40.0), seed=7,
              duration=SHORT, name="s.toml"):
    return load_scenario(_write(tmp_path, _text(scenario_text, extra, temps=temps, seed=seed,
                                                duration=duration), name))


def _columns_equal(a, b):
    assert a.columns.keys() == b.columns.keys()
    for k in a.columns:
        np.testing.assert_array_equal(a.columns[k], b.columns[k], err_msg=k)


# ------------------------------------------------------------------------------ no variability

def test_preset_none_gives_the_runs_of_before(tmp_path, scenario_text):
    # Oracle: the RunConditions a scenario made before units and variability existed
    # (name {name}_T{T0}C_r{r}, seed (seed, i, r), soaked at T0, chamber at T0); the same
    # measurement files, byte for byte.
    plain = _scenario(tmp_path, scenario_text, "repeats = 2\n", name="a.toml")
    none = _scenario(tmp_path, scenario_text, 'repeats = 2\n[variability]\npreset = "none"\n',
                     name="b.toml")
    assert none.variability.active is False and plain.variability == NO_VARIABILITY
    for k, (c, d) in enumerate(zip(plain.conditions(), none.conditions())):
        i, r = divmod(k, 2)
        old = RunConditions(name=f"v_T{plain.start_temperatures_c[i]:+g}C_r{r}",
                            start_temperature_c=plain.start_temperatures_c[i],
                            latitude_deg=30.0, true_heading_deg=40.0, schedule=plain.schedule,
                            duration_s=SHORT, seed=(7, i, r))
        assert (c.name, c.seed, d.name, d.seed) == (old.name, old.seed, old.name, old.seed)
        runs = [simulate_run(plain.instrument, x).run for x in (old, c, d)]
        files = [write_run(run, tmp_path / f"out{j}") for j, run in enumerate(runs)]
        texts = [f.read_bytes() for f in files]
        assert texts[0] == texts[1] == texts[2]


def test_zero_scatter_is_the_nominal_world(tmp_path, scenario_text):
    # A [variability] table whose every value is zero is the same world as preset "none".
    zero = "\n".join(f"{k} = 0.0" for k in ("soak_offset_c", "soak_node_c", "chamber_wander_c",
                                            "cycling_c", "thermometer_offset_c",
                                            "capacity_rel_std", "conductance_rel_std",
                                            "power_rel_std", "effect_rel_std"))
    sc = _scenario(tmp_path, scenario_text,
                   f"[variability]\nunfinished_soak = false\n{zero}\n")
    assert not sc.variability.active and sc.variability.preset == "realistic (modified)"
    c = sc.conditions()[0]
    assert c.variability is None


# ------------------------------------------------------------------------------ determinism

@pytest.fixture(scope="module")
def default():
    """The default scenario (the realistic set) made by 3 units, shortened to 2 cycles."""
    return dataclasses.replace(load_scenario(), units=3, duration_s=SHORT)


def test_default_scenario_holds_the_realistic_set():
    sc = load_scenario()
    assert sc.units == 1
    assert sc.variability == dataclasses.replace(REALISTIC, unit_seed=sc.seed)
    assert sc.unit_split(sc.compensation.train_units, sc.compensation.test_units) == \
        ((0,), (0,))


def test_fleet_scenario_trains_and_tests_on_different_units():
    sc = load_scenario(Path(__file__).resolve().parents[1] / "scenarios"
                       / "startup_7temps_fleet.toml")
    assert sc.units == 3 and sc.variability == dataclasses.replace(REALISTIC, unit_seed=sc.seed)
    assert sc.compensation.train_units == (0, 1)
    assert sc.compensation.test_units == (2,)


def test_same_seed_same_bytes(default, tmp_path):
    c = dataclasses.replace(default, repeats=3).conditions()[2]
    assert c.unit == 2 and c.variability is not None
    a, b = (write_run(simulate_run(default.instrument, c).run, tmp_path / d).read_bytes()
            for d in ("a", "b"))
    assert a == b


def test_adding_a_unit_changes_no_other_units_draws(default):
    # Start-up k of unit u keeps its seed (seed, i, k[, u]) and its unit's parameters,
    # whatever the number of units.
    two = dataclasses.replace(default, units=2, repeats=2, start_temperatures_c=(-32.0,))
    three = dataclasses.replace(default, units=3, repeats=6, start_temperatures_c=(-32.0,))
    by_key = {}
    for c in three.conditions():
        by_key[(c.unit, c.name.rsplit("_r", 1)[1])] = c
    for c in two.conditions():
        d = by_key[(c.unit, c.name.rsplit("_r", 1)[1])]
        assert (c.seed, c.name) == (d.seed, d.name)
        a, b = simulate_run(two.instrument, c), simulate_run(three.instrument, d)
        _columns_equal(a.run, b.run)
    assert [c.unit for c in three.conditions()] == [0, 1, 2, 0, 1, 2]


def test_a_parameter_draw_depends_only_on_its_unit_and_path(default):
    # Oracle: the CRC-keyed streams; an instrument with one effect fewer draws the same
    # values for every other parameter.
    inst = default.instrument
    var = default.variability
    fewer = inst.with_effects([e for e in inst.effects if e.name != "turn_on_transient"])
    a, b = unit_instrument(inst, var, 4), unit_instrument(fewer, var, 4)
    for path in unit_scatter(fewer, var):
        assert get_param(a, path) == get_param(b, path), path
    assert get_param(a, "effects.shupe_winding.k_m") != \
        get_param(unit_instrument(inst, var, 5), "effects.shupe_winding.k_m")
    # a design's constants are the same in every unit (the fibre's length and dn/dT)
    for path in ("effects.shupe_winding.L", "effects.shupe_winding.dn_dT"):
        assert get_param(a, path) == get_param(inst, path) and path not in unit_scatter(inst, var)


# ------------------------------------------------------------------------------ the world varies

def test_two_start_ups_differ_beyond_noise(default):
    # Run-to-run: two start-ups of one unit at one T0 have noise-free coil temperature
    # histories that differ by more than ten times the thermometer noise (0.01 K); without
    # variability they are identical.  Unit-to-unit: the drift averaged over a 150 s dwell
    # differs by more than twice the white noise of such an average, N 60 / sqrt(150) deg/h.
    sc = dataclasses.replace(default, repeats=6, start_temperatures_c=(17.0,), duration_s=3600.0)
    sims = [simulate_run(sc.instrument, c) for c in sc.conditions()]
    u0a, u0b = sims[0], sims[3]
    assert u0a.conditions.unit == u0b.conditions.unit == 0
    coil = [s.thermal.node("coil_1") for s in (u0a, u0b)]
    assert np.max(np.abs(coil[0] - coil[1])) > 0.1
    noise = sc.instrument.thermometers["fog"].noise_c
    assert noise <= 0.01

    def dwell_means(x):
        return x[:3600].reshape(-1, 150).mean(axis=1)

    arw = sc.instrument.gyro.arw_deg_per_rth_h * 60.0 / np.sqrt(150.0)
    d = dwell_means(sims[0].drift_dph - sims[1].drift_dph)     # units 0 and 1
    assert np.sqrt(np.mean(d ** 2)) > 2.0 * arw

    flat = dataclasses.replace(sc, variability=NO_VARIABILITY, units=1)
    a, b = (simulate_run(flat.instrument, c) for c in flat.conditions()[:2])
    np.testing.assert_array_equal(a.thermal.temperature_c, b.thermal.temperature_c)
    np.testing.assert_array_equal(a.drift_dph, b.drift_dph)


def test_run_names_and_notes_record_the_unit(default):
    from nfs.studies.scenario_runs import run_scenario, uncompensated_table
    sc = dataclasses.replace(default, repeats=3, start_temperatures_c=(17.0,))
    names = [c.name for c in sc.conditions()]
    assert names == ["startup_7temps_T+17C_u0_r0", "startup_7temps_T+17C_u1_r0",
                     "startup_7temps_T+17C_u2_r0"]
    notes = " ".join(uncompensated_table(run_scenario(sc)).notes)
    assert "units 0, 1, 2 of 3" in notes and "realistic" in notes


# ------------------------------------------------------------------------------ statistics

def test_lognormal_factor_mean_and_std():
    # Closed form: mean 1 and standard deviation rel for z ~ N(0, 1) (checked by quadrature).
    x, w = np.polynomial.hermite_e.hermegauss(80)
    w = w / w.sum()
    for rel in (0.05, 0.2, 1.0):
        f = lognormal_factor(x, rel)
        m = np.sum(w * f)
        assert m == pytest.approx(1.0, rel=1e-10)
        assert np.sqrt(np.sum(w * (f - m) ** 2)) == pytest.approx(rel, rel=1e-8)


def test_unit_scatter_matches_its_stated_std(default):
    # 400 units: the sample standard deviation of a relative draw lies within 15 % of the
    # stated one (4 sigma of a sample std over 400 draws is about 14 %), the mean factor
    # within 4 sigma / sqrt(400) of 1, and a coefficient never changes sign.
    inst, var = default.instrument, default.variability
    paths = {"thermal.nodes.housing.capacity_j_per_k": var.capacity_rel_std,
             "thermal.links.housing-chamber.conductance_w_per_k": var.conductance_rel_std,
             "thermal.nodes.board.power_w": var.power_rel_std,
             "effects.tec_power.c_h": var.power_rel_std,
             "effects.shupe_winding.k_m": var.effect_rel_std,
             "coil.heat_capacity_j_per_m3_k": var.capacity_rel_std,
             "coil.outer_contacts.housing": var.conductance_rel_std,
             "effects.acc_bias_temperature:y.b_q1": var.effect_rel_std}
    units = [unit_instrument(inst, var, u) for u in range(400)]
    for path, rel in paths.items():
        f = np.array([get_param(u, path) for u in units]) / get_param(inst, path)
        assert np.all(f > 0), path
        assert f.mean() == pytest.approx(1.0, abs=4 * rel / 20), path
        assert f.std(ddof=1) == pytest.approx(rel, rel=0.15), path
    off = np.array([u.thermometers["acc_x"].offset_c for u in units])
    assert off.std(ddof=1) == pytest.approx(var.thermometer_offset_c, rel=0.15)
    # set points and angles are not coefficients
    assert {get_param(u, "effects.tec_power.T_set") for u in units} == {25.0}
    assert "effects.tec_power.T_set" not in unit_scatter(inst, var)


def _initial(inst, var, t0_c, entropy):
    return start_up_state(inst, var, t0_c, np.arange(10.0), entropy)[0]


def test_soak_scatter_matches_its_stated_std(default):
    # Complete soak in still air: T(0) - T0 = common + e, e = sum_i s_i z_i v_i along the
    # network's free modes with s_i^2 = soak_node^2 tau_i / tau_1, so over 600 start-ups a
    # node's std is sqrt(soak_offset^2 + sum_i s_i^2 v_ji^2) and a difference of two nodes
    # sqrt(sum_i s_i^2 (v_ji - v_ki)^2): two layers of the wound coil, which equalise within
    # seconds, start far closer than two nodes drawn apart (sqrt(2) soak_node).
    var = Variability(soak_offset_c=0.2, soak_node_c=0.1)
    inst = default.instrument
    t0 = np.array([_initial(inst, var, 17.0, (3, k)) for k in range(600)]) - 17.0
    taus, v = inst.network.modes()
    var_e = (v ** 2) @ (var.soak_node_c ** 2 * taus / taus[0])
    names = inst.network.node_names
    h, e = names.index("housing"), names.index("electronics")
    assert t0[:, h].std(ddof=1) == pytest.approx(np.hypot(var.soak_offset_c,
                                                           np.sqrt(var_e[h])), rel=0.15)
    for a, b in ((h, e), (names.index("coil_3"), names.index("coil_4"))):
        want = np.sqrt((v[a] - v[b]) ** 2 @ (var.soak_node_c ** 2 * taus / taus[0]))
        assert (t0[:, a] - t0[:, b]).std(ddof=1) == pytest.approx(want, rel=0.15)
    layers = t0[:, names.index("coil_3")] - t0[:, names.index("coil_4")]
    assert layers.std(ddof=1) < 0.2 * np.sqrt(2) * var.soak_node_c


def test_unfinished_soak_of_one_node_is_exponential():
    # Closed form: one node (C, G to the chamber) brought from T_from into the chamber at T0
    # for t_soak: T(0) - T0 = (T_from - T0) exp(-t_soak G / C).
    net = thermal.Network(nodes=(thermal.Node("m", 3600.0, power_w=5.0),),
                          links=(thermal.Link("m", "chamber", 1.0),))
    var = Variability(unfinished_soak=True, soak_from_c=23.0, soak_h=2.0)
    got = _initial(SimpleNamespace(network=net), var, -32.0, 1)
    assert got[0] - (-32.0) == pytest.approx(55.0 * np.exp(-2.0), rel=1e-9)


def test_soak_under_a_wandering_chamber_is_its_low_pass():
    # Closed form: a node of time constant tau_n = C / G driven by Ornstein-Uhlenbeck air
    # (sigma, tau_w) has the stationary variance sigma^2 tau_w / (tau_w + tau_n); at power-on
    # after a 4 h soak, over 400 start-ups within 15 % (std), and the node follows its air
    # (positive correlation with the chamber's wander at t = 0, which the run continues).
    net = thermal.Network(nodes=(thermal.Node("m", 600.0),),
                          links=(thermal.Link("m", "chamber", 1.0),))
    var = Variability(chamber_wander_c=0.1, chamber_wander_tau_s=600.0)
    got = [start_up_state(SimpleNamespace(network=net), var, 5.0, np.arange(10.0), (8, k))
           for k in range(400)]
    node = np.array([g[0][0] for g in got]) - 5.0
    air = np.array([g[1][0] for g in got])
    assert node.std() == pytest.approx(0.1 * np.sqrt(600.0 / 1200.0), rel=0.15)
    assert np.corrcoef(node, air)[0, 1] > 0.5


def test_chamber_wander_and_cycling_statistics():
    # Ornstein-Uhlenbeck: variance sigma^2 at every sample (started stationary) and
    # correlation exp(-lag / tau); over 2000 start-ups within 10 % (std) and 0.06 (corr).
    # Cycling: amplitude a (max over a long run), random phase (the mean at t = 0 about 0).
    t = np.arange(0.0, 1201.0)
    wander = Variability(chamber_wander_c=0.1, chamber_wander_tau_s=600.0)
    uneven = np.concatenate([t[:600], t[600:] + 0.5])     # the loop and the filter agree
    np.testing.assert_allclose(chamber_terms(wander, uneven, 1)[:600],
                               chamber_terms(wander, t, 1)[:600], rtol=1e-12, atol=1e-15)
    w = np.array([chamber_terms(wander, t, (5, k)) for k in range(2000)])
    assert w[:, 0].std() == pytest.approx(0.1, rel=0.1)
    assert w[:, -1].std() == pytest.approx(0.1, rel=0.1)
    assert np.corrcoef(w[:, 0], w[:, 600])[0, 1] == pytest.approx(np.exp(-1.0), abs=0.06)
    cyc = Variability(cycling_c=0.1, cycling_period_s=600.0, cycling_period_rel_std=0.1)
    c = np.array([chamber_terms(cyc, t, (6, k)) for k in range(400)])
    assert np.max(np.abs(c)) == pytest.approx(0.1, rel=1e-3)
    assert abs(c[:, 0].mean()) < 4 * 0.1 / np.sqrt(2 * 400)
    tri = chamber_terms(dataclasses.replace(cyc, cycling_shape="triangle"), t, (6, 0))
    assert np.max(np.abs(np.diff(tri))) <= 4 * 0.1 / 500.0      # slope 4 a / P, P >= 500 s


# ------------------------------------------------------------------------------ bad values

@pytest.mark.parametrize("extra, key, words", [
    ("[variability]\nsoak_node_c = -0.1\n", "variability.soak_node_c", ">= 0"),
    ("[variability]\neffect_rel_std = -1\n", "variability.effect_rel_std", ">= 0"),
    ("[variability]\nsoak_nodes_c = 0.1\n", "variability.soak_nodes_c", "unknown key"),
    ('[variability]\npreset = "typical"\n', "variability.preset", "realistic"),
    ('[variability]\ncycling_shape = "square"\n', "variability.cycling_shape", "triangle"),
    ("[variability]\nchamber_wander_tau_s = 0\n", "variability.chamber_wander_tau_s", "> 0"),
    ("[variability]\nunfinished_soak = 1\n", "variability.unfinished_soak", "true or false"),
    ('[variability.parameters]\n"effects.shupe_windng.k_m" = 0.3\n',
     'variability.parameters."effects.shupe_windng.k_m"', "shupe_winding"),
    ('[variability.parameters]\n"effects.shupe_winding.k_m" = -0.3\n',
     'variability.parameters."effects.shupe_winding.k_m"', ">= 0"),
    ("[variability.parameters]\neffects.shupe_winding.k_m = 0.3\n",
     'variability.parameters."effects"', "quote"),
    ('variability = "none"\n', "variability", "preset"),
    ("units = 0\n", "units", ">= 1"),
    ("units = 2\n[compensation]\ntest_units = [2]\n", "compensation.test_units", "out of range"),
    ("units = 2\n[compensation]\ntrain_units = [0, 0]\n", "compensation.train_units", "twice"),
    ("[compensation]\ntrain_units = []\n", "compensation.train_units", "non-empty"),
])
def test_bad_values_are_located(tmp_path, scenario_text, extra, key, words):
    path = _write(tmp_path, _text(scenario_text, extra, temps=(20.0,), seed=1))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    msg = str(err.value)
    assert key in msg and words in msg and str(path) in msg and "\n" not in msg, msg


def test_bad_variability_exits_2_with_one_line(tmp_path, cli, scenario_text):
    path = _write(tmp_path, scenario_text("v", 1, (20.0,), SHORT)
                  + "[variability]\nsoak_offset_c = -0.2\n")
    code, out, err = cli("table", path, "-o", tmp_path / "t", "--no-compensation")
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and "variability.soak_offset_c" in lines[0]
    assert "Traceback" not in err and not (tmp_path / "t").exists()


def test_parameters_of_ones_own(tmp_path, scenario_text):
    sc = _scenario(tmp_path, scenario_text,
                   '[variability]\npreset = "custom"\n[variability.parameters]\n'
                   '"effects.shupe_winding.k_m" = 0.3\n"thermometers.*.lag_s" = { std = 5.0 }\n')
    scatter = unit_scatter(sc.instrument, sc.variability)
    assert scatter == {"effects.shupe_winding.k_m": (0.3, True),
                       "thermometers.fog.lag_s": (5.0, False),
                       "thermometers.acc_x.lag_s": (5.0, False),
                       "thermometers.acc_y.lag_s": (5.0, False)}
    assert sc.variability.per_unit and not sc.variability.per_start_up
    assert sc.variability.preset == "custom"


def test_preset_none_switches_a_written_table_off(tmp_path):
    # The default scenario's table, every value written, with preset = "none": no variability
    # (the keys are still checked: a negative one is still an error).
    text = load_scenario().path.read_text().replace('preset = "realistic"', 'preset = "none"')
    sc = load_scenario(_write(tmp_path, text))
    assert sc.variability == NO_VARIABILITY and sc.units == 1
    bad = text.replace("soak_node_c = ", "soak_node_c = -")
    assert bad != text
    with pytest.raises(ScenarioError, match="variability.soak_node_c"):
        load_scenario(_write(tmp_path, bad, "bad.toml"))


# ------------------------------------------------------------------------------ the study

def test_unit_split_defaults(default):
    assert default.unit_split() == ((0, 1), (2,))
    assert default.unit_split(None, (0,)) == ((1, 2), (0,))
    assert default.unit_split((1,), None) == ((1,), (2,))
    one = dataclasses.replace(default, units=1)
    assert one.unit_split() == ((0,), (0,))
    made = default.made_by((0, 1), 2)
    assert made.repeats == 4 and [c.unit for c in made.conditions()[:4]] == [0, 1, 0, 1]
    with pytest.raises(Exception, match="units 0..2"):
        default.made_by((3,), 1)


def test_study_trains_and_tests_on_different_units(tmp_path, scenario_text):
    from nfs.studies.startup_study import run_study
    sc = _scenario(tmp_path, scenario_text,
                   "units = 3\n[variability]\n[compensation]\nmethods = ['ls']\n"
                   "test_repeats = 1\ntrain_repeats = 1\n", temps=(-20.0, 40.0))
    st = run_study(sc)
    assert {c.unit for c in (s.conditions for s in st.test.simulations)} == {2}
    assert all("_u2_" in s.run.name for s in st.test.simulations)
    assert sorted(r.name.split("_u")[1][0] for r in st.train_runs) == ["0", "0", "1", "1"]
    notes = " ".join(st.heading_table().notes)
    assert "trained on 0, 1, tested on 2 of 3 (different units)" in notes


def test_nominal_is_the_world_before_variability(default):
    # The default scenario's nominal() makes the runs the scenario made before units and
    # variability existed: names {name}_T{T0}C_r{r}, seeds (seed, i, r), no draws.
    nom = dataclasses.replace(default, repeats=2).nominal()
    conds = nom.conditions()
    assert [c.name for c in conds[:2]] == ["startup_7temps_T-32C_r0", "startup_7temps_T-32C_r1"]
    assert [c.seed for c in conds[:3]] == [(default.seed, 0, 0), (default.seed, 0, 1),
                                          (default.seed, 1, 0)]
    assert all(c.variability is None and c.unit == 0 for c in conds)
