"""The mapping of a chamber log: which file holds which channel, in which unit, on which clock.

A test engineer's start-up run often comes as several files: the gyro's log (with the
turntable's position), the built-in thermometers' log, the chamber's log, each with its own
time column and rate, a semicolon separator, a decimal comma. A mapping (TOML) names them,
and :func:`nfs.io.log_import.import_log` makes one ``nfs-measurement/1`` run of them
(docs/measurement-format.md, "Chamber logs: nfs import")::

    [run]                                    # the sidecar's keys (NAME.toml), and:
    name = "unit7_T-32C"                     #   the run's name (default: the mapping's stem)
    latitude_deg = 30.26
    start_temperature_c = -32.0
    power_on = "2024-03-01 08:00:00.000"     #   time_s = 0, in the gyro's time_format

    [sources.gyro]
    file = "gyro.csv"                        # relative to the mapping file
    separator = ";"                          # default ","
    decimal = ","                            # default "."
    time = "Timestamp"
    time_format = "%Y-%m-%d %H:%M:%S.%f"     # or time_unit = "s", "ms", "min" or "h"
    columns.gyro_dph = { column = "Rate", unit = "mdeg/h" }
    columns.position_deg = "Table"           # a column in the format's own unit

Every fault raises :class:`~nfs.errors.InputError` naming the mapping file and the key.
"""

from __future__ import annotations

import codecs
import math
import os
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from ..constants import ABSOLUTE_ZERO_C, STANDARD_GRAVITY_M_S2
from ..docfields import document_fields
from ..errors import InputError
from ..power import POWERED_COLUMN
from ..run import REQUIRED_COLUMNS, RunMeta
from .measurement import FORMAT, meta_from_dict

__all__ = ["MAPPING_FORMAT", "TIME_UNITS", "UNITS", "METHODS", "ColumnMap", "SourceMap",
           "LogMapping", "read_mapping"]

#: The format tag a mapping may give (``format = ...``).
MAPPING_FORMAT = "nfs-log-mapping/1"

#: Relative time units of a source's time column: name -> seconds per unit, as the
#: fraction (numerator, denominator), so that 1500 ms is exactly 1500 / 1000 s.
TIME_UNITS = {"s": (1, 1), "ms": (1, 1000), "min": (60, 1), "h": (3600, 1)}

_RAD = 180.0 / math.pi
#: The units a column may be logged in, by the unit of its format column (the suffix of its
#: name): unit -> (factor, offset), format value = logged value x factor + offset.
UNITS: dict[str, dict[str, tuple[float, float]]] = {
    "dph": {"deg/h": (1.0, 0.0), "mdeg/h": (1e-3, 0.0), "deg/s": (3600.0, 0.0),
            "rad/s": (3600.0 * _RAD, 0.0), "rad/h": (_RAD, 0.0)},
    "c": {"degC": (1.0, 0.0), "K": (1.0, ABSOLUTE_ZERO_C),
          "degF": (5.0 / 9.0, -32.0 * 5.0 / 9.0)},
    "g": {"g": (1.0, 0.0), "mg": (1e-3, 0.0), "m/s^2": (1.0 / STANDARD_GRAVITY_M_S2, 0.0)},
    "deg": {"deg": (1.0, 0.0), "rad": (_RAD, 0.0)},
    "flag": {"0/1": (1.0, 0.0)},
    "aux": {"as logged": (1.0, 0.0)},
}

#: How a source other than the gyro's is brought onto the gyro's time base.
METHODS = {
    "linear": "linear interpolation between its samples",
    "previous": "its last sample at or before each gyro time (a state held)",
    "nearest": "its sample nearest to each gyro time",
}

#: Columns that hold a state (the turntable's, the power's): resampled with ``previous``.
_STATES = ("position_deg", "moving", POWERED_COLUMN)
_SOURCE_KEYS = ("file", "separator", "decimal", "skip_rows", "encoding", "time", "time_unit",
                "time_format", "time_offset_s", "columns")
