"""Scenario files: a start-up experiment described in TOML.

A scenario names an instrument (a built-in preset or an instrument TOML file), the start
temperatures, the schedule and the north-finding settings; ``[[effects]]`` in the scenario,
when present, replace the instrument's effect list.  ``units`` simulated units make the
start-ups, and ``[variability]`` says how start-ups and units differ
(:mod:`nfs.variability`; no table: every start-up soaked exactly at T0, every unit the
nominal instrument).  Every key is checked: an unknown key is an error that names it and
lists the allowed ones.  See ``scenarios/startup_7temps.toml``.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..effects import load_effects_file
from ..errors import EffectError, NfsError, ScenarioError
from ..instrument import Instrument, _check_effect_targets, load_instrument, parse_effects
from ..parameters import ParameterError, expand_paths
from ..sensors import ORDERS, Schedule
from ..variability import (CYCLING_SHAPES, NO_VARIABILITY, VARIABILITY_KEYS,
                           VARIABILITY_PRESETS, Variability)
from .tomlio import check_keys, load_toml, number, number_list, string, table

__all__ = ["NorthFindSettings", "ChamberProfile", "Scenario", "load_scenario",
           "default_scenario_path"]

_TOP = ("name", "description", "instrument", "seed", "start_temperatures_c", "repeats",
        "duration_s", "sample_rate_hz", "latitude_deg", "true_heading_deg", "effects_files",
        "effects", "schedule", "northfind", "chamber", "compensation", "units",
        "variability")
_COMPENSATION = ("methods", "features", "features_mode", "budget", "decimate_s",
                 "cutoff_period_s",
                 "train_seed", "train_repeats", "train_temperatures_c", "test_repeats",
                 "train_units", "test_units", "random_state", "tuner_seeds", "n_jobs")
_VARIABILITY = ("preset", *VARIABILITY_KEYS, "parameters")
_SCHEDULE = ("positions_deg", "order", "dwell_s", "move_s")
_NORTHFIND = ("startup_end_s", "stable_start_s", "tilt_correction", "settle_s", "spec_deg")
_CHAMBER = ("ripple_c", "ripple_period_s")

#: The dotted scenario keys :func:`load_scenario` may override (every value key of the file
#: but its name, description, seed and effect lists): what a sweep can put on an axis.
OVERRIDE_KEYS: tuple[str, ...] = (
    "instrument", "start_temperatures_c", "repeats", "duration_s", "sample_rate_hz",
    "latitude_deg", "true_heading_deg", "units",
    *(f"schedule.{k}" for k in _SCHEDULE), *(f"northfind.{k}" for k in _NORTHFIND),
    *(f"chamber.{k}" for k in _CHAMBER),
    *(f"variability.{k}" for k in _VARIABILITY if k != "parameters"),
    *(f"compensation.{k}" for k in _COMPENSATION))
__all__ += ["OVERRIDE_KEYS"]


@dataclass(frozen=True)
class NorthFindSettings:
    """How runs are north-found and scored."""

    startup_end_s: float = 3600.0
    """Start-up stage: cycles ending within this time after power-on [s]."""
    stable_start_s: float = 5400.0
    """Stable stage: cycles starting after this time [s]."""
    tilt_correction: bool = True
    """Correct each position for tilt with the x accelerometer."""
    settle_s: float = 0.0
    """Samples skipped at the start of each dwell [s]."""
    spec_deg: float = 0.02
    """Heading specification of the time to spec in the reports [deg]
    (:mod:`nfs.northfind.spec`); 0.02 deg is about the uncompensated start-up RMSE of the FOG
    start-up paper ("A FOG start-up drift compensation method at full temperatures", Table 3)."""


@dataclass(frozen=True)
class ChamberProfile:
    """Chamber air temperature T_amb(t) = T0 + ripple_c sin(2 pi t / ripple_period_s)."""

    ripple_c: float = 0.0
    """Amplitude of the chamber control ripple [K]."""
    ripple_period_s: float = 600.0
    """Period of the ripple [s]."""

    def ambient(self, start_temperature_c: float):
        """T_amb(t) as a function of time [degC], or None when the chamber holds T0."""
        if self.ripple_c == 0.0:
            return None
        a, p = self.ripple_c, self.ripple_period_s
        return lambda t: start_temperature_c + a * np.sin(2.0 * np.pi * np.asarray(t) / p)


@dataclass(frozen=True)
class Scenario:
    """A start-up experiment: instrument, temperatures, schedule, scoring."""

    name: str
    """Name; run files are called ``{name}_T{T0}C_r{repeat}``."""
    instrument: Instrument
    """The instrument (with the scenario's effect list, if it gives one)."""
    start_temperatures_c: tuple[float, ...]
    """T0 of each run set [degC]."""
    schedule: Schedule
    """North-finding schedule."""
    seed: int = 0
    """Root seed; start-up k of unit u at T0 number i draws from SeedSequence([seed, i, k])
    for unit 0 (the runs of a one-unit scenario), [seed, i, k, u] for u > 0."""
    repeats: int = 1
    """Start-ups per start temperature, made by the units of :attr:`unit_ids` in turn
    (start-up r by unit ``unit_ids[r % n]``, its ``r // n``-th)."""
    duration_s: float = 9000.0
    """Length of each run [s]."""
    sample_rate_hz: float = 1.0
    """Sample rate [Hz]."""
    latitude_deg: float = 30.0
    """Latitude L [deg]."""
    true_heading_deg: float = 0.0
    """psi, azimuth of the FOG axis at position 0 [deg]."""
    northfind: NorthFindSettings = field(default_factory=NorthFindSettings)
    """North-finding settings."""
    chamber: ChamberProfile = field(default_factory=ChamberProfile)
    """Chamber temperature profile."""
    description: str = ""
    """Free text."""
    compensation: Any = None
    """:class:`~nfs.compensate.study.CompensationSettings` of ``[compensation]`` (defaults
    when the table is absent)."""
    path: Path | None = None
    """The file it was read from."""
    units: int = 1
    """Simulated units (each start-up is made by one unit; a unit's parameters are drawn
    once from :attr:`variability`)."""
    run_units: tuple[int, ...] | None = None
    """The units that make this scenario's start-ups (None: every unit, 0 .. units-1)."""
    variability: Variability = NO_VARIABILITY
    """How start-ups and units differ (:mod:`nfs.variability`)."""

    @property
    def unit_ids(self) -> tuple[int, ...]:
        """The units that make the start-ups, in turn."""
        return tuple(range(self.units)) if self.run_units is None else tuple(self.run_units)

    def run_name(self, i_temp: int, repeat: int, unit: int = 0) -> str:
        """File stem of start-up ``repeat`` of ``unit`` at T0 number ``i_temp``:
        ``{name}_T{T0}C_r{repeat}``, with ``_u{unit}`` before ``_r`` when there are several
        units."""
        t0 = self.start_temperatures_c[i_temp]
        t0s = f"{t0:+g}".replace(".", "p")
        u = f"_u{unit}" if self.units > 1 else ""
        return f"{self.name}_T{t0s}C{u}_r{repeat}"

    def conditions(self):
        """The :class:`~nfs.experiment.RunConditions` of every run, temperature-major."""
        from ..experiment import RunConditions
        units = self.unit_ids
        var = self.variability if self.variability.active else None
        out = []
        for i, t0 in enumerate(self.start_temperatures_c):
            for r in range(self.repeats):
                u, k = units[r % len(units)], r // len(units)
                out.append(RunConditions(
                    name=self.run_name(i, k, u), start_temperature_c=t0,
                    latitude_deg=self.latitude_deg, true_heading_deg=self.true_heading_deg,
                    schedule=self.schedule, duration_s=self.duration_s,
                    sample_rate_hz=self.sample_rate_hz,
                    seed=(self.seed, i, k) if u == 0 else (self.seed, i, k, u),
                    chamber_c=self.chamber.ambient(t0), unit=u, variability=var))
        return out

    def nominal(self) -> "Scenario":
        """The same experiment in the world without variability: one unit, the nominal
        instrument, every start-up soaked exactly at T0 (``[variability] preset = "none"``,
        ``units = 1``); its runs are those unit 0 made before units existed."""
        return dataclasses.replace(self, units=1, run_units=None, variability=NO_VARIABILITY)

    def made_by(self, units: Sequence[int], repeats: int, **changes) -> "Scenario":
        """The same experiment with ``repeats`` start-ups per start temperature by each of
        ``units`` (``changes``: other fields to replace, e.g. ``seed``)."""
        units = tuple(int(u) for u in units)
        bad = [u for u in units if not 0 <= u < self.units]
        if not units or bad:
            raise NfsError(f"units {list(units)}: scenario '{self.name}' has units "
                           f"0..{self.units - 1}")
        return dataclasses.replace(self, run_units=units, repeats=repeats * len(units),
                                   **changes)

    def unit_split(self, train_units: Sequence[int] | None = None,
                   test_units: Sequence[int] | None = None
                   ) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """(training units, test units) of a compensation study.

        Defaults: with one unit, unit 0 for both (the start-ups differ by their seeds); with
        several, the test units are the last one and the training units all the others
        (or those not tested, when only ``test_units`` is given).
        """
        every = tuple(range(self.units))
        if test_units is None:
            held = tuple(u for u in every if train_units is None or u not in train_units)
            test_units = (held[-1],) if held and self.units > 1 else every[-1:]
        if train_units is None:
            train_units = tuple(u for u in every if u not in test_units) or every
        return tuple(train_units), tuple(test_units)


def default_scenario_path() -> Path:
    """The built-in default scenario (seed 004's seven start temperatures)."""
    return Path(str(resources.files("nfs") / "presets" / "startup_7temps.toml"))


def _bool(tbl, key, prefix, file, default):
    if key not in tbl:
        return default
    v = tbl[key]
    if not isinstance(v, bool):
        raise ScenarioError(f"must be true or false, got {v!r}", file=file,
                            key=f"{prefix}.{key}" if prefix else key)
    return v


def _int(tbl, key, prefix, file, default, minimum=None, allow_none=False):
    name = f"{prefix}.{key}" if prefix else key
    if key not in tbl:
        return default
    v = tbl[key]
    if isinstance(v, bool) or not isinstance(v, int) or (minimum is not None and v < minimum):
        raise ScenarioError(f"must be an integer{'' if minimum is None else f' >= {minimum}'}"
                            f", got {v!r}", file=file, key=name)
    return v


def _unit_list(tbl, key, prefix, file, units):
    """A list of distinct unit indices in 0 .. units-1, or None when absent."""
    if key not in tbl:
        return None
    v = tbl[key]
    name = f"{prefix}.{key}"
    if (not isinstance(v, list) or not v
            or not all(isinstance(u, int) and not isinstance(u, bool) for u in v)):
        raise ScenarioError(f"must be a non-empty list of unit indices, got {v!r}", file=file,
                            key=name)
    bad = [u for u in v if not 0 <= u < units]
    if bad:
        raise ScenarioError(f"unit {bad[0]} is out of range: the scenario has units "
                            f"0..{units - 1} (units = {units})", file=file, key=name)
    if len(set(v)) != len(v):
        raise ScenarioError(f"names a unit twice: {v!r}", file=file, key=name)
    return tuple(v)


def _variability(d: dict, inst: Instrument, seed: int, file) -> Variability:
    """``[variability]``: its ``preset`` with the values written overriding the preset's.

    ``realistic`` (the default when the table is given): the realistic set; ``custom``:
    nothing varies but what is written; ``none``: no variability at all, the other keys
    checked but not used (a table switched off without deleting it).  No table: ``none``.
    """
    p = "variability"
    if "variability" not in d:
        return NO_VARIABILITY
    tbl = d["variability"]
    if not isinstance(tbl, dict):
        raise ScenarioError(f"must be a table, got {tbl!r}; write [variability] and "
                            f"preset = \"none\", \"custom\" or \"realistic\"", file=file,
                            key=p)
    check_keys(tbl, _VARIABILITY, p, file)
    preset = string(tbl, "preset", p, file, "realistic", choices=tuple(VARIABILITY_PRESETS))
    base = VARIABILITY_PRESETS[preset]
    kw: dict[str, Any] = {"preset": preset}
    for key in VARIABILITY_KEYS:
        default = getattr(base, key)
        if key == "unfinished_soak":
            kw[key] = _bool(tbl, key, p, file, default)
        elif key == "cycling_shape":
            kw[key] = string(tbl, key, p, file, default, choices=CYCLING_SHAPES)
        elif key == "unit_seed":
            kw[key] = _int(tbl, key, p, file, seed, minimum=0)
        elif key == "soak_from_c":
            kw[key] = number(tbl, key, p, file, default, minimum=-273.15)
        elif key in ("soak_h", "chamber_wander_tau_s", "cycling_period_s"):
            kw[key] = number(tbl, key, p, file, default, positive=True)
        else:                                           # standard deviations
            kw[key] = number(tbl, key, p, file, default, minimum=0.0)
    kw["parameters"] = _variability_parameters(table(tbl, "parameters", p, file, {}), inst,
                                               file)
    out = Variability(**kw)
    if preset == "none":
        return NO_VARIABILITY
    if preset == "realistic" and out != dataclasses.replace(base, unit_seed=out.unit_seed):
        out = dataclasses.replace(out, preset=f"{preset} (modified)")
    return out


def _variability_parameters(tbl: dict, inst: Instrument, file):
    """``[variability.parameters]``: "path or pattern" = relative std, or { std = K }."""
    out = []
    for pattern, v in tbl.items():
        name = f'variability.parameters."{pattern}"'
        if isinstance(v, dict):
            if set(v) != {"std"}:
                raise ScenarioError(
                    "must be a relative standard deviation or { std = value } (quote a "
                    "dotted path: \"effects.shupe_gradient.k_r\" = 0.3)", file=file, key=name)
            std, rel = number(v, "std", name, file, minimum=0.0), False
        else:
            std, rel = number({name: v}, name, "", file, minimum=0.0), True
        try:
            expand_paths(inst, pattern)
        except ParameterError as exc:
            raise ScenarioError(str(exc), file=file, key=name) from None
        out.append((pattern, std, rel))
    return tuple(out)


def _compensation(tbl: dict, file, units: int = 1) -> Any:
    from ..compensate.features import FeatureError, resolve_features
    from ..compensate.methods import get_method
    from ..compensate.modes import FeatureModeError, check_features_mode
    from ..compensate.study import CompensationSettings
    p = "compensation"
    check_keys(tbl, _COMPENSATION, p, file)
    d = CompensationSettings()
    methods = tbl.get("methods", list(d.methods))
    if not isinstance(methods, list) or not all(isinstance(m, str) for m in methods):
        raise ScenarioError("must be a list of method names", file=file, key=f"{p}.methods")
    try:
        methods = tuple(get_method(m).key for m in methods)
    except NfsError as exc:
        raise ScenarioError(str(exc), file=file, key=f"{p}.methods") from None
    feats = tbl.get("features", list(d.features))
    if isinstance(feats, str):
        feats = [feats]
    if not isinstance(feats, list) or not all(isinstance(f, str) for f in feats):
        raise ScenarioError("must be a feature name or a list of them", file=file,
                            key=f"{p}.features")
    try:
        resolve_features(feats, ["aux_*"])
    except FeatureError as exc:
        raise ScenarioError(str(exc), file=file, key=f"{p}.features") from None
    try:
        mode = check_features_mode(tbl.get("features_mode", d.features_mode), option="")
    except FeatureModeError as exc:
        raise ScenarioError(str(exc), file=file, key=f"{p}.features_mode") from None
    temps = number_list(tbl, "train_temperatures_c", p, file, None)
    n_jobs = tbl.get("n_jobs", d.n_jobs)
    if n_jobs is not None and (isinstance(n_jobs, bool) or not isinstance(n_jobs, int)):
        raise ScenarioError(f"must be an integer, got {n_jobs!r}", file=file, key=f"{p}.n_jobs")
    return CompensationSettings(
        methods=methods, features=tuple(feats), features_mode=mode,
        budget=_int(tbl, "budget", p, file, d.budget, minimum=1),
        decimate_s=number(tbl, "decimate_s", p, file, d.decimate_s, positive=True),
        cutoff_period_s=number(tbl, "cutoff_period_s", p, file, d.cutoff_period_s,
                               positive=True),
        train_seed=_int(tbl, "train_seed", p, file, d.train_seed, minimum=0),
        train_repeats=_int(tbl, "train_repeats", p, file, d.train_repeats, minimum=1),
        train_temperatures_c=temps,
        test_repeats=_int(tbl, "test_repeats", p, file, d.test_repeats, minimum=1),
        train_units=_unit_list(tbl, "train_units", p, file, units),
        test_units=_unit_list(tbl, "test_units", p, file, units),
        random_state=_int(tbl, "random_state", p, file, d.random_state, minimum=0),
        tuner_seeds=_int(tbl, "tuner_seeds", p, file, d.tuner_seeds, minimum=1),
        n_jobs=n_jobs)


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


def load_scenario(path: str | Path | None = None,
                  overrides: dict[str, Any] | None = None) -> Scenario:
    """Read and check a scenario file (the built-in default when ``path`` is None).

    ``overrides`` ({dotted key: value}, keys of :data:`OVERRIDE_KEYS`) replace values of the
    file before it is checked, as if the file said so (``{"schedule.dwell_s": 60.0}``).
    """
    path = default_scenario_path() if path is None else Path(path)
    d = load_toml(path)
    f = path
    if overrides:
        d = _overridden(d, overrides, f)
    check_keys(d, _TOP, "", f, required=("start_temperatures_c", "schedule"))
    base = path.parent
    files = d.get("effects_files", [])
    if not isinstance(files, list) or not all(isinstance(x, str) for x in files):
        raise ScenarioError("must be a list of Python file paths", file=f, key="effects_files")
    for name in files:
        p = Path(name) if Path(name).is_absolute() else base / name
        try:
            load_effects_file(p)
        except EffectError as exc:
            raise ScenarioError(str(exc), file=f, key="effects_files") from None
    inst_ref = string(d, "instrument", "", f, "default")
    try:
        inst = load_instrument(inst_ref, base=base)
    except ScenarioError as exc:
        if exc.file is None:
            raise ScenarioError(exc.message, file=f, key="instrument") from None
        raise
    if "effects" in d:
        effects = parse_effects(d["effects"], f)
        inst = Instrument(**{**inst.__dict__, "effects": effects})
        _check_effect_targets(inst, f)

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

    nf = table(d, "northfind", "", f, {})
    check_keys(nf, _NORTHFIND, "northfind", f)
    settings = NorthFindSettings(
        startup_end_s=number(nf, "startup_end_s", "northfind", f, 3600.0, positive=True),
        stable_start_s=number(nf, "stable_start_s", "northfind", f, 5400.0, minimum=0.0),
        tilt_correction=_bool(nf, "tilt_correction", "northfind", f, True),
        settle_s=number(nf, "settle_s", "northfind", f, 0.0, minimum=0.0),
        spec_deg=number(nf, "spec_deg", "northfind", f, 0.02, positive=True))
    ch = table(d, "chamber", "", f, {})
    check_keys(ch, _CHAMBER, "chamber", f)
    chamber = ChamberProfile(ripple_c=number(ch, "ripple_c", "chamber", f, 0.0, minimum=0.0),
                             ripple_period_s=number(ch, "ripple_period_s", "chamber", f,
                                                    600.0, positive=True))
    seed = d.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ScenarioError(f"must be a non-negative integer, got {seed!r}", file=f, key="seed")
    repeats = d.get("repeats", 1)
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise ScenarioError(f"must be a positive integer, got {repeats!r}", file=f,
                            key="repeats")
    temps = number_list(d, "start_temperatures_c", "", f)
    for t0 in temps:
        if t0 < -273.15:
            raise ScenarioError(f"{t0} is below absolute zero", file=f,
                                key="start_temperatures_c")
    units = _int(d, "units", "", f, 1, minimum=1)
    variability = _variability(d, inst, seed, f)
    duration = number(d, "duration_s", "", f, 9000.0, positive=True)
    if duration < schedule.cycle_s:
        raise ScenarioError(f"{duration} s is shorter than one cycle ({schedule.cycle_s} s)",
                            file=f, key="duration_s")
    return Scenario(
        name=string(d, "name", "", f, path.stem), instrument=inst,
        start_temperatures_c=temps, schedule=schedule, seed=seed, repeats=repeats,
        duration_s=duration,
        sample_rate_hz=number(d, "sample_rate_hz", "", f, 1.0, positive=True),
        latitude_deg=number(d, "latitude_deg", "", f, 30.0, minimum=-89.0, maximum=89.0),
        true_heading_deg=number(d, "true_heading_deg", "", f, 0.0),
        northfind=settings, chamber=chamber,
        compensation=_compensation(table(d, "compensation", "", f, {}), f, units),
        description=string(d, "description", "", f, ""), path=path, units=units,
        variability=variability)
