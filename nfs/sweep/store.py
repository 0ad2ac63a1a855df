"""The cell store: each finished cell's record in its own file, named by the cell's hash.

``DIR/cells/<key>.json`` is written atomically (:mod:`nfs.io.atomic`) as soon as the cell's
batch is done (a batch's records made durable together: one flush of the disks, not an
fsync per cell), so an interrupted sweep keeps every finished batch and a rerun computes
only the missing cells.  A record is read back only when the table is assembled, one cell at a time.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..errors import NfsError
from ..io.atomic import atomic_write_files, atomic_write_text

__all__ = ["CellStore"]


class CellStore:
    """Cell records under ``folder/cells``."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.cells = self.folder / "cells"

    def prepare(self) -> None:
        """Create the folders (an error naming the path when it cannot be a folder)."""
        for p in (self.folder, self.cells):
            if p.exists() and not p.is_dir():
                raise NfsError(f"{p}: exists and is not a folder (the sweep's output folder)")
            try:
                p.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise NfsError(f"{p}: cannot create the sweep's output folder: "
                               f"{exc.strerror or exc}") from None

    def path(self, key: str) -> Path:
        """File of the cell ``key``."""
        return self.cells / f"{key}.json"

    def has(self, key: str) -> bool:
        """True when cell ``key`` is stored."""
        return self.path(key).is_file()

    def write(self, record: dict[str, Any]) -> None:
        """Store a record (atomically) under its ``key``."""
        atomic_write_text(self.path(record["key"]), _text(record))

    def write_many(self, records: list[dict[str, Any]]) -> None:
        """Store the records of a batch of cells together (:func:`~nfs.io.atomic.atomic_write_files`:
        each atomically, made durable at once rather than file by file)."""
        atomic_write_files({self.path(r["key"]): _text(r) for r in records})

    def read(self, key: str) -> dict[str, Any]:
        """The record of cell ``key``."""
        p = self.path(key)
        try:
            with open(p, encoding="utf-8") as fh:
                rec = json.load(fh)
        except FileNotFoundError:
            raise NfsError(f"{p}: cell not computed") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise NfsError(f"{p}: unreadable cell record ({exc}); delete it to recompute "
                           "the cell") from None
        if rec.get("key") != key:
            raise NfsError(f"{p}: holds cell {rec.get('key')!r}, not {key}; delete it to "
                           "recompute the cell")
        return rec


def _text(record: dict[str, Any]) -> str:
    """A record's file: compact JSON with sorted keys, one line."""
    return json.dumps(record, sort_keys=True, separators=(",", ":")) + "\n"
