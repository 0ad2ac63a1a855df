"""The examples are tests (PySINDy practice): each answers its question on every run."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def load(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_missing_effect_example(tmp_path):
    """Oracle: the hidden magnetic bias (m = 0.012 deg/h, 1.9x the drift noise floor) is the
    top and only significant candidate; adding it brings the gyro drift residual down to the
    noise floor (RMS at least halved) and the per-position spread below 3 standard errors;
    the heading RMSE does not get worse."""
    r = load("missing_effect").main(tmp_path)
    assert r["top"] == "magnetic" and r["significant"] == ["magnetic"]
    assert r["rms_after"] <= 0.5 * r["rms_before"]
    assert r["rms_after"] <= 1.5 * r["floor"]
    assert r["position_ratio_before"] > 3 > r["position_ratio_after"]
    assert r["heading_after_deg"] <= r["heading_before_deg"] * 1.001
