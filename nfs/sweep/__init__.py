"""Monte Carlo sweeps of start-up experiments: ``nfs sweep SWEEP.toml -o DIR``.

- :mod:`~nfs.sweep.definition`: the sweep file (base scenario, axes, seeds, method, spec), checked
  as a whole before anything runs;
- :mod:`~nfs.sweep.cells`: one point x one seed, its hash and what a worker computes;
- :mod:`~nfs.sweep.store`: each finished cell stored under its hash (resumable);
- :mod:`~nfs.sweep.executors`: local joblib workers or a Dask cluster, and the progress;
- :mod:`~nfs.sweep.results_table`: the tidy table, streamed from the store (CSV, Parquet);
- :mod:`~nfs.sweep.figures`: heading RMSE and time to spec against each axis;
- :mod:`~nfs.sweep.run`: the whole sweep.
"""

from .cells import (BATCH_CELLS, CellTask, canonical, cell_batches, cell_key, cell_tasks,
                    digest, run_cell, run_cells)
from .executors import DaskExecutor, LocalExecutor, SweepProgress
from .figures import write_figures
from .run import SweepResult, run_sweep
from .definition import Axis, Draws, SweepError, SweepSpec, load_sweep, sweep_from_dict
from .store import CellStore
from .results_table import columns, iter_rows, write_csv, write_parquet

__all__ = ["Axis", "Draws", "SweepError", "SweepSpec", "load_sweep", "sweep_from_dict",
           "CellTask", "canonical", "digest", "cell_key", "cell_tasks", "run_cell",
           "run_cells", "cell_batches", "BATCH_CELLS",
           "CellStore", "LocalExecutor", "DaskExecutor", "SweepProgress", "columns",
           "iter_rows", "write_csv", "write_parquet", "write_figures", "SweepResult",
           "run_sweep"]
