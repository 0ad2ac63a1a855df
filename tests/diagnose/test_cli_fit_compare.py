"""nfs fit and nfs compare from the command line: outputs and one-line errors."""

import json

import pytest


@pytest.fixture
def scen_text(scenario_text):
    return scenario_text("fc", 3, (-20.0, 5.0, 40.0), 3900.0)


def test_fit_then_compare(tmp_path, cli, scen_text):
    (tmp_path / "s.toml").write_text(scen_text)
    assert cli("simulate", str(tmp_path / "s.toml"), "-o", str(tmp_path / "runs"),
                   "-q")[0] == 0
    fitted = tmp_path / "fitted.toml"
    code, out, err = cli("fit", str(tmp_path / "runs"), "-o", str(fitted), "-q")
    assert code == 0, err
    assert "thermal.nodes.housing.capacity_j_per_k" in out and fitted.exists()
    code, out, err = cli("compare", str(tmp_path / "runs"), "--model", str(fitted),
                             "-o", str(tmp_path / "rep"), "--json", str(tmp_path / "c.json"),
                             "-q")
    assert code == 0, err
    # Oracle: the model fitted to runs it could have made itself explains them to the noise.
    assert out.count("consistent with noise") == 6, out
    assert (tmp_path / "rep" / "report.md").exists()
    for name in ("dwell_bias.png", "heading_vs_time.png"):      # against time, per run
        assert (tmp_path / "rep" / "figures" / name).exists()
    json.loads((tmp_path / "c.json").read_text())


def test_fit_bad_path_and_model(tmp_path, cli, scen_text):
    (tmp_path / "s.toml").write_text(scen_text)
    cli("simulate", str(tmp_path / "s.toml"), "-o", str(tmp_path / "runs"), "-q")
    code, _, err = cli("fit", str(tmp_path / "runs"), "-o",
                           str(tmp_path / "f.toml"), "--free", "thermal.nodes.attic.power_w",
                           "-q")
    assert code == 2 and "attic" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "f.toml").exists()
    code, _, err = cli("compare", str(tmp_path / "runs"), "--model",
                           str(tmp_path / "missing.toml"), "-o", str(tmp_path / "rep"))
    assert code == 2 and "missing.toml" in err


def test_diagnose_cli(tmp_path, cli, scen_text):
    (tmp_path / "s.toml").write_text(scen_text)
    cli("simulate", str(tmp_path / "s.toml"), "-o", str(tmp_path / "runs"), "-q")
    code, out, err = cli("diagnose", str(tmp_path / "runs"), "--json",
                             str(tmp_path / "d.json"), "-q")
    assert code == 0, err
    # the finding (nfs.rivals.Finding): the diagnosis's fields at the top, its settlement
    # and the one answer
    doc = json.loads((tmp_path / "d.json").read_text())
    assert doc["schema"] == "nfs-finding/1"
    assert {"answer", "verdict", "provenance", "settlement"} <= set(doc)
    assert {"ranking", "unexplained", "not_tried"} <= set(doc) and doc["ranking"]
    assert {"effect", "target", "significant", "cv_rms_before", "cv_rms_after", "cv_drop"} <= \
        set(doc["ranking"][0])
    code, out, err = cli("diagnose", str(tmp_path / "runs"), "--apply",
                             "magnetic", "-o", str(tmp_path / "m2.toml"))
    assert code == 0, err
    assert "effects.magnetic.m" in out and (tmp_path / "m2.toml").exists()
    # the runs hold no magnetic effect: the diagnosis did not find it, and the user is told
    warning = [line for line in err.splitlines() if line.startswith("nfs: warning:")]
    assert len(warning) == 1 and "'magnetic' is not significant" in warning[0]
    assert "adding it as asked" in warning[0]
    # the same from the saved diagnosis, without diagnosing again
    code, out, err = cli("diagnose", str(tmp_path / "runs"), "--apply", "magnetic",
                         "--diagnosis", str(tmp_path / "d.json"), "-o",
                         str(tmp_path / "m3.toml"), "-q")
    assert code == 0 and "the diagnosis in" in err and "is not significant" in err
    assert "diagnosing" not in err
    code, _, err = cli("diagnose", str(tmp_path / "runs"), "--apply", "magnetic",
                       "--diagnosis", str(tmp_path / "nothing.json"), "-o",
                       str(tmp_path / "m4.toml"))
    assert code == 2 and "--diagnosis" in err and not (tmp_path / "m4.toml").exists()
    code, _, err = cli("diagnose", str(tmp_path / "runs"), "--apply",
                           "magnetc", "-o", str(tmp_path / "x.toml"))
    assert code == 2 and "unknown effect 'magnetc'" in err
    assert not (tmp_path / "x.toml").exists()
