"""Output folders hold one experiment: stale files removed, foreign ones refused, a manifest."""

import json
import os

import pytest

from nfs.errors import NfsError
from nfs.io.atomic import atomic_write_text
from nfs.io.outdir import MANIFEST_NAME, OutputFolder, check_output_file, read_manifest


def _run(folder, names, command="table", overwrite=False):
    out = OutputFolder(folder, command, overwrite=overwrite)
    folder.mkdir(exist_ok=True)
    for n in names:
        atomic_write_text(folder / n, f"content of {n}\n")
    out.finish(arguments=["x"], inputs={"what": "test"})
    return out


def test_files_of_the_earlier_output_that_are_not_rewritten_are_removed(tmp_path):
    d = tmp_path / "out"
    _run(d, ["a.csv", "b.csv", "c.md"])
    assert [f["path"] for f in read_manifest(d)["files"]] == ["a.csv", "b.csv", "c.md"]
    out = _run(d, ["a.csv"])
    assert sorted(p.name for p in d.iterdir()) == ["a.csv", MANIFEST_NAME]
    assert out.removed == ["b.csv", "c.md"] and "removed 2 file(s)" in out.summary()
    assert [f["path"] for f in read_manifest(d)["files"]] == ["a.csv"]


def test_manifest_lists_files_in_subfolders_with_their_hash(tmp_path):
    import hashlib
    d = tmp_path / "out"
    out = OutputFolder(d, "compare")
    (d / "figures").mkdir(parents=True)
    atomic_write_text(d / "figures" / "f.png", "png")
    out.finish()
    m = json.loads((d / MANIFEST_NAME).read_text())
    assert m["command"] == "compare"
    assert m["files"] == [{"path": "figures/f.png",
                           "sha256": hashlib.sha256(b"png").hexdigest()}]


def test_files_of_unknown_origin_are_refused_before_any_work(tmp_path):
    d = tmp_path / "out"
    d.mkdir()
    (d / "notes.txt").write_text("mine")
    with pytest.raises(NfsError, match=r"1 file\(s\) this package did not list.*notes\.txt"):
        OutputFolder(d, "simulate")
    out = _run(d, ["a.csv"], command="simulate", overwrite=True)
    assert (d / "notes.txt").read_text() == "mine"          # never removed
    assert out.foreign == ["notes.txt"] and "unknown origin" in out.summary()


def test_another_commands_output_is_refused_unless_overwrite(tmp_path):
    d = tmp_path / "out"
    _run(d, ["run.csv"], command="simulate")
    with pytest.raises(NfsError, match="output of 'nfs simulate'"):
        OutputFolder(d, "table")
    _run(d, ["report.md"], command="table", overwrite=True)
    assert sorted(p.name for p in d.iterdir()) == [MANIFEST_NAME, "report.md"]


def test_a_file_or_an_unwritable_place_is_refused(tmp_path):
    f = tmp_path / "file.txt"
    f.write_text("x")
    with pytest.raises(NfsError, match="is a file, not a folder"):
        OutputFolder(f, "table")
    with pytest.raises(NfsError, match="is a file, so no folder can be made there"):
        OutputFolder(f / "sub", "table")
    with pytest.raises(NfsError, match="is a folder; give a file name"):
        check_output_file(tmp_path, "-o")
    with pytest.raises(NfsError, match="does not exist"):
        check_output_file(tmp_path / "no" / "model.toml", "-o")
    if os.geteuid() != 0:  # root writes everywhere
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        try:
            with pytest.raises(NfsError, match="not writable"):
                OutputFolder(ro / "out", "table")
        finally:
            ro.chmod(0o700)


# --------------------------------------------------------------------------------------------
# Through the command line


def _small(tmp_path, scenario_text):
    p = tmp_path / "small.toml"
    p.write_text(scenario_text("small", 5, (-20.0, 40.0), 700.0))
    return p


