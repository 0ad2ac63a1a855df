"""A heading table read back from its JSON (``nfs table --json``, ``heading_rmse.json``).

What a later comparison needs (:mod:`nfs.scoring.baseline`): the start temperatures, each
row's RMSE, the cycle errors behind each cell and the provenance, checked on reading: a file
that is not such a table is one located error (file and key), never a traceback.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..docfields import document_fields
from ..errors import InputError
from .heading_table import HeadingTable

__all__ = ["TableData", "read_table", "check_common", "common_columns"]

#: Start temperatures closer than this are one column [degC].
_SAME_T_C = 1e-6


@document_fields
@dataclass(frozen=True)
class TableData:
    """A heading table as its JSON holds it (what a comparison needs)."""

    temperatures_c: tuple[float, ...]
    """Start temperatures, the columns [degC]."""
    rmse_deg: dict
    """Row name -> RMSE at each start temperature [deg] (NaN where the table has none)."""
    errors_deg: dict
    """Row name -> ``errors[column][start-up]``: cycle errors [deg] (rows with intervals)."""
    provenance: dict | None
    """What produced the table (None: not recorded)."""
    features_mode: str | None
    """Features mode of the compensated rows."""
    source: str
    """Where it was read from (a file, or ``the table``)."""




def read_table(source, what: str = "--baseline") -> TableData:
    """A heading table from a JSON file written by ``nfs table --json`` (or its
    ``heading_rmse.json``), from its dict, or from a :class:`HeadingTable`.

    A :class:`HeadingTable` goes through its JSON form, so that a table compared with its own
    JSON file differs by exactly 0.

    Raises
    ------
    InputError
        One located line: the file unreadable, not JSON, or not a heading table.
    """
    if isinstance(source, HeadingTable):
        return _parse(source.to_dict(), "the table")
    if isinstance(source, dict):
        return _parse(source, "the table")
    path = Path(source)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{what}: cannot read the file ({exc.__class__.__name__}: "
                         f"{getattr(exc, 'strerror', None) or exc})", file=path) from None
    try:
        doc = json.loads(text)
    except ValueError as exc:
        raise InputError(f"{what}: not JSON ({exc})", file=path) from None
    return _parse(doc, str(path))


def _parse(doc, source: str) -> TableData:
    where = {"file": None if source == "the table" else source}

    def bad(msg: str, key: str | None = None):
        return InputError(f"not a heading table written by nfs table --json: {msg}",
                          key=key, **where)

    if not isinstance(doc, dict) or not isinstance(doc.get("rows"), list) or \
            not isinstance(doc.get("temperatures_c"), list):
        raise bad("no 'temperatures_c' and 'rows' lists")
    temps = doc["temperatures_c"]
    if not temps or not all(_number(t) for t in temps):
        raise bad("'temperatures_c' must be a non-empty list of numbers", "temperatures_c")
    temps = tuple(float(t) for t in temps)
    rmse = {}
    for i, row in enumerate(doc["rows"]):
        if not isinstance(row, dict) or not isinstance(row.get("method"), str):
            raise bad("a row without a 'method' name", f"rows[{i}]")
        vals = row.get("rmse_deg")
        if not isinstance(vals, list) or len(vals) != len(temps) or \
                not all(v is None or _number(v) for v in vals):
            raise bad(f"row '{row['method']}': 'rmse_deg' needs {len(temps)} numbers (or "
                      "null), one per start temperature", f"rows[{i}].rmse_deg")
        rmse[row["method"]] = tuple(math.nan if v is None else float(v) for v in vals)
    errors = {}
    raw = doc.get("errors_deg") or {}
    if not isinstance(raw, dict):
        raise bad("'errors_deg' must map row names to cycle errors", "errors_deg")
    for name, cols in raw.items():
        key = f"errors_deg.{name}"
        if name not in rmse:
            raise bad(f"errors of a row '{name}' the table does not have", key)
        if not isinstance(cols, list) or len(cols) != len(temps):
            raise bad(f"{len(temps)} columns of start-ups expected", key)
        out = []
        for j, col in enumerate(cols):
            if not isinstance(col, list) or not all(
                    isinstance(c, list) and all(v is None or _number(v) for v in c)
                    for c in col):
                raise bad("each column must be a list of start-ups, each a list of cycle "
                          "errors", f"{key}[{j}]")
            out.append([np.array([math.nan if v is None else v for v in c], dtype=float)
                        for c in col])
        errors[name] = out
    prov = doc.get("provenance")
    mode = doc.get("features_mode")
    return TableData(temps, rmse, errors, prov if isinstance(prov, dict) else None,
                     mode if isinstance(mode, str) else None, source)


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def common_columns(a: tuple[float, ...], b: tuple[float, ...]) -> list[tuple[int, int]]:
    """(index in a, index in b) of the start temperatures both have, in a's order."""
    out = []
    for i, t in enumerate(a):
        j = next((j for j, u in enumerate(b) if abs(t - u) <= _SAME_T_C), None)
        if j is not None:
            out.append((i, j))
    return out


def check_common(baseline: TableData, temperatures_c, methods) -> None:
    """Check, before any work, that a table of ``methods`` at ``temperatures_c`` has start
    temperatures and rows in common with ``baseline`` (InputError naming the file if not)."""
    temps = tuple(float(t) for t in temperatures_c)
    where = {"file": None if baseline.source == "the table" else baseline.source}
    if not common_columns(temps, baseline.temperatures_c):
        raise InputError(
            "no start temperature in common with the table: baseline "
            f"{', '.join(f'{t:g}' for t in baseline.temperatures_c)} C, table "
            f"{', '.join(f'{t:g}' for t in temps)} C", **where)
    if not [m for m in methods if m in baseline.rmse_deg]:
        raise InputError(
            f"no row in common with the table: baseline {', '.join(baseline.rmse_deg)}; "
            f"table {', '.join(methods)}", **where)
