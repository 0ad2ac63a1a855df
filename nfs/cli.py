"""The ``nfs`` command: thin; parse, call the library, turn NfsError into one line + exit 2.

    nfs table [SCENARIO] [-o DIR] [--json FILE]      heading-RMSE table by start temperature
              [--baseline OLD.json]              ... set beside an earlier table (exit 1: worse)
    nfs simulate SCENARIO -o DIR                     measurement files, one run per T0
    nfs northfind DATA... [--json FILE]              north-find measured or simulated runs
    nfs train DATA... --method M -o MODEL            train a drift compensator
    nfs compensate DATA... --model MODEL -o DIR      apply it
    nfs fit DATA... [--model M] -o FITTED.toml       calibrate a model to measured runs
    nfs compare DATA... --model M -o DIR             the model beside the runs
    nfs diagnose DATA... --model M [--apply NAME]    the missing effect, ranked
    nfs preset [NAME]                                print a built-in instrument or scenario
    nfs init DIR                                     a starter scenario and instrument
    nfs effects                                      list the registered physical effects
"""

from __future__ import annotations

import argparse
import os
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

from .errors import NfsError, USER_ERRORS
from .ranges import check, one_line_warnings

__all__ = ["main"]

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


def _cmd_table(args) -> int:
    from .chain import ModelChain
    from .compensate.modes import check_features_mode
    from .compensate.settings import CompensationSettings
    from .config.scenario import load_scenario
    if args.features_mode is not None:
        check_features_mode(args.features_mode, "--features-mode")
    scenario = _with_overrides(load_scenario(args.scenario), args)
    _file(args.json, "--json", args.overwrite)
    settings = _table_settings(args, scenario.compensation or CompensationSettings())
    baseline = _baseline(args, scenario, settings)
    folder = _folder(args, "table")
    progress = Progress("simulating" if args.no_compensation else "", args.quiet)
    result = ModelChain(scenario, settings, compensate=not args.no_compensation,
                        progress=progress).run_model()
    provenance, table, text = result.provenance, result.table, result.markdown
    paths = result.write(args.output, json_path=args.json)
    comparison = None
    if baseline is not None:
        from .report.baseline import compare_tables, write_baseline_comparison
        comparison = compare_tables(table, baseline, tolerance=args.tolerance)
        paths += write_baseline_comparison(comparison, args.output)
    inputs = {"scenario": provenance["scenario"], "compensation": not args.no_compensation}
    if baseline is not None:
        inputs["baseline"] = {"file": str(args.baseline), "sha256": args.baseline_sha256}
    _finish(folder, args, inputs)
    print(text, end="")
    if comparison is not None:
        print(f"\n## Against the baseline {args.baseline}\n\n" + comparison.to_markdown(),
              end="")
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


def _baseline(args, scenario, settings):
    """The --baseline table, read and checked against the table to come before any work
    (None without --baseline)."""
    if args.baseline is None:
        if args.tolerance is not None:
            raise NfsError("--tolerance needs --baseline OLD.json")
        return None
    from .compensate import get_method
    from .io.provenance import sha256_of_file
    from .report.baseline import TOLERANCE, check_common, read_table
    from .scoring.heading_table import REFERENCE_ROWS
    if args.tolerance is None:
        args.tolerance = TOLERANCE
    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise NfsError(f"--tolerance must be a finite number >= 0 (0.05: 5 %), got "
                       f"{args.tolerance}")
    baseline = read_table(args.baseline, "--baseline")
    # hashed now: the file may be the --json this run replaces
    args.baseline_sha256 = sha256_of_file(args.baseline)
    methods = list(REFERENCE_ROWS)
    if not args.no_compensation:
        if settings.protocol != "start-ups":
            raise NfsError(f"--baseline compares heading tables; scenario '{scenario.name}' "
                           f"has compensation.protocol = \"{settings.protocol}\", which writes "
                           "another table (or add --no-compensation)")
        methods += [get_method(m).name for m in settings.methods]
    check_common(baseline, scenario.start_temperatures_c, methods)
    return baseline


def _cmd_train(args) -> int:
    from .compensate import get_method, resolve_features, train_compensator
    from .compensate.modes import check_features_mode
    from .io.measurement import read_runs
    get_method(args.method)                  # a bad name fails before any work
    resolve_features(args.features, ["aux_*"])
    check_features_mode(args.features_mode, "--features-mode")
    _file(args.output, "-o", args.overwrite)
    runs = read_runs(args.data)
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


def _cmd_compensate(args) -> int:
    import warnings
    from .compensate import load_compensator
    from .compensate.model_file import model_file_kind
    from .compensate.modes import check_features_mode
    from .io.measurement import read_runs, write_run
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
    from .io.provenance import runs_provenance
    runs = read_runs(args.data)
    folder = _folder(args, "compensate")
    # Every run is compensated before anything is written: a run that lacks an input
    # channel stops the command with nothing half-written.
    out = [comp.compensate(r) for r in runs]
    for r in out:
        print(write_run(r, args.output))
    _finish(folder, args, {"runs": runs_provenance(runs), "model": str(args.model)})
    return 0


