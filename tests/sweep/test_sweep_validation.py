"""A bad sweep file stops before any work with one located line and exit 2."""

from pathlib import Path

import pytest

from nfs.cli import main
from nfs.sweep import load_sweep

CASES = [
    ("seeds = [1]\nbogus = 1\n", "key 'bogus'", "unknown key"),
    ("seeds = [1]\n[axes]\nlatitud_deg = [30.0]\n", "key 'axes.latitud_deg'",
     "did you mean latitude_deg"),
    ("seeds = [1]\n[axes]\nlatitude_deg = []\n", "key 'axes.latitude_deg'",
     "at least one value"),
    ("seeds = [1]\n[axes]\nlatitude_deg = [30.0, 95.0]\n", "key 'axes.latitude_deg'",
     "value 95.0: must be <= 89.0"),
    ("seeds = [1]\n[axes]\n\"gyro.arw_deg_per_rth_h\" = { low = 0.001, high = 0.0001 }\n",
     "key 'axes.gyro.arw_deg_per_rth_h'", "low < high"),
    ("seeds = [1]\n[axes]\n\"effects.shupe_winding.k_m\" = { low = 0.0, high = 1e-5, "
     "log = true }\n", "key 'axes.effects.shupe_winding.k_m'", "log range needs low > 0"),
    ("seeds = [1]\n[axes]\n\"thermal.nodes.housing.capacity_j_per_k\" = [-5.0]\n",
     "key 'axes.thermal.nodes.housing.capacity_j_per_k'", "capacity_j_per_k must be > 0"),
    ("seeds = [1]\n[axes]\nschedule.dwell_s = [60.0, 5000.0]\n", "key 'axes.schedule.dwell_s'",
     "shorter than one north-finding cycle"),
    ("seeds = [1]\n[axes]\nlatitude_deg = { low = 0.0, high = 60.0 }\n[draws]\ncount = 6\n",
     "key 'draws.count'", "power of 2"),
    ("seeds = []\n", "key 'seeds'", "non-empty list"),
    ("seeds = [1]\nmethod = \"ssa\"\n", "key 'method'", "unknown compensation method"),
    ("seeds = [1, 2]\nmethod = \"ls\"\n", "key 'seeds'", "compensation.train_seed"),
    ("seeds = [1]\nspec_deg = -0.01\n", "key 'spec_deg'", "> 0"),
    ("seeds = [1]\nscenario = \"missing.toml\"\n", "key 'scenario'", "file not found"),
    ("seeds = [1]\n[axes]\nseed = [1, 2]\n", "key 'axes.seed'", "list the seeds"),
]


@pytest.mark.parametrize("text, where, what", CASES)
def test_bad_sweep_is_one_located_line_and_exit_2(tmp_path, capsys, text, where, what):
    sweep = tmp_path / "bad.toml"
    sweep.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["sweep", str(sweep), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"{sweep}, {where}" in err and what in err
    assert not out.exists()                           # checked before any work


def test_output_that_is_a_file_is_an_error(tmp_path, capsys):
    sweep = tmp_path / "s.toml"
    sweep.write_text("seeds = [1]\n", encoding="utf-8")
    target = tmp_path / "file"
    target.write_text("x")
    assert main(["sweep", str(sweep), "-o", str(target), "-q"]) == 2
    assert "not a folder" in capsys.readouterr().err


@pytest.mark.parametrize("path", sorted(
    (Path(__file__).resolve().parents[2] / "scenarios" / "sweeps").glob("*.toml")),
    ids=lambda p: p.name)
def test_sample_sweeps_are_valid(path):
    # Oracle: the files themselves; every axis value is applied to the base scenario
    spec = load_sweep(path)
    assert spec.n_cells >= 5 and spec.scenario.name == "startup_7temps"
