"""A heading table set beside an earlier one (a baseline): the change of every cell, beyond noise?

The question of a regression test: did a change (of the code, the instrument, the settings)
make the table worse, or is the difference what another draw of the same start-ups would
give?  Every cell (method x start temperature, and each method's mean over the start
temperatures both tables have) gets

    change = RMSE_new - RMSE_baseline   [deg]

with its 95 % interval from the two-level bootstrap of :mod:`nfs.scoring.intervals` (Davison &
Hinkley 1997, section 3.8: start-ups resampled, then their cycles), and a verdict:

* ``worse``: the interval lies above 0 (beyond noise) *and* the change exceeds
  ``tolerance`` x the baseline's RMSE (a relative tolerance, default 5 %);
* ``better``: the mirror image (interval below 0, change below -tolerance x baseline);
* ``within noise``: anything else (a change inside the noise, or beyond it but smaller than
  the tolerance).

Paired or unpaired.  When both tables come from the same test start-ups (the same seed of
the test start-ups and the same number of start-ups at every start temperature), the two
tables' errors are resampled with the same draws: the same start-ups and the same cycle
slots in both (common random numbers), so the interval holds only what changed, and two
identical tables differ by exactly 0.  Otherwise the two tables are resampled independently
and the interval holds the noise of both.  A row without cycle errors (the white-noise
``floor``, computed in closed form; a table written without intervals) counts as exact on its
side.

A tuned row is compared through the training the table shows (its median tuner seed); the
spread of its tuner seeds is not part of the interval here.

The baseline's provenance (:func:`nfs.io.provenance.output_provenance`) is set beside the new
table's: another scenario, instrument, package version, library versions or platform does not
stop the comparison; each is said in one line.

This module holds the statistics and the result as data (its JSON included); the Markdown
and the files are rendered by :mod:`nfs.report.baseline`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np

from ..docfields import document_fields
from ..errors import InputError
from .intervals import DEFAULT_N_BOOT, bc_interval, cluster_bootstrap, finite_mean, json_number
from .tablefile import TableData, check_common, common_columns, read_table

__all__ = ["TOLERANCE", "CellChange", "BaselineComparison", "compare_tables"]

#: Default relative tolerance of the verdict ``worse`` (5 % of the baseline's RMSE).
TOLERANCE = 0.05


@document_fields
@dataclass(frozen=True)
class CellChange:
    """The change of one cell against the baseline."""

    method: str
    """Row."""
    temperature_c: float | None
    """Start temperature of the cell [degC]; None for the row's mean over the compared
    start temperatures."""
    baseline_deg: float
    """The baseline's RMSE [deg]."""
    new_deg: float
    """The new table's RMSE [deg]."""
    change_deg: float
    """new - baseline [deg]."""
    ci_low_deg: float
    ci_high_deg: float
    """95 % interval of the change (bias-corrected percentile, two-level bootstrap) [deg]."""
    verdict: str
    """``better``, ``within noise``, ``worse``, or ``n/a`` (a cell without a value)."""

    @property
    def column(self) -> str:
        """The column's label: the start temperature (``-32``) or ``mean``."""
        return "mean" if self.temperature_c is None else f"{self.temperature_c:g}"

    @property
    def relative(self) -> float:
        """change / baseline (NaN when the baseline is 0 or missing)."""
        if not (math.isfinite(self.change_deg) and self.baseline_deg):
            return math.nan
        return self.change_deg / abs(self.baseline_deg)

    def label(self) -> str:
        """E.g. ``SSA-SVR at -32 C`` or ``SSA-SVR (mean)``."""
        return (f"{self.method} (mean)" if self.temperature_c is None
                else f"{self.method} at {self.temperature_c:g} C")

    def to_dict(self) -> dict:
        """JSON form (NaN as null)."""
        return {"method": self.method, "temperature_c": self.temperature_c,
                "baseline_deg": json_number(self.baseline_deg, 9),
                "new_deg": json_number(self.new_deg, 9),
                "change_deg": json_number(self.change_deg, 9),
                "change_pct": json_number(100.0 * self.relative, 4),
                "ci_low_deg": json_number(self.ci_low_deg, 9),
                "ci_high_deg": json_number(self.ci_high_deg, 9),
                "verdict": self.verdict}


