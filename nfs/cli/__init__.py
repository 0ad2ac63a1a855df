"""The ``nfs`` command: thin; parse, call the library, turn NfsError into one line + exit 2.

    nfs table [SCENARIO] [-o DIR] [--json FILE]      heading-RMSE table by start temperature
              [--baseline OLD.json]              ... set beside an earlier table (exit 1: worse)
    nfs simulate SCENARIO -o DIR                     measurement files, one run per T0
    nfs import MAPPING.toml -o DIR                   a chamber log's files made one run
    nfs northfind DATA... [--json FILE]              north-find measured or simulated runs
    nfs train DATA... --method M -o MODEL            train a drift compensator
    nfs compensate DATA... --model MODEL -o DIR      apply it
    nfs fit DATA... [--model M] -o FITTED.toml       calibrate a model to measured runs
    nfs compare DATA... --model M -o DIR             the model beside the runs
    nfs allan DATA... [--model M] [-o DIR]           the gyro's Allan deviation, dwell by dwell
    nfs diagnose DATA... --model M [--apply NAME]    the missing effect, ranked
    nfs design DATA... --model M --diagnosis D -o DIR   the run that would decide a tie
    nfs preset [NAME]                                print a built-in instrument or scenario
    nfs init DIR                                     a starter scenario and instrument
    nfs effects                                      list the registered physical effects

The commands live in :mod:`nfs.cli.compensation`, :mod:`nfs.cli.experiment`,
:mod:`nfs.cli.measured`, :mod:`nfs.cli.noise`, :mod:`nfs.cli.design` and
:mod:`nfs.cli.importing`, their arguments in :mod:`nfs.cli.parser` (``nfs allan``'s in
:mod:`nfs.cli.noise`).
"""

from __future__ import annotations

import os
import sys

from ..errors import USER_ERRORS
from ..ranges import one_line_warnings
from .common import EXIT_USAGE
from .parser import build_parser, check_options

__all__ = ["main", "build_parser"]


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``nfs`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    if getattr(args, "trust_effects", False):   # a scenario's effects_files may run
        from ..config.scenario import TRUST_EFFECTS_ENV  # lazy: nfs --help stays fast
        os.environ[TRUST_EFFECTS_ENV] = "1"
    try:
        with one_line_warnings():             # an unusual input value: one line, then on
            check_options(args)
            return args.func(args)
    except USER_ERRORS as exc:
        print(f"nfs: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        print("nfs: interrupted", file=sys.stderr)
        return 130
