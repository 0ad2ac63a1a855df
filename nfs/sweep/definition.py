"""Sweep files: a base scenario, the axes to vary, the seeds; read and checked as a whole.

A sweep file (TOML)::

    scenario = "default"                # or a scenario file, relative to the sweep file
    seeds = [1, 2]                      # or { first = 0, count = 100 }
    method = "ls"                       # optional: also compensate with this method
    spec_deg = 0.01                     # optional: heading spec of the time to spec [deg]
                                        # (default: the scenario's northfind.spec_deg)
    rmse_window_cycles = 5              # optional: cycles of the rolling RMSE (default 5)

    [axes]                              # grid axes: a list of values each
    latitude_deg = [30.0, 60.0]                         # a scenario key
    schedule.dwell_s = [60.0, 150.0]                    # a scenario key in a table
    "gyro.arw_deg_per_rth_h" = [0.0003, 0.001]          # an instrument parameter
    "effects.shupe_gradient.k_r" = { low = 0.1, high = 1.0 }   # a drawn axis (a range)

    [draws]                             # how ranges are drawn (needed when an axis is a range)
    sampler = "sobol"                   # or "random"
    count = 16                          # points (a power of 2 for sobol)
    seed = 0

An axis names any scenario key of :data:`nfs.config.scenario.OVERRIDE_KEYS` (``latitude_deg``,
``schedule.dwell_s``, ``start_temperatures_c``, ...) or any instrument parameter by the
dotted path ``nfs fit`` uses (:mod:`nfs.parameters`: ``gyro.arw_deg_per_rth_h``,
``effects.shupe_gradient.k_r``, ``thermal.nodes.housing.capacity_j_per_k``).  The points are
the product of the grid axes, each combined with every draw of the ranges (drawn jointly:
random with ``numpy.random.default_rng(seed)`` or a scrambled Sobol sequence,
``scipy.stats.qmc.Sobol``; a range with ``log = true`` is drawn uniformly in its logarithm).
A cell is one point with one seed: the base scenario with the point's values and
``seed = `` the cell's seed, every run of it simulated, north-found (and compensated).

Everything is checked before any cell runs: every key, every axis value on the base scenario
(a grid value by value, a range at its two ends), the method; the first fault is one
:class:`SweepError` naming the sweep file and the key.
"""

from __future__ import annotations

import difflib
import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import numpy as np
from scipy.stats import qmc

from ..compensate import get_method
from ..errors import USER_ERRORS, InputError, NfsError
from ..config.scenario import OVERRIDE_KEYS, load_scenario
from ..config.presets import scenario_file
from ..scenario import Scenario
from ..io.tomlio import check_keys, load_toml
from ..northfind.time_to_spec import DEFAULT_WINDOW
from ..parameters import canonical_path, param_paths, set_params
from ..ranges import check, check_tree, deferred_warnings, find

__all__ = ["SweepError", "Axis", "Draws", "SweepSpec", "load_sweep", "sweep_from_dict"]

_TOP = ("scenario", "description", "seeds", "method", "spec_deg", "rmse_window_cycles", "axes",
        "draws")
_DRAWS = ("sampler", "count", "seed")
_RANGE = ("low", "high", "log")
SAMPLERS = ("random", "sobol")


class SweepError(InputError):
    """A sweep file that cannot be run (located by file and key)."""


@dataclass(frozen=True)
class Axis:
    """One swept key."""

    key: str
    """Dotted scenario key or instrument parameter path (as written, links canonical)."""
    target: str
    """``scenario`` or ``instrument``."""
    values: tuple[Any, ...] | None = None
    """Grid values, in the file's order (None for a drawn axis)."""
    low: float | None = None
    """Lower end of a drawn axis."""
    high: float | None = None
    """Upper end of a drawn axis."""
    log: bool = False
    """Draw uniformly in log(value) rather than in value."""

    @property
    def drawn(self) -> bool:
        """True for a range drawn by the sampler."""
        return self.values is None


@dataclass(frozen=True)
class Draws:
    """How the ranges are drawn."""

    sampler: str = "sobol"
    """``random`` (independent uniform draws) or ``sobol`` (scrambled Sobol points)."""
    count: int = 16
    """Points drawn."""
    seed: int = 0
    """Seed of the draws."""


