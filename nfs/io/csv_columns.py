"""The CSV text of a run's samples: parsing (fast and careful paths) and formatting.

Reading hands well-formed files to NumPy's C parser and anything else to the csv module,
which locates every fault by line and column; writing gives each float its shortest exact
text, so a written run reads back bitwise.
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import MeasurementError
from ..run import REQUIRED_COLUMNS
from .completeness import CutLine
from .measurement_checks import check_columns, check_header

__all__ = ["IMPORT_HINT", "CsvTable", "read_columns", "format_csv"]

#: What a file in another layout is told: the format's layout and the way in.
IMPORT_HINT = ("nfs-measurement/1 is comma-separated with '.' as decimal point: bring a "
               "chamber log in with nfs import (docs/measurement-format.md, 'Chamber logs: "
               "nfs import')")

_DECIMAL_COMMA = re.compile(r"\s*[+-]?\d+,\d+\s*")


class CsvTable(NamedTuple):
    """The checked columns of a ``NAME.csv`` and where each sample was."""

    columns: dict[str, np.ndarray]
    """Column name -> samples, in file order."""
    line_of: Callable[[int], int]
    """Sample index -> its 1-based line in the file (the header is line 1)."""
    cut: CutLine | None
    """The last line when it was cut while written (left out of the columns), else None."""

# ---------------------------------------------------------------------------------------------
# NAME.csv: reading
#
# A fast path hands well-formed files (no quotes, no blank lines inside, no all-empty rows)
# to numpy's C parser, where row k is line k + 2. Anything else, and any file the fast path
# cannot read, goes through the careful path (csv module, per-row line numbers), which is the
# authority: it either reads the file or locates the fault.


class _UseCarefulPath(Exception):
    """The fast CSV path does not apply to this text."""


_ODD_LINE_BREAKS = ("\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029")


def _parse_csv_fast(text: str) -> tuple[list[str], np.ndarray]:
    """Names and a (columns, samples) array; sample k is on line k + 2."""
    if '"' in text or any(mark in text for mark in _ODD_LINE_BREAKS):
        raise _UseCarefulPath  # quoting or line breaks that str.splitlines and csv disagree on
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if len(lines) < 2 or not lines[0].strip():
        raise _UseCarefulPath
    names = [name.strip() for name in lines[0].split(",")]
    body = "\n".join(lines[1:])
    if "\n\n" in body:
        raise _UseCarefulPath  # a blank line inside
    if ",," in body or "\n," in body or ",\n" in body or body[0] == "," or body[-1] == ",":
        # Empty fields -> "nan". Two passes of ",," catch runs of any length: the first
        # leaves runs of at most two commas, the second splits those.
        body = "\n" + body + "\n"
        if ",," in body:
            body = body.replace(",,", ",nan,").replace(",,", ",nan,")
        if "\n," in body:
            body = body.replace("\n,", "\nnan,")
        if ",\n" in body:
            body = body.replace(",\n", ",nan\n")
        body = body[1:-1]
    try:
        data = np.loadtxt(io.StringIO(body), delimiter=",", comments=None,
                          dtype=np.float64, ndmin=2)
    except ValueError:
        raise _UseCarefulPath from None
    if data.shape != (len(lines) - 1, len(names)):
        raise _UseCarefulPath
    data = np.ascontiguousarray(data.T)
    if "time_s" in names and np.isnan(data[names.index("time_s")]).any():
        raise _UseCarefulPath  # maybe an all-empty row, which the careful path skips
    return names, data


def _is_blank(row: list[str]) -> bool:
    return not any(f.strip() for f in row)


def _parse_values(values: tuple[str, ...]) -> tuple[np.ndarray, int | None]:
    """Floats of *values* (empty -> NaN) and the index of the first one that does not parse.

    A value is what ``float`` reads, except digit separators (``1_000``) and non-ASCII
    digits, which neither the spec nor numpy's parser (the fast path) accepts.
    """
    joined = "".join(values)
    if "_" not in joined and joined.isascii():
        try:
            return np.array(list(map(float, values)), dtype=np.float64), None
        except ValueError:
            pass
    out = np.empty(len(values))
    for i, value in enumerate(values):
        try:
            if "_" in value or not value.isascii():
                raise ValueError
            out[i] = float(value)
        except ValueError:
            if value.strip():
                return out, i
            out[i] = math.nan
    return out, None


def _field_count_error(fields: int, n: int, file: Path, line: int) -> MeasurementError:
    hint = (f"; a decimal comma ('1,5' for 1.5)? {IMPORT_HINT}" if fields > n else "")
    return MeasurementError(f"row has {fields} field{'s' if fields != 1 else ''}, the header "
                            f"has {n}{hint}", file=file, row=line)


def _parse_csv_careful(text: str, file: Path
                       ) -> tuple[list[str], list[np.ndarray], list[int], CutLine | None]:
    """Names, columns, the line of every sample and a cut last line (fewer fields than the
    header, nothing after it; left out); raises on the first fault."""
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = None
        for row in reader:
            if not _is_blank(row):
                header = row
                break
        if header is None:
            raise MeasurementError("empty file: no header row", file=file)
        header_line = reader.line_num
        names = [name.strip() for name in header]
        check_header(names, file, header_line)
        n = len(names)
        t = names.index("time_s")
        rows: list[list[str]] = []
        lines: list[int] = []
        short: tuple[int, int] | None = None     # (line, fields) of a row with too few
        for row in reader:
            if _is_blank(row):
                continue
            if short is not None:                # a short row with rows after it: not cut
                raise _field_count_error(short[1], n, file, short[0])
            if len(row) != n:
                if len(row) > n:
                    raise _field_count_error(len(row), n, file, reader.line_num)
                short = (reader.line_num, len(row))
                continue
            rows.append(row)
            lines.append(reader.line_num)
    except csv.Error as exc:
        raise MeasurementError(f"CSV syntax error: {exc}", file=file,
                               row=reader.line_num) from None
    cut = None if short is None else CutLine(short[0], short[1], n)
    if not rows:
        if cut is not None:
            raise _field_count_error(cut.fields, n, file, cut.line)
        raise MeasurementError("no data rows after the header", file=file, row=header_line)
    columns = []
    faults = []
    for name, values in zip(names, zip(*rows)):
        column, bad = _parse_values(values)
        columns.append(column)
        if bad is not None:
            faults.append((bad, name, values[bad]))
    if faults:
        bad, name, value = min(faults, key=lambda fault: fault[0])  # first line, then column
        shown = value if len(value) <= 40 else value[:37] + "..."
        hint = f"; a decimal comma? {IMPORT_HINT}" if _DECIMAL_COMMA.fullmatch(value) else ""
        raise MeasurementError(f"cannot read {shown!r} as a number{hint}", file=file,
                               column=name, row=lines[bad])
    return names, columns, lines, cut


def _check_layout(text: str, file: Path) -> None:
    """A header separated by ';' or tabs instead of ',' is another layout: say so."""
    header = next((line for line in text.splitlines() if line.strip()), "")
    if "," in header:
        return
    for mark, name in ((";", "';'"), ("\t", "tabs")):
        if mark in header:
            raise MeasurementError(f"the header is separated by {name}, not ','; "
                                   f"{IMPORT_HINT}", file=file, row=1)


def read_columns(path: Path) -> CsvTable:
    """The checked columns of ``NAME.csv`` in file order, the line of each sample and a cut
    last line (:class:`CsvTable`)."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise MeasurementError(f"cannot read: {exc.strerror}", file=path) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise MeasurementError(f"not UTF-8 text: {exc.reason} at byte {exc.start}",
                               file=path, row=line) from None
    if not text.strip():
        raise MeasurementError("empty file: no header row", file=path)
    _check_layout(text, path)
    try:
        names, data = _parse_csv_fast(text)
        check_header(names, path, 1)
        columns = dict(zip(names, data))
        line_of, cut = _line_after_header, None
    except (_UseCarefulPath, MeasurementError):
        names, arrays, lines, cut = _parse_csv_careful(text, path)
        columns = dict(zip(names, arrays))
        line_of = lines.__getitem__
    check_columns(columns, file=path, line_of=line_of)
    return CsvTable(columns, line_of, cut)


