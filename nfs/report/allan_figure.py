"""The Allan deviation of a set of runs on a figure and on disk (``nfs allan``).

:func:`plot_allan` draws an :class:`nfs.comparison.allan_runs.AllanReport`: every dwell's
overlapping Allan deviation as a thin line (one colour per run; the start-up dwells grey, drawn whole so
that the thermal drift at their long-tau end shows), the pooled curve the fit used with its
+-1 sigma error bars, the fitted angle random walk (slope -1/2), bias instability (flat) and
rate random walk (slope +1/2) lines, each labelled with its value, interval and unit, the
instrument's stated values as dashed lines, and the sum of the fitted terms.  Log-log with
one decade as long on both axes, so that a slope of -1/2 looks like one.
:func:`allan_figure` writes the figure, :func:`write_allan` the figure and ``allan.json``.
"""

from __future__ import annotations

import json
import math
import textwrap
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..comparison.allan_runs import TERMS, AllanReport
from ..io.atomic import atomic_write_bytes, atomic_write_text
from ..noise.generators import BI_FLOOR_FACTOR
from .drift_figures import png_bytes

__all__ = ["plot_allan", "allan_figure", "write_allan", "term_adev_dph"]

#: Colour of each term's fitted and stated lines.
_COLOUR = {"N": "tab:blue", "B": "tab:green", "K": "tab:red"}
#: Colour of each term's stated (dashed) line: a darker shade, so that its dashes show on top
#: of a fitted line it matches.
_STATED = {"N": "navy", "B": "darkgreen", "K": "darkred"}
#: Colour of the start-up dwells.
_STARTUP = "0.6"
#: Width of a legend entry [characters].
_WRAP = 58


def term_adev_dph(symbol: str, value: float, taus_s: np.ndarray) -> np.ndarray:
    """The Allan deviation of one noise term alone [deg/h] at ``taus_s`` [s] (IEEE Std
    952-2020 Annex C): N: 60 N / sqrt(tau); B: 0.6643 B; K: (K / 60) sqrt(tau / 3); NaN
    where it is 0 (no line on a log axis)."""
    tau = np.asarray(taus_s, dtype=float)
    if not value > 0:
        return np.full(tau.shape, np.nan)
    if symbol == "N":
        return 60.0 * value / np.sqrt(tau)
    if symbol == "B":
        return np.full(tau.shape, BI_FLOOR_FACTOR * value)
    return value / 60.0 * np.sqrt(tau / 3.0)


def _num(v: float) -> str:
    return "n/a" if not math.isfinite(v) else f"{v:.3g}"


def _decades(lo: float, hi: float) -> tuple[float, float]:
    """Whole decades around [lo, hi]."""
    return 10.0 ** math.floor(math.log10(lo)), 10.0 ** math.ceil(math.log10(hi))


def _limits(report: AllanReport, pooled) -> tuple[tuple[float, float], tuple[float, float]]:
    """Whole decades of tau around the taus, and of sigma around the pooled points and both
    flat bias-instability lines (the sloped lines may leave the axes)."""
    flats = [BI_FLOOR_FACTOR * v for v in (report.fitted("B")[0], report.stated("B"))]
    shown = np.concatenate([pooled.adev, [v for v in flats if v > 0]])
    shown = shown[np.isfinite(shown)]
    return (_decades(report.taus_s[0], report.taus_s[-1]),
            _decades(0.8 * shown.min(), 1.5 * shown.max()))


