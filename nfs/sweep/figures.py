"""Summary figures of a sweep: heading RMSE (and time to spec) against each axis.

One PNG per axis (and per start temperature when the scenario has several): every run's
stage RMSE as a faint point, the RMS over the runs at each grid value as a line, one colour
per method and stage, and the white-noise floor of the cell's schedule and latitude as a
dashed line (it follows 1 / cos L on a latitude axis).  A figure pools only runs that share
a floor: the runs of other axes' values that move the floor (a latitude, a dwell, an ARW
against the start temperature) go to a panel each, its floor labelled with the values that
set it (``white-noise floor, latitude_deg = 30``); beyond :data:`MAX_PANELS` floors, each
run's RMSE is set over its own cell's floor.  A second PNG per axis gives the time to spec
of every run (the median over the runs as a line), in the same panels.  With two grid axes
or more, one more figure sets the first against the second (start-up stage).  Figures are
made without pyplot (no display needed), legends outside the data; written atomically.
"""

from __future__ import annotations

import json
import math
import re
from collections import defaultdict
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from ..io.atomic import atomic_output
from ..northfind.time_to_spec import median_time_s
from .keys import STAGES
from .definition import SweepSpec
from .store import CellStore
from .results_table import iter_rows

__all__ = ["write_figures", "sweep_figures", "floor_groups", "axis_label", "MAX_PANELS"]

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



def _save(fig: Figure, path: Path) -> Path:
    with atomic_output(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110, metadata={"Software": None})
    return path


#: Most panels of one figure, one per white-noise floor; a sweep with more floors along an
#: axis sets each run's RMSE against its own cell's floor instead.
MAX_PANELS = 4


def _collect(spec: SweepSpec, store: CellStore, keys: list[str]):
    """Every row's plotted fields (one pass over the cells) and the start-up pairs of the
    first two grid axes."""
    points = []
    pairs = []
    grid = [a.key for a in spec.grid_axes]
    for row in iter_rows(spec, store):
        points.append({"method": row["method"], "stage": row["stage"],
                       "values": {k: row[k] for k in keys},
                       "rmse": row["heading_rmse_deg"], "floor": row["floor_deg"],
                       "tts": row["time_to_spec_s"]})
        if len(grid) >= 2 and row["stage"] == "startup":
            pairs.append((row["method"], row[grid[0]], row[grid[1]], row["heading_rmse_deg"]))
    return points, pairs


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


def _same(v: float) -> str:
    """A floor as the key it is grouped by (NaN: no closed form)."""
    return "nan" if not math.isfinite(v) else f"{v:.12g}"


def floor_groups(points: list[dict], key: str) -> list[tuple[str, list[dict]]]:
    """The points of a figure against ``key`` split so that each group shares one
    white-noise floor at every value of ``key``: (label, points) per group, in order of
    appearance.

    Points are first told apart by the values of the other axes; those whose floor is the
    same function of ``key`` are pooled again (a start temperature, a soak time leave the
    floor alone; a latitude, a dwell, an ARW move it).  The label names the other axes whose
    value sets a group apart (``latitude_deg = 30``); empty for a single group.
    """
    by_point: dict[tuple, list[dict]] = defaultdict(list)
    for p in points:
        by_point[tuple((k, _text(v)) for k, v in p["values"].items() if k != key)].append(p)
    merged: dict[tuple, list[tuple]] = {}
    for g, pts in by_point.items():
        sig = tuple(sorted({(_text(p["values"][key]), _same(p["floor"])) for p in pts}))
        merged.setdefault(sig, []).append(g)
    if len(merged) == 1:
        return [("", points)]
    groups = list(merged.values())
    others = [k for k, _ in next(iter(by_point))]
    # an axis names the groups when each holds one value of it and the groups differ by it
    values = [[{dict(g)[k] for g in gs} for k in others] for gs in groups]
    named = [k for i, k in enumerate(others)
             if all(len(v[i]) == 1 for v in values) and len({min(v[i]) for v in values}) > 1]
    out = []
    for n, (gs, v) in enumerate(zip(groups, values)):
        label = ", ".join(f"{k} = {min(v[others.index(k)])}" for k in named) or \
            f"floor group {n + 1}"
        out.append((label, [p for g in gs for p in by_point[g]]))
    return out


def _series(points: list[dict], x_of, field: str) -> dict[tuple[str, str], list]:
    """(method, stage) -> [(x, value)] in a plotting order: uncompensated first."""
    out: dict[tuple[str, str], list] = defaultdict(list)
    for p in points:
        out[(p["method"], p["stage"])].append((x_of(p["x"]), p[field]))
    return dict(sorted(out.items(), key=lambda kv: (
        kv[0][0] != "none", kv[0][0], STAGES.index(kv[0][1]) if kv[0][1] else 0)))


def _stage_label(method: str, stage: str) -> str:
    who = "uncompensated" if method == "none" else method
    return f"{'start-up' if stage == 'startup' else stage}, {who}" if stage else who


