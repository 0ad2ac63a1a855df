"""The heading-RMSE table by start temperature (seed 004, Table 3) and its outputs.

Rows are methods (``before``: start-up, uncompensated; ``stable``: the stable stage;
``floor``: the white-noise limit of the schedule; the compensation study adds a row per
compensator and states the features mode they were computed in), columns are start
temperatures plus their mean.  Written as Markdown, CSV, JSON and a PNG
bar chart, every file atomically.
"""

from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from ..io.atomic import atomic_write_bytes, atomic_write_text

__all__ = ["TableRow", "HeadingTable", "pooled_rmse", "write_table", "plot_heading_table",
           "REFERENCE_ROWS"]

#: Rows that are not a compensator: the uncompensated start-up, the stable stage, the floor.
REFERENCE_ROWS = ("before", "stable", "floor")


def pooled_rmse(errors_deg: Iterable[np.ndarray]) -> float:
    """sqrt(mean(e^2)) over the finite errors of several runs pooled together [deg]."""
    e = np.concatenate([np.asarray(x, dtype=float).ravel() for x in errors_deg] or [[]])
    e = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(e * e))) if e.size else math.nan


@dataclass(frozen=True)
class TableRow:
    """One method's heading RMSE at each start temperature."""

    method: str
    """Row label (``before``, ``stable``, ``floor``, a compensator's name)."""
    rmse_deg: tuple[float, ...]
    """RMSE at each start temperature [deg]."""

    @property
    def mean_deg(self) -> float:
        """Mean over the temperatures (NaN-aware) [deg]."""
        v = np.asarray(self.rmse_deg, dtype=float)
        return float(np.nanmean(v)) if np.any(np.isfinite(v)) else math.nan


@dataclass(frozen=True)
class HeadingTable:
    """Heading RMSE by start temperature and method."""

    temperatures_c: tuple[float, ...]
    """Start temperatures T0 [degC], the columns."""
    rows: tuple[TableRow, ...]
    """The rows, in display order."""
    notes: tuple[str, ...] = field(default_factory=tuple)
    """Lines printed under the table (what each row means, budgets, seeds)."""
    features_mode: str | None = None
    """What the compensated rows' features could use: ``cycle``, ``causal`` or ``offline``
    (:mod:`nfs.compensate.modes`); None when the table has no compensated row."""

    def row(self, method: str) -> TableRow:
        """The row of ``method`` (KeyError listing the rows if absent)."""
        for r in self.rows:
            if r.method == method:
                return r
        raise KeyError(f"no row '{method}'; rows: {', '.join(r.method for r in self.rows)}")

    def with_rows(self, rows: Sequence[TableRow], notes: Sequence[str] = (),
                  features_mode: str | None = None) -> "HeadingTable":
        """A table with ``rows`` inserted before ``stable`` and ``floor``.

        Parameters
        ----------
        rows : sequence of TableRow
            The compensated rows.
        notes : sequence of str
            Lines added under the table.
        features_mode : str, optional
            The features mode of the compensated rows (kept from this table when None).

        Returns
        -------
        HeadingTable
        """
        tail = [r for r in self.rows if r.method in ("stable", "floor")]
        head = [r for r in self.rows if r.method not in ("stable", "floor")]
        return HeadingTable(self.temperatures_c, tuple(head + list(rows) + tail),
                            self.notes + tuple(notes), features_mode or self.features_mode)

    def _labels(self) -> list[str]:
        return [f"{t:g}" for t in self.temperatures_c]

    def to_markdown(self, digits: int = 4) -> str:
        """A Markdown table: method, one column per T0, mean; notes below."""
        head = ["method", *self._labels(), "mean"]
        lines = ["| " + " | ".join(head) + " |",
                 "|" + "|".join(["---"] + ["---:"] * (len(head) - 1)) + "|"]
        for r in self.rows:
            cells = [_fmt(v, digits) for v in (*r.rmse_deg, r.mean_deg)]
            lines.append("| " + " | ".join([r.method, *cells]) + " |")
        text = "\n".join(lines) + "\n"
        if self.notes:
            text += "\n" + "\n".join(self.notes) + "\n"
        return text

    def to_csv(self) -> str:
        """CSV: header ``method,<T0>...,mean``, one line per row, values in deg.

        With compensated rows, a last column ``features_mode`` gives their mode (empty for
        ``before``, ``stable`` and ``floor``, which use no feature).
        """
        mode = self.features_mode
        lines = [",".join(["method", *self._labels(), "mean"]
                          + (["features_mode"] if mode else []))]
        for r in self.rows:
            cells = [r.method, *(_fmt(v, 6) for v in (*r.rmse_deg, r.mean_deg))]
            if mode:
                cells.append("" if r.method in REFERENCE_ROWS else mode)
            lines.append(",".join(cells))
        return "\n".join(lines) + "\n"

    def to_dict(self) -> dict:
        """The JSON form: ``{"temperatures_c": [...], "features_mode": ..., "rows":
        [{"method", "rmse_deg", "mean_deg"}, ...], "notes": [...]}`` (NaN as null;
        ``features_mode`` null without compensated rows)."""
        return {
            "temperatures_c": [float(t) for t in self.temperatures_c],
            "features_mode": self.features_mode,
            "rows": [{"method": r.method, "rmse_deg": [_json(v) for v in r.rmse_deg],
                      "mean_deg": _json(r.mean_deg)} for r in self.rows],
            "notes": list(self.notes),
        }

    def to_json(self) -> str:
        """:meth:`to_dict` as indented JSON text."""
        return json.dumps(self.to_dict(), indent=2) + "\n"


def _fmt(v: float, digits: int) -> str:
    return "nan" if not math.isfinite(v) else f"{v:.{digits}f}"


def _json(v: float):
    return None if not math.isfinite(v) else round(float(v), 8)


def plot_heading_table(table: HeadingTable, title: str = ""):
    """A grouped bar chart of heading RMSE by start temperature; ``floor`` as a dashed line.

    Returns a matplotlib Figure (made without pyplot, so no display is needed).
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.0, 4.5), dpi=110)
    ax = fig.add_subplot(111)
    bars = [r for r in table.rows if r.method != "floor"]
    x = np.arange(len(table.temperatures_c))
    width = 0.8 / max(1, len(bars))
    # Enough distinct colours for every method (the default cycle repeats after 10);
    # the reference rows in greys.
    import matplotlib
    tab20 = matplotlib.colormaps["tab20"].colors
    palette = [c for j, c in enumerate(tab20[0::2] + tab20[1::2]) if j not in (7, 17)]  # no greys
    fixed = {"before": "0.25", "stable": "0.7"}
    k = 0
    for i, r in enumerate(bars):
        color = fixed.get(r.method)
        if color is None:
            color, k = palette[k % len(palette)], k + 1
        ax.bar(x - 0.4 + width * (i + 0.5), r.rmse_deg, width, label=r.method, color=color)
    for r in table.rows:
        if r.method == "floor":
            ax.axhline(r.mean_deg, color="k", ls="--", lw=1.0, label="white-noise floor")
    ax.set_xticks(x, [f"{t:g}" for t in table.temperatures_c])
    ax.set_xlabel("start temperature T0 [degC]")
    ax.set_ylabel("heading RMSE [deg]")
    title = title or "North-finding heading RMSE by start temperature"
    if table.features_mode:
        title += f" (features: {table.features_mode})"
    ax.set_title(title)
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
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
