"""The ``nfs`` command line: every command, its arguments and options (``nfs --help``), and
the numeric options checked against the table of ranges."""

from __future__ import annotations

import argparse

from ..ranges import check
from .common import FEATURES_MODE_HELP
from .compensation import cmd_compensate, cmd_table, cmd_train
from .experiment import (cmd_effects, cmd_init, cmd_northfind, cmd_preset, cmd_simulate,
                         cmd_sweep)
from .design import cmd_design
from .importing import add_import_parser
from .measured import cmd_compare, cmd_diagnose, cmd_fit
from .noise import add_allan_command

__all__ = ["build_parser", "check_options"]


def _runs_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", nargs="+", help="NAME.csv files, NAME.toml files or folders")
    p.add_argument("--partial", action="store_true",
                   help="read a run that is not whole (shorter than its duration_s, or its "
                        "last line cut while written) instead of refusing it; every output "
                        "says so")
    p.add_argument("--allow-nan", action="store_true",
                   help="read missing samples (empty fields, nan) as missing instead of "
                        "refusing them; every output names their columns and rows")


def _trust_effects_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--trust-effects", action="store_true",
                   help="let the scenario's effects_files (Python files of your own "
                        "effects) run; read them first: a scenario file does not run code "
                        "otherwise")


def _yes_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--yes", action="store_true",
                   help="run a job estimated past 10 min, 2 GB written or 4 GB of memory "
                        "(nfs.studies.job_estimate.JOB_LIMITS) instead of refusing it")


