"""Time to spec in the table's report: medians by start temperature, against the per-run
closed form, and written into report.md beside the figure of error against time."""

import math
from types import SimpleNamespace

import numpy as np

from nfs.northfind import run_time_to_spec_s
from nfs.report.startup import time_to_spec_table

T = 640.0 * np.arange(1, 11)


def _run(a, tau):
    """A run whose heading error decays as a exp(-t / tau)."""
    return SimpleNamespace(t_end_s=T, error_deg=a * np.exp(-T / tau))


def test_medians_by_start_temperature_are_the_closed_form():
    # three start-ups at each of two T0: error a exp(-t/tau) is within s from the first
    # cycle output at or after tau ln(a / s)
    s, tau = 0.01, 1800.0
    amps = [[0.02, 0.04, 0.08], [0.005, 0.012, 0.5]]
    nf = [_run(a, tau) for row in amps for a in row]
    result = SimpleNamespace(scenario=SimpleNamespace(start_temperatures_c=(-30.0, 40.0),
                                                      repeats=3),
                             runs_at=lambda i: [3 * i, 3 * i + 1, 3 * i + 2])
    table = time_to_spec_table(result, {"before": nf}, s, window=2)

    def first(a):
        return T[T >= tau * math.log(a / s)][0] if a > s else T[0]

    assert table.every_s["before"] == (first(0.04), first(0.012))     # the middle start-up
    assert table.rolling_s["before"][0] == float(np.median(
        [run_time_to_spec_s(T, r.error_deg, s, 2)[1] for r in nf[:3]]))
    # 0.5 exp(-6400/1800) = 0.014 > s at the last cycle: that start-up never settles
    assert run_time_to_spec_s(T, nf[5].error_deg, s)[0] == math.inf
    md = table.to_markdown()
    assert "| before | " in md and "-30 C" in md and f"{first(0.04) / 60:.1f}" in md


def test_report_has_time_to_spec_and_error_figure(tmp_path, scenario_text):
    from nfs.studies.startup_study import run_study
    from nfs.compensate.settings import CompensationSettings
    from nfs.config.scenario import load_scenario
    from nfs.report.compensation import write_study
    p = tmp_path / "s.toml"
    p.write_text(scenario_text("tts", 3, (-20.0, 40.0), 3900.0,
                               extra="[northfind]\nspec_deg = 0.015\n"))
    sc = load_scenario(p)
    study = run_study(sc, CompensationSettings(methods=("ls",), train_seed=9, test_repeats=2,
                                               n_jobs=1))
    paths = write_study(study, tmp_path / "out", title="t")
    names = {q.name for q in paths}
    assert {"time_to_spec.md", "error_vs_time.png", "report.md"} <= names
    assert (tmp_path / "out" / "error_vs_time.png").stat().st_size > 10000
    report = (tmp_path / "out" / "report.md").read_text()
    assert "## Time to spec" in report and "(0.015 deg)" in report
    # the table's cell is the median of the per-run closed form
    nf = study.results["LS"].northfind
    per_run = [run_time_to_spec_s(nf[k].t_end_s, nf[k].error_deg, 0.015)[0]
               for k in study.test.runs_at(0)]
    med = float(np.median(per_run))
    cell = "never" if math.isinf(med) else f"{med / 60:.1f}"
    section = report[report.index("## Time to spec"):].splitlines()
    row = next(line for line in section if line.startswith("| LS | "))
    assert row.split("|")[2].strip() == cell
