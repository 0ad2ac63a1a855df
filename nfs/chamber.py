"""Chamber temperature programs: holds, ramps, steps and repeated cycles, read from TOML.

A program is the list ``program`` under ``[chamber]`` in a scenario file.  It starts at the
run's start temperature T0 (each entry of ``start_temperatures_c`` runs the program from its
own T0; the unit is soaked unpowered at T0 before the program starts) and its temperatures are
absolute [degC].  Steps, in order:

``{ hold_s = S }``
    hold the chamber where it is for S > 0 seconds;
``{ ramp_to_c = X, rate_c_per_min = R }``
    ramp linearly to X at R > 0 K/min (a magnitude: the direction is towards X), taking
    |X - T| / R minutes;
``{ ramp_to_c = X, over_s = S }``
    ramp linearly to X over S > 0 seconds;
``{ step_to_c = X }``
    jump to X: the air cannot jump, so the step is the steepest ramp the samples resolve,
    over one sample interval;
``{ repeat = N, steps = [...] }``
    the steps N >= 1 times in a row (nested repeats allowed); the iterations of the first
    repeat at the top level are the program's *cycles* (a study that trains on cycle 1 and
    tests on the others, :mod:`nfs.studies.cycle_study`);
``{ power_on = true }``
    the unit is powered on here (at most once, not inside a repeat).  The steps before it
    are the unpowered soak: simulated, not recorded.  The run, its time axis (t = 0 at
    power-on), its north-finding cycles and its recorded ``start_temperature_c`` (the
    chamber's temperature at power-on, where the unit was soaked) start here.  Without the
    marker the unit is powered at the program's start.
``{ power_off_s = S }``
    a power cycle (a warm restart): the unit is switched off for S > 0 seconds while the
    chamber holds, then on again.  Off, no heat is released inside the unit (its node
    powers and thermal effects are zero), the sensors record nothing (NaN) and the run's
    ``powered`` column is 0; at the restart every turn-on effect starts again from its
    power-on value (``turn_on_transient`` is a function of the time since the latest
    power-on).  Allowed after power-on, also inside a repeat (repeated power cycles).

The chamber temperature is piecewise linear between the program's corners; the thermal
network is solved under it with a first-order hold (:func:`thermal.simulate`), exact when
the corners fall on samples (a rate ramp whose length is not a whole number of sample
intervals has one corner between two samples, where the hold's chord differs from the
corner by at most rate x interval / 4).

Every value is checked before anything runs: unknown keys, a missing or non-positive rate or
time, a negative rate (a ramp the wrong way would never reach its target), non-finite values,
temperatures outside :data:`TEMPERATURE_RANGE_C`, and every value against its range in
:mod:`nfs.ranges` (a hold of more than 1e7 s, a ramp faster than 60 K/min, a program of more
steps than ``limits.program_steps``, checked before its repeats are expanded; an unusual value
warns); the error names the file and the step
(``chamber.program[2].steps[0].rate_c_per_min``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import ScenarioError
from .ranges import KELVIN_OFFSET, TEMPERATURE_RANGE_C, check, check_tree, find

__all__ = ["ChamberStep", "ChamberProgram", "parse_program", "TEMPERATURE_RANGE_C",
           "check_temperature"]

# TEMPERATURE_RANGE_C: chamber and start temperatures accepted [degC] (nfs.ranges: climatic
# chambers span about -70 to +150 C; a value outside is most likely a unit mistake, kelvin).

_KEYS = {
    "hold": ("hold_s",),
    "ramp": ("ramp_to_c", "rate_c_per_min", "over_s"),
    "step": ("step_to_c",),
    "repeat": ("repeat", "steps"),
    "power_on": ("power_on",),
    "power_off": ("power_off_s",),
}
_KIND_OF = {"hold_s": "hold", "ramp_to_c": "ramp", "step_to_c": "step", "repeat": "repeat",
            "power_on": "power_on", "power_off_s": "power_off"}


#: Steps during which the chamber holds its temperature.
_HOLDS = ("hold", "power_off")


@dataclass(frozen=True)
class ChamberStep:
    """One hold, ramp or step of a program (repeats expanded)."""

    kind: str
    """"hold", "ramp", "step" or "power_off" (a hold with the unit switched off)."""
    target_c: float | None = None
    """Temperature the ramp or step ends at [degC]; None for a hold."""
    duration_s: float | None = None
    """Length of a hold, a power-off or a ramp given ``over_s`` [s]; None otherwise."""
    rate_c_per_s: float | None = None
    """Ramp rate magnitude [K/s] (``rate_c_per_min`` / 60); None otherwise."""

    def length_s(self, from_c: float, sample_s: float) -> float:
        """Time the step takes from the chamber temperature ``from_c`` [s]."""
        if self.kind == "step":
            return sample_s if self.target_c != from_c else 0.0
        if self.rate_c_per_s is not None:
            return abs(self.target_c - from_c) / self.rate_c_per_s
        return float(self.duration_s)


@dataclass(frozen=True)
class ChamberProgram:
    """A chamber program: its steps in order and where the unit is powered on."""

    steps: tuple[ChamberStep, ...]
    """The steps, repeats expanded."""
    power_on_index: int = 0
    """Number of steps before power-on (0: powered from the start)."""
    cycles: tuple[tuple[int, int], ...] = ()
    """The iterations of the first top-level repeat: (first step, one past the last step)
    indices into :attr:`steps`; empty without a top-level repeat."""

    def step_times_s(self, start_c: float, sample_s: float) -> np.ndarray:
        """Start time of every step and the end of the last, from power-on [s], shape
        (n_steps + 1,)."""
        t, now = [0.0], float(start_c)
        for s in self.steps:
            t.append(t[-1] + s.length_s(now, sample_s))
            now = now if s.kind in _HOLDS else float(s.target_c)
        t = np.array(t)
        return t - t[self.power_on_index]

    def cycle_spans_s(self, start_c: float, sample_s: float) -> list[tuple[float, float]]:
        """(start, end) of every cycle from power-on [s] (:attr:`cycles`)."""
        t = self.step_times_s(start_c, sample_s)
        return [(float(t[a]), float(t[b])) for a, b in self.cycles]

    def corners(self, start_c: float, sample_s: float) -> tuple[np.ndarray, np.ndarray]:
        """(time from the program's start [s], chamber temperature [degC]) at every corner;
        the temperature is linear between them and holds the last value after the end."""
        times, temps = [0.0], [float(start_c)]
        for s in self.steps:
            now = temps[-1]
            dt = s.length_s(now, sample_s)
            if dt == 0.0:
                continue
            times.append(times[-1] + dt)
            temps.append(now if s.kind in _HOLDS else float(s.target_c))
        return np.array(times), np.array(temps)

    def power_off_spans_s(self, start_c: float, sample_s: float
                          ) -> tuple[tuple[float, float], ...]:
        """(switched off, switched on again) of every power cycle, from power-on [s]."""
        t = self.step_times_s(start_c, sample_s)
        return tuple((float(t[i]), float(t[i + 1])) for i, s in enumerate(self.steps)
                     if s.kind == "power_off")

    def power_on_s(self, start_c: float, sample_s: float) -> float:
        """Time of power-on from the program's start [s]."""
        pre = ChamberProgram(self.steps[:self.power_on_index])
        return float(pre.corners(start_c, sample_s)[0][-1])

    def powered_s(self, start_c: float, sample_s: float) -> float:
        """Length of the program from power-on to its end [s]."""
        return float(self.corners(start_c, sample_s)[0][-1]) - self.power_on_s(start_c,
                                                                                sample_s)

    def ambient(self, start_c: float, sample_s: float):
        """T_amb(t) [degC] with t from power-on [s] (negative during the soak), vectorised."""
        t_c, temp_c = self.corners(start_c, sample_s)
        t_c = t_c - self.power_on_s(start_c, sample_s)
        return lambda t: np.interp(np.asarray(t, dtype=float), t_c, temp_c)


def check_temperature(value: float, file: Any, key: str) -> None:
    """ScenarioError unless ``value`` lies in :data:`TEMPERATURE_RANGE_C` (a hint when it
    looks like kelvin)."""
    lo, hi = TEMPERATURE_RANGE_C
    if lo <= value <= hi:
        return
    hint = (f" (Kelvin? {value:g} K is {value - KELVIN_OFFSET:.2f} C)"
            if lo <= value - KELVIN_OFFSET <= hi else "")
    raise ScenarioError(f"{value:g} C is outside the chamber range {lo:g} .. {hi:+g} C"
                        f"{hint}", file=file, key=key)


def _finite(step: dict, key: str, where: str, file: Any) -> float:
    v = step[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ScenarioError(f"must be a finite number, got {v!r}", file=file,
                            key=f"{where}.{key}")
    return float(v)


def _positive(step: dict, key: str, where: str, file: Any, what: str) -> float:
    v = _finite(step, key, where, file)
    if v <= 0.0:
        raise ScenarioError(f"must be > 0, got {v:g}: {what}", file=file, key=f"{where}.{key}")
    return v


def _one(step: Any, where: str, file: Any, top: bool) -> list[ChamberStep] | str:
    """The steps of one program entry (a list), or "power_on" for the marker."""
    if not isinstance(step, dict) or not step:
        raise ScenarioError("must be a table such as { hold_s = 600.0 }, "
                            "{ ramp_to_c = 10.0, rate_c_per_min = 1.0 }, "
                            "{ ramp_to_c = 10.0, over_s = 900.0 }, { step_to_c = 10.0 }, "
                            "{ repeat = 2, steps = [...] }, { power_on = true } or "
                            "{ power_off_s = 600.0 }; "
                            f"got {step!r}", file=file, key=where)
    kinds = {_KIND_OF[k] for k in step if k in _KIND_OF}
    if len(kinds) != 1:
        what = ("names no step kind" if not kinds
                else f"mixes {' and '.join(sorted(kinds))}")
        raise ScenarioError(f"{what}: a step has exactly one of hold_s, ramp_to_c, "
                            "step_to_c, repeat, power_on, power_off_s", file=file, key=where)
    kind = kinds.pop()
    for k in step:
        if k not in _KEYS[kind]:
            raise ScenarioError(f"unknown key in a {kind} step; allowed: "
                                f"{', '.join(_KEYS[kind])}", file=file, key=f"{where}.{k}")
    if kind == "hold":
        return [ChamberStep("hold", duration_s=_positive(step, "hold_s", where, file,
                                                         "a hold lasts some time"))]
    if kind == "power_off":
        return [ChamberStep("power_off", duration_s=_positive(
            step, "power_off_s", where, file, "a power cycle is off for some time"))]
    if kind == "step":
        target = _finite(step, "step_to_c", where, file)
        check_temperature(target, file, f"{where}.step_to_c")
        return [ChamberStep("step", target_c=target)]
    if kind == "ramp":
        target = _finite(step, "ramp_to_c", where, file)
        check_temperature(target, file, f"{where}.ramp_to_c")
        has_rate, has_over = "rate_c_per_min" in step, "over_s" in step
        if has_rate == has_over:
            raise ScenarioError("a ramp takes exactly one of rate_c_per_min and over_s",
                                file=file, key=where)
        if has_over:
            return [ChamberStep("ramp", target_c=target,
                                duration_s=_positive(step, "over_s", where, file,
                                                     "a ramp over no time never ramps"))]
        rate = _positive(step, "rate_c_per_min", where, file,
                         "the rate is a magnitude (the ramp goes towards ramp_to_c); a "
                         "ramp at a rate <= 0 never reaches its target")
        return [ChamberStep("ramp", target_c=target, rate_c_per_s=rate / 60.0)]
    if kind == "power_on":
        if step["power_on"] is not True:
            raise ScenarioError(f"must be true (the unit is powered on here), got "
                                f"{step['power_on']!r}", file=file, key=f"{where}.power_on")
        if not top:
            raise ScenarioError("the unit is powered on once: power_on cannot be inside a "
                                "repeat", file=file, key=where)
        return "power_on"
    n = step["repeat"]
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ScenarioError(f"must be an integer >= 1, got {n!r}", file=file,
                            key=f"{where}.repeat")
    check("chamber.program.repeat", n, file=file, key=f"{where}.repeat", error=ScenarioError)
    if "steps" not in step:
        raise ScenarioError("required key is missing: a repeat needs its steps", file=file,
                            key=f"{where}.steps")
    inner = _steps(step["steps"], f"{where}.steps", file, top=False)[0]
    _check_length(len(inner) * n, f"{where}.repeat", file)
    return list(inner) * n


def _check_length(n_steps: int, key: str, file: Any) -> None:
    """A program's steps, repeats expanded, against ``limits.program_steps`` (checked before
    the repeats are expanded)."""
    r = find("limits.program_steps")
    if r.impossible(n_steps):
        raise ScenarioError(f"expands to {n_steps:g} steps, more than the {r.hard[1]:g} a "
                            f"program may hold ({r.source})", file=file, key=key)


def _steps(value: Any, where: str, file: Any, top: bool
           ) -> tuple[list[ChamberStep], int, list[tuple[int, int]]]:
    """(steps, number of steps before power-on (0 without a marker), the cycles of the
    first top-level repeat)."""
    if not isinstance(value, list) or not value:
        raise ScenarioError(f"must be a non-empty list of steps, got {value!r}", file=file,
                            key=where)
    out: list[ChamberStep] = []
    origin: list[int] = []     # the entry of ``value`` each expanded step came from
    power_on = None
    cycles: list[tuple[int, int]] = []
    for i, entry in enumerate(value):
        got = _one(entry, f"{where}[{i}]", file, top)
        if top and not cycles and isinstance(entry, dict) and "repeat" in entry and got:
            n_rep = int(entry["repeat"])
            size = len(got) // n_rep
            cycles = [(len(out) + k * size, len(out) + (k + 1) * size) for k in range(n_rep)]
        if got == "power_on":
            if power_on is not None:
                raise ScenarioError("the unit is powered on once: a second power_on",
                                    file=file, key=f"{where}[{i}]")
            power_on = len(out)
            continue
        out.extend(got)
        origin.extend([i] * len(got))
        _check_length(len(out), f"{where}[{i}]", file)
    off = [k for k, s in enumerate(out) if s.kind == "power_off"]
    if top and off and off[0] < (power_on or 0):
        raise ScenarioError("a power_off_s step before power_on: the unit is not on yet "
                            "(the steps before power_on are the unpowered soak)", file=file,
                            key=f"{where}[{origin[off[0]]}]")
    if power_on is not None and power_on == len(out):
        raise ScenarioError("power_on is the last step: nothing would be recorded",
                            file=file, key=where)
    if not out:
        raise ScenarioError("holds no hold, ramp or step", file=file, key=where)
    return out, power_on or 0, cycles


def parse_program(value: Any, file: Any, key: str = "chamber.program") -> ChamberProgram:
    """The :class:`ChamberProgram` of a TOML ``program`` list (module docstring);
    :class:`~nfs.errors.ScenarioError` naming ``file`` and the step otherwise."""
    steps, power_on, cycles = _steps(value, key, file, top=True)
    check_tree(value, file=file, error=ScenarioError, shown=key, canonical="chamber.program")
    if cycles and power_on > cycles[0][0]:
        raise ScenarioError("power_on comes after the start of the cycles (the first "
                            "repeat): the unit must be on for every cycle", file=file, key=key)
    return ChamberProgram(tuple(steps), power_on, tuple(cycles))
