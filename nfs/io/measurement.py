"""The measurement format ``nfs-measurement/1`` (docs/measurement-format.md).

A run is two files with one stem: ``NAME.csv`` (samples) and ``NAME.toml`` (metadata).

Reading
    :func:`read_run` reads one run, :func:`read_runs` any number of files and folders,
    :func:`find_runs` only lists the runs a set of paths names. Every fault in the input
    raises :class:`~nfs.errors.MeasurementError` whose message names the file and, where they
    apply, the column, the 1-based line (the header is line 1) or the TOML key.

Missing values
    An empty field or ``nan`` is a missing sample (NaN). It is allowed in every column except
    ``time_s``, ``position_deg`` and ``moving``: without those a sample cannot be placed in
    the schedule, so their absence is an error. A missing gyro, accelerometer or temperature
    sample (a logger drop-out inside a dwell) is read as NaN and left to the consumers, which
    must skip or interpolate it. Rows whose fields are all empty (a spreadsheet's trailing
    ``,,,,``) are skipped like blank lines. Infinite values are errors in every column.

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

import csv
import io
import math
import os
import re
import tomllib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nfs.constants import ABSOLUTE_ZERO_C, OMEGA_IE_DPH
from nfs.docfields import document_fields
from nfs.errors import MeasurementError
from nfs.io.atomic import atomic_write_files
from nfs.io.tomlio import toml_key, toml_value
from nfs.ranges import (G_N_M_PER_S2, KELVIN_OFFSET, check_tree, deferred_warnings, find,
                        warn_unusual)

__all__ = [
    "FORMAT",
    "REQUIRED_COLUMNS",
    "NO_MISSING_COLUMNS",
    "MAX_ABS_ACC_G",
    "SAMPLE_RATE_RTOL",
    "RunMeta",
    "Run",
    "read_run",
    "read_runs",
    "find_runs",
    "write_run",
    "check_columns",
    "check_units",
    "MAX_TEMPERATURE_C",
]

#: The format tag written to and required in ``NAME.toml``.
FORMAT = "nfs-measurement/1"

#: Required CSV columns, in the order the writer puts them first.
REQUIRED_COLUMNS: tuple[str, ...] = (
    "time_s", "position_deg", "moving", "gyro_dph", "acc_x_g", "acc_y_g",
    "temp_fog_c", "temp_acc_x_c", "temp_acc_y_c",
)

#: Required columns that may not hold a missing value (NaN): they place a sample in time
#: and in the turntable schedule.
NO_MISSING_COLUMNS: tuple[str, ...] = ("time_s", "position_deg", "moving")

#: Largest physically possible |specific force| of an ``acc_*_g`` column [g] (the spec;
#: :mod:`nfs.ranges`, ``measurement.columns.acc_*_g``).
MAX_ABS_ACC_G = find("measurement.columns.acc_x_g").hard[1]

#: Highest temperature a ``temp_*_c`` column may read [degC] (:mod:`nfs.ranges`).
MAX_TEMPERATURE_C = find("measurement.columns.temp_fog_c").hard[1]

#: Relative tolerance between ``sample_rate_hz`` and the median step of ``time_s``.
SAMPLE_RATE_RTOL = 0.01

_TEMPERATURE_COLUMN = re.compile(r"temp_.*_c")
_ACCELERATION_COLUMN = re.compile(r"acc_.*_g")


@document_fields
@dataclass(frozen=True)
class RunMeta:
    """What the samples of a run do not say (``NAME.toml``)."""

    latitude_deg: float
    """Latitude L of the site [deg]."""
    start_temperature_c: float
    """The chamber's soak temperature T0 before power-on [degC]."""
    true_heading_deg: float | None = None
    """Azimuth of the FOG axis at turntable position 0 [deg], clockwise from north, if known."""
    sample_rate_hz: float | None = None
    """Nominal sample rate [Hz], if given."""
    positions_deg: tuple[float, ...] | None = None
    """The indexing sequence of one north-finding cycle [deg], if given."""
    dwell_s: float | None = None
    """Time at each position [s], if given."""
    move_s: float | None = None
    """Time to move between positions [s], if given."""
    instrument: str | None = None
    """Free text naming the instrument."""
    extra: dict = field(default_factory=dict)
    """Any other keys of the TOML file, kept and passed along."""


