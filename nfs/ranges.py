"""The one table of ranges: every value a user writes, its unit, what is impossible, what is usual.

Every number of an instrument, a scenario, a chamber program, a sweep and a measurement
sidecar has one :class:`Range` in :data:`RANGES`, found by its key path (:func:`find`):

hard
    physically impossible outside (a node cannot dissipate 7 kW inside a north finder, a
    thermometer cannot read below absolute zero): the loaders refuse the file, naming the
    file and the key, before any work;
typical
    what real units and experiments have (docs/physics.md's ranges, datasheet classes,
    standards): a value outside loads and runs with one warning line on stderr
    (:class:`RangeWarning`), since a design can differ from the default one;
slips
    the unit mistakes a value off by 1000, 60 or 273.15 most likely comes from: when the
    converted value is typical, the message says so ("7000 W ...; mW? (7 W)").

Key paths are the TOML key paths a user reads in the file (``thermal.nodes.board.power_w``,
``schedule.dwell_s``), with these canonical forms: an array of tables is named by what
identifies an entry (``effects.<effect name>.<parameter>`` for ``effects[3].k_r`` and
``added_effects[0].k_r``, ``thermal.links.<a>-<b>.conductance_w_per_k`` for a link between
``a`` and ``b``, ``chamber.program.<key>`` for a step at any depth of a program), a list of
numbers by its key (``start_temperatures_c``); a sweep's keys start with ``sweep.``, a
measurement sidecar's with ``measurement.``; ``limits.`` holds the derived quantities a
loader checks (samples per run, the steady-state rise of the network).  A pattern's ``*``
matches any name; the first matching entry wins, so specific entries come before generic
ones.  Every range is finite: a value of 1e300 is refused wherever it is written.

The module is long on purpose: the table is one list of about 140 entries, kept in one place
so that every loader, the presets' comments and the documentation read the same ranges.

This module imports nothing of the package but its errors: the loaders (:mod:`nfs.instrument`,
:mod:`nfs.config.scenario`, :mod:`nfs.chamber`, :mod:`nfs.sweep.definition`,
:mod:`nfs.io.measurement`) call :func:`check_tree` on what they parsed and :func:`check`
on derived values, inside :func:`deferred_warnings` so that a refused file shows its one
error and no warnings.  The comments of ``nfs/presets/default_instrument.toml`` state the
typical ranges of this table (tests/io/test_ranges.py checks that they agree).
"""

from __future__ import annotations

import contextvars
import fnmatch
import math
import re
import sys
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Iterator

from .errors import InputError

__all__ = ["Range", "RANGES", "RangeWarning", "find", "check", "check_tree", "leaves",
           "warn", "warn_unusual", "one_line_warnings", "deferred_warnings",
           "MAX_SAMPLES_PER_RUN", "TEMPERATURE_RANGE_C", "G_N_M_PER_S2", "KELVIN_OFFSET"]

#: 0 degC in kelvin (the offset of a temperature written in K).
KELVIN_OFFSET = 273.15

#: Standard acceleration of gravity g_n [m/s^2] (CGPM (1901)): a specific force written in
#: m/s^2 is 9.80665 times its value in g.
G_N_M_PER_S2 = 9.80665

#: Most samples one simulated run may hold, soak before power-on included: a run holds about
#: 1.3 kB per sample at its peak (1e6 samples: 1.3 GB and about a minute), so 2e6 samples
#: (23 days at 1 Hz, 2.3 days at 10 Hz) is the largest run a workstation is sure to allocate.
MAX_SAMPLES_PER_RUN = 2_000_000

@dataclass(frozen=True)
class Range:
    """The range of one value (or of every value whose key path matches :attr:`key`)."""

    key: str
    """Key path pattern (``*`` matches any name)."""
    unit: str
    """Unit as written in messages (``""`` for counts and ratios)."""
    hard: tuple[float, float]
    """Closed interval (low, high) outside which the value is physically impossible."""
    typical: tuple[float, float]
    """Closed interval (low, high) of what real units and experiments have."""
    what: str
    """Completes "{what} {typical range}" in messages: "a board dissipates"."""
    source: str
    """Where the ranges come from: a docs/physics.md section, a standard, a datasheet class."""
    slips: tuple[tuple[float, float, str], ...] = ()
    """Likely unit mistakes: (factor, offset, unit name): value * factor + offset is the
    value in :attr:`unit` if it was written in that unit."""
    low_open: bool = False
    """The hard low bound is excluded (``> 0``)."""
    magnitude: bool = False
    """Both ranges bound |value| (coefficients whose sign is set by a winding or a
    direction); the hard range is then (0, high) on |value|."""
    off: float | None = None
    """A value that switches the term off: never unusual (0 noise, 0 bias)."""
    integer: bool = False
    """The value is a count or a seed (an integer)."""

    # -- the checks

    def impossible(self, value: float) -> bool:
        """True when ``value`` lies outside :attr:`hard`."""
        v = abs(value) if self.magnitude else value
        lo, hi = self.hard
        if not math.isfinite(v):
            return True
        if self.magnitude:
            return v > hi
        return v < lo or v > hi or (self.low_open and v == lo)

    def unusual(self, value: float) -> bool:
        """True when ``value`` is possible but outside :attr:`typical`."""
        if self.off is not None and value == self.off:
            return False
        v = abs(value) if self.magnitude else value
        lo, hi = self.typical
        return not lo <= v <= hi

    def slip(self, value: float) -> str:
        """"; mW? (7 W)" when a unit mistake brings ``value`` into the typical range."""
        lo, hi = self.typical
        a = abs(value) if self.magnitude else value
        far = a > 5.0 * hi if hi > 0 else False
        far = far or (lo > 0 and a < lo / 5.0)
        for factor, offset, unit in self.slips:
            if offset == 0.0 and not far:      # a slip of 60 or 1000 lands far outside
                continue
            v = value * factor + offset
            if not self.unusual(v) and not self.impossible(v):
                return f"; {unit}? ({_num(v)}{_sp(self.unit)})"
        return ""

    # -- the words

    def typical_text(self) -> str:
        lo, hi = self.typical
        bar = "|x| " if self.magnitude else ""
        a, b = _num(lo), _num(hi)
        dash = "-" if lo >= 0 and "e" not in a + b else " to "
        return f"{bar}{a}{dash}{b}{_sp(self.unit)}"

    def hard_text(self) -> str:
        lo, hi = self.hard
        u = _sp(self.unit)
        if self.magnitude:
            return f"possible: |x| <= {_num(hi)}{u}"
        if self.low_open and lo == 0:
            return f"possible: > 0 and <= {_num(hi)}{u}"
        return f"possible: {_num(lo)} to {_num(hi)}{u}"

    def refusal(self, value: float) -> str:
        """The one-line message of an impossible ``value``."""
        return (f"{_num(value)}{_sp(self.unit)} is impossible ({self.hard_text()}); "
                f"{self.what} {self.typical_text()}{self.slip(value)}")

    def warning(self, value: float) -> str:
        """The one-line message of an unusual ``value``."""
        return (f"{_num(value)}{_sp(self.unit)} is unusual ({self.what} "
                f"{self.typical_text()}){self.slip(value)}; running anyway")


