"""Outputs of a parameter-level study (:mod:`nfs.studies.parameter_study`): the parameter table
(RMSE, MAE, R^2, residual variance of each calibrated parameter's model, with intervals), the
heading table by schedule, and Liang et al.'s figures beside them.

The paper set beside the table is Liang, Tao, Wang, Guo and Zhao, "System-Level Temperature
Compensation Method for the RLG-IMU Based on HHO-RVR", Journal of Sensors 2021, 6613574
(:data:`~nfs.report.reference.LIANG2021_RVR_OVER_LS_PCT`): their unit is a laser-gyro IMU, so
the comparison is of shape (does the RVR better the cubic, by about how much), not of digits.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from .drift_figures import plot_parameter_residuals, plot_parameters_vs_temperature, png_bytes
from ..scoring.intervals import json_number
from .cycle_report import intervals_csv, write_table_files
from .reference import LIANG2021_RVR_OVER_LS_PCT

__all__ = ["parameter_table_markdown", "parameter_table_json", "write_parameter_study"]

_METRICS = (("rmse", "RMSE"), ("mae", "MAE"), ("r2", "R^2"),
            ("residual_variance", "residual variance"))
_PAPER_LS, _PAPER_RVR = "LS", "HHO-RVR"


def _num(v: float) -> str:
    if not math.isfinite(v):
        return "-"
    return f"{v:.4g}"


def _cell(v: float, ci) -> str:
    if ci is None or not all(math.isfinite(c) for c in ci) or ci[0] == ci[1]:
        return _num(v)
    return f"{_num(v)} ({_num(ci[0])} .. {_num(ci[1])})"


def _gain_pct(study, parameter: str) -> float:
    """How much HHO-RVR lowers LS's RMSE on one parameter [%] (NaN without both rows)."""
    by = {r.method: r.values["rmse"] for r in study.parameters if r.parameter == parameter}
    if _PAPER_LS not in by or _PAPER_RVR not in by or not by[_PAPER_LS]:
        return math.nan
    return 100.0 * (1.0 - by[_PAPER_RVR] / by[_PAPER_LS])


def _notes(study) -> list[str]:
    n_tr = sum(len(c.t_end_s) for c in study.train)
    n_te = sum(len(c.t_end_s) for c in study.test)
    inputs = "; ".join(f"{desc} [{unit}] against {col}" for desc, unit, col in
                       study.described.values())
    return [
        f"Calibrated in every north-finding cycle: {n_tr} cycles of {len(study.train)} "
        f"training run(s) fit each model, {n_te} cycles of {len(study.test)} test run(s) "
        f"score it. Models: {inputs}.",
        "Parameter table: the test cycles' calibrated parameter minus the model's prediction "
        "from the cycle's mean temperature (Liang et al. 2021, equations (32)-(34)); "
        "constant: the training cycles' mean.",
        "Heading table: the biases known from each row (predicted from the cycle's own "
        "temperatures, known when its heading is output), solved with every dwell of the "
        "schedule, two positions 90 deg apart, and one; bias fitted: the multiposition fit; "
        "(samples): the gyro compensated sample by sample with the scenario's features, the "
        "accelerometers and scale factor by the constant. One position takes the sign of psi "
        "from the run's true heading, as from a compass.",
        f"{study.startup_stage} RMSE: the test cycles ending within "
        f"{study.scenario.northfind.startup_end_s:g} s of power-on"
        + (" (the chamber program moves the chamber during them)."
           if study.startup_stage != "start-up" else ".")
        + " No interval where one bootstrap block or fewer holds those cycles.",
        "A schedule of three or more positions cancels a constant bias error within a cycle, "
        "so every bias-known row equals the fitted one there; two positions 90 deg apart and "
        "one position do not, and show what the predicted biases are worth.",
        f"Intervals: 95 %, bias-corrected, from a bootstrap of blocks of {study.block_cycles} "
        f"consecutive test cycles ({study.n_boot} replicates, every row with the same draws); "
        "versus best: the paired difference to the schedule's best row (tie: its interval "
        "holds 0).",
    ]


def _shape(study) -> list[str]:
    params = list(dict.fromkeys(r.parameter for r in study.parameters))
    gains = {p: _gain_pct(study, p) for p in params}
    if not any(math.isfinite(g) for g in gains.values()):
        return []
    paper = LIANG2021_RVR_OVER_LS_PCT
    text = ", ".join(f"{p} {g:+.1f} %" for p, g in gains.items() if math.isfinite(g))
    return [f"Shape beside Liang et al. 2021: HHO-RVR betters the cubic LS there on every "
            f"parameter, on average by {paper['rmse']:.2f} % in RMSE, {paper['mae']:.2f} % in "
            f"MAE, {paper['r2']:.2f} % in R^2 and {paper['residual_variance']:.2f} % in the "
            f"residual variance; here (RMSE): {text}. Their unit is a laser-gyro IMU, ours a "
            "FOG north finder: compare shapes, not digits."]