@document_fields
@dataclass(frozen=True)
class Run:
    """One start-up run: named sample columns plus metadata.

    ``columns`` maps each CSV column name to a float array (``moving`` as 0.0/1.0), in file
    order; every array has the same length.
    """

    name: str
    """The stem of the files (``NAME``)."""
    columns: dict[str, np.ndarray]
    """Column name -> samples."""
    meta: RunMeta
    """Metadata from ``NAME.toml``."""
    path: Path | None = None
    """The ``NAME.csv`` this run was read from, if any."""

    def __getitem__(self, column: str) -> np.ndarray:
        return self.columns[column]

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return len(self.columns["time_s"])


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


def _meta_from_toml(doc: Mapping, file: Path, warn: bool = True) -> RunMeta:
    """Check the parsed ``NAME.toml`` and turn it into a :class:`RunMeta`; every number
    against its range (:mod:`nfs.ranges`, ``measurement.*``; ``warn``: unusual values warn)."""
    meta = _meta_fields(doc, file)
    check_tree(dict(doc), file=file, error=MeasurementError, canonical="measurement",
               quiet=not warn)
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
        instrument=instrument,
        extra={k: v for k, v in doc.items() if k not in _META_KEYS},
    )


#: Keys of NAME.toml that RunMeta holds in its own fields, in the order they are written.
_META_KEYS = ("format", "latitude_deg", "start_temperature_c", "true_heading_deg",
              "sample_rate_hz", "positions_deg", "dwell_s", "move_s", "instrument")


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
    return _meta_from_toml(doc, path)


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
# NAME.csv: checks shared by the reader and the writer


def _first(mask: np.ndarray) -> int | None:
    hits = np.flatnonzero(mask)
    return int(hits[0]) if hits.size else None


def check_columns(columns: Mapping[str, np.ndarray], *, file: str | os.PathLike | None = None,
                  line_of: Callable[[int], int] | None = None) -> None:
    """Check sample columns against the format; raise on the first fault.

    Checks, in this order: every value finite or NaN; no NaN in :data:`NO_MISSING_COLUMNS`
    and not every sample NaN in any required column;
    ``time_s`` strictly increasing; ``moving`` 0 or 1; every ``temp_*_c`` >= -273.15;
    every ``|acc_*_g|`` <= 2. Also that the required columns are there; equal lengths and
    float dtype are the caller's concern (the reader and :func:`write_run` ensure them).

    Parameters
    ----------
    columns : mapping
        Column name -> float array.
    file : path, optional
        The file named in the error.
    line_of : callable, optional
        Sample index -> 1-based line number in *file*; default ``index + 2`` (header line 1).

    Raises
    ------
    MeasurementError
        Naming the file, the column and the line of the first offending sample.
    """
    if line_of is None:
        def line_of(i: int) -> int:
            return i + 2

    def fail(message: str, name: str, index: int) -> MeasurementError:
        return MeasurementError(message, file=file, column=name, row=line_of(index))

    missing = [name for name in REQUIRED_COLUMNS if name not in columns]
    if missing:
        raise MeasurementError(f"required column{'s' if len(missing) > 1 else ''} missing: "
                               f"{', '.join(missing)}", file=file,
                               column=missing[0] if len(missing) == 1 else None)

    for name, values in columns.items():
        i = _first(np.isinf(values))
        if i is not None:
            raise fail(f"value {float(values[i])!r} is not finite", name, i)
    for name in NO_MISSING_COLUMNS:
        i = _first(np.isnan(columns[name]))
        if i is not None:
            raise fail(f"missing value ({', '.join(NO_MISSING_COLUMNS)} "
                       "must be given in every row)", name, i)
    for name in REQUIRED_COLUMNS:
        if len(columns[name]) and np.isnan(columns[name]).all():
            raise MeasurementError("every sample is missing (a required column needs "
                                   "values)", file=file, column=name)
    time = columns["time_s"]
    i = _first(~(np.diff(time) > 0.0))
    if i is not None:
        raise fail(f"time does not increase: {float(time[i + 1])!r} after {float(time[i])!r}",
                   "time_s", i + 1)
    moving = columns["moving"]
    i = _first((moving != 0.0) & (moving != 1.0))
    if i is not None:
        raise fail(f"must be 0 or 1, not {float(moving[i])!r}", "moving", i)
    for name, values in columns.items():
        if _TEMPERATURE_COLUMN.fullmatch(name):
            i = _first(values < ABSOLUTE_ZERO_C)
            if i is not None:
                raise fail(f"temperature {float(values[i])!r} C is below absolute zero "
                           f"({ABSOLUTE_ZERO_C} C)", name, i)
            i = _first(values > MAX_TEMPERATURE_C)
            if i is not None:
                raise fail(f"temperature {float(values[i])!r} C is above the "
                           f"{MAX_TEMPERATURE_C:g} C no working north finder reaches", name, i)
        elif _ACCELERATION_COLUMN.fullmatch(name):
            i = _first(np.abs(values) > MAX_ABS_ACC_G)
            if i is not None:
                v = float(values[i])
                hint = (f"; m/s^2? ({v / G_N_M_PER_S2:.4g} g)"
                        if abs(v) / G_N_M_PER_S2 <= MAX_ABS_ACC_G else "")
                raise fail(f"|{v!r}| g exceeds the physical limit of "
                           f"{MAX_ABS_ACC_G} g{hint}", name, i)


