"""The drawn unit beside its runs, and a runs folder resumed run by run.

Oracles: the unit's values are the simulation's own (SimulationResult.instrument), read back
bit for bit from its TOML; a drawn unit whose draw lies outside 3 typical ranges warns 3
times as a plain instrument file and once beside its manifest; runs are seeded, so a folder
interrupted, damaged and resumed holds the bytes of a folder written at once.
"""

import dataclasses
import json
import shutil
import warnings

import pytest

import nfs
from nfs.io.outdir import MANIFEST_NAME, read_manifest
from nfs.io.resume import JOURNAL_NAME
from nfs.ranges import RangeWarning
from nfs.studies import runs_folder as rf

# unit 0 of the default instrument drawn with the realistic scatter and unit seed 374 lies
# outside 3 typical ranges (two capacities and a board power): found by drawing seeds 0-399
SCENARIO = """
name = "drawn"
seed = 374
start_temperatures_c = [-10.0, 20.0]
repeats = REPEATS
duration_s = 1300.0
[schedule]
positions_deg = [0.0, 90.0, 180.0, 270.0]
dwell_s = 150.0
move_s = 10.0
[variability]
preset = "realistic"
"""


def _scenario(tmp_path, repeats=1, name="s.toml"):
    path = tmp_path / name
    path.write_text(SCENARIO.replace("REPEATS", str(repeats)))
    return path


def _range_warnings(fn):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn()
    return out, [str(w.message) for w in caught if issubclass(w.category, RangeWarning)]


def test_unit_file_holds_the_drawn_values_and_warns_once(tmp_path):
    sc = nfs.load_scenario(_scenario(tmp_path))
    res = rf.simulate_to_folder(sc, tmp_path / "runs")
    unit = sc.unit_instrument(0)
    # the unit's values are those the runs were simulated with, and not the preset's
    sim = nfs.simulate_run(sc.instrument, sc.conditions()[0])
    assert sim.instrument == unit == res.units[0] and unit != sc.instrument
    path = tmp_path / "runs" / "unit_00.toml"
    assert res.unit_files == {0: path}
    loaded, said = _range_warnings(lambda: nfs.load_instrument(path))
    assert loaded == rf.unit_file_instrument(unit, 0)          # every value, bit for bit
    assert loaded.effects == unit.effects and loaded.network == unit.network
    assert len(said) == 1 and "3 value(s) outside their typical ranges" in said[0], said
    # the same file away from its manifest is a user's instrument: a warning per value
    shutil.copy(path, tmp_path / "copy.toml")
    _, said = _range_warnings(lambda: nfs.load_instrument(tmp_path / "copy.toml"))
    assert len(said) == 3, said
    # the manifest names the unit file, each run's sidecar the file of the unit that made it
    manifest = read_manifest(tmp_path / "runs")
    assert manifest["units"] == [{"file": "unit_00.toml", "unit": 0, "scenario": "drawn",
                                  "drawn": True, "runs": 2}]
    assert "unit_00.toml" in {f["path"] for f in manifest["files"]}
    for run in nfs.read_runs(tmp_path / "runs"):
        assert run.meta.extra["unit_file"] == "unit_00.toml"


def test_edited_unit_file_warns_per_value(tmp_path):
    sc = nfs.load_scenario(_scenario(tmp_path))
    rf.simulate_to_folder(sc, tmp_path / "runs")
    path = tmp_path / "runs" / "unit_00.toml"
    path.write_text(path.read_text() + "\n# edited\n")       # no longer the file recorded
    _, said = _range_warnings(lambda: nfs.load_instrument(path))
    assert len(said) == 3


def test_each_unit_of_a_fleet_gets_its_file(tmp_path):
    path = _scenario(tmp_path, repeats=3)
    path.write_text(path.read_text().replace("repeats = 3", "repeats = 3\nunits = 3"))
    sc = nfs.load_scenario(path)
    res = rf.simulate_to_folder(sc, tmp_path / "runs")
    assert sorted(res.unit_files) == [0, 1, 2]
    for u, p in res.unit_files.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RangeWarning)
            assert nfs.load_instrument(p) == rf.unit_file_instrument(sc.unit_instrument(u), u)
    by_run = {r.name: r.meta.extra["unit_file"] for r in nfs.read_runs(tmp_path / "runs")}
    assert by_run["drawn_T+20C_u2_r0"] == "unit_02.toml"
    assert len({p.read_text() for p in res.unit_files.values()}) == 3


def _interrupt_after(monkeypatch, n_runs):
    """write_run raises KeyboardInterrupt as run n_runs + 1 is about to be written."""
    calls = []
    real = rf.write_run

    def write(run, target):
        if len(calls) == n_runs:
            raise KeyboardInterrupt
        calls.append(run.name)
        return real(run, target)
    monkeypatch.setattr(rf, "write_run", write)
    return calls


