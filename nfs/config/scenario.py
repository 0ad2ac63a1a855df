"""Scenario files: a start-up experiment described in TOML.

A scenario names an instrument (a built-in preset or an instrument TOML file), the start
temperatures, the schedule and the north-finding settings; ``[[effects]]`` in the scenario,
when present, replace the instrument's effect list, ``[[added_effects]]`` are added to it and
``[[aux]]`` channels (the instrument file's format) are added to the instrument's.  ``units``
simulated units make the
start-ups, and ``[variability]`` says how start-ups and units differ
(:mod:`nfs.variability`; no table: every start-up soaked exactly at T0, every unit the
nominal instrument).  Every key is checked: an unknown key is an error that names it and
lists the allowed ones.  See ``scenarios/startup_7temps.toml``.

Inheritance.  A scenario file gives only what differs from the built-in default scenario
(:func:`default_scenario_path`), or from another scenario file it names as
``base = "path.toml"`` (relative to the file; the base may name its own base, and a chain
that loops back is an error).  Every key it leaves out comes from there, table by table
(a key under ``[compensation]`` replaces that key only); lists (``program``, ``[[effects]]``,
``start_temperatures_c``) are replaced whole.  Not inherited: ``name`` (the file's stem
unless written) and ``description``; and from the built-in default, its ``[variability]``
table (a scenario without the table is the world without scatter, as always: write
``[variability]`` to get the default's realistic scatter), when the scenario has a chamber
program its ``duration_s``, and when it sets ``units`` the default's split of its one unit
(``compensation.train_units``, ``test_units``).  Paths in a base (``instrument``,
``effects_files``) stay
relative to the base.  The base is checked on its own first, so an error names the file that
holds the bad value.

Chamber.  ``[chamber]`` holds the chamber at T0 with an optional ripple, or runs a
``program`` of holds, ramps, steps and repeated cycles from each start temperature T0, with
the unit powered on at the program's start or at a ``{ power_on = true }`` marker after an
unpowered soak (:mod:`nfs.chamber`).  A run lasts as long as its program after power-on
unless ``duration_s`` is written (in the file or a base): then it is cut there, or the chamber
holds the program's last temperature until then.  Start and chamber temperatures outside
-70 .. +150 C are refused (a value such as 293.15 is kelvin).

Ranges.  Every value is checked against its range in :mod:`nfs.ranges` before anything runs:
an impossible value is refused naming the file and the key (with the unit it was likely
written in: a dwell of 2.5 s, minutes?), an unusual one loads with one warning line.  So are
what a run needs as a whole: distinct positions that determine the heading, samples in every
dwell, a start-up stage that holds a cycle, runs of at most
:data:`nfs.ranges.MAX_SAMPLES_PER_RUN` samples (a program's soak included), a wavelet cutoff
the shortest run can be separated at, distinct start temperatures.
"""

from __future__ import annotations

import copy
import math
import os
from pathlib import Path
from typing import Any

from ..chamber import check_temperature, parse_program
from ..compensate.catalog import lookup_method
from ..constants import POSITION_TOL_DEG
from ..denoise.levels import (DEFAULT_WAVELET, FILTER_LENGTHS, check_edge_fit, check_level,
                              level_for_cutoff)
from ..effects import check_geometry, load_effects_file
from ..errors import EffectError, NfsError, ScenarioError
from ..instrument import (Instrument, check_effect_targets, check_heating, load_instrument,
                          parse_aux, parse_effects)
from ..io.tomlio import (boolean, check_keys, integer, load_toml, number, number_list, string,
                         table)
from ..ranges import check_tree, deferred_warnings, find, warn_unusual
from ..scenario import ChamberProfile, NorthFindSettings, Scenario
from ..sensors import ORDERS, Schedule
from .presets import default_scenario_path, scenario_file
from .sections import (COMPENSATION_KEYS, VARIABILITY_TABLE_KEYS, compensation_table,
                       variability_table)