# ---------------------------------------------------------------------------------------------
# NAME.csv against NAME.toml: the units the samples must be in


#: Positions closer than this (modulo 360 deg) are one position when the dwell means are
#: grouped [deg] (the north-finding solver's tolerance).
_POSITION_TOL_DEG = 0.5

#: Thermometer samples from the first this many seconds are compared with
#: ``start_temperature_c`` [s].
_POWER_ON_WINDOW_S = 60.0


def check_units(meta: RunMeta, columns: Mapping[str, np.ndarray], *,
                file: str | os.PathLike | None = None, toml_file: str | os.PathLike | None = None,
                warn: bool = True) -> None:
    """Check that the samples are in the units of the format, given the sidecar: raise
    :class:`MeasurementError` naming the file, the column and the likely unit otherwise.

    - every thermometer (``temp_*_c``) reads, over its first minute, near
      ``start_temperature_c`` (a soaked unit): more than 100 K away is impossible
      (kelvin: a reading near T0 + 273.15; Fahrenheit), more than 20 K unusual;
    - the gyro's dwell means (``moving`` = 0, pooled by position) span, across positions
      that see the horizontal Earth rate whatever the heading, what Omega_ie cos L in deg/h
      gives: at least ``g`` Omega_ie cos L, where ``g`` is the least spread of cos(psi +
      theta_k) over every heading psi (sqrt(2) for 0/90/180/270).  A span 3600x too small
      is deg/s, 206265x rad/s, 57x rad/h (``measurement.columns.gyro_dph.earth_rate``);
      skipped for positions on one line and within 6 deg of a pole;
    - the median |specific force| of each ``acc_*_g`` column on a levelled table: above
      0.5 g impossible, above 0.05 g (a 3 deg tilt) unusual; m/s^2 is 9.81x.
    """
    t0 = meta.start_temperature_c
    time = np.asarray(columns["time_s"], dtype=float)
    first = time <= time[0] + _POWER_ON_WINDOW_S
    for name, values in columns.items():
        if not _TEMPERATURE_COLUMN.fullmatch(name):
            continue
        v = values[first]
        v = v[np.isfinite(v)]
        if not v.size:
            continue
        reading = float(np.median(v))
        r = find(f"measurement.columns.{name}.at_power_on")
        d = reading - t0
        if not (r.impossible(d) or (warn and r.unusual(d))):
            continue
        if abs(reading - KELVIN_OFFSET - t0) <= 30.0:
            hint = f"kelvin? ({reading:g} K is {reading - KELVIN_OFFSET:.2f} C)"
        elif abs((reading - 32.0) * 5.0 / 9.0 - t0) <= 10.0:
            hint = f"Fahrenheit? ({reading:g} F is {(reading - 32.0) * 5.0 / 9.0:.1f} C)"
        else:
            hint = "is start_temperature_c right?"
        msg = (f"reads {reading:g} C over its first minute, {d:+g} K from "
               f"start_temperature_c = {t0:g} C"
               + (f" of {Path(toml_file).name}" if toml_file is not None else "")
               + f" (a soaked unit starts within {r.typical[1]:g} K of it, never "
               f"{r.hard[1]:g} K away); {hint}")
        if r.impossible(d):
            raise MeasurementError(msg, file=file, column=name)
        warn_unusual(msg + "; running anyway", file=file, column=name)
    _check_gyro_units(meta, columns, file, warn)
    moving = np.asarray(columns["moving"]) != 0.0
    for name, values in columns.items():
        if not _ACCELERATION_COLUMN.fullmatch(name):
            continue
        v = np.abs(values[~moving])
        v = v[np.isfinite(v)]
        if not v.size:
            continue
        median = float(np.median(v))
        r = find(f"measurement.columns.{name}.median")
        if not (r.impossible(median) or (warn and r.unusual(median))):
            continue
        hint = (f"; m/s^2? ({median / G_N_M_PER_S2:.3g} g)"
                if not r.unusual(median / G_N_M_PER_S2) else "")
        msg = (f"median |{median:.4g}| g while turned about a vertical axis: {r.what} "
               f"{r.typical_text()} (never {r.hard[1]:g} g){hint}")
        if r.impossible(median):
            raise MeasurementError(msg, file=file, column=name)
        warn_unusual(msg + "; running anyway", file=file, column=name)