@document_fields
@dataclass(frozen=True)
class BaselineComparison:
    """Every cell of a heading table set beside a baseline table."""

    methods: tuple[str, ...]
    """Rows compared (in the new table's order)."""
    temperatures_c: tuple[float, ...]
    """Start temperatures compared [degC]."""
    cells: tuple[CellChange, ...]
    """Each method's cells, then its mean, method by method."""
    tolerance: float
    """Relative tolerance of the verdicts."""
    paired: bool
    """True when the tables were resampled over the same test start-ups."""
    notes: tuple[str, ...]
    """One line each: pairing, what differs in the provenance, what was left out."""
    baseline: str = ""
    """Where the baseline was read from."""
    provenance: dict | None = None
    """The new table's provenance."""
    baseline_provenance: dict | None = None
    """The baseline's provenance."""

    @property
    def worse(self) -> list[CellChange]:
        """The cells worse beyond both the noise and the tolerance."""
        return [c for c in self.cells if c.verdict == "worse"]

    @property
    def exit_code(self) -> int:
        """1 when a cell is worse beyond noise and tolerance, 0 otherwise."""
        return 1 if self.worse else 0

    def summary(self) -> str:
        """One line, e.g. ``3 cells worse beyond noise and 5 %: SSA-SVR at -32 C, ...``."""
        tol = f"{100.0 * self.tolerance:g} %"
        worse = self.worse
        if worse:
            n = len(worse)
            return (f"{n} cell{'s' if n > 1 else ''} worse beyond noise and {tol}: "
                    + ", ".join(c.label() for c in worse))
        counts = {v: sum(c.verdict == v for c in self.cells)
                  for v in ("better", "within noise", "n/a")}
        return (f"no cell worse beyond noise and {tol} ({len(self.cells)} cells: "
                f"{counts['better']} better, {counts['within noise']} within noise"
                + (f", {counts['n/a']} without a value" if counts["n/a"] else "") + ")")

    def to_dict(self) -> dict:
        """JSON form: tolerance, pairing, baseline, the compared rows and temperatures,
        every cell with its change, interval and verdict, the worse cells, notes, summary and
        both tables' provenance."""
        return {"baseline": self.baseline, "tolerance": self.tolerance,
                "paired": self.paired, "methods": list(self.methods),
                "temperatures_c": list(self.temperatures_c),
                "cells": [c.to_dict() for c in self.cells],
                "worse": [c.label() for c in self.worse],
                "notes": list(self.notes), "summary": self.summary(),
                "provenance": self.provenance,
                "baseline_provenance": self.baseline_provenance}

    def to_json(self) -> str:
        """:meth:`to_dict` as indented JSON text."""
        return json.dumps(self.to_dict(), indent=1) + "\n"


def compare_tables(table, baseline, *, tolerance: float = TOLERANCE,
                   n_boot: int = DEFAULT_N_BOOT, random_state: int = 0,
                   paired: bool | None = None) -> BaselineComparison:
    """Compare every cell of ``table`` with ``baseline`` (see the module docstring).

    Parameters
    ----------
    table, baseline : HeadingTable, dict, path or TableData
        The new table and the baseline (a JSON file of ``nfs table --json``, its dict, or a
        table).
    tolerance : float
        Relative tolerance of the verdicts (0.05: a cell is ``worse`` only when it is more
        than 5 % above the baseline, beyond noise).
    n_boot, random_state : int
        Replicates and seed of the bootstrap.
    paired : bool, optional
        Whether both tables rest on the same start-ups (None: decided from their
        provenance, the seed of the test start-ups, and their numbers of start-ups; True:
        given, e.g. the same runs with and without a compensator, and the provenance is not
        checked).

    Returns
    -------
    BaselineComparison

    Raises
    ------
    InputError
        Bad input: not a table, no start temperature or row in common, a bad tolerance.
    """
    if not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance)
            and tolerance >= 0):
        raise InputError(f"--tolerance must be a finite number >= 0, got {tolerance}")
    new = table if isinstance(table, TableData) else read_table(table, "table")
    old = baseline if isinstance(baseline, TableData) else read_table(baseline)
    methods = [m for m in new.rmse_deg if m in old.rmse_deg]
    check_common(old, new.temperatures_c, list(new.rmse_deg))
    cols = common_columns(new.temperatures_c, old.temperatures_c)
    temps = tuple(new.temperatures_c[i] for i, _ in cols)
    given = paired is not None
    if paired is False:
        why = "unpaired: the tables resampled independently"
    elif paired:
        n_new = _clusters(new, [i for i, _ in cols])
        if n_new != _clusters(old, [j for _, j in cols]) or n_new is None:
            raise InputError("paired comparison of tables on different start-ups: "
                             f"{new.source} and {old.source}")
        why = "paired: the same start-ups in both, resampled with the same draws"
    else:
        paired, why = _pairing(new, old, methods, cols)
    sides = []
    if paired:
        cells, reps = _side_replicates([(new, [i for i, _ in cols]), (old, [j for _, j in cols])],
                                       methods, n_boot, random_state)
        sides = [(cells[0], reps[0]), (cells[1], reps[1])]
    else:
        for k, (side, idx) in enumerate(((new, [i for i, _ in cols]),
                                         (old, [j for _, j in cols]))):
            c, r = _side_replicates([(side, idx)], methods, n_boot, random_state + k)
            sides.append((c[0], r[0]))
    (c_new, r_new), (c_old, r_old) = sides
    out = []
    for m_i, m in enumerate(methods):
        for j in range(len(temps) + 1):
            if j < len(temps):
                a, b, ra, rb = c_new[m_i, j], c_old[m_i, j], r_new[m_i, j], r_old[m_i, j]
            else:                                       # the mean over compared columns
                a = float(finite_mean(c_new[m_i], axis=0))
                b = float(finite_mean(c_old[m_i], axis=0))
                ra, rb = finite_mean(r_new[m_i], axis=0), finite_mean(r_old[m_i], axis=0)
            out.append(_cell(m, temps[j] if j < len(temps) else None, b, a, ra - rb,
                             tolerance))
    notes = [why] + ([] if given else _provenance_notes(new, old)) + \
        _left_out(new, old, methods, cols)
    return BaselineComparison(tuple(methods), temps, tuple(out), float(tolerance), paired,
                              tuple(n for n in notes if n), old.source, new.provenance,
                              old.provenance)