__all__ = ["load_scenario", "OVERRIDE_KEYS", "TRUST_EFFECTS_ENV"]

_TOP = ("name", "description", "base", "instrument", "seed", "start_temperatures_c", "repeats",
        "duration_s", "sample_rate_hz", "latitude_deg", "true_heading_deg", "effects_files",
        "effects", "added_effects", "aux", "schedule", "northfind", "chamber", "compensation", "units",
        "variability")
_SCHEDULE = ("positions_deg", "order", "dwell_s", "move_s")
_NORTHFIND = ("startup_end_s", "stable_start_s", "tilt_correction", "settle_s", "spec_deg")
_CHAMBER = ("ripple_c", "ripple_period_s", "program")

#: The dotted scenario keys :func:`load_scenario` may override (every value key of the file
#: but its name, description, seed and effect lists): what a sweep can put on an axis.
OVERRIDE_KEYS: tuple[str, ...] = (
    "instrument", "start_temperatures_c", "repeats", "duration_s", "sample_rate_hz",
    "latitude_deg", "true_heading_deg", "units",
    *(f"schedule.{k}" for k in _SCHEDULE), *(f"northfind.{k}" for k in _NORTHFIND),
    *(f"chamber.{k}" for k in _CHAMBER),
    *(f"variability.{k}" for k in VARIABILITY_TABLE_KEYS if k != "parameters"),
    *(f"compensation.{k}" for k in COMPENSATION_KEYS))


_NOT_INHERITED = ("name", "description")


def _merged(base: dict, over: dict) -> dict:
    """``base`` with ``over`` written on top, table by table (lists replaced whole)."""
    out = dict(base)
    for k, v in over.items():
        out[k] = _merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k),
                                                                            dict) else v
    return out


def _anchored(d: dict, folder: Path) -> dict:
    """``d`` with its relative paths (a path-like ``instrument``, ``effects_files``) made
    absolute from ``folder``, so that they keep their meaning in a file that inherits them."""
    d = dict(d)
    inst = d.get("instrument")
    if isinstance(inst, str) and (inst.endswith(".toml") or "/" in inst or "\\" in inst) \
            and not Path(inst).is_absolute():
        d["instrument"] = str(folder / inst)
    files = d.get("effects_files")
    if isinstance(files, list):
        d["effects_files"] = [str(folder / x) if isinstance(x, str) and not
                              Path(x).is_absolute() else x for x in files]
    return d


def _inherited(path: Path, d: dict, chain: tuple[Path, ...]) -> tuple[dict, dict]:
    """(the file's keys over its base's, as written; the same over the built-in default).

    The base, if any, is loaded and checked on its own first (its errors name it)."""
    here = dict(d)
    ref = here.pop("base", None)
    if ref is not None:
        if not isinstance(ref, str) or not ref:
            raise ScenarioError(f"must be the path of a scenario file, got {ref!r}",
                                file=path, key="base")
        bpath = Path(ref) if Path(ref).is_absolute() else path.parent / ref
        if not bpath.is_file():
            raise ScenarioError(f"base scenario {bpath} not found (the path is relative to "
                                f"{path.parent})", file=path, key="base")
        key = bpath.resolve()
        if key in chain:
            loop = " -> ".join(str(p) for p in (*chain, key))
            raise ScenarioError(f"the bases loop back: {loop}", file=path, key="base")
        written = _load(bpath, None, (*chain, key))[1]        # checked on its own
        written = {k: v for k, v in _anchored(written, bpath.parent).items()
                   if k not in _NOT_INHERITED}
        here = _merged(written, here)
    default = {} if path.resolve() == default_scenario_path().resolve() else \
        {k: v for k, v in load_toml(default_scenario_path()).items()
         if k not in (*_NOT_INHERITED, "variability")}
    chamber = here.get("chamber")
    if isinstance(chamber, dict) and "program" in chamber and "duration_s" not in here:
        default.pop("duration_s", None)
    if "units" in here and isinstance(default.get("compensation"), dict):
        default["compensation"] = {k: v for k, v in default["compensation"].items()
                                   if k not in ("train_units", "test_units")}
    return here, _merged(default, here)