def _folder(args, command: str):
    """The checked output folder of a folder-writing command (before any work)."""
    from .io.outdir import OutputFolder
    return OutputFolder(args.output, command, overwrite=args.overwrite)


def _file(path, option: str, overwrite: bool = False):
    """Check an output file's place before any work (None passes): its folder exists and
    takes files, and no file is there unless ``overwrite`` (the command's --overwrite)."""
    from .io.outdir import check_output_file
    if path is None:
        return
    p = check_output_file(path, option)
    if not overwrite and (p.exists() or p.is_symlink()):
        raise NfsError(f"{option} {p}: the file exists; give --overwrite to replace it")


def _finish(folder, args, inputs: dict) -> None:
    """Write the folder's manifest and say what happened to an earlier output's files."""
    # The command line without the folder itself: the same command into two folders writes
    # the same manifest.
    argv, skip = [], False
    for tok in getattr(args, "argv", []):
        if skip:
            skip = False
        elif tok in ("-o", "--output"):
            skip = True
        elif not tok.startswith("--output=") and not (tok.startswith("-o") and
                                                      not tok.startswith("--")):
            argv.append(tok)
    folder.finish(arguments=argv, inputs=inputs)
    note = folder.summary()
    if note:
        print(f"nfs: {note}", file=sys.stderr)


def _with_overrides(scenario, args):
    changes = {}
    if getattr(args, "seed", None) is not None:
        changes["seed"] = args.seed
    if getattr(args, "repeats", None) is not None:
        if args.repeats < 1:
            raise NfsError(f"--repeats must be >= 1, got {args.repeats}")
        changes["repeats"] = args.repeats
    return dataclasses.replace(scenario, **changes) if changes else scenario


def _cmd_simulate(args) -> int:
    from .experiment import simulate_run
    from .io.measurement import write_run
    from .config.scenario import load_scenario
    from .io.provenance import scenario_provenance
    scenario = _with_overrides(load_scenario(args.scenario), args)
    folder = _folder(args, "simulate")
    out = Path(args.output)
    conds = scenario.conditions()
    progress = Progress("simulating", args.quiet)
    written = []
    for i, cond in enumerate(conds):
        progress(i, len(conds), cond.name)
        written.append(write_run(simulate_run(scenario.instrument, cond).run, out))
    progress(len(conds), len(conds), "done")
    _finish(folder, args, {"scenario": scenario_provenance(scenario)})
    for p in written:
        print(p)
    return 0