def _cell(method: str, t: float | None, old: float, new: float, reps: np.ndarray,
          tolerance: float) -> CellChange:
    if not (math.isfinite(old) and math.isfinite(new)):
        return CellChange(method, t, old, new, math.nan, math.nan, math.nan, "n/a")
    d = new - old
    lo, hi = bc_interval(reps, d)
    if not math.isfinite(lo):          # no finite replicate: an exact cell
        lo = hi = d
    margin = tolerance * abs(old)
    verdict = ("worse" if lo > 0.0 and d > margin else
               "better" if hi < 0.0 and d < -margin else "within noise")
    return CellChange(method, t, old, new, d, lo, hi, verdict)


def _clusters(side: TableData, idx: list[int]) -> list[int] | None:
    """Start-ups per compared column (None when the table keeps no cycle errors)."""
    rows = list(side.errors_deg.values())
    return [len(rows[0][j]) for j in idx] if rows else None


def _pairing(new: TableData, old: TableData, methods, cols) -> tuple[bool, str]:
    """Whether the two tables rest on the same test start-ups, and the line that says so."""
    if not any(m in new.errors_deg and m in old.errors_deg for m in methods):
        return False, ("unpaired: the " + ("baseline" if not old.errors_deg else "table")
                       + " keeps no cycle errors (written without intervals or before they "
                       "were kept); rows without them count as exact")
    seed_new, seed_old = _test_seed(new), _test_seed(old)
    n_new = _clusters(new, [i for i, _ in cols])
    n_old = _clusters(old, [j for _, j in cols])
    if seed_new is None or seed_old is None:
        return False, ("unpaired: the " + ("baseline" if seed_old is None else "table")
                       + " does not record the seed of its test start-ups")
    if seed_new != seed_old:
        return False, (f"unpaired: other test start-ups (seed {seed_old} in the baseline, "
                       f"{seed_new} now): the two tables resampled independently")
    if n_new != n_old:
        return False, (f"unpaired: other numbers of test start-ups per start temperature "
                       f"({n_old} in the baseline, {n_new} now)")
    per = (f"{n_new[0]}" if len(set(n_new)) == 1 else "/".join(map(str, n_new)))
    return True, (f"paired: the same test start-ups (seed {seed_new}, {per} per start "
                  "temperature), resampled with the same draws in both tables")


def _test_seed(side: TableData):
    seeds = (side.provenance or {}).get("seeds") or {}
    return seeds.get("test_start_ups")