def _check_geometry(inst: Instrument, schedule: Schedule, file, own_effects: bool) -> None:
    """The geometry effects against the schedule and the turntable (one offset of
    indexing_error per position, one platform tilt), before any run is simulated."""
    for i, e in enumerate(inst.effects):
        try:
            check_geometry([e], schedule.positions_deg, inst.turntable.tilt_north_deg,
                           inst.turntable.tilt_east_deg)
        except EffectError as exc:
            where = f"effects[{i}]" if own_effects else f"instrument (effects[{i}])"
            raise ScenarioError(str(exc), file=file, key=where) from None



def _check_schedule(schedule: Schedule, settings: NorthFindSettings, fs: float, file) -> None:
    """What a north-finding cycle needs, before anything runs: distinct positions that
    determine the heading (three or more, or two 180 deg apart), samples in every dwell
    after the settling skip, and a cycle that ends inside the start-up stage."""
    pos = schedule.positions_deg
    for i, a in enumerate(pos):
        for j in range(i):
            if abs(math.remainder(a - pos[j], 360.0)) <= POSITION_TOL_DEG:
                raise ScenarioError(
                    f"positions {j} and {i} ({pos[j]:g} and {a:g} deg) are the same "
                    "position (modulo 360 deg); each position is listed once (order = "
                    "\"forward-reverse\" visits them back again)", file=file,
                    key="schedule.positions_deg")
    if len(pos) < 3 and not (len(pos) == 2 and abs(abs(math.remainder(
            pos[1] - pos[0], 360.0)) - 180.0) <= POSITION_TOL_DEG):
        raise ScenarioError(f"{len(pos)} position{'s' if len(pos) > 1 else ''} "
                            f"({', '.join(f'{p:g}' for p in pos)} deg) cannot determine the "
                            "heading: north finding needs three distinct positions, or two "
                            "180 deg apart", file=file, key="schedule.positions_deg")
    if settings.settle_s >= schedule.dwell_s:
        raise ScenarioError(f"{settings.settle_s:g} s skips the whole dwell of "
                            f"{schedule.dwell_s:g} s (schedule.dwell_s): no sample would be "
                            "left to north-find", file=file, key="northfind.settle_s")
    r = find("limits.samples_per_dwell")
    n = (schedule.dwell_s - settings.settle_s) * fs
    if r.impossible(n):
        raise ScenarioError(f"a dwell of {schedule.dwell_s:g} s"
                            + (f" less {settings.settle_s:g} s settling"
                               if settings.settle_s else "")
                            + f" at {fs:g} Hz holds {n:.3g} samples, fewer than the "
                            f"{r.hard[0]:g} a dwell mean needs", file=file,
                            key="schedule.dwell_s")
    if settings.startup_end_s < schedule.cycle_s:
        raise ScenarioError(f"{settings.startup_end_s:g} s ends the start-up stage before the "
                            f"first north-finding cycle ends ({schedule.cycle_s:g} s): the "
                            "start-up row would be empty", file=file,
                            key="northfind.startup_end_s")


def _check_work(temps, duration: float | None, chamber: ChamberProfile, fs: float,
                file) -> None:
    """The samples each run will hold (a program's unpowered soak included) against
    ``limits.samples_per_run`` of :mod:`nfs.ranges`, before any array is allocated."""
    r = find("limits.samples_per_run")
    key = "duration_s" if duration is not None else "chamber.program"
    warned = False
    for t0 in temps:
        soak = chamber.soak_s(t0, 1.0 / fs)
        length = duration if duration is not None else chamber.powered_s(t0, 1.0 / fs)
        n = (soak + length) * fs
        what = (f"{length:g} s" + (f" after a soak of {soak:g} s" if soak else "")
                + f" at {fs:g} Hz is {n:.3g} samples per run")
        if r.impossible(n):
            raise ScenarioError(f"{what}, more than the {r.hard[1]:g} one run may hold "
                                f"({r.source})", file=file, key=key)
        if r.unusual(n) and not warned:
            warn_unusual(f"{what}: slow (about a minute and 1.3 GB per million samples); "
                         "running anyway", file=file, key=key, once=("samples", n))
            warned = True


