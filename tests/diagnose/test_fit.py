"""Calibration of a model to runs (nfs.fit.calibration).

Oracle: runs simulated from a known instrument (the default with some parameters perturbed by
+20 %, noise as usual) -- the fit started from the unperturbed default must recover the
perturbed values within the stated tolerance, and the thermometer residual must fall to the
thermometer's own noise and quantisation level sqrt(0.01^2 + 0.0625^2/12) = 0.0206 K.
The runs are soaked exactly at T0 (the nominal world) and the fit is told so
(``start_state=None``); tests/diagnose/test_start_state.py fits unfinished soaks.
At-bound, single-run and bad-input cases are checked against what they must report.
"""

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

from nfs.fit.calibration import fit_model
from nfs.fit.fit_result import write_fitted_model
from nfs.fit.free_set import default_free
from nfs.fit.params import get_param, set_params
from nfs.errors import NfsError
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.config.scenario import load_scenario

#: The perturbed parameters (+20 % of the default) and the truth.
PERTURBED = {
    "coil.heat_capacity_j_per_m3_k": 1.2,
    "thermal.links.housing-chamber.conductance_w_per_k": 1.2,
    "thermometers.fog.lag_s": 1.2,
    "effects.tec_power.c_h": 1.2,
    "effects.shupe_winding.k_m": 1.2,
    "effects.bias_temperature.b1": 1.2,
}

#: Thermometer white noise 0.01 K and quantisation 0.0625 K (default instrument).
THERMOMETER_FLOOR_K = math.hypot(0.01, 0.0625 / math.sqrt(12.0))


@pytest.fixture(scope="module")
def scenario():
    return load_scenario().nominal()


@pytest.fixture(scope="module")
def truth(scenario):
    inst = scenario.instrument
    return set_params(inst, {p: f * get_param(inst, p) for p, f in PERTURBED.items()})


@pytest.fixture(scope="module")
def runs(scenario, truth):
    return [simulate_run(truth, c).run for c in scenario.conditions()]


@pytest.fixture(scope="module")
def fitted(scenario, runs):
    return fit_model(scenario.instrument, runs, start_state=None)


def test_recovers_perturbed_parameters(fitted, truth):
    # Tolerance: within 3 standard errors (or 1 % where the error is tiny) and never more
    # than 6 % off (the thermal solver holds the TEC power over 10 s knots, and the
    # capacities trade off against each other: the wound coil's and its spool's are seen
    # only through the FOG's thermometer and the drift).
    for p in PERTURBED:
        want = get_param(truth, p)
        got = fitted.params[p]
        err = abs(got - want)
        assert err <= max(3.0 * fitted.stderr[p], 0.01 * abs(want)), (p, got, want,
                                                                      fitted.stderr[p])
        assert err <= 0.06 * abs(want), (p, got, want)


def test_thermometer_residual_at_noise_floor(fitted):
    for ch in ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c"):
        assert fitted.rms_before[ch] > 10 * THERMOMETER_FLOOR_K
        assert fitted.rms_after[ch] == pytest.approx(THERMOMETER_FLOOR_K, rel=0.1), ch
    assert fitted.rms_after["drift_dph"] < 0.5 * fitted.rms_before["drift_dph"]


def test_report(fitted, scenario):
    assert set(fitted.params) == set(default_free(scenario.instrument))
    assert fitted.converged == {"thermal": True, "drift": True}
    assert fitted.at_bound == ()
    assert all(np.isfinite(v) and v > 0 for v in fitted.stderr.values())
    assert fitted.n_residuals["thermal"] == 3 * 7 * 900
    # the fitted instrument is the input with the fitted values, the input is untouched
    for p, v in fitted.params.items():
        assert get_param(fitted.instrument, p) == v
        assert get_param(scenario.instrument, p) == fitted.initial_params[p]