def _num(v: float) -> str:
    if isinstance(v, int) and not isinstance(v, bool):
        return str(v)
    return f"{v:g}"


def _sp(unit: str) -> str:
    return f" {unit}" if unit else ""


# ------------------------------------------------------------------------------------------
# The table

_PHYS = "docs/physics.md section"


def _R(key, unit, hard, typical, what, source, slips=(), **kw) -> Range:
    return Range(key, unit, tuple(map(float, hard)), tuple(map(float, typical)), what, source,
                 tuple(slips), **kw)


def _I(key, hard, typical, what, source) -> Range:
    return Range(key, "", hard, typical, what, source, integer=True)


# Unit mistakes, as (factor, offset, name): the value written times factor plus offset.
MINUTES = (60.0, 0.0, "minutes")            # 2.5 written for 150 s
HOURS = (3600.0, 0.0, "hours")
SECONDS_FOR_HOURS = (1.0 / 3600.0, 0.0, "seconds")
MINUTES_FOR_HOURS = (1.0 / 60.0, 0.0, "minutes")
KELVIN = (1.0, -KELVIN_OFFSET, "Kelvin")
FAHRENHEIT = (5.0 / 9.0, -160.0 / 9.0, "Fahrenheit")


def _k(unit):  # 3.5 written in kJ/K for 3500 J/K
    return (1000.0, 0.0, f"k{unit}")


def _m(unit):  # 7000 written in mW for 7 W
    return (1e-3, 0.0, f"m{unit}")


#: Chamber and start temperatures [degC]: climatic chambers span about -70 to +150 C
#: (IEC 60068-3-5; the test temperatures of IEC 60068-2-1 and -2-2 run from -65 to +155 C).
TEMPERATURE_RANGE_C = (-70.0, 150.0)
_TEMP_TYPICAL_C = (-55.0, 85.0)
_TEMP_SRC = ("IEC 60068-3-5 chambers (-70 to +150 C); north finders are specified and tested "
             "within -55 to +85 C (docs/physics.md section 1: -32 to 54 C)")


def _temperature(key, what="a start-up experiment starts at") -> Range:
    return _R(key, "C", TEMPERATURE_RANGE_C, _TEMP_TYPICAL_C, what, _TEMP_SRC,
              (KELVIN, FAHRENHEIT))


#: Dwell and move of a north-finding schedule [s]: docs/physics.md section 5 gives 60-180 s
#: and 5-15 s for the default design; calibration schedules (Liang et al. (2021): 595.5 s
#: dwells, 4.5 s moves at 20 deg/s) reach further.
_DWELL_S, _MOVE_S = (30.0, 600.0), (2.0, 30.0)
_DWELL_SRC = f"{_PHYS} 5: 60-180 s; calibration schedules up to 600 s"
_MOVE_SRC = f"{_PHYS} 5: 5-15 s; fast indexers 2 s"

_NODE_CAPACITY = {  # docs/physics.md section 2, default nodes (est.)
    "housing": ((2000, 4500), "a housing/base holds"),
    "electronics": ((100, 300), "FOG electronics with source and TEC hold"),
    "board": ((150, 400), "a main board with the turntable driver holds"),
    "coil_outer": ((40, 100), "a coil's outer layers hold"),
    "coil_inner": ((80, 200), "a coil's inner layers with the spool hold"),
    "spool": ((50, 200), "a coil's spool (an aluminium hub of 60-200 g) holds"),
    "qfa_x": ((30, 60), "a quartz flexure accelerometer holds"),
    "qfa_y": ((30, 60), "a quartz flexure accelerometer holds"),
}
_NODE_POWER = {
    "housing": ((0, 2), "a housing dissipates", "nothing of its own; a heater at most"),
    "electronics": ((2, 5), "FOG electronics dissipate", f"{_PHYS} 2"),
    "board": ((3, 8), "a main board dissipates", f"{_PHYS} 2"),
    "coil_outer": ((0, 0.5), "a coil dissipates", "the coil is passive (absorbed light only)"),
    "coil_inner": ((0, 0.5), "a coil dissipates", "the coil is passive (absorbed light only)"),
    "spool": ((0, 0.5), "a coil's spool dissipates", "the spool is passive"),
    "qfa_x": ((0.3, 0.6), "a quartz flexure accelerometer dissipates", f"{_PHYS} 2"),
    "qfa_y": ((0.3, 0.6), "a quartz flexure accelerometer dissipates", f"{_PHYS} 2"),
}
_CAP_HARD = (0.1, 1e6)          # a tenth of a gram of metal .. a tonne of aluminium
_POWER_HARD = (-50.0, 100.0)    # a sealed portable unit sheds tens of watts, not kilowatts
_G_HARD = (0.0, 1000.0)
_COMPONENT_LINK = ((0.3, 2.0), "a component's mount to the housing conducts",
                   f"{_PHYS} 2: components to housing 0.3-2 W/K")

