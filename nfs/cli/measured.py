"""``nfs fit``, ``nfs compare``, ``nfs diagnose``: the model beside measured runs.

Each command is :class:`nfs.UnitChain` on files: it reads the model and the runs, runs the
chain's step and writes the step's result (the fitted model's TOML, the comparison's
report, the finding's JSON: ``to_dict``), and reads an earlier result with ``from_dict``.
The library is imported inside each function (lazily), so that ``nfs --help`` and a
mistyped option answer without loading scikit-learn and matplotlib.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..errors import NfsError
from .common import finish, output_file, output_folder, read_command_runs, start_model

__all__ = ["cmd_fit", "cmd_compare", "cmd_diagnose", "read_finding"]


def read_finding(path: str, option: str = "--diagnosis"):
    """The finding an earlier ``nfs diagnose --json`` wrote (:class:`nfs.rivals.Finding`)."""
    from ..io.records import RecordError
    from ..rivals import Finding
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise NfsError(f"{option} {path}: not a readable JSON file written by nfs diagnose "
                       f"--json ({exc})") from None
    try:
        return Finding.from_dict(data)
    except RecordError as exc:
        raise NfsError(f"{option} {path}: not a finding written by nfs diagnose --json "
                       f"({exc})") from None


def _chain(args, check=None, say: bool = True):
    """The unit's chain on the command's model and runs; ``check(model, runs)`` runs before
    any work (a rival's label, an effect's name); ``say``: print the runs' caveats."""
    from .. import UnitChain, load_instrument
    inst = load_instrument(args.model)
    runs = read_command_runs(args, say=say)
    if check is not None:
        check(inst, runs)
    # only nfs fit has --decimate-s; the others take the chain's default
    grid = {"decimate_s": args.decimate_s} if hasattr(args, "decimate_s") else {}
    return UnitChain(inst, runs, start_state=start_model(args), **grid)


def cmd_fit(args) -> int:
    output_file(args.output, "-o", args.overwrite)
    chain = _chain(args, say=False)     # the fit's warnings state the runs' caveats
    if not args.quiet:
        print(f"fitting {chain.model.name} to {len(chain.runs)} run(s)...", file=sys.stderr)
    res = chain.fit(refine=not args.no_refine, free=args.free, stages=tuple(args.stages),
                    prior=None if args.no_prior else "default", prior_scale=args.prior_scale,
                    n_starts=args.starts, fit_noise=not args.no_noise_fit)
    chain.write_model(args.output)
    print(res.summary())
    print(f"wrote {args.output}")
    return 0


def cmd_compare(args) -> int:
    from ..report.compare_report import write_report
    from ..io.atomic import atomic_write_text
    from ..io.provenance import output_provenance
    output_file(args.json, "--json", args.overwrite)
    chain = _chain(args)
    folder = output_folder(args, "compare")
    if not args.quiet:
        print(f"simulating {chain.model.name} beside {len(chain.runs)} run(s)...",
              file=sys.stderr)
    c = chain.compare(seed=args.seed, startup_end_s=args.startup_end_s,
                      stable_start_s=args.stable_start_s)
    paths = write_report(c, args.output)
    # the runs are hashed once, for the JSON and the folder's manifest
    prov = output_provenance(instrument=chain.model, runs=chain.runs,
                             seeds={"model_noise": args.seed})
    if args.json:
        atomic_write_text(args.json, json.dumps({**c.to_dict(), "provenance": prov}, indent=1)
                          + "\n")
    finish(folder, args, {"runs": prov["runs"], "model": prov["instrument"],
                           "seeds": prov["seeds"]})
    for line in c.sentences() + [c.heading_sentence()]:
        print(f"- {line}")
    if not args.quiet:
        print("wrote " + ", ".join(str(p) for p in paths[:3]) + " ...", file=sys.stderr)
    return 0


