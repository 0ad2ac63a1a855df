"""``nfs design``: the run that would tell a diagnosis's rival explanations apart.

The library is imported inside the command (as in every command module) so that
``nfs --help`` stays fast.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from pathlib import Path

from ..errors import NfsError
from .common import finish, output_folder, start_model

__all__ = ["cmd_design"]


def _rival_labels(args) -> list[str]:
    from ..design import rivals_from_diagnosis
    if args.rivals:
        return list(args.rivals)
    if args.diagnosis is None:
        raise NfsError("give the rivals: --diagnosis D.json (what nfs diagnose --json found) "
                       "or --rivals A B ...")
    try:
        found = json.loads(Path(args.diagnosis).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise NfsError(f"--diagnosis {args.diagnosis}: not a readable JSON file written by "
                       f"nfs diagnose --json ({exc})") from None
    if not isinstance(found, dict):
        raise NfsError(f"--diagnosis {args.diagnosis}: not a diagnosis (a JSON object "
                       "written by nfs diagnose --json)")
    return rivals_from_diagnosis(found)


def cmd_design(args) -> int:
    from .. import load_instrument, read_runs
    from ..design import design_experiment, rival_models
    from ..design.report import write_design
    from ..design.rivals import check_label
    from ..design.space import base_conditions, default_space
    from ..io.provenance import output_provenance
    if args.rivals is not None and args.diagnosis is not None:
        raise NfsError("give either --diagnosis or --rivals, not both")
    if args.rivals is not None and len(args.rivals) < 2:
        raise NfsError(f"--rivals: a design needs at least two rivals, got "
                       f"{len(args.rivals)}")
    labels = _rival_labels(args)
    inst = load_instrument(args.model)
    runs = read_runs(args.data)
    for label in labels:                # what each rival is, before any work
        check_label(inst, runs, label)
    folder = output_folder(args, "design")
    space = default_space(runs, soak_h=args.soak_h)
    if args.start_temperatures is not None:
        space = dataclasses.replace(space,
                                    start_temperatures_c=tuple(args.start_temperatures))
    if args.max_hours is not None:
        step = space.duration_step_s
        longest = step * math.floor((args.max_hours - args.soak_h) * 3600.0 / step + 1e-9)
        if longest < step:
            raise NfsError(f"--max-hours {args.max_hours:g}: no run of {step / 60.0:g} min "
                           f"fits after the {args.soak_h:g} h soak (--soak-h)")
        space = dataclasses.replace(space, max_duration_s=longest)
    say = (lambda m: None) if args.quiet else (lambda m: print(m, file=sys.stderr))
    say(f"fitting {len(labels)} rivals ({', '.join(labels)}) to {len(runs)} run(s)...")
    rivals = rival_models(inst, runs, labels, start_state=start_model(args))
    say(f"searching {len(space.experiments())} experiments...")
    design = design_experiment(rivals, runs, base_conditions(runs), space,
                               margin_sigma=args.margin, n_draws=args.draws, seed=args.seed,
                               progress=None if args.quiet else say)
    prov = output_provenance(instrument=inst, runs=runs, seeds={"draws": args.seed})
    paths = write_design(design, args.output, runs, args.model if Path(args.model).exists()
                         else inst.name, provenance=prov)
    finish(folder, args, {"runs": prov["runs"], "model": prov["instrument"],
                           "seeds": prov["seeds"]})
    print(design.verdict)
    for k, v in design.proposed.items():
        now = design.current.get(k)
        print(f"- {design.pair_label(k)}: {now.sigma if now else float('nan'):.1f} sigma on "
              f"the runs taken -> {v.sigma:.1f} sigma on the proposed run")
    say("wrote " + ", ".join(str(p) for p in paths))
    return 0