@dataclass(frozen=True)
class SweepSpec:
    """A checked sweep."""

    path: Path | None
    """The sweep file."""
    scenario_path: Path | None
    """The base scenario file (None: the built-in default)."""
    scenario: Scenario
    """The base scenario, as loaded."""
    axes: tuple[Axis, ...]
    """Grid axes first (in file order), then drawn axes."""
    seeds: tuple[int, ...]
    """Seed of each cell of a point (the scenario's ``seed``)."""
    draws: Draws | None = None
    """The sampler of the drawn axes (None when every axis is a grid)."""
    method: str | None = None
    """Compensation method key (None: uncompensated only)."""
    spec_deg: float = 0.02
    """Heading specification of the time-to-spec columns [deg]."""
    rmse_window_cycles: int = DEFAULT_WINDOW
    """Cycles of the rolling RMSE whose time to spec is reported."""
    description: str = ""
    """Free text."""

    @property
    def grid_axes(self) -> tuple[Axis, ...]:
        """The axes with a list of values."""
        return tuple(a for a in self.axes if not a.drawn)

    @property
    def drawn_axes(self) -> tuple[Axis, ...]:
        """The axes drawn from a range."""
        return tuple(a for a in self.axes if a.drawn)

    @property
    def n_points(self) -> int:
        """Points: product of the grid axes' lengths, times the draws."""
        n = math.prod(len(a.values) for a in self.grid_axes)
        return n * (self.draws.count if self.drawn_axes else 1)

    @property
    def n_cells(self) -> int:
        """Cells: points x seeds."""
        return self.n_points * len(self.seeds)

    def drawn_values(self) -> np.ndarray:
        """The draws of the drawn axes, shape (count, n drawn axes)."""
        drawn = self.drawn_axes
        if not drawn:
            return np.zeros((1, 0))
        d = self.draws
        if d.sampler == "sobol":
            u = qmc.Sobol(len(drawn), scramble=True, seed=d.seed).random(d.count)
        else:
            u = np.random.default_rng(d.seed).random((d.count, len(drawn)))
        out = np.empty_like(u)
        for j, a in enumerate(drawn):
            if a.log:
                lo, hi = math.log(a.low), math.log(a.high)
                out[:, j] = np.exp(lo + u[:, j] * (hi - lo))
            else:
                out[:, j] = a.low + u[:, j] * (a.high - a.low)
        return out

    def points(self) -> Iterator[dict[str, Any]]:
        """Every point as {axis key: value}, grid-major (the last grid axis fastest), each
        grid point with every draw in turn; generated lazily."""
        grid = self.grid_axes
        draws = self.drawn_values()
        names = [a.key for a in self.drawn_axes]
        for combo in itertools.product(*(a.values for a in grid)):
            base = {a.key: v for a, v in zip(grid, combo)}
            for row in draws:
                yield {**base, **{k: float(v) for k, v in zip(names, row)}}


def _located(exc: NfsError, file, key: str, what: str = "") -> SweepError:
    """``exc`` re-located at ``key`` of the sweep file (naming the scenario key it met)."""
    msg = str(exc)
    if isinstance(exc, InputError):
        msg = exc.message
        if exc.key is not None and not key.endswith(exc.key):
            msg = f"scenario key '{exc.key}': {msg}"
    return SweepError(f"{what}{msg}", file=file, key=key)


def _flatten_axes(tbl: dict, prefix: str = "") -> Iterator[tuple[str, Any]]:
    """(dotted key, value) of ``[axes]``: a TOML dotted key (``schedule.dwell_s = [...]``)
    parses as nested tables; a table whose keys are those of a range is a value."""
    for k, v in tbl.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict) and v and not set(v) <= set(_RANGE):
            yield from _flatten_axes(v, key + ".")
        else:
            yield key, v


def _positive_int(v, file, key, minimum=1) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < minimum:
        raise SweepError(f"must be an integer >= {minimum}, got {v!r}", file=file, key=key)
    return v


