"""A sweep's cells as data: one point x one seed, its canonical inputs and their hash.

A cell's key is the SHA-256 of its inputs written canonically: the base scenario and its
instrument as loaded (every field of the frozen dataclasses, floats by their exact repr,
effect functions by their qualified name; the file path left out, so a moved file keeps its
cells), the point's axis values, the seed, the compensation method and the code version
``nfs.__version__``.  Equal inputs give the same key on every machine and in every process,
so a rerun finds the cells it already has.

This module computes nothing of a cell (that is :mod:`nfs.sweep.cells`): listing a sweep's
cells and finding them in the store imports neither the simulator nor the learners, so a
fully stored rerun (:mod:`nfs.sweep.plan`) pays for reading the store only.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
from dataclasses import dataclass
from pathlib import PurePath
from typing import Any, Iterator

import numpy as np

import nfs

from ..io.provenance import sha256_of_text
from .definition import SweepSpec

__all__ = ["CellTask", "canonical", "digest", "scenario_digest", "cell_key", "cell_tasks",
           "STAGES", "STORE_FORMAT"]

#: Version of the stored cell record (part of every key: a new format recomputes).
STORE_FORMAT = 1
#: The stages of a run, as in the heading-RMSE table: the start-up stage (cycles ending
#: within ``northfind.startup_end_s``) and the stable stage (cycles starting after
#: ``northfind.stable_start_s``).
STAGES = ("startup", "stable")


def canonical(obj: Any) -> Any:
    """``obj`` as plain JSON data that says everything about its value and nothing else.

    Dataclasses become {"__type__": qualified name, field: value, ...} (a ``path`` field
    is left out: where a file lies is not what it holds), mappings have sorted keys,
    floats are written by ``repr`` (exact), arrays by dtype, shape and the hash of their
    bytes, functions by module and qualified name.
    """
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        out = {"__type__": f"{type(obj).__module__}.{type(obj).__qualname__}"}
        for f in dataclasses.fields(obj):
            if f.name != "path":
                out[f.name] = canonical(getattr(obj, f.name))
        return out
    if isinstance(obj, dict):
        return {str(k): canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, (list, tuple)):
        return [canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return {"__array__": str(obj.dtype), "shape": list(obj.shape),
                "sha256": hashlib.sha256(np.ascontiguousarray(obj).tobytes()).hexdigest()}
    if isinstance(obj, np.generic):
        return canonical(obj.item())
    if isinstance(obj, bool) or obj is None or isinstance(obj, (int, str)):
        return obj
    if isinstance(obj, float):
        return repr(obj)
    if isinstance(obj, enum.Enum):
        return f"{type(obj).__qualname__}.{obj.name}"
    if isinstance(obj, PurePath):
        return str(obj)
    if callable(obj):
        return f"{getattr(obj, '__module__', '?')}.{getattr(obj, '__qualname__', repr(obj))}"
    raise TypeError(f"cannot hash a {type(obj).__name__} canonically")


def digest(obj: Any) -> str:
    """SHA-256 (hex) of :func:`canonical` ``(obj)``."""
    return sha256_of_text(json.dumps(canonical(obj), sort_keys=True, separators=(",", ":")))


def scenario_digest(spec: SweepSpec) -> str:
    """Digest of the base scenario and its instrument as loaded."""
    return digest(spec.scenario)


@dataclass(frozen=True)
class CellTask:
    """What a worker needs to compute one cell (small and picklable)."""

    index: int
    """Position of the cell in the sweep (its row order)."""
    key: str
    """The cell's hash (:func:`cell_key`)."""
    scenario_path: str | None
    """Base scenario file (None: the built-in default)."""
    scenario_values: tuple[tuple[str, Any], ...]
    """The point's scenario keys and values."""
    instrument_values: tuple[tuple[str, float], ...]
    """The point's instrument parameters and values."""
    seed: int
    """The scenario's seed in this cell."""
    method: str | None
    """Compensation method key, or None."""
    base_digest: str = ""
    """:func:`scenario_digest` of the sweep's base scenario as the sweep loaded it ('': not
    known), so a worker can tell that consecutive batches share their base."""

    @property
    def values(self) -> dict[str, Any]:
        """Every axis value of the point, {key: value}."""
        return dict(self.scenario_values + self.instrument_values)


def cell_key(base_digest: str, values: dict[str, Any], seed: int, method: str | None) -> str:
    """The hash a cell's record is stored under (module docstring)."""
    return digest({"scenario": base_digest, "axes": values, "seed": seed, "method": method,
                   "version": nfs.__version__, "format": STORE_FORMAT})


def cell_tasks(spec: SweepSpec, base_digest: str | None = None) -> Iterator[CellTask]:
    """Every cell of ``spec`` in row order (point-major, then seed), generated lazily."""
    base_digest = base_digest or scenario_digest(spec)
    targets = {a.key: a.target for a in spec.axes}
    path = None if spec.scenario_path is None else str(spec.scenario_path)
    index = 0
    for point in spec.points():
        sc_vals = tuple((k, v) for k, v in point.items() if targets[k] == "scenario")
        inst_vals = tuple((k, float(v)) for k, v in point.items() if targets[k] == "instrument")
        for seed in spec.seeds:
            yield CellTask(index, cell_key(base_digest, point, seed, spec.method), path,
                           sc_vals, inst_vals, seed, spec.method, base_digest)
            index += 1