# The default instrument's bias instability, 0.002 deg/h, is the lower end of its typical
# range in nfs.ranges; fitted to these runs it comes out at 0.00186, and loading the written
# model says so (a RangeWarning that is not what this test is about).
@pytest.mark.filterwarnings(r"ignore:.*key 'gyro\.bias_instability_dph'.* is unusual"
                            ":nfs.ranges.RangeWarning")
def test_write_fitted_model(fitted, tmp_path):
    path = write_fitted_model(fitted, tmp_path / "fitted.toml")
    text = path.read_text()
    assert "# Fitted parameters" in text
    assert "effects.shupe_winding.k_m = " in text
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        back = load_instrument(path)
    # at most one line: the values the fit stated beyond their typical range, if any
    shown = [str(w.message) for w in caught]
    assert len(shown) == (1 if fitted.departures else 0), shown
    for p, v in fitted.params.items():
        assert get_param(back, p) == pytest.approx(v, rel=1e-12)
    # named after what it came from, and the name survives the file
    assert fitted.instrument.name.startswith(f"{fitted.initial.name} fitted to ")
    assert back.name == fitted.instrument.name


def test_fitted_name_says_where_the_model_came_from(tmp_path):
    from nfs.fit.calibration import fitted_name
    from nfs.run import Run
    mk = lambda name, path=None: Run(name=name, columns={}, meta=None, path=path)  # noqa: E731
    assert fitted_name("default", [mk("a", tmp_path / "chamber" / "a.csv"),
                                   mk("b", tmp_path / "chamber" / "b.csv")]) == \
        "default fitted to the runs in chamber/"
    assert fitted_name("default", [mk("unit3_m32"), mk("unit3_p54")]) == \
        "default fitted to unit3*"
    assert fitted_name("default fitted to x", [mk("r1")]) == "default fitted to r1"
    assert fitted_name("m", [mk("a"), mk("b")]) == "m fitted to 2 runs"


def _shift(run, column, delta):
    cols = dict(run.columns)
    cols[column] = cols[column] + delta
    return replace(run, columns=cols)


def test_at_bound_reported(scenario, runs):
    # a 3 K thermometer offset lies outside the default +-2 K box: the offset must end at
    # +2 K and be reported
    shifted = [_shift(r, "temp_fog_c", 3.0) for r in runs[:2]]
    res = fit_model(scenario.instrument, shifted, ["thermometers.fog.offset_c"],
                    stages=("thermal",))
    assert res.params["thermometers.fog.offset_c"] == pytest.approx(2.0, abs=1e-6)
    assert res.at_bound == ("thermometers.fog.offset_c",)
    assert any("bound" in w for w in res.warnings)


def test_single_run_reports_unidentifiable(scenario, runs):
    # at T0 = -32 C the source never reaches T_set = 25 C: c_c cannot be identified
    res = fit_model(scenario.instrument, runs[:1],
                    ["effects.tec_power.c_h", "effects.tec_power.c_c", "thermometers.fog.lag_s"],
                    stages=("thermal",))
    assert "effects.tec_power.c_c" in res.unidentifiable
    assert "effects.tec_power.c_h" not in res.unidentifiable
    assert math.isinf(res.stderr["effects.tec_power.c_c"])
    assert any("single run" in w for w in res.warnings)
    assert any("c_c" in w and "identifiable" in w for w in res.warnings)


def test_not_converged_reported(scenario, runs):
    res = fit_model(scenario.instrument, runs[:1], ["thermal.nodes.*.capacity_j_per_k"],
                    stages=("thermal",), max_nfev=1)
    assert res.converged == {"thermal": False}
    assert any("did not converge" in w for w in res.warnings)