def _least_spread(angles_deg: np.ndarray) -> float:
    """min over headings psi of max_k cos(psi + theta_k) - min_k cos(psi + theta_k)."""
    psi = np.radians(np.arange(0.0, 360.0, 0.5))[:, None]
    c = np.cos(psi + np.radians(angles_deg)[None, :])
    return float(np.min(c.max(axis=1) - c.min(axis=1)))


def _check_gyro_units(meta: RunMeta, columns: Mapping[str, np.ndarray], file,
                      warn: bool) -> None:
    """The span of the gyro's dwell means across positions against the horizontal Earth
    rate in deg/h (:func:`check_units`)."""
    omega_h = OMEGA_IE_DPH * math.cos(math.radians(meta.latitude_deg))
    if omega_h < OMEGA_IE_DPH * 0.1:
        return
    gyro = np.asarray(columns["gyro_dph"], dtype=float)
    still = (np.asarray(columns["moving"]) == 0.0) & np.isfinite(gyro)
    if np.count_nonzero(still) < 2:
        return
    key = np.round(np.mod(columns["position_deg"][still], 360.0) / _POSITION_TOL_DEG)
    key = np.mod(key, round(360.0 / _POSITION_TOL_DEG))
    groups, inverse = np.unique(key, return_inverse=True)
    if len(groups) < 2:
        return
    means = np.bincount(inverse, weights=gyro[still]) / np.bincount(inverse)
    g = _least_spread(groups * _POSITION_TOL_DEG)
    if g < 0.5:
        return
    spread = float(means.max() - means.min())
    ratio = spread / (g * omega_h)
    r = find("measurement.columns.gyro_dph.earth_rate")
    if not (r.impossible(ratio) or (warn and r.unusual(ratio))):
        return
    hint = ""
    for factor, _, unit in r.slips:
        if not r.unusual(ratio * factor):
            hint = f"; {unit}? (x{factor:.6g}: a span of {spread * factor:.4g} deg/h)"
            break
    msg = (f"the dwell means span {spread:.4g} deg/h across {len(groups)} positions, where "
           f"the Earth rate alone spans {g * omega_h:.4g}-{2 * omega_h:.4g} deg/h "
           f"(15.041 cos L at latitude {meta.latitude_deg:g} deg): not deg/h{hint}")
    if r.impossible(ratio):
        raise MeasurementError(msg, file=file, column="gyro_dph")
    warn_unusual(msg + "; running anyway", file=file, column="gyro_dph")


def _check_sample_rate(meta: RunMeta, time: np.ndarray, toml_file: Path,
                       csv_file: Path) -> None:
    """``sample_rate_hz`` against the median step of ``time_s`` (within 1 %)."""
    if meta.sample_rate_hz is None or len(time) < 2:
        return
    step = float(np.median(np.diff(time)))
    if abs(step * meta.sample_rate_hz - 1.0) > SAMPLE_RATE_RTOL:
        raise MeasurementError(
            f"sample_rate_hz = {meta.sample_rate_hz!r} does not match the median step of "
            f"time_s in {csv_file.name} ({step!r} s, i.e. {1.0 / step!r} Hz; tolerance "
            f"{SAMPLE_RATE_RTOL:.0%})", file=toml_file, key="sample_rate_hz")


def _check_header(names: list[str], file: Path, line: int) -> None:
    seen: set[str] = set()
    for k, name in enumerate(names):
        if not name:
            raise MeasurementError(f"header field {k + 1} is empty (every column needs a "
                                   "name)", file=file, row=line)
        if name in seen:
            raise MeasurementError("column name appears twice in the header", file=file,
                                   column=name, row=line)
        seen.add(name)
    missing = [name for name in REQUIRED_COLUMNS if name not in seen]
    if missing:
        raise MeasurementError(
            f"required column{'s' if len(missing) > 1 else ''} missing: "
            f"{', '.join(missing)} (the header has: {', '.join(names)})",
            file=file, column=missing[0] if len(missing) == 1 else None, row=line)


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