def test_simulate_twice_into_one_folder_leaves_one_experiment(tmp_path, cli, scenario_text):
    scen = _small(tmp_path, scenario_text)
    d = tmp_path / "runs"
    assert cli("simulate", scen, "-o", d, "--repeats", "3", "-q")[0] == 0
    assert len(list(d.glob("*.csv"))) == 6
    code, out, err = cli("simulate", scen, "-o", d, "--repeats", "1", "-q")
    assert code == 0 and "removed 8 file(s) of the earlier output" in err
    # two runs and the unit that made them (unit_00.toml)
    assert len(list(d.glob("*.csv"))) == 2 and len(list(d.glob("*.toml"))) == 3
    m = read_manifest(d)
    assert m["command"] == "simulate" and m["inputs"]["scenario"]["name"] == "small"
    assert len(m["files"]) == 5 and m["units"][0]["file"] == "unit_00.toml"
    code, out, _ = cli("northfind", d)
    assert code == 0 and sum(line.startswith("| small") for line in out.splitlines()) == 2


def test_table_into_a_run_folder_is_refused_with_one_line(tmp_path, cli, scenario_text):
    scen = _small(tmp_path, scenario_text)
    d = tmp_path / "runs"
    assert cli("simulate", scen, "-o", d, "-q")[0] == 0
    before = sorted(p.name for p in d.iterdir())
    code, _, err = cli("table", scen, "-o", d, "--no-compensation", "-q")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "output of 'nfs simulate'" in err and "--overwrite" in err
    assert sorted(p.name for p in d.iterdir()) == before


@pytest.mark.parametrize("command", [
    ["table", "--no-compensation"], ["simulate"], ["compare"], ["compensate", "--model", "m"]])
def test_folder_commands_refuse_an_existing_file_as_output(tmp_path, cli, scenario_text,
                                                          command):
    scen = _small(tmp_path, scenario_text)
    f = tmp_path / "taken"
    f.write_text("keep me")
    args = [command[0], scen] + command[1:] if command[0] in ("table", "simulate") else \
        [command[0], tmp_path / "runs"] + command[1:]
    if command[0] in ("compare", "compensate"):
        assert cli("simulate", scen, "-o", tmp_path / "runs", "-q")[0] == 0
    if command[0] == "compensate":
        args[3] = tmp_path / "model.npz"
        assert cli("train", tmp_path / "runs", "--method", "ls", "-o", args[3], "-q")[0] == 0
    code, _, err = cli(*args, "-o", f)
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert f"-o {f}: is a file, not a folder" in err
    assert f.read_text() == "keep me"


@pytest.mark.parametrize("command", [["train", "--method", "ls"], ["fit"],
                                     ["diagnose", "--apply", "magnetic"]])
def test_file_commands_refuse_a_folder_or_a_missing_place(tmp_path, cli, scenario_text,
                                                         command):
    scen = _small(tmp_path, scenario_text)
    assert cli("simulate", scen, "-o", tmp_path / "runs", "-q")[0] == 0
    for target, msg in ((tmp_path, "is a folder; give a file name"),
                        (tmp_path / "no" / "x.toml", "does not exist")):
        code, _, err = cli(command[0], tmp_path / "runs", *command[1:], "-o", target)
        assert code == 2 and msg in err and len(err.strip().splitlines()) == 1


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux /proc")
def test_a_place_where_nothing_can_be_made_is_refused_even_for_root(tmp_path, cli):
    # Oracle: /proc takes no new folder or file, whoever asks (os.access says yes to root);
    # the command stops before any work with one line, exit 2, and writes nothing.
    with pytest.raises(NfsError, match="no folder can be made"):
        OutputFolder("/proc/nfs-test/out", "table")
    with pytest.raises(NfsError, match="no file can be written"):
        check_output_file("/proc/nfs-test.json", "--json")
    code, _, err = cli("table", "--no-compensation", "-q", "-o", tmp_path / "o",
                       "--json", "/proc/nfs-test.json")
    assert code == 2 and "--json" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()
