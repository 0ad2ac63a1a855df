"""Outputs of the compensation study: tables, figures, and the comparison with the FOG start-up paper."""

from __future__ import annotations

import io
import json
import math
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..compensate.modes import FEATURE_MODE_NOTES
from ..denoise import separate_drift
from ..io.atomic import atomic_write_bytes, atomic_write_text
from ..scoring.intervals import json_number
from .reference import (SEED004_TABLE1_SVR, SEED004_TABLE2_DRIFT_DPH,
                        SEED004_TABLE3_HEADING_RMSE_DEG, SEED004_TEMPERATURES_C)
from .startup import plot_error_vs_time, time_to_spec_table
from ..scoring.heading_table import NOT_APPLICABLE, UNCOMPENSATED_ROWS, HeadingTable
from .table_files import write_table

__all__ = ["ShapeCheck", "shape_checks", "paper_comparison_markdown", "drift_table_markdown",
           "write_study", "plot_drift_vs_compensated"]

#: The SVR family of the table (the rows the FOG start-up paper says beat BP).
SVR_FAMILY = ("SVR (grid)", "PSO-SVR", "GWO-SVR", "SSA-SVR")


@dataclass(frozen=True)
class ShapeCheck:
    """One expected property of the heading-RMSE table, checked."""

    name: str
    """What is expected."""
    passed: bool
    """Whether the table has it."""
    detail: str
    """The figures behind the verdict."""


def shape_checks(table: HeadingTable) -> list[ShapeCheck]:
    """The shape the FOG start-up paper's Table 3 leads us to expect, checked on our table.

    - SSA-SVR's mean at most 0.6x the uncompensated mean (the FOG start-up paper: 0.0101 / 0.0209 =
    0.48),
      and, when the table has its paired comparisons, below it beyond the uncertainty;
    - the SVR family ahead of BP: no SVR row behind BP beyond the uncertainty when the table
      has its paired comparisons (a crossing of the means inside the noise is a tie), else
      each SVR row's mean below BP's;
    - every compensated mean above the white-noise floor;
    - no compensated row above ``before`` at any start temperature (a compensator that
      makes some start-up worse is not safe to switch on there);
    - beyond the paper: the best method's start-up RMSE within 1.3x of the stable-stage RMSE
      at every start temperature (the paper misses this at 28 C).
    """
    names = [r.method for r in table.rows]
    comp = [r for r in table.rows if r.method not in UNCOMPENSATED_ROWS]
    out = []
    before = table.row("before").mean_deg
    if "SSA-SVR" in names:
        ssa = table.row("SSA-SVR").mean_deg
        out.append(ShapeCheck("SSA-SVR mean <= 0.6 x before", ssa <= 0.6 * before,
                              f"{ssa:.4f} / {before:.4f} = {ssa / before:.2f}"))
        c = table.comparison("SSA-SVR", "before")
        if c is not None:
            out.append(ShapeCheck("SSA-SVR below before beyond the uncertainty",
                                  c.distinguishable and c.difference_deg < 0, c.sentence()))
    if "BP" in names:
        bp = table.row("BP").mean_deg
        fam = [table.row(n) for n in SVR_FAMILY if n in names]
        if fam:
            worst = max(r.mean_deg for r in fam)
            detail = f"worst SVR-family mean {worst:.4f} vs BP {bp:.4f}"
            compared = [c for c in (table.comparison("BP", r.method) for r in fam)
                        if c is not None]
            if compared:
                # where the table has its paired comparisons, a crossing of the means the
                # noise cannot support is a tie, not BP ahead
                beaten = [c for c in compared if c.distinguishable and c.difference_deg < 0]
                ahead = not beaten
                detail += ("; BP ahead beyond the uncertainty: "
                           + "; ".join(c.sentence() for c in beaten) if beaten else
                           "; no SVR row behind BP beyond the uncertainty")
            else:
                ahead = worst < bp
            out.append(ShapeCheck("SVR family ahead of BP", ahead, detail))
    if "floor" in names and comp:
        floor = table.row("floor").mean_deg
        lowest = min(comp, key=lambda r: r.mean_deg)
        out.append(ShapeCheck("every compensated mean above the floor",
                              lowest.mean_deg > floor,
                              f"lowest {lowest.method} {lowest.mean_deg:.4f} vs floor "
                              f"{floor:.4f}"))
    if comp:
        worse = [f"{r.method} at {t:g} C ({v:.4f} vs {b:.4f})" for r in comp
                 for t, v, b in zip(table.temperatures_c, r.rmse_deg,
                                    table.row("before").rmse_deg) if v > b]
        out.append(ShapeCheck("no compensated row worse than before at any T0", not worse,
                              "; ".join(worse) if worse else "every row at or below before"))
    if "stable" in names and comp:
        best = min(comp, key=lambda r: r.mean_deg)
        stable = np.asarray(table.row("stable").rmse_deg)
        ratio = np.asarray(best.rmse_deg) / stable
        out.append(ShapeCheck(
            f"best method ({best.method}) within 1.3x of the stable stage at every T0",
            bool(np.all(ratio <= 1.3)),
            "ratios " + ", ".join(f"{t:g} C: {r:.2f}" for t, r in
                                  zip(table.temperatures_c, ratio))))
    return out


