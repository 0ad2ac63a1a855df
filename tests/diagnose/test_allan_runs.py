"""Tests of nfs allan: nfs.comparison.allan_runs (every dwell's Allan deviation, N, B, K with
intervals beside the stated values), its figure (nfs.report.allan_figure) and its command.

The runs are simulated by the default instrument (N = 0.0003 deg/sqrt(h), B = 0.002 deg/h,
K = 0) from the default scenario's schedule (150 s dwells, 10 s moves, 1 Hz), one start-up of
2.5 h at T0 = 17 C.  Each test names its oracle.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from nfs.comparison import AllanReport, allan_of_runs, stated_instrument
from nfs.comparison.allan_runs import STARTUP_TAU_FRACTION, TAU_FRACTION
from nfs.config.scenario import load_scenario
from nfs.errors import InputError
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.io.measurement import write_run
from nfs.noise import BI_FLOOR_FACTOR
from nfs.report.allan_figure import allan_figure, plot_allan


@pytest.fixture(scope="module")
def runs():
    sc = dataclasses.replace(load_scenario().nominal(), start_temperatures_c=(17.0,), seed=1)
    return [simulate_run(sc.instrument, c).run for c in sc.conditions()]


@pytest.fixture(scope="module")
def report(runs) -> AllanReport:
    return allan_of_runs(runs)


def _with_meta(run, **changes):
    return dataclasses.replace(run, meta=dataclasses.replace(run.meta, **changes))


def test_fitted_values_hold_the_instrument_within_their_intervals(report):
    # Oracle: the instrument that made the run states N = 0.0003 deg/sqrt(h), B = 0.002
    # deg/h, K = 0; each lies within its fitted interval, and N's interval is a few per cent
    # wide (N is what 150 s dwells read best; B only at their long end, K hardly at all).
    assert report.stated("N") == 3e-4 and report.stated("B") == 2e-3 and report.stated("K") == 0
    for sym in ("N", "B", "K"):
        value, (lo, hi) = report.fitted(sym)
        assert lo <= report.stated(sym) <= hi, (sym, value, lo, hi)
        assert lo <= value <= hi
        assert report.verdict(sym) == "stated value within the interval"
    _, (lo, hi) = report.fitted("N")
    assert (hi - lo) / 3e-4 < 0.05
    _, (lo, hi) = report.fitted("B")
    assert hi < 2.5 * 2e-3          # the interval says something about B
    assert "built-in instrument 'default'" in report.stated_source


def test_dwells_are_the_north_finders_and_startup_dwells_stop_early(runs, report):
    # Oracle: 9000 s of 160 s periods hold 56 dwells of 150 samples and a last one of 40;
    # a dwell that starts before 3600 s enters the fit to a tenth of its length, a later one
    # to a quarter; the fit's taus stop at a quarter of a whole dwell (37.5 s -> 32 s).
    n = report.dwell_samples
    assert len(report.dwell_run) == 57 and set(report.dwell_run) == {0}
    assert np.all(n[:-1] == 150) and n[-1] == 40
    early = report.dwell_start_s < 3600.0
    assert report.n_startup_dwells == int(early.sum()) == 23
    assert np.allclose(report.dwell_fit_max_tau_s[early], STARTUP_TAU_FRACTION * n[early])
    assert np.allclose(report.dwell_fit_max_tau_s[~early], TAU_FRACTION * n[~early])
    assert report.noise.taus_s[-1] == 32.0
    assert "23 dwell(s) that start within 3600 s" in report.taus_note()
    # settle_s drops the same seconds as the north finder: 10 samples of every dwell
    settled = allan_of_runs(runs, settle_s=10.0, n_boot=20)
    assert np.all(settled.dwell_samples[:-1] == 140)


def test_a_missing_sample_splits_a_dwell(runs):
    # Oracle: a NaN in the middle of a dwell leaves two records where there was one.
    run = runs[0]
    gyro = np.array(run["gyro_dph"], dtype=float)
    gyro[4075] = np.nan                       # in the middle of the dwell from 4000 s
    holed = dataclasses.replace(run, columns={**run.columns, "gyro_dph": gyro})
    a = allan_of_runs([run], n_boot=20)
    b = allan_of_runs([holed], n_boot=20)
    assert len(b.dwell_run) == len(a.dwell_run) + 1
    assert b.dwell_samples.sum() == a.dwell_samples.sum() - 1


def test_json_round_trip_is_exact(report):
    # Oracle: to_dict -> JSON text -> from_dict gives back every field (arrays bitwise, NaN
    # where a dwell has no value).
    back = AllanReport.from_dict(json.loads(json.dumps(report.to_dict())))
    for f in dataclasses.fields(AllanReport):
        a, b = getattr(report, f.name), getattr(back, f.name)
        if isinstance(a, np.ndarray):
            assert np.array_equal(a, b, equal_nan=True), f.name
        elif f.name != "noise":
            assert a == b, f.name
    assert back.noise.arw_interval_deg_per_rth_h == report.noise.arw_interval_deg_per_rth_h
    assert back.noise.fit.arw_deg_per_rth_h == report.noise.fit.arw_deg_per_rth_h
    assert back.summary() == report.summary()


def test_figure_has_the_labelled_lines(report, tmp_path):
    # Oracle: the closed forms of IEEE Std 952 Annex C on the drawn lines (60 N / sqrt(tau),
    # 0.6643 B), every fitted and stated term labelled with value, unit (and the fitted with
    # its interval); the axes in units, log-log, one decade as long on both.
    fig = plot_allan(report)
    ax = fig.axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines() if not ln.get_label().startswith("_")}
    labels = list(lines)
    units = {"N": "deg/sqrt(h)", "B": "deg/h", "K": "deg/h/sqrt(h)"}
    for sym, unit in units.items():
        value, (lo, hi) = report.fitted(sym)
        fitted = [t for t in labels if t.startswith(f"fitted {sym} (")]
        assert len(fitted) == 1, labels
        assert f"= {value:.3g} {unit}" in fitted[0] and f"[{lo:.3g}, {hi:.3g}]" in fitted[0]
        assert "95 % interval" in fitted[0]
        stated = [t for t in labels if t.startswith(f"stated {sym} = ")]
        assert len(stated) == 1 and f"{report.stated(sym):.3g} {unit}" in stated[0]
        assert lines[stated[0]].get_linestyle() == "--"
        assert lines[fitted[0]].get_linestyle() == "-"
    n_line = lines[next(t for t in labels if t.startswith("stated N"))]
    tau, sigma = n_line.get_data()
    assert np.allclose(sigma, 60.0 * 3e-4 / np.sqrt(tau))
    b_line = lines[next(t for t in labels if t.startswith("fitted B"))]
    assert np.allclose(b_line.get_ydata(), BI_FLOOR_FACTOR * report.fitted("B")[0])
    assert "no line on a log axis" in next(t for t in labels if t.startswith("stated K"))
    assert any(t.startswith(f"{report.run_names[0]}: 34 dwells after 3600 s") for t in labels)
    assert ax.get_xscale() == ax.get_yscale() == "log"
    assert ax.get_xlabel() == "averaging time tau [s]" and "[deg/h]" in ax.get_ylabel()
    # no exaggeration: the decades are as long on both axes (the drawn box, in inches)
    box = ax.get_position()
    w_in, h_in = box.width * fig.get_figwidth(), box.height * fig.get_figheight()
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert w_in / math.log10(x1 / x0) == pytest.approx(h_in / math.log10(y1 / y0), rel=1e-6)
    path = allan_figure(report, tmp_path / "allan.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_stated_values_come_from_the_model_the_sidecar_or_the_default(runs):
    # Oracle: the source named in words, and the preset it names loaded.
    lumped = load_instrument("lumped")
    inst, src = stated_instrument([_with_meta(runs[0], instrument="lumped")])
    assert inst.name == "lumped" and "'lumped' the runs' sidecars name" in src
    inst, src = stated_instrument([_with_meta(runs[0], instrument="unit-07")])
    assert inst.name == "default" and "'unit-07', which is no built-in preset" in src
    inst, src = stated_instrument(runs, lumped)
    assert inst is lumped and src == "the model 'lumped'"
    with pytest.raises(InputError, match="different instruments"):
        stated_instrument([runs[0], _with_meta(runs[0], instrument="lumped")])


def test_stated_values_come_from_the_drawn_unit_beside_the_runs(tmp_path, runs):
    # Oracle: a unit file every sidecar names, beside the runs, is the instrument stated
    # (what nfs simulate writes: the unit as its variability drew it), loaded as written.
    lumped = dataclasses.replace(load_instrument("lumped"), name="lumped_unit_00")
    (tmp_path / "unit_00.toml").write_text(lumped.to_toml())
    beside = [dataclasses.replace(_with_meta(r, extra={"unit_file": "unit_00.toml"}),
                                  path=tmp_path / "r.csv") for r in runs]
    inst, src = stated_instrument(beside)
    assert inst.to_toml() == lumped.to_toml() and "unit_00.toml beside them" in src
    # a run that names none beside one that does, or a file that is not there: the
    # sidecar's preset as before
    mixed = [beside[0], dataclasses.replace(runs[0], path=tmp_path / "s.csv")]
    inst, src = stated_instrument(mixed)
    assert "unit_00.toml" not in src and "default" in src
    (tmp_path / "unit_00.toml").unlink()
    assert "unit_00.toml" not in stated_instrument(beside)[1]


def test_cli_writes_the_table_json_and_figure(tmp_path, cli, runs):
    # Oracle: exit 0, the table on stdout, allan.json readable by AllanReport.from_dict,
    # allan.png, and the folder's manifest.
    folder = tmp_path / "runs"
    write_run(runs[0], folder / "r17.csv")
    out = tmp_path / "allan"
    code, stdout, err = cli("allan", folder, "-o", out, "-q")
    assert code == 0, err
    assert "| N (angle random walk) |" in stdout and "stated value within the interval" in stdout
    assert "the 23 dwell(s) that start within 3600 s of power-on only up to a tenth" in stdout
    rep = AllanReport.from_dict(json.loads((out / "allan.json").read_text()))
    assert rep.run_names == ("r17",)
    assert (out / "allan.png").read_bytes()[:4] == b"\x89PNG"
    assert (out / "nfs-manifest.json").exists()


def test_cli_bad_path_and_model_are_one_line(tmp_path, cli, runs):
    code, out, err = cli("allan", tmp_path / "nowhere", "-o", tmp_path / "a")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "nowhere" in err
    assert not (tmp_path / "a").exists()
    write_run(runs[0], tmp_path / "runs" / "r17.csv")
    code, out, err = cli("allan", tmp_path / "runs", "--model", tmp_path / "no.toml", "-o",
                         tmp_path / "a")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "no.toml" in err
    assert not (tmp_path / "a").exists()