def _seeds(v, file) -> tuple[int, ...]:
    if isinstance(v, dict):
        check_keys(v, ("first", "count"), "seeds", file, required=("count",))
        first = _positive_int(v.get("first", 0), file, "seeds.first", minimum=0)
        count = _positive_int(v["count"], file, "seeds.count")
        return tuple(range(first, first + count))
    if (not isinstance(v, list) or not v
            or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in v)):
        raise SweepError(f"must be a non-empty list of non-negative integers or "
                         f"{{ first = 0, count = N }}, got {v!r}", file=file, key="seeds")
    if len(set(v)) != len(v):
        raise SweepError(f"names a seed twice: {v!r}", file=file, key="seeds")
    return tuple(v)


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _unknown_axis(key: str, sc: Scenario, valid: list[str]) -> str:
    """Why ``key`` is no axis, in the words of the files: an effect the instrument lacks, a
    near miss, or what an axis may be."""
    parts = key.split(".")
    if parts[0] == "effects" and len(parts) > 1:
        label = parts[1]
        have = sorted({e.label for e in sc.instrument.effects})
        if label not in have and label.split(":")[0] not in {e.name for e in
                                                             sc.instrument.effects}:
            return (f"the scenario's instrument '{sc.instrument.name}' has no effect "
                    f"'{label}' (it has: {', '.join(have)}); add it to the instrument's "
                    "[[effects]] first, then sweep its parameter")
    close = difflib.get_close_matches(key, [*OVERRIDE_KEYS, *valid], n=4, cutoff=0.6)
    scenario_keys = ", ".join(sorted(OVERRIDE_KEYS)[:6])
    return ("neither a key of the scenario file nor a parameter of its instrument"
            + (f"; did you mean {' or '.join(close)}?" if close else "")
            + f" (scenario keys such as {scenario_keys}, ...; instrument parameters as "
            "`nfs fit --free` names them, e.g. thermal.nodes.board.power_w)")


def _axis(key: str, v: Any, sc: Scenario, scenario_path, file) -> Axis:
    name = f"axes.{key}"
    if key == "seed":
        raise SweepError("the seed is not an axis: list the seeds in 'seeds'", file=file,
                         key=name)
    if key in OVERRIDE_KEYS:
        target = "scenario"
    else:
        valid = [p for p, _ in param_paths(sc.instrument)]
        try:
            key = canonical_path(sc.instrument, key, set(valid))
        except NfsError:
            raise SweepError(_unknown_axis(key, sc, valid), file=file, key=name) from None
        target = "instrument"
    if isinstance(v, dict):
        check_keys(v, _RANGE, name, file, required=("low", "high"))
        low, high, log = v["low"], v["high"], v.get("log", False)
        if not (_number(low) and _number(high)) or not low < high:
            raise SweepError(f"a range needs finite numbers low < high, got low = {low!r}, "
                             f"high = {high!r}", file=file, key=name)
        if not isinstance(log, bool):
            raise SweepError(f"must be true or false, got {log!r}", file=file, key=f"{name}.log")
        if log and low <= 0:
            raise SweepError(f"a log range needs low > 0, got {low!r}", file=file, key=name)
        axis = Axis(key, target, low=float(low), high=float(high), log=log)
        checks = (float(low), float(high))
    elif isinstance(v, list):
        if not v:
            raise SweepError("an axis needs at least one value", file=file, key=name)
        if len({json.dumps(x, sort_keys=True) for x in v}) != len(v):
            raise SweepError(f"names a value twice: {v!r}", file=file, key=name)
        axis = Axis(key, target, values=tuple(v))
        checks = tuple(v)
    else:
        raise SweepError(f"must be a list of values or a range {{ low = ..., high = ... }}, "
                         f"got {v!r}", file=file, key=name)
    for value in checks:
        _check_value(axis, value, sc, scenario_path, file)
    for value in checks:
        for number in (value if isinstance(value, list) else [value]):
            # the base scenario refused what it cannot run; here every value is checked
            # against its range (an instrument parameter's too) and warned about by its axis
            check(axis.key, number, file=file, key=name, error=SweepError)
    return axis


def _check_value(axis: Axis, value: Any, sc: Scenario, scenario_path, file) -> None:
    """Apply one value to the base scenario: the first fault, located in the sweep file."""
    name = f"axes.{axis.key}"
    try:
        if axis.target == "scenario":
            load_scenario(scenario_path, {axis.key: value})
        else:
            if not _number(value):
                raise SweepError(f"an instrument parameter takes numbers, got {value!r}",
                                 file=file, key=name)
            set_params(sc.instrument, {axis.key: value})
    except SweepError:
        raise
    except USER_ERRORS as exc:
        raise _located(exc, file, name, f"value {value!r}: ") from None


def sweep_from_dict(d: dict[str, Any], file: Path | None = None,
                    base: Path | None = None) -> SweepSpec:
    """Check a parsed sweep (``base``: folder that a relative scenario path is read from):
    every key, every value against its range (:mod:`nfs.ranges`), the number of cells."""
    with deferred_warnings():
        return _sweep_from_dict(d, file, base)


