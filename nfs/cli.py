"""The ``nfs`` command: thin; parse, call the library, turn NfsError into one line + exit 2.

    nfs table [SCENARIO] [-o DIR] [--json FILE]      heading-RMSE table by start temperature
    nfs simulate SCENARIO -o DIR                     measurement files, one run per T0
    nfs northfind DATA... [--json FILE]              north-find measured or simulated runs
    nfs train DATA... --method M -o MODEL            train a drift compensator
    nfs compensate DATA... --model MODEL -o DIR      apply it
    nfs fit DATA... [--model M] -o FITTED.toml       calibrate a model to measured runs
    nfs compare DATA... --model M -o DIR             the model beside the runs
    nfs diagnose DATA... --model M [--apply NAME]    the missing effect, ranked
    nfs preset [NAME]                                print a built-in instrument preset
    nfs effects                                      list the registered physical effects
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

from .errors import NfsError

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
    from .compensate.modes import check_features_mode
    from .compensate.study import errors_by_temperature
    from .experiment import run_scenario, uncompensated_table
    from .io.scenario import load_scenario
    from .report import write_table
    if args.features_mode is not None:
        check_features_mode(args.features_mode, "--features-mode")
    scenario = _with_overrides(load_scenario(args.scenario), args)
    title = f"{scenario.name}: heading RMSE by start temperature"
    progress = Progress("", args.quiet)
    if args.no_compensation:
        progress.what = "simulating"
        res = run_scenario(scenario, progress=progress)
        table = uncompensated_table(res).with_intervals(
            {"before": errors_by_temperature(res), "stable": errors_by_temperature(res, stage=1)},
            random_state=scenario.seed)
        paths = write_table(table, args.output, json_path=args.json, title=title)
    else:
        import dataclasses
        from .compensate.study import CompensationSettings, run_study
        from .report.compensation import write_study
        settings = scenario.compensation or CompensationSettings()
        if args.budget is not None:
            if args.budget < 1:
                raise NfsError(f"--budget must be >= 1, got {args.budget}")
            settings = dataclasses.replace(settings, budget=args.budget)
        if args.repeats is not None:
            settings = dataclasses.replace(settings, test_repeats=args.repeats)
        if args.n_jobs is not None:
            settings = dataclasses.replace(settings, n_jobs=args.n_jobs)
        if args.tuner_seeds is not None:
            if args.tuner_seeds < 1:
                raise NfsError(f"--tuner-seeds must be >= 1, got {args.tuner_seeds}")
            settings = dataclasses.replace(settings, tuner_seeds=args.tuner_seeds)
        if args.features_mode is not None:
            settings = dataclasses.replace(settings, features_mode=args.features_mode)
        study = run_study(scenario, settings, progress=progress)
        table = study.heading_table()
        paths = write_study(study, args.output, json_path=args.json, title=title)
    print(table.to_markdown(), end="")
    if not args.quiet:
        print("\nwrote " + ", ".join(str(p) for p in paths), file=sys.stderr)
    return 0


def _cmd_train(args) -> int:
    from .compensate import get_method, resolve_features, train_compensator
    from .compensate.modes import check_features_mode
    from .io.measurement import read_runs
    get_method(args.method)                  # a bad name fails before any work
    resolve_features(args.features, ["aux_*"])
    check_features_mode(args.features_mode, "--features-mode")
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
    from .compensate import load_compensator
    from .compensate.modes import check_features_mode
    from .io.measurement import read_runs, write_run
    comp = load_compensator(args.model)
    if args.features_mode is not None and \
            check_features_mode(args.features_mode, "--features-mode") != comp.features_mode:
        raise NfsError(f"--features-mode {args.features_mode}: the model was trained in "
                       f"{comp.features_mode} mode, and is applied in the mode it was "
                       "trained in")
    runs = read_runs(args.data)
    # Every run is compensated before anything is written: a run that lacks an input
    # channel stops the command with nothing half-written.
    out = [comp.compensate(r) for r in runs]
    for r in out:
        print(write_run(r, args.output))
    return 0


def _with_overrides(scenario, args):
    import dataclasses
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
    from .io.scenario import load_scenario
    scenario = _with_overrides(load_scenario(args.scenario), args)
    out = Path(args.output)
    conds = scenario.conditions()
    progress = Progress("simulating", args.quiet)
    written = []
    for i, cond in enumerate(conds):
        progress(i, len(conds), cond.name)
        written.append(write_run(simulate_run(scenario.instrument, cond).run, out))
    progress(len(conds), len(conds), "done")
    for p in written:
        print(p)
    return 0


def _cmd_northfind(args) -> int:
    from .io.atomic import atomic_write_text
    from .io.measurement import read_runs
    from .northfind import heading_rmse, north_find
    if args.heading_hint is not None and not math.isfinite(args.heading_hint):
        raise NfsError(f"--heading-hint: {args.heading_hint} is not a finite angle in degrees")
    runs = read_runs(args.data)
    rows = []
    out = {"runs": []}
    for run in runs:
        res = north_find(run, tilt_correction=not args.no_tilt, settle_s=args.settle_s,
                         heading_hint_deg=args.heading_hint)
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
    from .diagnose import fit_model, write_fitted_model
    from .io.measurement import read_runs
    inst = _load_model(args.model)
    runs = read_runs(args.data)
    if not args.quiet:
        print(f"fitting {inst.name} to {len(runs)} run(s)...", file=sys.stderr)
    res = fit_model(inst, runs, free=args.free, stages=tuple(args.stages),
                    decimate_s=args.decimate_s,
                    prior=None if args.no_prior else "default", prior_scale=args.prior_scale,
                    n_starts=args.starts, fit_noise=not args.no_noise_fit)
    write_fitted_model(res, args.output)
    print(res.summary())
    print(f"wrote {args.output}")
    return 0


def _cmd_compare(args) -> int:
    from .diagnose import compare, write_report
    from .io.atomic import atomic_write_text
    from .io.measurement import read_runs
    inst = _load_model(args.model)
    runs = read_runs(args.data)
    if not args.quiet:
        print(f"simulating {inst.name} beside {len(runs)} run(s)...", file=sys.stderr)
    c = compare(inst, runs, seed=args.seed, startup_end_s=args.startup_end_s,
                stable_start_s=args.stable_start_s)
    paths = write_report(c, args.output)
    for line in c.sentences():
        print(f"- {line}")
    if args.json:
        atomic_write_text(args.json, json.dumps(c.to_dict(), indent=1) + "\n")
    if not args.quiet:
        print("wrote " + ", ".join(str(p) for p in paths[:3]) + " ...", file=sys.stderr)
    return 0


def _cmd_diagnose(args) -> int:
    from .diagnose import apply_candidate, diagnose
    from .io.atomic import atomic_write_text
    from .io.measurement import read_runs
    inst = _load_model(args.model)
    runs = read_runs(args.data)
    if args.apply:
        name, _, target = args.apply.partition(":")
        if args.output is None:
            raise NfsError("--apply needs -o FILE for the new model")
        new, fit, report = apply_candidate(inst, runs, name, target or None)
        from .diagnose import write_fitted_model
        write_fitted_model(fit, args.output)
        print(f"added {args.apply}; refitted:")
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
                 check_structure=not args.no_structure)
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
        atomic_write_text(args.json, json.dumps(d.to_dict(), indent=1, default=_j) + "\n")
    return 0


def _cmd_preset(args) -> int:
    from .instrument import preset_names, preset_path
    if args.name is None:
        print("\n".join(preset_names()))
        return 0
    sys.stdout.write(preset_path(args.name).read_text(encoding="utf-8"))
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
                   help="override the runs per start temperature (Monte Carlo)")
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
    t.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    t.set_defaults(func=_cmd_table)

    tr = sub.add_parser("train", help="train a drift compensator on measured runs",
                        description="Train a compensator (features of the three thermometers "
                                    "-> wavelet-separated gyro drift) on runs with a known "
                                    "heading, and save it with its feature list and versions.")
    _runs(tr)
    tr.add_argument("--method", default="ssa-svr",
                    help="ls, stepwise, bp, rbf, lssvm, ir-lssvm, svr-grid, pso-svr, gwo-svr, "
                         "ssa-svr (default), hho-rvr, tpe-svr")
    tr.add_argument("-o", "--output", required=True, help="model file to write (.joblib)")
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
    co.add_argument("-o", "--output", required=True, help="output folder")
    co.add_argument("--features-mode", default=None, metavar="MODE",
                    help="check that the model was trained in this features mode (it is "
                         "always applied in its own)")
    co.set_defaults(func=_cmd_compensate)

    s = sub.add_parser("simulate", help="write measurement files for a scenario",
                       description="Simulate every run of a scenario and write each as "
                                   "nfs-measurement/1 files (NAME.csv + NAME.toml).")
    s.add_argument("scenario", help="scenario TOML file")
    s.add_argument("-o", "--output", required=True, help="output folder")
    s.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    s.add_argument("--repeats", type=int, default=None, help="override runs per temperature")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    s.set_defaults(func=_cmd_simulate)

    n = sub.add_parser("northfind", help="north-find measured or simulated runs",
                       description="North-find runs in nfs-measurement/1 format (files or "
                                   "folders) and print heading and RMSE per run.")
    _runs(n)
    n.add_argument("--json", default=None, help="write per-cycle results as JSON")
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
    fi.add_argument("--free", nargs="+", default=None,
                    help="free parameter paths or patterns (default: see nfs.diagnose.fit)")
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
    fi.add_argument("--starts", type=int, default=3,
                    help="most starts of the thermal stage: the preset, then capacities and "
                         "conductances +-30 %% while the fit stays above the noise (default 3)")
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

    pr = sub.add_parser("preset", help="print a built-in instrument preset (TOML)",
                        description="Print a built-in instrument preset to copy and edit; "
                                    "without a name, list the presets.")
    pr.add_argument("name", nargs="?", default=None,
                    help="preset to print (default: list the presets)")
    pr.set_defaults(func=_cmd_preset)

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


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``nfs`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except NfsError as exc:
        print(f"nfs: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        print("nfs: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
