"""Atomic file output: a file is either fully written or left as it was.

Every output file of the package (CSV, JSON, PNG, TOML) goes through this module. The data
go to a temporary file in the destination's folder (same file system, so the final rename is
atomic), are flushed and fsync'ed (a batch of many files: one ``os.sync`` for all), and the
temporary file is then renamed over the destination with :func:`os.replace`. If anything fails before the rename, the temporary file
is removed and the destination keeps its previous content (or stays absent).

Text is written as UTF-8 without newline translation, so the bytes on disk are the same on
every platform.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import IO

__all__ = [
    "atomic_output",
    "atomic_write_bytes",
    "atomic_write_text",
    "atomic_write_files",
]

_TEXT_MODES = ("w", "wt")
_BINARY_MODES = ("wb",)


def _create_temp(path: Path) -> tuple[int, Path]:
    """Create a new, empty temporary file next to *path*; return its descriptor and path.

    Created with ``os.open(..., 0o666)`` so that the process umask applies, as for an
    ordinary ``open(path, "w")`` (``tempfile.mkstemp`` would make it owner-only).
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(100):
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
        try:
            return os.open(tmp, flags, 0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"could not create a temporary file next to {path}")


def _fsync_dir(folder: Path) -> None:
    """Make a rename in *folder* durable (POSIX); silently skipped where unsupported."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


class _Pending:
    """A temporary file next to its destination, committed by :meth:`commit`."""

    def __init__(self, path: str | os.PathLike, mode: str, encoding: str,
                 newline: str | None) -> None:
        if mode not in _TEXT_MODES + _BINARY_MODES:
            raise ValueError(f"atomic output mode must be one of "
                             f"{', '.join(_TEXT_MODES + _BINARY_MODES)}, not {mode!r}")
        self.path = Path(path)
        fd, self.tmp = _create_temp(self.path)
        try:
            try:  # keep the permissions of a file being replaced
                os.chmod(self.tmp, os.stat(self.path).st_mode & 0o7777)
            except OSError:
                pass
            if mode in _BINARY_MODES:
                self.file: IO = os.fdopen(fd, "wb")
            else:
                self.file = os.fdopen(fd, "w", encoding=encoding, newline=newline)
        except BaseException:
            os.close(fd)
            self.tmp.unlink(missing_ok=True)
            raise

    def flush(self, sync: bool = True) -> None:
        """Flush and (``sync``) fsync the temporary file, then close it."""
        self.file.flush()
        if sync:
            os.fsync(self.file.fileno())
        self.file.close()

    def commit(self) -> None:
        """Rename the temporary file over the destination."""
        os.replace(self.tmp, self.path)

    def discard(self) -> None:
        """Close and remove the temporary file (after a failure)."""
        try:
            self.file.close()
        except Exception:  # already broken; the original error is what matters
            pass
        self.tmp.unlink(missing_ok=True)


@contextmanager
def atomic_output(path: str | os.PathLike, mode: str = "w", *, encoding: str = "utf-8",
                  newline: str | None = "") -> Iterator[IO]:
    """Open *path* for writing so that it is replaced only when the block succeeds.

    Use it for writers that stream into a file object:

    .. code-block:: python

        with atomic_output("fig.png", "wb") as f:
            figure.savefig(f, format="png")

    Parameters
    ----------
    path : str or path-like
        The destination; its folder must exist.
    mode : {"w", "wt", "wb"}
        Text or binary.
    encoding : str
        Text encoding (text modes only).
    newline : str or None
        As for :func:`open`; the default ``""`` writes ``"\\n"`` untranslated on every
        platform (and is what :mod:`csv` writers expect).

    Yields
    ------
    file object
        The temporary file. On a normal exit it is fsync'ed and renamed over *path*; if the
        block raises, it is removed, *path* is untouched, and the exception propagates.
    """
    pending = _Pending(path, mode, encoding, newline)
    try:
        yield pending.file
        pending.flush()
        pending.commit()
    except BaseException:
        pending.discard()
        raise
    _fsync_dir(pending.path.parent)


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write *data* to *path* atomically (all or nothing)."""
    with atomic_output(path, "wb") as f:
        f.write(data)


def atomic_write_text(path: str | os.PathLike, text: str, *, encoding: str = "utf-8") -> None:
    """Write *text* to *path* atomically, encoded with *encoding*, newlines untranslated."""
    atomic_write_bytes(path, text.encode(encoding))


def atomic_write_files(contents: Mapping[str | os.PathLike, bytes | str], *,
                       encoding: str = "utf-8") -> None:
    """Write several files that belong together (e.g. ``NAME.csv`` and ``NAME.toml``, or a
    batch of a sweep's cell records).

    All temporary files are written and made durable first; only when every one succeeded
    are they renamed over their destinations, one after the other. A failure while writing
    leaves every destination as it was. (The renames themselves are not one transaction, but
    a rename does not fail for lack of space and takes microseconds.)  Many files are made
    durable by one ``os.sync`` where the platform has it (one flush of the disks instead of
    an fsync per file, which costs milliseconds each), else by an fsync each.

    Parameters
    ----------
    contents : mapping
        Destination path -> bytes, or str (encoded with *encoding*).
    """
    pendings: list[_Pending] = []
    once = len(contents) > 2 and hasattr(os, "sync")
    try:
        for path, data in contents.items():
            pending = _Pending(path, "wb", encoding, None)
            pendings.append(pending)
            pending.file.write(data.encode(encoding) if isinstance(data, str) else data)
            pending.flush(sync=not once)
        if once:
            os.sync()
        for pending in pendings:
            pending.commit()
    except BaseException:
        for pending in pendings:
            pending.discard()  # a committed one is already renamed: nothing left to remove
        raise
    for folder in {p.path.parent for p in pendings}:
        _fsync_dir(folder)
