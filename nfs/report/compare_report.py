"""The report of a comparison of a model with measured runs: Markdown, JSON and figures.

:func:`write_report` writes ``report.md`` (where the model fails, in words; the summary table;
the heading RMSE; per channel and run, per turntable position), ``comparison.json``
(:meth:`~nfs.comparison.compare_runs.Comparison.to_dict`) and PNG figures: per run, the measured
channels beside the model's deterministic prediction with its noise band
(:func:`plot_overlay`) and the residuals over time (:func:`plot_residuals`); over the runs,
the residual RMS against the start temperature (:func:`plot_rms_vs_t0`), each dwell's bias by
turntable position against time (:func:`plot_dwell_bias`) and each cycle's heading error
against time (:func:`plot_heading_vs_time`), measured beside the model.  Figures are made
with matplotlib's object API (no pyplot state) and saved with pinned metadata, so the same
comparison gives the same bytes.
"""

from __future__ import annotations

import io
import json
import math
import re
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..io.atomic import atomic_write_bytes, atomic_write_text
from ..comparison.channel_residual import CHANNEL_BY_KEY, CHANNELS, COMPARISON_STAGES
from ..comparison.channel_summary import format_sig
from ..comparison.compare_runs import Comparison

__all__ = ["plot_overlay", "plot_residuals", "plot_rms_vs_t0", "plot_dwell_bias",
           "plot_heading_vs_time", "to_markdown", "write_report"]


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.+-]+", "_", name)


def _png(fig) -> bytes:
    buf = io.BytesIO()
    # Metadata pinned so that the same comparison gives the same PNG bytes.
    fig.savefig(buf, format="png", metadata={"Software": None})
    return buf.getvalue()


def _scale(unit: str) -> tuple[float, str]:
    return (1e6, "ug") if unit == "g" else (1.0, unit)


