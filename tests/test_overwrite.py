"""No single output file is replaced without --overwrite.

Oracle: an invariant.  Every command that writes one file (a model, a fitted TOML, a JSON)
and finds that file already there stops before any work with one line naming it (exit 2),
and the file keeps its bytes (SHA-256 before and after).  With --overwrite it is replaced.
"""

import hashlib

import pytest

from nfs.cli import main
from nfs.compensate import load_compensator


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Two short simulated runs (nfs simulate) and their scenario."""
    from tests.conftest import _scenario_text
    d = tmp_path_factory.mktemp("overwrite")
    (d / "s.toml").write_text(_scenario_text("small", 5, (-20.0, 40.0), 700.0))
    assert main(["simulate", str(d / "s.toml"), "-o", str(d / "runs"), "-q"]) == 0
    return d


def _sha(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


# (command line with RUNS, SCEN and OUT placeholders, the option that names the file)
COMMANDS = [
    (["train", "RUNS", "--method", "ls", "-o", "FILE", "-q"], "-o"),
    (["fit", "RUNS", "-o", "FILE", "-q"], "-o"),
    (["diagnose", "RUNS", "--apply", "magnetic", "-o", "FILE", "-q"], "-o"),
    (["diagnose", "RUNS", "--json", "FILE", "-q"], "--json"),
    (["compare", "RUNS", "-o", "OUT", "--json", "FILE", "-q"], "--json"),
    (["northfind", "RUNS", "--json", "FILE"], "--json"),
    (["table", "SCEN", "--no-compensation", "-o", "OUT", "--json", "FILE", "-q"], "--json"),
]


@pytest.mark.parametrize("argv, option", COMMANDS,
                         ids=[f"{argv[0]} {option}" for argv, option in COMMANDS])
def test_an_existing_file_is_refused_and_kept(runs, tmp_path, capsys, argv, option):
    target = tmp_path / "taken.out"
    target.write_bytes(b"an earlier result\n")
    before = _sha(target)
    subst = {"RUNS": runs / "runs", "SCEN": runs / "s.toml", "OUT": tmp_path / "out",
             "FILE": target}
    code = main([str(subst.get(a, a)) for a in argv])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert f"{option} {target}: the file exists; give --overwrite to replace it" in err
    assert _sha(target) == before
    assert not (tmp_path / "out").exists()           # stopped before any work


def test_overwrite_replaces_the_file(runs, tmp_path, capsys):
    model = tmp_path / "model.npz"
    model.write_bytes(b"an earlier model\n")
    assert main(["train", str(runs / "runs"), "--method", "ls", "-o", str(model), "-q",
                 "--overwrite"]) == 0
    assert load_compensator(model).method == "LS"
    headings = tmp_path / "headings.json"
    headings.write_text("{}")
    assert main(["northfind", str(runs / "runs"), "--json", str(headings),
                 "--overwrite"]) == 0
    assert '"runs"' in headings.read_text()
    capsys.readouterr()
