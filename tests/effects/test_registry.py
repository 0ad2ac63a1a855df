"""The effect registry: names of effects.md, lookup errors, user-defined effects."""

import re
from pathlib import Path

import pytest

import nfs.effects.registry as reg
from nfs.effects import (Parameter, available_effects, get_effect, load_effects_file,
                         make_effect, register_effect)
from nfs.errors import EffectError

#: Oracle: the contract table of ../shared/spec/effects.md, copied here so the test does not
#: need ../shared at run time (test_effects_md_matches checks the copy when shared/ is there).
EFFECTS_MD = {
    "shupe_winding": ("gyro", {"L", "D", "pattern", "N_opt", "n", "dn_dT", "alpha", "k_m", "c_m",
                               "L_asym"}),
    "bias_temperature": ("gyro", {"b1", "b2"}),
    "shupe_gradient": ("gyro", {"k_r"}),
    "shupe_rate": ("gyro", {"k_s"}),
    "shupe_product": ("gyro", {"k_p"}),
    "turn_on_transient": ("gyro", {"a", "tau"}),
    "aux_linear": ("gyro", {"channel", "k", "aux_ref"}),
    "scale_factor_temperature": ("gyro", {"s1"}),
    "magnetic": ("gyro", {"m", "D_mag"}),
    "polarization_ripple": ("gyro", {"A_p", "T_p", "phi"}),
    "shupe_stress": ("gyro", {"k_m", "c_m"}),
    "acc_bias_temperature": ("accelerometer", {"axis", "b_q1"}),
    "tec_power": ("thermal", {"T_set", "c_h", "c_c"}),
    "heat_source": ("thermal", {"node", "power"}),
    "thermometer_lag": ("thermometer", {"thermometer", "tau"}),
    "motor_heat": ("thermal", {"node", "power"}),
    "axis_misalignment": ("geometry", {"delta_deg", "gamma_deg"}),
    "indexing_error": ("geometry", {"offsets_deg", "sigma_deg"}),
    "tilt_exact": ("geometry", {"pitch_deg", "roll_deg"}),
}

SHARED = Path(__file__).resolve().parents[2].parent / "shared"


@pytest.mark.parametrize("name", sorted(EFFECTS_MD))
def test_every_effects_md_name_is_registered(name):
    spec = get_effect(name)
    kind, params = EFFECTS_MD[name]
    assert spec.kind == kind
    assert params <= {p.name for p in spec.parameters}
    doc = spec.function.__doc__
    assert doc and "[" in doc, "docstring must give the equation with units"


def test_effects_md_matches():
    """Oracle: the page itself.  A name marked "(planned)" is in the contract but need not
    be registered yet; whoever registers it drops the mark, so the check holds on the page
    before and after: every unmarked name is registered (and in the copy above), and every
    name of the copy is on the page, marked or not."""
    path = SHARED / "spec" / "effects.md"
    if not path.exists():
        pytest.skip(f"{path} absent (../shared not beside the repo)")
    rows = re.findall(r"^\| `([a-z_]+)`( \(planned\))? \|", path.read_text(), flags=re.M)
    on_page = {name for name, _ in rows}
    unmarked = {name for name, mark in rows if not mark}
    assert unmarked, "no effect names found on the page"
    assert unmarked <= set(EFFECTS_MD), sorted(unmarked - set(EFFECTS_MD))
    assert unmarked <= set(available_effects()), sorted(unmarked - set(available_effects()))
    assert set(EFFECTS_MD) <= on_page, sorted(set(EFFECTS_MD) - on_page)


def test_unknown_name_lists_valid_names():
    with pytest.raises(EffectError) as exc:
        get_effect("shupe_gradeint")
    msg = str(exc.value)
    assert "shupe_gradeint" in msg and "shupe_gradient" in msg and "tec_power" in msg
    assert "\n" not in msg


def test_null_effect_is_explicit():
    assert "null" in available_effects()
    assert get_effect("null").function(None) == 0.0


