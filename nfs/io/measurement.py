"""The measurement format ``nfs-measurement/1`` (docs/measurement-format.md).

A run is two files with one stem: ``NAME.csv`` (samples) and ``NAME.toml`` (metadata).

Reading
    :func:`read_run` reads one run, :func:`read_runs` any number of files and folders,
    :func:`find_runs` only lists the runs a set of paths names. Every fault in the input
    raises :class:`~nfs.errors.MeasurementError` whose message names the file and, where they
    apply, the column, the 1-based line (the header is line 1) or the TOML key.

Missing values
    An empty field or ``nan`` is a missing sample (NaN). It is never allowed in ``time_s``,
    ``position_deg`` and ``moving``: without those a sample cannot be placed in the
    schedule. A missing gyro, accelerometer or temperature sample (a logger drop-out) is
    refused, naming the columns and their first rows, unless it is read with ``allow_nan``:
    then it is NaN, which the consumers skip (a dwell mean, a fit window leaves it out), and
    the run's caveats say where (:mod:`nfs.io.completeness`). The unit's channels while it is
    switched off (``powered`` = 0) are empty by definition, not missing. Rows whose fields
    are all empty (a spreadsheet's trailing ``,,,,``) are skipped like blank lines. Infinite
    values are errors in every column.

Whole runs
    A run shorter than its sidecar's ``duration_s``, or whose last line was cut while being
    written (fewer fields than the header), is refused with the rows found and expected,
    unless it is read with ``partial`` (:mod:`nfs.io.completeness`).

Values
    Every column is numeric: a value is what Python's ``float`` reads (after stripping
    blanks; ASCII only, no ``_`` digit separators), so ``1``, ``1.0``, ``1e3``, ``+2.5``
    and ``NaN`` all load. A non-numeric value in any column, known or not, is an error
    naming the column and line.

Units
    A value the format's units cannot hold is refused, the file, column and likely unit
    named (:func:`check_units`, ranges from :mod:`nfs.ranges`): thermometers that do not
    start near ``start_temperature_c`` (kelvin, Fahrenheit), gyro dwell means whose span
    across positions is not the Earth rate in deg/h (deg/s, rad/s, rad/h), specific forces
    that are not in g (m/s^2); so is a sidecar value outside its range.  An unusual value
    (outside its typical range) loads with one warning line.

Writing
    :func:`write_run` writes both files atomically (:mod:`nfs.io.atomic`), required columns
    first, each float in its shortest exact form (``repr``), so reading a written run gives
    back bitwise the same arrays, and the same run always gives the same bytes.
"""

from __future__ import annotations

import math
import os
import re
import tomllib
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from ..constants import ABSOLUTE_ZERO_C
from ..errors import MeasurementError
from ..ranges import check_tree, deferred_warnings
from ..run import Run, RunMeta
from .atomic import atomic_write_files
from .completeness import check_missing, check_whole
from .csv_columns import format_csv, read_columns
from .measurement_checks import check_columns, check_header, check_sample_rate, check_units
from .tomlio import toml_key, toml_value

__all__ = ["FORMAT", "read_run", "read_runs", "find_runs", "write_run", "meta_from_dict"]

#: The format tag written to and required in ``NAME.toml``.
FORMAT = "nfs-measurement/1"

_UNSAFE_NAME = re.compile(r'[,"\r\n]')


# ---------------------------------------------------------------------------------------------
# Paths


def _run_files(path: str | os.PathLike) -> tuple[Path, Path]:
    """``(NAME.csv, NAME.toml)`` for a path given as ``NAME.csv``, ``NAME.toml`` or ``NAME``."""
    path = Path(path)
    if path.suffix.lower() in (".csv", ".toml"):
        stem = path.with_suffix("")
    else:
        stem = path
    return stem.with_name(stem.name + ".csv"), stem.with_name(stem.name + ".toml")


def find_runs(paths: str | os.PathLike | Iterable[str | os.PathLike]) -> list[Path]:
    """The ``NAME.csv`` of every run that *paths* name, in the order given.

    Each path is a run (``NAME.csv``, ``NAME.toml`` or the stem ``NAME``) or a folder, which
    stands for every ``*.csv`` directly inside it, sorted by name. A run named twice is
    listed once.

    Raises
    ------
    MeasurementError
        A path that does not exist, a file that is not ``.csv``/``.toml``, a folder without
        any ``*.csv``, or no paths at all.
    """
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    found: list[Path] = []
    for given in paths:
        path = Path(given)
        if path.is_dir():
            csvs = sorted(p for p in path.glob("*.csv") if p.is_file())
            if not csvs:
                raise MeasurementError("folder holds no runs (no *.csv files)", file=path)
            found.extend(csvs)
        elif path.is_file():
            if path.suffix.lower() not in (".csv", ".toml"):
                raise MeasurementError(
                    "not a measurement file: expected NAME.csv or NAME.toml", file=path)
            found.append(_run_files(path)[0])
        elif path.suffix.lower() not in (".csv", ".toml") and _run_files(path)[0].is_file():
            found.append(_run_files(path)[0])  # the stem of a run
        else:
            raise MeasurementError("no such file or folder", file=path)
    if not found:
        raise MeasurementError("no measurement files or folders given")
    unique: dict[Path, Path] = {}
    for csv_path in found:
        unique.setdefault(csv_path.resolve(), csv_path)
    return list(unique.values())


