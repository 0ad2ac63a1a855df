"""Experiments a chamber and a turntable can run, and what each costs.

An :class:`Experiment` is one start-up run the package can simulate and a chamber can run:
the unit soaked unpowered at a start temperature T0, powered on at t = 0, north-finding on
the turntable's schedule, with at most one *event* at ``event_s`` after power-on:

- ``power_off_s = S``: a power cycle, the unit off for S seconds while the chamber holds,
  then on again (a warm restart, :mod:`nfs.power`), ``cycles`` times, a cycle starting
  every ``every_s``; with ``power_off_2_s = S2``, two cycles whose second is off for S2;
- ``ramp_to_c = X`` at ``rate_c_per_min``: the chamber ramps to X and holds there;

and recording for ``duration_s`` from power-on (the off time included).  Its cost is the
time the chamber is busy: the soak at T0 (``soak_h``, the same for every experiment; a
unit soaked from room temperature needs hours) plus the run.

:class:`Space` is the grid a design searches (a few knobs: T0, the event and its size, the
run's length; the schedule of the runs already taken); the run's length is searched on the
simulated record itself, since a shorter run is a prefix of a longer one
(:mod:`nfs.design.search`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from ..chamber import parse_program
from ..errors import NfsError
from ..conditions import RunConditions
from ..ranges import TEMPERATURE_RANGE_C
from ..run import Run
from ..sensors import Schedule

__all__ = ["Experiment", "Space", "default_space", "base_conditions", "SOAK_H"]

#: Chamber hours of the soak before a run (a unit brought from room temperature to T0 and
#: left until its core follows: several of its slowest time constants).
SOAK_H = 3.0


@dataclass(frozen=True)
class Experiment:
    """One start-up run (module docstring)."""

    start_temperature_c: float
    """T0, the soak and start temperature [degC]."""
    duration_s: float
    """Record length from power-on [s], the off time included."""
    event: str = "none"
    """``none``, ``power_off`` or ``ramp``."""
    event_s: float = 3600.0
    """When the event starts, from power-on [s]."""
    power_off_s: float = 0.0
    """Off time of a power cycle [s]."""
    cycles: int = 1
    """Number of power cycles."""
    every_s: float = 1200.0
    """Time from one power cycle's switch-off to the next's [s]."""
    power_off_2_s: float | None = None
    """Off time of the second of two power cycles [s] (None: every cycle ``power_off_s``).
    Two off times in one run tell stored heat from a reset: a turn-on transient restarts
    whole after any off time, heat stored in the coil restarts by 1 - exp(-t_off / tau)
    (tau its radial time constant, 10-120 s), so the ratio of the two restarts differs."""
    ramp_to_c: float | None = None
    """Temperature a ramp ends at [degC]."""
    rate_c_per_min: float = 1.0
    """Ramp rate [K/min]."""
    soak_h: float = SOAK_H
    """Chamber hours of the soak before power-on."""
    dwell_s: float | None = None
    """Time at each turntable position [s]; None: the schedule of the runs taken."""

    def __post_init__(self) -> None:
        lo, hi = TEMPERATURE_RANGE_C
        if not lo <= self.start_temperature_c <= hi:
            raise NfsError(f"experiment: start temperature {self.start_temperature_c:g} C "
                           f"outside {lo:g} to {hi:g} C")
        if self.event not in ("none", "power_off", "ramp"):
            raise NfsError(f"experiment: event must be none, power_off or ramp, got "
                           f"{self.event!r}")
        if self.event == "power_off" and not self.power_off_s > 0:
            raise NfsError("experiment: a power cycle needs power_off_s > 0")
        if self.event == "power_off" and self.cycles > 1 and not self.every_s > self.power_off_s:
            raise NfsError("experiment: power cycles must start every_s > power_off_s apart")
        if self.event == "ramp" and (self.ramp_to_c is None or not self.rate_c_per_min > 0):
            raise NfsError("experiment: a ramp needs ramp_to_c and rate_c_per_min > 0")
        if self.event == "ramp" and not lo <= self.ramp_to_c <= hi:
            raise NfsError(f"experiment: a ramp to {self.ramp_to_c:g} C leaves the chamber's "
                           f"{lo:g} to {hi:g} C")
        if not self.duration_s > 0:
            raise NfsError(f"experiment: duration_s must be > 0, got {self.duration_s:g}")
        if self.dwell_s is not None and not self.dwell_s > 0:
            raise NfsError(f"experiment: dwell_s must be > 0, got {self.dwell_s:g}")
        if self.event == "power_off" and (isinstance(self.cycles, bool) or self.cycles < 1):
            raise NfsError(f"experiment: cycles must be >= 1, got {self.cycles!r}")
        if self.power_off_2_s is not None and not (
                self.event == "power_off" and self.cycles == 2 and self.power_off_2_s > 0
                and self.every_s > self.power_off_2_s):
            raise NfsError("experiment: power_off_2_s is the second of two power cycles: "
                           "event power_off, cycles = 2, 0 < power_off_2_s < every_s")

    @property
    def event_end_s(self) -> float:
        """When the event ends, from power-on [s] (0 without one)."""
        if self.event == "power_off":
            return self.event_s + (self.cycles - 1) * self.every_s + self.off_times_s()[-1]
        if self.event == "ramp":
            return (self.event_s + abs(float(self.ramp_to_c) - self.start_temperature_c)
                    / self.rate_c_per_min * 60.0)
        return 0.0

    @property
    def hours(self) -> float:
        """Chamber hours: the soak plus the run."""
        return self.soak_h + self.duration_s / 3600.0

    def program(self) -> list[dict[str, float]]:
        """The chamber program (TOML steps of :mod:`nfs.chamber`), from power-on."""
        if self.event == "none":
            return [{"hold_s": float(self.duration_s)}]
        steps: list[dict[str, float]] = [{"hold_s": float(self.event_s)}]
        if self.event == "power_off":
            offs = self.off_times_s()
            for k, off in enumerate(offs):  # written out: a top-level repeat would make
                if k:                          # the program's "cycles" (nfs.chamber)
                    steps.append({"hold_s": float(self.every_s - offs[k - 1])})
                steps.append({"power_off_s": float(off)})
            used = self.event_end_s
        else:
            steps.append({"ramp_to_c": float(self.ramp_to_c),
                          "rate_c_per_min": float(self.rate_c_per_min)})
            used = (self.event_s + abs(float(self.ramp_to_c) - self.start_temperature_c)
                    / self.rate_c_per_min * 60.0)
        rest = self.duration_s - used
        if rest > 0:
            steps.append({"hold_s": float(rest)})
        return steps

    def off_times_s(self) -> tuple[float, ...]:
        """The off time of each power cycle, in order [s]."""
        offs = [float(self.power_off_s)] * self.cycles
        if self.power_off_2_s is not None:
            offs[1] = float(self.power_off_2_s)
        return tuple(offs)

    def off_spans_s(self) -> tuple[tuple[float, float], ...]:
        """(switched off, switched on again) of every power cycle, from power-on [s], read
        from the program as the simulator reads it."""
        prog = parse_program(self.program(), file=None, key="design.program")
        return prog.power_off_spans_s(self.start_temperature_c, 1.0)

    def describe(self) -> str:
        """The run in words."""
        head = (f"soak at {self.start_temperature_c:g} C, power on, north-find for "
                f"{self.duration_s / 3600.0:.3g} h"
                + ("" if self.dwell_s is None else f" with dwells of {self.dwell_s:g} s"))
        if self.event == "power_off":
            off = _off_words(self.power_off_s)
            if self.power_off_2_s is not None:
                return (head + f"; at {self.event_s / 60.0:.0f} min switch the unit off for "
                        f"{off}, then on again; {self.every_s / 60.0:.0f} min later off for "
                        f"{_off_words(self.power_off_2_s)}, then on again (chamber holding)")
            if self.cycles > 1:
                return (head + f"; from {self.event_s / 60.0:.0f} min, {self.cycles} power "
                        f"cycles {self.every_s / 60.0:.0f} min apart: the unit off for {off}, "
                        "then on again (chamber holding)")
            return (head + f"; at {self.event_s / 60.0:.0f} min switch the unit off for "
                    f"{off}, then on again (chamber holding)")
        if self.event == "ramp":
            return (head + f"; at {self.event_s / 60.0:.0f} min ramp the chamber to "
                    f"{self.ramp_to_c:g} C at {self.rate_c_per_min:g} K/min and hold")
        return head + " (chamber holding T0)"

    def with_duration(self, duration_s: float) -> "Experiment":
        return replace(self, duration_s=float(duration_s))

    def schedule(self, base: Schedule) -> Schedule:
        """The turntable schedule: ``base`` with this experiment's dwell."""
        return base if self.dwell_s is None else replace(base, dwell_s=float(self.dwell_s))

    def conditions(self, base: RunConditions, name: str = "designed") -> RunConditions:
        """The run's :class:`~nfs.experiment.RunConditions`: ``base``'s site, heading,
        schedule (this experiment's dwell) and sample rate, this experiment's chamber and
        power."""
        prog = parse_program(self.program(), file=None, key="design.program")
        fs = base.sample_rate_hz
        return RunConditions(
            name=name, start_temperature_c=self.start_temperature_c,
            latitude_deg=base.latitude_deg, true_heading_deg=base.true_heading_deg,
            schedule=self.schedule(base.schedule), duration_s=float(self.duration_s), sample_rate_hz=fs,
            seed=base.seed, chamber_c=prog.ambient(self.start_temperature_c, 1.0 / fs),
            power_off_s=prog.power_off_spans_s(self.start_temperature_c, 1.0 / fs))

    def to_dict(self) -> dict[str, Any]:
        out = {"start_temperature_c": self.start_temperature_c,
               "duration_s": self.duration_s, "event": self.event, "hours": self.hours,
               "soak_h": self.soak_h, "program": self.program(),
               "description": self.describe()}
        if self.event != "none":
            out["event_s"] = self.event_s
        if self.event == "power_off":
            out.update(power_off_s=self.power_off_s, cycles=self.cycles,
                       every_s=self.every_s)
            if self.power_off_2_s is not None:
                out.update(power_off_2_s=self.power_off_2_s)
        if self.event == "ramp":
            out.update(ramp_to_c=self.ramp_to_c, rate_c_per_min=self.rate_c_per_min)
        if self.dwell_s is not None:
            out["dwell_s"] = self.dwell_s
        return out


