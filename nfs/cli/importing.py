"""``nfs import``: a chamber log's files (gyro, thermometers, chamber: each its own clock,
rate, separator and decimal mark) made one ``nfs-measurement/1`` run, as a mapping says
(:func:`nfs.io.import_log`; docs/measurement-format.md, "Chamber logs: nfs import").

The library is imported inside the command (as in every command module) so that
``nfs --help`` stays fast.
"""

from __future__ import annotations

from .common import finish, output_folder

__all__ = ["add_import_parser", "cmd_import"]


def add_import_parser(sub) -> None:
    """Register ``nfs import`` on the parser's subcommands."""
    p = sub.add_parser("import", help="a chamber log's files made one run (nfs-measurement/1)",
                       description="Read the source files a mapping TOML names (each its own "
                                   "time column and unit or timestamp format, separator, "
                                   "decimal mark, column units), bring them onto the gyro's "
                                   "time base by each column's stated method, refuse a gap "
                                   "(or --cut to the span every source covers), check the "
                                   "units as the reader does, and write the run "
                                   "(NAME.csv + NAME.toml) into the output folder.")
    p.add_argument("mapping", help="mapping TOML file (docs/measurement-format.md)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    p.add_argument("--cut", action="store_true",
                   help="cut the run to the longest stretch every source covers instead of "
                        "refusing a gap; the sidecar says so")
    p.add_argument("--partial", action="store_true",
                   help="accept a log shorter than [run] duration_s, or a last line cut while "
                        "written (left out)")
    p.add_argument("--allow-nan", action="store_true",
                   help="accept empty fields as missing samples instead of refusing them")
    p.add_argument("--overwrite", action="store_true",
                   help="write into a folder that holds another command's output or files "
                        "of unknown origin")
    p.set_defaults(func=cmd_import)


def cmd_import(args) -> int:
    from ..io.log_import import import_log
    from ..io.log_mapping import read_mapping
    from ..io.measurement import write_run
    from ..io.provenance import sha256_of_file
    mapping = read_mapping(args.mapping)
    folder = output_folder(args, "import")
    run = import_log(mapping, cut=args.cut, partial=args.partial, allow_nan=args.allow_nan)
    path = write_run(run, args.output)
    inputs = {"mapping": {"file": str(mapping.path), "sha256": sha256_of_file(mapping.path)},
              "sources": [{"name": s.name, "file": str(s.file), "sha256": sha256_of_file(s.file)}
                          for s in mapping.sources]}
    finish(folder, args, inputs)
    account = run.meta.extra["imported"]
    print(f"time base: {account['time_base']}")
    for line in account["resampling"]:
        print(f"resampling: {line}")
    if "cut" in account:
        print(f"cut: {account['cut']}")
    for caveat in run.caveats:
        print(f"note: {caveat}")
    print(f"wrote {path} and {path.with_suffix('.toml').name}")
    return 0
