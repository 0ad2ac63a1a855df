"""What every command shares: progress lines, output files and folders, overrides from the
command line, number formatting, loading a model."""

from __future__ import annotations

import dataclasses
import math
import sys
import time

from ..errors import NfsError
from ..run import run_caveats

__all__ = ["EXIT_USAGE", "FEATURES_MODE_HELP", "Progress", "output_folder", "output_file",
           "finish", "recorded_arguments", "say_removed", "gate", "say_ignored",
           "with_overrides", "circular_mean_deg", "fmt", "start_model", "read_command_runs"]


EXIT_USAGE = 2


FEATURES_MODE_HELP = (
    "what the thermometer features at time t may use: cycle (data up to the end of t's "
    "north-finding cycle, when its heading is output), causal (data up to t) or offline "
    "(the whole run, centred rate window: not computable by an instrument)")


class Progress:
    """A progress line on stderr (rewritten in place on a terminal)."""

    def __init__(self, what: str, quiet: bool = False) -> None:
        self.what = what  # prefix of each line; may be empty
        self.quiet = quiet
        self.tty = sys.stderr.isatty()
        self.t0 = time.perf_counter()

    def __call__(self, i: int, n: int, name: str) -> None:
        if self.quiet:
            return
        msg = (f"{self.what} " if self.what else "") + \
            f"{min(i + 1, n)}/{n}: {name} ({time.perf_counter() - self.t0:.1f} s)"
        if self.tty:
            sys.stderr.write("\r\033[K" + msg)
            if i >= n:
                sys.stderr.write("\n")
        else:
            sys.stderr.write(msg + "\n")
        sys.stderr.flush()


def output_folder(args, command: str):
    """The checked output folder of a folder-writing command (before any work)."""
    from ..io.outdir import OutputFolder
    return OutputFolder(args.output, command, overwrite=args.overwrite)


def output_file(path, option: str, overwrite: bool = False):
    """Check an output file's place before any work (None passes): its folder exists and
    takes files, and no file is there unless ``overwrite`` (the command's --overwrite)."""
    from ..io.outdir import check_output_file
    if path is None:
        return
    p = check_output_file(path, option)
    if not overwrite and (p.exists() or p.is_symlink()):
        raise NfsError(f"{option} {p}: the file exists; give --overwrite to replace it")


#: Options that change how a command runs, not what it writes: left out of the manifest's
#: command line, so that a resumed or confirmed folder is the folder written at once.
_NOT_RECORDED = ("--resume", "--yes")


def recorded_arguments(args) -> list[str]:
    """The command line as the manifest records it: without the folder itself (the same
    command into two folders writes the same manifest) and without :data:`_NOT_RECORDED`."""
    argv, skip = [], False
    for tok in getattr(args, "argv", []):
        if skip:
            skip = False
        elif tok in ("-o", "--output"):
            skip = True
        elif not tok.startswith("--output=") and not (tok.startswith("-o") and
                                                      not tok.startswith("--")) \
                and tok not in _NOT_RECORDED:
            argv.append(tok)
    return argv


def finish(folder, args, inputs: dict) -> None:
    """Write the folder's manifest and say what happened to an earlier output's files."""
    folder.finish(arguments=recorded_arguments(args), inputs=inputs)
    say_removed(folder)


def say_removed(folder) -> None:
    """One line on stderr on what happened to an earlier output's files (if anything)."""
    note = folder.summary()
    if note:
        print(f"nfs: {note}", file=sys.stderr)


def with_overrides(scenario, args):
    changes = {}
    if getattr(args, "seed", None) is not None:
        changes["seed"] = args.seed
    if getattr(args, "repeats", None) is not None:
        if args.repeats < 1:
            raise NfsError(f"--repeats must be >= 1, got {args.repeats}")
        changes["repeats"] = args.repeats
    return dataclasses.replace(scenario, **changes) if changes else scenario


def circular_mean_deg(angles_deg) -> float:
    import numpy as np
    a = np.radians(np.asarray(angles_deg, dtype=float))
    a = a[np.isfinite(a)]
    if a.size == 0:
        return math.nan
    return float(np.degrees(np.arctan2(np.sin(a).mean(), np.cos(a).mean())) % 360.0)


def fmt(v: float) -> str:
    return "n/a" if not math.isfinite(v) else f"{v:.4f}"


def start_model(args):
    """The start model of ``--start`` (nfs.fit.start_state)."""
    from ..fit.thermal_residual import DEFAULT_START
    return DEFAULT_START if args.start == "estimated" else None


def gate(make_estimate, samples: int, args, *, held: bool = False, rows: bool = True,
         fewer: str = "") -> None:
    """Before a job that may be long: its estimate (:func:`nfs.studies.job_estimate.gate_job`),
    refused past the limits without ``--yes`` (exit 2, the figures in one line), stated on
    stderr past the notice (unless ``-q``)."""
    from ..studies.job_estimate import JOB_NOTICE, gate_job
    estimate = gate_job(make_estimate, samples, yes=args.yes, rows=rows, held=held,
                        fewer=fewer)
    if estimate is not None and estimate.exceeds(JOB_NOTICE) and not args.quiet:
        print(f"nfs: {estimate.line()}", file=sys.stderr)


def say_ignored(scenario, command: str, settings=None, compensate: bool = True) -> None:
    """One line on stderr per count of the scenario the command ignores
    (:func:`nfs.studies.job_estimate.ignored_keys`)."""
    from ..studies.job_estimate import ignored_keys
    for line in ignored_keys(scenario, command, settings, compensate):
        print(f"nfs: note: {line}", file=sys.stderr)


def read_command_runs(args, *, say: bool = True) -> list:
    """The runs a command's DATA name, read as its ``--partial`` and ``--allow-nan`` ask
    (:func:`nfs.read_runs`); what they let through printed a line each on standard output
    (``say=False``: the command's own result states it, as a fit's warnings do)."""
    from .. import read_runs
    runs = read_runs(args.data, partial=args.partial, allow_nan=args.allow_nan)
    if say:
        for line in run_caveats(runs):
            print(f"note: {line}")
    return runs
