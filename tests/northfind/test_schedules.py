"""North finding on every schedule: 2, 3, 4 and 8 positions at headings around the circle.

Runs come from nfs.northfind.synthetic_run (exactly tilted table, constant bias, optional
seeded white noise); the simulator's two-position table and the command line are checked
at the end.
"""

import math

import numpy as np
import pytest

from nfs.errors import NfsError
from nfs.northfind import north_find, synthetic_run, white_noise_floor_deg, wrap_deg_180

SCHEDULES = {
    2: (0.0, 180.0),
    3: (0.0, 120.0, 240.0),
    4: (0.0, 90.0, 180.0, 270.0),
    8: tuple(45.0 * np.arange(8)),
}
HEADINGS = np.arange(0.0, 360.0, 15.0)
LAT = 30.26


def _run(psi, positions, **kw):
    kw = {"n_cycles": 2, **kw}
    return synthetic_run(heading_deg=psi, latitude_deg=LAT, positions_deg=positions,
                         dwell_s=60.0, move_s=5.0, tilt_north_deg=0.3, tilt_east_deg=-0.2,
                         bias_dph=0.7, **kw)


@pytest.mark.parametrize("n", [3, 4, 8])
def test_noiseless_multiposition_runs_give_the_heading_everywhere(n):
    # Oracle: noiseless data of an exactly tilted table -> psi to rounding; no flag.
    for psi in HEADINGS:
        res = north_find(_run(psi, SCHEDULES[n]))
        assert not res.ambiguous
        assert np.all(np.abs(res.error_deg) < 1e-9), (psi, res.error_deg)


@pytest.mark.parametrize("positions", [(0.0, 180.0), (30.0, 210.0)], ids=["0-180", "30-210"])
def test_two_positions_flag_without_a_hint_and_take_the_hinted_branch(positions):
    # Oracle: two positions see only Omega_h cos(psi + theta_a): without a hint the run is
    # flagged and psi is one of the two branches: psi itself (to rounding), or its mirror
    # about the line of the positions, -psi - 2 theta_a on a level table (the 0.3 deg tilt
    # moves the mirror by ~1e-3 deg, second order); a hint within 10 deg (closer to the
    # true branch than to the mirror, 2 |psi + theta_a| away) gives psi to rounding, except
    # where the axis lies on the line of the positions (sin(psi + theta_a) = 0): there the
    # two branches merge (within the tilt's 1e-3 deg) and either is the answer.
    theta_a = positions[0]
    for i, psi in enumerate(HEADINGS):
        run = _run(psi, positions)
        bare = north_find(run)
        assert bare.ambiguous
        mirror = -psi - 2 * theta_a
        true_branch = np.abs(wrap_deg_180(bare.heading_deg - psi)) < 1e-9
        mirror_branch = np.abs(wrap_deg_180(bare.heading_deg - mirror)) < 0.01
        assert np.all(true_branch | mirror_branch), (psi, bare.heading_deg)
        hinted = north_find(run, heading_hint_deg=psi + (10.0 if i % 2 else -10.0))
        assert not hinted.ambiguous
        on_line = abs(math.sin(math.radians(psi + theta_a))) < 1e-6
        tol = 0.01 if on_line else 1e-9
        assert np.all(np.abs(hinted.error_deg) < tol), (psi, hinted.error_deg)


@pytest.mark.parametrize("n", [2, 3, 4, 8])
def test_lightly_noisy_runs_stay_within_the_floor(n):
    # Oracle: white_noise_floor_deg; 20 seeded cycles per heading give an RMSE within
    # 2x the floor (relative standard error of a 20-cycle RMSE ~ 16 %: 2x is > 6 sigma).
    arw = 0.0003
    for i, psi in enumerate(HEADINGS):
        run = _run(psi, SCHEDULES[n], n_cycles=20, arw_deg_per_rth_h=arw,
                   random_state=1000 * n + i)
        res = north_find(run, heading_hint_deg=psi + 10.0)
        rmse = float(np.sqrt(np.mean(res.error_deg ** 2)))
        floor = white_noise_floor_deg(arw, 60.0, n, LAT, heading_deg=psi)
        assert rmse < 2.0 * floor, (psi, rmse, floor)


def test_two_position_floor_matches_the_scatter():
    # Oracle: sigma_psi = (ARW / sqrt(tau)) / (sqrt(2) Omega_h |sin(psi + theta_a)|)
    # (budget.white_noise_floor_deg, N = 2); 1500 cycles: RMSE relative standard error
    # 1.8 %, so 10 % is > 5 sigma.
    arw, dwell, psi = 0.0005, 150.0, 212.7
    run = synthetic_run(heading_deg=psi, latitude_deg=LAT, positions_deg=(0.0, 180.0),
                        dwell_s=dwell, move_s=10.0, n_cycles=1500, arw_deg_per_rth_h=arw,
                        bias_dph=0.5, random_state=20240602)
    res = north_find(run, heading_hint_deg=200.0)
    rmse = float(np.sqrt(np.mean(res.error_deg ** 2)))
    floor = white_noise_floor_deg(arw, dwell, 2, LAT, heading_deg=psi)
    sigma_w = arw / math.sqrt(dwell / 3600.0)
    omega_h = 15.041067 * math.cos(math.radians(LAT))
    hand = math.degrees(sigma_w / (math.sqrt(2) * omega_h * abs(math.sin(math.radians(psi)))))
    assert floor == pytest.approx(hand, rel=1e-12)
    assert rmse == pytest.approx(floor, rel=0.10)
    # the floor of N >= 3 does not depend on the heading; visits count as more positions
    assert white_noise_floor_deg(arw, dwell, 4, LAT, visits=2) == pytest.approx(
        white_noise_floor_deg(arw, dwell, 8, LAT))
    assert white_noise_floor_deg(arw, dwell, 2, LAT, heading_deg=0.0) == math.inf
    with pytest.raises(NfsError, match="depends on the heading"):
        white_noise_floor_deg(arw, dwell, 2, LAT)
    with pytest.raises(NfsError, match="n_positions >= 2"):
        white_noise_floor_deg(arw, dwell, 1, LAT)


def test_two_position_scenario_on_the_command_line(tmp_path, cli, scenario_text):
    # Oracle: the scenario's true heading. With --heading-hint 200 every run's mean heading
    # is 212.7 deg within the start-up drift (0.05 deg); without a hint every run is
    # flagged ambiguous and prints no heading.
    text = scenario_text("two", 3, (-20.0, 40.0), 2600.0, latitude_deg=30.26,
                         true_heading_deg=212.7)
    text = text.replace("positions_deg = [0.0, 90.0, 180.0, 270.0]", "positions_deg = [0.0, 180.0]")
    assert "positions_deg = [0.0, 180.0]" in text
    (tmp_path / "two.toml").write_text(text)
    code, _, _ = cli("simulate", tmp_path / "two.toml", "-o", tmp_path / "runs", "-q")
    assert code == 0
    code, out, _ = cli("northfind", tmp_path / "runs", "--heading-hint", "200")
    rows = [l.split("|") for l in out.splitlines() if l.startswith("| two")]
    assert code == 0 and len(rows) == 2
    for r in rows:
        assert float(r[4]) == pytest.approx(212.7, abs=0.05)
    code, out, _ = cli("northfind", tmp_path / "runs")
    rows = [l for l in out.splitlines() if l.startswith("| two")]
    assert code == 0 and len(rows) == 2 and all("| ambiguous |" in r for r in rows)
    code, out, _ = cli("table", tmp_path / "two.toml", "-o", tmp_path / "tab", "--no-compensation")
    assert code == 0 and "two positions" in out
