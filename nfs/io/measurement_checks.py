"""Checks of a run's samples against the measurement format and against its sidecar.

:func:`check_columns` checks the columns alone (names, finite values, ``moving`` 0/1, time
increasing, physically possible temperatures and specific forces); :func:`check_units`
checks that the samples are in the format's units given ``NAME.toml`` (ranges from
:mod:`nfs.ranges`; the likely unit slip named); :func:`check_sample_rate` and
:func:`check_header` are the reader's and the writer's shared checks.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from ..constants import ABSOLUTE_ZERO_C, OMEGA_IE_DPH, POSITION_TOL_DEG
from ..errors import MeasurementError
from ..ranges import G_N_M_PER_S2, KELVIN_OFFSET, find, warn_unusual
from ..run import NO_MISSING_COLUMNS, REQUIRED_COLUMNS, RunMeta

__all__ = ["MAX_ABS_ACC_G", "MAX_TEMPERATURE_C", "SAMPLE_RATE_RTOL", "check_columns",
           "check_values", "check_units", "check_sample_rate", "check_header"]

#: Largest physically possible ``|specific force|`` of an ``acc_*_g`` column [g] (the spec;
#: :mod:`nfs.ranges`, ``measurement.columns.acc_*_g``).
MAX_ABS_ACC_G = find("measurement.columns.acc_x_g").hard[1]

#: Highest temperature a ``temp_*_c`` column may read [degC] (:mod:`nfs.ranges`).
MAX_TEMPERATURE_C = find("measurement.columns.temp_fog_c").hard[1]

#: Relative tolerance between ``sample_rate_hz`` and the median step of ``time_s``.
SAMPLE_RATE_RTOL = 0.01

_TEMPERATURE_COLUMN = re.compile(r"temp_.*_c")
_ACCELERATION_COLUMN = re.compile(r"acc_.*_g")


# ---------------------------------------------------------------------------------------------
# NAME.csv: checks shared by the reader and the writer


def _first(mask: np.ndarray) -> int | None:
    hits = np.flatnonzero(mask)
    return int(hits[0]) if hits.size else None


def check_columns(columns: Mapping[str, np.ndarray], *, file: str | os.PathLike | None = None,
                  line_of: Callable[[int], int] | None = None) -> None:
    """Check sample columns against the format; raise on the first fault.

    Checks, in this order: the required columns are there; every value finite or NaN; no
    NaN in :data:`NO_MISSING_COLUMNS`; ``time_s`` strictly increasing; ``moving`` 0 or 1;
    every ``temp_*_c`` >= -273.15; every ``|acc_*_g|`` <= 2 (:func:`check_values`); not
    every sample NaN in any required column. Equal lengths and float dtype are the
    caller's concern (the reader and :func:`write_run` ensure them).

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
    missing = [name for name in REQUIRED_COLUMNS if name not in columns]
    if missing:
        raise MeasurementError(f"required column{'s' if len(missing) > 1 else ''} missing: "
                               f"{', '.join(missing)}", file=file,
                               column=missing[0] if len(missing) == 1 else None)
    check_values(columns, file=file, line_of=line_of)
    for name in REQUIRED_COLUMNS:
        if len(columns[name]) and np.isnan(columns[name]).all():
            raise MeasurementError("every sample is missing (a required column needs "
                                   "values)", file=file, column=name)


def check_values(columns: Mapping[str, np.ndarray], *, file: str | os.PathLike | None = None,
                 line_of: Callable[[int], int] | None = None) -> None:
    """The checks of :func:`check_columns` that each column's values answer for themselves,
    on whichever of the format's columns are there (a chamber log's source file holds a
    few): finite or NaN; no NaN in :data:`NO_MISSING_COLUMNS`; ``time_s`` strictly
    increasing; ``moving`` 0 or 1; ``temp_*_c`` >= -273.15 and below the highest a north
    finder reads; ``|acc_*_g|`` <= 2. Parameters and errors as :func:`check_columns`."""
    if line_of is None:
        def line_of(i: int) -> int:
            return i + 2

    def fail(message: str, name: str, index: int) -> MeasurementError:
        return MeasurementError(message, file=file, column=name, row=line_of(index))

    for name, values in columns.items():
        i = _first(np.isinf(values))
        if i is not None:
            raise fail(f"value {float(values[i])!r} is not finite", name, i)
    for name in NO_MISSING_COLUMNS:
        i = _first(np.isnan(columns[name])) if name in columns else None
        if i is not None:
            raise fail(f"missing value ({', '.join(NO_MISSING_COLUMNS)} "
                       "must be given in every row)", name, i)
    if "time_s" in columns:
        time = columns["time_s"]
        i = _first(~(np.diff(time) > 0.0))
        if i is not None:
            raise fail(f"time does not increase: {float(time[i + 1])!r} after "
                       f"{float(time[i])!r}", "time_s", i + 1)
    if "moving" in columns:
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
    - the median ``|specific force|`` of each ``acc_*_g`` column on a levelled table: above
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
    key = np.round(np.mod(columns["position_deg"][still], 360.0) / POSITION_TOL_DEG)
    key = np.mod(key, round(360.0 / POSITION_TOL_DEG))
    groups, inverse = np.unique(key, return_inverse=True)
    if len(groups) < 2:
        return
    means = np.bincount(inverse, weights=gyro[still]) / np.bincount(inverse)
    g = _least_spread(groups * POSITION_TOL_DEG)
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


def check_sample_rate(meta: RunMeta, time: np.ndarray, toml_file: Path,
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


def check_header(names: list[str], file: Path, line: int) -> None:
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

