"""One source file of a chamber log, read as its mapping says (:mod:`nfs.io.log_mapping`):
its separator, decimal mark, preamble and encoding, its times in seconds and its columns in
the format's units, with the line of every sample.

The checks of :mod:`nfs.io.measurement_checks` that a column answers for alone (finite,
``moving`` 0 or 1, temperatures above absolute zero, specific forces within 2 g) are made
here, on the source's own rows, so that an error names the source file, its column and its
line; so is a missing sample (:mod:`nfs.io.completeness`).
"""

from __future__ import annotations

import csv
import datetime as dt
import io
from dataclasses import dataclass

import numpy as np

from ..docfields import document_fields
from ..errors import MeasurementError
from .completeness import CutLine, check_missing
from .log_mapping import TIME_UNITS, SourceMap
from .measurement_checks import check_values

__all__ = ["SourceData", "read_source"]


@document_fields
@dataclass(frozen=True)
class SourceData:
    """A source file's samples."""

    source: SourceMap
    """What the mapping says of it."""
    time_s: np.ndarray
    """Its times [s]: relative times as logged (times the unit, plus its offset), absolute
    ones from ``anchor``."""
    anchor: dt.datetime | None
    """The absolute time of ``time_s = 0`` (its first sample), or None for relative times."""
    columns: dict[str, np.ndarray]
    """The run's column -> its samples in the format's unit."""
    lines: np.ndarray
    """The 1-based line of each sample in the file."""
    cut: CutLine | None
    """Its last line, when cut while written (left out)."""
    caveat: str | None
    """Its missing samples, when read with ``allow_nan`` (None: none)."""

    def line_of(self, index: int) -> int:
        """The file's line of sample ``index``."""
        return int(self.lines[index])

    def step_s(self) -> float:
        """Its median time step [s] (0 with one sample: it covers its own time only)."""
        return float(np.median(np.diff(self.time_s))) if self.time_s.size > 1 else 0.0


def _rows(src: SourceMap) -> tuple[list[str], list[list[str]], list[int], CutLine | None]:
    """Header, data rows and their lines; a cut last line apart."""
    try:
        text = src.file.read_bytes().decode(src.encoding)
    except OSError as exc:
        raise MeasurementError(f"cannot read: {exc.strerror}", file=src.file) from None
    except UnicodeDecodeError as exc:
        raise MeasurementError(f"not {src.encoding} text ({src.key}.encoding): {exc.reason}",
                               file=src.file) from None
    text = text.removeprefix("\ufeff")
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=src.separator)
    header, rows, lines, short = None, [], [], None
    try:
        for row in reader:
            if reader.line_num <= src.skip_rows or not any(f.strip() for f in row):
                continue
            if header is None:
                header = [f.strip() for f in row]
                header_line = reader.line_num
                continue
            if short is not None:
                raise MeasurementError(f"row has {short[1]} fields, the header has "
                                       f"{len(header)}", file=src.file, row=short[0])
            if len(row) < len(header):
                short = (reader.line_num, len(row))
                continue
            if len(row) > len(header):
                # more fields than names: a decimal comma read as the separator would shift
                # every column after it
                raise MeasurementError(
                    f"row has {len(row)} fields, the header has {len(header)}; a decimal comma "
                    f"with separator '{src.separator}'? (set {src.key}.decimal and "
                    f"{src.key}.separator)", file=src.file, row=reader.line_num)
            rows.append(row)
            lines.append(reader.line_num)
    except csv.Error as exc:
        raise MeasurementError(f"CSV syntax error: {exc}", file=src.file,
                               row=reader.line_num) from None
    if header is None:
        raise MeasurementError(f"no header row (after the {src.skip_rows} rows of "
                               f"{src.key}.skip_rows)", file=src.file)
    if not rows:
        raise MeasurementError("no data rows after the header", file=src.file, row=header_line)
    cut = None if short is None else CutLine(short[0], short[1], len(header))
    return header, rows, lines, cut


def _index(header: list[str], name: str, src: SourceMap, key: str) -> int:
    if name not in header:
        sep = "tabs" if src.separator == "\t" else repr(src.separator)
        raise MeasurementError(f"no column {name!r} ({key}); the header, split at {sep}, "
                               f"has: {', '.join(header)}", file=src.file, row=src.skip_rows + 1)
    return header.index(name)