_COLUMN_KEYS = ("column", "unit", "method")
_TARGET = re.compile(r"(temp_\w+_c|acc_\w+_g|\w+_dph|aux_\w+|position_deg|moving|"
                     + POWERED_COLUMN + ")")


@document_fields
@dataclass(frozen=True)
class ColumnMap:
    """One column of the run, from one column of a source file."""

    target: str
    """The run's column (``gyro_dph``, ``temp_fog_c``, ...)."""
    column: str
    """The source file's column (its header's name)."""
    unit: str
    """The unit it is logged in (a key of :data:`UNITS` for its kind)."""
    factor: float
    """Format value = logged value x factor + offset."""
    offset: float
    """See ``factor`` [the format's unit]."""
    method: str
    """How it is brought onto the gyro's time base (a key of :data:`METHODS`)."""
    key: str
    """Its key in the mapping (``sources.gyro.columns.gyro_dph``), named by errors."""


@document_fields
@dataclass(frozen=True)
class SourceMap:
    """One source file of a chamber log."""

    name: str
    """Its name under ``[sources]``."""
    file: Path
    """The file (resolved against the mapping's folder)."""
    separator: str
    """Field separator (one character; ``"\\t"`` for tabs)."""
    decimal: str
    """Decimal mark, ``"."`` or ``","``."""
    skip_rows: int
    """Lines before the header (a logger's preamble)."""
    encoding: str
    """Text encoding (default ``utf-8``, a byte-order mark skipped)."""
    time_column: str
    """The column of its times."""
    time_unit: str | None
    """Unit of relative times (a key of :data:`TIME_UNITS`), or None with ``time_format``."""
    time_format: str | None
    """strptime format of absolute times, or None with ``time_unit``."""
    time_offset_s: float
    """When its relative time zero falls after power-on [s] (default 0)."""
    columns: tuple[ColumnMap, ...]
    """The run's columns it holds."""

    @property
    def key(self) -> str:
        """Its table in the mapping, ``sources.NAME``."""
        return f"sources.{self.name}"


@document_fields
@dataclass(frozen=True)
class LogMapping:
    """A chamber log's mapping (module docstring), checked."""

    path: Path
    """The mapping file."""
    name: str
    """The run's name (``[run] name``, default the mapping file's stem)."""
    meta: RunMeta
    """The sidecar's metadata from ``[run]``."""
    power_on: str | None
    """The absolute time of power-on (``time_s`` = 0), in the format of the absolute
    sources, or None: the gyro's first sample (absolute times) or its time zero."""
    max_gap_samples: float
    """A source's step longer than this many of its median steps is a hole (``[align]
    max_gap_samples``, default 3)."""
    sources: tuple[SourceMap, ...]
    """The source files, in the mapping's order."""

    @property
    def gyro(self) -> SourceMap:
        """The source that holds ``gyro_dph``: its times are the run's."""
        return next(s for s in self.sources if any(c.target == "gyro_dph" for c in s.columns))


def _fail(message: str, path: Path, key: str | None = None) -> InputError:
    return InputError(message, file=path, key=key)


def _table(doc: dict, key: str, path: Path, shown: str) -> dict:
    value = doc.get(key)
    if not isinstance(value, dict):
        what = "missing" if value is None else f"a {type(value).__name__}, not a table"
        raise _fail(f"required table is {what}", path, shown)
    return value


def _unknown(table: dict, allowed: tuple[str, ...], path: Path, shown: str) -> None:
    for k in table:
        if k not in allowed:
            raise _fail(f"unknown key; valid keys: {', '.join(allowed)}", path,
                        f"{shown}.{k}" if shown else k)


def _text(table: dict, key: str, path: Path, shown: str, default: str | None = None
          ) -> str | None:
    value = table.get(key, default)
    if value is not None and (not isinstance(value, str) or not value):
        raise _fail(f"must be a non-empty string, not {value!r}", path, f"{shown}.{key}")
    return value


def _kind(target: str) -> str:
    if target in ("moving", POWERED_COLUMN):
        return "flag"
    if target.startswith("aux_"):
        return "aux"
    return target.rsplit("_", 1)[1]


