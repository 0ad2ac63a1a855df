"""The candidates' shape parameters come from each effect's registration, not a global grid.

A user's own effect, registered in the test on a copy of the registry (restored after it),
is tried by the diagnosis on the grid its Parameter declares; without a grid or a default
its shape parameter is reported as not tried, with the fix in the reason.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import nfs.effects.registry as reg
from nfs.config.scenario import load_scenario
from nfs.diagnose.candidates import candidates, shape_grid, split_parameters
from nfs.diagnose.columns import bare_instrument, candidate_columns, grid_columns, prepare_runs
from nfs.effects import Parameter, available_effects, get_effect, register_effect
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument

#: Oracle: the values of the global SHAPE_GRID that the built-in effects' registrations
#: replaced (nfs/diagnose/candidates.py before the grids moved into the registry), per
#: effect and parameter: the stored diagnosis numbers rest on them.
FORMER_GRIDS = {
    ("turn_on_transient", "tau"): (60.0, 150.0, 300.0, 600.0, 1200.0),
    ("thermometer_lag", "tau"): (60.0, 150.0, 300.0, 600.0, 1200.0),
    ("magnetic", "D_mag"): (0.0, 45.0, 90.0, 135.0),
    ("polarization_ripple", "T_p"): (2.0, 5.0, 10.0, 20.0),
    ("polarization_ripple", "phi"): (0.0, math.pi / 2),
    ("shupe_stress", "c_m"): (-0.02, -0.01, 0.01),
    ("shupe_winding", "c_m"): (-0.02, -0.01, 0.01),
}

#: The user's heater warm-up grid [s], deliberately not a built-in grid.
WARMUP_GRID = (100.0, 400.0, 1600.0)


@pytest.fixture
def user_registry(monkeypatch):
    """A copy of the registry for the test to register into; the original is put back."""
    monkeypatch.setattr(reg, "_REGISTRY", dict(reg._REGISTRY))


def _register_warmup(name: str, **grid) -> None:
    @register_effect(name, kind="gyro", replace=True, parameters=[
        Parameter("b", "deg/h", "amplitude of the heater's warm-up"),
        Parameter("t_w", "s", "time constant of the heater's warm-up", **grid)])
    def warmup(ctx, *, b, t_w):
        """A heater's warm-up: b (1 - exp(-t / t_w)) [deg/h]; b [deg/h], t_w [s]."""
        return b * (1.0 - np.exp(-ctx.time_s / t_w))


def _candidate(name: str):
    inst = load_instrument("default")
    found = [c for c in candidates(inst, []) if c.effect == name]
    assert len(found) == 1, found
    return found[0]


def test_builtin_grids_are_the_former_global_grid():
    # Oracle: FORMER_GRIDS (stored above); and every shape parameter without a default has a grid.
    for (name, par), grid in FORMER_GRIDS.items():
        assert get_effect(name).parameter(par).grid == grid, (name, par)
    for name in available_effects():
        spec = get_effect(name)
        # the package's own effects (a test elsewhere may have registered one of its own)
        if spec.kind == "geometry" or not spec.function.__module__.startswith("nfs."):
            continue
        _, shapes, missing = split_parameters(spec)
        assert not missing, (name, missing)
        for s in shapes:
            p = spec.parameter(s)
            assert (name, s) in FORMER_GRIDS or p.default is not None, (name, s)


def test_user_shape_parameter_with_a_grid_is_tried(user_registry):
    # Oracle: the grid given at registration, and the closed form of the effect's column.
    _register_warmup("user_heater_warmup", grid=list(WARMUP_GRID))
    assert get_effect("user_heater_warmup").parameter("t_w").grid == WARMUP_GRID  # a tuple
    c = _candidate("user_heater_warmup")
    assert c.tried and c.reason == ""
    assert (c.coefficients, c.shapes) == (("b",), ("t_w",))
    assert shape_grid(c) == [{"t_w": v} for v in WARMUP_GRID]

    inst = load_instrument("default")
    sc = load_scenario().nominal()
    run = simulate_run(inst, sc.conditions()[0]).run
    preps, _ = prepare_runs(inst, [run], 10.0)
    bare = bare_instrument(inst)
    grid = grid_columns(c, preps, bare)
    assert [g for g, _ in grid] == shape_grid(c)
    for g, cols in grid:
        full = candidate_columns(c, g, preps, bare, full=True)[0][:, 0]
        t = preps[0].ctx.time_s
        np.testing.assert_allclose(full, 1.0 - np.exp(-t / g["t_w"]), rtol=0, atol=1e-12)
        assert cols[0].shape == (preps[0].X.shape[0], 1)


def test_user_shape_parameter_without_a_grid_is_not_tried(user_registry):
    # Oracle: the rule (a shape parameter needs a grid or a default) and the reason's fix.
    _register_warmup("user_heater_warmup")
    c = _candidate("user_heater_warmup")
    assert not c.tried
    assert c.reason == ("register a grid for parameter t_w of effect user_heater_warmup: "
                        "Parameter('t_w', 's', ..., grid=(...))")

