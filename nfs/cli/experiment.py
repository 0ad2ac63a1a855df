"""``nfs simulate``, ``nfs northfind``, ``nfs preset``, ``nfs init``, ``nfs effects``,
``nfs sweep``: runs made, north-found, and the files to start from.

Each command imports the library inside its function (lazily), so that ``nfs --help`` and
a mistyped option answer without loading scikit-learn and matplotlib.
"""

from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path

from ..errors import NfsError
from .common import (Progress, circular_mean_deg, finish, fmt, gate, output_file,
                     output_folder, read_command_runs, recorded_arguments, say_ignored,
                     say_removed, with_overrides)

__all__ = ["cmd_simulate", "cmd_northfind", "cmd_preset", "cmd_init", "cmd_effects", "cmd_sweep"]


def cmd_simulate(args) -> int:
    from .. import load_scenario
    from ..studies.job_estimate import estimate_runs, run_samples
    from ..studies.runs_folder import check_runs_folder, simulate_to_folder
    scenario = with_overrides(load_scenario(args.scenario), args)
    say_ignored(scenario, "simulate")
    folder = check_runs_folder(scenario, args.output, overwrite=args.overwrite,
                         resume=True if args.resume else None)
    conds = scenario.conditions()
    done = {c.name for c in conds
            if f"{c.name}.csv" in folder.done and f"{c.name}.toml" in folder.done}
    gate(lambda: estimate_runs("nfs simulate", [scenario], write=True, skip=done),
         sum(run_samples([c for c in conds if c.name not in done])), args,
         fewer="or fewer runs: --repeats N")
    if folder.resuming and not args.quiet:
        print(f"nfs: resuming {args.output}: {len(done)} of {len(conds)} runs already "
              "written", file=sys.stderr)
    res = simulate_to_folder(scenario, folder, progress=Progress("simulating", args.quiet),
                             arguments=recorded_arguments(args))
    say_removed(folder)
    for p in res.runs:
        print(p)
    return 0


