"""``nfs allan``: the gyro's noise a user can see, dwell by dwell, beside the stated values.

:func:`nfs.comparison.allan_of_runs` on files, :func:`nfs.report.allan_figure.write_allan`
into the output folder.  The command's arguments are declared here (:func:`add_allan_command`) and
added to the parser by :mod:`nfs.cli.parser`.  The library is imported inside the command
(as in every command module) so that ``nfs --help`` stays fast.
"""

from __future__ import annotations

import argparse
import sys

from .common import finish, output_folder

__all__ = ["add_allan_command", "cmd_allan"]


def add_allan_command(sub) -> argparse.ArgumentParser:
    """Add ``nfs allan`` to the parser's sub-commands ``sub``; returns its parser."""
    al = sub.add_parser(
        "allan", help="the Allan deviation of the gyro at rest, dwell by dwell",
        description="The overlapping Allan deviation of every dwell's gyro at rest (the "
                    "dwells cut as the north finder cuts them), the angle random walk N, "
                    "bias instability B and rate random walk K fitted to the pooled curve "
                    "with bootstrap intervals, beside the values the instrument states. "
                    "Dwells within the first hour after power-on enter the fit only up to a "
                    "tenth of the dwell (the start-up's thermal drift). Prints the table and "
                    "writes DIR/allan.json and DIR/allan.png.")
    al.add_argument("data", nargs="+", help="NAME.csv files, NAME.toml files or folders")
    al.add_argument("--model", default=None,
                    help="instrument preset name or TOML file whose stated N, B, K to show "
                         "(default: the unit file beside the runs their sidecars name, "
                         "else the built-in preset they name, else default)")
    al.add_argument("-o", "--output", default="allan", metavar="DIR",
                    help="output folder (default: allan)")
    al.add_argument("--settle-s", type=float, default=0.0,
                    help="seconds skipped at the start of each dwell, as for nfs northfind "
                         "(default 0)")
    al.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (default 0)")
    al.add_argument("--overwrite", action="store_true",
                    help="write into a folder that holds another command's output or files "
                         "of unknown origin")
    al.add_argument("-q", "--quiet", action="store_true",
                    help="no progress on standard error")
    al.set_defaults(func=cmd_allan)
    return al


def cmd_allan(args) -> int:
    from .. import read_runs
    from ..comparison.allan_runs import allan_of_runs, stated_instrument
    from ..io.provenance import output_provenance
    from ..report.allan_figure import write_allan
    folder = output_folder(args, "allan")
    runs = read_runs(args.data)
    stated = stated_instrument(runs, args.model)          # a bad --model: before any work
    if not args.quiet:
        print(f"Allan deviation of the dwells of {len(runs)} run(s)...", file=sys.stderr)
    report = allan_of_runs(runs, stated=stated, settle_s=args.settle_s, seed=args.seed)
    prov = output_provenance(runs=runs, seeds={"bootstrap": args.seed})
    paths = write_allan(report, args.output, provenance=prov)
    finish(folder, args, {"runs": prov["runs"], "stated": report.stated_source,
                          "seeds": prov["seeds"]})
    print(report.summary())
    if not args.quiet:
        print("wrote " + ", ".join(str(p) for p in paths), file=sys.stderr)
    return 0
