"""The scenario: a start-up experiment as data (instrument, start temperatures, schedule,
chamber, north-finding settings, variability between start-ups and units, compensation
settings). Scenario files are read by :mod:`nfs.config.scenario`."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from .chamber import ChamberProgram
from .docfields import document_fields
from .errors import NfsError
from .conditions import RunConditions
from .instrument import Instrument
from .sensors import Schedule
from .variability import NO_VARIABILITY, Variability, unit_instrument

__all__ = ["NorthFindSettings", "ChamberProfile", "Scenario"]


@document_fields
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
    (:mod:`nfs.northfind.time_to_spec`); 0.02 deg is about the uncompensated start-up RMSE of the FOG
    start-up paper ("A FOG start-up drift compensation method at full temperatures", Table 3)."""


@document_fields
@dataclass(frozen=True)
class ChamberProfile:
    """Chamber air temperature T_amb(t) = P(t) + ripple_c sin(2 pi t / ripple_period_s),
    t from power-on, P the program (:mod:`nfs.chamber`) or T0 without one."""

    ripple_c: float = 0.0
    """Amplitude of the chamber control ripple [K]."""
    ripple_period_s: float = 600.0
    """Period of the ripple [s]."""
    program: ChamberProgram | None = None
    """The chamber program from each T0; None holds T0."""

    def ambient(self, start_temperature_c: float, sample_s: float = 1.0):
        """T_amb(t) as a function of time from power-on [s] (negative during a program's
        unpowered soak) [degC], or None when the chamber holds T0.  ``sample_s``: the
        sample interval, over which a program's steps are taken."""
        if self.ripple_c == 0.0 and self.program is None:
            return None
        t0 = start_temperature_c
        base = (self.program.ambient(t0, sample_s) if self.program is not None
                else lambda t: np.full(np.shape(t), float(t0)))
        if self.ripple_c == 0.0:
            return base
        a, p = self.ripple_c, self.ripple_period_s
        return lambda t: base(t) + a * np.sin(2.0 * np.pi * np.asarray(t) / p)

    def soak_s(self, start_temperature_c: float, sample_s: float = 1.0) -> float:
        """Time the program runs before power-on, the unit unpowered [s] (0 without)."""
        if self.program is None:
            return 0.0
        return self.program.power_on_s(start_temperature_c, sample_s)

    def power_off_s(self, start_temperature_c: float, sample_s: float = 1.0
                    ) -> tuple[tuple[float, float], ...]:
        """The program's power cycles: (switched off, on again) from power-on [s]."""
        if self.program is None:
            return ()
        return self.program.power_off_spans_s(start_temperature_c, sample_s)

    def powered_s(self, start_temperature_c: float, sample_s: float = 1.0) -> float | None:
        """Length of the program from power-on [s]; None without a program."""
        if self.program is None:
            return None
        return self.program.powered_s(start_temperature_c, sample_s)


@document_fields
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
    duration_s: float | None = 9000.0
    """Length of each run from power-on [s]; None: as long as the chamber program after
    power-on (:meth:`run_duration_s`)."""
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
    """:class:`~nfs.compensate.settings.CompensationSettings` of ``[compensation]`` (defaults
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

    def run_duration_s(self, start_temperature_c: float) -> float:
        """Length of the runs at ``start_temperature_c`` from power-on [s]."""
        if self.duration_s is not None:
            return self.duration_s
        return self.chamber.powered_s(start_temperature_c, 1.0 / self.sample_rate_hz)

    @property
    def unit_ids(self) -> tuple[int, ...]:
        """The units that make the start-ups, in turn."""
        return tuple(range(self.units)) if self.run_units is None else tuple(self.run_units)

    def unit_instrument(self, unit: int = 0) -> Instrument:
        """The instrument unit ``unit`` is: the scenario's instrument with every parameter
        that scatters from unit to unit drawn once (:func:`nfs.variability.unit_instrument`),
        or the instrument itself when units do not differ.

        It is the instrument each run of the unit was simulated with (the
        :attr:`~nfs.experiment.SimulationResult.instrument` of its runs), so it holds the
        values a fit of the unit's runs should find: ``nfs simulate`` writes it beside the
        runs as ``unit_00.toml``, ``unit_01.toml``, ... (:meth:`drawn_units`).
        """
        if not 0 <= unit < self.units:
            raise NfsError(f"unit {unit}: scenario '{self.name}' has units 0..{self.units - 1}")
        var = self.variability
        return unit_instrument(self.instrument, var, unit) if var.per_unit else self.instrument

    def drawn_units(self) -> dict[int, Instrument]:
        """{unit: :meth:`unit_instrument`} of the units that make this scenario's start-ups
        (each once, in the order of their first start-up: with fewer ``repeats`` than
        units, some units make none)."""
        made = [self.unit_ids[r % len(self.unit_ids)] for r in range(self.repeats)]
        return {u: self.unit_instrument(u) for u in dict.fromkeys(made)}

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
        units = self.unit_ids
        var = self.variability if self.variability.active else None
        out = []
        sample_s = 1.0 / self.sample_rate_hz
        for i, t0 in enumerate(self.start_temperatures_c):
            for r in range(self.repeats):
                u, k = units[r % len(units)], r // len(units)
                out.append(RunConditions(
                    name=self.run_name(i, k, u), start_temperature_c=t0,
                    latitude_deg=self.latitude_deg, true_heading_deg=self.true_heading_deg,
                    schedule=self.schedule, duration_s=self.run_duration_s(t0),
                    sample_rate_hz=self.sample_rate_hz,
                    seed=(self.seed, i, k) if u == 0 else (self.seed, i, k, u),
                    chamber_c=self.chamber.ambient(t0, sample_s), unit=u, variability=var,
                    soak_s=self.chamber.soak_s(t0, sample_s),
                    power_off_s=self.chamber.power_off_s(t0, sample_s)))
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
