"""``nfs design``: the run that would tell a diagnosis's rival explanations apart.

:meth:`nfs.UnitChain.design` on files: the rivals come from ``--rivals`` or from the finding
an earlier ``nfs diagnose --json`` wrote (read with :meth:`nfs.rivals.Finding.from_dict`).
The library is imported inside the command (as in every command module) so that
``nfs --help`` stays fast.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import NfsError
from .common import finish, output_folder, read_command_runs, start_model
from .measured import read_finding

__all__ = ["cmd_design"]


def cmd_design(args) -> int:
    from .. import UnitChain, load_instrument
    from ..report.design_report import write_design
    from ..io.provenance import output_provenance
    if args.rivals is not None and args.diagnosis is not None:
        raise NfsError("give either --diagnosis or --rivals, not both")
    if args.rivals is not None and len(args.rivals) < 2:
        raise NfsError(f"--rivals: a design needs at least two rivals, got "
                       f"{len(args.rivals)}")
    if args.rivals is None and args.diagnosis is None:
        raise NfsError("give the rivals: --diagnosis D.json (what nfs diagnose --json found) "
                       "or --rivals A B ...")
    labels = list(args.rivals) if args.rivals else read_finding(args.diagnosis).rivals()
    inst = load_instrument(args.model)
    chain = UnitChain(inst, read_command_runs(args), start_state=start_model(args))
    chain.check_rivals(labels)         # what each rival is, before any work
    space = chain.design_space(soak_h=args.soak_h, start_temperatures_c=args.start_temperatures,
                               max_hours=args.max_hours, option="--max-hours")
    folder = output_folder(args, "design")
    say = (lambda m: None) if args.quiet else (lambda m: print(m, file=sys.stderr))
    say(f"fitting {len(labels)} rivals ({', '.join(labels)}) to {len(chain.runs)} run(s), "
        "then searching the experiments...")
    design = chain.design(labels, space=space, margin_sigma=args.margin, n_draws=args.draws,
                          seed=args.seed, progress=None if args.quiet else say)
    prov = output_provenance(instrument=inst, runs=chain.runs, seeds={"draws": args.seed})
    paths = write_design(design, args.output, chain.runs,
                         args.model if Path(args.model).exists() else inst.name,
                         provenance=prov)
    finish(folder, args, {"runs": prov["runs"], "model": prov["instrument"],
                           "seeds": prov["seeds"]})
    print(design.verdict)
    for k, v in design.proposed.items():
        now = design.current.get(k)
        print(f"- {design.pair_label(k)}: {now.sigma if now else float('nan'):.1f} sigma on "
              f"the runs taken -> {v.sigma:.1f} sigma on the proposed run")
    say("wrote " + ", ".join(str(p) for p in paths))
    return 0
