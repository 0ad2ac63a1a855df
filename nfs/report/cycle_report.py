"""Outputs of a temperature-cycling study (:mod:`nfs.studies.cycle_study`): the drift table with
its intervals, the ramps separately, and the paper's figures beside ours.

The paper set beside the table is Tao, Li, Zheng, Wu and Fu, "High Precision Compensation for
a Total Reflection Prism Laser Gyro Bias in Consideration of High Frequency Oscillator
Voltage", Sensors 19(13), 2986 (2019) (:data:`~nfs.report.reference.TAO2019_BIAS_STABILITY`):
its gyro is not ours, so the comparison is of shape (every method improves the bias
stability, by how much, which wins), not of digits.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

from ..io.atomic import atomic_write_bytes, atomic_write_text
from .drift_figures import plot_drift_vs_temperature, plot_residual_vs_time, png_bytes
from ..scoring.intervals import json_number
from ..scoring.heading_table import NOT_APPLICABLE
from .reference import CHENG2015_TABLE2_MSD, TAO2019_BIAS_STABILITY

__all__ = ["cycle_table_markdown", "cycle_table_json", "write_cycle_study", "intervals_csv",
           "write_table_files"]

_METRICS = (("mae_dph", "MAE [deg/h]", 4), ("std_dph", "STD [deg/h]", 4),
            ("rmse_dph", "RMSE [deg/h]", 4), ("bias_stability_dph", "bias stability [deg/h]", 5),
            ("improvement_pct", "improvement [%]", 1))
_RAMPS = (("up_rmse_dph", "up-ramp RMSE [deg/h]"), ("up_mean_dph", "up-ramp mean [deg/h]"),
          ("down_rmse_dph", "down-ramp RMSE [deg/h]"),
          ("down_mean_dph", "down-ramp mean [deg/h]"))


def _cell(v: float, ci, digits: int) -> str:
    if not math.isfinite(v):
        return NOT_APPLICABLE
    if ci is None or not all(math.isfinite(c) for c in ci) or ci[0] == ci[1]:
        return f"{v:.{digits}f}"
    return f"{v:.{digits}f} ({ci[0]:.{digits}f} .. {ci[1]:.{digits}f})"


def _runs(study) -> bool:
    """True for a drift table over whole runs (no cycles of a program)."""
    return not study.spans_s


def _notes(study) -> list[str]:
    s = study.settings
    if _runs(study):
        split = (f"{len(study.train_runs)} training run(s) train every method, "
                 f"{len(study.test_runs)} test run(s) are scored (the scenario's train/test "
                 "split of units and repeats).")
    else:
        spans = ", ".join(f"{a / 3600:.2f}-{b / 3600:.2f} h" for a, b in study.spans_s)
        split = (f"Cycles of the chamber program (from power-on): {spans}; cycle 1 of "
                 f"{len(study.train_runs)} run(s) trains every method, the other "
                 f"{len(study.test_runs)} cycle(s) are scored.")
    part = "run" if _runs(study) else "cycle"
    return [
        split,
        f"Features {', '.join(study.feature_names)} in {s.features_mode} mode; drift by wavelet "
        f"separation (cutoff {s.cutoff_period_s:g} s); training samples every "
        f"{s.decimate_s:g} s.",
        "MAE, STD, RMSE: the separated drift minus the prediction at every trusted sample of the "
        f"test {part}s; bias stability: standard deviation of the 100 s means of the gyro output "
        "minus Earth rate minus prediction (Tao et al. 2019, section 4.1: data at 100 s); "
        "improvement: 1 - bias stability / the uncompensated row's.",
        f"uncompensated: the mean bias of the training {part}s subtracted (a constant "
        f"calibration). Intervals: 95 %, bias-corrected, from a block bootstrap of the test "
        f"{part}s "
        f"({study.n_boot} replicates, 30 min blocks, every row with the same draws).",
        "Ramps: residuals where the chamber program rises (up) or falls (down) faster than "
        "0.006 C/min (the controller's cycling and wander are no ramp); opposite signed "
        "means on the two are thermal hysteresis, a rate term the model lacks.",
        f"heading RMSE: every north-finding cycle of the test {part}s, compensated [deg].",
    ]


def _paper(method: str) -> tuple[float, float] | None:
    return TAO2019_BIAS_STABILITY.get(method)


def cycle_table_markdown(study) -> str:
    """The drift table and the ramp table as Markdown, with the notes and the paper's
    figures."""
    head = ["method"] + [h for _, h, _ in _METRICS] + ["heading RMSE [deg]",
                                                     "paper: bias stability, improvement"]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for r in study.rows:
        cells = [_cell(r.values[k], r.intervals.get(k), d) for k, _, d in _METRICS]
        pub = None if _runs(study) else _paper(r.method)
        cells += [_cell(r.heading_rmse_deg, None, 4),
                  f"{pub[0]:.5f} deg/h, {pub[1]:.2f} %" if pub else ""]
        lines.append(f"| {r.method} | " + " | ".join(cells) + " |")
    ramp = _ramp_table(study)
    best = min((r for r in study.rows[1:]), key=lambda r: r.values["bias_stability_dph"],
               default=None)
    shape = []
    if _runs(study):
        msd = _msd_table(study)
        return ("\n".join(lines) + "\n\n" + "\n".join(ramp) + "\n\n" + msd + "\n"
                + "\n".join(f"- {n}" for n in _notes(study) + _cheng_shape(study)) + "\n")
    if best is not None:
        improved = [r.method for r in study.rows[1:]
                    if r.intervals["improvement_pct"][0] > 0]
        paper = {m: v[1] for m, v in TAO2019_BIAS_STABILITY.items() if m != study.rows[0].method}
        top = max(paper, key=paper.get)
        shape = [f"Shape beside Tao et al. 2019: every method there improves the bias "
                 f"stability ({min(paper.values()):.1f}-{paper[top]:.1f} %, {top} best); "
                 f"here {len(improved)} of "
                 f"{len(study.rows) - 1} improve it beyond the uncertainty "
                 f"({', '.join(improved) or 'none'}), {best.method} best "
                 f"({best.values['improvement_pct']:.1f} %). Their gyro is a laser gyro, ours "
                 "a FOG: compare shapes, not digits."]
    notes = _notes(study) + shape
    return ("\n".join(lines) + "\n\n" + "\n".join(ramp) + "\n\n"
            + "\n".join(f"- {n}" for n in notes) + "\n")


def _ramp_table(study) -> list[str]:
    """The up- and down-ramp residuals as Markdown lines; a side the chamber never takes in
    the test parts is left out, and a line says so."""
    moves = {"up": "rises", "down": "falls"}
    missing = [side for side in moves
               if not any(math.isfinite(r.values[f"{side}_rmse_dph"]) for r in study.rows)]
    part = "run" if _runs(study) else "cycle"
    why = (f"No {' or '.join(missing)}-ramp residual: the chamber program never "
           f"{' or '.join(moves[m] for m in missing)} faster than 0.006 C/min in the test "
           f"{part}s.") if missing else ""
    cols = [(k, h) for k, h in _RAMPS if k.split("_")[0] not in missing]
    if not cols:
        return [why]
    lines = ["| method | " + " | ".join(h for _, h in cols) + " |", "|---|" + "---:|" * len(cols)]
    for r in study.rows:
        lines.append(f"| {r.method} | " + " | ".join(
            _cell(r.values[k], r.intervals.get(k), 4) for k, _ in cols) + " |")
    return lines + ([""] + [why] if why else [])


def _msd_table(study) -> str:
    """Mean square deviation of every test run by row (Cheng et al. 2015, Table 2), with the
    paper's before/after figures beside the first five runs."""
    head = ["test run"] + [f"MSD {r.method} [(deg/h)^2]" for r in study.rows] + \
        ["paper: before, after"]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for i, run in enumerate(study.test_runs):
        pub = CHENG2015_TABLE2_MSD[i] if i < len(CHENG2015_TABLE2_MSD) else None
        lines.append(f"| {run.name} | " + " | ".join(_g(r.msd_by_part[i])
                                                      for r in study.rows)
                     + (f" | {pub[0]:.3g}, {pub[1]:.3g} |" if pub else " | |"))
    return "\n".join(lines) + "\n"