def _column(target: str, spec, path: Path, shown: str) -> ColumnMap:
    if target == "time_s" or not _TARGET.fullmatch(target):
        raise _fail("not a column of the format: a mapping names gyro_dph, position_deg, "
                    "moving, acc_*_g, temp_*_c, powered or aux_* (time_s comes from the "
                    "source's time)", path, shown)
    if isinstance(spec, str):
        spec = {"column": spec}
    if not isinstance(spec, dict):
        raise _fail(f"must be the source's column name or a table {{ column = ..., unit = "
                    f"... }}, not {spec!r}", path, shown)
    _unknown(spec, _COLUMN_KEYS, path, shown)
    column = _text(spec, "column", path, shown)
    if column is None:
        raise _fail("required key is missing: the source's column name", path,
                    f"{shown}.column")
    units = UNITS[_kind(target)]
    unit = _text(spec, "unit", path, shown, next(iter(units)))
    if unit not in units:
        raise _fail(f"unknown unit {unit!r} for {target}; valid: {', '.join(units)}", path,
                    f"{shown}.unit")
    method = _text(spec, "method", path, shown,
                   "previous" if target in _STATES else "linear")
    if method not in METHODS:
        raise _fail(f"unknown method {method!r}; valid: {', '.join(METHODS)}", path,
                    f"{shown}.method")
    factor, offset = units[unit]
    return ColumnMap(target, column, unit, factor, offset, method, shown)


def _source(name: str, table, folder: Path, path: Path) -> SourceMap:
    shown = f"sources.{name}"
    if not isinstance(table, dict):
        raise _fail(f"must be a table, not {table!r}", path, shown)
    _unknown(table, _SOURCE_KEYS, path, shown)
    file = _text(table, "file", path, shown)
    if file is None:
        raise _fail("required key is missing: the source file, relative to the mapping",
                    path, f"{shown}.file")
    resolved = folder / file
    if not resolved.is_file():
        raise _fail(f"no such file: {resolved}", path, f"{shown}.file")
    separator = _text(table, "separator", path, shown, ",")
    if len(separator) != 1 or separator in "\"\r\n.0123456789-+":
        raise _fail(f"must be one character (',', ';', '\\t', ...), not {separator!r}",
                    path, f"{shown}.separator")
    decimal = _text(table, "decimal", path, shown, ".")
    if decimal not in (".", ","):
        raise _fail(f"must be '.' or ',', not {decimal!r}", path, f"{shown}.decimal")
    if decimal == separator:
        raise _fail(f"the decimal mark {decimal!r} is also the separator", path,
                    f"{shown}.decimal")
    skip = table.get("skip_rows", 0)
    if isinstance(skip, bool) or not isinstance(skip, int) or skip < 0:
        raise _fail(f"must be a whole number >= 0, not {skip!r}", path, f"{shown}.skip_rows")
    encoding = _text(table, "encoding", path, shown, "utf-8")
    try:
        codecs.lookup(encoding)
    except LookupError:
        raise _fail(f"unknown encoding {encoding!r}", path, f"{shown}.encoding") from None
    time_column = _text(table, "time", path, shown)
    if time_column is None:
        raise _fail("required key is missing: the column of the source's times", path,
                    f"{shown}.time")
    unit = _text(table, "time_unit", path, shown)
    fmt = _text(table, "time_format", path, shown)
    if (unit is None) == (fmt is None):
        raise _fail("give one of time_unit (relative times: "
                    f"{', '.join(TIME_UNITS)}) and time_format (absolute times, a strptime "
                    "format such as '%Y-%m-%d %H:%M:%S.%f')", path, f"{shown}.time_unit")
    if unit is not None and unit not in TIME_UNITS:
        raise _fail(f"unknown time unit {unit!r}; valid: {', '.join(TIME_UNITS)}", path,
                    f"{shown}.time_unit")
    if fmt is not None and "%" not in fmt:
        raise _fail(f"not a strptime format (no % directive): {fmt!r}", path,
                    f"{shown}.time_format")
    offset = table.get("time_offset_s", 0.0)
    if isinstance(offset, bool) or not isinstance(offset, (int, float)) \
            or not math.isfinite(offset):
        raise _fail(f"must be a finite number of seconds, not {offset!r}", path,
                    f"{shown}.time_offset_s")
    if offset and fmt is not None:
        raise _fail("an absolute time (time_format) has no offset; give [run] power_on",
                    path, f"{shown}.time_offset_s")
    columns = _table(table, "columns", path, shown)
    if not columns:
        raise _fail("names no column", path, f"{shown}.columns")
    maps = tuple(_column(t, spec, path, f"{shown}.columns.{t}") for t, spec in columns.items())
    for m in maps:
        if m.column == time_column:
            raise _fail(f"is the source's time column {time_column!r}", path, m.key)
    return SourceMap(name, resolved, separator, decimal, skip, encoding, time_column, unit,
                     fmt, float(offset), maps)


