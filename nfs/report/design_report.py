"""The designed run on disk: a scenario to run, a report with its figure, and design.json.

:func:`write_design` writes into a folder

- ``scenario.toml``: the proposed run as a scenario (one start temperature, its chamber
  program with the power cycles or the ramp, the schedule and site of the runs taken, the
  model as its instrument), commented with what it separates and why; ``nfs simulate`` and
  ``nfs table`` run it;
- ``report.md``: the verdict, the run, every pair's separation on the runs taken and on the
  proposed run (per channel), the chance that the run decides, the experiments tried;
- ``design.png`` (:func:`plot_design`): the rivals' predictions of the proposed run against
  the noise band;
- ``design.json``: :meth:`nfs.design.search.Design.to_dict` with the provenance.
"""

from __future__ import annotations

import io
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..io.atomic import atomic_write_files
from ..scoring.intervals import json_number
from ..run import Run, run_caveats
from ..rivals.decide import LAMBDA_NAME, Z_NAME, decision_rates
from ..rivals.predict import CHANNELS
from ..design.search import Design
from ..rivals.separation import separation

__all__ = ["plot_design", "scenario_toml", "to_markdown", "write_design", "decide_command"]

_UNITS = {"drift_dph": "deg/h", "acc_x_g": "g", "acc_y_g": "g", "temp_fog_c": "K",
          "temp_acc_x_c": "K", "temp_acc_y_c": "K"}
_WORDS = {"drift_dph": "gyro drift (dwell means)", "acc_x_g": "accelerometer x (dwell means)",
          "acc_y_g": "accelerometer y (dwell means)", "temp_fog_c": "FOG thermometer",
          "temp_acc_x_c": "accelerometer x thermometer",
          "temp_acc_y_c": "accelerometer y thermometer"}


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})   # same design, same bytes
    return buf.getvalue()


def plot_design(design: Design):
    """The rivals' predictions of the proposed run (a matplotlib Figure, no pyplot).

    Top: each rival's drift, as dwell means [deg/h] (the gyro less the Earth rate), the
    first rival's with its +-1 sigma noise band (the noise the runs show).  Bottom: the
    separation of every pair the run must separate, had the run stopped at that time (all
    channels, parameter uncertainty included), against the margin.  Grey: the unit switched
    off, or the chamber ramping.
    """
    fig = Figure(figsize=(8.0, 6.5), dpi=100)
    ax1, ax2 = fig.add_subplot(2, 1, 1), fig.add_subplot(2, 1, 2, sharex=None)
    labels = list(design.predictions)
    first = design.predictions[labels[0]].mean[0]
    sig_all = design.sigma
    t = first.time_s["drift_dph"] / 60.0
    band = sig_all["drift_dph"]
    ax1.fill_between(t, first.values["drift_dph"] - band, first.values["drift_dph"] + band,
                     color="tab:blue", alpha=0.2, lw=0,
                     label=f"{labels[0]} +-1 sigma noise of a dwell mean "
                           f"({band.max():.2g} deg/h)")
    colours = ("tab:blue", "tab:red", "tab:green", "tab:purple")
    for k, lab in enumerate(labels):
        p = design.predictions[lab].mean[0]
        ax1.plot(p.time_s["drift_dph"] / 60.0, p.values["drift_dph"], "o-", ms=3,
                 color=colours[k % 4], label=f"{lab}: predicted drift")
    ax1.set_ylabel("drift, dwell mean [deg/h]")
    ax1.set_title("Rivals' predictions of the proposed run\n" + design.experiment.describe(),
                  fontsize=8)
    # bottom: how each pair's separation grows with the run's length
    ends = np.unique(np.concatenate([first.time_s["drift_dph"], [design.experiment.duration_s]]))
    for n, k in enumerate(design.open_pairs):
        i, j = k
        a, b = design.predictions[labels[i]], design.predictions[labels[j]]
        curve = []
        for t_end in ends:
            ca, cb = a.until(t_end), b.until(t_end)
            sig = {c: v[: ca.mean[0].values[c].size] for c, v in sig_all.items()}
            curve.append(separation(ca, cb, [sig]).sigma)
        ax2.plot(ends / 60.0, curve, "o-", ms=3, color=colours[(n + 1) % 4],
                 label=f"{design.pair_label(k)}")
    ax2.axhline(design.margin_sigma, color="k", ls="--", lw=1,
                label=f"margin: {design.margin_sigma:g} noise standard deviations")
    ax2.set_ylim(bottom=0.0)
    ax2.set_ylabel("separation if the run stopped here\n[noise standard deviations]")
    ax2.set_xlabel("time from power-on [min]")
    e = design.experiment
    spans = e.off_spans_s() if e.event == "power_off" else (
        [(e.event_s, e.event_end_s)] if e.event == "ramp" else [])
    for ax in (ax1, ax2):
        for k, (a, b) in enumerate(spans):
            ax.axvspan(a / 60.0, b / 60.0, color="0.85", zorder=0,
                       label=("unit switched off" if e.event == "power_off"
                              else "chamber ramping") if k == 0 else None)
        ax.set_xlim(0.0, e.duration_s / 60.0)
        ax.legend(fontsize=7, loc="best")
        ax.grid(True, lw=0.3)
    fig.tight_layout()
    return fig