def _check_cutoff(cutoff_period_s: float, temps, duration: float | None,
                  chamber: ChamberProfile, fs: float, file) -> None:
    """The drift target of a compensated run is separated at the wavelet level of
    ``compensation.cutoff_period_s`` (:func:`nfs.denoise.drift.separate_drift`): the checks
    the denoiser makes of its record (:mod:`nfs.denoise.levels`: the level of the cutoff,
    the record with its smooth extension long enough for it with the separation's wavelet,
    the edge fit), made on the length of the shortest run, refuse the level now rather than
    after the start-ups are simulated, without PyWavelets."""
    n = min(int((duration if duration is not None else chamber.powered_s(t0, 1.0 / fs)) * fs)
            + 1 for t0 in temps)
    try:
        level = level_for_cutoff(cutoff_period_s, fs)
        check_level(level, max(n, 2), DEFAULT_WAVELET, FILTER_LENGTHS[DEFAULT_WAVELET],
                    extended=True)
        check_edge_fit(level, max(n, 2), None, "auto")
    except NfsError as exc:
        raise ScenarioError(f"the drift of the shortest run ({n} samples) cannot be separated "
                            f"at this cutoff: {exc}", file=file,
                            key="compensation.cutoff_period_s") from None


def _overridden(d: dict, overrides: dict[str, Any], file) -> dict:
    """A copy of the parsed file ``d`` with each dotted key of ``overrides`` set (a table on
    the way is created when the file leaves it out)."""
    d = copy.deepcopy(d)
    for dotted, value in overrides.items():
        if dotted not in OVERRIDE_KEYS:
            raise ScenarioError("cannot be overridden; keys that can: "
                                + ", ".join(OVERRIDE_KEYS), file=file, key=dotted)
        *heads, last = dotted.split(".")
        tbl = d
        for h in heads:
            tbl = tbl.setdefault(h, {})
            if not isinstance(tbl, dict):
                raise ScenarioError(f"must be a table, got {tbl!r}", file=file, key=h)
        tbl[last] = value
    return d


#: The environment variable that lets a scenario's ``effects_files`` run (``nfs COMMAND
#: --trust-effects`` sets it, so that a sweep's worker processes inherit it): a scenario
#: passed between colleagues must not run code because it was loaded.
TRUST_EFFECTS_ENV = "NFS_TRUST_EFFECTS_FILES"


def load_scenario(path: str | Path | None = None,
                  overrides: dict[str, Any] | None = None) -> Scenario:
    """Read and check a scenario file (the built-in default when ``path`` is None), with
    every key it leaves out from its ``base`` or the built-in default (module docstring).

    ``overrides`` ({dotted key: value}, keys of :data:`OVERRIDE_KEYS`) replace values of the
    file before it is checked, as if the file said so (``{"schedule.dwell_s": 60.0}``).
    """
    path = default_scenario_path() if path is None else scenario_file(path)
    with deferred_warnings():
        return _load(path, overrides, (path.resolve(),))[0]