def _same_bytes(a, b):
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    for name in names:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


@pytest.mark.parametrize("flag", [[], ["--resume"]], ids=["automatic", "--resume"])
def test_interrupted_folder_resumes_to_the_same_bytes(tmp_path, monkeypatch, cli, flag):
    scen = _scenario(tmp_path, repeats=3)
    assert cli("simulate", scen, "-o", tmp_path / "once")[0] == 0
    sc = nfs.load_scenario(scen)
    written = _interrupt_after(monkeypatch, 4)
    with pytest.raises(KeyboardInterrupt):
        rf.simulate_to_folder(sc, tmp_path / "cut")
    monkeypatch.undo()
    cut = tmp_path / "cut"
    assert read_manifest(cut)["partial"] is True and len(written) == 4
    # what an interruption can leave besides: a recorded run lost, a record cut mid-line
    (cut / f"{written[0]}.csv").unlink()
    with open(cut / JOURNAL_NAME, "a") as f:
        f.write('{"files":[{"path":"drawn_T+20C_r2.csv","by')
    code, out, err = cli("simulate", scen, "-o", cut, *flag)
    assert code == 0, err
    assert "resuming" in err and "3 of 6 runs already written" in err
    assert "simulating 3/3" in err                  # the lost run and the two never written
    _same_bytes(tmp_path / "once", cut)
    assert not (cut / JOURNAL_NAME).exists()


def test_resume_refuses_a_users_file_and_another_scenario(tmp_path, monkeypatch, cli):
    scen = _scenario(tmp_path, repeats=3)
    sc = nfs.load_scenario(scen)
    _interrupt_after(monkeypatch, 2)
    with pytest.raises(KeyboardInterrupt):
        rf.simulate_to_folder(sc, tmp_path / "cut")
    monkeypatch.undo()
    cut = tmp_path / "cut"
    (cut / "notes.txt").write_text("mine")
    code, _, err = cli("simulate", scen, "-o", cut, "-q")
    assert code == 2 and "notes.txt" in err
    (cut / "notes.txt").unlink()
    # another seed is another job: nothing of this folder is its own
    code, _, err = cli("simulate", scen, "-o", cut, "--seed", "5", "--resume", "-q")
    assert code == 2 and "nothing to resume" in err
    # a complete folder resumed keeps every file and writes the same manifest
    assert cli("simulate", scen, "-o", cut)[0] == 0
    before = {p.name: p.stat().st_mtime_ns for p in cut.iterdir()}
    manifest = (cut / MANIFEST_NAME).read_bytes()
    code, _, err = cli("simulate", scen, "-o", cut, "--resume")
    assert code == 0 and "6 of 6 runs already written" in err
    after = {p.name: p.stat().st_mtime_ns for p in cut.iterdir()}
    assert {k: v for k, v in after.items() if k != MANIFEST_NAME} == \
        {k: v for k, v in before.items() if k != MANIFEST_NAME}
    assert (cut / MANIFEST_NAME).read_bytes() == manifest
    assert json.loads(manifest)["arguments"] == ["simulate", str(scen)]


def test_drawn_units_are_those_that_make_start_ups(tmp_path):
    path = _scenario(tmp_path, repeats=2)
    path.write_text(path.read_text().replace("repeats = 2", "repeats = 2\nunits = 4"))
    sc = nfs.load_scenario(path)
    assert list(sc.drawn_units()) == [0, 1]
    assert sc.nominal().drawn_units() == {0: sc.instrument}
    with pytest.raises(nfs.NfsError, match="units 0..3"):
        sc.unit_instrument(4)
    assert dataclasses.replace(sc, units=4).unit_instrument(3) != sc.unit_instrument(0)


@pytest.mark.integration
def test_nfs_fit_takes_the_unit_file_as_its_model(tmp_path, cli):
    # 3 s: a fit of the drift stage from the unit itself, whose file warns in one line
    scen = _scenario(tmp_path)
    assert cli("simulate", scen, "-o", tmp_path / "runs", "-q")[0] == 0
    code, out, err = cli("fit", tmp_path / "runs", "--model", tmp_path / "runs" / "unit_00.toml",
                         "-o", tmp_path / "fitted.toml", "--stages", "drift", "--no-refine",
                         "--no-noise-fit", "-q")
    assert code == 0, err
    warned = [l for l in err.splitlines() if l.startswith("nfs: warning:") and "unit_00" in l]
    assert len(warned) == 1 and "3 value(s) outside their typical ranges" in warned[0]