def paper_comparison_markdown(table: HeadingTable) -> str:
    """Our table beside the FOG start-up paper's Table 3, and the shape checks."""
    lines = ["## Beside the FOG start-up paper (Table 3)", "",
             "The FOG start-up paper's instrument is not ours: compare the shape (which methods win, by about "
             "how much, how the error spreads over start temperatures), not the digits.", "",
             "| method | source | " + " | ".join(f"{t:g}" for t in SEED004_TEMPERATURES_C)
             + " | mean |", "|---|---|" + "---:|" * (len(SEED004_TEMPERATURES_C) + 1)]
    ours = {r.method: r for r in table.rows}
    same_t = tuple(table.temperatures_c) == SEED004_TEMPERATURES_C
    for method, ref in SEED004_TABLE3_HEADING_RMSE_DEG.items():
        lines.append(f"| {method} | the FOG start-up paper | " + " | ".join(f"{v:.4f}" for v in ref) + " |")
        if method in ours and same_t:
            r = ours[method]
            lines.append(f"| {method} | ours | " + " | ".join(
                _f(v) for v in (*r.rmse_deg, r.mean_deg)) + " |")
    ref_ratio = SEED004_TABLE3_HEADING_RMSE_DEG["SSA-SVR"][-1] / \
        SEED004_TABLE3_HEADING_RMSE_DEG["before"][-1]
    lines += ["", f"The FOG start-up paper: SSA-SVR / before = {ref_ratio:.2f}; SSA-SVR C = "
              f"{SEED004_TABLE1_SVR['C']}, sigma = {SEED004_TABLE1_SVR['sigma']} (Table 1).", "",
              "### Expected shape", ""]
    for c in shape_checks(table):
        lines.append(f"- [{'x' if c.passed else ' '}] {c.name}: {c.detail}")
    return "\n".join(lines) + "\n"


def _f(v: float) -> str:
    return NOT_APPLICABLE if not math.isfinite(v) else f"{v:.4f}"


def drift_table_markdown(rows, features_mode: str | None = None) -> str:
    """Drift residual MAE and STD by method, beside the FOG start-up paper's Table 2.

    Parameters
    ----------
    rows : sequence of DriftRow
        The uncompensated row, then one per method.
    features_mode : str, optional
        The features mode of the compensated rows, stated under the table.

    Returns
    -------
    str
        Markdown.
    """
    lines = ["| method | MAE [deg/h] | STD [deg/h] |", "|---|---:|---:|"]
    for r in rows:
        lines.append(f"| {r.method} | {_f(r.mae_dph)} | {_f(r.std_dph)} |")
    if any(not math.isfinite(r.mae_dph) for r in rows[:1]):
        lines += ["", f"{rows[0].method}: MAE {NOT_APPLICABLE}, as in the FOG start-up "
                  "paper: the drift's mean level over a run is no error a compensator is asked "
                  "to remove (a rotating north-finding cycle cancels it), so only its spread "
                  "(STD within each run) compares with the compensated rows."]
    if features_mode:
        lines += ["", f"Features mode: {features_mode}."]
    lines += ["", "The FOG start-up paper, Table 2: " + "; ".join(
        f"{k} MAE {'-' if v[0] is None else v[0]} STD {v[1]}"
        for k, v in SEED004_TABLE2_DRIFT_DPH.items()) + " [deg/h]."]
    return "\n".join(lines) + "\n"