def _numbers(texts: list[str], src: SourceMap, column: str, lines: list[int]) -> np.ndarray:
    out = np.empty(len(texts))
    for i, text in enumerate(texts):
        t = text.strip()
        if src.decimal == ",":
            t = t.replace(",", ".")
        try:
            if "_" in t or not t.isascii():
                raise ValueError
            out[i] = float(t) if t else np.nan
        except ValueError:
            hint = ("; a decimal comma? give decimal = \",\" in " + src.key
                    if src.decimal == "." and "," in t else "")
            raise MeasurementError(f"cannot read {text!r} as a number{hint}", file=src.file,
                                   column=column, row=lines[i]) from None
    return out


def _times(texts: list[str], src: SourceMap, lines: list[int]
           ) -> tuple[np.ndarray, dt.datetime | None]:
    if src.time_unit is not None:
        t = _numbers(texts, src, src.time_column, lines)
        bad = np.flatnonzero(np.isnan(t))
        if bad.size:
            raise MeasurementError("missing time", file=src.file, column=src.time_column,
                                   row=lines[bad[0]])
        num, den = TIME_UNITS[src.time_unit]
        return t * num / den + src.time_offset_s, None
    stamps = []
    for text, line in zip(texts, lines):
        try:
            stamps.append(dt.datetime.strptime(text.strip(), src.time_format))
        except ValueError as exc:
            raise MeasurementError(f"cannot read {text!r} as a time of {src.key}.time_format "
                                   f"{src.time_format!r}: {exc}", file=src.file,
                                   column=src.time_column, row=line) from None
    anchor = stamps[0]
    aware = {s.tzinfo is not None for s in stamps}
    if len(aware) > 1:
        raise MeasurementError("some times carry a time zone and some do not", file=src.file,
                               column=src.time_column)
    micro = np.array([(s - anchor) // dt.timedelta(microseconds=1) for s in stamps],
                     dtype=np.int64)
    return micro / 1e6, anchor


def read_source(src: SourceMap, *, partial: bool = False,
                allow_nan: bool = False) -> SourceData:
    """Read one source file of a chamber log (module docstring).

    Parameters
    ----------
    src : SourceMap
        The source as the mapping gives it.
    partial : bool
        Leave out a last line cut while written instead of refusing it.
    allow_nan : bool
        Read missing samples as NaN instead of refusing them.

    Raises
    ------
    MeasurementError
        A file that cannot be read, a column the header lacks, a value or time that does
        not parse, times that do not increase, a value no north finder logs, a cut last
        line or missing samples unless asked; the message names the file, the column and
        the line.
    """
    header, rows, lines, cut = _rows(src)
    if cut is not None and not partial:
        raise MeasurementError(f"{cut.text()}; {len(rows)} complete rows found; read them "
                               "with --partial", file=src.file, row=cut.line)
    need = [(src.time_column, f"{src.key}.time")] + [(c.column, c.key) for c in src.columns]
    index = {name: _index(header, name, src, key) for name, key in need}
    fields = list(zip(*rows))
    time_s, anchor = _times(list(fields[index[src.time_column]]), src, lines)
    columns = {}
    for c in src.columns:
        logged = _numbers(list(fields[index[c.column]]), src, c.column, lines)
        columns[c.target] = logged * c.factor + c.offset if c.factor != 1.0 or c.offset \
            else logged
    line_of = lines.__getitem__
    by_target = {c.target: c.column for c in src.columns}
    by_target["time_s"] = src.time_column
    try:
        check_values({"time_s": time_s, **columns}, file=src.file, line_of=line_of)
        caveat = check_missing(columns, file=src.file, line_of=line_of, allow_nan=allow_nan)
    except MeasurementError as exc:
        raise MeasurementError(_logged_names(exc.message, by_target), file=src.file,
                               column=by_target.get(exc.column), row=exc.row) from None
    if caveat:
        caveat = f"{src.file.name}: {_logged_names(caveat, by_target)}"
    return SourceData(src, time_s, anchor, columns, np.asarray(lines), cut, caveat)


def _logged_names(text: str, by_target: dict[str, str]) -> str:
    """A message of the format's checks with each column named as the log names it (the
    checks list columns as ``name: count (rows ...)``)."""
    for target, column in by_target.items():
        text = text.replace(f"{target}: ", f"{column}: ")
    return text