def _q(text: str) -> str:
    return json.dumps(text)


def scenario_toml(design: Design, runs: list[Run], model_path: str | os.PathLike,
                  folder: str | os.PathLike) -> str:
    """The proposed run as a commented scenario file (module docstring)."""
    e = design.experiment
    m = runs[0].meta
    pos = list(m.positions_deg or (0.0,))
    model = os.path.relpath(Path(model_path).resolve(), Path(folder).resolve())
    pairs = "; ".join(f"{design.pair_label(k)}: {design.current[k].sigma:.1f} -> "
                      f"{v.sigma:.1f} sigma" for k, v in design.proposed.items())
    steps = ",\n    ".join("{ " + ", ".join(f"{k} = {float(v)!r}" for k, v in s.items()) + " }"
                           for s in e.program())
    fs = m.sample_rate_hz or 1.0
    dwell = float(e.dwell_s if e.dwell_s is not None else (m.dwell_s or 1.0))
    cycle = len(pos) * (dwell + float(m.move_s or 0.0))
    # the start-up stage: the first half of the whole cycles (at least one)
    half = cycle * max(1, int(e.duration_s // cycle) // 2)
    lines = [
        "# A run designed by `nfs design` to tell rival explanations apart.",
        "#",
        f"# {e.describe()}.",
        f"# Chamber time: {e.hours:.2f} h ({e.soak_h:g} h soak + the run).",
        f"# Separation (noise standard deviations, the runs taken -> this run): {pairs}.",
        f"# Why: {design.verdict}",
        "#",
        "# Run it in the chamber with the unit that made the runs taken, add the run to them,",
        "# fit again (nfs fit) and put the rivals to the runs:",
        f"#   {decide_command(design)}",
        "# `nfs simulate` shows what the model predicts the run records.",
        f"name = {_q('designed')}",
        f"description = {_q('run designed to separate ' + ' / '.join(r.label for r in design.rivals))}",
        f"instrument = {_q(model)}    # the model the design was made with",
        "seed = 1",
        f"start_temperatures_c = [{float(e.start_temperature_c)!r}]",
        "repeats = 1",
        f"duration_s = {float(e.duration_s)!r}",
        f"sample_rate_hz = {float(fs)!r}",
        f"latitude_deg = {float(m.latitude_deg)!r}",
        f"true_heading_deg = {float(m.true_heading_deg or 0.0)!r}",
        "",
        "[schedule]                          # the positions of the runs taken",
        f"positions_deg = {[float(p) for p in pos]!r}",
        'order = "sequential"',
        f"dwell_s = {dwell!r}",
        f"move_s = {float(m.move_s or 0.0)!r}",
        "",
        "[northfind]",
        f"startup_end_s = {half!r}",
        f"stable_start_s = {half!r}",
        "",
        "[chamber]                           # from power-on; power_off_s: a warm restart",
        "program = [",
        f"    {steps},",
        "]",
        "",
        "[compensation]",
        'methods = ["ls"]',
        "",
        "[variability]",
        'preset = "none"                     # the model as it is: what it predicts',
        "",
    ]
    return "\n".join(lines)


def decide_command(design: Design) -> str:
    """The command that puts the design's rivals to the runs once its run is taken."""
    rivals = " ".join(_q(r.label) if " " in r.label else r.label for r in design.rivals)
    return f"nfs diagnose DATA... --model FITTED.toml --rivals {rivals}"


def _fmt(x: float) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.2f}"


def to_markdown(design: Design, caveats: list[str] | tuple[str, ...] = ()) -> str:
    """``report.md`` (module docstring); ``caveats``: what the reader was asked to accept in
    the runs taken (:func:`nfs.run.run_caveats`), listed under the verdict."""
    e = design.experiment
    out = ["# Designed run", "", design.verdict, ""]
    if caveats:
        out += ["The runs taken, as read:", ""] + [f"- {c}" for c in caveats] + [""]
    out += ["## The run", "",
           f"- {e.describe()}", f"- chamber hours: {e.hours:.2f} ({e.soak_h:g} h soak + "
           f"{e.duration_s / 3600.0:.2f} h run)", "- chamber program from power-on: `"
           + json.dumps(e.program()) + "`", "", "![rivals' predictions](design.png)", "",
           "## Separation", "",
           "How far apart the rivals' predictions are, in standard deviations of the noise "
           "the runs show (parameter uncertainty included, a constant per channel and run "
           "free: `nfs.rivals.separation`).", ""]
    chans = list(CHANNELS)
    out.append("| pair | runs | all channels | " + " | ".join(_WORDS[c] for c in chans) + " |")
    out.append("|---|---|---:|" + "---:|" * len(chans))
    for k, v in design.proposed.items():
        for what, s in (("taken", design.current.get(k)), ("proposed", v)):
            if s is None:
                continue
            out.append(f"| {design.pair_label(k)} | {what} | {_fmt(s.sigma)} | "
                       + " | ".join(_fmt(s.by_channel.get(c, math.nan)) for c in chans)
                       + " |")
    worst = min(design.proposed[k].sigma for k in design.open_pairs)
    right, wrong = decision_rates(worst)
    out += ["", f"After the run, the rivals and the model as it is are put to the runs "
            f"(`{decide_command(design)}`: a decision needs a likelihood ratio of "
            f"e^{LAMBDA_NAME:g} after the price of the numbers a rival adds, and Vuong's Z "
            f"{Z_NAME:.3g}, `nfs.rivals.decide`): at {worst:.1f} sigma the run names the "
            f"right one with probability {right:.2f} and the wrong one with {wrong:.2g} "
            "where one rival is the unit (the rest: still a tie).", "",
            "Noise factors (the runs' residual over the sensor noise, per channel): "
            + ", ".join(f"{_WORDS[c]} {f:.2f}" for c, f in design.noise_factors.items()), "",
            "## Rivals", ""]
    for r in design.rivals:
        out.append(f"- **{r.label}**: {r.description}")
    out += ["", "## Experiments tried", "",
            "| stage | chamber hours | worst pair [sigma] | reaches the margin | run |",
            "|---|---:|---:|---|---|"]
    for t in sorted(design.trials, key=lambda t: (not t.met, t.experiment.hours,
                                                  -t.worst_sigma)):
        out.append(f"| {t.stage} | {t.experiment.hours:.2f} | {t.worst_sigma:.2f} | "
                   f"{'yes' if t.met else 'no'} | {t.experiment.describe()} |")
    out.append("")
    return "\n".join(out)


def write_design(design: Design, folder: str | os.PathLike, runs: list[Run],
                 model_path: str | os.PathLike, provenance: dict[str, Any] | None = None
                 ) -> list[Path]:
    """Write the four files (module docstring) into ``folder`` atomically; their paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    data = design.to_dict()
    if provenance is not None:
        data["provenance"] = provenance
    files = {folder / "scenario.toml": scenario_toml(design, runs, model_path, folder),
             folder / "report.md": to_markdown(design, run_caveats(runs)),
             folder / "design.png": _png(plot_design(design)),
             folder / "design.json": json.dumps(data, indent=1, default=json_number) + "\n"}
    atomic_write_files(files)
    return list(files)