def _load(path: Path, overrides, chain: tuple[Path, ...]) -> tuple[Scenario, dict]:
    """The checked scenario of ``path`` and its keys over its bases' as written (what a file
    naming it as ``base`` inherits): each base is loaded and checked once."""
    f = path
    d = load_toml(path)
    check_keys(d, _TOP, "", f)
    written, d = _inherited(path, d, chain)
    if overrides:
        d = _overridden(d, overrides, f)
    check_keys(d, _TOP, "", f, required=("start_temperatures_c", "schedule"))
    base = path.parent
    files = d.get("effects_files", [])
    if not isinstance(files, list) or not all(isinstance(x, str) for x in files):
        raise ScenarioError("must be a list of Python file paths", file=f, key="effects_files")
    if files and os.environ.get(TRUST_EFFECTS_ENV) != "1":
        raise ScenarioError(
            "names Python files to run (" + ", ".join(files) + "): a scenario file does not "
            "run code on its own; after reading them, give --trust-effects on the command "
            f"line (or set {TRUST_EFFECTS_ENV}=1 for a Python script and its workers)",
            file=f, key="effects_files")
    for name in files:
        p = Path(name) if Path(name).is_absolute() else base / name
        try:
            load_effects_file(p)
        except EffectError as exc:
            raise ScenarioError(str(exc), file=f, key="effects_files") from None
    inst_ref = string(d, "instrument", "", f, "default")
    inst_path = Path(inst_ref) if Path(inst_ref).is_absolute() else base / inst_ref
    if (inst_ref.endswith(".toml") or "/" in inst_ref or "\\" in inst_ref) \
            and not inst_path.is_file():
        raise ScenarioError(f"the instrument file {inst_path} does not exist (a path is taken "
                            "relative to this scenario's folder; a preset is named without "
                            ".toml: nfs preset lists them)", file=f, key="instrument")
    try:
        inst = load_instrument(inst_ref, base=base)
    except ScenarioError as exc:
        if exc.file is None:
            raise ScenarioError(exc.message, file=f, key="instrument") from None
        raise
    if "aux" in d:
        extra = parse_aux(d["aux"], inst.network, f)
        have = {a.name for a in inst.aux}
        dup = next((a.name for a in extra if a.name in have), None)
        if dup is not None:
            raise ScenarioError(f"the instrument already has a channel '{dup}'", file=f,
                                key="aux")
        inst = Instrument(**{**inst.__dict__, "aux": inst.aux + extra})
    if "effects" in d or "added_effects" in d:
        effects = parse_effects(d["effects"], f) if "effects" in d else inst.effects
        if "added_effects" in d:
            effects = effects + parse_effects(d["added_effects"], f, "added_effects")
        inst = Instrument(**{**inst.__dict__, "effects": effects})
        check_effect_targets(inst, f)
        check_heating(inst.network, f, inst.effects)

    sch = table(d, "schedule", "", f)
    check_keys(sch, _SCHEDULE, "schedule", f, required=("positions_deg", "dwell_s"))
    try:
        schedule = Schedule(
            positions_deg=number_list(sch, "positions_deg", "schedule", f),
            dwell_s=number(sch, "dwell_s", "schedule", f, positive=True),
            move_s=number(sch, "move_s", "schedule", f, 10.0, minimum=0.0),
            order=string(sch, "order", "schedule", f, "sequential", choices=ORDERS))
    except ScenarioError:
        raise
    except NfsError as exc:
        raise ScenarioError(str(exc), file=f, key="schedule") from None
    _check_geometry(inst, schedule, f, "effects" in d)

    nf = table(d, "northfind", "", f, {})
    check_keys(nf, _NORTHFIND, "northfind", f)
    settings = NorthFindSettings(
        startup_end_s=number(nf, "startup_end_s", "northfind", f, 3600.0, positive=True),
        stable_start_s=number(nf, "stable_start_s", "northfind", f, 5400.0, minimum=0.0),
        tilt_correction=boolean(nf, "tilt_correction", "northfind", f, True),
        settle_s=number(nf, "settle_s", "northfind", f, 0.0, minimum=0.0),
        spec_deg=number(nf, "spec_deg", "northfind", f, 0.02, positive=True))
    ch = table(d, "chamber", "", f, {})
    check_keys(ch, _CHAMBER, "chamber", f)
    chamber = ChamberProfile(ripple_c=number(ch, "ripple_c", "chamber", f, 0.0, minimum=0.0),
                             ripple_period_s=number(ch, "ripple_period_s", "chamber", f,
                                                    600.0, positive=True),
                             program=(parse_program(ch["program"], f) if "program" in ch
                                      else None))
    seed = d.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ScenarioError(f"must be a non-negative integer, got {seed!r}", file=f, key="seed")
    repeats = d.get("repeats", 1)
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise ScenarioError(f"must be a positive integer, got {repeats!r}", file=f,
                            key="repeats")
    temps = number_list(d, "start_temperatures_c", "", f)
    for t0 in temps:
        check_temperature(t0, f, "start_temperatures_c")
    if len(set(temps)) != len(temps):
        twice = next(t for t in temps if temps.count(t) > 1)
        raise ScenarioError(f"names {twice:g} C twice (runs are named by their start "
                            "temperature; write repeats = N for more start-ups at one "
                            "temperature)", file=f, key="start_temperatures_c")
    units = integer(d, "units", "", f, 1, minimum=1)
    variability = variability_table(d, inst, seed, f)
    fs = number(d, "sample_rate_hz", "", f, 1.0, positive=True)
    duration = number(d, "duration_s", "", f, 9000.0 if chamber.program is None else None,
                      positive=True)
    for t0 in temps:
        length = duration if duration is not None else chamber.powered_s(t0, 1.0 / fs)
        if length < schedule.cycle_s:
            what = ("" if duration is not None
                    else f"the chamber program after power-on from {t0:g} C, ")
            raise ScenarioError(f"{what}{length:g} s is shorter than one north-finding "
                                f"cycle ({schedule.cycle_s:g} s)", file=f,
                                key="duration_s" if duration is not None
                                else "chamber.program")
    comp = compensation_table(table(d, "compensation", "", f, {}), f, units)
    if comp.protocol == "cycles":
        if chamber.program is None or len(chamber.program.cycles) < 2:
            raise ScenarioError("\"cycles\" trains on cycle 1 of the chamber program and "
                                "tests on the others: [chamber] needs a program with a "
                                "{ repeat = N, steps = [...] } step, N >= 2", file=f,
                                key="compensation.protocol")
    if comp.protocol in ("cycles", "runs"):
        tuned = [m for m in comp.methods if lookup_method(m).tuned]
        if tuned:
            raise ScenarioError(f"{tuned[0]} tunes by leaving a start temperature or a run "
                                "out, and a drift-table study trains once: use untuned "
                                f"methods with protocol = \"{comp.protocol}\"", file=f,
                                key="compensation.methods")
    if comp.protocol == "parameters" and len(
            {round(a % 360.0, 6) for a in schedule.positions_deg}) < 3:
        raise ScenarioError("\"parameters\" calibrates the biases and the scale factor in "
                            "every north-finding cycle: [schedule] positions_deg needs three "
                            "distinct positions or more", file=f,
                            key="compensation.protocol")
    latitude = number(d, "latitude_deg", "", f, 30.0, minimum=-89.0, maximum=89.0)
    # every value against its range (nfs.ranges); an overridden value is the caller's to
    # warn about in its own words (a sweep names its axis)
    check_tree(d, file=f, error=ScenarioError,
               quiet=tuple(p for k in (overrides or {}) for p in (k, f"{k}.*")))
    _check_schedule(schedule, settings, fs, f)
    _check_work(temps, duration, chamber, fs, f)
    _check_cutoff(comp.cutoff_period_s, temps, duration, chamber, fs, f)
    if comp.n_jobs == 0:
        raise ScenarioError("must not be 0 (joblib: -1 is every core, N is N cores)",
                            file=f, key="compensation.n_jobs")
    scenario = Scenario(
        name=string(d, "name", "", f, path.stem), instrument=inst,
        start_temperatures_c=temps, schedule=schedule, seed=seed, repeats=repeats,
        duration_s=duration, sample_rate_hz=fs,
        latitude_deg=latitude,
        true_heading_deg=number(d, "true_heading_deg", "", f, 0.0),
        northfind=settings, chamber=chamber,
        compensation=comp,
        description=string(d, "description", "", f, ""), path=path, units=units,
        variability=variability)
    return scenario, written