# ---------------------------------------------------------------------------------------------
# NAME.toml


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number(doc: Mapping, key: str, file: Path, *, required: bool = False,
            low: float | None = None, high: float | None = None,
            low_open: bool = False) -> float | None:
    """A finite number from *doc* as float, within [low, high] (or (low, high])."""
    if key not in doc:
        if required:
            raise MeasurementError("required key is missing", file=file, key=key)
        return None
    value = doc[key]
    if not _is_number(value):
        raise MeasurementError(f"must be a number, not {type(value).__name__} {value!r}",
                               file=file, key=key)
    value = float(value)
    if not math.isfinite(value):
        raise MeasurementError(f"must be finite, not {value!r}", file=file, key=key)
    if low is not None and (value <= low if low_open else value < low):
        bound = ">" if low_open else ">="
        raise MeasurementError(f"must be {bound} {low!r}, not {value!r}", file=file, key=key)
    if high is not None and value > high:
        raise MeasurementError(f"must be <= {high!r}, not {value!r}", file=file, key=key)
    return value


def meta_from_dict(doc: Mapping, *, file: str | os.PathLike | None = None, shown: str = "",
                   warn: bool = True) -> RunMeta:
    """The keys of a sidecar as parsed from TOML, checked as the reader checks
    ``NAME.toml``, as a :class:`RunMeta`.

    Parameters
    ----------
    doc : mapping
        ``format`` (exactly :data:`FORMAT`), ``latitude_deg``, ``start_temperature_c`` and
        the optional keys of docs/measurement-format.md; any other key goes to ``extra``.
    file : path, optional
        The file named in an error.
    shown : str
        The table the keys sit in, when not at the file's top (``"run"``: an error names
        ``run.latitude_deg``).
    warn : bool
        Warn about unusual values (:mod:`nfs.ranges`, ``measurement.*``).

    Raises
    ------
    MeasurementError
        A missing or mistyped key, a value outside its range.
    """
    try:
        meta = _meta_fields(doc, file)
    except MeasurementError as exc:
        if not shown or exc.key is None:
            raise
        raise MeasurementError(exc.message, file=exc.file, key=f"{shown}.{exc.key}") from None
    check_tree(dict(doc), file=file, error=MeasurementError, canonical="measurement",
               shown=shown, quiet=not warn)
    return meta


def _meta_fields(doc: Mapping, file: Path) -> RunMeta:
    if "format" not in doc:
        raise MeasurementError(f'required key is missing; must be "{FORMAT}"',
                               file=file, key="format")
    if doc["format"] != FORMAT:
        raise MeasurementError(f'must be "{FORMAT}", not {doc["format"]!r}',
                               file=file, key="format")
    positions = doc.get("positions_deg")
    if positions is not None:
        if not isinstance(positions, list) or not positions:
            raise MeasurementError(
                f"must be a non-empty list of numbers, not {positions!r}",
                file=file, key="positions_deg")
        for k, value in enumerate(positions):
            if not _is_number(value) or not math.isfinite(value):
                raise MeasurementError(f"must be a finite number, not {value!r}",
                                       file=file, key=f"positions_deg[{k}]")
        positions = tuple(float(v) for v in positions)
    instrument = doc.get("instrument")
    if instrument is not None and not isinstance(instrument, str):
        raise MeasurementError(
            f"must be a string, not {type(instrument).__name__} {instrument!r}",
            file=file, key="instrument")
    return RunMeta(
        latitude_deg=_number(doc, "latitude_deg", file, required=True, low=-90.0, high=90.0),
        start_temperature_c=_number(doc, "start_temperature_c", file, required=True,
                                    low=ABSOLUTE_ZERO_C),
        true_heading_deg=_number(doc, "true_heading_deg", file),
        sample_rate_hz=_number(doc, "sample_rate_hz", file, low=0.0, low_open=True),
        positions_deg=positions,
        dwell_s=_number(doc, "dwell_s", file, low=0.0, low_open=True),
        move_s=_number(doc, "move_s", file, low=0.0),
        duration_s=_number(doc, "duration_s", file, low=0.0, low_open=True),
        instrument=instrument,
        extra={k: v for k, v in doc.items() if k not in _META_KEYS},
    )


