"""Tests of nfs.diagnose.missing_effect: name the effect a model lacks, add it, watch the error fall.

"Measured" runs: the default scenario's 7 start temperatures, 2.5 h at 1 Hz, simulated
(nfs.experiment.simulate_run) with noise from an instrument with ONE effect the model lacks;
the model is the lumped-coil preset (load_instrument("lumped"): the default instrument with
its coil as two nodes, on which the figures below were measured; the wound default is
diagnosed in tests/diagnose/test_wound_coil.py), with that effect removed when it has it.  Six effects of the library are hidden in turn, each with noise seed 11
(12 and 13 in the slow set).  Oracle: the generating instrument (we know
which effect is hidden, on which target, and its value).

Strengths relative to the noise floor.  Drift channel: the floor is the residual RMS of the
10 s window means when the true instrument's own drift coefficients are fitted, about
0.0065 deg/h (ARW 0.0003 deg/sqrt(h) gives 0.0057 deg/h on a 10 s mean, plus bias
instability); the number is the model's excess RMS over the floor, sqrt(rms^2 - floor^2),
divided by the floor, measured with seed 11:

- shupe_product k_p = 0.02 (not in the default instrument): 3.5x
- turn_on_transient a = 0.1 deg/h, tau = 120 s: 1.05x over 2.5 h (all of it in the first
  10 min)
- magnetic m = 0.01 deg/h, D_mag = 30 deg: 1.07x (constant in time, follows the position)
- aux_linear k = 3 deg/h/V on aux_osc_v (Tao et al.'s (2019) oscillator voltage, :data:`OSC`): 2.3x.
  Raised from 1 deg/h/V (0.78x) when significance became run-level: at k = 1 the hidden
  effect is the top candidate on seeds 11 and 12 (CV RMS -40 % and -50 %) but its test,
  clustered by run, has only 3.3 and 2.9 Bell-McCaffrey degrees of freedom (the voltage's
  own wander is what tells it from the temperature terms, and a few runs carry most of
  it): p = 0.0032 and 0.00023, Holm-adjusted over 55 candidates 0.18 (not significant) and
  0.013.  (k = 0.02 deg/h/W on the TEC drive power aux_tec_power_w instead, a function of
  the source temperature, is confounded with the temperature terms.)
- polarization_ripple A_p = 0.005 deg/h, T_p = 5 K: 0.52x
- heat_source 1 W at coil_inner (a thermal effect), after the model's own thermal fit:
  0.38x on the FOG thermometer (floor 0.0206 K: noise 0.01 K and the 0.0625 K quantum),
  0.15x on the accelerometers' thermometers, 0.3x on the drift.  Significant against the
  model, but a structural alternative (a node inserted between coil_outer and housing, in
  effect a weaker coil-to-housing path) fits the thermometers as well: held-out CV RMS
  0.020591 against 0.020601 K on seed 11, won on 6 runs of 7, run-level paired t test
  p = 0.076.  The diagnosis reports the tie instead of naming it (it did name it, on that
  0.05 % margin, before the run-by-run comparison).

Significance is run-level (nfs.diagnose.missing_effect: a test clustered by run with run-level
degrees of freedom, the shape grid paid for by Bonferroni, Holm over all candidates at 5 %,
and a drop of the leave-one-start-temperature-out RMS).  Holm-adjusted p of the hidden
effect, seeds 11 / 12: shupe_product 2e-4 / 2e-4, turn_on_transient 3e-6 / 2e-6, magnetic
6e-8 / 1e-8, polarization_ripple 0.024 / 0.004, heat_source 9e-6 / 3e-5 (aux_linear above).

Candidates the data cannot tell apart from the hidden one (the board's warm-up and the
turn-on transient; every node's temperature for a coil-temperature term) come out
significant too; the test asks that the hidden one is the top significant candidate and
that the top one explains the others (``explained_by``).

The runs are soaked exactly at T0 (the nominal world) and the fit and the diagnosis are told
so (``start_state=None``); the default world's unfinished soaks are diagnosed in
tests/diagnose/test_start_state.py.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import replace

import numpy as np
import pytest

from nfs.diagnose.apply import apply_candidate
from nfs.diagnose.candidates import candidates
from nfs.diagnose.missing_effect import diagnose
from nfs.diagnose.ranking import CV_DROP
from nfs.fit.calibration import fit_model
from nfs.fit.params import set_params
from nfs.effects import make_effect
from nfs.errors import NfsError
from nfs.experiment import simulate_run
from nfs.instrument import AuxChannel, instrument_from_dict, load_instrument, preset_path
from nfs.config.scenario import load_scenario
from nfs.io.tomlio import load_toml

#: hidden effect -> (parameters, expected target)
HIDDEN = {
    "shupe_product": ({"k_p": 0.02}, None),
    "turn_on_transient": ({"a": 0.1, "tau": 120.0}, None),
    "magnetic": ({"m": 0.01, "D_mag": 30.0}, None),
    "aux_linear": ({"channel": "aux_osc_v", "k": 3.0}, "aux_osc_v"),
    "polarization_ripple": ({"A_p": 0.005, "T_p": 5.0}, None),
    "heat_source": ({"node": "coil_inner", "power": 1.0}, "coil_inner"),
}
THERMAL = ("heat_source",)
#: the hidden effect diagnosed in the default run (noise seed 11); the five others, and the
#: runs with other kinds of hidden signal, are the middle tier's (-m integration); seeds 12
#: and 13 of every effect are slow
DEFAULT_TIER = "magnetic"
NAMES = [n if n == DEFAULT_TIER else pytest.param(n, marks=pytest.mark.integration)
         for n in HIDDEN]


def _scenario(seed):
    return dataclasses.replace(load_scenario().nominal(), duration_s=9000.0, seed=seed)


@pytest.fixture(scope="module")
def scenario():
    return _scenario(11)


@pytest.fixture(scope="module")
def default():
    return load_instrument("lumped")


def _without(inst, name):
    return inst.with_effects([e for e in inst.effects if e.name != name])


#: Tao et al.'s (2019) oscillator voltage: an electrical channel that follows the source temperature
#: (10 mV/K) and wanders by itself (a random walk no thermometer sees, 0.1 mV/sqrt(s): about
#: 10 mV over a run); recorded by model and truth alike (a channel, not an effect).
OSC = AuxChannel(name="aux_osc_v", source="temperature:electronics", gain=0.01, offset=5.0,
                 noise=2e-4, walk_per_rth_s=1e-4)


def _case(scenario, default, name):
    """(model, truth, runs); a thermal hidden effect gets the model's thermal fit first,
    as a user runs `nfs fit` before `nfs diagnose`."""
    default = dataclasses.replace(default, aux=default.aux + (OSC,))
    model = _without(default, name)
    truth = model.with_effects(list(model.effects) + [make_effect(name, HIDDEN[name][0])])
    runs = [simulate_run(truth, c).run for c in scenario.conditions()]
    if name in THERMAL:
        model = fit_model(model, runs, stages=("thermal",), start_state=None).instrument
    return model, truth, runs


_CACHE: dict = {}


def _diagnosed(name, seed):
    if (name, seed) not in _CACHE:
        model, truth, runs = _case(_scenario(seed), load_instrument("lumped"), name)
        _CACHE[name, seed] = (model, truth, runs, diagnose(model, runs, start_state=None))
    return _CACHE[name, seed]


class _OnFirstUse(dict):
    """name -> ``make(name)``, made when a test first reads it (a test of one hidden effect
    does not simulate and diagnose the six)."""

    def __init__(self, make):
        super().__init__()
        self._make = make

    def __missing__(self, name):
        self[name] = value = self._make(name)
        return value


@pytest.fixture(scope="module")
def cases():
    return _OnFirstUse(lambda name: _diagnosed(name, 11)[:3])


@pytest.fixture(scope="module")
def diagnoses():
    return _OnFirstUse(lambda name: _diagnosed(name, 11)[3])


def _floor(truth, runs):
    """Drift residual RMS of the true instrument with its drift coefficients fitted."""
    return fit_model(truth, runs, stages=("drift",)).rms_after["drift_dph"]


def test_candidates_lists_targets_and_skips_model_effects(default, cases):
    model, _, runs = cases["magnetic"]
    cs = candidates(model, runs)
    labels = {c.label for c in cs}
    assert "magnetic" in labels and "shupe_gradient" not in labels  # in the model
    assert "shupe_rate:housing" in labels and "shupe_rate" not in labels
    assert "shupe_stress" not in labels and "shupe_product" in labels
    assert "aux_linear:aux_tec_power_w" in labels
    assert {"thermometer_lag:fog", "heat_source:board", "heat_source:coil_inner"} <= labels
    assert "heat_source" not in labels  # its node has no default
    by = {c.label: c for c in cs}
    assert by["heat_source:coil_inner"].tried
    assert by["heat_source:coil_inner"].channel == "thermometers"
    # the board's power is free: the diagnosis's span check sets the candidate aside
    # (test_thermal_candidate_scored_on_thermometers), not the candidate list
    assert by["heat_source:board"].tried and by["heat_source:board"].channel == "thermometers"
    # a QFA always dissipates (its typical power starts above 0 W): a fit that took its power
    # to 0 W still has that number, so no heat source there either
    cold = set_params(model, {"thermal.nodes.qfa_y.power_w": 0.0})
    qfa = next(c for c in candidates(cold, runs) if c.label == "heat_source:qfa_y")
    assert not qfa.tried and "qfa_y.power_w" in qfa.reason
    assert by["thermometer_lag:fog"].coefficients == ("tau",)  # linearised at 0
    assert by["magnetic"].shapes == ("D_mag",) and by["magnetic"].coefficients == ("m",)
    # shupe_stress is linear in k_m, not in c_m (registered as a shape): a model without it
    # gets a candidate that chooses c_m on its grid, inside the sign-keeping bounds
    bare = _without(model, "shupe_stress")
    stress = next(c for c in candidates(bare, runs) if c.label == "shupe_stress")
    assert stress.tried and stress.coefficients == ("k_m",) and stress.shapes == ("c_m",)


def _check_top(d, name):
    params, target = HIDDEN[name]
    top = d.ranking[0]
    assert top.effect == name, [(s.effect, s.target, round(s.cv_drop, 4))
                                for s in d.ranking[:4]]
    if top.target != target:
        # the right effect on a target the data cannot tell from the true one (a ripple in
        # the coil-inner temperature vs the coil mean: a phase shift): the true target is
        # significant and explained by the top one
        true = next(s for s in d.ranking if (s.effect, s.target) == (name, target))
        assert true.significant and true.explained_by == f"{top.effect}:{top.target}", true
        assert true.cv_rms_after <= 1.02 * top.cv_rms_after
    assert top.significant and top.holm_p <= 0.05
    assert top.cv_rms_after < (1 - CV_DROP) * top.cv_rms_before
    assert top.explained_by is None
    # one effect, one explanation: every other significant candidate on the same channel
    # is explained by the hidden one
    others = [s for s in d.significant[1:] if s.channel == top.channel]
    assert all(s.explained_by for s in others), [
        (s.effect, s.target) for s in others if not s.explained_by]
    # one answer: add the effect, with its coefficient and interval; or, when the runs
    # cannot tell it from a rate term on every node, the tie that holds it (never both)
    label = top.effect if top.target is None else f"{top.effect}:{top.target}"
    if (d.drift_structure is not None and label in d.drift_structure.tied) or \
            name == "turn_on_transient":
        # a transient is tied with a rate term on every node, or with heat released inside
        # the coil (the same decay after power-on at every start temperature)
        assert d.answer.kind == "tie" and d.answer.labels[0] == label, d.verdict
        assert d.verdict.startswith(f"these runs cannot tell apart: {label} (")
        assert "add " not in d.verdict
    else:
        assert d.answer.kind == "add" and d.answer.labels == (label,), d.verdict
        assert d.verdict.startswith(f"add {label} (")
        assert "tie" not in d.verdict
    assert "[" in d.verdict and "Holm p" in d.verdict
    # the fitted coefficients' intervals (CR2, clustered by run) hold the true values
    # (10 % slack: the interval is at the refined shape, one of several near-equivalent)
    for p, v in params.items():
        if p in top.interval and isinstance(v, float) and p not in ("tau", "T_p", "D_mag"):
            lo, hi = top.interval[p]
            assert lo - 0.1 * abs(v) <= v <= hi + 0.1 * abs(v), (p, v, top.interval[p])
    assert top.heading_rmse_after_deg <= top.heading_rmse_before_deg * 1.001
    return top


def _check_thermal_tie(d, name):
    """A hidden thermal effect: significant against the model (Holm), its coefficient's
    interval holds the truth, and tied with a structural alternative that fits the
    thermometers as well run by run, which the verdict says (so it is not named)."""
    params, target = HIDDEN[name]
    label = f"{name}:{target}"
    hidden = next(s for s in d.ranking if (s.effect, s.target) == (name, target))
    assert hidden.holm_p <= 0.05 and hidden.cv_rms_after < (1 - CV_DROP) * hidden.cv_rms_before
    assert hidden.structure_tie and not hidden.significant, hidden
    for p, v in params.items():
        if p in hidden.interval:
            lo, hi = hidden.interval[p]
            assert lo - 0.1 * abs(v) <= v <= hi + 0.1 * abs(v), (p, v, hidden.interval[p])
    assert d.answer.kind == "tie" and d.answer.labels == (label, hidden.structure_tie), \
        d.verdict
    assert d.verdict.startswith(f"these runs cannot tell apart: {label} (")
    assert not any(s.channel == "thermometers" for s in d.significant), d.verdict


def _check(name, seed):
    if name in THERMAL:
        _check_thermal_tie(_diagnosed(name, seed)[3], name)
    else:
        _check_top(_diagnosed(name, seed)[3], name)


@pytest.mark.parametrize("name", NAMES)
def test_hidden_effect_is_top_significant_candidate(name):
    _check(name, 11)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(HIDDEN))
@pytest.mark.parametrize("seed", [12, 13])
def test_hidden_effect_is_top_with_other_noise(name, seed):
    _check(name, seed)


@pytest.mark.integration
def test_turn_on_transient_coefficients(diagnoses):
    s = diagnoses["turn_on_transient"].ranking[0]
    assert abs(s.coefficient["a"] - 0.1) < 0.02 and 80.0 < s.coefficient["tau"] < 200.0


@pytest.mark.integration
def test_thermal_candidate_scored_on_thermometers(diagnoses):
    d = diagnoses["heat_source"]
    top = next(s for s in d.ranking if (s.effect, s.target) == ("heat_source", "coil_inner"))
    assert top.channel == "thermometers"
    assert abs(top.coefficient["power"] - 1.0) < 0.15
    # a heat source at a node whose power the model already fits has the same signature
    why = {f"{c.effect}:{c.target}": c.reason for c in d.not_tried}
    assert "board.power_w" in why["heat_source:board"]


@pytest.mark.integration
def test_extra_thermometer_lag_is_the_thermometers_own_lag(scenario, default):
    # Oracle: an extra first-order lag (tau = 60 s) on the FOG thermometer, which already
    # lags 30 s.  Two lags in series read x - (30 + 60) dx/dt + 30 * 60 d2x/dt2 + ...: to
    # first order the model's own free lag_s, so the fit takes it up (lag_s -> ~90 s).  The
    # second-order remainder is real (the truth has two lags) and a run-level test on 7 runs
    # may detect it: the only candidate allowed to be significant is the true one, and it
    # must explain less than 1 % of the thermometer residual.
    truth = default.with_effects(list(default.effects) + [
        make_effect("thermometer_lag", {"thermometer": "fog", "tau": 60.0})])
    runs = [simulate_run(truth, c).run for c in scenario.conditions()]
    fitted = fit_model(default, runs, stages=("thermal",))
    assert abs(fitted.params["thermometers.fog.lag_s"] - 90.0) < 10.0
    d = diagnose(fitted.instrument, runs)
    assert all((s.effect, s.target) == ("thermometer_lag", "fog") for s in d.significant), \
        d.verdict
    assert all(s.cv_drop < 0.01 for s in d.significant), d.verdict


def test_no_hidden_effect_no_significant_candidate(scenario, default):
    # Oracle: runs made by the model itself (only noise is left to explain).
    runs = [simulate_run(default, c).run
            for c in dataclasses.replace(scenario, seed=12).conditions()]
    d = diagnose(default, runs)
    assert not d.significant, [(s.effect, s.target, s.cv_drop) for s in d.significant]
    assert d.answer.kind == "nothing", d.verdict
    assert d.verdict.startswith("nothing beyond noise")
    assert max(s.cv_drop for s in d.ranking) < CV_DROP


@pytest.mark.integration
def test_effect_outside_the_library(scenario, default):
    # Oracle: a quadrantal error 0.01 cos(2A) deg/h (A the turntable position; e.g. an
    # elliptic bearing), added to the measured rate.  No registered effect has a second
    # harmonic of the position (magnetic is the first), so no candidate may be significant,
    # and the residual's strongest cross-correlation is with cos(2A).
    runs = []
    for c in scenario.conditions():
        r = simulate_run(default, c).run
        a = np.radians(np.asarray(r["position_deg"], dtype=float))
        cols = dict(r.columns)
        cols["gyro_dph"] = np.asarray(r["gyro_dph"], dtype=float) + 0.01 * np.cos(2 * a)
        runs.append(replace(r, columns=cols))
    d = diagnose(default, runs)
    assert not d.significant, [(s.effect, s.target) for s in d.significant]
    assert d.answer.kind == "unexplained", d.verdict
    u = d.unexplained
    assert u["ljung_box"]["p_value"] < 0.01
    assert u["cross_correlation"][0]["channel"] == "cos_2_position"
    assert u["cross_correlation"][0]["max_abs_r"] > 0.5


@pytest.mark.slow  # a second fit of every run with another network
def test_ranking_survives_a_model_with_another_node_count(scenario, default):
    # Oracle: the data come from the default 7-node instrument with a hidden shupe_product;
    # the model has 8 nodes (a mounting plate between the housing and the chamber), is
    # thermally fitted to the runs, and must still name shupe_product.
    truth = default.with_effects([e for e in default.effects if e.name != "shupe_product"]
                                 + [make_effect("shupe_product", HIDDEN["shupe_product"][0])])
    runs = [simulate_run(truth, c).run for c in scenario.conditions()]
    d = load_toml(preset_path("lumped"))
    d["thermal"]["nodes"]["mount"] = {"capacity_j_per_k": 1500.0, "power_w": 0.0}
    links = [ln for ln in d["thermal"]["links"] if "chamber" not in ln["between"]]
    links += [{"between": ["housing", "mount"], "conductance_w_per_k": 4.0},
              {"between": ["mount", "chamber"], "conductance_w_per_k": 1.6}]
    d["thermal"]["links"] = links
    other = instrument_from_dict(d)
    other = other.with_effects([e for e in other.effects if e.name != "shupe_product"])
    assert len(other.network.node_names) == len(default.network.node_names) + 1
    fitted = fit_model(other, runs, stages=("thermal",)).instrument
    diag = diagnose(fitted, runs)
    top = diag.ranking[0]
    assert top.effect == "shupe_product", [(s.effect, s.target) for s in diag.ranking[:4]]
    assert top.significant
    if top.target is not None:
        # the model's shupe_stress holds T_coil x the radial gradient rate, and what it leaves
        # of T_coil dT_coil/dt is close to a coil node's own T dT/dt: the true target must
        # then be significant, explained by the top one and as good within 2 % (as in
        # _check_top)
        true = next(s for s in diag.ranking if (s.effect, s.target) == ("shupe_product", None))
        assert true.significant and true.explained_by == f"{top.effect}:{top.target}", true
        assert true.cv_rms_after <= 1.02 * top.cv_rms_after


@pytest.mark.integration
def test_users_own_effect_is_a_candidate(scenario, default, monkeypatch):
    # Oracle: a user's effect (a registered Python function, as in the simulator issue):
    # a chamber fan's 20-min periodic disturbance c sin(2 pi t / P), c = 0.006 deg/h, hidden
    # in the runs.  No built-in effect follows time this way; the user's is the top one.
    import nfs.effects.registry as reg
    from nfs.effects import Parameter, register_effect
    monkeypatch.setattr(reg, "_REGISTRY", dict(reg._REGISTRY))  # restored after the test

    @register_effect("user_fan", kind="gyro", parameters=[
        Parameter("c", "deg/h", "amplitude"),
        Parameter("period", "s", "fan cycle", default=1200.0)])
    def user_fan(ctx, *, c, period=1200.0):
        """c sin(2 pi t / period) [deg/h]: a chamber fan's periodic disturbance."""
        return c * np.sin(2 * np.pi * ctx.time_s / period)

    truth = default.with_effects(list(default.effects)
                                 + [make_effect("user_fan", {"c": 0.006, "period": 1250.0})])
    runs = [simulate_run(truth, c).run for c in scenario.conditions()]
    d = diagnose(default, runs)
    top = d.ranking[0]
    assert (top.effect, top.significant) == ("user_fan", True), d.verdict
    assert abs(top.coefficient["period"] - 1250.0) < 25.0
    new, _, rep = apply_candidate(default, runs, "user_fan")
    assert rep["rms_after"]["drift_dph"] < rep["rms_before"]["drift_dph"]


