"""``nfs fit``, ``nfs compare``, ``nfs diagnose``: the model beside measured runs.

Each command imports the library inside its function (lazily), so that ``nfs --help`` and
a mistyped option answer without loading scikit-learn and matplotlib.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from ..errors import NfsError
from .common import finish, output_file, output_folder, start_model

__all__ = ["cmd_fit", "cmd_compare", "cmd_diagnose"]


def cmd_fit(args) -> int:
    from .. import fit_unit, load_instrument, read_runs
    from ..diagnose import write_fitted_model
    inst = load_instrument(args.model)
    output_file(args.output, "-o", args.overwrite)
    runs = read_runs(args.data)
    if not args.quiet:
        print(f"fitting {inst.name} to {len(runs)} run(s)...", file=sys.stderr)
    res = fit_unit(inst, runs, refine=not args.no_refine, free=args.free,
                   stages=tuple(args.stages), decimate_s=args.decimate_s,
                   prior=None if args.no_prior else "default", prior_scale=args.prior_scale,
                   n_starts=args.starts, fit_noise=not args.no_noise_fit,
                   start_state=start_model(args))
    write_fitted_model(res, args.output)
    print(res.summary())
    print(f"wrote {args.output}")
    return 0


def cmd_compare(args) -> int:
    from .. import compare, load_instrument, read_runs
    from ..diagnose import write_report
    from ..io.atomic import atomic_write_text
    from ..io.provenance import output_provenance
    inst = load_instrument(args.model)
    output_file(args.json, "--json", args.overwrite)
    runs = read_runs(args.data)
    folder = output_folder(args, "compare")
    if not args.quiet:
        print(f"simulating {inst.name} beside {len(runs)} run(s)...", file=sys.stderr)
    c = compare(inst, runs, seed=args.seed, startup_end_s=args.startup_end_s,
                stable_start_s=args.stable_start_s, start_state=start_model(args))
    paths = write_report(c, args.output)
    # the runs are hashed once, for the JSON and the folder's manifest
    prov = output_provenance(instrument=inst, runs=runs, seeds={"model_noise": args.seed})
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


def cmd_diagnose(args) -> int:
    from ..diagnose import apply_candidate, candidate_finding, diagnose
    from ..effects import get_effect
    from ..io.atomic import atomic_write_text
    from ..scoring.intervals import json_number
    from .. import load_instrument, read_runs
    inst = load_instrument(args.model)
    if args.rivals is not None and len(args.rivals) < 2:
        raise NfsError(f"--rivals: a decision needs at least two explanations, got "
                       f"{len(args.rivals)}")
    if args.rivals is not None and args.apply:
        raise NfsError("--rivals puts explanations to the runs, --apply adds one: give one")
    if args.apply and args.output is None:
        raise NfsError("--apply needs -o FILE for the new model")
    output_file(args.output, "-o", args.overwrite)
    output_file(args.json, "--json", args.overwrite)
    runs = read_runs(args.data)
    if args.rivals:
        from ..design.rivals import check_label
        for label in args.rivals:          # before the diagnosis's work
            check_label(inst, runs, label)
    if args.apply:
        name, _, target = args.apply.partition(":")
        get_effect(name)  # an unknown name fails before any work
        if args.diagnosis is not None:
            try:
                found = json.loads(Path(args.diagnosis).read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:
                raise NfsError(f"--diagnosis {args.diagnosis}: not a readable JSON file "
                               f"written by nfs diagnose --json ({exc})") from None
            source = f"the diagnosis in {args.diagnosis}"
        else:
            if not args.quiet:
                print(f"diagnosing {inst.name} on {len(runs)} run(s) before adding "
                      f"{args.apply}...", file=sys.stderr)
            found = diagnose(inst, runs, random_state=args.seed, alpha=args.alpha,
                             node_temperatures=args.node_temperatures,
                             check_structure=not args.no_structure,
                             start_state=start_model(args)).to_dict()
            source = "the diagnosis of these runs"
        significant, finding = candidate_finding(found, name, target or None)
        if not significant:
            print(f"nfs: warning: {source} does not support this effect: {finding}; "
                  "adding it as asked", file=sys.stderr)
        new, fit, report = apply_candidate(inst, runs, name, target or None,
                                           start_state=start_model(args))
        from ..diagnose import write_fitted_model
        write_fitted_model(fit, args.output)
        print(f"added {args.apply} ({source}: {finding}); refitted:")
        print(fit.summary())
        for ch, after in report.get("rms_after", {}).items():
            before = report.get("rms_before", {}).get(ch, math.nan)
            print(f"- {ch}: residual RMS {before:.4g} -> {after:.4g}")
        hb, ha = report.get("heading_rmse_before_deg"), report.get("heading_rmse_after_deg")
        if hb is not None and ha is not None:
            print(f"- start-up heading RMSE {hb:.4f} -> {ha:.4f} deg")
        print(f"wrote {args.output}")
        return 0
    if not args.quiet:
        print(f"diagnosing {inst.name} on {len(runs)} run(s)...", file=sys.stderr)
    d = diagnose(inst, runs, random_state=args.seed, alpha=args.alpha,
                 node_temperatures=args.node_temperatures,
                 check_structure=not args.no_structure, start_state=start_model(args))
    print("| rank | effect | target | channel | significant | CV RMS before | after | "
          "coefficient |")
    print("|---:|---|---|---|---|---:|---:|---|")
    for i, sc in enumerate(d.ranking[:args.top], 1):
        row = sc.to_dict()
        coef = ", ".join(f"{k} = {v:.3g}" for k, v in (row.get("coefficient") or {}).items())
        sig = "yes" if row["significant"] else "no"
        if row["explained_by"]:
            sig += f" (explained by {row['explained_by']})"
        print(f"| {i} | {row['effect']} | {row['target'] or ''} | {row['channel']} | {sig} | "
              f"{row['cv_rms_before']:.4g} | {row['cv_rms_after']:.4g} | {coef} |")
    settled = None
    if (d.answer.kind == "tie" and args.decide) or args.rivals:
        from ..design.decide import settle_tie
        if not args.quiet:
            print(f"{'a tie: ' if not args.rivals else ''}fitting each explanation and "
                  "putting them to the runs...", file=sys.stderr)
        settled = settle_tie(d.to_dict(), inst, runs, labels=args.rivals,
                             start_state=start_model(args))
    print(d.verdict if settled is None else settled.answer.text)
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
    if args.json:
        from ..io.provenance import output_provenance
        doc = {**d.to_dict(), "provenance": output_provenance(
            instrument=inst, runs=runs, seeds={"bootstrap": args.seed})}
        if settled is not None:
            # the one answer: the tie put to the runs (the diagnosis's own tie stays in
            # "settlement" for nfs design --diagnosis)
            doc["settlement"] = settled.to_dict()
            doc["tie"] = doc["answer"]
            doc["answer"] = settled.answer.to_dict()
            doc["verdict"] = settled.answer.text
        atomic_write_text(args.json, json.dumps(doc, indent=1, default=json_number) + "\n")
    return 0