def _cmd_northfind(args) -> int:
    from .io.atomic import atomic_write_text
    from .io.measurement import read_runs
    from .northfind import heading_rmse, north_find
    if args.heading_hint is not None and not math.isfinite(args.heading_hint):
        raise NfsError(f"--heading-hint: {args.heading_hint} is not a finite angle in degrees")
    _file(args.json, "--json", args.overwrite)
    runs = read_runs(args.data)
    rows = []
    out = {"runs": []}
    for run in runs:
        res = north_find(run, tilt_correction=not args.no_tilt, settle_s=args.settle_s,
                         heading_hint_deg=args.heading_hint)
        if res.n_missing:
            print(f"nfs: warning: run '{run.name}': "
                  + ", ".join(f"{n} samples without a {c} value" for c, n in
                              res.n_missing.items())
                  + " inside the dwells, left out of their dwell means", file=sys.stderr)
        known = res.true_heading_deg is not None
        st = heading_rmse(res, startup_end_s=args.startup_end_s,
                          stable_start_s=args.stable_start_s) if known else None
        rows.append((run.name, run.meta.start_temperature_c, res.n_cycles, res.ambiguous,
                     _circ_mean(res.heading_deg),
                     st.startup_deg if st else math.nan, st.stable_deg if st else math.nan))
        out["runs"].append({
            "name": run.name, "start_temperature_c": run.meta.start_temperature_c,
            "latitude_deg": run.meta.latitude_deg, "true_heading_deg": res.true_heading_deg,
            "ambiguous": bool(res.ambiguous),
            "startup_rmse_deg": _j(st.startup_deg) if st else None,
            "stable_rmse_deg": _j(st.stable_deg) if st else None,
            "cycles": [{"t_start_s": _j(a), "t_end_s": _j(b), "heading_deg": _j(h),
                        "error_deg": _j(e), "bias_dph": _j(bb)}
                       for a, b, h, e, bb in zip(res.t_start_s, res.t_end_s, res.heading_deg,
                                                 res.error_deg, res.bias_dph)],
        })
    print("| run | T0 [C] | cycles | mean heading [deg] | start-up RMSE [deg] | stable RMSE [deg] |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, t0, n, amb, h, su, sb in rows:
        if amb:
            print(f"| {name} | {t0:g} | {n} | ambiguous | - | - |")
        else:
            print(f"| {name} | {t0:g} | {n} | {h:.4f} | {_f(su)} | {_f(sb)} |")
    ambiguous = [r[0] for r in rows if r[3]]
    if ambiguous:
        print(f"ambiguous: {', '.join(ambiguous)}: a schedule whose positions lie on one "
              "line (e.g. 0 and 180 deg) cannot tell the heading from its mirror image about "
              "that line; give --heading-hint DEG (a coarse heading, e.g. from a magnetic "
              "compass) to pick the branch (the JSON holds one branch, marked ambiguous)")
    if args.json:
        from .io.provenance import output_provenance
        out["provenance"] = output_provenance(runs=runs)
        atomic_write_text(args.json, json.dumps(out, indent=1) + "\n")
    return 0


def _circ_mean(angles_deg) -> float:
    import numpy as np
    a = np.radians(np.asarray(angles_deg, dtype=float))
    a = a[np.isfinite(a)]
    if a.size == 0:
        return math.nan
    return float(np.degrees(np.arctan2(np.sin(a).mean(), np.cos(a).mean())) % 360.0)


def _f(v: float) -> str:
    return "n/a" if not math.isfinite(v) else f"{v:.4f}"


def _j(v):
    v = float(v)
    return v if math.isfinite(v) else None


def _load_model(name_or_path):
    from .instrument import load_instrument
    return load_instrument(name_or_path)


def _cmd_fit(args) -> int:
    from .diagnose import fit_unit, write_fitted_model
    from .io.measurement import read_runs
    inst = _load_model(args.model)
    _file(args.output, "-o", args.overwrite)
    runs = read_runs(args.data)
    if not args.quiet:
        print(f"fitting {inst.name} to {len(runs)} run(s)...", file=sys.stderr)
    res = fit_unit(inst, runs, refine=not args.no_refine, free=args.free,
                   stages=tuple(args.stages), decimate_s=args.decimate_s,
                   prior=None if args.no_prior else "default", prior_scale=args.prior_scale,
                   n_starts=args.starts, fit_noise=not args.no_noise_fit,
                   start_state=_start_model(args))
    write_fitted_model(res, args.output)
    print(res.summary())
    print(f"wrote {args.output}")
    return 0


def _cmd_compare(args) -> int:
    from .diagnose import compare, write_report
    from .io.atomic import atomic_write_text
    from .io.measurement import read_runs
    from .io.provenance import output_provenance
    inst = _load_model(args.model)
    _file(args.json, "--json", args.overwrite)
    runs = read_runs(args.data)
    folder = _folder(args, "compare")
    if not args.quiet:
        print(f"simulating {inst.name} beside {len(runs)} run(s)...", file=sys.stderr)
    c = compare(inst, runs, seed=args.seed, startup_end_s=args.startup_end_s,
                stable_start_s=args.stable_start_s, start_state=_start_model(args))
    paths = write_report(c, args.output)
    # the runs are hashed once, for the JSON and the folder's manifest
    prov = output_provenance(instrument=inst, runs=runs, seeds={"model_noise": args.seed})
    if args.json:
        atomic_write_text(args.json, json.dumps({**c.to_dict(), "provenance": prov}, indent=1)
                          + "\n")
    _finish(folder, args, {"runs": prov["runs"], "model": prov["instrument"],
                           "seeds": prov["seeds"]})
    for line in c.sentences() + [c.heading_sentence()]:
        print(f"- {line}")
    if not args.quiet:
        print("wrote " + ", ".join(str(p) for p in paths[:3]) + " ...", file=sys.stderr)
    return 0


def _cmd_diagnose(args) -> int:
    from .diagnose import apply_candidate, candidate_finding, diagnose
    from .effects import get_effect
    from .io.atomic import atomic_write_text
    from .io.measurement import read_runs
    inst = _load_model(args.model)
    if args.apply and args.output is None:
        raise NfsError("--apply needs -o FILE for the new model")
    _file(args.output, "-o", args.overwrite)
    _file(args.json, "--json", args.overwrite)
    runs = read_runs(args.data)
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
                             start_state=_start_model(args)).to_dict()
            source = "the diagnosis of these runs"
        significant, finding = candidate_finding(found, name, target or None)
        if not significant:
            print(f"nfs: warning: {source} does not support this effect: {finding}; "
                  "adding it as asked", file=sys.stderr)
        new, fit, report = apply_candidate(inst, runs, name, target or None,
                                           start_state=_start_model(args))
        from .diagnose import write_fitted_model
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
                 check_structure=not args.no_structure, start_state=_start_model(args))
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
    print(d.verdict)
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
        from .io.provenance import output_provenance
        doc = {**d.to_dict(), "provenance": output_provenance(
            instrument=inst, runs=runs, seeds={"bootstrap": args.seed})}
        atomic_write_text(args.json, json.dumps(doc, indent=1, default=_j) + "\n")
    return 0