@pytest.mark.integration
def test_runs_with_different_latitudes_and_schedules(scenario, default):
    # Oracle: each run is replayed with its own latitude and schedule; a hidden magnetic
    # bias is still named when the runs mix 30/50 deg latitude and 150/200 s dwells.
    from nfs.sensors import Schedule
    truth = default.with_effects(list(default.effects)
                                 + [make_effect("magnetic", HIDDEN["magnetic"][0])])
    conds = []
    for i, c in enumerate(scenario.conditions()):
        if i % 2:
            c = replace(c, latitude_deg=50.0,
                        schedule=Schedule(c.schedule.positions_deg, 200.0, c.schedule.move_s))
        conds.append(c)
    runs = [simulate_run(truth, c).run for c in conds]
    assert len({r.meta.latitude_deg for r in runs}) == 2
    d = diagnose(default, runs)
    assert (d.ranking[0].effect, d.ranking[0].significant) == ("magnetic", True), d.verdict


@pytest.mark.parametrize("name", NAMES)
def test_apply_halves_the_excess_and_keeps_heading(cases, name):
    # Oracle: the truth.  The excess of the affected channel's residual over its noise
    # floor, sqrt(rms^2 - floor^2), falls by at least half; heading RMSE does not get worse.
    model, truth, runs = cases[name]
    params, target = HIDDEN[name]
    new, res, rep = apply_candidate(model, runs, name, target)
    assert any(e.name == name for e in new.effects)
    if name in THERMAL:
        floors = fit_model(truth, runs, free=[], stages=("thermal",)).rms_before
        channel = max(floors, key=lambda ch: rep["rms_before"][ch] ** 2 - floors[ch] ** 2)
        floor = floors[channel]
    else:
        channel, floor = "drift_dph", _floor(truth, runs)
    before, after = rep["rms_before"][channel], rep["rms_after"][channel]
    excess = lambda r: math.sqrt(max(r * r - floor * floor, 0.0))  # noqa: E731
    assert excess(after) <= 0.5 * excess(before), (channel, before, after, floor)
    assert rep["heading_rmse_after_deg"] <= rep["heading_rmse_before_deg"] * 1.001