def _side_replicates(sides, methods, n_boot: int, random_state: int):
    """Cells (n_methods, n_columns) and replicates (n_methods, n_columns, B) of each side;
    every row with cycle errors of every side in one bootstrap (common draws), rows without
    as constants."""
    rows, owner = [], []
    for s, (side, idx) in enumerate(sides):
        for m_i, m in enumerate(methods):
            if m in side.errors_deg:
                rows.append([side.errors_deg[m][j] for j in idx])
                owner.append((s, m_i))
    boot = cluster_bootstrap(rows, n_boot=n_boot, random_state=random_state) if rows else None
    cells, reps = [], []
    for s, (side, idx) in enumerate(sides):
        c = np.array([[side.rmse_deg[m][j] for j in idx] for m in methods], dtype=float)
        r = np.repeat(c[..., None], n_boot, axis=2)
        cells.append(c)
        reps.append(r)
    for k, (s, m_i) in enumerate(owner):
        cells[s][m_i] = boot.cells[k]
        reps[s][m_i] = boot.cell_replicates[k]
    return cells, reps


def _provenance_notes(new: TableData, old: TableData) -> list[str]:
    """One line for each way the baseline was made differently (none when alike)."""
    pn, po = new.provenance, old.provenance
    if po is None:
        return ["the baseline records no provenance (scenario, instrument, versions, "
                "platform unknown)"]
    if pn is None:
        return ["the table records no provenance: the baseline's cannot be checked"]
    out = []
    sn, so = pn.get("scenario") or {}, po.get("scenario") or {}
    if sn.get("sha256") != so.get("sha256"):
        out.append(f"another scenario: the baseline's is '{so.get('name')}' (sha256 "
                   f"{str(so.get('sha256'))[:12]}), this one '{sn.get('name')}' (sha256 "
                   f"{str(sn.get('sha256'))[:12]})")
    i_n = sn.get("instrument") or pn.get("instrument") or {}
    i_o = so.get("instrument") or po.get("instrument") or {}
    if i_n.get("sha256") != i_o.get("sha256"):
        out.append(f"another instrument: the baseline's is '{i_o.get('name')}' (sha256 "
                   f"{str(i_o.get('sha256'))[:12]}), this one '{i_n.get('name')}' (sha256 "
                   f"{str(i_n.get('sha256'))[:12]})")
    vn, vo = pn.get("versions") or {}, po.get("versions") or {}
    if vn.get("nfs") != vo.get("nfs"):
        out.append(f"another package version: nfs {vo.get('nfs')} in the baseline, "
                   f"{vn.get('nfs')} now")
    libs = [f"{k} {vo.get(k)} -> {vn.get(k)}" for k in sorted(set(vn) | set(vo))
            if k != "nfs" and vn.get(k) != vo.get(k)]
    if libs:
        out.append("other library versions: " + ", ".join(libs))
    if pn.get("platform") != po.get("platform"):
        out.append(f"another platform: {po.get('platform')} in the baseline, "
                   f"{pn.get('platform')} now (uncompensated rows agree within 1e-8 deg "
                   "across platforms, tuned rows within their noise: nfs.testing)")
    sd_n, sd_o = pn.get("seeds") or {}, po.get("seeds") or {}
    other = [f"{k} {sd_o.get(k)} -> {sd_n.get(k)}" for k in sorted(set(sd_n) | set(sd_o))
             if k != "test_start_ups" and sd_n.get(k) != sd_o.get(k)]
    if other:
        out.append("other seeds: " + ", ".join(other))
    if new.features_mode and old.features_mode and new.features_mode != old.features_mode:
        out.append(f"another features mode: {old.features_mode} in the baseline, "
                   f"{new.features_mode} now")
    return out


def _left_out(new: TableData, old: TableData, methods, cols) -> list[str]:
    out = []
    only_old = [m for m in old.rmse_deg if m not in methods]
    only_new = [m for m in new.rmse_deg if m not in methods]
    if only_old:
        out.append("rows only in the baseline, not compared: " + ", ".join(only_old))
    if only_new:
        out.append("rows only in this table, not compared: " + ", ".join(only_new))
    t_old = [t for j, t in enumerate(old.temperatures_c) if j not in {b for _, b in cols}]
    t_new = [t for i, t in enumerate(new.temperatures_c) if i not in {a for a, _ in cols}]
    if t_old or t_new:
        out.append("start temperatures not in both, not compared (the means are over the "
                   "common ones): " + "; ".join(
                       s for s in (f"baseline only {', '.join(f'{t:g}' for t in t_old)} C"
                                   if t_old else "",
                                   f"table only {', '.join(f'{t:g}' for t in t_new)} C"
                                   if t_new else "") if s))
    return out