_TABLE: list[Range] = [
    # ---------------------------------------------------------------- instrument
    _R("t_ref_c", "C", TEMPERATURE_RANGE_C, (15, 35), "a reference temperature is",
       "docs/effects.md: the room temperature a FOG is calibrated at (25 C)",
       (KELVIN, FAHRENHEIT)),
    *(_R(f"thermal.nodes.{n}.capacity_j_per_k", "J/K", _CAP_HARD, t, w,
         f"{_PHYS} 2 (est.)", (_k("J/K"),))
      for n, (t, w) in _NODE_CAPACITY.items()),
    _R("thermal.nodes.*.capacity_j_per_k", "J/K", _CAP_HARD, (10, 10000),
       "a node of a north finder holds", f"{_PHYS} 2: nodes of 30-4500 J/K",
       (_k("J/K"),)),
    *(_R(f"thermal.nodes.{n}.power_w", "W", _POWER_HARD, t, w, s, (_m("W"),), off=0.0)
      for n, (t, w, s) in _NODE_POWER.items()),
    _R("thermal.nodes.*.power_w", "W", _POWER_HARD, (0, 20), "a node dissipates",
       f"{_PHYS} 2: 0.3-8 W per component", (_m("W"),), off=0.0),
    _R("thermal.links.housing-chamber.conductance_w_per_k", "W/K", _G_HARD, (1, 5),
       "a housing conducts to the chamber", f"{_PHYS} 2 (est.)", (_m("W/K"),)),
    _R("thermal.links.coil_outer-coil_inner.conductance_w_per_k", "W/K", _G_HARD,
       (0.1, 0.4), "a coil conducts radially", f"{_PHYS} 2 (est.)", (_m("W/K"),)),
    *(_R(f"thermal.links.{a}-housing.conductance_w_per_k", "W/K", _G_HARD, *_COMPONENT_LINK,
         (_m("W/K"),))
      for a in ("electronics", "board", "coil_outer", "coil_inner", "spool", "qfa_x",
                "qfa_y")),
    _R("thermal.links.*.conductance_w_per_k", "W/K", _G_HARD, (0.01, 10),
       "a link inside a north finder conducts", f"{_PHYS} 2: links of 0.1-5 W/K",
       (_m("W/K"),), off=0.0),
    # the wound coil (docs/physics.md section 3, "the wound coil"; nfs/coil.py)
    _I("coil.layers", (1, 200), (4, 32), "a coil's thermal layers are",
       "a few to tens of shells resolve a winding's radial field (8 to 16 agree within 2 %)"),
    _R("coil.*_radius_m", "m", (0.001, 1.0), (0.025, 0.065), "a north finder's coil is wound at",
       f"{_PHYS} 3: D 60-120 mm", ((1e-3, 0.0, "mm"),), low_open=True),
    _R("coil.height_m", "m", (0.0005, 1.0), (0.005, 0.05), "a coil's winding is high",
       "navigation-grade coils: 10-30 mm (Lefevre (2014) ch. 3)", ((1e-3, 0.0, "mm"),),
       low_open=True),
    _R("coil.conductivity_w_per_m_k", "W/(m K)", (0.01, 50.0), (0.1, 1.0),
       "a potted fibre winding conducts across its layers",
       "fibre, acrylate and epoxy potting: 0.2-0.5 W/(m K) (Mohr (1996); Lefevre (2014))",
       low_open=True),
    _R("coil.heat_capacity_j_per_m3_k", "J/(m^3 K)", (1e5, 1e7), (1.2e6, 2.4e6),
       "a potted fibre winding holds per cubic metre",
       "silica 1.6e6, acrylate and epoxy 1.7-2.2e6 J/(m^3 K)", ((1e3, 0.0, "kJ/(m^3 K)"),),
       low_open=True),
    _R("coil.*_contacts.*", "W/K", _G_HARD, (0.01, 10), "a coil's face conducts to its mount",
       f"{_PHYS} 2: links of 0.1-5 W/K", (_m("W/K"),), off=0.0),
    _R("gyro.bias_dph", "deg/h", (0, 500), (0, 1), "a north finder's FOG has a bias of",
       "IEEE Std 952-2020; FOG north finders: navigation/tactical grade, below 1 deg/h",
       magnitude=True),
    _R("gyro.scale_factor", "", (0.5, 2.0), (0.99, 1.01),
       "the output is calibrated in deg/h: K0 is",
       "docs/measurement-format.md: gyro_dph in deg/h; a calibrated scale factor within 1 %"),
    _R("gyro.arw_deg_per_rth_h", "deg/sqrt(h)", (0, 10), (0.0003, 0.001),
       "angle random walk of a north finder's FOG is", f"{_PHYS} 3 (IEEE Std 952-2020)",
       off=0.0),
    _R("gyro.bias_instability_dph", "deg/h", (0, 100), (0.002, 0.005),
       "bias instability of a north finder's FOG is", f"{_PHYS} 3 (IEEE Std 952-2020)",
       off=0.0),
    _R("gyro.rrw_deg_per_h_per_rth_h", "deg/h/sqrt(h)", (0, 100), (0, 0.01),
       "rate random walk of a north finder's FOG is",
       f"{_PHYS} 3 (IEEE Std 952-2020: far below the bias instability over hours)"),
    _R("accelerometers.noise_ug_per_rth_hz", "ug/sqrt(Hz)", (0, 1e5), (10, 40),
       "a quartz flexure accelerometer's noise is",
       f"{_PHYS} 4: about 20 ug/sqrt(Hz) (IEEE Std 1293-2018)",
       ((1e6, 0.0, "g/sqrt(Hz)"), (1e3, 0.0, "mg/sqrt(Hz)")), off=0.0),
    _R("accelerometers.bias_*_g", "g", (0, 0.1), (0, 0.004),
       "a quartz flexure accelerometer's bias is",
       "QFA datasheet class: bias below 4 mg (IEEE Std 1293-2018)",
       ((1e-6, 0.0, "ug"), (1e-3, 0.0, "mg")), magnitude=True),
    _R("turntable.tilt_*_deg", "deg", (0, 10), (0, 0.1), "a levelled turntable is tilted by",
       f"{_PHYS} 4: a levelled table, a few arc-minutes at most",
       ((1 / 60, 0.0, "arc-minutes"), (1 / 3600, 0.0, "arc-seconds")), magnitude=True),
    _R("thermometers.*.nodes.*", "", (0, 1e3), (0, 1e3), "a thermometer's node weight is",
       "weights are relative (normalised by their sum)", low_open=True),
    _R("thermometers.*.lag_s", "s", (0, 3600), (10, 60), "a built-in thermometer lags by",
       f"{_PHYS} 2: tau 10-60 s", (MINUTES,), off=0.0),
    _R("thermometers.*.offset_c", "K", (0, 20), (0, 0.5), "a thermometer's offset is",
       "IEC 60751 class A/B platinum sensors: 0.15-0.8 K", ((1e-3, 0.0, "mK"),),
       magnitude=True),
    _R("thermometers.*.noise_c", "K", (0, 5), (0.005, 0.02), "a thermometer's noise is",
       f"{_PHYS} 2", ((1e-3, 0.0, "mK"),), off=0.0),
    _R("thermometers.*.quantum_c", "K", (0, 1), (0.01, 0.0625),
       "a thermometer's resolution is", f"{_PHYS} 2", ((1e-3, 0.0, "mK"),), off=0.0),
    _R("aux.*", "channel units", (0, 1e9), (0, 1e9), "an auxiliary channel's value is",
       "any electrical unit; beyond 1e9 no logger writes it", magnitude=True),
    # effects (docs/effects.md; docs/physics.md sections 2-4 and 7)
    _R("effects.tec_power.T_set", "C", TEMPERATURE_RANGE_C, (15, 35),
       "a TEC holds a light source at", f"{_PHYS} 2: about 25 C", (KELVIN,)),
    _R("effects.tec_power.c_h", "W/K", (0, 1), (0.02, 0.04),
       "a TEC draws per kelvin below its set point", f"{_PHYS} 2 (est.)", (_m("W/K"),),
       off=0.0),
    _R("effects.tec_power.c_c", "W/K", (0, 1), (0.05, 0.1),
       "a TEC draws per kelvin above its set point", f"{_PHYS} 2 (est.)", (_m("W/K"),),
       off=0.0),
    _R("effects.bias_temperature.b1", "deg/h/K", (0, 1), (0.0005, 0.003),
       "a FOG's bias slope is", f"{_PHYS} 3 (magnitude)", magnitude=True, off=0.0),
    _R("effects.bias_temperature.b2", "deg/h/K^2", (0, 0.1), (0, 1e-4),
       "a FOG's bias curvature is", f"{_PHYS} 3: small against b1 over -40..85 C",
       magnitude=True),
    _R("effects.shupe_gradient.k_r", "deg/h per K/min", (0, 100), (0.1, 1),
       "a Shupe radial coefficient is", f"{_PHYS} 3 (magnitude; Shupe (1980))",
       magnitude=True, off=0.0),
    _R("effects.shupe_rate.k_s", "deg/h per K/min", (0, 100), (0, 1),
       "a winding-imperfection Shupe coefficient is", f"{_PHYS} 3: at most k_r's 0.1-1",
       magnitude=True),
    _R("effects.shupe_stress.k_m", "deg/h per K/min", (0, 100), (0, 1),
       "a Shupe-Mohr stress coefficient is", f"{_PHYS} 3: with k_r within 0.1-1 (Mohr (1996))",
       magnitude=True),
    _R("effects.shupe_stress.c_m", "1/K", (-1 / 35, 1 / 65), (-0.02, 0.01),
       "a potting modulus changes per kelvin by",
       "the effect's own bound: 1 + c_m (T - 25) > 0 over -40..90 C"),
    _R("effects.shupe_winding.L", "m", (1, 1e5), (500, 2000), "a north finder's coil holds",
       f"{_PHYS} 3: L 0.5-2 km", ((1e3, 0.0, "km"),)),
    _R("effects.shupe_winding.D", "m", (0.005, 2), (0.06, 0.12),
       "a north finder's coil has a mean diameter of", f"{_PHYS} 3: D 60-120 mm",
       ((1e-3, 0.0, "mm"),)),
    _I("effects.shupe_winding.N_opt", (1, 10000), (8, 200), "a coil's optical layers are",
       "navigation-grade coils: tens of layers (Lefevre (2014) ch. 3)"),
    _R("effects.shupe_winding.n", "", (1.0, 2.0), (1.44, 1.48),
       "a silica fibre's mode index is", "fused silica 1.444 at 1550 nm, 1.447 at 1310 nm "
       "(Malitson (1965)); the mode's effective index 1.44-1.47"),
    _R("effects.shupe_winding.dn_dT", "1/K", (0, 1e-3), (7e-6, 1.3e-5),
       "a silica fibre's dn/dT is", "fused silica 0.95-1.1e-5 /K near room temperature "
       "(Leviton and Frey (2006))", magnitude=True),
    _R("effects.shupe_winding.alpha", "1/K", (0, 1e-4), (3e-7, 7e-7),
       "a silica fibre expands per kelvin by", "fused silica 5.5e-7 /K (Corning 7980)",
       magnitude=True),
    _R("effects.shupe_winding.k_m", "1/K", (0, 1e-3), (0, 5e-5),
       "a potted winding's stress-optic coefficient is",
       "Mohr (1996): the elasto-optic term up to a few times dn/dT", magnitude=True),
    _R("effects.shupe_winding.c_m", "1/K", (-1 / 35, 1 / 65), (-0.02, 0.01),
       "a potting modulus changes per kelvin by",
       "the effect's own bound: 1 + c_m (T - 25) > 0 over -40..90 C"),
    _R("effects.shupe_winding.L_asym", "m", (0, 1000), (0, 1),
       "a winding's asymmetric length is",
       "a midpoint placed within centimetres (Lefevre (2014) ch. 3)", magnitude=True),
    _R("effects.shupe_product.k_p", "deg/h per K*K/min", (0, 10), (0, 0.05),
       "a temperature-dependent Shupe coefficient is", f"{_PHYS} 7 (magnitude)",
       magnitude=True),
    _R("effects.turn_on_transient.a", "deg/h", (0, 100), (0.005, 0.05),
       "a turn-on transient starts at", f"{_PHYS} 3 (magnitude)", magnitude=True, off=0.0),
    _R("effects.turn_on_transient.tau", "s", (0, 86400), (60, 300),
       "a turn-on transient decays in", f"{_PHYS} 3: tau_e 1-5 min", (MINUTES,),
       low_open=True),
    _R("effects.scale_factor_temperature.s1", "1/K", (0, 0.01), (1.7e-5, 8e-4),
       "a FOG's scale factor changes per kelvin by", f"{_PHYS} 3: 17-800 ppm/K",
       ((1e-6, 0.0, "ppm/K"),), magnitude=True, off=0.0),
    _R("effects.magnetic.m", "deg/h", (0, 100), (0, 0.05), "a FOG's magnetic bias is",
       f"{_PHYS} 7; Hotate and Tabe (1986)", magnitude=True),
    _R("effects.magnetic.D_mag", "deg", (-360, 360), (-360, 360),
       "an azimuth is", "an angle of one turn"),
    _R("effects.polarization_ripple.A_p", "deg/h", (0, 100), (0, 0.05),
       "a polarisation ripple is", "Kintner (1981)", magnitude=True),
    _R("effects.polarization_ripple.T_p", "K", (0, 1000), (0.5, 20),
       "a polarisation ripple's temperature period is", "Kintner (1981)", low_open=True),
    _R("effects.polarization_ripple.phi", "rad", (-100, 100), (-2 * math.pi, 2 * math.pi),
       "a phase is", "one turn"),
    # heat released inside a fibre coil: the winding is passive (absorbed light, microwatts);
    # what can be there is a heater wound in or bonded on, or heat reaching a layer through
    # the spool's hub or the outer face's mount, a fraction of a watt of the electronics' few
    _R("effects.heat_source:coil*.power", "W", _POWER_HARD, (0, 0.5),
       "heat inside a fibre coil (a heater, or a hub or outer-face path; the winding itself "
       "is passive) is", f"{_PHYS} 2: a coil dissipates 0-0.5 W", (_m("W"),), off=0.0),
    _R("effects.heat_source:spool.power", "W", _POWER_HARD, (0, 1),
       "heat reaching a coil's spool (through its hub from the base) is",
       f"{_PHYS} 2: the spool is passive", (_m("W"),), off=0.0),
    _R("effects.heat_source.power", "W", _POWER_HARD, (0, 20), "an extra heat source gives",
       f"{_PHYS} 2", (_m("W"),), off=0.0),
    _R("effects.motor_heat.power", "W", (0, 100), (0, 10),
       "a turntable motor dissipates while moving", f"{_PHYS} 7", (_m("W"),)),
    _R("effects.thermometer_lag.tau", "s", (0, 3600), (1, 300),
       "a thermometer's extra lag is", f"{_PHYS} 2: lags of 10-60 s", (MINUTES,),
       low_open=True),
    _R("effects.indexing_error.offsets_deg", "deg", (0, 5), (0, 0.05),
       "an indexer's position error is", "indexing turntables: arc-seconds to arc-minutes",
       ((1 / 60, 0.0, "arc-minutes"), (1 / 3600, 0.0, "arc-seconds")), magnitude=True),
    _R("effects.indexing_error.sigma_deg", "deg", (0, 1), (0, 0.01),
       "an indexer's repeatability is", "indexing turntables: arc-seconds",
       ((1 / 60, 0.0, "arc-minutes"), (1 / 3600, 0.0, "arc-seconds"))),
    _R("effects.axis_misalignment.delta_deg", "deg", (0, 180), (0, 1),
       "a gyro axis is misaligned by", "Titterton and Weston (2004) ch. 4: mounting errors",
       magnitude=True),
    _R("effects.axis_misalignment.gamma_deg", "deg", (0, 5), (0, 0.5),
       "a gyro axis is misaligned by", "Titterton and Weston (2004) ch. 4: mounting errors",
       magnitude=True),
    _R("effects.tilt_exact.*_deg", "deg", (0, 5), (0, 0.1), "a levelled platform is tilted by",
       f"{_PHYS} 4", ((1 / 60, 0.0, "arc-minutes"),), magnitude=True),
    _R("effects.acc_bias_temperature.b_q1", "g/K", (0, 1e-3), (1e-5, 5e-5),
       "a QFA's bias changes per kelvin by", f"{_PHYS} 4: 10-50 ug/K",
       ((1e-6, 0.0, "ug/K"),), magnitude=True, off=0.0),
    _R("effects.aux_linear.*", "channel units", (0, 1e9), (0, 1e9),
       "an auxiliary channel's coefficient is", "any electrical unit", magnitude=True),
    _R("effects.*", "", (0, 1e9), (0, 1e9), "an effect parameter is",
       "a user's effect: its own function checks it", magnitude=True),
    # ---------------------------------------------------------------- scenario
    _I("seed", (0, 2 ** 63 - 1), (0, 2 ** 63 - 1), "a seed is", "numpy SeedSequence"),
    _R("design.margin", "sigma", (0, 100), (1, 10), "a design's separation margin is",
       "a test at 2 to 6 noise standard deviations", low_open=True),
    _I("design.draws", (0, 1000), (2, 64), "parameter draws per rival are",
       "a few to tens of draws estimate a prediction's spread"),
    _R("design.soak_h", "h", (0, 1000), (0.5, 48), "a soak before a chamber run lasts",
       "IEC 60068-2-1/-2: a unit soaked for hours", (SECONDS_FOR_HOURS, MINUTES_FOR_HOURS)),
    _R("design.max_hours", "h", (0, 10000), (1, 100), "a designed run's chamber time is at most",
       "a chamber booked for hours to days", (SECONDS_FOR_HOURS, MINUTES_FOR_HOURS),
       low_open=True),
    _temperature("design.start_temperatures", "a designed run starts at"),
    _temperature("start_temperatures_c"),
    _I("repeats", (1, 10000), (1, 100), "start-ups per temperature are",
       "Monte Carlo sets of tens of start-ups"),
    _I("units", (1, 1000), (1, 20), "simulated units are", "a fleet of a few units"),
    _R("duration_s", "s", (0, 30 * 86400), (600, 86400), "a start-up run lasts",
       f"{_PHYS} 1 and 5: a north-finding cycle of 5-12 min, a start-up stage of 30-90 min, "
       "a stable stage after it",
       (MINUTES, HOURS), low_open=True),
    _R("sample_rate_hz", "Hz", (0.001, 10000), (0.1, 100), "a north finder samples at",
       "FOG outputs of 1-2000 Hz, logged at 1 Hz (docs/measurement-format.md)"),
    _R("latitude_deg", "deg", (-89, 89), (-70, 70), "a north finder works at",
       f"{_PHYS} 5: the heading error grows as 1/cos L; none at the poles"),
    _R("true_heading_deg", "deg", (-360, 360), (-360, 360), "an azimuth is", "one turn"),
    _R("schedule.positions_deg", "deg", (-360, 360), (-360, 360),
       "a turntable position is", "one turn"),
    _R("schedule.dwell_s", "s", (0, 86400), _DWELL_S, "a dwell lasts", _DWELL_SRC,
       (MINUTES,), low_open=True),
    _R("schedule.move_s", "s", (0, 3600), _MOVE_S, "a move between positions lasts",
       _MOVE_SRC, (MINUTES,), off=0.0),
    _R("northfind.startup_end_s", "s", (0, 30 * 86400), (1800, 5400),
       "a start-up stage ends after", f"{_PHYS} 1: 30-90 min", (MINUTES, HOURS),
       low_open=True),
    _R("northfind.stable_start_s", "s", (0, 30 * 86400), (1800, 10800),
       "a stable stage starts after", f"{_PHYS} 1: after the 30-90 min start-up",
       (MINUTES, HOURS)),
    _R("northfind.settle_s", "s", (0, 3600), (0, 30), "a dwell's settling skip is",
       f"{_PHYS} 5: a few seconds of a 60-180 s dwell"),
    _R("northfind.spec_deg", "deg", (0, 180), (0.001, 1), "a heading specification is",
       f"{_PHYS} 1: start-up RMSE 0.01-0.02 deg", low_open=True),
    _R("chamber.ripple_c", "K", (0, 50), (0, 1), "a chamber's control ripple is",
       "IEC 60068-3-5: fluctuation +-0.3-1 K"),
    _R("chamber.ripple_period_s", "s", (1, 1e6), (60, 3600), "a chamber ripple's period is",
       "IEC 60068-3-5: controller cycles of 5-15 min", (MINUTES,)),
    _R("chamber.program.hold_s", "s", (0, 1e7), (60, 1e6), "a chamber hold lasts",
       "IEC 60068-2-1/-2: dwells of minutes to days", (MINUTES, HOURS), low_open=True),
    _R("chamber.program.power_off_s", "s", (0, 1e7), (10, 1e5),
       "a power cycle keeps the unit off for", "a warm restart: seconds to a day",
       (MINUTES, HOURS), low_open=True),
    _R("chamber.program.over_s", "s", (0, 1e7), (60, 1e6), "a chamber ramp lasts",
       "IEC 60068-2-14: ramps of minutes to hours; Liang et al. (2021): 7000 min",
       (MINUTES, HOURS), low_open=True),
    _R("chamber.program.rate_c_per_min", "K/min", (0, 60), (0.1, 15),
       "a chamber ramps at", "IEC 60068-2-14 test Nb: 1, 3 or 5 K/min; fast chambers 15",
       ((60.0, 0.0, "K/s"), (1 / 60, 0.0, "K/h")), low_open=True),
    _temperature("chamber.program.ramp_to_c", "a chamber program runs within"),
    _temperature("chamber.program.step_to_c", "a chamber program runs within"),
    _I("chamber.program.repeat", (1, 10000), (1, 50), "a program repeats its steps",
       "temperature cycling tests of a few to tens of cycles"),
    _R("variability.soak_offset_c", "K", (0, 10), (0, 1), "a soak's offset scatter is",
       "IEC 60068-3-5: +-0.3-0.5 K"),
    _R("variability.soak_node_c", "K", (0, 5), (0, 0.5), "a soak's node scatter is",
       "IEC 60068-3-5: spread of +-0.5-1 K"),
    _R("variability.soak_from_c", "C", TEMPERATURE_RANGE_C, (10, 35),
       "a unit is brought from a laboratory at", "a laboratory", (KELVIN, FAHRENHEIT)),
    _R("variability.soak_h", "h", (0, 240), (1, 24), "a soak lasts",
       "hours before power-on", (MINUTES_FOR_HOURS, SECONDS_FOR_HOURS), low_open=True),
    _R("variability.*_rel_std", "", (0, 1), (0, 0.5), "a relative scatter is",
       f"{_PHYS} 9: 5-20 % for one design"),
    _R("variability.chamber_wander_c", "K", (0, 10), (0, 1), "a chamber's wander is",
       "IEC 60068-3-5: fluctuation +-0.3-0.5 K"),
    _R("variability.chamber_wander_tau_s", "s", (1, 1e6), (60, 3600),
       "a chamber wander's correlation time is", "a chamber's outer loop: minutes",
       (MINUTES,)),
    _R("variability.cycling_c", "K", (0, 10), (0, 1), "a chamber's cycling is",
       "IEC 60068-3-5: fluctuation +-0.3-0.5 K"),
    _R("variability.cycling_period_s", "s", (1, 1e6), (60, 3600),
       "a chamber's cycling period is", "controller cycles of 5-15 min", (MINUTES,)),
    _R("variability.thermometer_offset_c", "K", (0, 10), (0, 0.5),
       "a thermometer offset scatter is", "IEC 60751 class A: +-(0.15 + 0.002 |T|) K"),
    _I("variability.unit_seed", (0, 2 ** 63 - 1), (0, 2 ** 63 - 1), "a seed is",
       "numpy SeedSequence"),
    _R("variability.parameters.*.std", "", (0, 1e9), (0, 1e9),
       "an absolute scatter is", "in the parameter's unit"),
    _R("variability.parameters.*", "", (0, 3), (0, 0.5), "a relative scatter is",
       f"{_PHYS} 9: 5-20 % for one design"),
    _I("compensation.budget", (1, 100000), (1, 1000), "a tuner's budget is",
       "evaluations per tuned method"),
    _R("compensation.decimate_s", "s", (0, 86400), (1, 300), "training samples are taken every",
       "the drift is low-passed at 512 s", (MINUTES,), low_open=True),
    _R("compensation.cutoff_period_s", "s", (0, 1e6), (60, 4096),
       "a wavelet cutoff period is", "wavelet level 8 at 1 Hz (512 s)", (MINUTES,),
       low_open=True),
    _I("compensation.train_seed", (0, 2 ** 63 - 1), (0, 2 ** 63 - 1), "a seed is",
       "numpy SeedSequence"),
    _I("compensation.random_state", (0, 2 ** 32 - 1), (0, 2 ** 32 - 1), "a random_state is",
       "scikit-learn: 0 to 2**32 - 1"),
    _I("compensation.train_repeats", (1, 1000), (1, 20), "training start-ups are",
       "a maker's calibration runs"),
    _I("compensation.test_repeats", (1, 1000), (1, 50), "test start-ups are",
       "start-ups scored per temperature"),
    _I("compensation.tuner_seeds", (1, 1000), (1, 20), "tuner restarts are", "a few restarts"),
    _I("compensation.n_jobs", (-1024, 1024), (-1024, 1024), "joblib's n_jobs is",
       "joblib: -1 every core, N cores; never 0"),
    _I("compensation.*_units", (0, 999), (0, 999), "a unit index is", "units 0 .. units - 1"),
    _temperature("compensation.train_temperatures_c"),
    # ---------------------------------------------------------------- sweep
    _I("sweep.seeds", (0, 2 ** 63 - 1), (0, 2 ** 63 - 1), "a seed is", "numpy SeedSequence"),
    _I("sweep.seeds.first", (0, 2 ** 63 - 1), (0, 2 ** 63 - 1), "a seed is",
       "numpy SeedSequence"),
    _I("sweep.seeds.count", (1, 100000), (1, 1000), "seeds per point are",
       "Monte Carlo sets of tens to hundreds"),
    _R("sweep.spec_deg", "deg", (0, 180), (0.001, 1), "a heading specification is",
       f"{_PHYS} 1: start-up RMSE 0.01-0.02 deg", low_open=True),
    _I("sweep.rmse_window_cycles", (1, 1000), (1, 20), "a rolling RMSE spans cycles",
       "nfs.northfind.time_to_spec: 5 cycles"),
    _I("sweep.draws.count", (1, 65536), (1, 4096), "drawn points are",
       "Sobol sets of 2**k points"),
    _I("sweep.draws.seed", (0, 2 ** 63 - 1), (0, 2 ** 63 - 1), "a seed is",
       "numpy SeedSequence"),
    # ---------------------------------------------------------------- measurement sidecar
    _R("measurement.latitude_deg", "deg", (-90, 90), (-70, 70), "a north finder works at",
       f"{_PHYS} 5"),
    _temperature("measurement.start_temperature_c"),
    _R("measurement.true_heading_deg", "deg", (-360, 360), (-360, 360), "an azimuth is",
       "one turn"),
    _R("measurement.sample_rate_hz", "Hz", (0, 10000), (0.1, 100),
       "a north finder samples at", "FOG outputs of 1-2000 Hz", low_open=True),
    _R("measurement.positions_deg", "deg", (-360, 360), (-360, 360),
       "a turntable position is", "one turn"),
    _R("measurement.dwell_s", "s", (0, 86400), _DWELL_S, "a dwell lasts", _DWELL_SRC,
       (MINUTES,), low_open=True),
    _R("measurement.move_s", "s", (0, 3600), _MOVE_S, "a move between positions lasts",
       _MOVE_SRC, (MINUTES,), off=0.0),
    _R("measurement.duration_s", "s", (0, 30 * 86400), (60, 7 * 86400),
       "a logged run lasts", f"{_PHYS} 1 and 5: a start-up stage of 30-90 min, a stable "
       "stage after it", (MINUTES, HOURS), low_open=True),
    # ---------------------------------------------------------------- measurement columns
    _R("measurement.columns.temp_*_c.at_power_on", "K", (0, 100), (0, 20),
       "a soaked unit's thermometers read at power-on, from start_temperature_c,",
       f"{_PHYS} 1: soaked until uniform; the internal rise is 5-15 K over hours",
       magnitude=True),
    _R("measurement.columns.gyro_dph.earth_rate", "", (0.1, 20), (0.5, 2),
       "dwell means of a FOG in deg/h span, in units of Omega_ie cos L times the "
       "positions' least spread,",
       f"{_PHYS} 5: w_k = Omega_ie cos L cos A_k + b, Omega_ie = 15.041 deg/h",
       ((3600.0, 0.0, "deg/s"), (180 * 3600 / math.pi, 0.0, "rad/s"),
        (180 / math.pi, 0.0, "rad/h"), (60.0, 0.0, "deg/min"), (1e-3, 0.0, "mdeg/h"))),
    _R("measurement.columns.temp_*_c", "C", (-273.15, 500), (-273.15, 500),
       "a north finder's thermometer reads", "absolute zero; no working unit reaches 500 C "
       "(solders melt near 220 C)"),
    _R("measurement.columns.acc_*_g", "g", (0, 2), (0, 2), "a specific force is",
       "docs/measurement-format.md: |acc| <= 2 g", ((1 / G_N_M_PER_S2, 0.0, "m/s^2"),),
       magnitude=True),
    _R("measurement.columns.acc_*_g.median", "g", (0, 0.5), (0, 0.05),
       "a horizontal accelerometer on a levelled table reads",
       f"{_PHYS} 4: tilts of arc-minutes; 0.05 g is a 3 deg tilt",
       ((1 / G_N_M_PER_S2, 0.0, "m/s^2"),), magnitude=True),
    # ---------------------------------------------------------------- derived limits
    _I("limits.samples_per_run", (1, MAX_SAMPLES_PER_RUN), (1, 500_000),
       "samples of one run (soak included) are",
       "about 1.3 kB per sample: 2e6 samples need 2.6 GB"),
    _R("limits.samples_per_dwell", "", (2, 1e9), (10, 1e9), "samples per dwell are",
       "a dwell mean needs samples"),
    _R("limits.steady_rise_k", "K", (0, 150), (0, 40),
       "the steady-state rise of a node above the chamber is",
       f"{_PHYS} 2: an internal rise of 5-15 C (the TEC adds a few K)", magnitude=True),
    _R("limits.fibre_pitch_mm", "mm", (0.05, 5.0), (0.1, 0.3),
       "a coil's fibre pitch sqrt(winding volume / L) is",
       "fibres of 80-250 um with their coatings, wound and potted"),
    _R("limits.layer_pitch_mm", "mm", (0.05, 5.0), (0.1, 0.3),
       "a coil's radial pitch (r_o - r_i) / N_opt is",
       "fibres of 80-250 um with their coatings, wound and potted"),
    _I("limits.program_steps", (1, 100_000), (1, 10_000),
       "steps of a chamber program (repeats expanded) are",
       "cycling tests of tens of cycles of a few steps"),
    _I("limits.sweep_cells", (1, 1_000_000), (1, 10000), "cells of a sweep are",
       "a sweep of a million cells runs for weeks"),
]

