"""A chamber log's files made one ``nfs-measurement/1`` run (``nfs import``).

The time base
    The gyro's source (the one that holds ``gyro_dph``) gives the run's times, as logged:
    its samples are not touched. ``time_s = 0`` is power-on: ``[run] power_on`` when the
    mapping gives it, else the gyro's first sample (absolute times) or its time zero
    (relative times). Absolute times of every source are counted from power-on; relative
    times are taken as already counted from it (plus the source's ``time_offset_s``).

Resampling
    Every other source is brought onto the gyro's times column by column, by the column's
    stated method (:data:`~nfs.io.log_mapping.METHODS`: ``linear`` for temperatures and
    forces by default, ``previous`` for the turntable and power states). At either end of a
    source, up to one of its own (median) steps is held at its end value: the reading a
    logger shows until its next sample. The method of every column is written in the
    sidecar (``imported``) and said by the command.

Gaps
    A gyro time that a source does not cover (before its first sample or after its last by
    more than one of its steps, or inside a hole: a step longer than ``max_gap_samples`` of
    its median steps) is a gap, and so is a hole in the gyro's own log. Nothing is filled:
    the import is refused, naming the source and the spans, or, with ``cut``, the run is
    cut to the longest stretch every source covers, and the sidecar and the command say so.

Checks
    Each source's values are checked on its own rows (:mod:`nfs.io.log_sources`); the run
    made is checked as the reader checks a run: the sidecar's sample rate and duration, and
    the units (:func:`~nfs.io.measurement_checks.check_units`: a thermometer in kelvin, a
    gyro in mdeg/h or rad/s), the error naming the source file and column the unit came
    from.
"""

from __future__ import annotations

import datetime as dt
import os
from dataclasses import replace

import numpy as np

from ..errors import InputError, MeasurementError
from ..run import REQUIRED_COLUMNS, Run
from .completeness import check_whole
from .log_mapping import METHODS, ColumnMap, LogMapping, read_mapping
from .log_sources import SourceData, read_source
from .measurement_checks import check_sample_rate, check_units

__all__ = ["import_log"]


def _power_on(mapping: LogMapping, data: list[SourceData]) -> dt.datetime | None:
    """The absolute time of power-on, or None when no source logs absolute times."""
    absolute = [d for d in data if d.anchor is not None]
    gyro = next(d for d in data if d.source is mapping.gyro)
    if mapping.power_on is not None:
        if not absolute:
            raise InputError("no source logs absolute times (time_format): power-on is "
                             "every source's time zero", file=mapping.path, key="run.power_on")
        fmt = absolute[0].source.time_format
        try:
            return dt.datetime.strptime(mapping.power_on, fmt)
        except ValueError as exc:
            raise InputError(f"cannot read {mapping.power_on!r} as a time of "
                             f"{absolute[0].source.key}.time_format {fmt!r}: {exc}",
                             file=mapping.path, key="run.power_on") from None
    if absolute and gyro.anchor is None:
        raise InputError(f"{absolute[0].source.key} logs absolute times and the gyro's "
                         "source relative ones: give [run] power_on (the absolute time of "
                         "time_s = 0)", file=mapping.path, key="run.power_on")
    return gyro.anchor


def _on_run_clock(d: SourceData, power_on: dt.datetime | None, path) -> np.ndarray:
    """A source's times counted from power-on [s] (whole microseconds for absolute times)."""
    if d.anchor is None:
        return d.time_s
    try:
        shift = (d.anchor - power_on) // dt.timedelta(microseconds=1)
    except TypeError:
        raise InputError(f"{d.source.key}: its times and power-on's do not agree on carrying "
                         "a time zone (%z)", file=path, key=f"{d.source.key}.time_format"
                         ) from None
    return (np.round(d.time_s * 1e6).astype(np.int64) + shift) / 1e6


def _holes(t: np.ndarray, step: float, max_gap: float) -> list[tuple[float, float]]:
    k = np.flatnonzero(np.diff(t) > max_gap * step)
    return [(float(t[i]), float(t[i + 1])) for i in k]


def _covered(tg: np.ndarray, ts: np.ndarray, step: float, max_gap: float) -> np.ndarray:
    """Gyro times a source of times ``ts`` covers (module docstring, Gaps)."""
    ok = (tg >= ts[0] - step) & (tg <= ts[-1] + step)
    for a, b in _holes(ts, step, max_gap):
        ok &= ~((tg > a) & (tg < b))
    return ok