def _cmd_preset(args) -> int:
    from .instrument import preset_names, preset_path
    from .config.presets import (scenario_preset_names, scenario_preset_path, sweep_preset_names, sweep_preset_path)
    if args.name is None:
        print("instruments (nfs preset NAME > my_instrument.toml):")
        print("\n".join(f"  {n}" for n in preset_names()))
        print("scenarios (run by name from any folder: nfs table NAME; a copy to edit with "
              "its instrument: nfs init DIR --from NAME):")
        print("\n".join(f"  {n}" for n in scenario_preset_names()))
        print("sweeps (nfs sweep NAME -o DIR; nfs init DIR --from NAME):")
        print("\n".join(f"  {n}" for n in sweep_preset_names()))
        return 0
    if args.name in scenario_preset_names():
        path = scenario_preset_path(args.name)
    elif args.name in sweep_preset_names():
        path = sweep_preset_path(args.name)
    elif args.name in preset_names():
        path = preset_path(args.name)
    else:
        raise NfsError(f"unknown preset '{args.name}'; instruments: "
                       f"{', '.join(preset_names())}; scenarios: "
                       f"{', '.join(scenario_preset_names())}; sweeps: "
                       f"{', '.join(sweep_preset_names())}")
    sys.stdout.write(path.read_text(encoding="utf-8"))
    return 0


def _set_key(text: str, key: str, value: str, comment: str) -> str:
    """``text`` (TOML) with its top-level ``key = ...`` line set to the string ``value`` (added
    after the first comment block when absent)."""
    import re
    line = f'{key} = "{value}"' + (f"      # {comment}" if comment else "")
    m = re.search(rf'^{key}\s*=.*$', text, flags=re.MULTILINE)
    if m is not None:
        return text[:m.start()] + line + text[m.end():]
    head = re.match(r'(?:#.*\n|\s*\n)*', text).end()
    return text[:head] + line + "\n" + text[head:]


def _cmd_init(args) -> int:
    import re
    from .instrument import preset_path
    from .io.atomic import atomic_write_files
    from .config.scenario import load_scenario
    from .config.presets import (scenario_preset_names, scenario_preset_path, sweep_preset_names, sweep_preset_path)
    from .sweep import load_sweep
    name = args.source
    out = Path(args.output)
    label = out.resolve().name or "my_unit"
    files: dict[Path, str] = {}
    if name in sweep_preset_names():
        sweep_path = sweep_preset_path(name)
        sweep_text = sweep_path.read_text(encoding="utf-8")
        m = re.search(r'^scenario\s*=\s*"([^"]+)".*$', sweep_text, flags=re.MULTILINE)
        scen_path = (sweep_path.parent / m.group(1)).resolve()
        files[out / "sweep.toml"] = _set_key(sweep_text, "scenario", "scenario.toml",
                                             "the file beside this one")
        source = f"sweep preset '{name}'"
    elif name in scenario_preset_names():
        scen_path = scenario_preset_path(name)
        source = f"scenario preset '{name}'"
    else:
        raise NfsError(f"--from {name}: no such scenario or sweep preset; scenarios: "
                       f"{', '.join(scenario_preset_names())}; sweeps: "
                       f"{', '.join(sweep_preset_names())}")
    scen_text = scen_path.read_text(encoding="utf-8")
    m = re.search(r'^instrument\s*=\s*"([^"]+)".*$', scen_text, flags=re.MULTILINE)
    inst_preset = m.group(1) if m is not None else "default"
    inst_text = _set_key(preset_path(inst_preset).read_text(encoding="utf-8"), "name", label,
                         "your unit's name: reports compare models by it")
    scen_text = _set_key(scen_text, "instrument", "instrument.toml",
                         "the file beside this one (or a built-in preset name: nfs preset)")
    scen_text = _set_key(scen_text, "name", label, "your experiment's name")
    header = (f"# Written by `nfs init` from the built-in {source}.\n"
              f"# Edit it and run:  nfs table scenario.toml -o results\n"
              f"# Its instrument is instrument.toml beside it (the preset '{inst_preset}').\n#\n")
    files[out / "scenario.toml"] = header + scen_text
    files[out / "instrument.toml"] = inst_text
    folder = _folder(args, "init")
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_files(files)
    load_scenario(out / "scenario.toml")  # what was written loads (a check of the package)
    if out / "sweep.toml" in files:
        load_sweep(out / "sweep.toml")
    _finish(folder, args, {"preset": name, "instrument_preset": inst_preset})
    run = (f"nfs sweep {out / 'sweep.toml'} -o {out / 'sweep_results'}" if out / "sweep.toml"
           in files else f"nfs table {out / 'scenario.toml'} -o {out / 'results'}")
    print("wrote " + ", ".join(str(p) for p in files) + f"; run: {run}")
    return 0


