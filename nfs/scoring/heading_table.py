"""The heading-RMSE table by start temperature (the FOG start-up paper, Table 3), as data.

Rows are methods (``before``: start-up, uncompensated; ``stable``: the stable stage;
``floor``: the white-noise limit of the schedule; the compensation study adds a row per
compensator and states the features mode they were computed in), columns are start
temperatures plus their mean.  Cells and means may carry 95 % intervals, and the table the
paired comparisons of its rows (:mod:`nfs.scoring.intervals`: a two-level bootstrap over the
start-ups and their cycles); a row that is not distinguishable from the best compensated row
is marked as tied with it.  The table serialises itself as Markdown, CSV and JSON;
:mod:`nfs.report.table_files` draws it and writes its files.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import Iterable, Sequence

import numpy as np

from ..docfields import document_fields
from .intervals import DEFAULT_N_BOOT, PairedComparison, cluster_bootstrap, compare_rows, json_number

__all__ = ["TableRow", "HeadingTable", "pooled_rmse", "REFERENCE_ROWS", "STAGE_ROWS",
           "UNCOMPENSATED_ROWS", "NOT_APPLICABLE", "STAGE_LABELS"]

_NAN2 = (math.nan, math.nan)

#: Rows of the uncompensated stages (:func:`nfs.studies.scenario_runs.stage_names`): the start-up,
#: the stable stage, or under a chamber program that moves, the cycles with the chamber held
#: after the start-up and those with it ramping.
STAGE_ROWS = ("before", "stable", "held", "ramping")
#: The reference rows of a table without a chamber program: the uncompensated start-up, the
#: stable stage, the floor (what a rerun of the same scenario must reproduce exactly).
REFERENCE_ROWS = ("before", "stable", "floor")
#: Rows that are not a compensator: the uncompensated stages and the white-noise floor.
UNCOMPENSATED_ROWS = STAGE_ROWS + ("floor",)
#: How the figure and the notes name each stage row.
STAGE_LABELS = {"before": "before (uncompensated start-up)",
                "stable": "stable stage (uncompensated)",
                "held": "chamber held, after the start-up (uncompensated)",
                "ramping": "chamber ramping (uncompensated)"}
#: What a Markdown or CSV cell holds where nothing applies (JSON: null).
NOT_APPLICABLE = "-"


def pooled_rmse(errors_deg: Iterable[np.ndarray]) -> float:
    """sqrt(mean(e^2)) over the finite errors of several runs pooled together [deg]."""
    e = np.concatenate([np.asarray(x, dtype=float).ravel() for x in errors_deg] or [[]])
    e = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(e * e))) if e.size else math.nan


@document_fields
@dataclass(frozen=True)
class TableRow:
    """One method's heading RMSE at each start temperature."""

    method: str
    """Row label (``before``, ``stable``, ``floor``, a compensator's name)."""
    rmse_deg: tuple[float, ...]
    """RMSE at each start temperature [deg]."""
    cell_ci_deg: tuple[tuple[float, float], ...] | None = None
    """95 % interval of each cell [deg] (None: not computed; ``floor`` has none)."""
    mean_ci_deg: tuple[float, float] | None = None
    """95 % interval of the mean [deg]."""
    seed_means_deg: tuple[float, ...] = ()
    """Mean of the row trained with each tuner seed [deg] (a tuned row shows the median
    seed's; empty for a row trained once)."""
    group: str = ""
    """Panel of the figure a compensated row is drawn in (methods of one paper, or of the
    other papers); empty for the reference rows ``before``, ``stable`` and ``floor``."""

    @property
    def mean_deg(self) -> float:
        """Mean over the temperatures (NaN-aware) [deg]."""
        v = np.asarray(self.rmse_deg, dtype=float)
        return float(np.nanmean(v)) if np.any(np.isfinite(v)) else math.nan

    @property
    def ci_low_deg(self) -> float:
        """Lower end of the mean's interval [deg] (NaN without one)."""
        return (self.mean_ci_deg or _NAN2)[0]

    @property
    def ci_high_deg(self) -> float:
        """Upper end of the mean's interval [deg] (NaN without one)."""
        return (self.mean_ci_deg or _NAN2)[1]


