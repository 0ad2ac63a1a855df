"""A sweep's bookkeeping around its computation: the store prepared and the missing cells
listed before, the table and the figures' record after.

None of this computes a cell or draws a figure, so a sweep whose every cell is stored and
whose figures are current (:func:`stored_sweep`) imports neither the simulator, the
learners, the executors nor matplotlib: it costs reading the store.  :func:`nfs.sweep.run_sweep`
is these steps around the computation of the missing cells and the drawing of the figures.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import nfs

from ..io.atomic import atomic_write_text
from ..io.provenance import sha256_of_text
from .definition import SweepSpec
from .keys import CellTask, canonical, cell_tasks, scenario_digest
from .results_table import write_csv, write_parquet
from .store import CellStore

__all__ = ["SweepPlan", "SweepResult", "FIGURES_RECORD", "plan_sweep", "write_tables",
           "kept_figures", "record_figures", "stored_sweep"]

#: The digest of what the figures show and their file names (:func:`kept_figures`).
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


@dataclass(frozen=True)
class SweepPlan:
    """A sweep's folder prepared and what it lacks (:func:`plan_sweep`)."""

    spec: SweepSpec
    """The checked sweep."""
    store: CellStore
    """The sweep's cell store (its folder created)."""
    manifest: str
    """The text of ``sweep.json``: the sweep as run (axes, seeds, base digest, version)."""
    missing: tuple[CellTask, ...]
    """The cells not in the store, in row order."""


def _manifest(spec: SweepSpec, base: str) -> str:
    """The text of ``sweep.json`` for ``spec`` on the base scenario of digest ``base``."""
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


def plan_sweep(spec: SweepSpec, output: str | Path) -> SweepPlan:
    """Prepare ``output`` (its cell store), write ``sweep.json`` and list the cells of
    ``spec`` that are not stored yet."""
    store = CellStore(output)
    store.prepare()
    base = scenario_digest(spec)
    manifest = _manifest(spec, base)
    atomic_write_text(store.folder / "sweep.json", manifest)
    missing = tuple(t for t in cell_tasks(spec, base) if not store.has(t.key))
    return SweepPlan(spec, store, manifest, missing)


def write_tables(plan: SweepPlan) -> tuple[int, list[Path]]:
    """(rows, paths): ``results.csv`` (and ``results.parquet`` when pyarrow is importable)
    assembled from the store."""
    folder = plan.store.folder
    paths = [folder / "results.csv"]
    n_rows = write_csv(plan.spec, plan.store, paths[0])
    if write_parquet(plan.spec, plan.store, folder / "results.parquet"):
        paths.append(folder / "results.parquet")
    return n_rows, paths


def _figures_digest(plan: SweepPlan) -> str:
    """SHA-256 of what the figures show: the manifest and ``results.csv``."""
    return sha256_of_text(plan.manifest + (plan.store.folder / "results.csv").read_text(
        encoding="utf-8"))


def kept_figures(plan: SweepPlan) -> list[Path] | None:
    """The figures already drawn of what the sweep now shows, or None when they must be
    drawn (again).

    The figures are a function of the sweep (its manifest: axes, seeds, spec, code version)
    and of the table assembled from the store (``results.csv``, written first by
    :func:`write_tables`): their SHA-256 is kept in ``figures.json`` beside the files, and a
    rerun that finds the same digest and every file in place keeps them.
    """
    try:
        kept = json.loads((plan.store.folder / FIGURES_RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(kept, dict):      # a record not of ours: draw again
        return None
    files = [plan.store.folder / str(f) for f in kept.get("files", [])]
    if kept.get("digest") == _figures_digest(plan) and all(f.is_file() for f in files):
        return files
    return None


def record_figures(plan: SweepPlan, paths: list[Path]) -> None:
    """Keep the digest of what the figures ``paths`` (just drawn) show, in ``figures.json``."""
    atomic_write_text(plan.store.folder / FIGURES_RECORD,
                      json.dumps({"digest": _figures_digest(plan),
                                  "files": [p.name for p in paths]}, indent=1) + "\n")


def stored_sweep(plan: SweepPlan, *, figures: bool = True) -> SweepResult | None:
    """The result of the sweep ``plan`` prepared (:func:`plan_sweep`) when every cell is
    stored and (with ``figures``) its figures are current: the table written again from the
    store, nothing computed or drawn; None when a cell is missing or a figure must be drawn
    (then :func:`nfs.sweep.run_sweep` does it, given the same plan)."""
    if plan.missing:
        return None
    n_rows, paths = write_tables(plan)
    if figures:
        kept = kept_figures(plan)
        if kept is None:
            return None
        paths += kept
    return SweepResult(plan.spec.n_cells, 0, n_rows, tuple(paths))
