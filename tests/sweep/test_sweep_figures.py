"""Sweep figures pool only runs that share a white-noise floor.

Oracle: the floor in closed form, sqrt(2/N) (ARW / sqrt(dwell)) / (Omega_ie cos L)
(:func:`nfs.northfind.white_noise_floor_deg`), different at 30 and 60 deg of latitude; the
line of each panel is the RMS over that latitude's runs alone (read back from results.csv).
"""

from __future__ import annotations

import csv
import math

import pytest

from nfs.northfind import white_noise_floor_deg
from nfs.sweep import LocalExecutor, load_sweep, run_sweep
from nfs.sweep.figures import MAX_PANELS, floor_groups, sweep_figures
from nfs.sweep.store import CellStore


@pytest.fixture
def latitudes(tmp_path, short_scenario):
    """A sweep of two latitudes on the short two-temperature scenario."""
    folder = tmp_path
    (folder / "sweep.toml").write_text(f'scenario = "{short_scenario.name}"\nseeds = [3]\n'
                                       "[axes]\nlatitude_deg = [30.0, 60.0]\n")
    spec = load_sweep(folder / "sweep.toml")
    run_sweep(spec, folder / "out", executor=LocalExecutor(1), quiet=True, figures=False)
    with open(folder / "out" / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return spec, CellStore(folder / "out"), rows


def test_a_figure_across_latitudes_draws_one_labelled_floor_per_latitude(latitudes):
    spec, store, rows = latitudes
    fig = sweep_figures(spec, store)["heading_rmse_vs_start_temperature_c.png"]
    assert len(fig.axes) == 2
    for ax, lat in zip(fig.axes, (30.0, 60.0)):
        assert ax.get_title() == f"latitude_deg = {lat}"
        floors = [ln for ln in ax.get_lines()
                  if ln.get_label().startswith("white-noise floor")]
        assert len(floors) == 1 and f"latitude_deg = {lat}" in floors[0].get_label()
        want = white_noise_floor_deg(0.0003, 100.0, 4, lat)
        assert floors[0].get_ydata() == pytest.approx([want, want], rel=1e-9)
        # the start-up line: the RMS over this latitude's runs only
        line = next(ln for ln in ax.get_lines()
                    if ln.get_label().startswith("start-up, uncompensated"))
        for t0, y in zip(line.get_xdata(), line.get_ydata()):
            mine = [float(r["heading_rmse_deg"]) for r in rows
                    if float(r["latitude_deg"]) == lat and r["stage"] == "startup"
                    and float(r["start_temperature_c"]) == t0]
            assert y == pytest.approx(math.sqrt(sum(v * v for v in mine) / len(mine)))
    # along latitude itself the floor follows 1 / cos L in one panel
    one = sweep_figures(spec, store)["heading_rmse_vs_latitude_deg.png"]
    assert len(one.axes) == 1
    floor = next(ln for ln in one.axes[0].get_lines()
                 if ln.get_label() == "white-noise floor")
    assert floor.get_ydata()[1] / floor.get_ydata()[0] == pytest.approx(
        math.cos(math.radians(30.0)) / math.cos(math.radians(60.0)), rel=1e-9)


def test_floors_that_do_not_differ_are_pooled_and_many_are_set_over_each_cells():
    # Oracle: grouping is by the floor as a function of the axis, not by the axis values:
    # two soak times with the same floor pool; five latitudes make five groups.
    pts = [{"values": {"t": t, "soak": s}, "floor": 0.0046, "method": "none",
            "stage": "startup", "rmse": 0.01}
           for t in (-20.0, 30.0) for s in (1.0, 4.0)]
    assert [g for g, _ in floor_groups([dict(p, x=p["values"]["t"]) for p in pts], "t")] == [""]
    many = [{"values": {"t": t, "lat": lat}, "floor": 0.004 / math.cos(math.radians(lat)),
             "method": "none", "stage": "startup", "rmse": 0.01, "x": t}
            for t in (-20.0, 30.0) for lat in (0.0, 20.0, 40.0, 50.0, 60.0)]
    groups = floor_groups(many, "t")
    assert len(groups) == 5 > MAX_PANELS and groups[1][0] == "lat = 20.0"