@document_fields
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
    comparisons: tuple[PairedComparison, ...] = ()
    """Paired comparisons of row means, Holm-adjusted together."""
    errors_deg: dict | None = field(default=None, compare=False)
    """Row name -> ``errors[column][start-up]``: the heading errors [deg] of the cycles
    behind each cell (set by :meth:`with_intervals`; kept in the JSON so that a later table
    can be compared with this one start-up by start-up, :mod:`nfs.scoring.baseline`)."""
    provenance: dict | None = field(default=None, compare=False)
    """What produced the table: versions, platform, scenario and instrument hashes, seeds
    (:func:`nfs.io.provenance.output_provenance`); None when not recorded."""

    @property
    def best(self) -> str | None:
        """The compensated row with the lowest mean (None without compensated rows)."""
        comp = [r for r in self.rows if r.method not in UNCOMPENSATED_ROWS
                and math.isfinite(r.mean_deg)]
        return min(comp, key=lambda r: r.mean_deg).method if comp else None

    def comparison(self, a: str, b: str) -> PairedComparison | None:
        """The comparison of rows a and b (as a - b; None if not made)."""
        for c in self.comparisons:
            if (c.method_a, c.method_b) == (a, b):
                return c
            if (c.method_a, c.method_b) == (b, a):
                return PairedComparison(a, b, -c.difference_deg, -c.ci_high_deg, -c.ci_low_deg,
                                  c.p_value, c.p_adjusted, c.alpha)
        return None

    def versus_best(self, method: str) -> str:
        """``best``, ``tie`` (not distinguishable from the best row), ``worse`` or ``''``
        (no comparison with the best row)."""
        best = self.best
        if best is None:
            return ""
        if method == best:
            return "best"
        c = self.comparison(method, best)
        if c is None:
            return ""
        return "worse" if c.distinguishable else "tie"

    def key_comparisons(self) -> list[PairedComparison]:
        """The comparisons that the text states: every row against ``before``, SSA-SVR (the
        method of the start-up experiment reproduced) against every other, and the best
        row against the runner-up."""
        names = [r.method for r in self.rows if r.method not in UNCOMPENSATED_ROWS]
        want = [(m, "before") for m in names]
        if "SSA-SVR" in names:
            want += [("SSA-SVR", m) for m in names if m != "SSA-SVR"]
        ranked = sorted((r for r in self.rows if r.method in names
                         and math.isfinite(r.mean_deg)), key=lambda r: r.mean_deg)
        if len(ranked) > 1:
            want.append((ranked[1].method, ranked[0].method))
        out, seen = [], set()
        for a, b in want:
            c = self.comparison(a, b)
            if c is not None and frozenset((a, b)) not in seen:
                seen.add(frozenset((a, b)))
                out.append(c)
        return out

    def with_intervals(self, errors_deg: dict, *, pairs=(), variants: dict | None = None,
                       n_boot: int = DEFAULT_N_BOOT, random_state: int = 0
                       ) -> "HeadingTable":
        """This table with 95 % intervals on the rows of ``errors_deg`` and comparisons.

        Parameters
        ----------
        errors_deg : dict
            Row name -> ``errors[column][start-up]``: the heading errors [deg] of the cycles
            behind each cell, one array per start-up; every row on the same start-ups
            (:func:`~nfs.scoring.intervals.cluster_bootstrap`).
        pairs : sequence of (str, str)
            Row pairs (a, b) to compare as a - b, Holm-adjusted together.
        variants : dict, optional
            Row name -> the errors of each of its trainings (e.g. tuner seeds), like
            ``errors_deg``'s; comparisons draw one per replicate, so they carry the spread
            of the trainings too (the row's own intervals are those of ``errors_deg``).
        n_boot, random_state : int
            Replicates and seed of the bootstrap.

        Returns
        -------
        HeadingTable
        """
        names = list(errors_deg)
        if not names:
            return self
        variants = variants or {}
        boot = cluster_bootstrap([errors_deg[n] for n in names],
                                 variants=[variants.get(n) for n in names], n_boot=n_boot,
                                 random_state=random_state)
        cells, means = boot.cell_intervals(), boot.row_intervals()
        ci = {n: (tuple((float(a), float(b)) for a, b in cells[i]),
                  (float(means[i][0]), float(means[i][1]))) for i, n in enumerate(names)}
        rows = tuple(dataclasses.replace(r, cell_ci_deg=ci[r.method][0],
                                         mean_ci_deg=ci[r.method][1])
                     if r.method in ci else r for r in self.rows)
        comps = tuple(compare_rows(boot, names, list(pairs)))
        kept = {n: [[np.asarray(c, dtype=float).ravel() for c in col] for col in errors_deg[n]]
                for n in names}
        return dataclasses.replace(self, rows=rows, comparisons=comps, errors_deg=kept)

    def row(self, method: str) -> TableRow:
        """The row of ``method`` (KeyError listing the rows if absent)."""
        for r in self.rows:
            if r.method == method:
                return r
        raise KeyError(f"no row '{method}'; rows: {', '.join(r.method for r in self.rows)}")

    def with_rows(self, rows: Sequence[TableRow], notes: Sequence[str] = (),
                  features_mode: str | None = None) -> "HeadingTable":
        """A table with ``rows`` inserted after ``before`` and before the other reference
        rows (``stable`` or ``held`` and ``ramping``, ``floor``).

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
        later = set(UNCOMPENSATED_ROWS) - {"before"}
        tail = [r for r in self.rows if r.method in later]
        head = [r for r in self.rows if r.method not in later]
        return dataclasses.replace(self, rows=tuple(head + list(rows) + tail),
                                   notes=self.notes + tuple(notes),
                                   features_mode=features_mode or self.features_mode)

    def _labels(self) -> list[str]:
        return [f"{t:g}" for t in self.temperatures_c]

    def _has_ci(self) -> bool:
        return any(r.mean_ci_deg is not None for r in self.rows)

    def to_markdown(self, digits: int = 4) -> str:
        """A Markdown table (``-`` where nothing applies): method, one column per T0, mean;
        with intervals also the mean's 95 % interval, the spread of the tuned rows over
        their seeds and the verdict against the best row; notes and the key comparisons
        below (cells' intervals: CSV, JSON)."""
        ci = self._has_ci()
        seeds = any(r.seed_means_deg for r in self.rows)
        head = ["method", *self._labels(), "mean"] + (["95 % CI"] if ci else []) + \
            (["seeds (min-max)"] if seeds else []) + (["vs best"] if self.comparisons else [])
        lines = ["| " + " | ".join(head) + " |",
                 "|" + "|".join(["---"] + ["---:"] * (len(head) - 1)) + "|"]
        for r in self.rows:
            cells = [_fmt(v, digits) for v in (*r.rmse_deg, r.mean_deg)]
            if ci:
                cells.append(f"[{_fmt(r.ci_low_deg, digits)}, {_fmt(r.ci_high_deg, digits)}]"
                             if math.isfinite(r.ci_low_deg) else "")
            if seeds:
                sm = r.seed_means_deg
                cells.append(f"{_fmt(min(sm), digits)}-{_fmt(max(sm), digits)} ({len(sm)})"
                             if sm else "")
            if self.comparisons:
                cells.append(self.versus_best(r.method))
            lines.append("| " + " | ".join([r.method, *cells]) + " |")
        text = "\n".join(lines) + "\n"
        if self.notes:
            text += "\n" + "\n".join(self.notes) + "\n"
        key = self.key_comparisons()
        if key:
            text += ("\nPaired comparisons of the means (difference, its 95 % interval, "
                     f"Holm-adjusted over the {len(self.comparisons)} comparisons made):\n\n"
                     + "".join(f"- {c.sentence(digits)}\n" for c in key))
        return text

    def to_csv(self) -> str:
        """CSV: header ``method,<T0>...,mean``, one line per row, values in deg (``-``
        where nothing applies: a stage without cycles at that start temperature).

        With intervals, then ``mean_ci_low,mean_ci_high``, ``<T0>_ci_low,<T0>_ci_high`` per
        start temperature, ``seeds_min,seeds_max,n_seeds`` (tuned rows) and ``vs_best``
        (empty where not computed).  With compensated rows, a last column ``features_mode``
        gives their mode (empty for ``before``, ``stable`` and ``floor``, which use no
        feature).
        """
        mode = self.features_mode
        ci = self._has_ci()
        labels = self._labels()
        head = ["method", *labels, "mean"]
        if ci:
            head += ["mean_ci_low", "mean_ci_high"]
            head += [f"{t}_ci_{e}" for t in labels for e in ("low", "high")]
            head += ["seeds_min", "seeds_max", "n_seeds", "vs_best"]
        lines = [",".join(head + (["features_mode"] if mode else []))]
        for r in self.rows:
            cells = [r.method, *(_fmt(v, 6) for v in (*r.rmse_deg, r.mean_deg))]
            if ci:
                cells += ["" if r.mean_ci_deg is None else _fmt(v, 6) for v in
                          (r.ci_low_deg, r.ci_high_deg)]
                cells += ([_fmt(v, 6) for lo_hi in r.cell_ci_deg for v in lo_hi]
                          if r.cell_ci_deg else [""] * (2 * len(labels)))
                sm = r.seed_means_deg
                cells += ([_fmt(min(sm), 6), _fmt(max(sm), 6), str(len(sm))] if sm
                          else ["", "", ""])
                cells.append(self.versus_best(r.method))
            if mode:
                cells.append("" if r.method in UNCOMPENSATED_ROWS else mode)
            lines.append(",".join(cells))
        return "\n".join(lines) + "\n"

    def to_dict(self) -> dict:
        """The JSON form: ``{"temperatures_c": [...], "features_mode": ..., "best": ...,
        "rows": [{"method", "rmse_deg", "mean_deg", "ci_low_deg", "ci_high_deg",
        "cell_ci_deg": [[low, high], ...], "seed_means_deg": [...], "vs_best"}, ...],
        "comparisons": [{"method_a", "method_b", "difference_deg", "ci_low_deg",
        "ci_high_deg", "p_value", "p_adjusted", "distinguishable"}, ...], "notes": [...],
        "errors_deg": {row: [[[cycle errors of start-up k] for k] for column]},
        "provenance": {...}}`` (NaN as null; ``features_mode`` null without compensated rows;
        intervals null where not computed; ``errors_deg`` rounded to 1e-9 deg, empty without
        intervals; ``provenance`` null when not recorded)."""
        return {
            "temperatures_c": [float(t) for t in self.temperatures_c],
            "features_mode": self.features_mode,
            "best": self.best,
            "rows": [{"method": r.method, "rmse_deg": [json_number(v, 8) for v in r.rmse_deg],
                      "mean_deg": json_number(r.mean_deg, 8),
                      "ci_low_deg": json_number(r.ci_low_deg, 8),
                      "ci_high_deg": json_number(r.ci_high_deg, 8),
                      "cell_ci_deg": None if r.cell_ci_deg is None else
                      [[json_number(a, 8), json_number(b, 8)] for a, b in r.cell_ci_deg],
                      "seed_means_deg": [json_number(v, 8) for v in r.seed_means_deg],
                      "group": r.group or None,
                      "vs_best": self.versus_best(r.method) or None} for r in self.rows],
            "comparisons": [c.to_dict() for c in self.comparisons],
            "notes": list(self.notes),
            "errors_deg": {n: [[[json_number(v, 9) for v in c] for c in col] for col in errs]
                           for n, errs in (self.errors_deg or {}).items()},
            "provenance": self.provenance,
        }

    def to_json(self) -> str:
        """:meth:`to_dict` as indented JSON text, each row's cycle errors on one line (the
        file stays small and readable)."""
        d = self.to_dict()
        errs = d["errors_deg"]
        d["errors_deg"] = {n: f"\0{n}\0" for n in errs}
        text = json.dumps(d, indent=2)
        for n, e in errs.items():
            text = text.replace(json.dumps(f"\0{n}\0"), json.dumps(e, separators=(",", ":")),
                                1)
        return text + "\n"


def _fmt(v: float, digits: int) -> str:
    """A number of the Markdown and CSV tables; ``-`` where nothing applies (a stage without
    cycles, as the papers print it)."""
    return NOT_APPLICABLE if not math.isfinite(v) else f"{v:.{digits}f}"