def _longest(covered: np.ndarray, breaks: np.ndarray) -> tuple[int, int] | None:
    """First and last index of the longest stretch of ``covered`` samples with no break
    between neighbours (``breaks[i]``: a hole between samples i and i + 1)."""
    segment = np.r_[0, np.cumsum(breaks | ~covered[1:] | ~covered[:-1])]
    best = None
    for s in np.unique(segment[covered]):
        idx = np.flatnonzero((segment == s) & covered)
        if best is None or idx[-1] - idx[0] > best[1] - best[0]:
            best = (int(idx[0]), int(idx[-1]))
    return best


def _spans(t: np.ndarray, mask: np.ndarray) -> list[tuple[float, float]]:
    """(first, last) time of every stretch of ``mask``."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    return [(float(t[a]), float(t[b - 1])) for a, b in zip(edges[::2], edges[1::2])]


def _span_text(spans: list[tuple[float, float]]) -> str:
    shown = ", ".join(f"{a:.6g}-{b:.6g} s" for a, b in spans[:3])
    return shown + (f" and {len(spans) - 3} more" if len(spans) > 3 else "")


def _resample(tg: np.ndarray, ts: np.ndarray, v: np.ndarray, method: str) -> np.ndarray:
    if method == "linear":
        return np.interp(tg, ts, v)
    if method == "previous":
        i = np.searchsorted(ts, tg, side="right") - 1
        return v[np.clip(i, 0, ts.size - 1)]
    i = np.clip(np.searchsorted(ts, tg), 1, ts.size - 1)        # nearest
    i -= (tg - ts[i - 1]) <= (ts[i] - tg)
    return v[i]


def _rate_text(step: float) -> str:
    if not step > 0.0:
        return "one sample"
    return f"{1.0 / step:.3g} Hz" if step <= 1.0 else f"every {step:.3g} s"


def _relocate(exc: MeasurementError, where: dict[str, tuple[SourceData, ColumnMap]],
              mapping: LogMapping) -> MeasurementError:
    """A check of the run made, told of the source file and column its column came from."""
    if exc.column not in where:
        return MeasurementError(exc.message, file=mapping.path, key="run")
    d, c = where[exc.column]
    return MeasurementError(f"{exc.message} (logged in {c.unit}: {c.key}.unit of "
                            f"{mapping.path.name})", file=d.source.file, column=c.column)


def import_log(mapping: LogMapping | str | os.PathLike, *, cut: bool = False,
               partial: bool = False, allow_nan: bool = False) -> Run:
    """Make one ``nfs-measurement/1`` run of a chamber log's files (module docstring).

    Parameters
    ----------
    mapping : LogMapping, or the mapping's TOML file
        What each source file holds (:func:`~nfs.io.log_mapping.read_mapping`).
    cut : bool
        Cut the run to the longest stretch every source covers instead of refusing a gap.
    partial : bool
        Accept a run shorter than ``[run] duration_s`` and a source whose last line was cut
        while written (that line left out).
    allow_nan : bool
        Accept missing samples (empty fields) as NaN instead of refusing them.

    Returns
    -------
    Run
        On the gyro's time base, each column in the format's unit; its metadata from
        ``[run]`` with the sample rate (when not given) and the duration of the record
        (when not given), and under ``imported`` the account of the import: the mapping,
        the time base, every column's source and method, the cut. Its ``caveats`` say what
        ``partial`` and ``allow_nan`` let through. Write it with
        :func:`~nfs.io.measurement.write_run`.

    Raises
    ------
    InputError
        A bad mapping, a gap (the source and the spans it does not cover), a fault in a
        source file (its file, column and line), a unit slip (the source file and column).
    """
    if not isinstance(mapping, LogMapping):
        mapping = read_mapping(mapping)
    data = [read_source(s, partial=partial, allow_nan=allow_nan) for s in mapping.sources]
    power_on = _power_on(mapping, data)
    clock = {d.source.name: _on_run_clock(d, power_on, mapping.path) for d in data}
    gyro = next(d for d in data if d.source is mapping.gyro)
    tg = clock[gyro.source.name]
    step_g = gyro.step_s()
    covered = np.ones(tg.size, bool)
    breaks = np.diff(tg) > mapping.max_gap_samples * step_g      # holes in the gyro's log
    gaps = []
    if breaks.any():
        holes = _holes(tg, step_g, mapping.max_gap_samples)
        gaps.append((gyro, f"has holes at {_span_text(holes)} (steps over "
                           f"{mapping.max_gap_samples:g} of its {step_g:.3g} s)"))
    for d in data:
        if d is gyro:
            continue
        ts = clock[d.source.name]
        mask = _covered(tg, ts, d.step_s(), mapping.max_gap_samples)
        if not mask.all():
            gaps.append((d, f"does not cover {_span_text(_spans(tg, ~mask))} of the gyro's "
                            f"{tg[0]:.6g}-{tg[-1]:.6g} s (it logs {ts[0]:.6g}-{ts[-1]:.6g} s, "
                            f"{_rate_text(d.step_s())})"))
        covered &= mask
    keep = np.ones(tg.size, bool)
    cut_text = None
    if gaps:
        best = _longest(covered, breaks)
        what = "; ".join(f"{d.source.file.name} ({d.source.key}) {w}" for d, w in gaps)
        if not cut or best is None or best[1] == best[0]:
            raise MeasurementError(
                f"a gap: {what}; an import fills no gap"
                + (f": give --cut to keep the {tg[best[0]]:.6g}-{tg[best[1]]:.6g} s every "
                   "source covers" if best is not None and best[1] > best[0] and not cut
                   else ": no stretch is covered by every source" if cut else ""),
                file=gaps[0][0].source.file)
        keep[:] = False
        keep[best[0]:best[1] + 1] = True
        cut_text = (f"cut to {tg[best[0]]:.6g}-{tg[best[1]]:.6g} s of the gyro's "
                    f"{tg[0]:.6g}-{tg[-1]:.6g} s ({int(keep.sum())} of {tg.size} rows): {what}")
    t = tg[keep]
    columns: dict[str, np.ndarray] = {"time_s": t}
    where: dict[str, tuple[SourceData, ColumnMap]] = {}
    methods, used = [], set()
    for d in data:
        ts = clock[d.source.name]
        moved = []
        for c in d.source.columns:
            where[c.target] = (d, c)
            if d is gyro:
                columns[c.target] = d.columns[c.target][keep]
            else:
                columns[c.target] = _resample(t, ts, d.columns[c.target], c.method)
                moved.append(f"{c.target} ({c.column}, {c.unit}) by {c.method}")
                used.add(c.method)
        if moved:
            methods.append(f"{d.source.file.name} ({_rate_text(d.step_s())}) onto the "
                           "gyro's times: " + ", ".join(moved))
    order = [c for c in REQUIRED_COLUMNS if c in columns]
    columns = {c: columns[c] for c in order + [c for c in columns if c not in order]}
    if methods:
        methods.append("; ".join(f"{m}: {text}" for m, text in METHODS.items() if m in used)
                       + "; at a source's ends, up to one of its own steps held at its end "
                         "value")
    return _checked_run(mapping, data, gyro, columns, where, methods, cut_text, partial)


def _checked_run(mapping: LogMapping, data: list[SourceData], gyro: SourceData,
                 columns: dict[str, np.ndarray], where: dict, methods: list[str],
                 cut_text: str | None, partial: bool) -> Run:
    """The run made, its sidecar completed and checked as the reader checks a run."""
    t = columns["time_s"]
    step = float(np.median(np.diff(t))) if t.size > 1 else None
    changes = {}
    if mapping.meta.sample_rate_hz is None and step:
        changes["sample_rate_hz"] = round(1.0 / step, 9)
    if mapping.meta.duration_s is None and step and gyro.cut is None:
        changes["duration_s"] = round(t.size * step, 9)     # the record as logged
    meta = replace(mapping.meta, **changes)
    try:
        check_sample_rate(meta, t, mapping.path, gyro.source.file)
        check_units(meta, columns, file=mapping.path, toml_file=mapping.path)
        whole = check_whole(meta, t, file=gyro.source.file,
                            toml_name=f"[run] of {mapping.path.name}", cut=gyro.cut,
                            partial=partial)
    except MeasurementError as exc:
        if exc.key == "sample_rate_hz":
            raise MeasurementError(exc.message, file=mapping.path, key="run.sample_rate_hz"
                                   ) from None
        if exc.column is not None:
            raise _relocate(exc, where, mapping) from None
        raise
    caveats = [d.caveat for d in data if d.caveat] + ([whole] if whole else [])
    caveats += [f"{d.source.file.name}: {d.cut.text()}; left out (--partial)"
                for d in data if d.cut is not None and d is not gyro]
    imported = {
        "mapping": mapping.path.name,
        "time_base": f"{gyro.source.file.name} ({gyro.source.key}), {t.size} samples at "
                     f"{_rate_text(step) if step else 'one time'}, as logged",
        "resampling": methods or ["none: every column is the gyro's source's"],
    }
    if cut_text:
        imported["cut"] = cut_text
    if caveats:
        imported["caveats"] = caveats
    meta = replace(meta, extra={**meta.extra, "imported": imported})
    return Run(name=mapping.name, columns=columns, meta=meta, path=None,
               caveats=tuple(caveats))
