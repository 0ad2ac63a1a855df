"""The conditions of one start-up run: where, when and how it is made.

A run's start temperature, latitude and heading, the turntable schedule (or a measured run's
own motion to replay), its length and sample rate, the chamber it sits in, its power cycles,
the unit that makes it and the scatter that unit is drawn with (:class:`RunConditions`); the
conditions of a measured run, to simulate a model beside it (:func:`conditions_from_run`).
:mod:`nfs.experiment` simulates runs from them and exports these names with its own.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .power import POWERED_COLUMN, off_spans_s, powered_mask
from .run import Run
from .sensors import Schedule, turntable_motion
from .variability import Variability

__all__ = ["RunConditions", "chamber_assumption", "conditions_from_run"]


@dataclass(frozen=True)
class RunConditions:
    """The conditions of one start-up run."""

    name: str
    """Stem of the measurement files."""
    start_temperature_c: float
    """T0, chamber soak and hold temperature [degC] (a chamber program starts there)."""
    latitude_deg: float
    """L [deg]."""
    true_heading_deg: float
    """psi, azimuth of the FOG axis at turntable angle 0 [deg]."""
    schedule: Schedule
    """The north-finding schedule."""
    duration_s: float = 9000.0
    """Length of the run from power-on [s]."""
    sample_rate_hz: float = 1.0
    """Sample rate [Hz]."""
    seed: int | tuple[int, ...] = 0
    """Entropy of the run's random streams (noise of every sensor, and the start-up's soak
    and chamber draws when ``variability`` is given)."""
    chamber_c: Callable[[np.ndarray], np.ndarray] | None = None
    """Chamber temperature T_amb(t) [degC], t from power-on [s]; None holds T0."""
    unit: int = 0
    """The unit that makes the start-up (its parameters are drawn from ``variability``)."""
    variability: Variability | None = None
    """Run-to-run and unit-to-unit scatter (:mod:`nfs.variability`); None: the unit is the
    instrument as given, soaked exactly at T0, in the chamber ``chamber_c``."""
    motion: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    """(time_s, position_deg, moving) of a measured run to replay instead of the schedule:
    the model is then simulated on the run's own time base and turntable motion."""
    soak_s: float = 0.0
    """Time the unpowered unit follows the chamber before power-on [s]: soaked at T0, it
    sits in ``chamber_c`` over [-soak_s, 0) (a chamber program's steps before its power-on
    marker); not recorded."""
    initial_c: np.ndarray | None = None
    """Node temperatures at the start of the record [degC] (n_nodes,), when known (a
    measured run's start estimated from its thermometers, :mod:`nfs.fit.start_state`);
    None: soaked at T0 (and ``variability``'s soak)."""
    power_off_s: tuple[tuple[float, float], ...] = ()
    """Power cycles: (switched off, switched on again) from power-on [s] (a chamber
    program's ``power_off_s`` steps, :mod:`nfs.power`); empty: on throughout."""

    @property
    def time_s(self) -> np.ndarray:
        """Sample times [s]: the replayed run's, or t_k = k / fs from power-on."""
        if self.motion is not None:
            return np.asarray(self.motion[0], dtype=float)
        n = int(round(self.duration_s * self.sample_rate_hz))
        return np.arange(n) / self.sample_rate_hz

    def turntable(self, time_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """theta(t) [deg] and the moving flag: replayed, or from the schedule."""
        if self.motion is not None:
            return (np.asarray(self.motion[1], dtype=float),
                    np.asarray(self.motion[2], dtype=float) > 0.5)
        return turntable_motion(self.schedule, time_s)

    def powered(self, time_s: np.ndarray) -> np.ndarray | None:
        """The power state s(t_k) (True: on), or None without power cycles."""
        return powered_mask(time_s, self.power_off_s) if self.power_off_s else None


def chamber_assumption(runs) -> str:
    """'' when every run recorded its chamber (``temp_chamber_c``, every sample finite); else
    one sentence naming the runs without one and what is assumed for them."""
    missing = [r.name for r in runs if not ("temp_chamber_c" in r.columns and np.all(
        np.isfinite(np.asarray(r.columns["temp_chamber_c"], dtype=float))))]
    if not missing:
        return ""
    shown = ", ".join(missing[:3]) + (f" and {len(missing) - 3} more" if len(missing) > 3
                                      else "")
    return (f"{len(missing)} run(s) without a complete chamber record (temp_chamber_c): "
            f"{shown}; the chamber is taken to hold each run's T0 throughout")


def conditions_from_run(run: Run, *, seed=0, schedule: Schedule | None = None,
                        initial_c: np.ndarray | None = None) -> RunConditions:
    """The conditions of a measured run, to simulate a model beside it.

    The model replays the run's own time base and turntable motion (``position_deg``,
    ``moving``), start temperature, latitude and heading (0 when unknown), and its chamber
    temperature when the run recorded ``temp_chamber_c``, and its power cycles when it
    recorded ``powered``; its nodes start at ``initial_c`` [degC] when given (the run's
    estimated start), else at T0.
    """
    m = run.meta
    t = np.asarray(run.columns["time_s"], dtype=float)
    cols = run.columns
    chamber = None
    if "temp_chamber_c" in cols and np.all(np.isfinite(cols["temp_chamber_c"])):
        amb_t, amb = t.copy(), np.asarray(cols["temp_chamber_c"], dtype=float)
        chamber = lambda tt: np.interp(tt, amb_t, amb)  # noqa: E731
    if schedule is None:
        pos = tuple(m.positions_deg) if m.positions_deg else (0.0,)
        schedule = Schedule(pos, m.dwell_s or 1.0, m.move_s or 0.0)
    fs = m.sample_rate_hz or (1.0 / float(np.median(np.diff(t))) if t.size > 1 else 1.0)
    return RunConditions(
        name=run.name, start_temperature_c=m.start_temperature_c, latitude_deg=m.latitude_deg,
        true_heading_deg=m.true_heading_deg if m.true_heading_deg is not None else 0.0,
        schedule=schedule, duration_s=float(t[-1] - t[0]) if t.size else 0.0,
        sample_rate_hz=fs, seed=seed, chamber_c=chamber,
        initial_c=None if initial_c is None else np.asarray(initial_c, dtype=float),
        power_off_s=off_spans_s(t, cols.get(POWERED_COLUMN)),
        motion=(t, np.asarray(cols["position_deg"], dtype=float),
                np.asarray(cols["moving"], dtype=float)))