#: Keys of NAME.toml that RunMeta holds in its own fields, in the order they are written.
_META_KEYS = ("format", "latitude_deg", "start_temperature_c", "true_heading_deg",
              "sample_rate_hz", "positions_deg", "dwell_s", "move_s", "duration_s",
              "instrument")


def _read_meta(path: Path) -> RunMeta:
    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise MeasurementError(f"TOML syntax error: {exc}", file=path) from None
    except UnicodeDecodeError as exc:
        raise MeasurementError(f"not UTF-8 text: {exc.reason}", file=path) from None
    except OSError as exc:
        raise MeasurementError(f"cannot read: {exc.strerror}", file=path) from None
    return meta_from_dict(doc, file=path)


# The TOML value writer is nfs.io.tomlio's (tomllib only reads TOML); errors get the file here.

def _toml_value(value: object, key: str, file: Path) -> str:
    """One TOML value, or MeasurementError naming the key when it cannot be written."""
    try:
        return toml_value(value)
    except TypeError as exc:
        raise MeasurementError(str(exc), file=file, key=key) from None


def _format_meta(meta: RunMeta, file: Path) -> str:
    """``NAME.toml`` text of *meta*: format tag, required keys, given optional keys, extra."""
    values: dict[str, object] = {
        "format": FORMAT,
        "latitude_deg": meta.latitude_deg,
        "start_temperature_c": meta.start_temperature_c,
        "true_heading_deg": meta.true_heading_deg,
        "sample_rate_hz": meta.sample_rate_hz,
        "positions_deg": meta.positions_deg,
        "dwell_s": meta.dwell_s,
        "move_s": meta.move_s,
        "duration_s": meta.duration_s,
        "instrument": meta.instrument,
    }
    lines = []
    for key, value in values.items():
        if value is None:
            continue
        if _is_number(value) or isinstance(value, np.number):
            value = float(value)
        elif key == "positions_deg" and isinstance(value, (list, tuple, np.ndarray)):
            value = [float(v) if _is_number(v) or isinstance(v, np.number) else v
                     for v in value]
        lines.append(f"{key} = {_toml_value(value, key, file)}")
    for key, value in meta.extra.items():
        if key in _META_KEYS:
            raise MeasurementError("extra key clashes with a key of the format",
                                   file=file, key=key)
        if value is None:
            raise MeasurementError("TOML has no null value", file=file, key=key)
        lines.append(f"{toml_key(str(key))} = {_toml_value(value, str(key), file)}")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Public reading


def read_run(path: str | os.PathLike, *, partial: bool = False,
             allow_nan: bool = False) -> Run:
    """Read one run from ``NAME.csv`` and ``NAME.toml``.

    Parameters
    ----------
    path : str or path-like
        ``NAME.csv``, ``NAME.toml`` or the stem ``NAME``.
    partial : bool
        Read a run that is not whole (shorter than its sidecar's ``duration_s``, or its last
        line cut while written: that line is left out) instead of refusing it.
    allow_nan : bool
        Read missing samples (empty fields, ``nan``) as NaN instead of refusing them.

    Returns
    -------
    Run
        Columns in file order as float64 arrays (missing samples NaN), the metadata,
        ``path`` set to ``NAME.csv``, and in ``caveats`` what ``partial`` and ``allow_nan``
        let through, one sentence each.

    Raises
    ------
    MeasurementError
        A missing file, a TOML syntax error or a wrong key, or a CSV fault (see the module
        docstring); a partial run (the rows found and expected) or missing samples (the
        columns and their first rows) unless asked to read them; the message names the
        file and the key, column or line.
    """
    csv_path, toml_path = _run_files(path)
    if not csv_path.is_file():
        if toml_path.is_file():
            raise MeasurementError(f"run has no sample file {csv_path.name} next to its "
                                   f"{toml_path.name}", file=csv_path)
        raise MeasurementError("no such file", file=csv_path)
    if not toml_path.is_file():
        raise MeasurementError(f"run has no metadata file {toml_path.name} "
                               f"({FORMAT} needs NAME.csv and NAME.toml)", file=csv_path)
    with deferred_warnings():
        meta = _read_meta(toml_path)
        table = read_columns(csv_path)
        columns = table.columns
        check_sample_rate(meta, columns["time_s"], toml_path, csv_path)
        check_units(meta, columns, file=csv_path, toml_file=toml_path)
        caveats = (check_whole(meta, columns["time_s"], file=csv_path, toml_name=toml_path.name,
                               cut=table.cut, partial=partial),
                   check_missing(columns, file=csv_path, line_of=table.line_of,
                                 allow_nan=allow_nan))
    return Run(name=csv_path.stem, columns=columns, meta=meta, path=csv_path,
               caveats=tuple(c for c in caveats if c))