def plot_overlay(comparison: Comparison, i_run: int):
    """Measured against the model's deterministic prediction, with its +-1 sigma noise band,
    for the gyro drift and the FOG thermometer of run ``i_run`` (a matplotlib Figure, made
    without pyplot).  The band is the run's noise floor (:mod:`nfs.comparison.compare_runs`):
    where the model is right, about two thirds of the measured points fall inside it."""
    fig = Figure(figsize=(8.0, 6.0), dpi=100)
    for j, key in enumerate(("gyro_drift_dph", "temp_fog_c")):
        cr = comparison.per_run[key][i_run]
        ax = fig.add_subplot(2, 1, j + 1)
        t_min = cr.time_s / 60.0
        band = cr.stages["all"].floor_rms
        unit = CHANNEL_BY_KEY[key].unit
        ax.fill_between(t_min, cr.model - band, cr.model + band, color="tab:red", alpha=0.2,
                        lw=0, label=f"model +-1 sigma noise ({format_sig(band)} {unit})")
        ax.plot(t_min, cr.measured, ".", ms=1.0, color="0.3", label="measured")
        ax.plot(t_min, cr.model, "-", lw=1.2, color="tab:red",
                label="model (deterministic prediction)")
        ax.set_ylabel(f"{CHANNEL_BY_KEY[key].label} [{CHANNEL_BY_KEY[key].unit}]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    ax.set_xlabel("time after power-on [min]")
    fig.suptitle(f"{comparison.run_names[i_run]} (T0 = "
                 f"{comparison.start_temperatures_c[i_run]:g} C): measured vs model")
    fig.tight_layout()
    return fig


def plot_residuals(comparison: Comparison, i_run: int):
    """Residual (measured - model) over time of every channel of run ``i_run``, with the
    +-noise-floor band."""
    fig = Figure(figsize=(8.0, 10.0), dpi=100)
    for j, spec in enumerate(CHANNELS):
        cr = comparison.per_run[spec.key][i_run]
        k, unit = _scale(spec.unit)
        ax = fig.add_subplot(len(CHANNELS), 1, j + 1)
        t_min = cr.time_s / 60.0
        fl = k * cr.stages["all"].floor_rms   # the run's floor RMS (the gyro's is a draw)
        ax.axhspan(-fl, fl, color="0.85", lw=0,
                   label=f"+-1 sigma noise floor ({format_sig(fl)} {unit})")
        style = {"accelerometer": (".-", 3.0), "gyro": ("-", 0.0)}.get(spec.kind, (".", 0.5))
        ax.plot(t_min, k * cr.residual, style[0], lw=0.8, ms=style[1], color="tab:blue",
                label="residual, measured - model")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylabel(f"{spec.label}\n[{unit}]", fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    ax.set_xlabel("time after power-on [min]")
    fig.suptitle(f"{comparison.run_names[i_run]}: residual measured - model\n(grey band: the "
                 "run's +-1 sigma noise floor; a right model's residual stays mostly inside)",
                 fontsize=10)
    fig.tight_layout()
    return fig


def plot_rms_vs_t0(comparison: Comparison):
    """Per-run residual RMS by stage against the start temperature, one panel per channel,
    with the noise floor."""
    fig = Figure(figsize=(10.0, 8.0), dpi=100)
    t0 = np.asarray(comparison.start_temperatures_c, dtype=float)
    order = np.argsort(t0)
    for j, spec in enumerate(CHANNELS):
        k, unit = _scale(spec.unit)
        ax = fig.add_subplot(3, 2, j + 1)
        runs = comparison.per_run[spec.key]
        for stage, marker in (("startup", "o"), ("stable", "s"), ("all", "^")):
            v = np.array([cr.stages[stage].rms for cr in runs])
            ax.plot(t0[order], k * v[order], marker + "-", ms=4, lw=0.8, label=stage)
        fl = np.array([cr.stages["all"].floor_rms for cr in runs])
        ax.plot(t0[order], k * fl[order], "k--", lw=1.0, label="noise floor of the run")
        ax.set_title(spec.label, fontsize=9)
        ax.set_ylabel(f"residual RMS [{unit}]", fontsize=8)
        ax.set_xlabel("start temperature T0 [degC]", fontsize=8)
        ax.set_ylim(bottom=0.0)  # from zero: a 2 % spread must not look like a factor 2
        ax.grid(alpha=0.3)
        if j == 0:
            ax.legend(fontsize=7, title="stage", title_fontsize=7)
    fig.suptitle("residual RMS (measured - model) against start temperature, per stage: "
                 "start-up, stable, all")
    fig.tight_layout()
    return fig


def _run_title(comparison: Comparison, i_run: int) -> str:
    return (f"{comparison.run_names[i_run]} (T0 = "
            f"{comparison.start_temperatures_c[i_run]:g} C)")


def plot_dwell_bias(comparison: Comparison):
    """Each dwell's mean gyro rate less the Earth-rate projection against time, one panel
    per run, one colour per turntable position: measured (points, +-1 sigma of a dwell mean
    under the model's noise) and the model's prediction (line)
    (:class:`nfs.comparison.dwell_traces.DwellBias`).  Every panel's y axis holds 0."""
    biases = comparison.dwell_biases
    fig = Figure(figsize=(10.0, 1.0 + 2.3 * max(1, len(biases))), dpi=100)
    ax = None
    for i, b in enumerate(biases):
        ax = fig.add_subplot(len(biases), 1, i + 1, sharex=ax)
        t_min = b.time_s / 60.0
        angles = np.round(np.mod(b.theta_deg, 360.0), 1)
        for j, a in enumerate(np.unique(angles)):
            at = angles == a
            colour = f"C{j % 10}"
            ax.errorbar(t_min[at], b.measured_dph[at], yerr=b.noise_dph, fmt="o", ms=3,
                        color=colour, elinewidth=0.8, capsize=0,
                        label=f"theta = {a:g} deg: measured, +-1 sigma of a dwell mean")
            ax.plot(t_min[at], b.model_dph[at], "-", lw=1.2, color=colour,
                    label=f"theta = {a:g} deg: model")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylim(min(0.0, ax.get_ylim()[0]), max(0.0, ax.get_ylim()[1]))
        ax.set_ylabel("dwell mean - Earth rate\n[deg/h]", fontsize=8)
        ax.set_title(f"{_run_title(comparison, i)}: +-1 sigma of a dwell mean "
                     f"{format_sig(b.noise_dph)} deg/h (the model's noise)", fontsize=9)
        ax.grid(alpha=0.3)
        if i == 0:
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                      borderaxespad=0.0)
    if ax is not None:
        ax.set_xlabel("time after power-on [min] (dwell mid-time)")
    fig.suptitle("gyro bias per turntable position: each dwell's mean rate less the "
                 "Earth-rate projection, measured vs model", fontsize=10)
    fig.tight_layout()
    return fig


def plot_heading_vs_time(comparison: Comparison):
    """Each cycle's north-finding heading error against the time the cycle ends, one panel
    per run: measured (points) and the model's prediction (line) with its +-1 sigma noise
    band (:class:`nfs.comparison.dwell_traces.HeadingTrace`); one y scale for every run,
    symmetric about 0."""
    traces = comparison.heading_traces
    fig = Figure(figsize=(10.0, 1.0 + 2.0 * max(1, len(traces))), dpi=100)
    values = np.concatenate([np.concatenate([h.measured_deg, h.model_deg + h.noise_deg,
                                             h.model_deg - h.noise_deg]) for h in traces]
                            or [np.zeros(1)])
    values = values[np.isfinite(values)]
    half = 1.1 * float(np.max(np.abs(values))) if values.size and np.any(values) else 1.0
    ax = None
    for i, h in enumerate(traces):
        ax = fig.add_subplot(len(traces), 1, i + 1, sharex=ax)
        t_min = h.time_s / 60.0
        ax.fill_between(t_min, h.model_deg - h.noise_deg, h.model_deg + h.noise_deg,
                        color="tab:red", alpha=0.2, lw=0,
                        label="model +-1 sigma heading noise of a cycle (value in the title)")
        ax.plot(t_min, h.model_deg, "-", lw=1.2, color="tab:red",
                label="model (noise-free prediction)")
        ax.plot(t_min, h.measured_deg, "o", ms=3.5, color="0.2", label="measured")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylim(-half, half)
        ax.set_ylabel("heading error\n[deg]", fontsize=8)
        ax.set_title(f"{_run_title(comparison, i)}: +-1 sigma heading noise of a cycle "
                     f"{format_sig(h.noise_deg)} deg (the model's noise)", fontsize=9)
        ax.grid(alpha=0.3)
        if i == 0:
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                      borderaxespad=0.0)
    if ax is not None:
        ax.set_xlabel("time after power-on [min] (end of the north-finding cycle)")
    fig.suptitle("north-finding heading error (heading - true heading) per cycle, measured "
                 "vs model", fontsize=10)
    fig.tight_layout()
    return fig


