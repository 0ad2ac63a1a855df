"""nfs.report.design_report: the designed run on disk, and its scenario run by ``nfs simulate``.

A small design, built cheaply: two rivals without fits (the default instrument and the same
with a larger turn-on transient), two one-hour runs of the nominal default scenario, a grid of
two start temperatures and one power cycle early in the run (event_s = 600 s, so that a power
cycle fits in the hour and, separating more at the same cost, is proposed), no parameter
draws.  Oracles: the files written, the keys of design.json, the scenario read back by
nfs.config.scenario.load_scenario (its power-off spans are the design's) and simulated.
"""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from nfs.config.scenario import load_scenario
from nfs.fit import set_params
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.io.measurement import read_runs
from nfs.ranges import RangeWarning
from nfs.report.design_report import scenario_toml, to_markdown, write_design
from nfs.rivals.models import Rival
from nfs.design.search import design_experiment
from nfs.design.space import Space, base_conditions


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    inst = load_instrument("default")
    big = set_params(inst, {"effects.turn_on_transient.a": 0.05})
    sc = load_scenario().nominal()
    conds = [dataclasses.replace(c, duration_s=3600.0) for c in sc.conditions()[:2]]
    runs = [simulate_run(inst, c).run for c in conds]
    rivals = [Rival("model", "the model as given", inst, None),
              Rival("turn_on_transient", "a turn-on transient of 0.05 deg/h", big, None)]
    space = Space(start_temperatures_c=tuple(r.meta.start_temperature_c for r in runs),
                  power_off_s=(60.0,), cycles=(1,), ramps_k=(), max_duration_s=3600.0,
                  min_duration_s=1280.0, event_s=600.0)
    design = design_experiment(rivals, runs, base_conditions(runs), space, n_draws=0)
    root = tmp_path_factory.mktemp("design")
    model_path = root / "model.toml"
    text = inst.to_toml()
    assert text.startswith('name = "default"\n')
    # named anew: a file calling itself "default" (the built-in preset's name) warns
    model_path.write_text(text.replace('name = "default"', 'name = "designed_model"', 1),
                          encoding="utf-8")
    out = root / "out"
    paths = write_design(design, out, runs, model_path)
    return dict(inst=inst, runs=runs, design=design, out=out, paths=paths,
                model_path=model_path, root=root, space=space)


def test_the_design_is_a_power_cycle(made):
    d = made["design"]
    e = d.experiment
    assert e.event == "power_off"
    assert e.duration_s <= made["space"].max_duration_s
    assert e.event_end_s < e.duration_s
    assert d.open_pairs == ((0, 1),)
    assert set(d.proposed) == set(d.current) == {(0, 1)}
    assert d.proposed[(0, 1)].sigma > 0.0 and d.current[(0, 1)].sigma > 0.0


def test_the_four_files(made):
    out = made["out"]
    names = {p.name for p in made["paths"]}
    assert names == {"scenario.toml", "report.md", "design.png", "design.json"}
    for n in names:
        assert (out / n).is_file() and (out / n).stat().st_size > 0
    assert (out / "design.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_design_json(made):
    d = made["design"]
    data = json.loads((made["out"] / "design.json").read_text(encoding="utf-8"))
    for key in ("rivals", "current_separation", "proposed_separation", "hours",
                "open_pairs", "experiment", "verdict", "trials", "noise_factors"):
        assert key in data, key
    assert [r["label"] for r in data["rivals"]] == ["model", "turn_on_transient"]
    pair = "model vs turn_on_transient"
    assert data["open_pairs"] == [pair]
    assert data["current_separation"][pair]["sigma"] == pytest.approx(d.current[(0, 1)].sigma)
    assert data["proposed_separation"][pair]["sigma"] == pytest.approx(
        d.proposed[(0, 1)].sigma)
    assert data["hours"] == pytest.approx(d.experiment.hours)
    assert data["hours"] == pytest.approx(d.experiment.soak_h
                                          + d.experiment.duration_s / 3600.0)
    assert data["experiment"]["event"] == "power_off"
    assert len(data["trials"]) == len(d.trials)


def test_scenario_reads_back_with_the_designs_power_cycles(made):
    d, runs = made["design"], made["runs"]
    e = d.experiment
    # a one-hour design's stages (start-up to 800 s, stable from there) are shorter than
    # usual: a warning for each, not an error
    with pytest.warns(RangeWarning) as seen:
        sc = load_scenario(made["out"] / "scenario.toml")
    assert sorted(re.search(r"scenario\.toml, key '([^']+)': \d+ s is unusual",
                            str(w.message))[1] for w in seen) == \
        ["northfind.stable_start_s", "northfind.startup_end_s"]
    [c] = sc.conditions()
    want = e.conditions(base_conditions(runs)).power_off_s
    assert len(want) == e.cycles == 1
    np.testing.assert_allclose(c.power_off_s, want)
    np.testing.assert_allclose(c.power_off_s, [(e.event_s, e.event_s + e.power_off_s)])
    assert c.start_temperature_c == e.start_temperature_c
    assert c.duration_s == pytest.approx(e.duration_s)
    m = runs[0].meta
    assert c.schedule.positions_deg == tuple(m.positions_deg)
    # the schedule of the runs taken, with the dwell the design may have changed
    assert c.schedule.dwell_s == (e.dwell_s or m.dwell_s) and c.schedule.move_s == m.move_s
    assert c.latitude_deg == m.latitude_deg and c.true_heading_deg == m.true_heading_deg
    assert sc.instrument.name == "designed_model"
    [tot] = [x for x in sc.instrument.effects if x.label == "turn_on_transient"]
    assert tot.params["a"] == pytest.approx(0.008)
    # its text, written again in another folder, names the model relative to that folder
    text = scenario_toml(d, runs, made["model_path"], made["root"])
    assert 'instrument = "model.toml"' in text


def test_nfs_simulate_runs_the_scenario(made, cli):
    d = made["design"]
    sim = made["root"] / "sim"
    code, out, err = cli("simulate", made["out"] / "scenario.toml", "-o", sim, "-q")
    assert code == 0, err
    [run] = read_runs(sim)
    assert "powered" in run.columns
    t = np.asarray(run["time_s"], dtype=float)
    powered = np.asarray(run.columns["powered"], dtype=float) > 0.5
    e = d.experiment
    off = (t >= e.event_s + 1.0) & (t < e.event_s + e.power_off_s - 1.0)
    assert off.any() and not powered[off].any()
    assert powered[t < e.event_s - 1.0].all()
    assert powered[t > e.event_s + e.power_off_s + 1.0].all()
    assert t[-1] == pytest.approx(e.duration_s - 1.0 / run.meta.sample_rate_hz)


def test_report_md_has_the_verdict(made):
    d = made["design"]
    text = (made["out"] / "report.md").read_text(encoding="utf-8")
    assert d.verdict in text
    assert text == to_markdown(d)
    assert "model vs turn_on_transient" in text
    assert d.experiment.describe() in text