def _g(v: float) -> str:
    return f"{v:.3g}" if math.isfinite(v) else NOT_APPLICABLE


def _cheng_shape(study) -> list[str]:
    before = study.rows[0].msd_by_part
    out = []
    for r in study.rows[1:]:
        ratios = [b / a for a, b in zip(r.msd_by_part, before) if a > 0]
        if ratios:
            out.append(f"{r.method}: MSD {min(ratios):.1f}x to {max(ratios):.1f}x smaller "
                       "than uncompensated over the test runs")
    pub = [b / a for b, a in CHENG2015_TABLE2_MSD]
    return [f"Shape beside Cheng et al. 2015 (Table 2: the RBF network on T, dT, T x dT makes "
            f"the MSD {min(pub):.0f}x to {max(pub):.0f}x smaller on five test runs; their "
            "gyro is not ours, compare shapes, not digits): " + "; ".join(out) + ". The MSD "
            "is of the samples at the run's rate, so the gyro's white noise (angle random "
            "walk), which no model removes, sets its floor."]


def cycle_table_json(study, title: str = "", provenance: dict | None = None) -> str:
    """Every row with ``mae_dph``, ``std_dph``, ``rmse_dph``, ``bias_stability_dph``,
    ``improvement_pct``, each with ``*_ci`` [low, high], the ramp statistics, the heading
    RMSE and the paper's figure for the same method (null when it has none)."""
    rows = []
    for r in study.rows:
        row = {"method": r.method}
        for k in [m for m, _, _ in _METRICS] + [m for m, _ in _RAMPS]:
            row[k] = json_number(r.values[k])
            lo, hi = r.intervals.get(k, (math.nan, math.nan))
            row[f"{k}_ci"] = [json_number(lo), json_number(hi)]
        row["heading_rmse_deg"] = json_number(r.heading_rmse_deg)
        row["msd_by_part_dph2"] = [json_number(v) for v in r.msd_by_part]
        pub = None if _runs(study) else _paper(r.method)
        row["published_bias_stability_dph"] = pub[0] if pub else None
        row["published_improvement_pct"] = pub[1] if pub else None
        rows.append(row)
    doc = {"title": title, "scenario": study.scenario.name,
           "protocol": "runs" if _runs(study) else "cycles",
           "parts": [r.name for r in study.test_runs],
           "cycles_s": [list(sp) for sp in study.spans_s], "n_boot": study.n_boot,
           "published": ("Cheng, Qi, Chen and Landry, Sensors 15(5), 11189 (2015), Table 2"
                         if _runs(study) else
                         "Tao, Li, Zheng, Wu and Fu, Sensors 19(13), 2986 (2019), Tables 2-5"),
           "rows": rows, "provenance": provenance,
           "notes": _notes(study)}
    return json.dumps(doc, indent=2) + "\n"


