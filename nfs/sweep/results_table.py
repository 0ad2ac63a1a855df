"""The sweep's tidy table: one row per run, method and stage, assembled by streaming the cells.

Columns, in order:

- one per axis (its dotted key), the point's value;
- ``seed`` (the cell's scenario seed), ``run`` (the run's file stem), ``unit``,
  ``start_temperature_c`` [degC];
- ``method`` (``none``: uncompensated; else the compensation method's key) and ``stage``
  (``startup``: cycles ending within ``northfind.startup_end_s``; ``stable``: cycles
  starting after ``northfind.stable_start_s``; as in the heading-RMSE table);
- ``heading_rmse_deg`` of the stage's cycles and their number ``n_cycles`` (``-`` when the
  stage has no cycle: a run that ends before the stable stage);
- ``time_to_spec_s`` and ``time_to_spec_rmse_s`` [s after power-on] of the whole run at the
  sweep's ``spec_deg`` (:mod:`nfs.northfind.time_to_spec`: ``inf`` never within spec up to the run's
  end, ``-`` no error to judge), the same in both stage rows of a run and method;
- ``floor_deg``, the white-noise floor sqrt(2/N) (ARW / sqrt(dwell)) / (Omega_ie cos L) of
  the cell's schedule and latitude (:func:`nfs.northfind.white_noise_floor_deg`);
- ``drift_mean_dph``, ``drift_std_dph``, ``drift_ptp_dph``: the simulated thermal drift (sum
  of the gyro effect terms, no noise) over the stage's samples [deg/h], the same for every
  method (the drift the compensator faces);
- ``cell``: the cell's hash (its record is ``cells/<cell>.json``).

Rows come in cell order (point-major, then seed), then run, method, stage.  Numbers are
written exactly (``repr``), so the bytes depend only on the cells' inputs: the same whatever
executor or worker count computed them.  Where nothing applies (a stage without cycles or
samples, a floor without a closed form) the CSV holds ``-``, as every table of the package
does, and Parquet a null.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any, Iterator

from ..io.atomic import atomic_output
from ..northfind.time_to_spec import run_time_to_spec_s
from ..scoring.heading_table import NOT_APPLICABLE
from .keys import STAGES, cell_tasks
from .definition import SweepSpec
from .store import CellStore

__all__ = ["columns", "iter_rows", "write_csv", "write_parquet", "format_value"]

_INT = ("seed", "unit", "n_cycles")
_STR = ("run", "method", "stage", "cell")


def columns(spec: SweepSpec) -> list[str]:
    """The table's columns (module docstring)."""
    cols = [a.key for a in spec.axes]
    cols += ["seed", "run", "unit", "start_temperature_c", "method", "stage",
             "heading_rmse_deg", "n_cycles"]
    cols += ["time_to_spec_s", "time_to_spec_rmse_s"]
    cols += ["floor_deg", "drift_mean_dph", "drift_std_dph", "drift_ptp_dph", "cell"]
    return cols


def iter_rows(spec: SweepSpec, store: CellStore) -> Iterator[dict[str, Any]]:
    """Every row, reading one cell record at a time."""
    for task in cell_tasks(spec):
        rec = store.read(task.key)
        values = task.values
        axes = {a.key: values[a.key] for a in spec.axes}
        for run in rec["runs"]:
            for method in sorted(run["methods"], key=lambda m: (m != "none", m)):
                res = run["methods"][method]
                a, b = run_time_to_spec_s(res["t_end_s"], res["error_deg"], spec.spec_deg,
                                          spec.rmse_window_cycles)
                tts = {"time_to_spec_s": a, "time_to_spec_rmse_s": b}
                for stage in STAGES:
                    drift = run["drift_dph"][stage]
                    yield {**axes, "seed": rec["seed"], "run": run["name"],
                           "unit": run["unit"],
                           "start_temperature_c": run["start_temperature_c"],
                           "method": method, "stage": stage,
                           "heading_rmse_deg": res["rmse_deg"][stage],
                           "n_cycles": res["n_cycles"][stage], **tts,
                           "floor_deg": run["floor_deg"], "drift_mean_dph": drift["mean"],
                           "drift_std_dph": drift["std"], "drift_ptp_dph": drift["ptp"],
                           "cell": task.key}


def format_value(v: Any) -> str:
    """A cell of the CSV: floats exact (``repr``), NaN (nothing applies) as ``-``, lists as
    JSON, the rest as text."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return NOT_APPLICABLE if math.isnan(v) else repr(v)
    if isinstance(v, (list, tuple, dict)):
        return json.dumps(v)
    return str(v)


def write_csv(spec: SweepSpec, store: CellStore, path: str | Path) -> int:
    """Write the table as CSV (atomically, streaming); the number of rows."""
    cols = columns(spec)
    n = 0
    with atomic_output(path, "w") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(cols)
        for row in iter_rows(spec, store):
            w.writerow([format_value(row[c]) for c in cols])
            n += 1
    return n


def _arrow_type(spec: SweepSpec, col: str):
    import pyarrow as pa
    if col in _INT:
        return pa.int64()
    if col in _STR:
        return pa.string()
    axis = next((a for a in spec.axes if a.key == col), None)
    if axis is not None and not axis.drawn and not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in axis.values):
        return pa.string()                          # lists, strings, booleans: as in the CSV
    return pa.float64()


def write_parquet(spec: SweepSpec, store: CellStore, path: str | Path,
                  batch_rows: int = 10000) -> bool:
    """Write the table as Parquet when pyarrow is importable (streamed in row groups of
    ``batch_rows``); False when it is not."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return False
    cols = columns(spec)
    schema = pa.schema([(c, _arrow_type(spec, c)) for c in cols])
    text = {c for c in cols if schema.field(c).type == pa.string() and c not in _STR}

    def value(row, c):
        v = row[c]
        if c in text:
            return format_value(v)
        return None if isinstance(v, float) and math.isnan(v) else v

    with atomic_output(path, "wb") as fh:
        with pq.ParquetWriter(fh, schema) as writer:
            batch: list[dict] = []
            for row in iter_rows(spec, store):
                batch.append({c: value(row, c) for c in cols})
                if len(batch) >= batch_rows:
                    writer.write_table(pa.Table.from_pylist(batch, schema=schema))
                    batch = []
            if batch:
                writer.write_table(pa.Table.from_pylist(batch, schema=schema))
    return True

