"""Run a sweep: the missing cells on an executor, each stored as it finishes, then the table
and the figures assembled from the store."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

from .cells import cell_batches, run_cells
from .executors import LocalExecutor, SweepProgress
from .figures import write_figures
from .definition import SweepSpec
from .plan import (FIGURES_RECORD, SweepPlan, SweepResult, kept_figures, plan_sweep,
                   record_figures, write_tables)

__all__ = ["SweepResult", "run_sweep", "FIGURES_RECORD"]


def run_sweep(spec: SweepSpec, output: str | Path, *, executor=None, quiet: bool = False,
              on_cell: Callable[[dict[str, Any]], None] | None = None,
              figures: bool = True, log: Callable[[str], None] | None = None,
              plan: SweepPlan | None = None) -> SweepResult:
    """Compute the cells of ``spec`` missing from ``output/cells``, then write
    ``output/results.csv`` (and ``results.parquet`` when pyarrow is importable) and the
    summary figures (drawn only when what they show changed: :func:`~nfs.sweep.plan.kept_figures`).

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
    plan : SweepPlan, optional
        ``output`` already prepared for ``spec`` by :func:`~nfs.sweep.plan.plan_sweep` (as
        ``nfs sweep`` does before it looks for a fully stored sweep): not planned again.
    """
    plan = plan_sweep(spec, output) if plan is None else plan
    store, missing = plan.store, plan.missing
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
    n_rows, paths = write_tables(plan)
    if figures:
        kept = kept_figures(plan)
        if kept is None:
            kept = write_figures(spec, store, store.folder)
            record_figures(plan, kept)
        paths += kept
    return SweepResult(spec.n_cells, n_done, n_rows, tuple(paths))