def _md_table(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |",
             "|" + "|".join(["---"] + ["---:"] * (len(head) - 1)) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def _v(v: float, unit: str) -> str:
    k, _ = _scale(unit)
    return format_sig(v * k if v is not None and math.isfinite(v) else math.nan, 3)


def to_markdown(comparison: Comparison, figures: dict[str, list[str]] | None = None) -> str:
    """The Markdown report: summary, where it fails, heading, per-run tables, figures."""
    c = comparison
    out = [f"# Model '{c.model_name}' against {len(c.run_names)} run(s)", ""]
    s = c.settings
    out += [f"Residual = measured - model. Start-up stage t < {s['startup_end_s']:g} s, stable "
            f"stage t >= {s['stable_start_s']:g} s, worst window {s['window_s']:g} s, model "
            f"seed {s['seed']}. Accelerometer values in ug (dwell means); gyro drift after "
            "wavelet separation on both sides; noise floors as in "
            "`nfs.comparison.compare`.", "", "## Where it fails", ""]
    out += [f"- {x}" for x in c.sentences()] + [f"- {c.heading_sentence()}", ""]
    if c.assumptions:
        out += ["Assumed where the runs do not say:", ""] + [f"- {a}" for a in c.assumptions]
        out += [""]
    out += ["## Summary", ""]
    rows = []
    for spec in CHANNELS:
        sm = c.summaries[spec.key]
        _, unit = _scale(spec.unit)
        row = [spec.key, unit]
        for st in COMPARISON_STAGES:
            rms, fl = sm.stages[st]
            row += [_v(rms, spec.unit), _v(fl, spec.unit)]
        row += [f"{sm.ratio:.2f}", "noise" if sm.consistent else "FAILS"]
        rows.append(row)
    out.append(_md_table(["channel", "unit", "start-up RMS", "floor", "stable RMS", "floor",
                          "all RMS", "floor", "ratio", "verdict"], rows))
    out += ["## Heading RMSE [deg]", ""]
    rows = [[h.run_name, f"{h.start_temperature_c:g}", format_sig(h.measured_startup_deg, 4),
             format_sig(h.model_startup_deg, 4), format_sig(h.measured_stable_deg, 4),
             format_sig(h.model_stable_deg, 4)] for h in c.headings]
    p = c.heading_pooled
    rows.append(["RMS over runs", "", format_sig(p["measured_startup_deg"], 4),
                 format_sig(p["model_startup_deg"], 4), format_sig(p["measured_stable_deg"], 4),
                 format_sig(p["model_stable_deg"], 4)])
    out.append(_md_table(["run", "T0 [C]", "start-up measured", "start-up model",
                          "stable measured", "stable model"], rows))
    out += ["## Per channel and run", ""]
    for spec in CHANNELS:
        _, unit = _scale(spec.unit)
        out += [f"### {spec.key} [{unit}]", ""]
        rows = []
        for cr in c.per_run[spec.key]:
            for st in COMPARISON_STAGES:
                x = cr.stages[st]
                rows.append([cr.run_name, f"{cr.start_temperature_c:g}", st, _v(x.rms, spec.unit),
                             _v(x.bias, spec.unit), _v(x.std, spec.unit),
                             _v(x.floor_rms, spec.unit), format_sig(x.worst_start_s, 4),
                             _v(x.worst_rms, spec.unit)])
        out.append(_md_table(["run", "T0 [C]", "stage", "RMS", "bias", "std", "floor",
                              "worst window start [s]", "worst window RMS"], rows))
        rows = []
        for cr in c.per_run[spec.key]:
            pt = cr.position_test
            for a, x in cr.positions.items():
                i = pt.theta_deg.index(a) if a in pt.theta_deg else None
                rows.append([cr.run_name, f"{a:g}", _v(x.rms, spec.unit), _v(x.bias, spec.unit),
                             _v(pt.bias[i], spec.unit) if i is not None else "",
                             _v(pt.stderr[i], spec.unit) if i is not None else ""])
        out += ["By turntable position (detrended bias: dwell means minus the centred "
                "one-cycle moving average):", ""]
        out.append(_md_table(["run", "theta [deg]", "RMS", "bias", "detrended bias",
                              "its std. error"], rows))
    if figures:
        out += ["## Figures", ""]
        for title, paths in figures.items():
            out += [f"### {title}", ""] + [f"![{Path(q).stem}]({q})" for q in paths] + [""]
    return "\n".join(out) + "\n"


def write_report(comparison: Comparison, out_dir: str | Path) -> list[Path]:
    """Write ``report.md``, ``comparison.json`` and the figures (PNG) into ``out_dir``, every
    file atomically. Returns the paths written."""
    out = Path(out_dir)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    figures: dict[str, list[str]] = {"Measured vs model": [], "Residuals over time": [],
                                     "Residual RMS vs start temperature": [],
                                     "Gyro bias per position vs time": [],
                                     "Heading error vs time": []}

    def save(fig, rel: str, group: str) -> None:
        path = out / rel
        atomic_write_bytes(path, _png(fig))
        written.append(path)
        figures[group].append(rel)

    for i, name in enumerate(comparison.run_names):
        stem = f"{i:02d}_{_safe(name)}"
        save(plot_overlay(comparison, i), f"figures/overlay_{stem}.png", "Measured vs model")
        save(plot_residuals(comparison, i), f"figures/residuals_{stem}.png",
             "Residuals over time")
    save(plot_rms_vs_t0(comparison), "figures/rms_vs_t0.png",
         "Residual RMS vs start temperature")
    if comparison.dwell_biases:
        save(plot_dwell_bias(comparison), "figures/dwell_bias.png",
             "Gyro bias per position vs time")
    if comparison.heading_traces:
        save(plot_heading_vs_time(comparison), "figures/heading_vs_time.png",
             "Heading error vs time")
    js = out / "comparison.json"
    atomic_write_text(js, json.dumps(comparison.to_dict(), indent=2, allow_nan=False) + "\n")
    md = out / "report.md"
    atomic_write_text(md, to_markdown(comparison, figures))
    return [md, js, *written]