def cmd_northfind(args) -> int:
    from ..io.atomic import atomic_write_text
    from .. import north_find
    from ..northfind import heading_rmse
    from ..scoring.intervals import json_number
    if args.heading_hint is not None and not math.isfinite(args.heading_hint):
        raise NfsError(f"--heading-hint: {args.heading_hint} is not a finite angle in degrees")
    output_file(args.json, "--json", args.overwrite)
    runs = read_command_runs(args)
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
                     circular_mean_deg(res.heading_deg),
                     st.startup_deg if st else math.nan, st.stable_deg if st else math.nan))
        out["runs"].append({
            "name": run.name, "start_temperature_c": run.meta.start_temperature_c,
            "latitude_deg": run.meta.latitude_deg, "true_heading_deg": res.true_heading_deg,
            "ambiguous": bool(res.ambiguous),
            "startup_rmse_deg": json_number(st.startup_deg) if st else None,
            "stable_rmse_deg": json_number(st.stable_deg) if st else None,
            "cycles": [{"t_start_s": json_number(a), "t_end_s": json_number(b),
                        "heading_deg": json_number(h), "error_deg": json_number(e),
                        "bias_dph": json_number(bb)}
                       for a, b, h, e, bb in zip(res.t_start_s, res.t_end_s, res.heading_deg,
                                                 res.error_deg, res.bias_dph)],
        })
    print("| run | T0 [C] | cycles | mean heading [deg] | start-up RMSE [deg] "
          "| stable RMSE [deg] |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, t0, n, amb, h, su, sb in rows:
        if amb:
            print(f"| {name} | {t0:g} | {n} | ambiguous | - | - |")
        else:
            print(f"| {name} | {t0:g} | {n} | {h:.4f} | {fmt(su)} | {fmt(sb)} |")
    ambiguous = [r[0] for r in rows if r[3]]
    if ambiguous:
        print(f"ambiguous: {', '.join(ambiguous)}: a schedule whose positions lie on one "
              "line (e.g. 0 and 180 deg) cannot tell the heading from its mirror image about "
              "that line; give --heading-hint DEG (a coarse heading, e.g. from a magnetic "
              "compass) to pick the branch (the JSON holds one branch, marked ambiguous)")
    if args.json:
        from ..io.provenance import output_provenance
        out["provenance"] = output_provenance(runs=runs)
        atomic_write_text(args.json, json.dumps(out, indent=1) + "\n")
    return 0


def cmd_preset(args) -> int:
    from ..instrument import preset_names, preset_path
    from ..config.presets import (scenario_preset_names, scenario_preset_path,
                                  sweep_preset_names, sweep_preset_path)
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


def cmd_init(args) -> int:
    import re
    from ..instrument import preset_path
    from ..io.atomic import atomic_write_files
    from .. import load_scenario, load_sweep
    from ..config.presets import (scenario_preset_names, scenario_preset_path,
                                  sweep_preset_names, sweep_preset_path)
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
    folder = output_folder(args, "init")
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_files(files)
    load_scenario(out / "scenario.toml")  # what was written loads (a check of the package)
    if out / "sweep.toml" in files:
        load_sweep(out / "sweep.toml")
    finish(folder, args, {"preset": name, "instrument_preset": inst_preset})
    run = (f"nfs sweep {out / 'sweep.toml'} -o {out / 'sweep_results'}" if out / "sweep.toml"
           in files else f"nfs table {out / 'scenario.toml'} -o {out / 'results'}")
    print("wrote " + ", ".join(str(p) for p in files) + f"; run: {run}")
    return 0


def cmd_effects(args) -> int:
    from ..effects import available_effects, get_effect
    for name in available_effects():
        spec = get_effect(name)
        params = ", ".join(f"{p.name} [{p.unit}]" if p.unit else p.name
                           for p in spec.parameters)
        print(f"{name} ({spec.kind}): {spec.summary}")
        if params:
            print(f"    parameters: {params}")
    return 0


def cmd_sweep(args) -> int:
    # a fully stored sweep imports the definition, the store and the table only: the
    # simulator, the executors and matplotlib are imported when a cell or a figure is missing
    from ..sweep.definition import load_sweep
    from ..sweep.plan import plan_sweep, stored_sweep
    if args.dask_local is not None and args.scheduler is not None:
        raise NfsError("give --dask-local N or --scheduler ADDRESS, not both")
    spec = load_sweep(args.sweep)                   # the whole sweep checked before any work
    log = None if args.quiet else (lambda msg: print(f"sweep: {msg}", file=sys.stderr))
    _gate_sweep(spec, args)
    plan = plan_sweep(spec, args.output)            # the store prepared, its cells listed once
    res = stored_sweep(plan)
    if res is not None:
        if log is not None:
            log(f"{spec.n_cells} cells, every one stored, figures current: nothing to compute")
    else:
        from ..sweep.executors import DaskExecutor, LocalExecutor
        from ..sweep.run import run_sweep
        if args.dask_local is not None or args.scheduler is not None:
            executor = DaskExecutor(workers=args.dask_local, address=args.scheduler)
        else:
            executor = LocalExecutor(args.jobs)
        try:
            res = run_sweep(spec, args.output, executor=executor, quiet=args.quiet, log=log,
                            plan=plan)
        finally:
            executor.close()
    print(f"{res.n_cells} cells ({res.n_computed} computed, {res.n_cells - res.n_computed} "
          f"from the store), {res.n_rows} rows")
    for p in res.paths:
        print(p)
    return 0


def _gate_sweep(spec, args) -> None:
    """The sweep's missing cells estimated before the folder is prepared (:func:`gate`)."""
    from ..sweep.estimate import estimate_sweep, missing_cells, sweep_samples
    n = missing_cells(spec, args.output)
    if args.dask_local is not None:
        workers = args.dask_local
    elif args.scheduler is not None:
        workers = 1                     # a cluster's size is not known here: one worker
    else:
        workers = (os.cpu_count() or 1) if args.jobs == -1 else args.jobs
    gate(lambda: estimate_sweep(spec, n, workers), sweep_samples(spec, n), args, rows=False,
         fewer="or fewer cells: fewer seeds or axis values")