def plot_allan(report: AllanReport, fig: Figure | None = None) -> Figure:
    """The report's Allan deviations, fitted and stated lines (module docstring).  Every line
    carries a label in words and units.

    Parameters
    ----------
    report : AllanReport
        What :func:`nfs.comparison.allan_of_runs` found.
    fig : matplotlib.figure.Figure, optional
        An empty figure to draw into (e.g. ``matplotlib.pyplot.figure()``), resized to fit;
        default a new Figure made without pyplot.

    Returns
    -------
    matplotlib.figure.Figure
    """
    taus = report.taus_s
    pooled = report.pooled
    (x_lo, x_hi), (y_lo, y_hi) = _limits(report, pooled)
    # a decade as long on both axes [in], the axes sized to the decades they span
    n_x, n_y = math.log10(x_hi / x_lo), math.log10(y_hi / y_lo)
    decade = min(2.4, 5.6 / n_y, 6.0 / n_x)
    left, bottom, top, legend = 0.9, 1.25, 0.45, 4.8
    width, height = left + n_x * decade + legend, bottom + n_y * decade + top
    if fig is None:
        fig = Figure(figsize=(width, height), dpi=100)
    else:
        fig.set_size_inches(width, height)
    ax = fig.add_axes((left / width, bottom / height, n_x * decade / width,
                       n_y * decade / height))
    startup = report.dwell_start_s < report.startup_s
    runs = np.asarray(report.dwell_run)
    colours = [f"C{k % 10}" for k in range(len(report.run_names))]
    labelled_startup = False
    for k, name in enumerate(report.run_names):
        later = np.flatnonzero((runs == k) & ~startup)
        for j, i in enumerate(later):
            ax.plot(taus, report.dwell_adev_dph[i], "-", lw=0.5, alpha=0.35, color=colours[k],
                    label=f"{name}: {later.size} dwells after {report.startup_s:g} s"
                    if j == 0 else None)
    for i in np.flatnonzero(startup):
        ax.plot(taus, report.dwell_adev_dph[i], "-", lw=0.5, alpha=0.3, color=_STARTUP,
                label=None if labelled_startup else
                f"{report.n_startup_dwells} dwells within {report.startup_s:g} s of power-on "
                "(fitted only to a tenth of the dwell: thermal drift)")
        labelled_startup = True
    early = report.startup_pooled
    if early is not None:
        ax.plot(early.taus_s, early.adev, "s-", ms=3.5, lw=1.0, color="0.35", zorder=4,
                label=f"pooled over the {report.n_startup_dwells} start-up dwells, whole "
                      "(not fitted beyond a tenth of the dwell)")
    ax.errorbar(pooled.taus_s, pooled.adev, yerr=pooled.adev * pooled.adev_rel_err, fmt="o",
                ms=4, color="k", ecolor="k", elinewidth=1.0, capsize=2, zorder=5,
                label=f"pooled over the {len(report.dwell_run)} dwells (fitted), +-1 sigma")

    grid = np.geomspace(x_lo, x_hi, 200)
    pct = f"{100 * report.noise.level:g} %"
    for words, sym, _, unit in TERMS:
        value, (lo, hi) = report.fitted(sym)
        fitted = term_adev_dph(sym, value, grid)
        note = "" if value > 0 else ": 0, no line on a log axis"
        ax.plot(grid, fitted, "-", lw=1.8, color=_COLOUR[sym],
                label=f"fitted {sym} ({words}) = {_num(value)} {unit}, {pct} interval "
                      f"[{_num(lo)}, {_num(hi)}]{note}")
        stated = report.stated(sym)
        note = "" if stated > 0 else ": 0, no line on a log axis"
        ax.plot(grid, term_adev_dph(sym, stated, grid), "--", lw=1.4, color=_STATED[sym],
                zorder=6,
                label=f"stated {sym} = {_num(stated)} {unit}{note}")
    ax.plot(grid, report.noise.fit.adev_model_dph(grid), "-", lw=0.8, color="k",
            label="fitted N + B + K")

    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(x_lo, x_hi)
    ax.set_ylim(y_lo, y_hi)
    ax.set_aspect("equal", adjustable="box")     # a decade as long on both axes
    ax.set_xlabel("averaging time tau [s]")
    ax.set_ylabel("overlapping Allan deviation of the gyro sigma(tau) [deg/h]")
    ax.grid(True, which="both", alpha=0.25)
    handles, labels = ax.get_legend_handles_labels()
    ax.legend(handles, ["\n".join(textwrap.wrap(t, _WRAP)) for t in labels], fontsize=7,
              loc="upper left", bbox_to_anchor=(1.03, 1.0), borderaxespad=0.0)
    ax.set_title(f"Gyro at rest, dwell by dwell: {len(report.run_names)} run(s)", fontsize=10)
    fig.text(0.15 / width, 0.1 / height, "\n".join(textwrap.wrap(
        report.taus_note() + f". Stated: {report.stated_source}.", int(15 * width))),
        fontsize=7, va="bottom")
    return fig


def allan_figure(report: AllanReport, path: str | Path) -> Path:
    """Write :func:`plot_allan` of ``report`` to ``path`` (PNG, atomically); returns it."""
    path = Path(path)
    atomic_write_bytes(path, png_bytes(plot_allan(report)))
    return path


def write_allan(report: AllanReport, out_dir: str | Path,
                provenance: dict | None = None) -> list[Path]:
    """Write ``allan.json`` (:meth:`AllanReport.to_dict`, with ``provenance`` when given:
    :func:`nfs.io.provenance.output_provenance`) and ``allan.png`` (:func:`plot_allan`) into
    ``out_dir`` (made when missing); returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    js = out / "allan.json"
    doc = report.to_dict() if provenance is None else {**report.to_dict(),
                                                        "provenance": provenance}
    atomic_write_text(js, json.dumps(doc, indent=1) + "\n")
    return [js, allan_figure(report, out / "allan.png")]
