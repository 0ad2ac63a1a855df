"""The record of an output folder being written: what is complete, so that an interrupted
command resumes where it stopped (:class:`nfs.io.outdir.OutputFolder`).

While a long command writes its folder (``nfs simulate``: a run at a time), the folder's
manifest says ``"partial": true`` with the command and its job (the scenario's hash), and
every group of files written atomically (a run's ``NAME.csv`` and ``NAME.toml``) is recorded
as it lands by one line appended to ``nfs-progress.jsonl``: each file's path, size,
modification time and SHA-256.  A file is complete only when it was written atomically
(:mod:`nfs.io.atomic`: it exists whole or not at all) and recorded; a line cut by the
interruption is not a record.
The command's final manifest replaces the partial one and the journal is removed.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from .provenance import sha256_of_file

__all__ = ["JOURNAL_NAME", "Journal"]

#: File name of the journal of a folder being written.
JOURNAL_NAME = "nfs-progress.jsonl"


class Journal:
    """The append-only record of the complete files of a folder being written.

    Parameters
    ----------
    folder : path-like
        The output folder; the journal is ``folder/nfs-progress.jsonl``.
    """

    def __init__(self, folder: str | os.PathLike) -> None:
        self.folder = Path(folder)
        self.path = self.folder / JOURNAL_NAME

    def read(self) -> dict[str, dict]:
        """{relative path: {"bytes", "mtime_ns", "sha256"}} of every file recorded, a later
        record of a path replacing an earlier one; lines that do not parse (a line cut by
        an interruption) are no record."""
        out: dict[str, dict] = {}
        try:
            text = self.path.read_text(encoding="utf-8")
        except OSError:
            return out
        for line in text.split("\n"):
            try:
                entry = json.loads(line)
            except ValueError:
                continue
            for f in entry.get("files", []) if isinstance(entry, dict) else []:
                if isinstance(f, dict) and isinstance(f.get("path"), str):
                    out[f["path"]] = {"bytes": f.get("bytes"), "mtime_ns": f.get("mtime_ns"),
                                      "sha256": f.get("sha256")}
        return out

    def complete(self) -> dict[str, dict]:
        """:meth:`read`, less the files no longer in the folder as recorded (:meth:`holds`)."""
        return {rel: rec for rel, rec in self.read().items() if self.holds(rel, rec)}

    def holds(self, rel: str, record: dict | None) -> bool:
        """True when the folder holds file ``rel`` as ``record`` recorded it: its size and
        modification time (a file replaced or touched since is written again)."""
        if record is None:
            return False
        try:
            st = (self.folder / rel).stat()
        except OSError:
            return False
        return st.st_size == record.get("bytes") and st.st_mtime_ns == record.get("mtime_ns")

    def append(self, paths) -> None:
        """Record the files ``paths`` (already written atomically) as complete: one line,
        flushed to the disk before returning."""
        files = []
        for p in paths:
            p = Path(p)
            st = p.stat()
            files.append({"path": p.relative_to(self.folder).as_posix(), "bytes": st.st_size,
                          "mtime_ns": st.st_mtime_ns, "sha256": sha256_of_file(p)})
        line = (json.dumps({"files": files}, separators=(",", ":")) + "\n").encode("utf-8")
        with open(self.path, "a+b") as f:
            end = f.seek(0, os.SEEK_END)
            if end:
                # a line cut by an earlier interruption ends here: start a line of our own
                f.seek(end - 1)
                if f.read(1) != b"\n":
                    line = b"\n" + line
            f.write(line)
            f.flush()
            os.fsync(f.fileno())

    def remove(self) -> None:
        """Remove the journal (the folder's final manifest is written)."""
        self.path.unlink(missing_ok=True)