def test_to_dict_form_and_unexplained(diagnoses):
    d = diagnoses["magnetic"]
    doc = json.loads(json.dumps(d.to_dict()))
    r = doc["ranking"][0]
    for key in ("effect", "target", "significant", "cv_rms_before", "cv_rms_after",
                "correlation", "coefficient", "interval", "inclusion_frequency", "wald_p",
                "holm_p", "dof", "n_grid",
                "heading_rmse_before_deg", "heading_rmse_after_deg"):
        assert key in r
    assert r["effect"] == "magnetic" and r["target"] is None
    u = doc["unexplained"]
    assert 0.0 <= u["ljung_box"]["p_value"] <= 1.0
    # Oracle: m cos(A - D) follows the turntable position; the baseline residual is not
    # white and its strongest channel is the position's cos or sin.
    assert u["ljung_box"]["p_value"] < 0.01
    assert u["cross_correlation"][0]["channel"] in ("cos_position", "sin_position")


def test_bad_input(cases):
    model, _, runs = cases["magnetic"]
    with pytest.raises(NfsError, match="valid names"):
        apply_candidate(model, runs, "magnetik")
    with pytest.raises(NfsError, match="valid targets"):
        apply_candidate(model, runs, "shupe_product", "nowhere")
    with pytest.raises(NfsError, match="already"):
        apply_candidate(model, runs, "shupe_gradient")
    with pytest.raises(NfsError, match="at least 2 runs"):
        diagnose(model, runs[:1])