def plot_drift_vs_compensated(study, run_index: int | None = None, methods=None, *,
                              best: str | None = None):
    """Separated drift of one test run, the drift predicted by some rows, and the residual,
    over time (matplotlib Figure).

    By default the coldest test start-up (where the start-up drift is largest) and the rows
    BP and SSA-SVR (the pair the start-up paper's figure sets side by side) plus ``best`` (the
    table's best row, :attr:`HeadingTable.best`) when it is another; the figure says which
    rows it shows and why.  The raw trace is drawn where the turntable rests (a move adds
    its rotation rate, no drift); each panel's limits hold every trace drawn in it, the
    residual's symmetric about 0; the legends stand beside the panels, off the data.
    """
    from matplotlib.figure import Figure

    sims = study.test.simulations
    which = "the test start-up asked for"
    if run_index is None:
        run_index = int(np.argmin([s.conditions.start_temperature_c for s in sims]))
        which = "the coldest test start-up: largest drift"
    why = {}
    if methods is None:
        for m in ("BP", "SSA-SVR"):
            if m in study.results:
                why[m] = "as in the start-up paper's figure"
        if best in study.results:
            why[best] = (why[best] + "; best row" if best in why
                         else "best row of the table")
        methods = tuple(why)
    methods = [m for m in methods if m in study.results]
    run = sims[run_index].run
    # what the study scored: its separation of the run and each row's prediction (a study
    # made before they were kept: computed again)
    sep = (study.test_separations[run_index] if study.test_separations else
           separate_drift(run, cutoff_period_s=study.settings.cutoff_period_s))
    t_min = np.asarray(run.columns["time_s"]) / 60.0
    raw = np.where(np.asarray(sep.moving, dtype=bool), np.nan, sep.raw_drift_dph)
    preds = {m: (study.results[m].predicted_drift_dph[run_index]
                 if study.results[m].predicted_drift_dph else
                 study.results[m].compensator.predict_drift(run)) for m in methods}
    fig = Figure(figsize=(11.0, 6.4), dpi=110, layout="constrained")
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    ax1.plot(t_min, raw, color="0.8", lw=0.5,
             label="gyro output - Earth rate,\nat rest (1 Hz, noisy) [deg/h]")
    ax1.plot(t_min, sep.drift_dph, color="k", lw=1.2,
             label="thermal drift\n(wavelet-separated) [deg/h]")
    for i, m in enumerate(methods):
        ax1.plot(t_min, preds[m], color=f"C{i}", lw=1.0, label=f"{m}: predicted drift")
        ax2.plot(t_min, sep.drift_dph - preds[m], color=f"C{i}", lw=1.0,
                 label=f"{m}: drift - prediction")
    ax1.set_ylim(*_limits([raw, sep.drift_dph, *preds.values()]))
    ax1.set_ylabel("drift [deg/h]")
    ax1.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    shown = "; ".join(f"{m} ({why[m]})" if m in why else m for m in methods)
    fig.suptitle(f"{run.name} (T0 = {run.meta.start_temperature_c:g} C, {which})\n"
                 + "\n".join(textwrap.wrap("rows shown: " + (shown or "none"), 110)),
                 fontsize=9)
    ax2.axhline(0.0, color="k", lw=0.5)
    if methods:
        r = max(float(np.nanmax(np.abs(sep.drift_dph - p))) for p in preds.values())
        ax2.set_ylim(-1.08 * r, 1.08 * r)
        ax2.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax2.set_ylabel("residual drift [deg/h]")
    ax2.set_xlabel("time since power-on [min]")
    ax2.set_xlim(t_min[0], t_min[-1])
    return fig


def _limits(traces, pad: float = 0.04) -> tuple[float, float]:
    """y limits that hold every finite value of ``traces``, padded by ``pad`` of the span."""
    v = np.concatenate([np.asarray(t, dtype=float).ravel() for t in traces])
    v = v[np.isfinite(v)]
    lo, hi = float(v.min()), float(v.max())
    span = (hi - lo) or max(abs(hi), 1e-6)
    return lo - pad * span, hi + pad * span


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    return buf.getvalue()


