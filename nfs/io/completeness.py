"""Whether a run is whole: its rows against its sidecar, a line cut while written, missing
samples.

A logger that stops early, a disk that fills, a copy made while the file was still being
written: each leaves a run that reads as a good one, only shorter. And a drop-out leaves
empty fields. The reader refuses both by default, with the counts that show it, and reads
them when asked (``partial``, ``allow_nan`` of :func:`nfs.io.measurement.read_run`; the
commands' ``--partial`` and ``--allow-nan``); the run then carries what was accepted as its
:attr:`~nfs.run.Run.caveats`, which every output made from it states.

Whole
    A sidecar that gives ``duration_s`` says how long the record is: ``round(duration_s /
    step)`` rows, the step being ``1 / sample_rate_hz`` or the median step of ``time_s``. A
    run whose rows cover less (first sample to last, plus one step) by more than half a
    step is partial. A last line with fewer fields than the header (and nothing after it) is
    a line cut while written: partial too.

Missing
    A sample is missing where a value is due and the field is empty (or ``nan``): in every
    row of a column, except the unit's own channels (everything but ``time_s``,
    ``position_deg``, ``moving``, ``powered`` and ``temp_chamber_c``) while the unit is
    switched off (``powered`` = 0), which are empty by definition
    (docs/power_cycles.md).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ..docfields import document_fields
from ..errors import MeasurementError
from ..power import POWERED_COLUMN
from ..run import RunMeta

__all__ = ["ALWAYS_RECORDED", "CutLine", "expected_rows", "missing_samples",
           "describe_missing", "check_missing", "check_whole"]

#: Columns recorded whether the unit is on or off (the schedule, the power state, the
#: chamber's own thermometer): a missing value in them is missing in every row.
ALWAYS_RECORDED = ("time_s", "position_deg", "moving", POWERED_COLUMN, "temp_chamber_c")

#: Rows of a column listed in a message before the count says the rest.
_ROWS_SHOWN = 5


@document_fields
@dataclass(frozen=True)
class CutLine:
    """The last line of a CSV file, cut while written: fewer fields than the header."""

    line: int
    """Its 1-based line number (the header is line 1)."""
    fields: int
    """Fields it has."""
    header_fields: int
    """Fields of the header."""

    def text(self) -> str:
        """``'its last line (row L) has F of N fields: cut while written'``."""
        return (f"its last line (row {self.line}) has {self.fields} of {self.header_fields} "
                "fields: the file was cut while being written")


def _step_s(meta: RunMeta, time_s: np.ndarray) -> float | None:
    if meta.sample_rate_hz is not None:
        return 1.0 / meta.sample_rate_hz
    if time_s.size >= 2:
        return float(np.median(np.diff(time_s)))
    return None


def expected_rows(meta: RunMeta, time_s: np.ndarray) -> int | None:
    """Rows the sidecar's ``duration_s`` asks for (``round(duration_s / step)``), or None
    when it gives no duration or the run has no step to count by."""
    step = _step_s(meta, np.asarray(time_s, dtype=float))
    if meta.duration_s is None or step is None or not step > 0.0:
        return None
    return int(round(meta.duration_s / step))


def check_whole(meta: RunMeta, time_s: np.ndarray, *, file: str | os.PathLike | None,
                toml_name: str, cut: CutLine | None = None,
                partial: bool = False) -> str | None:
    """Refuse a partial run (module docstring) with the rows found and expected, or, with
    ``partial``, return the sentence that says what was read (None for a whole run).

    Parameters
    ----------
    meta : RunMeta
        The sidecar (``duration_s``, ``sample_rate_hz``).
    time_s : array
        The run's times [s], the rows read (without a cut last line).
    file : path
        The file named in the error.
    toml_name : str
        The sidecar's name, said where its ``duration_s`` is quoted.
    cut : CutLine, optional
        The cut last line, left out of ``time_s``.
    partial : bool
        Read it anyway.

    Raises
    ------
    MeasurementError
        A partial run without ``partial``.
    """
    t = np.asarray(time_s, dtype=float)
    n = int(t.size)
    expected = expected_rows(meta, t)
    short = False
    if expected is not None and n:
        step = _step_s(meta, t)
        covered = float(t[-1] - t[0]) + step
        short = covered < meta.duration_s - 0.5 * step
    if cut is None and not short:
        return None
    rows = (f"{n} rows found, {expected} expected (duration_s = {meta.duration_s:g} s in "
            f"{toml_name})" if expected is not None else
            f"{n} complete rows found, at least {n + 1} expected")
    what = ([cut.text()] if cut is not None else []) + (
        [f"the rows cover {float(t[-1] - t[0]) + _step_s(meta, t):g} s"] if short else [])
    if not partial:
        raise MeasurementError(f"the run is partial: {'; '.join(what)}; {rows}; read the "
                               "rows found with --partial (read_run(..., partial=True))",
                               file=file, row=cut.line if cut is not None else None)
    return (f"partial, read with --partial: {rows}"
            + (f"; the cut last line (row {cut.line}) left out" if cut is not None else ""))


def missing_samples(columns: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Column -> indices of its missing samples (module docstring), for the columns that
    miss any, in column order."""
    powered = columns.get(POWERED_COLUMN)
    on = None if powered is None else np.asarray(powered, dtype=float) != 0.0
    out = {}
    for name, values in columns.items():
        gone = np.isnan(np.asarray(values, dtype=float))
        if on is not None and name not in ALWAYS_RECORDED:
            gone &= on
        if gone.any():
            out[name] = np.flatnonzero(gone)
    return out


def describe_missing(missing: Mapping[str, np.ndarray],
                     line_of: Callable[[int], int] | None = None) -> str:
    """``'gyro_dph: 3 (rows 5, 19, 20); temp_fog_c: 1 (row 7)'``: each column's count and
    its first rows (``line_of``: sample index -> 1-based line; default index + 2)."""
    if line_of is None:
        def line_of(i: int) -> int:
            return i + 2
    parts = []
    for name, index in missing.items():
        shown = [str(line_of(int(i))) for i in index[:_ROWS_SHOWN]]
        more = ", ..." if index.size > _ROWS_SHOWN else ""
        word = "row" if index.size == 1 else "rows"
        parts.append(f"{name}: {index.size} ({word} {', '.join(shown)}{more})")
    return "; ".join(parts)


def check_missing(columns: Mapping[str, np.ndarray], *, file: str | os.PathLike | None,
                  line_of: Callable[[int], int] | None = None,
                  allow_nan: bool = False) -> str | None:
    """Refuse missing samples (module docstring), naming the columns and their first rows,
    or, with ``allow_nan``, return the sentence that says what was read (None: none).

    Raises
    ------
    MeasurementError
        Missing samples without ``allow_nan``.
    """
    missing = missing_samples(columns)
    if not missing:
        return None
    text = describe_missing(missing, line_of)
    total = sum(int(v.size) for v in missing.values())
    if not allow_nan:
        first = min(missing, key=lambda c: missing[c][0])
        row = (line_of or (lambda i: i + 2))(int(missing[first][0]))
        raise MeasurementError(
            f"{total} missing sample{'s' if total > 1 else ''} (empty or nan) where a value "
            f"is due: {text}; read them as missing with --allow-nan "
            "(read_run(..., allow_nan=True))",
            file=file, column=first if len(missing) == 1 else None, row=row)
    return (f"{total} missing sample{'s' if total > 1 else ''} read with --allow-nan "
            f"(left out where they fall: a dwell mean, a fit window; a chamber record with a "
            f"gap is set aside for T0): {text}")