def _check_diagnose(args):
    """What ``nfs diagnose``'s options ask, checked before any work."""
    from ..effects import get_effect
    from ..rivals.models import check_label
    if args.rivals is not None and len(args.rivals) < 2:
        raise NfsError(f"--rivals: a decision needs at least two explanations, got "
                       f"{len(args.rivals)}")
    if args.rivals is not None and args.apply:
        raise NfsError("--rivals puts explanations to the runs, --apply adds one: give one")
    if args.apply and args.output is None:
        raise NfsError("--apply needs -o FILE for the new model")

    def check(inst, runs):
        for label in args.rivals or ():
            check_label(inst, runs, label)
        if args.apply:
            get_effect(args.apply.partition(":")[0])   # an unknown name fails before work
    return check


def cmd_diagnose(args) -> int:
    from ..io.atomic import atomic_write_text
    from ..io.provenance import output_provenance
    from ..scoring.intervals import json_number
    check = _check_diagnose(args)
    output_file(args.output, "-o", args.overwrite)
    output_file(args.json, "--json", args.overwrite)
    chain = _chain(args, check)
    say = (lambda m: None) if args.quiet else (lambda m: print(m, file=sys.stderr))
    if args.apply:
        if args.diagnosis is not None:
            found, source = read_finding(args.diagnosis), f"the diagnosis in {args.diagnosis}"
        else:
            say(f"diagnosing {chain.model.name} on {len(chain.runs)} run(s) before adding "
                f"{args.apply}...")
            found = _diagnose(chain, args)
            source = "the diagnosis of these runs"
        applied = chain.apply(args.apply, finding=found)
        if not applied.supported:
            print(f"nfs: warning: {source} does not support this effect: {applied.support}; "
                  "adding it as asked", file=sys.stderr)
        chain.write_model(args.output)
        print(applied.summary(source))
        print(f"wrote {args.output}")
        return 0
    say(f"diagnosing {chain.model.name} on {len(chain.runs)} run(s)...")
    if args.decide or args.rivals:
        say("then, " + ("on a tie, " if not args.rivals else "")
            + "fitting each explanation and putting them to the runs...")
    finding = _diagnose(chain, args)
    d = finding.diagnosis
    print("| rank | effect | target | channel | significant | CV RMS before | after | "
          "coefficient |")
    print("|---:|---|---|---|---|---:|---:|---|")
    for i, sc in enumerate(d.ranking[:args.top], 1):
        coef = ", ".join(f"{k} = {v:.3g}" for k, v in sc.coefficient.items())
        sig = "yes" if sc.significant else "no"
        if sc.explained_by:
            sig += f" (explained by {sc.explained_by})"
        print(f"| {i} | {sc.effect} | {sc.target or ''} | {sc.channel} | {sig} | "
              f"{sc.cv_rms_before:.4g} | {sc.cv_rms_after:.4g} | {coef} |")
    print(finding.verdict)
    _print_checks(d)
    if args.json:
        prov = output_provenance(instrument=chain.model, runs=chain.runs,
                                 seeds={"bootstrap": args.seed})
        doc = type(finding)(d, finding.settlement, prov).to_dict()
        atomic_write_text(args.json, json.dumps(doc, indent=1, default=json_number) + "\n")
    return 0


def _diagnose(chain, args):
    return chain.diagnose(decide=args.decide, rivals=args.rivals, alpha=args.alpha,
                          seed=args.seed, node_temperatures=args.node_temperatures,
                          check_structure=not args.no_structure)


def _print_checks(d) -> None:
    """The residual's whiteness and the structure checks, a line each."""
    w = d.unexplained["ljung_box"]
    what = "against the gyro noise model" if w["whitened"] else "(plain: the model has no noise)"
    print(f"residual {what}: Ljung-Box p = {w['p_value']:.2g}, variance ratio "
          f"{w['variance_ratio']:.3g}: "
          + ("consistent with noise" if w["consistent"] else "not the noise alone"))
    if d.thermal_structure is not None and d.thermal_structure.adequate:
        print("thermal structure: adequate (every thermometer within "
              f"{d.thermal_structure.factor:g}x its noise floor, no generic alternative "
              "better)")
    if d.drift_structure is not None and d.drift_structure.adequate:
        print("drift structure: " + d.drift_structure.message)
    if d.not_tried:
        print(f"{len(d.not_tried)} candidate(s) not scored (reasons in --json 'not_tried')")