@dataclass(frozen=True)
class Space:
    """The grid of experiments a design searches."""

    start_temperatures_c: tuple[float, ...]
    """T0 values."""
    power_off_s: tuple[float, ...] = (60.0, 300.0, 1800.0)
    """Off times of the power cycles tried [s]: 1 min, and long enough for the unit to cool
    (5 and 30 min).  (Single cycles of 10-30 s, tried, let the search take a 10 s cycle
    that separates a transient from a rate term and leaves heat in the coil tied with them;
    the short off times are in :attr:`off_pairs_s`.)"""
    off_pairs_s: tuple[tuple[float, float], ...] = ((20.0, 120.0),)
    """Two power cycles of different off times in one run [s] (the first, the second):
    around the coil's radial time constant (10-120 s), stored heat restarts by
    1 - exp(-t_off / tau) after each, a turn-on transient whole after both."""
    cycles: tuple[int, ...] = (1, 4)
    """Numbers of power cycles tried (a cycle every :attr:`every_s`)."""
    every_s: float = 1200.0
    """Time between the switch-offs of repeated power cycles [s]."""
    ramps_k: tuple[float, ...] = (-20.0, 20.0)
    """Chamber ramps tried, as steps from T0 [K] (within the chamber's range)."""
    rate_c_per_min: float = 1.0
    """Rate of the ramps [K/min]."""
    event_s: float = 3600.0
    """When the event starts, from power-on [s]."""
    max_duration_s: float = 14400.0
    """The longest record tried [s]; shorter ones are its prefixes, every
    ``duration_step_s``."""
    duration_step_s: float = 600.0
    """Step of the record lengths tried [s]."""
    min_duration_s: float = 0.0
    """The shortest record [s]: two north-finding cycles of the schedule, so that the run
    has a start-up and a later stage to tabulate (``nfs table``)."""
    schedule: Schedule | None = None
    """The schedule of the runs taken; with it, a record holds at least two north-finding
    cycles of the experiment's own dwell too."""
    soak_h: float = SOAK_H
    """Soak hours charged to every run."""

    def durations_s(self, exp: "Experiment") -> np.ndarray:
        """The record lengths tried for ``exp`` [s]: every step from the end of its event
        (plus a step: a run must see the unit after it) up to the longest."""
        end = exp.event_end_s
        first = self.duration_step_s * (math.floor(end / self.duration_step_s) + 1)
        shortest = self.min_duration_s
        if self.schedule is not None:
            shortest = max(shortest, 2.0 * exp.schedule(self.schedule).cycle_s)
        first = max(first, self.duration_step_s * math.ceil(shortest / self.duration_step_s
                                                             - 1e-9))
        return np.arange(first, self.max_duration_s + 1e-9, self.duration_step_s)

    def experiments(self) -> list[Experiment]:
        """Every experiment of the grid at the longest duration (shorter ones are prefixes)."""
        longest = self.max_duration_s
        lo, hi = TEMPERATURE_RANGE_C
        out = []
        for t0 in self.start_temperatures_c:
            out.append(Experiment(t0, longest, soak_h=self.soak_h))
            for off in self.power_off_s:
                for n in self.cycles:
                    if n > 1 and off >= self.every_s:
                        continue
                    out.append(Experiment(t0, longest, "power_off", self.event_s, off,
                                          cycles=n, every_s=self.every_s,
                                          soak_h=self.soak_h))
            for first, second in self.off_pairs_s:
                if max(first, second) < self.every_s:
                    out.append(Experiment(t0, longest, "power_off", self.event_s, first,
                                          cycles=2, every_s=self.every_s,
                                          power_off_2_s=second, soak_h=self.soak_h))
            for dk in self.ramps_k:
                to = float(np.clip(t0 + dk, lo, hi))
                if to != t0:
                    out.append(Experiment(t0, longest, "ramp", self.event_s, ramp_to_c=to,
                                          rate_c_per_min=self.rate_c_per_min,
                                          soak_h=self.soak_h))
        # an event that ends after the longest run, or leaves no run length to try, is
        # no experiment of this space
        return [e for e in out if e.event_end_s < longest and self.durations_s(e).size]


def _off_words(off_s: float) -> str:
    """An off time in words (minutes from one minute up)."""
    return f"{off_s / 60.0:.3g} min" if off_s >= 60.0 else f"{off_s:.0f} s"


def default_space(runs: Sequence[Run], *, soak_h: float = SOAK_H) -> Space:
    """The default grid for ``runs``: T0 at the coldest, the middle and the hottest start
    temperature the runs took (the rivals are fitted there); one hour after power-on one or
    four power cycles of 1, 5 or 30 min off (20 min apart), two cycles of 20 s and 2 min
    off, or a chamber ramp of +-20 K at 1 K/min; runs of up to 4 h in steps of 10 min."""
    t0s = sorted({float(r.meta.start_temperature_c) for r in runs})
    if not t0s:
        raise NfsError("a design needs the runs already taken (none given)")
    picks = [t0s[0], t0s[len(t0s) // 2], t0s[-1]]
    temps = tuple(dict.fromkeys(round(t, 6) for t in picks))
    schedule = base_conditions(runs).schedule
    return Space(start_temperatures_c=temps, soak_h=soak_h,
                 min_duration_s=2.0 * schedule.cycle_s, schedule=schedule)


def base_conditions(runs: Sequence[Run]) -> RunConditions:
    """The site, heading, schedule and sample rate of the runs taken (the first run's
    metadata), for the proposed run."""
    if not runs:
        raise NfsError("a design needs the runs already taken (none given)")
    m = runs[0].meta
    pos = tuple(m.positions_deg) if m.positions_deg else (0.0,)
    t = np.asarray(runs[0]["time_s"], dtype=float)
    fs = m.sample_rate_hz or (1.0 / float(np.median(np.diff(t))) if t.size > 1 else 1.0)
    return RunConditions(name="designed", start_temperature_c=m.start_temperature_c,
                         latitude_deg=m.latitude_deg,
                         true_heading_deg=m.true_heading_deg or 0.0,
                         schedule=Schedule(pos, m.dwell_s or 1.0, m.move_s or 0.0),
                         sample_rate_hz=fs)