def parameter_table_markdown(study) -> str:
    """The parameter table and the heading table as Markdown, with the notes."""
    head = ["parameter", "model"] + [h for _, h in _METRICS]
    lines = ["| " + " | ".join(head) + " |", "|---|---|" + "---:|" * len(_METRICS)]
    for r in study.parameters:
        desc, unit, _ = study.described[r.parameter]
        lines.append(f"| {desc} [{unit}] | {r.method} | " + " | ".join(
            _cell(r.values[k], r.intervals.get(k)) for k, _ in _METRICS) + " |")
    heads = ["| schedule | positions [deg] | biases from | heading RMSE [deg] | "
             f"{study.startup_stage} RMSE [deg] | versus best |", "|---|---|---|---:|---:|---|"]
    for h in study.headings:
        heads.append(f"| {h.schedule} | {', '.join(f'{v:g}' for v in h.positions_deg)} | "
                     f"{h.method} | {_cell(h.rmse_deg, h.interval)} | "
                     f"{_cell(h.startup_rmse_deg, h.startup_interval)} | {h.versus_best} |")
    notes = _notes(study) + _shape(study)
    return ("\n".join(lines) + "\n\n" + "\n".join(heads) + "\n\n"
            + "\n".join(f"- {n}" for n in notes) + "\n")


def parameter_table_json(study, title: str = "", provenance: dict | None = None) -> str:
    """Every parameter row (``rmse``, ``mae``, ``r2``, ``residual_variance``, each with
    ``*_ci``), every heading row, the notes and Liang et al.'s average gains."""
    params = []
    for r in study.parameters:
        row = {"parameter": r.parameter, "unit": study.described[r.parameter][1],
               "thermometer": study.described[r.parameter][2], "method": r.method}
        for k, _ in _METRICS:
            row[k] = json_number(r.values[k])
            row[f"{k}_ci"] = [json_number(v) for v in r.intervals.get(k, (math.nan, math.nan))]
        params.append(row)
    heads = [{"schedule": h.schedule, "positions_deg": list(h.positions_deg),
              "method": h.method, "heading_rmse_deg": json_number(h.rmse_deg),
              "heading_rmse_deg_ci": [json_number(v) for v in h.interval],
              "startup_rmse_deg": json_number(h.startup_rmse_deg),
              "startup_rmse_deg_ci": [json_number(v) for v in h.startup_interval],
              "versus_best": h.versus_best} for h in study.headings]
    doc = {"title": title, "scenario": study.scenario.name, "protocol": "parameters",
           "n_boot": study.n_boot, "startup_stage": study.startup_stage,
           "parameters": params, "headings": heads,
           "published": "Liang, Tao, Wang, Guo and Zhao, Journal of Sensors 2021, 6613574, "
                        "section 4.2: HHO-RVR over LS, average over 15 parameters [%]",
           "published_rvr_over_ls_pct": dict(LIANG2021_RVR_OVER_LS_PCT),
           "provenance": provenance,
           "notes": _notes(study) + _shape(study)}
    return json.dumps(doc, indent=2) + "\n"


def write_parameter_study(study, out_dir, *, json_path=None, title: str = "",
                          provenance: dict | None = None) -> list[Path]:
    """Write parameter_table.md, parameter_table.csv, heading_by_schedule.csv,
    parameter_table.json, the figures parameters_vs_temperature.png and
    parameter_residual_vs_time.png (:mod:`nfs.report.drift_figures`) and report.md into
    ``out_dir`` (and the JSON also to ``json_path``), each atomically.  Returns the paths
    written."""
    md = parameter_table_markdown(study)
    js = parameter_table_json(study, title, provenance)
    doc = json.loads(js)
    figures = {
        "parameters_vs_temperature.png": png_bytes(plot_parameters_vs_temperature(study)),
        "parameter_residual_vs_time.png": png_bytes(plot_parameter_residuals(study))}
    report = (f"# {title or 'Parameter-level compensation'}\n\n" + md + "\n"
              "![each cycle's calibrated parameters against temperature, with the models]"
              "(parameters_vs_temperature.png)\n\n"
              "![calibrated minus predicted against time, before and after compensation]"
              "(parameter_residual_vs_time.png)\n")
    return write_table_files(out_dir, {
        "parameter_table.md": md,
        "parameter_table.csv": intervals_csv(doc["parameters"]),
        "heading_by_schedule.csv": intervals_csv(doc["headings"], skip=("positions_deg",)),
        "parameter_table.json": js, **figures, "report.md": report}, js, json_path)