def test_bad_input(scenario, runs):
    inst = scenario.instrument
    with pytest.raises(NfsError, match="no runs"):
        fit_model(inst, [])
    cols = {k: v for k, v in runs[0].columns.items() if k != "temp_acc_y_c"}
    with pytest.raises(NfsError, match="temp_acc_y_c"):
        fit_model(inst, [replace(runs[0], columns=cols)])
    no_heading = replace(runs[0], meta=replace(runs[0].meta, true_heading_deg=None))
    with pytest.raises(NfsError, match="true_heading_deg"):
        fit_model(inst, [no_heading], stages=("drift",))
    with pytest.raises(NfsError, match="shupe_winding.k_m"):
        fit_model(inst, runs[:1], ["effects.shupe_winding.km"])
    with pytest.raises(NfsError, match="stage"):
        fit_model(inst, runs[:1], stages=("thermals",))


def test_model_drift_dph_is_the_simulators_drift(scenario):
    # Oracle: simulate_run's own terms. The model drift on the simulator's context equals
    # bias + sum of the gyro terms - Omega_ie sin L (b_x + x accelerometer terms), exactly.
    from nfs.constants import OMEGA_IE_DPH
    from nfs.fit.drift_residual import model_drift_dph
    inst = scenario.instrument
    cond = replace(scenario.conditions()[0], duration_s=600.0)
    sim = simulate_run(inst, cond)
    acc_x = inst.accelerometers.bias_x_g + sim.acc_terms_g["acc_bias_temperature:x"]
    want = (inst.gyro.bias_dph + sum(sim.gyro_terms_dph.values())
            - OMEGA_IE_DPH * math.sin(math.radians(cond.latitude_deg)) * acc_x)
    got = model_drift_dph(inst, sim.context, cond.latitude_deg)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


def test_at_bound_advice_and_unsoaked_runs(scenario, runs):
    # Oracle: the 3 K shift of the FOG thermometer lies outside the +-2 K offset box and
    # makes both runs start 3 K from their soak temperature: the bound must come with the
    # offset's advice, and both runs must be named as not soaked (left out of the anchor).
    shifted = [_shift(r, "temp_fog_c", 3.0) for r in runs[:2]]
    res = fit_model(scenario.instrument, shifted, ["thermometers.fog.offset_c"],
                    stages=("thermal",))
    assert "not soaked" in res.bound_advice["thermometers.fog.offset_c"]
    assert res.soak is not None and res.soak.unsoaked == tuple(r.name for r in shifted)
    for r in shifted:
        assert any(r.name in w and "not soaked" in w for w in res.warnings)


def test_a_run_without_a_chamber_record_says_what_is_assumed(scenario, runs):
    """A run whose CSV has no temp_chamber_c is replayed with the chamber at its T0, and the
    fit says so, naming the run."""
    bare = replace(runs[0], columns={k: v for k, v in runs[0].columns.items()
                                     if k != "temp_chamber_c"})
    res = fit_model(scenario.instrument, [bare, runs[1]], ["thermometers.fog.lag_s"],
                    stages=("thermal",), start_state=None, n_starts=1)
    said = [w for w in res.warnings if "chamber record" in w]
    assert len(said) == 1 and bare.name in said[0] and "T0" in said[0], res.warnings
    assert runs[1].name not in said[0]


def test_far_from_start():
    """The rule of a parameter pushed far: 3x its start or a third of it, a change of sign
    (for a parameter with a scale), or 3 prior widths away (for any)."""
    from nfs.fit.departures import far_from_start
    assert far_from_start(0.008, 0.061, 0.28) == "from 0.008 to 0.061 (7.6 times; +0.3 prior widths)"
    assert far_from_start(380.0, 1636.0, 6.1).startswith("from 380 to 1636 (4.3 times")
    assert far_from_start(1.0, 2.9, 1.0) == ""
    assert far_from_start(1.0, -0.5, 0.5) != ""                 # a sign change
    assert far_from_start(0.02, -0.012, 0.0, by_ratio=False) == ""   # a bias: prior only
    assert far_from_start(0.0, 0.14, -19.8, by_ratio=False) == "from 0 to 0.14 (-19.8 prior widths)"