def _axis_figure(key: str, drawn: bool, points: list[dict], field: str, ylabel: str,
                 title: str, floor: bool, log: bool, agg=None, agg_name: str = "RMS", *,
                 floor_line: bool = True):
    """One panel per white-noise floor (:func:`floor_groups`; ``floor``): each run's value
    as a faint point, the ``agg`` over the runs at each grid value as a line, one colour per
    method and stage, and (``floor_line``) the panel's white-noise floor as a dashed line
    labelled with the axes that set it.  More floors than :data:`MAX_PANELS`: with a floor
    line, each run's value over its own cell's floor in one panel, against the floor's line
    at 1; without, one panel that says how many floors it pools."""
    agg = agg or _rms
    pts = [dict(p, x=p["values"][key]) for p in points]
    x_of, cats = _positions([p["x"] for p in pts], drawn)
    groups = floor_groups(pts, key) if floor else [("", pts)]
    ratio = floor_line and len(groups) > MAX_PANELS
    pooled = len(groups) if len(groups) > MAX_PANELS else 0
    if pooled:
        if ratio:
            pts = [dict(p, **{field: p[field] / p["floor"]}) for p in pts]
            ylabel = "heading RMSE / white-noise floor of its cell"
        groups = [("", pts)]
    names = list(_series(pts, x_of, field))          # one colour per method and stage
    fig = Figure(figsize=(1.2 + 4.2 * len(groups) + 2.6, 4.4), dpi=110,
                 layout="constrained")
    axes = fig.subplots(1, len(groups), sharey=True, squeeze=False)[0]
    for ax, (label, gpts) in zip(axes, groups):
        for (method, stage), xy in _series(gpts, x_of, field).items():
            colour = f"C{names.index((method, stage))}"
            xs, ys = [x for x, _ in xy], [y for _, y in xy]
            ax.plot(xs, ys, ".", color=colour, alpha=0.25, ms=4)
            lab = _stage_label(method, stage)
            if drawn:
                ax.plot([], [], ".", color=colour, label=f"{lab} (each run)")
                continue
            at: dict[float, list] = defaultdict(list)
            for x, y in xy:
                at[x].append(y)
            gx = sorted(at)
            ax.plot(gx, [agg(at[x]) for x in gx], "-o", color=colour, ms=4,
                    label=f"{lab} ({agg_name} over runs)")
        if ratio:
            ax.axhline(1.0, color="k", ls="--", lw=1,
                       label="white-noise floor of each run's cell (= 1)")
        elif floor_line:
            fl: dict[float, list] = defaultdict(list)
            for p in gpts:
                fl[x_of(p["x"])].append(p["floor"])
            fx = sorted(fl)
            fy = [sum(fl[x]) / len(fl[x]) for x in fx]
            flat = all(_same(v) == _same(fy[0]) for v in fy)
            ax.plot(fx, fy, "k--", lw=1,
                    label="white-noise floor" + (f", {label}" if label else "")
                    + (f" ({fy[0]:.4f} deg)" if flat and math.isfinite(fy[0]) else ""))
        if label:
            ax.set_title(label, fontsize=9)
        if cats is not None:
            ax.set_xticks(range(len(cats)), [_text(c) for c in cats], rotation=20,
                          fontsize=8)
        if log:
            ax.set_yscale("log")
        else:
            ax.set_ylim(bottom=0.0)                 # a time after power-on starts at 0
        ax.set_xlabel(axis_label(key))
        ax.grid(True, which="both", alpha=0.3)
        if len(groups) > 1:
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.16),
                      frameon=False)
    axes[0].set_ylabel(ylabel)
    if len(groups) == 1:
        axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
                       frameon=False)
    fig.suptitle(title + (f"\n({len(groups)} white-noise floors: one panel each)"
                          if len(groups) > 1 else
                          f"\n({pooled} white-noise floors: each run over its own cell's)"
                          if ratio else f"\n(runs of {pooled} white-noise floors pooled)"
                          if pooled else ""), fontsize=10)
    return fig


def write_figures(spec: SweepSpec, store: CellStore, folder: str | Path) -> list[Path]:
    """Write the summary figures into ``folder``; their paths."""
    folder = Path(folder)
    out = []
    for name, fig in sweep_figures(spec, store).items():
        out.append(_save(fig, folder / name))
    return out


def sweep_figures(spec: SweepSpec, store: CellStore) -> dict[str, Figure]:
    """The summary figures of a sweep (module docstring), {file name: figure}."""
    keys = [a.key for a in spec.axes]
    drawn = {a.key: a.drawn for a in spec.axes}
    if len(spec.scenario.start_temperatures_c) > 1 and "start_temperature_c" not in keys:
        keys.append("start_temperature_c")
        drawn["start_temperature_c"] = False
    if not keys:
        return {}
    points, pairs = _collect(spec, store, keys)
    name = spec.scenario.name
    out = {}
    for key in keys:
        out[f"heading_rmse_vs_{_slug(key)}.png"] = _axis_figure(
            key, drawn[key], points, "rmse", "heading RMSE [deg]",
            f"{name}: heading RMSE against {key}", True, True)
        tts = [dict(p, stage="", tts=p["tts"] / 60.0) for p in points
               if p["stage"] == "startup"]                   # one value per run
        never = sum(1 for p in tts if p["tts"] == math.inf)
        out[f"time_to_spec_vs_{_slug(key)}.png"] = _axis_figure(
            key, drawn[key], tts, "tts", "time to spec [min after power-on]",
            f"{name}: time until every cycle stays within {spec.spec_deg:g} deg "
            f"({never} start-up(s) never within spec, not drawn)", True, False,
            median_time_s, "median", floor_line=False)
    if pairs:
        a, b = spec.grid_axes[0].key, spec.grid_axes[1].key
        out[f"heading_rmse_{_slug(a)}_by_{_slug(b)}.png"] = _pair_figure(a, b, pairs, name)
    return out


def _pair_figure(a: str, b: str, pairs, name: str):
    """Start-up RMSE against axis ``a``, one line per value of axis ``b`` (and method)."""
    fig = Figure(figsize=(8.6, 4.4), dpi=110, layout="constrained")
    ax = fig.subplots()
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
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    return fig