def _cmd_effects(args) -> int:
    from .effects import available_effects, get_effect
    for name in available_effects():
        spec = get_effect(name)
        params = ", ".join(f"{p.name} [{p.unit}]" if p.unit else p.name
                           for p in spec.parameters)
        print(f"{name} ({spec.kind}): {spec.summary}")
        if params:
            print(f"    parameters: {params}")
    return 0


def _cmd_sweep(args) -> int:
    from .sweep import CellStore, DaskExecutor, LocalExecutor, load_sweep, run_sweep
    spec = load_sweep(args.sweep)                   # the whole sweep checked before any work
    CellStore(args.output).prepare()
    if args.dask_local is not None and args.scheduler is not None:
        raise NfsError("give --dask-local N or --scheduler ADDRESS, not both")
    if args.dask_local is not None or args.scheduler is not None:
        executor = DaskExecutor(workers=args.dask_local, address=args.scheduler)
    else:
        executor = LocalExecutor(args.jobs)
    log = None if args.quiet else (lambda msg: print(f"sweep: {msg}", file=sys.stderr))
    try:
        res = run_sweep(spec, args.output, executor=executor, quiet=args.quiet, log=log)
    finally:
        executor.close()
    print(f"{res.n_cells} cells ({res.n_computed} computed, {res.n_cells - res.n_computed} "
          f"from the store), {res.n_rows} rows")
    for p in res.paths:
        print(p)
    return 0