def _sweep_from_dict(d: dict[str, Any], file: Path | None, base: Path | None) -> SweepSpec:
    check_keys(d, _TOP, "", file, required=("seeds",))
    check_tree(d, file=file, error=SweepError, canonical="sweep", skip=("sweep.axes.*",))
    ref = d.get("scenario", "default")
    if not isinstance(ref, str):
        raise SweepError(f"must be \"default\" or a scenario file path, got {ref!r}",
                         file=file, key="scenario")
    scenario_path = None
    if ref != "default":
        scenario_path = Path(ref) if Path(ref).is_absolute() else (base or Path.cwd()) / ref
    try:
        sc = load_scenario(scenario_path)
    except USER_ERRORS as exc:
        raise SweepError(f"the scenario does not load: {exc}", file=file,
                         key="scenario") from None
    seeds = _seeds(d["seeds"], file)
    axes_tbl = d.get("axes", {})
    if not isinstance(axes_tbl, dict):
        raise SweepError(f"must be a table, got {axes_tbl!r}", file=file, key="axes")
    axes: list[Axis] = []
    for key, v in _flatten_axes(axes_tbl):
        axis = _axis(key, v, sc, scenario_path, file)
        if any(a.key == axis.key for a in axes):
            raise SweepError(f"the same parameter as axis '{axis.key}'", file=file,
                             key=f"axes.{key}")
        axes.append(axis)
    axes.sort(key=lambda a: a.drawn)                     # stable: file order within each kind
    draws = None
    if "draws" in d:
        tbl = d["draws"]
        if not isinstance(tbl, dict):
            raise SweepError(f"must be a table, got {tbl!r}", file=file, key="draws")
        check_keys(tbl, _DRAWS, "draws", file)
        sampler = tbl.get("sampler", "sobol")
        if sampler not in SAMPLERS:
            raise SweepError(f"'{sampler}' is not one of {', '.join(SAMPLERS)}", file=file,
                             key="draws.sampler")
        count = _positive_int(tbl.get("count", 16), file, "draws.count")
        if sampler == "sobol" and count & (count - 1):
            raise SweepError(f"a Sobol sequence keeps its balance at a power of 2 points, "
                             f"got {count}", file=file, key="draws.count")
        draws = Draws(sampler, count, _positive_int(tbl.get("seed", 0), file, "draws.seed",
                                                    minimum=0))
    if any(a.drawn for a in axes) and draws is None:
        draws = Draws()
    method = d.get("method", "none")
    if not isinstance(method, str):
        raise SweepError(f"must be a method name, got {method!r}", file=file, key="method")
    if method == "none":
        method = None
    else:
        try:
            method = get_method(method).key
        except NfsError as exc:
            raise _located(exc, file, "method") from None
        train_seed = (sc.compensation.train_seed if sc.compensation is not None else None)
        if train_seed in seeds:
            raise SweepError(f"seed {train_seed} is the seed of the compensator's training "
                             f"start-ups (compensation.train_seed of the scenario): the "
                             f"test start-ups must differ from them", file=file, key="seeds")
    spec_deg = d.get("spec_deg", sc.northfind.spec_deg)
    if not _number(spec_deg) or spec_deg <= 0:
        raise SweepError(f"must be an angle > 0 [deg], got {spec_deg!r}", file=file,
                         key="spec_deg")
    window = _positive_int(d.get("rmse_window_cycles", DEFAULT_WINDOW), file,
                           "rmse_window_cycles")
    desc = d.get("description", "")
    if not isinstance(desc, str):
        raise SweepError(f"must be a string, got {desc!r}", file=file, key="description")
    n_cells = math.prod(len(a.values) for a in axes if not a.drawn) * \
        (draws.count if draws is not None and any(a.drawn for a in axes) else 1) * len(seeds)
    r = find("limits.sweep_cells")
    if r.impossible(n_cells):
        raise SweepError(f"{n_cells:g} cells (points x seeds), more than the {r.hard[1]:g} a "
                         f"sweep may hold ({r.source})", file=file, key="axes")
    return SweepSpec(path=file, scenario_path=scenario_path, scenario=sc, axes=tuple(axes),
                     seeds=seeds, draws=draws, method=method,
                     spec_deg=float(spec_deg),
                     rmse_window_cycles=window, description=desc)


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file, or a built-in sweep preset by name (module docstring);
    :class:`SweepError` on any fault."""
    path = scenario_file(path, "sweeps")
    try:
        d = load_toml(path)
    except InputError as exc:
        raise SweepError(exc.message, file=path) from None
    return sweep_from_dict(d, path, path.parent)