def _line_after_header(index: int) -> int:
    """Line of sample ``index`` in a file without blank lines: the header is line 1."""
    return index + 2





def _format_column(values: np.ndarray) -> list[str]:
    """Shortest exact text of every value: integers as integers, NaN as an empty field.

    A column whose values are all integral (``moving``, a whole-second ``time_s``) is written
    as integers; otherwise every value as ``repr(float)``, the shortest string that reads
    back to the same double. Columns with few distinct values format each value once.
    """
    nan = np.isnan(values)
    has_nan = bool(nan.any())
    given = values[~nan] if has_nan else values
    negative_zero = bool(((given == 0.0) & np.signbit(given)).any())
    if (not negative_zero and bool((given == np.trunc(given)).all())
            and bool((np.abs(given) < 2.0 ** 53).all())):
        texts = list(map(str, np.where(nan, 0.0, values).astype(np.int64).tolist()))
    else:
        unique, inverse = (np.unique(values, return_inverse=True) if not negative_zero
                           else (values, None))
        if inverse is not None and 2 * len(unique) <= len(values):
            table = np.array([repr(v) for v in unique.tolist()], dtype=object)
            texts = table[inverse.ravel()].tolist()
        else:
            texts = list(map(repr, values.tolist()))
    if has_nan:
        for i in np.flatnonzero(nan).tolist():
            texts[i] = ""
    return texts


def format_csv(columns: Mapping[str, np.ndarray]) -> str:
    names = [name for name in REQUIRED_COLUMNS if name in columns]
    names += [name for name in columns if name not in REQUIRED_COLUMNS]
    texts = [_format_column(columns[name]) for name in names]
    return ",".join(names) + "\n" + "\n".join(map(",".join, zip(*texts))) + "\n"