def write_study(study, out_dir, *, json_path=None, title: str = "",
                table: HeadingTable | None = None) -> list[Path]:
    """Write every output of a compensation study into ``out_dir``.

    heading_rmse.{md,csv,json,png} (all rows), drift_residual.{md,csv,json},
    svr_parameters.{md,csv,json}, drift_vs_compensated.png (the coldest test run) and
    report.md (tables, figures, the comparison with the FOG start-up paper).  ``table``: the study's
    heading table if already made (e.g. with its provenance; default
    ``study.heading_table()``).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if table is None:
        table = study.heading_table()
    paths = write_table(table, out, json_path=json_path, title=title)
    tts_md = _write_time_to_spec(study, table, out)
    mode = study.dataset.features_mode
    drift = study.drift_rows()
    # the uncompensated row uses no feature: its mode is left empty
    modes = ["" if r is study.uncompensated_drift else mode for r in drift]
    drift_md = drift_table_markdown(drift, mode)
    atomic_write_text(out / "drift_residual.md", drift_md)
    atomic_write_text(out / "drift_residual.csv", "method,MAE_dph,STD_dph,features_mode\n"
                      + "".join(f"{r.method},{_f(r.mae_dph)},{_f(r.std_dph)},{m}\n"
                                for r, m in zip(drift, modes)))
    atomic_write_text(out / "drift_residual.json", json.dumps(
        [{"method": r.method, "mae_dph": json_number(r.mae_dph),
          "std_dph": json_number(r.std_dph), "features_mode": m or None}
         for r, m in zip(drift, modes)], indent=2) + "\n")
    params = study.tuned_parameters()
    keys = sorted({k for p in params.values() for k in p})
    p_md = ["| method | " + " | ".join(keys) + " |", "|---|" + "---:|" * len(keys)]
    for m, p in params.items():
        p_md.append(f"| {m} | " + " | ".join(
            f"{p[k]:.4g}" if k in p else "" for k in keys) + " |")
    p_md_text = "\n".join(p_md) + f"\n\nTuned on features in {mode} mode.\n"
    atomic_write_text(out / "svr_parameters.md", p_md_text)
    atomic_write_text(out / "svr_parameters.csv", "method," + ",".join(keys) + "\n" + "".join(
        f"{m}," + ",".join(repr(p[k]) if k in p else "" for k in keys) + "\n"
        for m, p in params.items()))
    atomic_write_text(out / "svr_parameters.json", json.dumps(params, indent=2) + "\n")
    atomic_write_bytes(out / "drift_vs_compensated.png", _png(plot_drift_vs_compensated(study,
                                                                  best=table.best)))
    report = "\n".join([
        f"# {title or 'Start-up heading RMSE with drift compensation'}", "",
        f"Features mode: **{mode}**: {FEATURE_MODE_NOTES[mode]}.", "",
        "## Heading RMSE by start temperature [deg]", "", table.to_markdown(),
        "![heading RMSE by start temperature](heading_rmse.png)", "",
        "## Drift residual over the start-up stage (the FOG start-up paper, Table 2)", "", drift_md,
        "## Tuned hyperparameters (the FOG start-up paper, Table 1)", "", p_md_text,
        "![drift and its compensation](drift_vs_compensated.png)", "",
        "## Time to spec (northfind.spec_deg of the scenario)", "", tts_md,
        "![heading error against time since power-on](error_vs_time.png)", "",
        paper_comparison_markdown(table)])
    atomic_write_text(out / "report.md", report)
    return paths + [out / n for n in ("drift_residual.md", "drift_residual.csv",
                                      "drift_residual.json", "svr_parameters.md",
                                      "svr_parameters.csv", "svr_parameters.json",
                                      "drift_vs_compensated.png", "time_to_spec.md",
                                      "error_vs_time.png", "report.md")]


def _write_time_to_spec(study, table: HeadingTable, out: Path) -> str:
    """Outputs of :func:`write_study` on the start-up answers: time_to_spec.md (median time
    to spec by row and start temperature at the scenario's ``northfind.spec_deg``) and
    error_vs_time.png (heading error against time since power-on per start temperature,
    ``before`` and the best row); returns the Markdown."""
    spec = study.test.scenario.northfind.spec_deg
    every = {"before": study.test.northfind,
             **{n: r.northfind for n, r in study.results.items()}}
    md = time_to_spec_table(study.test, every, spec).to_markdown()
    atomic_write_text(out / "time_to_spec.md", md)
    shown = {k: every[k] for k in ("before", table.best) if k in every}
    atomic_write_bytes(out / "error_vs_time.png",
                       _png(plot_error_vs_time(study.test, shown, spec)))
    return md
