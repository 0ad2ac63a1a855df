"""Run a sweep: the missing cells on an executor, each stored as it finishes, then the table
and the figures assembled from the store."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import nfs

from ..io.atomic import atomic_write_text
from .cells import canonical, cell_batches, cell_tasks, run_cells, scenario_digest
from .executors import LocalExecutor, SweepProgress
from .figures import write_figures
from .definition import SweepSpec
from .store import CellStore
from .results_table import write_csv, write_parquet

__all__ = ["SweepResult", "run_sweep"]


@dataclass(frozen=True)
class SweepResult:
    """What a sweep did."""

    n_cells: int
    """Cells of the sweep."""
    n_computed: int
    """Cells computed by this call (the others were in the store)."""
    n_rows: int
    """Rows of the table."""
    paths: tuple[Path, ...]
    """Files written: results.csv, results.parquet (with pyarrow), figures."""


def _manifest(spec: SweepSpec, base: str) -> str:
    axes = [{"key": a.key, "target": a.target,
             **({"values": list(a.values)} if not a.drawn else
                {"low": a.low, "high": a.high, "log": a.log})} for a in spec.axes]
    return json.dumps({
        "sweep": None if spec.path is None else str(spec.path),
        "scenario": "default" if spec.scenario_path is None else str(spec.scenario_path),
        "scenario_digest": base, "version": nfs.__version__, "axes": axes,
        "draws": canonical(spec.draws), "seeds": list(spec.seeds), "method": spec.method,
        "spec_deg": spec.spec_deg, "rmse_window_cycles": spec.rmse_window_cycles,
        "n_cells": spec.n_cells}, indent=1) + "\n"


def run_sweep(spec: SweepSpec, output: str | Path, *, executor=None, quiet: bool = False,
              on_cell: Callable[[dict[str, Any]], None] | None = None,
              figures: bool = True, log: Callable[[str], None] | None = None) -> SweepResult:
    """Compute the cells of ``spec`` missing from ``output/cells``, then write
    ``output/results.csv`` (and ``results.parquet`` when pyarrow is importable) and the
    summary figures.

    Parameters
    ----------
    spec : SweepSpec
        The checked sweep (:func:`~nfs.sweep.load_sweep`).
    output : path
        The sweep's folder (created); a rerun into the same folder reuses its cells.
    executor : LocalExecutor or DaskExecutor, optional
        Where the cells run (default: local joblib on every core).  Not closed here.
    quiet : bool
        No progress output.
    on_cell : callable, optional
        Called with each record right after it is stored (in this process).
    figures : bool
        Write the summary figures.
    log : callable, optional
        Receives one-line messages (default: nothing).
    """
    store = CellStore(output)
    store.prepare()
    base = scenario_digest(spec)
    atomic_write_text(store.folder / "sweep.json", _manifest(spec, base))
    missing = [t for t in cell_tasks(spec, base) if not store.has(t.key)]
    n_missing = len(missing)
    executor = executor or LocalExecutor()
    if log is not None:
        log(f"{spec.n_cells} cells, {spec.n_cells - n_missing} already stored, "
            f"{n_missing} to compute ({executor.describe()})")
    progress = SweepProgress(n_missing, quiet=quiet)
    n_done = 0
    try:
        if n_missing:
            for records in executor.map_unordered(run_cells, cell_batches(missing)):
                for record in records:
                    store.write(record)
                    n_done += 1
                    progress.update()
                    if on_cell is not None:
                        on_cell(record)
    finally:
        progress.close()
    paths = [store.folder / "results.csv"]
    n_rows = write_csv(spec, store, paths[0])
    if write_parquet(spec, store, store.folder / "results.parquet"):
        paths.append(store.folder / "results.parquet")
    if figures:
        paths += write_figures(spec, store, store.folder)
    return SweepResult(spec.n_cells, n_done, n_rows, tuple(paths))