def _run_table(doc: dict, path: Path) -> tuple[str, RunMeta, str | None]:
    run = dict(_table(doc, "run", path, "run"))
    name = _text(run, "name", path, "run", path.stem)
    if name in (".", "..") or "/" in name or "\\" in name:
        raise _fail(f"cannot be a file name: {name!r}", path, "run.name")
    power_on = _text(run, "power_on", path, "run")
    for k in ("name", "power_on"):
        run.pop(k, None)
    if "format" in run:
        raise _fail(f"the run's format is {FORMAT} (nfs import writes it)", path, "run.format")
    meta = meta_from_dict({"format": FORMAT, **run}, file=path, shown="run")
    return name, meta, power_on


def read_mapping(path: str | os.PathLike) -> LogMapping:
    """Read and check a chamber log's mapping (module docstring).

    Parameters
    ----------
    path : str or path-like
        The mapping TOML file; source files are relative to its folder.

    Returns
    -------
    LogMapping
        The checked mapping: every source file exists, every unit and method is known,
        every required column of ``nfs-measurement/1`` comes from exactly one source, and
        exactly one source holds ``gyro_dph``.

    Raises
    ------
    InputError
        A TOML syntax error, a missing, unknown or mistyped key, a unit or method not known,
        a column mapped twice or by no source; the message names the file and the key.
    """
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except OSError as exc:
        raise _fail(f"cannot read: {exc.strerror}", path) from None
    except UnicodeDecodeError as exc:
        raise _fail(f"not UTF-8 text: {exc.reason}", path) from None
    except tomllib.TOMLDecodeError as exc:
        raise _fail(f"TOML syntax error: {exc}", path) from None
    _unknown(doc, ("format", "run", "align", "sources"), path, "")
    if "format" in doc and doc["format"] != MAPPING_FORMAT:
        raise _fail(f'must be "{MAPPING_FORMAT}", not {doc["format"]!r}', path, "format")
    name, meta, power_on = _run_table(doc, path)
    align = doc.get("align", {})
    if not isinstance(align, dict):
        raise _fail(f"must be a table, not {align!r}", path, "align")
    _unknown(align, ("max_gap_samples",), path, "align")
    gap = align.get("max_gap_samples", 3)
    if isinstance(gap, bool) or not isinstance(gap, (int, float)) or not gap >= 1 \
            or not math.isfinite(gap):
        raise _fail(f"must be a number >= 1, not {gap!r}", path, "align.max_gap_samples")
    sources = _table(doc, "sources", path, "sources")
    if not sources:
        raise _fail("names no source file", path, "sources")
    maps = tuple(_source(n, t, path.parent, path) for n, t in sources.items())
    seen: dict[str, str] = {}
    for s in maps:
        for c in s.columns:
            if c.target in seen:
                raise _fail(f"{c.target} comes from two places (also {seen[c.target]})", path,
                            c.key)
            seen[c.target] = c.key
    missing = [c for c in REQUIRED_COLUMNS if c != "time_s" and c not in seen]
    if missing:
        raise _fail(f"no source gives the required column{'s' if len(missing) > 1 else ''} "
                    f"{', '.join(missing)} ({FORMAT}; docs/measurement-format.md)", path,
                    "sources")
    return LogMapping(path, name, meta, power_on, float(gap), maps)
