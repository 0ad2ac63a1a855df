"""Run a sweep: the missing cells on an executor, each stored as it finishes, then the table
and the figures assembled from the store."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import nfs

from ..io.atomic import atomic_write_text
from ..io.provenance import sha256_of_text
from .cells import canonical, cell_batches, cell_tasks, run_cells, scenario_digest
from .executors import LocalExecutor, SweepProgress
from .figures import write_figures
from .definition import SweepSpec
from .store import CellStore
from .results_table import write_csv, write_parquet

__all__ = ["SweepResult", "run_sweep", "FIGURES_RECORD"]

#: The digest of what the figures show and their file names (:func:`run_sweep`).
FIGURES_RECORD = "figures.json"


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
        Called with each record right after its batch of cells is stored (in this process;
        a batch's records are written and made durable together).
    figures : bool
        Write the summary figures.
    log : callable, optional
        Receives one-line messages (default: nothing).
    """
    store = CellStore(output)
    store.prepare()
    base = scenario_digest(spec)
    manifest = _manifest(spec, base)
    atomic_write_text(store.folder / "sweep.json", manifest)
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
                store.write_many(records)
                for record in records:
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
        paths += _figures(spec, store, manifest)
    return SweepResult(spec.n_cells, n_done, n_rows, tuple(paths))


def _figures(spec: SweepSpec, store: CellStore, manifest: str) -> list[Path]:
    """The summary figures, drawn only when what they show changed.

    The figures are a function of the sweep (its manifest: axes, seeds, spec, code version)
    and of the table assembled from the store (``results.csv``): their SHA-256 is kept in
    ``figures.json`` beside the files, and a rerun that finds the same digest and every file
    in place keeps them (a fully stored rerun costs reading the store, not drawing).
    """
    record = store.folder / FIGURES_RECORD
    drawn = sha256_of_text(manifest + (store.folder / "results.csv").read_text(
        encoding="utf-8"))
    try:
        kept = json.loads(record.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        kept = {}
    if not isinstance(kept, dict):      # a record not of ours: draw again
        kept = {}
    files = [store.folder / str(f) for f in kept.get("files", [])]
    if kept.get("digest") == drawn and all(f.is_file() for f in files):
        return files
    paths = write_figures(spec, store, store.folder)
    atomic_write_text(record, json.dumps({"digest": drawn, "files": [p.name for p in paths]},
                                         indent=1) + "\n")
    return paths