def test_parameter_checks():
    with pytest.raises(EffectError, match="needs parameter 'k_r'"):
        make_effect("shupe_gradient", {})
    with pytest.raises(EffectError, match="no parameter 'kr'.*allowed: k_r"):
        make_effect("shupe_gradient", {"kr": 1.0})
    with pytest.raises(EffectError, match="must be a number"):
        make_effect("shupe_gradient", {"k_r": "big"})
    e = make_effect("bias_temperature", {"b1": 0.001})
    assert e.params == {"b1": 0.001, "b2": 0.0, "node": None}
    assert e.label == "bias_temperature"
    assert make_effect("acc_bias_temperature", {"axis": "y", "b_q1": 1e-5}).label == \
        "acc_bias_temperature:y"


def test_user_effect_file(tmp_path):
    f = tmp_path / "my_effects.py"
    f.write_text(
        "from nfs.effects import register_effect, Parameter\n"
        "@register_effect('test_quadratic_time', kind='gyro',\n"
        "                 parameters=[Parameter('c', 'deg/h/s^2', 'curvature')])\n"
        "def test_quadratic_time(ctx, *, c):\n"
        "    '''c t^2 [deg/h].'''\n"
        "    return c * ctx.time_s ** 2\n")
    load_effects_file(f)
    load_effects_file(f)  # reloading the same file is allowed
    spec = get_effect("test_quadratic_time")
    assert spec.kind == "gyro" and spec.parameters[0].unit == "deg/h/s^2"
    with pytest.raises(EffectError, match="not found"):
        load_effects_file(tmp_path / "missing.py")


def test_duplicate_name_refused():
    with pytest.raises(EffectError, match="registered already"):
        register_effect("bias_temperature", kind="gyro")(lambda ctx: 0.0)


def test_entry_point_plugins(monkeypatch):
    """A plug-in package's entry point in group nfs.effects is loaded on first lookup."""
    loaded = []

    class EP:
        name = "demo"

        def load(self):
            register_effect("test_ep_effect", kind="gyro")(lambda ctx: 0.0)
            loaded.append(True)

    monkeypatch.setattr(reg, "_entry_points_loaded", False)
    monkeypatch.setattr(reg.metadata, "entry_points", lambda group: [EP()])
    assert get_effect("test_ep_effect").kind == "gyro"
    assert loaded == [True]


@pytest.mark.parametrize("parameter, match", [
    (Parameter("k", "deg/h", "gain", grid=(1.0, 2.0)), "linear coefficient"),
    (Parameter("tau", "s", "time constant", grid=()), "non-empty tuple of numbers"),
    (Parameter("tau", "s", "time constant", grid=60.0), "non-empty tuple of numbers"),
    (Parameter("tau", "s", "time constant", grid=(60.0, "long")), "non-empty tuple of numbers"),
    (Parameter("tau", "s", "time constant", bounds=(1.0, 100.0), grid=(10.0, 300.0)),
     r"grid value\(s\) 300 \[s\] outside its bounds"),
])
def test_grid_checked_at_registration(parameter, match):
    # Oracle: a grid the diagnosis could not use (on a linear coefficient, empty, not
    # numbers, outside the bounds) is refused when the effect is registered, naming both.
    with pytest.raises(EffectError, match=match) as err:
        register_effect("test_bad_grid", kind="gyro", parameters=[parameter])
    assert f"effect 'test_bad_grid' parameter '{parameter.name}'" in str(err.value)
    assert "test_bad_grid" not in available_effects()


def test_grid_on_a_shape_by_flag(monkeypatch):
    # Oracle: shape=True makes a parameter of any unit a shape, so it may carry a grid,
    # stored as a tuple of floats (the registry is a copy, restored after the test).
    monkeypatch.setattr(reg, "_REGISTRY", dict(reg._REGISTRY))
    p = Parameter("c", "1/K", "temperature coefficient", shape=True, grid=[-0.01, 0])
    assert p.nonlinear and not Parameter("c", "1/K", "temperature coefficient").nonlinear
    register_effect("test_flag_grid", kind="gyro", parameters=[p])(lambda ctx, *, c: 0.0)
    assert get_effect("test_flag_grid").parameter("c").grid == (-0.01, 0.0)