def _parse_csv_careful(text: str, file: Path) -> tuple[list[str], list[np.ndarray], list[int]]:
    """Names, columns and the line of every sample; raises on the first fault."""
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
        _check_header(names, file, header_line)
        n = len(names)
        t = names.index("time_s")
        rows: list[list[str]] = []
        lines: list[int] = []
        for row in reader:
            if len(row) != n:
                if _is_blank(row):
                    continue
                raise MeasurementError(
                    f"row has {len(row)} field{'s' if len(row) != 1 else ''}, the header "
                    f"has {n}", file=file, row=reader.line_num)
            if not row[t].strip() and _is_blank(row):
                continue
            rows.append(row)
            lines.append(reader.line_num)
    except csv.Error as exc:
        raise MeasurementError(f"CSV syntax error: {exc}", file=file,
                               row=reader.line_num) from None
    if not rows:
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
        raise MeasurementError(f"cannot read {shown!r} as a number", file=file, column=name,
                               row=lines[bad])
    return names, columns, lines


def _read_columns(path: Path) -> dict[str, np.ndarray]:
    """The checked columns of ``NAME.csv``, in file order."""
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
    try:
        names, data = _parse_csv_fast(text)
        _check_header(names, path, 1)
        columns = dict(zip(names, data))
        line_of = None
    except (_UseCarefulPath, MeasurementError):
        names, arrays, lines = _parse_csv_careful(text, path)
        columns = dict(zip(names, arrays))
        line_of = lines.__getitem__
    check_columns(columns, file=path, line_of=line_of)
    return columns


# ---------------------------------------------------------------------------------------------
# Public reading


def read_run(path: str | os.PathLike) -> Run:
    """Read one run from ``NAME.csv`` and ``NAME.toml``.

    Parameters
    ----------
    path : str or path-like
        ``NAME.csv``, ``NAME.toml`` or the stem ``NAME``.

    Returns
    -------
    Run
        Columns in file order as float64 arrays (missing samples NaN), the metadata, and
        ``path`` set to ``NAME.csv``.

    Raises
    ------
    MeasurementError
        A missing file, a TOML syntax error or a wrong key, or a CSV fault (see the module
        docstring); the message names the file and the key, column or line.
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
        columns = _read_columns(csv_path)
        _check_sample_rate(meta, columns["time_s"], toml_path, csv_path)
        check_units(meta, columns, file=csv_path, toml_file=toml_path)
    return Run(name=csv_path.stem, columns=columns, meta=meta, path=csv_path)


def _natural_key(name: str) -> tuple:
    """Sort key of a run name with its digit groups compared as numbers (``r2`` < ``r10``)."""
    return tuple((0, int(part), "") if part.isdigit() else (1, 0, part)
                 for part in re.split(r"(\d+)", name) if part)


def read_runs(paths: str | os.PathLike | Iterable[str | os.PathLike]) -> list[Run]:
    """Read every run that *paths* name (files, stems or folders; see :func:`find_runs`),
    ordered by start temperature, then by name (digit groups as numbers), so that tables,
    reports and figures list -32 C before -5 C before +17 C whatever the file names."""
    with deferred_warnings():
        runs = [read_run(csv_path) for csv_path in find_runs(paths)]
    return sorted(runs, key=lambda r: (r.meta.start_temperature_c, _natural_key(r.name)))


# ---------------------------------------------------------------------------------------------
# Writing

_UNSAFE_NAME = re.compile(r'[,"\r\n]')


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


def _format_csv(columns: Mapping[str, np.ndarray]) -> str:
    names = [name for name in REQUIRED_COLUMNS if name in columns]
    names += [name for name in columns if name not in REQUIRED_COLUMNS]
    texts = [_format_column(columns[name]) for name in names]
    return ",".join(names) + "\n" + "\n".join(map(",".join, zip(*texts))) + "\n"


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
    _check_header(list(columns), file, 1)
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
        meta = _meta_from_toml(tomllib.loads(toml_text), toml_path, warn=False)
    except tomllib.TOMLDecodeError as exc:  # a bug of _format_meta, not of the run
        raise AssertionError(f"nfs wrote invalid TOML for {toml_path}: {exc}") from exc
    _check_sample_rate(meta, columns["time_s"], toml_path, csv_path)
    check_units(meta, columns, file=csv_path, toml_file=toml_path, warn=False)
    csv_text = _format_csv(columns)
    csv_path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_files({csv_path: csv_text, toml_path: toml_text})
    return csv_path