def _natural_key(name: str) -> tuple:
    """Sort key of a run name with its digit groups compared as numbers (``r2`` < ``r10``)."""
    return tuple((0, int(part), "") if part.isdigit() else (1, 0, part)
                 for part in re.split(r"(\d+)", name) if part)


def read_runs(paths: str | os.PathLike | Iterable[str | os.PathLike], *,
              partial: bool = False, allow_nan: bool = False) -> list[Run]:
    """Read every run that *paths* name (files, stems or folders; see :func:`find_runs`),
    ordered by start temperature, then by name (digit groups as numbers), so that tables,
    reports and figures list -32 C before -5 C before +17 C whatever the file names;
    ``partial`` and ``allow_nan`` as in :func:`read_run`."""
    with deferred_warnings():
        runs = [read_run(csv_path, partial=partial, allow_nan=allow_nan)
                for csv_path in find_runs(paths)]
    return sorted(runs, key=lambda r: (r.meta.start_temperature_c, _natural_key(r.name)))


# ---------------------------------------------------------------------------------------------
# Writing


def _columns_for_writing(run: Run, file: Path) -> dict[str, np.ndarray]:
    """The run's columns as 1-D float64 arrays of one length, with valid names."""
    columns: dict[str, np.ndarray] = {}
    for name, values in run.columns.items():
        if not isinstance(name, str) or not name or name != name.strip() \
                or _UNSAFE_NAME.search(name):
            raise MeasurementError("column name must be non-empty text without commas, "
                                   "quotes, line breaks or surrounding blanks",
                                   file=file, column=str(name))
        try:
            array = np.asarray(values, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise MeasurementError(f"values are not numbers: {exc}", file=file,
                                   column=name) from None
        if array.ndim != 1:
            raise MeasurementError(f"must be one-dimensional, not shape {array.shape}",
                                   file=file, column=name)
        columns[name] = array
    check_header(list(columns), file, 1)
    n = len(columns["time_s"])
    for name, array in columns.items():
        if len(array) != n:
            raise MeasurementError(f"has {len(array)} samples, time_s has {n}", file=file,
                                   column=name)
    if n == 0:
        raise MeasurementError("run has no samples", file=file)
    check_columns(columns, file=file)
    return columns


def write_run(run: Run, target: str | os.PathLike) -> Path:
    """Write *run* as ``NAME.csv`` and ``NAME.toml``, atomically; return the ``.csv`` path.

    Parameters
    ----------
    run : Run
        The run. Its columns are checked as on reading (:func:`check_columns`), and the
        metadata are read back from the TOML text before anything is written, so a written
        run always reads back.
    target : str or path-like
        A folder (created if missing): the files are ``target/<run.name>.csv`` and
        ``.toml``. Or a path ending in ``.csv`` or ``.toml``: its stem names both files.

    Notes
    -----
    Required columns come first in :data:`REQUIRED_COLUMNS` order, then the others in the
    run's order. Floats are written in their shortest exact form, all-integral columns as
    integers, NaN as an empty field, lines end in ``"\\n"``: reading the files back gives
    bitwise the same arrays (NaN at the same places), and the same run gives the same bytes.
    Both files are written to temporary files first and renamed into place only when both
    succeeded (:func:`nfs.io.atomic.atomic_write_files`).

    Raises
    ------
    MeasurementError
        A run that would not read back: missing or malformed column, a value out of range,
        metadata of the wrong type.
    """
    target = Path(target)
    if target.suffix.lower() in (".csv", ".toml"):
        csv_path, toml_path = _run_files(target)
    else:
        name = run.name
        if not name or name in (".", "..") or "/" in name or "\\" in name:
            raise MeasurementError(f"run name {name!r} cannot be a file name",
                                   file=target)
        csv_path, toml_path = _run_files(target / name)
    columns = _columns_for_writing(run, csv_path)
    toml_text = _format_meta(run.meta, toml_path)
    try:
        meta = meta_from_dict(tomllib.loads(toml_text), file=toml_path, warn=False)
    except tomllib.TOMLDecodeError as exc:  # a bug of _format_meta, not of the run
        raise AssertionError(f"nfs wrote invalid TOML for {toml_path}: {exc}") from exc
    check_sample_rate(meta, columns["time_s"], toml_path, csv_path)
    check_units(meta, columns, file=csv_path, toml_file=toml_path, warn=False)
    csv_text = format_csv(columns)
    csv_path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_files({csv_path: csv_text, toml_path: toml_text})
    return csv_path