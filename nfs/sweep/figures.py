"""Summary figures of a sweep: heading RMSE (and time to spec) against each axis.

One PNG per axis (and per start temperature when the scenario has several): every run's
stage RMSE as a faint point, the RMS over the runs at each grid value as a line, one colour
per method and stage, and the white-noise floor of the cell's schedule and latitude as a
dashed line (it follows 1 / cos L on a latitude axis).  A second PNG per axis gives the
time to spec of every run (the median over the runs as a line).  With two grid axes or more, one more figure sets the first against
the second (start-up stage).  Matplotlib's Agg backend; written atomically.
"""

from __future__ import annotations

import json
import math
import re
from collections import defaultdict
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..io.atomic import atomic_output  # noqa: E402
from ..northfind.spec import median_time_s  # noqa: E402
from .cells import STAGES  # noqa: E402
from .spec import SweepSpec  # noqa: E402
from .store import CellStore  # noqa: E402
from .table import iter_rows  # noqa: E402

__all__ = ["write_figures", "axis_label"]

_UNITS = (("_deg_per_rth_h", "deg/sqrt(h)"), ("_dph", "deg/h"), ("_deg", "deg"),
          ("_c", "degC"), ("_s", "s"), ("_hz", "Hz"), ("_w_per_k", "W/K"),
          ("_j_per_k", "J/K"), ("_w", "W"), ("_g", "g"))


def axis_label(key: str) -> str:
    """An axis key with its unit from the name's suffix (``schedule.dwell_s`` ->
    ``schedule.dwell_s [s]``)."""
    last = key.rsplit(".", 1)[-1]
    for suffix, unit in _UNITS:
        if last.endswith(suffix):
            return f"{key} [{unit}]"
    return key


def _text(v: Any) -> str:
    """A short label of an axis value (a long list by its ends and its length)."""
    t = json.dumps(v, separators=(",", ":")) if isinstance(v, (list, tuple)) else f"{v}"
    if len(t) <= 24:
        return t
    if isinstance(v, (list, tuple)):
        return f"[{v[0]:g},{v[1]:g},...,{v[-1]:g}] ({len(v)})" if all(
            isinstance(x, (int, float)) for x in v) else f"{t[:18]}... ({len(v)})"
    return t[:21] + "..."


