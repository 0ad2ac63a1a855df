"""Output folders that hold one experiment: checked before work, a manifest after it.

Every command that writes a folder (``nfs table``, ``simulate``, ``compensate``, ``compare``)
goes through :class:`OutputFolder`:

1. **Before any work** the destination is checked: it must be a folder (or not exist yet) in
   a writable place. A folder that holds files of another command, or files of unknown
   origin, is refused with the list of those files unless the user passes ``--overwrite``:
   a folder holds one experiment, so nothing of an earlier one is read as part of this one.
2. **After the work**, :meth:`OutputFolder.finish` finds what this command wrote (every file
   created or replaced since the check: the writers replace files atomically, so a rewritten
   file has a new inode and modification time), removes the files that the folder's earlier
   manifest listed and this command did not rewrite (they are stale), and writes the
   manifest ``nfs-manifest.json``: the command, its arguments, what it read, the library
   versions and platform (:mod:`nfs.io.provenance`) and every written file with its SHA-256.

A long command that writes its folder file by file (``nfs simulate``) calls
:meth:`OutputFolder.begin` first: the manifest then says the folder is partial, and each
group of files is recorded as it lands (:meth:`OutputFolder.record`, :mod:`nfs.io.resume`).
The same command on the same job (``job``: the scenario's hash) finds such a folder and
resumes it: the recorded files are kept, the rest is written (``resume``).

The manifest holds no time stamp, so the same command on the same inputs writes the same
bytes. Stale files are removed only after everything new is in place: a command that fails
midway leaves the earlier experiment's files (and manifest) as they were, apart from the
files it had already replaced atomically.
"""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import NfsError
from .atomic import atomic_write_text
from .provenance import library_versions, platform_tag, sha256_of_file
from .resume import JOURNAL_NAME, Journal

__all__ = ["MANIFEST_NAME", "OutputFolder", "check_output_file", "read_manifest"]

#: File name of the manifest in every folder the package writes.
MANIFEST_NAME = "nfs-manifest.json"
_FORMAT = "nfs-manifest/1"


def read_manifest(folder: str | os.PathLike) -> dict | None:
    """The manifest of *folder* as a dict, or None when it has none (or an unreadable one)."""
    path = Path(folder) / MANIFEST_NAME
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("format") != _FORMAT:
        return None
    return data


def _files(folder: Path) -> dict[str, tuple[int, int]]:
    """Relative POSIX path -> (inode, mtime_ns) of every regular file under *folder*
    (hidden temporary files of the atomic writers excluded)."""
    out = {}
    for root, dirs, names in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for name in names:
            if name.startswith(".") and name.endswith(".tmp"):
                continue
            p = Path(root) / name
            try:
                st = p.stat()
            except OSError:
                continue
            out[p.relative_to(folder).as_posix()] = (st.st_ino, st.st_mtime_ns)
    return out


def _writable_place(path: Path, option: str) -> None:
    """Raise a located NfsError unless *path*'s nearest existing ancestor is a writable folder."""
    probe = path
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise NfsError(f"{option} {path}: '{probe}' is a file, so no folder can be made there")
    _can_write_in(probe, f"{option} {path}", "folder")


def _can_write_in(folder: Path, what: str, kind: str) -> None:
    """Raise a located NfsError unless a ``kind`` ("file" or "folder") can be made in
    *folder*: its permissions, then a probe made and removed (os.access answers yes to
    root on a read-only or virtual file system such as /proc)."""
    if not os.access(folder, os.W_OK | os.X_OK):
        raise NfsError(f"{what}: folder '{folder}' is not writable")
    try:
        if kind == "folder":
            os.rmdir(tempfile.mkdtemp(prefix=".nfs-probe-", dir=folder))
        else:
            fd, probe = tempfile.mkstemp(prefix=".nfs-probe-", dir=folder)
            os.close(fd)
            os.remove(probe)
    except OSError as exc:
        verb = "made" if kind == "folder" else "written"
        raise NfsError(f"{what}: no {kind} can be {verb} in '{folder}' ({exc.strerror})") \
            from None


def check_output_file(path: str | os.PathLike, option: str = "-o") -> Path:
    """Check, before any work, that a single output file can be written at *path*.

    The file may exist (it is replaced atomically); *path* must not be a folder, and its
    folder must exist and be writable.
    """
    p = Path(path)
    if p.is_dir():
        raise NfsError(f"{option} {p}: is a folder; give a file name")
    if not p.parent.is_dir():
        raise NfsError(f"{option} {p}: folder '{p.parent}' does not exist")
    _can_write_in(p.parent, f"{option} {p}", "file")
    return p


@dataclass
class OutputFolder:
    """A folder checked for one command's output before the work starts.

    Parameters
    ----------
    path : path-like
        The folder (created when missing, after the checks).
    command : str
        The command that writes it, e.g. ``"table"``; recorded in the manifest and compared
        with an earlier manifest's.
    overwrite : bool
        Write into a folder that holds another command's files or files of unknown origin.
        The earlier manifest's files that this command does not rewrite are still removed;
        files of unknown origin are left alone (and reported).
    option : str
        The option that named the folder, for messages.
    job : str, optional
        What the output is made of (e.g. the scenario's SHA-256), recorded in the manifest:
        the same command on the same job resumes a partial folder.
    resume : bool, optional
        None: resume a partial folder of the same command and job (:meth:`begin`), write
        anew otherwise; True: resume (a complete folder of the same job too, whose files are
        then kept), refused when the folder holds another job; False: write anew.
    expected : collection of str
        Relative paths the command writes: in a folder resumed, such a file that is not
        recorded is the interrupted command's own (written after its last record) and is
        written again.
    """

    path: Path
    command: str
    overwrite: bool = False
    option: str = "-o"
    job: str | None = None
    resume: bool | None = None
    expected: frozenset = frozenset()
    removed: list[str] = field(default_factory=list, init=False)
    """Files of the earlier experiment removed by :meth:`finish`."""
    foreign: list[str] = field(default_factory=list, init=False)
    """Files of unknown origin left in the folder (only with ``overwrite``)."""
    done: dict = field(default_factory=dict, init=False)
    """{relative path: its record} of the files a resumed folder already holds complete
    (empty when the folder is written anew): the command skips what makes them."""
    resuming: bool = field(default=False, init=False)
    """True when the folder is resumed."""
    _before: dict = field(default_factory=dict, init=False, repr=False)
    _earlier: list[str] = field(default_factory=list, init=False, repr=False)
    _journal: Journal | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        p = self.path
        if p.exists() and not p.is_dir():
            raise NfsError(f"{self.option} {p}: is a file, not a folder; give a folder name")
        _writable_place(p, self.option)
        if p.is_dir():
            self._before = _files(p)
        manifest = read_manifest(p) if p.is_dir() else None
        listed = set()
        journal = Journal(p)
        if manifest is not None:
            listed = {f["path"] for f in manifest.get("files", []) if isinstance(f, dict)
                      and isinstance(f.get("path"), str)}
            if manifest.get("partial") is True:
                listed |= set(journal.read()) | {JOURNAL_NAME}
            self._earlier = sorted(listed - {JOURNAL_NAME})
        other_command = manifest is not None and manifest.get("command") != self.command
        self._resume_from(manifest, journal)
        unknown = sorted(set(self._before) - listed - {MANIFEST_NAME}
                         - (set(self.expected) if self.resuming else set()))
        if not self.overwrite:
            if other_command:
                raise NfsError(
                    f"{self.option} {p}: the folder holds the output of 'nfs "
                    f"{manifest.get('command')}' ({len(listed)} files); a folder holds one "
                    "experiment: choose another folder, or --overwrite to replace it")
            if unknown:
                shown = ", ".join(unknown[:5]) + (", ..." if len(unknown) > 5 else "")
                raise NfsError(
                    f"{self.option} {p}: the folder holds {len(unknown)} file(s) this package "
                    f"did not list as its output ({shown}); choose an empty folder, or "
                    "--overwrite to write into it anyway")
        self.foreign = unknown  # the folder itself is made by the writers, when there is output

    def _resume_from(self, manifest: dict | None, journal: Journal) -> None:
        """Decide whether the folder is resumed, and what it holds complete."""
        same = (manifest is not None and self.job is not None
                and manifest.get("command") == self.command and manifest.get("job") == self.job)
        if self.resume and not same:
            what = ("no output of this package" if manifest is None else
                    f"the output of 'nfs {manifest.get('command')}' of another job "
                    f"({'partial' if manifest.get('partial') else 'complete'})")
            raise NfsError(f"{self.option} {self.path}: nothing to resume: the folder holds "
                           f"{what}, not this command on the same inputs (the scenario, its "
                           "instrument, --seed and --repeats must be the same)")
        partial = same and manifest.get("partial") is True
        self.resuming = same and (self.resume is True or (self.resume is None and partial))
        if not self.resuming:
            return
        if partial:
            self.done = journal.complete()
        else:
            # a complete folder resumed: every file its manifest lists that is still there
            self.done = {f["path"]: {"sha256": f.get("sha256")}
                         for f in manifest.get("files", []) if isinstance(f, dict)
                         and isinstance(f.get("path"), str) and (self.path / f["path"]).is_file()}

    def begin(self, *, arguments: list[str] | None = None, inputs: dict | None = None) -> None:
        """Make the folder and mark it partial (before any file is written), so that an
        interrupted command leaves a folder the same command resumes; then
        :meth:`record` each group of files as it lands and :meth:`finish` at the end."""
        self.path.mkdir(parents=True, exist_ok=True)
        journal = Journal(self.path)
        if not self.resuming:
            journal.remove()            # an earlier partial folder's record, not ours
        if self.done and not journal.path.exists():
            journal.append(self.path / rel for rel in sorted(self.done))
        partial = {"format": _FORMAT, "command": self.command, "job": self.job,
                   "partial": True, "arguments": list(arguments or []),
                   "inputs": inputs or {},
                   # what the folder held before: still this package's output, until
                   # finish removes what is not rewritten
                   "files": [{"path": rel} for rel in self._earlier]}
        atomic_write_text(self.path / MANIFEST_NAME, json.dumps(partial, indent=1) + "\n")
        self._journal = journal

    def record(self, paths) -> None:
        """Record files just written atomically (a run's pair) as complete (:meth:`begin`
        first)."""
        if self._journal is None:
            raise RuntimeError("OutputFolder.record before begin")
        self._journal.append(paths)

    def finish(self, *, arguments: list[str] | None = None, inputs: dict | None = None,
               units: list[dict] | None = None) -> Path:
        """Remove the earlier experiment's stale files and write the manifest; return its path.

        Parameters
        ----------
        arguments : list of str, optional
            The command line after ``nfs`` (recorded as given).
        inputs : dict, optional
            What the output was made from (scenario name and hash, data files, model), as
            JSON-serialisable values.
        units : list of dict, optional
            The unit files among the output (:func:`nfs.io.unit_files.unit_entry`).
        """
        self.path.mkdir(parents=True, exist_ok=True)
        after = _files(self.path)
        recorded = Journal(self.path).read() if self._journal is not None else {}
        written = sorted(k for k, v in after.items()
                         if k not in (MANIFEST_NAME, JOURNAL_NAME)
                         and (self._before.get(k) != v or k in self.done))
        stale = [k for k in self._earlier if k not in written and k in after]
        for rel in stale:
            (self.path / rel).unlink(missing_ok=True)
        self.removed = stale
        self.foreign = [k for k in self.foreign if k not in written]
        manifest = {
            "format": _FORMAT,
            "command": self.command,
            "arguments": list(arguments or []),
            "versions": library_versions(),
            "platform": platform_tag(),
            "inputs": inputs or {},
        }
        if self.job is not None:
            manifest["job"] = self.job
        if units is not None:
            manifest["units"] = units
        manifest["files"] = [{"path": rel, "sha256": self._sha256(rel, recorded.get(rel))}
                             for rel in written]
        out = self.path / MANIFEST_NAME
        atomic_write_text(out, json.dumps(manifest, indent=1, sort_keys=False) + "\n")
        Journal(self.path).remove()
        return out

    def _sha256(self, rel: str, record: dict | None) -> str:
        """A file's SHA-256: its journal record's while the folder holds the file as
        recorded (:meth:`~nfs.io.resume.Journal.holds`), else read again."""
        if record is not None and record.get("sha256") and Journal(self.path).holds(rel, record):
            return record["sha256"]
        return sha256_of_file(self.path / rel)

    def summary(self) -> str:
        """One line on what happened to files of an earlier experiment ('' when nothing)."""
        parts = []
        if self.removed:
            shown = ", ".join(self.removed[:5]) + (", ..." if len(self.removed) > 5 else "")
            parts.append(f"removed {len(self.removed)} file(s) of the earlier output that "
                         f"this run did not rewrite ({shown})")
        if self.foreign:
            shown = ", ".join(self.foreign[:5]) + (", ..." if len(self.foreign) > 5 else "")
            parts.append(f"left {len(self.foreign)} file(s) of unknown origin ({shown})")
        return "; ".join(parts)