#: Every range, specific entries before generic ones (the first match wins).
RANGES: tuple[Range, ...] = tuple(_TABLE)


def find(key: str) -> Range | None:
    """The range of the canonical key path ``key`` (module docstring), or None.

    A link ``thermal.links.<a>-<b>.<x>`` is looked up in both orders; an effect label
    ``name:target`` as itself (a row for the effect at some targets only: heat inside a
    coil), then as ``name``.
    """
    candidates = [key]
    m = re.fullmatch(r"thermal\.links\.([^.]+)-([^.]+)\.(.+)", key)
    if m:
        candidates.append(f"thermal.links.{m.group(2)}-{m.group(1)}.{m.group(3)}")
    m = re.fullmatch(r"effects\.([^.:]+):[^.]*\.(.+)", key)
    if m:
        # the effect at its target first (heat inside a coil), then the effect anywhere
        candidates = [key, f"effects.{m.group(1)}.{m.group(2)}"]
    for r in RANGES:
        if any(fnmatch.fnmatchcase(c, r.key) for c in candidates):
            return r
    return None


# ------------------------------------------------------------------------------------------
# Warnings, held until a load succeeds


class RangeWarning(UserWarning):
    """A value outside its typical range: the file loads and runs (one line on stderr)."""


_PENDING: contextvars.ContextVar[dict | None] = contextvars.ContextVar(
    "nfs_range_warnings", default=None)


