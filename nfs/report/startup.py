"""The start-up answers of the heading-RMSE table's report: time to spec by start temperature
and method, and the heading error against time since power-on.

Time to spec (:mod:`nfs.northfind.time_to_spec`): the output time of the first cycle after which
every cycle's heading error stays within the spec (and the same for the RMSE of the last
``window`` cycles), per test start-up; a cell of the table is the median over the start-ups
at that start temperature, ``never`` when that median is not within spec by the end of the
run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from ..northfind.time_to_spec import DEFAULT_WINDOW, median_time_s, run_time_to_spec_s

__all__ = ["TimeToSpecTable", "time_to_spec_table", "plot_error_vs_time"]


@dataclass(frozen=True)
class TimeToSpecTable:
    """Median time to spec by method and start temperature."""

    temperatures_c: tuple[float, ...]
    """Start temperatures of the columns [degC]."""
    spec_deg: float
    """The heading specification [deg]."""
    window: int
    """Cycles of the rolling RMSE."""
    every_s: dict[str, tuple[float, ...]]
    """Method -> median time to spec of every cycle at each start temperature [s]."""
    rolling_s: dict[str, tuple[float, ...]]
    """Method -> median time to spec of the rolling RMSE at each start temperature [s]."""
    n_runs: int
    """Start-ups per start temperature the medians are taken over."""

    def to_markdown(self) -> str:
        """Two Markdown tables (every cycle, rolling RMSE) in minutes after power-on."""
        head = "| method | " + " | ".join(f"{t:g} C" for t in self.temperatures_c) + " |"
        rule = "|---|" + "---:|" * len(self.temperatures_c)
        out = []
        for what, rows in (("every cycle within spec", self.every_s),
                           (f"RMSE of the last {self.window} cycles within spec",
                            self.rolling_s)):
            out += [f"Time to spec [min after power-on], {what} ({self.spec_deg:g} deg):", "",
                    head, rule]
            out += [f"| {m} | " + " | ".join(_minutes(v) for v in vals) + " |"
                    for m, vals in rows.items()]
            out.append("")
        out.append(f"Median over the {self.n_runs} test start-up(s) at each start temperature; "
                   "never: not within spec by the end of the run; -: no cycle to judge. "
                   "The time is a cycle's output time, so it moves in steps of one cycle; the "
                   f"RMSE of the last {self.window} cycles exists from the {self.window}th "
                   "cycle on.")
        return "\n".join(out) + "\n"


def _minutes(v: float) -> str:
    if math.isnan(v):
        return "-"
    return "never" if math.isinf(v) else f"{v / 60.0:.1f}"



def time_to_spec_table(result, northfind: Mapping[str, Sequence], spec_deg: float,
                       window: int = DEFAULT_WINDOW) -> TimeToSpecTable:
    """Median time to spec by start temperature for each entry of ``northfind``.

    Parameters
    ----------
    result : ScenarioResult
        The test start-ups (:func:`~nfs.studies.scenario_runs.run_scenario`).
    northfind : mapping
        Row name -> the NorthFindResult of every run of ``result`` (``before``: the
        result's own).
    spec_deg : float
        The heading specification [deg].
    window : int
        Cycles of the rolling RMSE.
    """
    sc = result.scenario
    every, rolling = {}, {}
    for name, nfs_ in northfind.items():
        a, b = [], []
        for i in range(len(sc.start_temperatures_c)):
            times = [run_time_to_spec_s(nfs_[k].t_end_s, nfs_[k].error_deg, spec_deg, window)
                     for k in result.runs_at(i)]
            a.append(median_time_s(t[0] for t in times))
            b.append(median_time_s(t[1] for t in times))
        every[name], rolling[name] = tuple(a), tuple(b)
    return TimeToSpecTable(tuple(sc.start_temperatures_c), float(spec_deg), window, every,
                           rolling, sc.repeats)


def plot_error_vs_time(result, northfind: Mapping[str, Sequence], spec_deg: float):
    """|heading error| against time since power-on, one line per start temperature (the RMS
    over its start-ups at each cycle), one panel per entry of ``northfind``, the spec as a
    dashed line (matplotlib Figure)."""
    sc = result.scenario
    temps = sc.start_temperatures_c
    fig = Figure(figsize=(4.2 * len(northfind) + 1.0, 4.0), dpi=110)
    axes = np.atleast_1d(fig.subplots(1, len(northfind), sharey=True))
    cmap = colormaps["coolwarm"]
    lo, hi = min(temps), max(temps)
    for ax, (name, nfs_) in zip(axes, northfind.items()):
        for i, t0 in enumerate(temps):
            runs = [nfs_[k] for k in result.runs_at(i)]
            n = min(len(r.error_deg) for r in runs)
            err = np.array([np.asarray(r.error_deg)[:n] for r in runs])
            with np.errstate(invalid="ignore"):
                rms = np.sqrt(np.nanmean(err ** 2, axis=0))
            t_min = np.asarray(runs[0].t_end_s)[:n] / 60.0
            ax.plot(t_min, rms, "-o", ms=3, lw=1.2, label=f"{t0:g} C",
                    color=cmap(0.5 if hi == lo else (t0 - lo) / (hi - lo)))
        ax.axhline(spec_deg, color="k", ls="--", lw=1, label=f"spec {spec_deg:g} deg")
        ax.set_yscale("log")
        ax.set_xlabel("time since power-on [min] (cycle output)")
        ax.set_title("before (uncompensated)" if name == "before" else name, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("|heading error| [deg] (RMS over start-ups)")
    axes[-1].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig
