"""Assertions for a user's own pytest suite: keep a heading table, or a compensator, honest.

* :func:`assert_table_within`: a heading table against a baseline that ``nfs table --json``
  wrote earlier, cell by cell, beyond noise and a relative tolerance (the comparison of
  ``nfs table --baseline``: :mod:`nfs.scoring.baseline`);
* :func:`assert_compensator_no_worse`: a trained compensator against no compensation on the
  same runs, start temperature by start temperature, beyond noise;
* :func:`assert_time_to_spec_below`: every run's time to spec (after power-on, the time from
  which every north-finding cycle's heading error stays within a spec) under a bound.

``examples/test_my_instrument.py`` is a test file to copy.  Each raises ``AssertionError``
listing the cells at fault, so pytest shows what got worse and by how much.

Agreement across platforms (operating system, CPU, BLAS, library versions)
-------------------------------------------------------------------------
The simulation is seeded (NumPy's generators give the same draws on every platform) and its
arithmetic is fixed, so the **uncompensated rows** (``before``, ``stable``, ``floor``) and
the cycle errors behind them agree within :data:`EXACT_ATOL_DEG` = 1e-8 deg: last-bit
differences of BLAS/LAPACK kernels stay far below the JSON's rounding (1e-9 deg for the cycle
errors, 1e-8 deg for the cells).  The **compensated rows** rest on fitted models; a tuned
row's search is chaotic in the last bits of its floating-point sums, so another platform can
land on other hyperparameters and move the row by more than its last printed digit while the
table's conclusions stay: those rows agree **within their noise** (no cell worse beyond its
95 % interval and the 5 % tolerance, :func:`assert_table_within`'s default).  The same
reasoning fixes what the README's tables must reproduce (``docs/readme_numbers.py``).
``tests/test_testing.py`` checks both on the machine it runs on against a table stored with
the package (``tests/data/regression/``), and that a table does not depend on the number of
parallel workers.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from .compensate import load_compensator
from .io.measurement import read_runs
from .northfind import north_find, run_time_to_spec_s
from .scoring.baseline import TOLERANCE, BaselineComparison, compare_tables
from .scoring.heading_table import pooled_rmse
from .scoring.tablefile import TableData

__all__ = ["assert_table_within", "assert_compensator_no_worse", "assert_time_to_spec_below",
           "EXACT_ATOL_DEG"]

#: How far the uncompensated rows may move across platforms [deg].
EXACT_ATOL_DEG = 1e-8


def _message(head: str, comp: BaselineComparison) -> str:
    lines = [head, comp.summary()]
    lines += [f"  {c.label()}: {c.baseline_deg:.6f} -> {c.new_deg:.6f} deg "
              f"({100.0 * c.relative:+.1f} %, change 95 % CI [{c.ci_low_deg:+.6f}, "
              f"{c.ci_high_deg:+.6f}] deg)" for c in comp.worse]
    lines += [f"  note: {n}" for n in comp.notes]
    return "\n".join(lines)


def assert_table_within(table_or_json, baseline_json, tolerance: float = TOLERANCE, *,
                        exact_rows: Sequence[str] = (), atol_deg: float = EXACT_ATOL_DEG,
                        n_boot: int | None = None) -> BaselineComparison:
    """Assert that no cell of a heading table is worse than the baseline's beyond noise and
    ``tolerance``.

    Parameters
    ----------
    table_or_json : HeadingTable, dict or path
        The table now: a :class:`~nfs.scoring.heading_table.HeadingTable`, its ``to_dict()``, or a JSON
        file written by ``nfs table --json``.
    baseline_json : path or dict
        The baseline: a JSON file written earlier by ``nfs table --json`` (or its dict).
    tolerance : float
        Relative tolerance (0.05: a cell fails only when it is more than 5 % above the
        baseline and its 95 % interval of the change lies above 0).
    exact_rows : sequence of str
        Rows that must also agree within ``atol_deg`` in every cell, better or worse (e.g.
        ``("before", "stable", "floor")`` for a rerun of the same scenario on another
        platform: see the module docstring).
    atol_deg : float
        Tolerance of ``exact_rows`` [deg].
    n_boot : int, optional
        Bootstrap replicates (default :data:`~nfs.scoring.intervals.DEFAULT_N_BOOT`).

    Returns
    -------
    BaselineComparison
        The comparison, when it passes.

    Raises
    ------
    AssertionError
        Listing the worse cells (their change and its interval) or the exact rows that moved.
    """
    kw = {} if n_boot is None else {"n_boot": n_boot}
    comp = compare_tables(table_or_json, baseline_json, tolerance=tolerance, **kw)
    moved = []
    for c in comp.cells:
        if c.method in exact_rows and c.temperature_c is not None and \
                not _close(c.new_deg, c.baseline_deg, atol_deg):
            moved.append(f"  {c.label()}: {c.baseline_deg!r} -> {c.new_deg!r} deg")
    missing = [r for r in exact_rows if r not in comp.methods]
    if moved or missing:
        raise AssertionError("\n".join(
            [f"rows that must agree within {atol_deg:g} deg moved:"] + moved
            + ([f"  rows not in both tables: {', '.join(missing)}"] if missing else [])))
    if comp.worse:
        raise AssertionError(_message(f"table worse than the baseline {comp.baseline}:", comp))
    return comp


def _close(a: float, b: float, atol: float) -> bool:
    if math.isnan(a) and math.isnan(b):
        return True
    return abs(a - b) <= atol


def assert_compensator_no_worse(compensator, runs, *, tolerance: float = 0.0,
                                startup_end_s: float = 3600.0, tilt_correction: bool = True,
                                settle_s: float = 0.0, n_boot: int | None = None
                                ) -> BaselineComparison:
    """Assert that a compensator makes no start temperature's start-up heading RMSE worse
    than no compensation, beyond noise, on the given runs.

    The runs are north-found as they are and with the compensator's drift subtracted; the
    start-up RMSE at each start temperature (runs of one T0 pooled, cycles ending within
    ``startup_end_s``) and its mean over the temperatures are compared *paired*, on the same
    runs and cycles (:func:`nfs.scoring.baseline.compare_tables`): a cell fails when the
    95 % interval of (compensated - uncompensated) lies above 0 and the change exceeds
    ``tolerance`` x the uncompensated RMSE.

    Parameters
    ----------
    compensator : DriftCompensator or path
        A trained compensator, or a model file written by ``nfs train``.
    runs : Run, path, or iterable of them
        Runs with a known heading (``true_heading_deg``): measurement files, folders, or
        :class:`~nfs.run.Run` objects.
    tolerance : float
        Relative tolerance (default 0: any change beyond noise fails).
    startup_end_s : float
        Start-up stage: cycles ending within this time [s].
    tilt_correction, settle_s
        North finding (:func:`nfs.northfind.north_find`).
    n_boot : int, optional
        Bootstrap replicates.

    Returns
    -------
    BaselineComparison
        The comparison (``baseline``: uncompensated), when it passes.

    Raises
    ------
    AssertionError
        Listing the start temperatures where the compensator is worse.
    ValueError
        A run without a known heading.
    """
    comp = compensator if hasattr(compensator, "compensate") else load_compensator(compensator)
    runs = _runs(runs)
    unknown = [r.name for r in runs if r.meta.true_heading_deg is None]
    if unknown:
        raise ValueError(f"run '{unknown[0]}' has no true_heading_deg: the heading error "
                         "needs the known heading")
    temps = sorted({float(r.meta.start_temperature_c) for r in runs})
    sides = []
    for label, rs in (("compensated", [comp.compensate(r) for r in runs]),
                      ("uncompensated", runs)):
        errs = [[] for _ in temps]
        for r in rs:
            nf = north_find(r, tilt_correction=tilt_correction, settle_s=settle_s)
            e = np.asarray(nf.error_deg)[np.asarray(nf.t_end_s) <= startup_end_s]
            errs[temps.index(float(r.meta.start_temperature_c))].append(e)
        rmse = tuple(pooled_rmse(col) for col in errs)
        sides.append(TableData(tuple(temps), {comp.method: rmse}, {comp.method: errs}, None,
                               None, f"{label} runs"))
    kw = {} if n_boot is None else {"n_boot": n_boot}
    result = compare_tables(sides[0], sides[1], tolerance=tolerance, paired=True, **kw)
    if result.worse:
        raise AssertionError(_message(f"{comp.method} is worse than no compensation on "
                                      f"{len(runs)} run(s):", result))
    return result


def assert_time_to_spec_below(runs, spec_deg: float, bound_s: float, *,
                              rolling: bool = False, compensator=None,
                              tilt_correction: bool = True, settle_s: float = 0.0
                              ) -> dict[str, float]:
    """Assert that every run reaches its heading spec within ``bound_s`` after power-on.

    Each run is north-found (after subtracting ``compensator``'s drift when one is given);
    its time to spec is the output time of the first cycle from which every later cycle's
    heading error stays within ``spec_deg`` (with ``rolling``, the rolling RMSE of
    :data:`nfs.northfind.time_to_spec.DEFAULT_WINDOW` cycles: :func:`nfs.northfind.run_time_to_spec_s`);
    a run that never stays within spec has an infinite time and fails.

    Parameters
    ----------
    runs : Run, path, or iterable of them
        Runs with a known heading (``true_heading_deg``).
    spec_deg : float
        Heading spec [deg], > 0.
    bound_s : float
        Largest acceptable time to spec [s].
    rolling : bool
        Judge the rolling RMSE instead of every single cycle.
    compensator : DriftCompensator or path, optional
        Compensate the runs first (a trained compensator or an ``nfs train`` model file).
    tilt_correction, settle_s
        North finding (:func:`nfs.northfind.north_find`).

    Returns
    -------
    dict
        Run name -> time to spec [s], when every run passes.

    Raises
    ------
    AssertionError
        Listing the runs over the bound with their times.
    ValueError
        A non-positive spec or a run without a known heading.
    """
    if not (math.isfinite(spec_deg) and spec_deg > 0.0):
        raise ValueError(f"spec_deg must be a finite number > 0, got {spec_deg}")
    runs = _runs(runs)
    unknown = [r.name for r in runs if r.meta.true_heading_deg is None]
    if unknown:
        raise ValueError(f"run '{unknown[0]}' has no true_heading_deg: the heading error "
                         "needs the known heading")
    if compensator is not None:
        comp = compensator if hasattr(compensator, "compensate") else \
            load_compensator(compensator)
        runs = [comp.compensate(r) for r in runs]
    times = {}
    for r in runs:
        nf = north_find(r, tilt_correction=tilt_correction, settle_s=settle_s)
        every, roll = run_time_to_spec_s(nf.t_end_s, nf.error_deg, spec_deg)
        times[r.name] = roll if rolling else every
    late = {n: t for n, t in times.items() if not t <= bound_s}
    if late:
        what = "rolling RMSE" if rolling else "heading error"
        raise AssertionError(
            f"{len(late)} of {len(times)} run(s) take longer than {bound_s:g} s for the "
            f"{what} to stay within {spec_deg:g} deg:\n" + "\n".join(
                f"  {n}: " + ("never within spec" if not math.isfinite(t) else f"{t:.0f} s")
                for n, t in late.items()))
    return times


def _runs(runs) -> list:
    if isinstance(runs, (str, Path)):
        return read_runs(runs)
    runs = list(runs) if isinstance(runs, Iterable) else [runs]
    paths = [r for r in runs if isinstance(r, (str, Path))]
    return [r for r in runs if not isinstance(r, (str, Path))] + (read_runs(paths)
                                                                   if paths else [])