@contextmanager
def deferred_warnings():
    """Hold the :class:`RangeWarning` of a load until it succeeds, each once.

    A file refused shows its one error and none of the warnings of the values before it;
    nested loads (a scenario's base, its instrument) share the outermost holder, so a value
    met twice (in a base and in the file inheriting it) warns once.
    """
    if _PENDING.get() is not None:
        yield
        return
    held: dict = {}
    token = _PENDING.set(held)
    try:
        yield
    finally:
        _PENDING.reset(token)
    for message in held.values():
        _emit(message)


@contextmanager
def one_line_warnings():
    """Show each :class:`RangeWarning` as one line ``nfs: warning: ...`` on stderr (the
    command line's form, beside its ``nfs: error: ...``); other warnings as Python shows
    them."""
    with warnings.catch_warnings():
        original = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            if issubclass(category, RangeWarning):
                print(f"nfs: warning: {message}", file=sys.stderr)
            else:
                original(message, category, filename, lineno, file, line)

        warnings.showwarning = show
        yield


def warn(message: str, *, key: Any = None) -> None:
    """Warn now, or when the enclosing :func:`deferred_warnings` ends (once per ``key``)."""
    held = _PENDING.get()
    if held is None:
        _emit(message)
    else:
        held.setdefault(message if key is None else key, message)