def intervals_csv(rows: list[dict], skip=()) -> str:
    """CSV of JSON rows whose ``*_ci`` [low, high] pairs become ``*_ci_low`` and
    ``*_ci_high`` columns (null, nothing applies, as ``-``, as in the Markdown); the keys in
    ``skip`` (lists) left out."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    keys = [k for k in rows[0] if not k.endswith("_ci") and k not in skip]
    cis = [k for k in rows[0] if k.endswith("_ci")]
    w.writerow(keys + [f"{k}_{e}" for k in cis for e in ("low", "high")])
    for r in rows:
        w.writerow([(NOT_APPLICABLE if r[k] is None else r[k]) for k in keys]
                   + [(NOT_APPLICABLE if v is None else v) for k in cis for v in r[k]])
    return buf.getvalue()


def write_table_files(out_dir, files: dict[str, str | bytes], js: str,
                      json_path=None) -> list[Path]:
    """Write ``files`` {name: text, or bytes of a figure} into ``out_dir`` (made if missing)
    and the JSON ``js`` also to ``json_path``, each atomically.  Returns the paths written,
    in order."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / name for name in files]
    for path, data in zip(paths, files.values()):
        if isinstance(data, bytes):
            atomic_write_bytes(path, data)
        else:
            atomic_write_text(path, data)
    if json_path is not None:
        atomic_write_text(json_path, js)
        paths.append(Path(json_path))
    return paths


def write_cycle_study(study, out_dir, *, json_path=None, title: str = "",
                      provenance: dict | None = None) -> list[Path]:
    """Write drift_table.md, .csv, .json, the figures drift_vs_temperature.png and
    residual_vs_time.png (:mod:`nfs.report.drift_figures`) and report.md into ``out_dir``
    (and the JSON also to ``json_path``), each atomically.  Returns the paths written."""
    md = cycle_table_markdown(study)
    js = cycle_table_json(study, title, provenance)
    figures = {"drift_vs_temperature.png": png_bytes(plot_drift_vs_temperature(study)),
               "residual_vs_time.png": png_bytes(plot_residual_vs_time(study))}
    report = (f"# {title or 'Drift table of a temperature cycle'}\n\n" + md + "\n"
              "![drift against temperature, before and after compensation]"
              "(drift_vs_temperature.png)\n\n"
              "![100 s means of the compensated bias against time, before and after "
              "compensation](residual_vs_time.png)\n")
    return write_table_files(out_dir, {
        "drift_table.md": md,
        "drift_table.csv": intervals_csv(json.loads(js)["rows"], skip=("msd_by_part_dph2",)),
        "drift_table.json": js, **figures, "report.md": report}, js, json_path)