def _slug(key: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", key)


def _rms(values) -> float:
    """RMS of the finite values (NaN if none)."""
    v = [x for x in values if isinstance(x, float) and math.isfinite(x)]
    return math.sqrt(sum(x * x for x in v) / len(v)) if v else math.nan



def _save(fig, path: Path) -> Path:
    with atomic_output(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110, metadata={"Software": None})
    plt.close(fig)
    return path


def _collect(spec: SweepSpec, store: CellStore, keys: list[str]):
    """Per (method, stage): {axis key: [(x, rmse, floor, tts, tts_rmse)]}, one pass."""
    data: dict[tuple[str, str], dict[str, list]] = defaultdict(lambda: defaultdict(list))
    pairs = []
    grid = [a.key for a in spec.grid_axes]
    for row in iter_rows(spec, store):
        m = (row["method"], row["stage"])
        for k in keys:
            data[m][k].append((row[k], row["heading_rmse_deg"], row["floor_deg"],
                               row["time_to_spec_s"], row["time_to_spec_rmse_s"]))
        if len(grid) >= 2 and row["stage"] == "startup":
            pairs.append((row["method"], row[grid[0]], row[grid[1]], row["heading_rmse_deg"]))
    return data, pairs


def _positions(values: list, drawn: bool):
    """(x of a value, categories): numbers where they are, other values (lists, strings)
    at 0, 1, ... in order of appearance, with the categories for the tick labels."""
    if drawn or all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return float, None
    where: dict[str, int] = {}
    cats = []
    for v in values:
        k = json.dumps(v, sort_keys=True)
        if k not in where:
            where[k] = len(cats)
            cats.append(v)
    return (lambda v: float(where[json.dumps(v, sort_keys=True)])), cats


def _axis_figure(key: str, drawn: bool, series: dict, column: int, ylabel: str, title: str,
                 floor: bool, log: bool, agg=_rms, agg_name: str = "RMS"):
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    allv = [p[0] for pts in series.values() for p in pts]
    x_of, cats = _positions(allv, drawn)
    floor_done = False
    order = sorted(series, key=lambda m: (m[0] != "none", m[0],
                                          STAGES.index(m[1]) if m[1] else 0))
    for i, (method, stage) in enumerate(order):
        pts = series[(method, stage)]
        colour = f"C{i}"
        xs = [x_of(p[0]) for p in pts]
        ys = [p[column] for p in pts]
        ax.plot(xs, ys, ".", color=colour, alpha=0.25, ms=4)
        groups: dict[float, list] = defaultdict(list)
        for x, y in zip(xs, ys):
            groups[x].append(y)
        label = ("uncompensated" if method == "none" else method)
        label = f"{stage}, {label}" if stage else label
        if not drawn:
            gx = sorted(groups)
            ax.plot(gx, [agg(groups[x]) for x in gx], "-o", color=colour, ms=4,
                    label=label + f" ({agg_name} over runs)")
        else:
            ax.plot([], [], ".", color=colour, label=label)
        if floor and not floor_done:
            fl: dict[float, list] = defaultdict(list)
            for x, p in zip(xs, pts):
                fl[x].append(p[2])
            fx = sorted(fl)
            ax.plot(fx, [sum(fl[x]) / len(fl[x]) for x in fx], "k--", lw=1,
                    label="white-noise floor")
            floor_done = True
    if cats is not None:
        ax.set_xticks(range(len(cats)), [_text(c) for c in cats], rotation=20, fontsize=8)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel(axis_label(key))
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def write_figures(spec: SweepSpec, store: CellStore, folder: str | Path) -> list[Path]:
    """Write the summary figures into ``folder``; their paths."""
    folder = Path(folder)
    keys = [a.key for a in spec.axes]
    drawn = {a.key: a.drawn for a in spec.axes}
    if len(spec.scenario.start_temperatures_c) > 1 and "start_temperature_c" not in keys:
        keys.append("start_temperature_c")
        drawn["start_temperature_c"] = False
    if not keys:
        return []
    data, pairs = _collect(spec, store, keys)
    name = spec.scenario.name
    out = []
    for key in keys:
        series = {m: d[key] for m, d in data.items()}
        fig = _axis_figure(key, drawn[key], series, 1, "heading RMSE [deg]",
                           f"{name}: heading RMSE against {key}", True, True)
        out.append(_save(fig, folder / f"heading_rmse_vs_{_slug(key)}.png"))
        tts = {(m[0], ""): [(p[0], p[3] / 60.0) for p in pts]
               for m, pts in series.items() if m[1] == "startup"}   # one value per run
        never = sum(1 for pts in tts.values() for p in pts if p[1] == math.inf)
        fig = _axis_figure(key, drawn[key], tts, 1, "time to spec [min after power-on]",
                           f"{name}: time until every cycle stays within "
                           f"{spec.spec_deg:g} deg\n({never} start-up(s) never within "
                           f"spec, not drawn)", False, False, median_time_s, "median")
        out.append(_save(fig, folder / f"time_to_spec_vs_{_slug(key)}.png"))
    if pairs:
        a, b = spec.grid_axes[0].key, spec.grid_axes[1].key
        out.append(_save(_pair_figure(a, b, pairs, name), folder /
                         f"heading_rmse_{_slug(a)}_by_{_slug(b)}.png"))
    return out


def _pair_figure(a: str, b: str, pairs, name: str):
    """Start-up RMSE against axis ``a``, one line per value of axis ``b`` (and method)."""
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    x_of, cats = _positions([p[1] for p in pairs], False)
    lines: dict[tuple[str, str], dict[float, list]] = defaultdict(lambda: defaultdict(list))
    order: dict[str, int] = {}
    for method, va, vb, r in pairs:
        lines[(method, _text(vb))][x_of(va)].append(r)
        order.setdefault(_text(vb), len(order))          # the file's order of b's values
    keys = sorted(lines, key=lambda m: (m[0] != "none", m[0], order[m[1]]))
    for i, (method, vb) in enumerate(keys):
        pts = lines[(method, vb)]
        xs = sorted(pts)
        label = f"{b} = {vb}" + ("" if method == "none" else f", {method}")
        ax.plot(xs, [_rms(pts[x]) for x in xs], "-o", ms=4, color=f"C{i}", label=label)
    if cats is not None:
        ax.set_xticks(range(len(cats)), [_text(c) for c in cats], rotation=20, fontsize=8)
    ax.set_yscale("log")
    ax.set_xlabel(axis_label(a))
    ax.set_ylabel("start-up heading RMSE [deg] (RMS over runs)")
    ax.set_title(f"{name}: start-up stage, by {b}", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig
