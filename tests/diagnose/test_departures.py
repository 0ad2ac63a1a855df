"""Fitted values beyond their typical range (nfs.fit.departures), the hard range as the fit's
limit (nfs.fit.params.fit_bounds), and the fitted model's file: its departures in its header
and one line, not one warning each, when it loads.

Oracles: the table of ranges (a housing of 2000-4500 J/K, a lag of 10-60 s, an offset of
|x| <= 0.5 K, a turn-on amplitude |a| of 0.005-0.05 deg/h and their hard ranges); the side a
value leaves by; the warnings a load emits, counted.
"""

import dataclasses
import math
import warnings

import pytest

from nfs import ranges
from nfs.config.scenario import load_scenario
from nfs.experiment import simulate_run
from nfs.fit import fit_model, write_fitted_model
from nfs.fit.departures import canonical_key, departure_line, departures, points_to
from nfs.fit.params import fit_bounds, get_param, set_params
from nfs.instrument import load_instrument


def test_lines_name_the_side_the_range_and_the_structure():
    line = departure_line("thermal.nodes.housing.capacity_j_per_k", 203.0, 12.0)
    assert line.startswith("thermal.nodes.housing.capacity_j_per_k = 203 +- 12 J/K, below the "
                           "typical 2000-4500 J/K: ")
    assert "within 2 sigma" not in line
    assert "thermometer" in line
    # a coil node whose capacity vanishes points to the winding in layers
    assert "layers" in departure_line("thermal.nodes.coil_outer.capacity_j_per_k", 5.0)
    assert "lags" not in departure_line("thermometers.fog.lag_s", 104.0)
    assert "behind a conductance" in departure_line("thermometers.fog.lag_s", 104.0)
    assert "leads its node" in departure_line("thermometers.fog.lag_s", 2.0)
    # inside the typical range, or the value that switches a term off: no line
    assert departure_line("thermal.nodes.housing.capacity_j_per_k", 3000.0) is None
    assert departure_line("thermal.nodes.coil_outer.power_w", 0.0) is None
    # a magnitude: the sign does not matter
    assert departure_line("effects.turn_on_transient.a", -0.04) is None
    assert "above" in departure_line("effects.turn_on_transient.a", -0.2)
    # an effect with a target is looked up by its name
    assert canonical_key("effects.acc_bias_temperature:x.b_q1") == \
        "effects.acc_bias_temperature.b_q1"
    assert departure_line("effects.acc_bias_temperature:x.b_q1", 4e-4) is not None
    # significance is stated, not decided
    assert "within 2 sigma" in departure_line("thermometers.fog.lag_s", 70.0, 6.0)
    assert list(departures({"thermometers.fog.lag_s": 70.0,
                            "thermometers.fog.offset_c": 0.1})) == ["thermometers.fog.lag_s"]
    assert "heater" in points_to("thermal.nodes.coil_inner.power_w", "above")


def test_heat_inside_a_coil_is_held_to_what_can_be_there():
    # the table of ranges: a passive winding releases 0-0.5 W (a heater or a hub path), the
    # spool's hub up to 1 W, a heat source elsewhere up to 20 W
    assert ranges.find("effects.heat_source:coil_3.power").typical == (0, 0.5)
    assert ranges.find("effects.heat_source:coil_outer.power").typical == (0, 0.5)
    assert ranges.find("effects.heat_source:spool.power").typical == (0, 1)
    assert ranges.find("effects.heat_source:board.power").typical == (0, 20)
    line = departure_line("effects.heat_source:coil_3.power", 2.0, 0.3)
    assert "above the typical 0-0.5 W" in line and "heater" in line and "hub" in line
    assert departure_line("effects.heat_source:board.power", 2.0, 0.3) is None
    assert departure_line("effects.heat_source:coil_3.power", 0.3, 0.1) is None


@pytest.mark.parametrize("path, value", [
    ("thermal.nodes.housing.capacity_j_per_k", 3500.0),
    ("thermal.nodes.housing.capacity_j_per_k", 0.5),
    ("thermometers.fog.offset_c", 0.0),
    ("effects.turn_on_transient.a", 0.008),
    ("gyro.bias_dph", 0.02),
])
def test_every_box_lies_inside_the_hard_range(path, value):
    inst = set_params(load_instrument("lumped"), {path: value})
    lo, hi = fit_bounds(inst, path)
    row = ranges.find(canonical_key(path))
    h_lo, h_hi = row.hard
    if row.magnitude:
        assert -h_hi <= lo and hi <= h_hi
    else:
        assert h_lo <= lo and hi <= h_hi
    assert lo <= value <= hi


def test_fitted_model_states_its_departures_once(tmp_path):
    """A unit whose housing is lighter than the table's housings (1200 J/K): the fit keeps
    it light (the runs say so), states it in one line with what it points to, and the file
    it writes loads with one line about it instead of one warning per value."""
    world = load_scenario().nominal()
    inst = load_instrument("lumped")
    truth = set_params(inst, {"thermal.nodes.housing.capacity_j_per_k": 1200.0})
    conds = [dataclasses.replace(c, duration_s=1800.0) for c in world.conditions()[:2]]
    runs = [simulate_run(truth, c).run for c in conds]
    free = ["thermal.nodes.housing.capacity_j_per_k", "thermal.nodes.board.capacity_j_per_k",
            "thermometers.fog.lag_s"]
    res = fit_model(inst, runs, free, stages=("thermal",))
    housing = "thermal.nodes.housing.capacity_j_per_k"
    assert res.params[housing] < 2000.0
    assert housing in res.departures
    assert "below the typical 2000-4500 J/K" in res.departures[housing]
    assert res.departures[housing] in res.summary()
    assert not any(housing in w and "moved" in w for w in res.warnings)
    path = write_fitted_model(res, tmp_path / "fitted.toml")
    text = path.read_text()
    assert f"#   {res.departures[housing]}" in text
    assert "[fit]" in text
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        back = load_instrument(path)
    shown = [str(w.message) for w in caught if issubclass(w.category, ranges.RangeWarning)]
    assert len(shown) == 1 and "as the fit that wrote this file states" in shown[0]
    assert math.isclose(get_param(back, housing), res.params[housing], rel_tol=1e-6)
    # a value the user edits off its typical range afterwards still warns on its own
    edited = tmp_path / "edited.toml"
    edited.write_text(text.replace("\nlag_s = ", "\nlag_s = 500.0 #", 1))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_instrument(edited)
    shown = [str(w.message) for w in caught if issubclass(w.category, ranges.RangeWarning)]
    assert len(shown) == 2 and any("500 s is unusual" in m for m in shown)
