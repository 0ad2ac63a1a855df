"""Monte Carlo sweeps of start-up experiments: ``nfs sweep SWEEP.toml -o DIR``.

- :mod:`~nfs.sweep.definition`: the sweep file (base scenario, axes, seeds, method, spec), checked
  as a whole before anything runs;
- :mod:`~nfs.sweep.keys`: one point x one seed as data, its canonical inputs and hash;
- :mod:`~nfs.sweep.cells`: what a worker computes of a batch of cells;
- :mod:`~nfs.sweep.store`: each finished cell stored under its hash (resumable);
- :mod:`~nfs.sweep.executors`: local joblib workers or a Dask cluster, and the progress;
- :mod:`~nfs.sweep.results_table`: the tidy table, streamed from the store (CSV, Parquet);
- :mod:`~nfs.sweep.figures`: heading RMSE and time to spec against each axis;
- :mod:`~nfs.sweep.plan`: the store prepared, the missing cells, the table and the figures'
  record (a fully stored rerun is this alone: :func:`~nfs.sweep.plan.stored_sweep`);
- :mod:`~nfs.sweep.estimate`: the missing cells' runs, time and disk before they run;
- :mod:`~nfs.sweep.run`: the whole sweep.

The names below load on first use (SPEC 1 lazy loading, as :mod:`nfs` itself does): each
module imports what it needs at its top, and ``from nfs.sweep import load_sweep`` loads
the definition, not the simulator, the learners, joblib and matplotlib, which a sweep whose
every cell is stored does not use.
"""

from importlib import import_module

#: Public name -> the module of this package that defines it.
_PUBLIC = {
    "Axis": "definition", "Draws": "definition", "SweepError": "definition",
    "SweepSpec": "definition", "load_sweep": "definition", "sweep_from_dict": "definition",
    "CellTask": "keys", "canonical": "keys", "digest": "keys", "cell_key": "keys",
    "cell_tasks": "keys",
    "run_cell": "cells", "run_cells": "cells", "cell_batches": "cells",
    "BATCH_CELLS": "cells",
    "CellStore": "store",
    "LocalExecutor": "executors", "DaskExecutor": "executors", "SweepProgress": "executors",
    "columns": "results_table", "iter_rows": "results_table", "write_csv": "results_table",
    "write_parquet": "results_table",
    "write_figures": "figures",
    "SweepResult": "plan", "stored_sweep": "plan",
    "estimate_sweep": "estimate", "missing_cells": "estimate",
    "run_sweep": "run",
}

__all__ = list(_PUBLIC)


def __getattr__(name: str):
    """Load a public name from its module on first use (PEP 562)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'nfs.sweep' has no attribute {name!r}")
    value = getattr(import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
