"""``nfs table``, ``nfs train``, ``nfs compensate``: the chain, and compensators trained and
applied.

Each command imports the library inside its function (lazily), so that ``nfs --help`` and
a mistyped option answer without loading scikit-learn and matplotlib.
"""

from __future__ import annotations

import dataclasses
import math
import sys

from ..errors import NfsError
from .common import (Progress, finish, gate, output_file, output_folder, read_command_runs,
                     say_ignored,
                     with_overrides)

__all__ = ["cmd_table", "cmd_train", "cmd_compensate"]


def cmd_table(args) -> int:
    from .. import CompensationSettings, ModelChain, load_scenario
    from ..compensate.modes import check_features_mode
    from ..studies.job_estimate import estimate_table, run_samples, table_scenarios
    if args.features_mode is not None:
        check_features_mode(args.features_mode, "--features-mode")
    scenario = with_overrides(load_scenario(args.scenario), args)
    output_file(args.json, "--json", args.overwrite)
    settings = _table_settings(args, scenario.compensation or CompensationSettings())
    compensate = not args.no_compensation
    if args.repeats is None:            # --repeats sets the table's start-ups: none ignored
        say_ignored(scenario, "table", settings, compensate)
    chain = ModelChain(scenario, settings, compensate=compensate)
    baseline = _baseline(args, chain)
    folder = output_folder(args, "table")
    scenarios = table_scenarios(scenario, settings, compensate)
    gate(lambda: estimate_table(scenario, settings, compensate),
         sum(n for sc in scenarios for n in run_samples(sc.conditions())), args, rows=False,
         held=True, fewer="or fewer test start-ups: --repeats N")
    chain.progress = Progress("simulating" if args.no_compensation else "", args.quiet)
    # what is printed and written is what the chain's result holds
    result = chain.run_model()
    paths = result.write(args.output, json_path=args.json)
    comparison = None
    if baseline is not None:
        from ..report.baseline import baseline_comparison_markdown, write_baseline_comparison
        from ..scoring.baseline import compare_tables
        comparison = compare_tables(result.table, baseline, tolerance=args.tolerance)
        paths += write_baseline_comparison(comparison, args.output)
    inputs = {"scenario": result.provenance["scenario"], "compensation": result.compensated}
    if baseline is not None:
        inputs["baseline"] = {"file": str(args.baseline), "sha256": args.baseline_sha256}
    finish(folder, args, inputs)
    print(result.markdown, end="")
    if comparison is not None:
        print(f"\n## Against the baseline {args.baseline}\n\n"
              + baseline_comparison_markdown(comparison), end="")
    if not args.quiet:
        print("\nwrote " + ", ".join(str(p) for p in paths), file=sys.stderr)
    return 0 if comparison is None else comparison.exit_code


def _table_settings(args, settings):
    """The scenario's ``[compensation]`` with the command line's overrides, checked."""
    # option -> (field of the settings, smallest value allowed or None)
    overrides = {"budget": ("budget", 1), "repeats": ("test_repeats", None),
                 "n_jobs": ("n_jobs", None), "tuner_seeds": ("tuner_seeds", 1),
                 "features_mode": ("features_mode", None)}
    for option, (name, least) in overrides.items():
        value = getattr(args, option)
        if value is None:
            continue
        if least is not None and value < least:
            raise NfsError(f"--{option.replace('_', '-')} must be >= {least}, got {value}")
        settings = dataclasses.replace(settings, **{name: value})
    return settings


def _baseline(args, chain):
    """The --baseline table, read and checked before any work against the rows and start
    temperatures of the table the chain will make (None without --baseline)."""
    if args.baseline is None:
        if args.tolerance is not None:
            raise NfsError("--tolerance needs --baseline OLD.json")
        return None
    from ..io.provenance import sha256_of_file
    from ..scoring.baseline import TOLERANCE
    from ..scoring.tablefile import check_common, read_table
    if args.tolerance is None:
        args.tolerance = TOLERANCE
    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise NfsError(f"--tolerance must be a finite number >= 0 (0.05: 5 %), got "
                       f"{args.tolerance}")
    baseline = read_table(args.baseline, "--baseline")
    # hashed now: the file may be the --json this run replaces
    args.baseline_sha256 = sha256_of_file(args.baseline)
    rows = chain.table_rows()
    if rows is None:
        raise NfsError(f"--baseline compares heading tables; scenario '{chain.scenario.name}' "
                       f"has compensation.protocol = \"{chain.settings.protocol}\", which "
                       "writes another table (or add --no-compensation)")
    check_common(baseline, chain.scenario.start_temperatures_c, rows)
    return baseline


def cmd_train(args) -> int:
    from .. import train_compensator
    from ..compensate import get_method, resolve_features
    from ..compensate.modes import check_features_mode
    get_method(args.method)                  # a bad name fails before any work
    resolve_features(args.features, ["aux_*"])
    check_features_mode(args.features_mode, "--features-mode")
    output_file(args.output, "-o", args.overwrite)
    runs = read_command_runs(args)
    missing = [r.name for r in runs if r.meta.true_heading_deg is None]
    if missing:
        raise NfsError(f"run '{missing[0]}' has no true_heading_deg in its TOML: training "
                       "needs the known heading to separate the drift")
    if not args.quiet:
        print(f"training {args.method} on {len(runs)} run(s)...", file=sys.stderr)
    comp = train_compensator(args.method, runs, features=args.features, budget=args.budget,
                             random_state=args.seed, n_jobs=args.n_jobs,
                             decimate_s=args.decimate_s, cutoff_period_s=args.cutoff_s,
                             features_mode=args.features_mode)
    comp.save(args.output)
    print(f"{comp.method} trained on {len(runs)} run(s) in {comp.fit_time_s:.1f} s; "
          f"features: {', '.join(comp.feature_names)} ({comp.features_mode} mode); "
          f"wrote {args.output}")
    est = comp.estimator
    if hasattr(est, "best_params_"):
        print("tuned: " + ", ".join(f"{k} = {v:.4g}" for k, v in est.best_params_.items()))
    return 0


def cmd_compensate(args) -> int:
    import warnings
    from .. import load_compensator, write_run
    from ..compensate.model_file import model_file_kind
    from ..compensate.modes import check_features_mode
    if args.trust_pickle and model_file_kind(args.model) not in ("nfs-model", "missing"):
        print(f"nfs: warning: --trust-pickle: unpickling {args.model} runs any code it holds; "
              "load_compensator(path, trust_pickle=True).save('model.npz') converts a trusted "
              "one", file=sys.stderr)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        comp = load_compensator(args.model, trust_pickle=args.trust_pickle)
    for w in caught:
        print(f"nfs: warning: {w.message}", file=sys.stderr)
    if args.features_mode is not None and \
            check_features_mode(args.features_mode, "--features-mode") != comp.features_mode:
        raise NfsError(f"--features-mode {args.features_mode}: the model was trained in "
                       f"{comp.features_mode} mode, and is applied in the mode it was "
                       "trained in")
    from ..io.provenance import runs_provenance
    runs = read_command_runs(args)
    folder = output_folder(args, "compensate")
    # Every run is compensated before anything is written: a run that lacks an input
    # channel stops the command with nothing half-written.
    out = [comp.compensate(r) for r in runs]
    for r in out:
        print(write_run(r, args.output))
    finish(folder, args, {"runs": runs_provenance(runs), "model": str(args.model)})
    return 0