#: Where Python's default filter records the messages shown (once each per process).
_REGISTRY: dict = {}


def _emit(message: str) -> None:
    # One place of issue ("nfs", line 0: no source line to print), so that a message is one
    # line even where the command line's one_line_warnings is not in force (a sweep's worker
    # processes), and Python's default filter shows it once per process (a value every cell
    # of a sweep loads again).
    warnings.warn_explicit(message, RangeWarning, "nfs", 0, module="nfs.ranges",
                           registry=_REGISTRY)


# ------------------------------------------------------------------------------------------
# Checks


def check(canonical: str, value: Any, *, file=None, key: str | None = None,
          error: type[InputError] = InputError, quiet: bool = False, **where) -> bool:
    """Check one number against its range: raise ``error`` (naming ``file`` and ``key``, the
    key path as the user wrote it, default ``canonical``) when it is impossible or not
    finite, warn when it is unusual (unless ``quiet``: the caller warns in its own words).
    Values that are not numbers are left to the loaders' type checks; a key without a range
    is only checked to be finite.  ``where``: ``column``, ``row`` of the error.  Returns
    whether the value is unusual."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    shown = canonical if key is None else key
    if not math.isfinite(value):
        raise error(f"must be a finite number, got {value!r}", file=file, key=shown, **where)
    r = find(canonical)
    if r is None:
        return False
    if r.impossible(value):
        raise error(r.refusal(value), file=file, key=shown, **where)
    unusual = r.unusual(value)
    if unusual and not quiet:
        warn_unusual(r.warning(value), file=file, key=shown,
                     once=(canonical, repr(value)), **where)
    return unusual


def warn_unusual(message: str, *, file=None, key: str | None = None, once: Any = None,
                 column: str | None = None, row: int | None = None) -> None:
    """:func:`warn` with the place in front, as an error names it (file, key, column)."""
    where = [str(file)] if file is not None else []
    if key:
        where.append(f"key '{key}'")
    if column is not None:
        where.append(f"column '{column}'")
    if row is not None:
        where.append(f"row {row}")
    warn(f"{', '.join(where)}: {message}" if where else message,
         key=message if once is None else once)


_BARE = re.compile(r"[A-Za-z0-9_-]+")


def _shown_key(k: str) -> str:
    return k if _BARE.fullmatch(k) else '"' + k.replace('"', '\\"') + '"'


def leaves(tree: Any, shown: str = "", canonical: str = "") -> Iterator[tuple[str, str, Any]]:
    """(key path as written, canonical key path, value) of every leaf of a parsed TOML tree
    (``shown``, ``canonical``: the paths of ``tree`` itself; empty at a file's top).

    Canonical paths (module docstring): ``added_effects`` entries are ``effects``; an entry
    of an array of tables is named by its ``name`` (effects) or its ``between`` (links) or
    not at all (program steps, aux channels); ``steps`` of a repeat keep the program's path.
    """
    if isinstance(tree, dict):
        for k, v in tree.items():
            k = str(k)
            s = f"{shown}.{_shown_key(k)}" if shown else _shown_key(k)
            c = f"{canonical}.{k}" if canonical else k
            if c == "added_effects":
                c = "effects"
            elif c.startswith("chamber.program") and c.endswith(".steps"):
                c = c[: -len(".steps")]
            yield from leaves(v, s, c)
    elif isinstance(tree, list):
        for i, v in enumerate(tree):
            c = canonical
            if isinstance(v, dict):
                name, between = v.get("name"), v.get("between")
                if canonical.endswith("effects") and isinstance(name, str):
                    c = f"{canonical}.{name}"
                elif (canonical.endswith("links") and isinstance(between, list)
                      and len(between) == 2 and all(isinstance(b, str) for b in between)):
                    c = f"{canonical}.{between[0]}-{between[1]}"
            yield from leaves(v, f"{shown}[{i}]", c)
    else:
        yield shown, canonical, tree


def check_tree(tree: Any, *, file=None, error: type[InputError] = InputError,
               shown: str = "", canonical: str = "", skip: tuple[str, ...] = (),
               quiet: tuple[str, ...] | bool = ()) -> list[str]:
    """:func:`check` every number of a parsed TOML tree; the keys (as written) of the
    unusual values ``quiet`` silenced, for the caller's own one line.

    ``shown``, ``canonical``: the paths of ``tree`` (``canonical="sweep"`` for a sweep file);
    ``skip``: canonical key patterns left to the caller; ``quiet``: patterns (or True for
    all) whose unusual values do not warn (values a caller checks in its own words, as a
    sweep its axes)."""
    quieted = []
    for s, c, value in leaves(tree, shown, canonical):
        if any(fnmatch.fnmatchcase(c, p) for p in skip):
            continue
        q = quiet if isinstance(quiet, bool) else any(fnmatch.fnmatchcase(c, p) for p in quiet)
        if check(c, value, file=file, key=s, error=error, quiet=q) and q:
            quieted.append(s)
    return quieted