def _runs(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", nargs="+", help="NAME.csv files, NAME.toml files or folders")


def _runs_and_model(p: argparse.ArgumentParser) -> None:
    _runs(p)
    p.add_argument("--model", default="default",
                   help="instrument preset name or TOML file (default: default)")
    p.add_argument("--start", choices=("estimated", "soaked"), default="estimated",
                   help="each run's node temperatures at power-on: estimated from its "
                        "thermometers with the model (an unfinished soak, a unit off its "
                        "air; default), or soaked: every node at the run's T0")


def _start_model(args):
    """The start model of ``--start`` (nfs.diagnose.start_state)."""
    from .diagnose.thermal_residual import DEFAULT_START
    return DEFAULT_START if args.start == "estimated" else None


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="nfs",
        description="Start-up experiments on fiber-optic-gyroscope north finders: simulate "
                    "chamber runs, north-find them, compensate the drift, tabulate heading "
                    "RMSE by start temperature.")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    t = sub.add_parser("table", help="heading-RMSE table by start temperature",
                       description="Simulate a scenario (the built-in default when none is "
                                   "given), north-find every run, print the Markdown table "
                                   "and write it as CSV, Markdown, JSON and a PNG bar chart.")
    t.add_argument("scenario", nargs="?", default=None, help="scenario TOML file")
    t.add_argument("-o", "--output", default="results", help="output folder (default: results)")
    t.add_argument("--json", default=None, help="also write the table as JSON to this file")
    t.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    t.add_argument("--repeats", type=int, default=None,
                   help="test start-ups per start temperature (overrides the "
                        "compensation's test_repeats; the before row is theirs in both modes)")
    t.add_argument("--budget", type=int, default=None,
                   help="evaluations per tuned method (default: the scenario's, 30)")
    t.add_argument("--n-jobs", type=int, default=None,
                   help="trainings (methods x tuner seeds) run in parallel (default: the "
                        "scenario's; -1 every core)")
    t.add_argument("--tuner-seeds", type=int, default=None,
                   help="seeds of each stochastic tuner; a tuned row is the median seed's "
                        "(default: the scenario's, 3)")
    t.add_argument("--features-mode", default=None, metavar="MODE",
                   help=FEATURES_MODE_HELP + " (default: the scenario's, cycle)")
    t.add_argument("--no-compensation", action="store_true",
                   help="only the uncompensated rows (before, stable, floor)")
    t.add_argument("--baseline", default=None, metavar="OLD.json",
                   help="compare every cell with a table an earlier nfs table --json wrote: "
                        "the change with its 95 %% interval, a verdict per cell, "
                        "baseline_comparison.{md,json} in the output folder; exit 1 when a "
                        "cell is worse beyond both the noise and --tolerance")
    t.add_argument("--tolerance", type=float, default=None,
                   help="relative change a worse cell must also exceed (default 0.05: 5 %%)")
    t.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    t.add_argument("--trust-effects", action="store_true",
                    help="let the scenario's effects_files (Python files of your own "
                         "effects) run; read them first: a scenario file does not run code "
                         "otherwise")
    t.add_argument("--overwrite", action="store_true",
                   help="replace an existing --json file, and write into a folder that holds "
                        "another command's output or files of unknown origin (files of the "
                        "earlier output that are not rewritten are removed)")
    t.set_defaults(func=_cmd_table)

    tr = sub.add_parser("train", help="train a drift compensator on measured runs",
                        description="Train a compensator (features of the three thermometers "
                                    "-> wavelet-separated gyro drift) on runs with a known "
                                    "heading, and save it with its feature list and versions.")
    _runs(tr)
    tr.add_argument("--method", default="ssa-svr",
                    help="ls, stepwise, bp, rbf, lssvm, ir-lssvm, svr-grid, pso-svr, gwo-svr, "
                         "ssa-svr (default), hho-rvr, tpe-svr")
    tr.add_argument("-o", "--output", required=True,
                    help="model file to write, e.g. model.npz (nfs-model/1: arrays and JSON, "
                         "loaded without running code)")
    tr.add_argument("--overwrite", action="store_true", help="replace an existing model file")
    tr.add_argument("--features", nargs="+", default=["seed004"],
                    help="feature names, sets or patterns (default: seed004)")
    tr.add_argument("--features-mode", default="cycle", metavar="MODE",
                    help=FEATURES_MODE_HELP + " (default: cycle); the model applies them in "
                         "the same mode")
    tr.add_argument("--budget", type=int, default=30, help="evaluations of a tuned method")
    tr.add_argument("--decimate-s", type=float, default=30.0,
                    help="training samples every this many seconds (default 30)")
    tr.add_argument("--cutoff-s", type=float, default=512.0,
                    help="wavelet cutoff period of the drift separation (default 512 s)")
    tr.add_argument("--seed", type=int, default=0, help="random state of models and tuners")
    tr.add_argument("--n-jobs", type=int, default=-1, help="parallel tuner evaluations")
    tr.add_argument("-q", "--quiet", action="store_true",
                    help="no progress on standard error")
    tr.set_defaults(func=_cmd_train)

    co = sub.add_parser("compensate", help="subtract a trained compensator's drift from runs",
                        description="Predict each run's drift from its own thermometers with a "
                                    "trained model, subtract it from gyro_dph and write the "
                                    "compensated runs (gyro_uncompensated_dph and "
                                    "drift_model_dph are kept as extra columns).")
    _runs(co)
    co.add_argument("--model", required=True, help="model file written by nfs train")
    co.add_argument("--trust-pickle", action="store_true",
                    help="also load a joblib pickle written by an earlier nfs train (loading "
                         "a pickle runs any code it holds: only a file you trust)")
    co.add_argument("-o", "--output", required=True, help="output folder")
    co.add_argument("--features-mode", default=None, metavar="MODE",
                    help="check that the model was trained in this features mode (it is "
                         "always applied in its own)")
    co.add_argument("--overwrite", action="store_true",
                    help="write into a folder that holds another command's output or files "
                         "of unknown origin (files of the earlier output that are not "
                         "rewritten are removed)")
    co.set_defaults(func=_cmd_compensate)

    s = sub.add_parser("simulate", help="write measurement files for a scenario",
                       description="Simulate every run of a scenario and write each as "
                                   "nfs-measurement/1 files (NAME.csv + NAME.toml).")
    s.add_argument("scenario", help="scenario TOML file")
    s.add_argument("-o", "--output", required=True, help="output folder")
    s.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    s.add_argument("--repeats", type=int, default=None, help="override runs per temperature")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    s.add_argument("--trust-effects", action="store_true",
                    help="let the scenario's effects_files (Python files of your own "
                         "effects) run; read them first: a scenario file does not run code "
                         "otherwise")
    s.add_argument("--overwrite", action="store_true",
                    help="write into a folder that holds another command's output or files "
                         "of unknown origin (files of the earlier output that are not "
                         "rewritten are removed)")
    s.set_defaults(func=_cmd_simulate)

    n = sub.add_parser("northfind", help="north-find measured or simulated runs",
                       description="North-find runs in nfs-measurement/1 format (files or "
                                   "folders) and print heading and RMSE per run.")
    _runs(n)
    n.add_argument("--json", default=None, help="write per-cycle results as JSON")
    n.add_argument("--overwrite", action="store_true", help="replace an existing --json file")
    n.add_argument("--no-tilt", action="store_true", help="no tilt correction")
    n.add_argument("--heading-hint", type=float, default=None, metavar="DEG",
                   help="coarse heading of the axis at position 0 [deg] (e.g. a magnetic "
                        "compass) that picks the branch a 2-position schedule cannot decide")
    n.add_argument("--settle-s", type=float, default=0.0,
                   help="seconds skipped at the start of each dwell (default 0)")
    n.add_argument("--startup-end-s", type=float, default=3600.0,
                   help="start-up stage: cycles ending before this time (default 3600)")
    n.add_argument("--stable-start-s", type=float, default=5400.0,
                   help="stable stage: cycles starting after this time (default 5400)")
    n.set_defaults(func=_cmd_northfind)

    fi = sub.add_parser("fit", help="calibrate a model to measured runs",
                        description="Calibrate a model's free parameters to runs by bounded "
                                    "least squares: thermal parameters against the three "
                                    "thermometers, then drift and sensor coefficients against "
                                    "the gyro (and accelerometer) channels. Writes the fitted "
                                    "model as an instrument TOML with each value's error.")
    _runs_and_model(fi)
    fi.add_argument("-o", "--output", required=True, help="fitted model TOML to write")
    fi.add_argument("--overwrite", action="store_true", help="replace an existing -o file")
    fi.add_argument("--free", nargs="+", default=None,
                    help="free parameter paths or patterns (default: nfs.diagnose.default_free)")
    fi.add_argument("--stages", nargs="+", default=["thermal", "drift"],
                    choices=["thermal", "drift"],
                    help="what to fit: thermal (network against the thermometers), drift "
                         "(effect coefficients against the gyro), or both in that order "
                         "(default)")
    fi.add_argument("--decimate-s", type=float, default=10.0,
                    help="time step of the fit [s] (default 10)")
    fi.add_argument("--prior-scale", type=float, default=1.0,
                    help="multiply every prior width of nfs.diagnose.prior by this (default 1; "
                         "inf: no prior)")
    fi.add_argument("--no-prior", action="store_true",
                    help="plain least squares: no prior on the parameters, no soak anchor")
    fi.add_argument("--starts", type=int, default=1,
                    help="most starts of the thermal stage: the preset, then capacities and "
                         "conductances +-30 %% while the fit stays above the noise (default 1)")
    fi.add_argument("--no-refine", action="store_true",
                    help="keep the model's thermal structure even where it misses a "
                         "thermometer by more than 2x its noise floor (default: adopt the "
                         "generic alternatives that pay on held-out runs, in a chain)")
    fi.add_argument("--no-noise-fit", action="store_true",
                    help="keep the model's gyro noise instead of fitting it to the Allan "
                         "deviation of the drift residual")
    fi.add_argument("-q", "--quiet", action="store_true",
                    help="no progress on standard error")
    fi.set_defaults(func=_cmd_fit)

    cm = sub.add_parser("compare", help="a model beside measured runs, channel by channel",
                        description="Simulate the model with each run's own schedule, start "
                                    "temperature and heading, set it beside the measurement "
                                    "per channel, stage and position, and say where it fails; "
                                    "writes report.md, comparison.json and figures.")
    _runs_and_model(cm)
    cm.add_argument("-o", "--output", required=True, help="report folder")
    cm.add_argument("--json", default=None, help="also write the comparison JSON here")
    cm.add_argument("--seed", type=int, default=0, help="seed of the model's noise")
    cm.add_argument("--startup-end-s", type=float, default=3600.0,
                    help="start-up stage: cycles ending before this time [s] (default 3600)")
    cm.add_argument("--stable-start-s", type=float, default=5400.0,
                    help="stable stage: cycles starting after this time [s] (default 5400)")
    cm.add_argument("-q", "--quiet", action="store_true",
                    help="no progress on standard error")
    cm.add_argument("--overwrite", action="store_true",
                    help="replace an existing --json file, and write into a folder that holds "
                         "another command's output or files of unknown origin (files of the "
                         "earlier output that are not rewritten are removed)")
    cm.set_defaults(func=_cmd_compare)

    dg = sub.add_parser("diagnose", help="which physical effect the model is missing",
                        description="Try every registered effect the model lacks (on each of "
                                    "its possible targets), refit, and rank them by the drop "
                                    "of the leave-one-start-temperature-out residual (drift, "
                                    "or the thermometers for thermal effects); mark the "
                                    "significant ones (a test clustered by run, Holm over "
                                    "all candidates); report what stays unexplained. With "
                                    "--apply NAME[:TARGET], add that effect, refit and write "
                                    "the new model.")
    _runs_and_model(dg)
    dg.add_argument("--json", default=None, help="write the ranking as JSON")
    dg.add_argument("--apply", default=None, metavar="NAME[:TARGET]",
                    help="add this effect, refit and write the model to -o")
    dg.add_argument("-o", "--output", default=None, help="new model TOML (with --apply)")
    dg.add_argument("--overwrite", action="store_true",
                    help="replace an existing -o or --json file")
    dg.add_argument("--diagnosis", default=None, metavar="JSON",
                    help="with --apply: what an earlier nfs diagnose --json found on these "
                         "runs (default: diagnose them first); adding an effect it did not "
                         "find significant gives a warning")
    dg.add_argument("--top", type=int, default=10, help="rows of the printed ranking")
    dg.add_argument("--seed", type=int, default=0, help="seed of the run bootstrap")
    dg.add_argument("--alpha", type=float, default=0.05,
                    help="family-wise error rate of Holm's procedure over all scored "
                         "candidates (default 0.05)")
    dg.add_argument("--node-temperatures", choices=("smoothed", "model"), default="smoothed",
                    help="node temperatures the drift candidates are evaluated on: estimated "
                         "from the measured thermometers through the model's network "
                         "(smoothed, default) or the model's open-loop solution (model)")
    dg.add_argument("--no-structure", action="store_true",
                    help="skip setting the model's thermal structure against generic "
                         "alternatives (one more node, a free link, a moved thermometer)")
    dg.add_argument("-q", "--quiet", action="store_true",
                    help="no progress line on standard error")
    dg.set_defaults(func=_cmd_diagnose)

    pr = sub.add_parser("preset", help="print a built-in instrument or scenario preset (TOML)",
                        description="Print a built-in instrument or scenario preset, with its "
                                    "comments, to copy and edit; without a name, list the "
                                    "presets.")
    pr.add_argument("name", nargs="?", default=None,
                    help="preset to print (default: list the presets)")
    pr.set_defaults(func=_cmd_preset)

    ini = sub.add_parser("init", help="write a starter scenario and instrument into a folder",
                         description="Write DIR/scenario.toml (a built-in scenario preset, "
                                     "with its comments) and DIR/instrument.toml (the "
                                     "instrument preset it names), the scenario pointing at "
                                     "the instrument file: a start for your own experiment.")
    ini.add_argument("output", metavar="DIR", help="folder to write (made when missing)")
    ini.add_argument("--from", "--scenario", dest="source", default="startup_7temps",
                     metavar="NAME",
                     help="scenario or sweep preset to start from (default: startup_7temps; "
                          "nfs preset lists them); its instrument comes along, and both "
                          "are named after DIR")
    ini.add_argument("--overwrite", action="store_true",
                     help="write into a folder that holds other files")
    ini.set_defaults(func=_cmd_init)

    e = sub.add_parser("effects", help="list the registered physical effects",
                       description="List every registered physical effect (built-in and your own\n"
                                   "registered ones): name, kind (gyro, accelerometer, thermal, "
                                   "thermometer) and parameters.")
    e.set_defaults(func=_cmd_effects)

    sw = sub.add_parser("sweep", help="Monte Carlo sweep of a scenario over axes and seeds",
                        description="Run a sweep file (a base scenario, axes over scenario "
                                    "keys and instrument parameters, seeds, an optional "
                                    "compensation method and heading spec): every missing "
                                    "cell is simulated, north-found and stored under the hash "
                                    "of its inputs (a rerun computes only the missing cells), "
                                    "then DIR/results.csv (and results.parquet with pyarrow) "
                                    "and the summary figures are written.")
    sw.add_argument("sweep", help="sweep TOML file")
    sw.add_argument("-o", "--output", required=True, metavar="DIR",
                    help="the sweep's folder (cells/, results.csv, figures); reused by a rerun")
    sw.add_argument("--trust-effects", action="store_true",
                    help="let the scenario's effects_files (Python files of your own "
                         "effects) run; read them first: a scenario file does not run code "
                         "otherwise")
    sw.add_argument("--jobs", type=int, default=-1, metavar="N",
                    help="local worker processes (default -1: every core; 1: this process)")
    sw.add_argument("--dask-local", type=int, default=None, metavar="N",
                    help="start a Dask LocalCluster of N worker processes and run there "
                         "(needs the dask extra)")
    sw.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="run on an existing Dask cluster, e.g. tcp://host:8786 (needs the "
                         "dask extra, and nfs installed on the workers)")
    sw.add_argument("-q", "--quiet", action="store_true",
                    help="no progress bar or log lines on standard error")
    sw.set_defaults(func=_cmd_sweep)
    return p


#: Numeric options checked against the table of ranges (nfs.ranges) before any work, as
#: the same values are when a file gives them: option attribute -> the file's key.
_OPTION_RANGES = {"repeats": "repeats", "seed": "seed", "settle_s": "northfind.settle_s",
                  "startup_end_s": "northfind.startup_end_s",
                  "stable_start_s": "northfind.stable_start_s"}


def _check_options(args) -> None:
    """Every numeric option of ``_OPTION_RANGES`` the command has, against its range."""
    for attr, key in _OPTION_RANGES.items():
        value = getattr(args, attr, None)
        if value is not None:
            check(key, value, key=f"--{attr.replace('_', '-')}")


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``nfs`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    if getattr(args, "trust_effects", False):   # a scenario's effects_files may run
        from .config.scenario import TRUST_EFFECTS_ENV  # lazy: nfs --help stays fast
        os.environ[TRUST_EFFECTS_ENV] = "1"
    try:
        with one_line_warnings():             # an unusual input value: one line, then on
            _check_options(args)
            return args.func(args)
    except USER_ERRORS as exc:
        print(f"nfs: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        print("nfs: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