def _runs_and_model_arguments(p: argparse.ArgumentParser) -> None:
    _runs_argument(p)
    p.add_argument("--model", default="default",
                   help="instrument preset name or TOML file (default: default)")
    p.add_argument("--start", choices=("estimated", "soaked"), default="estimated",
                   help="each run's node temperatures at power-on: estimated from its "
                        "thermometers with the model (an unfinished soak, a unit off its "
                        "air; default), or soaked: every node at the run's T0")


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
    _yes_option(t)
    _trust_effects_option(t)
    t.add_argument("--overwrite", action="store_true",
                   help="replace an existing --json file, and write into a folder that holds "
                        "another command's output or files of unknown origin (files of the "
                        "earlier output that are not rewritten are removed)")
    t.set_defaults(func=cmd_table)

    tr = sub.add_parser("train", help="train a drift compensator on measured runs",
                        description="Train a compensator (features of the three thermometers "
                                    "-> wavelet-separated gyro drift) on runs with a known "
                                    "heading, and save it with its feature list and versions.")
    _runs_argument(tr)
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
    tr.set_defaults(func=cmd_train)

    co = sub.add_parser("compensate", help="subtract a trained compensator's drift from runs",
                        description="Predict each run's drift from its own thermometers with a "
                                    "trained model, subtract it from gyro_dph and write the "
                                    "compensated runs (gyro_uncompensated_dph and "
                                    "drift_model_dph are kept as extra columns).")
    _runs_argument(co)
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
    co.set_defaults(func=cmd_compensate)

    s = sub.add_parser("simulate", help="write measurement files for a scenario",
                       description="Simulate every run of a scenario and write each as "
                                   "nfs-measurement/1 files (NAME.csv + NAME.toml).")
    s.add_argument("scenario", help="scenario TOML file")
    s.add_argument("-o", "--output", required=True, help="output folder")
    s.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    s.add_argument("--repeats", type=int, default=None, help="override runs per temperature")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    _trust_effects_option(s)
    s.add_argument("--overwrite", action="store_true",
                    help="write into a folder that holds another command's output or files "
                         "of unknown origin (files of the earlier output that are not "
                         "rewritten are removed)")
    s.add_argument("--resume", action="store_true",
                   help="keep the runs the folder holds of this scenario and write the "
                        "rest (automatic for a folder an interrupted nfs simulate of the "
                        "same scenario left)")
    _yes_option(s)
    s.set_defaults(func=cmd_simulate)

    n = sub.add_parser("northfind", help="north-find measured or simulated runs",
                       description="North-find runs in nfs-measurement/1 format (files or "
                                   "folders) and print heading and RMSE per run.")
    _runs_argument(n)
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
    n.set_defaults(func=cmd_northfind)

    fi = sub.add_parser("fit", help="calibrate a model to measured runs",
                        description="Calibrate a model's free parameters to runs by bounded "
                                    "least squares: thermal parameters against the three "
                                    "thermometers, then drift and sensor coefficients against "
                                    "the gyro (and accelerometer) channels. Writes the fitted "
                                    "model as an instrument TOML with each value's error.")
    _runs_and_model_arguments(fi)
    fi.add_argument("-o", "--output", required=True, help="fitted model TOML to write")
    fi.add_argument("--overwrite", action="store_true", help="replace an existing -o file")
    fi.add_argument("--free", nargs="+", default=None,
                    help="free parameter paths or patterns (default: nfs.fit.default_free)")
    fi.add_argument("--stages", nargs="+", default=["thermal", "drift"],
                    choices=["thermal", "drift"],
                    help="what to fit: thermal (network against the thermometers), drift "
                         "(effect coefficients against the gyro), or both in that order "
                         "(default)")
    fi.add_argument("--decimate-s", type=float, default=10.0,
                    help="time step of the fit [s] (default 10)")
    fi.add_argument("--prior-scale", type=float, default=1.0,
                    help="multiply every prior width of nfs.fit.prior by this (default 1; "
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
    fi.set_defaults(func=cmd_fit)

    cm = sub.add_parser("compare", help="a model beside measured runs, channel by channel",
                        description="Simulate the model with each run's own schedule, start "
                                    "temperature and heading, set it beside the measurement "
                                    "per channel, stage and position, and say where it fails; "
                                    "writes report.md, comparison.json and figures.")
    _runs_and_model_arguments(cm)
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
    cm.set_defaults(func=cmd_compare)
    add_allan_command(sub)

    dg = sub.add_parser("diagnose", help="which physical effect the model is missing",
                        description="Try every registered effect the model lacks (on each of "
                                    "its possible targets), refit, and rank them by the drop "
                                    "of the leave-one-start-temperature-out residual (drift, "
                                    "or the thermometers for thermal effects); mark the "
                                    "significant ones (a test clustered by run, Holm over "
                                    "all candidates); report what stays unexplained. With "
                                    "--apply NAME[:TARGET], add that effect, refit and write "
                                    "the new model.")
    _runs_and_model_arguments(dg)
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
    dg.add_argument("--rivals", nargs="+", default=None, metavar="RIVAL",
                    help="put these explanations, and the model as it is, to the runs (the "
                         "rivals an nfs design was made for, after its run was added): "
                         "'model', EFFECT[:TARGET], 'a rate term on every node' or a "
                         "structural alternative's name")
    dg.add_argument("--decide", action="store_true",
                    help="on a tie, fit the tied explanations and the model as it is and "
                         "put them to the runs (nfs.rivals.decide: a likelihood ratio of e^2 "
                         "after the price of the numbers a rival adds, and Vuong's Z 1.645 "
                         "with the model error along the runs counted); its rates on units "
                         "the model does not describe: docs/design.md, Limits")
    dg.add_argument("--no-structure", action="store_true",
                    help="skip setting the model's thermal structure against generic "
                         "alternatives (one more node, a free link, a moved thermometer)")
    dg.add_argument("-q", "--quiet", action="store_true",
                    help="no progress line on standard error")
    dg.set_defaults(func=cmd_diagnose)

    ds = sub.add_parser("design", help="the run that would tell rival explanations apart",
                        description="Fit each rival explanation (a diagnosis's tie, or named "
                                    "with --rivals) to the runs, then search start "
                                    "temperatures, power cycles, chamber ramps and run "
                                    "lengths for the cheapest run (chamber hours) whose "
                                    "predictions under the rivals stand --margin noise "
                                    "standard deviations apart. Writes DIR/scenario.toml "
                                    "(the run, for nfs simulate and nfs table), "
                                    "DIR/report.md, DIR/design.png and DIR/design.json.")
    _runs_and_model_arguments(ds)
    ds.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    ds.add_argument("--diagnosis", default=None, metavar="JSON",
                    help="what nfs diagnose --json found on these runs: its tie gives the "
                         "rivals")
    ds.add_argument("--rivals", nargs="+", default=None, metavar="RIVAL",
                    help="the rivals instead: 'model', EFFECT or EFFECT:TARGET, 'a rate term "
                         "on every node', or a structural alternative's name")
    ds.add_argument("--margin", type=float, default=3.0,
                    help="separation every pair must reach, in noise standard deviations "
                         "(default 3)")
    ds.add_argument("--draws", type=int, default=8,
                    help="parameter draws per rival (its fit's uncertainty; default 8)")
    ds.add_argument("--start-temperatures", type=float, nargs="+", default=None,
                    metavar="C", help="start temperatures to try (default: the coldest, "
                                      "middle and hottest of the runs)")
    ds.add_argument("--soak-h", type=float, default=3.0,
                    help="chamber hours of the soak before the run (default 3)")
    ds.add_argument("--max-hours", type=float, default=None,
                    help="longest chamber time to consider, soak included (default: soak + 4 h)")
    ds.add_argument("--seed", type=int, default=0, help="seed of the parameter draws")
    ds.add_argument("--overwrite", action="store_true",
                    help="write into a folder that holds another command's output")
    ds.add_argument("-q", "--quiet", action="store_true", help="no progress on standard error")
    ds.set_defaults(func=cmd_design)

    pr = sub.add_parser("preset", help="print a built-in instrument or scenario preset (TOML)",
                        description="Print a built-in instrument or scenario preset, with its "
                                    "comments, to copy and edit; without a name, list the "
                                    "presets.")
    pr.add_argument("name", nargs="?", default=None,
                    help="preset to print (default: list the presets)")
    pr.set_defaults(func=cmd_preset)

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
    ini.set_defaults(func=cmd_init)

    e = sub.add_parser("effects", help="list the registered physical effects",
                       description="List every registered physical effect (built-in and your own\n"
                                   "registered ones): name, kind (gyro, accelerometer, thermal, "
                                   "thermometer) and parameters.")
    e.set_defaults(func=cmd_effects)

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
    _trust_effects_option(sw)
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
    _yes_option(sw)
    sw.set_defaults(func=cmd_sweep)
    add_import_parser(sub)
    return p


#: Numeric options checked against the table of ranges (nfs.ranges) before any work, as
#: the same values are when a file gives them: option attribute -> the file's key.
_OPTION_RANGES = {"repeats": "repeats", "seed": "seed", "settle_s": "northfind.settle_s",
                  "startup_end_s": "northfind.startup_end_s",
                  "stable_start_s": "northfind.stable_start_s", "margin": "design.margin",
                  "draws": "design.draws", "soak_h": "design.soak_h",
                  "max_hours": "design.max_hours"}


def check_options(args) -> None:
    """Every numeric option of ``_OPTION_RANGES`` the command has, against its range."""
    for attr, key in _OPTION_RANGES.items():
        value = getattr(args, attr, None)
        if value is not None:
            check(key, value, key=f"--{attr.replace('_', '-')}")
    for t in getattr(args, "start_temperatures", None) or ():
        check("design.start_temperatures", t, key="--start-temperatures")
