"""North finding on real data made elsewhere: the Spresense gyrocompass logs.

Oracle: the publisher's result in ../shared/data/spresense-gyrocompass/README.md (Sony's
gyrocompass.py: circle fit of the per-file (gx, gy) means, no tilt correction): gyro bias x
-10.93 deg/h, radius 12.107 deg/h, directions of y per file (the x azimuth is y + 90).
We use the x gyro alone (examples/spresense_northfind.py builds one run of the 8 files).

Tolerances come from the data's own noise, measured here: sigma_w, the standard error of one
file's mean gx by batch means (about 1.1 deg/h). Ours, with N = 8 equally spaced positions:
sigma_psi = sqrt(2/N) sigma_w / Omega_h, sigma_b = sigma_w / sqrt(N), sigma_Omega_h =
sqrt(2/N) sigma_w (docs/physics.md section 5 error budget). The publisher's: the mean of N per-file
directions each uncertain by sigma_w / R (rad), a circle centre uncertain by
sqrt(2/N) sigma_w per component, a radius by sigma_w / sqrt(N) (assuming gy as noisy as gx).
Each comparison allows 3 standard deviations of the difference, taking the two estimates as
independent (they share gx, so this is conservative). The fit residual is checked to be
consistent with sigma_w (chi-square, 5 degrees of freedom), which is what makes sigma_w the
right yardstick.
"""

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from nfs.constants import OMEGA_IE_DPH
from nfs.northfind import north_find, wrap_deg_180

REPO = Path(__file__).resolve().parents[2]
DATA = REPO.parent / "shared" / "data" / "spresense-gyrocompass"
EXAMPLE = REPO / "examples" / "spresense_northfind.py"
N = 8

pytestmark = pytest.mark.skipif(
    not DATA.is_dir(), reason=f"Spresense data not found at {DATA} (../shared is absent)")


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("spresense_northfind", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up while it executes
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def fitted(example):
    logs = example.load_logs(DATA)
    run, res = example.north_find_spresense(logs)
    return logs, run, res, example.dwell_standard_error_dph(logs)


def test_run_is_one_cycle_of_eight_dwells(example, fitted):
    logs, run, res, _ = fitted
    assert run.n_samples == sum(log["time_s"].size for log in logs) == 34723  # README rows
    assert np.all(np.diff(run.columns["time_s"]) > 0)
    assert res.n_cycles == 1
    np.testing.assert_array_equal(res.theta_deg[0], example.NOMINAL_DEG)
    # per-file mean gx as tabulated in the data README (deg/h, 2 decimals)
    np.testing.assert_allclose(res.rate_dph[0], [-11.25, -19.89, -22.41, -19.03, -9.72,
                                                 -2.39, -0.08, -1.71], atol=0.006)
    # latitude from our own Omega_h (fixed point) is consistent with it
    assert OMEGA_IE_DPH * math.cos(math.radians(res.latitude_deg)) == pytest.approx(
        res.horizontal_rate_dph[0], abs=1e-6)


def test_fit_residual_is_consistent_with_the_noise(fitted):
    _, _, res, sigma_w = fitted
    assert 0.7 < sigma_w < 1.5  # per-sample std 63 deg/h, ~1000 bursts per file
    chi2 = N * res.residual_dph[0] ** 2 / sigma_w ** 2
    assert 0.21 < chi2 < 20.5  # 99.9 % interval of chi-square with N - 3 = 5 dof


def test_heading_agrees_with_publisher(example, fitted):
    _, _, res, sigma_w = fitted
    omega_h = res.horizontal_rate_dph[0]
    sig_ours = math.degrees(math.sqrt(2 / N) * sigma_w / omega_h)
    sig_pub = math.degrees(sigma_w / (example.PUBLISHER.radius_dph * math.sqrt(N)))
    tol = 3 * math.hypot(sig_ours, sig_pub)  # about 9 deg
    pub = example.PUBLISHER.heading_x_deg
    assert pub == pytest.approx(91.88, abs=0.01)  # mean(direction_y - nominal) + 90
    assert abs(wrap_deg_180(res.heading_deg[0] - pub)) < tol


def test_bias_agrees_with_publisher(example, fitted):
    logs, run, res, sigma_w = fitted
    tol = 3 * math.hypot(sigma_w / math.sqrt(N), math.sqrt(2 / N) * sigma_w)  # about 2 deg/h
    pub = example.PUBLISHER.bias_x_dph
    # the publisher's model has no tilt correction: compare like with like ...
    raw = north_find(run, tilt_correction=False)
    assert abs(raw.bias_dph[0] - pub) < tol
    # ... and ours, whose bias excludes the vertical Earth rate Omega_v * mean(f_x) that the
    # tilt takes into the publisher's bias
    shift = OMEGA_IE_DPH * math.sin(math.radians(res.latitude_deg)) * res.acc_x_g[0].mean()
    assert res.bias_dph[0] == pytest.approx(raw.bias_dph[0] - shift, abs=0.05)
    assert abs(res.bias_dph[0] - pub) < tol + abs(shift)


def test_horizontal_rate_agrees_with_publisher(example, fitted):
    _, _, res, sigma_w = fitted
    tol = 3 * math.hypot(math.sqrt(2 / N) * sigma_w, sigma_w / math.sqrt(N))  # about 2 deg/h
    assert abs(res.horizontal_rate_dph[0] - example.PUBLISHER.radius_dph) < tol


def test_example_script_runs(example, capsys):
    # style.md practice 13: the tests run the examples
    assert example.main([str(DATA)]) == 0
    out = capsys.readouterr().out
    assert "heading of x at position 0" in out and "91.88" in out
