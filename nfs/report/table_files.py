"""The heading-RMSE table's figure (a bar chart with error bars) and its files: Markdown, CSV,
JSON and PNG, every file atomically."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_bytes, atomic_write_text
from ..scoring.heading_table import (STAGE_LABELS, STAGE_ROWS, UNCOMPENSATED_ROWS, HeadingTable,
                                     TableRow)

__all__ = ["plot_heading_table", "write_table"]


#: Bar colour and hatch of each stage row: greys, apart from the compensated rows' hues.
_STAGE_STYLE = {"before": ("0.3", None), "stable": ("0.75", None), "held": ("0.75", None),
                "ramping": ("0.55", "..")}


def plot_heading_table(table: HeadingTable, title: str = ""):
    """Heading RMSE by start temperature as grouped bars, one panel per group of rows.

    Each panel holds the uncompensated stage rows (``before``, ``stable``, or ``held`` and
    ``ramping`` under a chamber program; greys) beside at most seven compensated rows of one
    group (:attr:`TableRow.group`), in colours far apart (a 14-row table in one panel needs
    near-identical colours); the white-noise ``floor`` is a dashed line. Bars start from zero
    and carry their 95 % intervals when computed; the legend, which names them, stands
    beside each panel, never over its bars.  Returns a matplotlib Figure (made without
    pyplot, so no display is needed).
    """
    from matplotlib import colormaps
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    refs = [r for r in table.rows if r.method in STAGE_ROWS]   # in every panel
    methods = [r for r in table.rows if r.method not in UNCOMPENSATED_ROWS]
    groups: dict[str, list[TableRow]] = {}
    for r in methods:
        groups.setdefault(r.group or "compensated", []).append(r)
    panels = list(groups.items()) or [("", [])]
    floor = next((r for r in table.rows if r.method == "floor"), None)
    # tab10 without its grey: seven hues that stay apart in print and for most colour vision
    hues = [c for j, c in enumerate(colormaps["tab10"].colors) if j != 7]
    fig = Figure(figsize=(11.0, 1.0 + 3.4 * len(panels)), dpi=110, layout="constrained")
    axes = fig.subplots(len(panels), 1, squeeze=False, sharey=True)[:, 0]
    x = np.arange(len(table.temperatures_c))
    with_ci = False
    for ax, (name, rows) in zip(axes, panels):
        drawn = refs + rows
        width = 0.84 / max(1, len(drawn))
        k = 0
        for i, r in enumerate(drawn):
            if r.method in _STAGE_STYLE:
                color, hatch = _STAGE_STYLE[r.method]
            else:
                color, hatch, k = hues[k % len(hues)], ("//" if k >= len(hues) else None), k + 1
            yerr = None
            if r.cell_ci_deg is not None:
                with_ci = True
                v = np.asarray(r.rmse_deg, dtype=float)
                lo_hi = np.asarray(r.cell_ci_deg, dtype=float)
                yerr = np.nan_to_num(np.vstack([v - lo_hi[:, 0], lo_hi[:, 1] - v]).clip(0.0))
            label = STAGE_LABELS.get(r.method, r.method)
            ax.bar(x - 0.42 + width * (i + 0.5), r.rmse_deg, width, label=label, color=color,
                   hatch=hatch, yerr=yerr,
                   error_kw={"elinewidth": 0.6, "capsize": 0.0, "ecolor": "0.15"})
        if floor is not None:
            ax.axhline(floor.mean_deg, color="k", ls="--", lw=1.0,
                       label=f"white-noise floor ({floor.mean_deg:.4f} deg)")
        ax.set_xticks(x, [f"{t:g}" for t in table.temperatures_c])
        ax.set_ylabel("heading RMSE [deg]")
        ax.set_ylim(bottom=0.0)
        if name:
            ax.set_title(name, fontsize=9, loc="left")
        ax.grid(axis="y", alpha=0.3)
        handles, labels = ax.get_legend_handles_labels()
        if with_ci:                      # the error bars, named once in every legend
            handles.append(Line2D([], [], color="0.15", ls="none", marker="|", ms=10,
                                  mew=0.8))
            labels.append("95 % interval of each cell\n(two-level bootstrap)")
        # beside the panel, never over its bars
        ax.legend(handles, labels, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                  frameon=False)
    axes[-1].set_xlabel("start temperature T0 [degC]")
    title = title or "North-finding heading RMSE by start temperature"
    if table.features_mode:
        title += f" (features: {table.features_mode})"
    fig.suptitle(title, fontsize=10)
    return fig


def write_table(table: HeadingTable, out_dir: str | Path, *, stem: str = "heading_rmse",
                json_path: str | Path | None = None, title: str = "") -> list[Path]:
    """Write ``stem``.md, .csv, .json and .png into ``out_dir`` (and the JSON also to
    ``json_path`` if given), each atomically.  Returns the paths written."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{stem}.md", out / f"{stem}.csv", out / f"{stem}.json", out / f"{stem}.png"]
    buf = io.BytesIO()
    # Metadata pinned so that the same table gives the same PNG bytes.
    plot_heading_table(table, title).savefig(buf, format="png", metadata={"Software": None})
    atomic_write_text(paths[0], table.to_markdown())
    atomic_write_text(paths[1], table.to_csv())
    atomic_write_text(paths[2], table.to_json())
    atomic_write_bytes(paths[3], buf.getvalue())
    if json_path is not None:
        atomic_write_text(json_path, table.to_json())
        paths.append(Path(json_path))
    return paths
