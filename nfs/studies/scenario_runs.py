"""A whole scenario: simulate every run (stacked, :func:`~nfs.experiment.simulate_runs`),
north-find each, and tabulate the uncompensated heading RMSE by start temperature."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..docfields import document_fields
from ..experiment import SimulationResult, simulate_runs
from ..northfind import north_find, white_noise_floor_deg
from ..scoring.heading_table import HeadingTable, TableRow, pooled_rmse
from ..variability import describe_units

__all__ = ["ScenarioResult", "run_scenario", "run_scenarios", "northfind_runs", "stage_errors",
           "chamber_moves", "stage_names", "run_stage_errors", "stage_errors_by_temperature",
           "floor_deg", "uncompensated_table"]


@document_fields
@dataclass(frozen=True)
class ScenarioResult:
    """Every run of a scenario, simulated and north-found."""

    scenario: Any
    """The :class:`~nfs.scenario.Scenario`."""
    simulations: tuple[SimulationResult, ...]
    """One per run, temperature-major (all repeats of T0[0] first)."""
    northfind: tuple[Any, ...]
    """The :class:`~nfs.northfind.NorthFindResult` of each run."""

    def runs_at(self, i_temp: int) -> list[int]:
        """Indices of the runs at start temperature number ``i_temp``."""
        r = self.scenario.repeats
        return list(range(i_temp * r, (i_temp + 1) * r))


def northfind_runs(runs, settings=None) -> list:
    """North-find each run with the scenario's settings (tilt correction, settle time).

    A two-position schedule leaves the sign of psi + theta_a to a heading hint (a compass
    in the field): a simulated run's own true heading serves as that hint.  It only picks
    which of the two mirror-image solutions is returned, never moves the value, and is
    ignored by schedules of three or more positions.
    """
    tilt = True if settings is None else settings.tilt_correction
    settle = 0.0 if settings is None else settings.settle_s
    return [north_find(run, tilt_correction=tilt, settle_s=settle,
                       heading_hint_deg=run.meta.true_heading_deg) for run in runs]


def run_scenario(scenario, *, progress: Callable[[int, int, str], None] | None = None
                 ) -> ScenarioResult:
    """Simulate and north-find every run of ``scenario``.

    ``progress(i, n, name)`` is called before each run (for a progress line).
    """
    return run_scenarios([scenario], progress=progress)[0]


def run_scenarios(scenarios, *, progress: Callable[[int, int, str], None] | None = None
                  ) -> list[ScenarioResult]:
    """:func:`run_scenario` for scenarios of one instrument (e.g. one scenario under several
    seeds), every run of all of them simulated together (:func:`simulate_runs`: a run's
    bits do not depend on the runs beside it)."""
    scenarios = list(scenarios)
    conds = [sc.conditions() for sc in scenarios]
    flat = [c for cs in conds for c in cs]
    sims = simulate_runs(scenarios[0].instrument, flat, progress=progress)
    if progress is not None:
        progress(len(flat), len(flat), "north finding")
    out, k = [], 0
    for sc, cs in zip(scenarios, conds):
        mine = tuple(sims[k:k + len(cs)])
        k += len(cs)
        nf = northfind_runs([s.run for s in mine], sc.northfind)
        out.append(ScenarioResult(scenario=sc, simulations=mine, northfind=tuple(nf)))
    return out


def stage_errors(result, settings, moving=None) -> tuple[np.ndarray, ...]:
    """Heading errors of a NorthFindResult's start-up and stable cycles [deg].

    With ``moving`` (one flag per cycle, :func:`chamber_moves`) the cycles during which the
    chamber program moves the chamber leave both stages and form a third: (start-up with the
    chamber held, stable with the chamber held, ramping), the stages of
    :func:`stage_names`.
    """
    err = np.asarray(result.error_deg)
    up = np.asarray(result.t_end_s) <= settings.startup_end_s
    st = np.asarray(result.t_start_s) >= settings.stable_start_s
    if moving is None:
        return err[up], err[st]
    m = np.asarray(moving, dtype=bool)
    return err[up & ~m], err[st & ~m], err[m]


def chamber_moves(scenario, start_temperature_c: float, t_start_s, t_end_s) -> np.ndarray:
    """Whether the scenario's chamber program changes the chamber temperature within each
    interval [t_start_s, t_end_s] (times from power-on [s]): a ramp or a step inside it or
    across its ends.  All False without a program; the chamber's ripple and the controller's
    wander (``[variability]``) are not the program and do not count.
    """
    a = np.atleast_1d(np.asarray(t_start_s, dtype=float))
    b = np.atleast_1d(np.asarray(t_end_s, dtype=float))
    prog = scenario.chamber.program
    if prog is None:
        return np.zeros(a.shape, dtype=bool)
    sample_s = 1.0 / scenario.sample_rate_hz
    t_c, temp_c = prog.corners(start_temperature_c, sample_s)
    t_c = t_c - prog.power_on_s(start_temperature_c, sample_s)
    at_a = np.interp(a, t_c, temp_c)
    out = np.abs(np.interp(b, t_c, temp_c) - at_a) > _HELD_K
    for k in range(a.size):
        inside = temp_c[(t_c > a[k]) & (t_c < b[k])]
        out[k] |= bool(np.any(np.abs(inside - at_a[k]) > _HELD_K))
    return out


#: A program whose temperature changes by less than this over a cycle holds it [K].
_HELD_K = 1e-9


def stage_names(scenario) -> tuple[str, ...]:
    """The heading table's stage rows of a scenario's runs.

    ``("before", "stable")``: the start-up stage (cycles ending within
    ``northfind.startup_end_s``) and the stable stage (cycles starting after
    ``northfind.stable_start_s``).  When a chamber program moves the chamber while the runs
    are recorded, a stage is named for what the chamber does: ``("before", "held",
    "ramping")``, the start-up cycles with the chamber held, the cycles after
    ``stable_start_s`` with the chamber held (the unit may still be settling after a ramp:
    not "stable"), and every cycle during which the chamber ramps or steps.
    """
    prog = scenario.chamber.program
    if prog is not None and any(
            chamber_moves(scenario, t0, 0.0, scenario.run_duration_s(t0))[0]
            for t0 in scenario.start_temperatures_c):
        return ("before", "held", "ramping")
    return ("before", "stable")


def run_stage_errors(result: ScenarioResult, k: int, northfind=None) -> tuple[np.ndarray, ...]:
    """Heading errors [deg] of run ``k`` of ``result`` by stage, in the order of
    :func:`stage_names` (``northfind``: the north-finding of every run, default the
    result's own, uncompensated)."""
    sc = result.scenario
    nf = (result.northfind if northfind is None else northfind)[k]
    if len(stage_names(sc)) == 2:
        return stage_errors(nf, sc.northfind)
    t0 = sc.start_temperatures_c[k // sc.repeats]
    return stage_errors(nf, sc.northfind, chamber_moves(sc, t0, nf.t_start_s, nf.t_end_s))


def stage_errors_by_temperature(result: ScenarioResult, northfind=None) -> dict:
    """Stage row name (:func:`stage_names`) -> ``errors[column][run]``: the heading errors
    [deg] of that stage of every run, by start temperature (the input of
    :meth:`~nfs.scoring.heading_table.HeadingTable.with_intervals`)."""
    sc = result.scenario
    per_run = [run_stage_errors(result, k, northfind) for k in range(len(result.northfind))]
    return {name: [[per_run[k][j] for k in result.runs_at(i)]
                   for i in range(len(sc.start_temperatures_c))]
            for j, name in enumerate(stage_names(sc))}


def _two_positions(schedule) -> bool:
    """True for a schedule of two distinct turntable angles."""
    return len({round(float(p) % 360.0, 9) for p in schedule.positions_deg}) == 2


def floor_deg(scenario) -> float:
    """White-noise floor of the scenario's schedule (:func:`~nfs.northfind.white_noise_floor_deg`):
    sqrt(2/N) (ARW/sqrt(dwell)) / Omega_h, or for two positions 180 deg apart
    ``(ARW/sqrt(dwell)) / (sqrt(2 v) Omega_h |sin(psi + theta_a)|)`` at the scenario's heading."""
    sched = scenario.schedule
    if _two_positions(sched):
        return white_noise_floor_deg(scenario.instrument.gyro.arw_deg_per_rth_h,
                                     sched.dwell_s, 2, scenario.latitude_deg,
                                     heading_deg=scenario.true_heading_deg,
                                     first_position_deg=sched.positions_deg[0],
                                     visits=len(sched.cycle_positions_deg) // 2)
    return white_noise_floor_deg(scenario.instrument.gyro.arw_deg_per_rth_h, sched.dwell_s,
                                 len(sched.cycle_positions_deg), scenario.latitude_deg)


def uncompensated_table(res: ScenarioResult, errors: dict | None = None):
    """Rows ``before`` (start-up, uncompensated), ``stable`` and ``floor`` by T0; ``errors``:
    :func:`stage_errors_by_temperature` of ``res`` when the caller holds it already."""
    sc = res.scenario
    if errors is None:
        errors = stage_errors_by_temperature(res)
    rmse = {name: tuple(pooled_rmse(runs) for runs in cols) for name, cols in errors.items()}
    n_t = len(sc.start_temperatures_c)
    fl = floor_deg(sc)
    nf = sc.northfind
    two = _two_positions(sc.schedule)
    floor_note = ("(ARW / sqrt(dwell)) / (sqrt(N) Omega_ie cos L |sin(psi + theta_1)|) at the "
                  "true heading (two positions; the true heading is the hint that picks the "
                  "sign of each cycle's solution)" if two else
                  "sqrt(2/N) (ARW / sqrt(dwell)) / (Omega_ie cos L)")
    held = "with the chamber held, " if "held" in rmse else ""
    stages = (f"before: start-up stage (cycles ending within {nf.startup_end_s:g} s), "
              f"{held}uncompensated; " + (
                  f"held: cycles starting after {nf.stable_start_s:g} s with the chamber held "
                  "by its program; ramping: every cycle during which the program ramps or "
                  f"steps the chamber ({_program_rates(sc)}); " if held else
                  f"stable: cycles starting after {nf.stable_start_s:g} s; ")
              + f"floor: white-noise limit {floor_note}.")
    notes = (
        f"Heading RMSE [deg], {sc.repeats} run(s) per start temperature, seed {sc.seed}, "
        f"latitude {sc.latitude_deg:g} deg, {len(sc.schedule.cycle_positions_deg)}-position "
        f"{sc.schedule.order} schedule, dwell {sc.schedule.dwell_s:g} s, "
        f"move {sc.schedule.move_s:g} s.",
        stages,
    )
    var = sc.variability
    if sc.units > 1 or var.active:
        notes += (f"Start-ups made by {describe_units(sc.units, sc.unit_ids)}; variability "
                  f"{var.describe()}.",)
    rows = [TableRow(name, values) for name, values in rmse.items()]
    # a stage row is kept where nothing applies (tables compared row by row keep their rows),
    # and a note says why
    notes += tuple(f"{name}: - at every start temperature: {_why_empty(sc, name)}."
                   for name, values in rmse.items() if not any(np.isfinite(values)))
    rows.append(TableRow("floor", (fl,) * n_t))
    return HeadingTable(tuple(sc.start_temperatures_c), tuple(rows), notes)


def _program_rates(sc) -> str:
    """How the program moves the chamber after power-on, e.g. ``ramps of 1 C/min``."""
    prog = sc.chamber.program
    sample_s = 1.0 / sc.sample_rate_hz
    rates, steps = set(), False
    for t0 in sc.start_temperatures_c:
        t_c, temp_c = prog.corners(t0, sample_s)
        dt, dtemp = np.diff(t_c), np.diff(temp_c)
        powered = t_c[1:] > prog.power_on_s(t0, sample_s)
        moving = powered & (np.abs(dtemp) > _HELD_K)
        step = moving & (dt <= sample_s * (1.0 + 1e-9))
        steps |= bool(np.any(step))
        rates |= {float(f"{v:.2g}") for v in 60.0 * np.abs(dtemp / dt)[moving & ~step]}
    text = ("ramps of " + ", ".join(f"{v:g}" for v in sorted(rates)) + " C/min") if rates \
        else ""
    return text + (" and " if text and steps else "") + ("steps" if steps else "")


def _why_empty(sc, name: str) -> str:
    """Why a stage has no cycle in any run (a line of the table's notes)."""
    nf = sc.northfind
    longest = max(sc.run_duration_s(t0) for t0 in sc.start_temperatures_c)
    if name == "before":
        if "held" in stage_names(sc):
            return (f"no cycle ends within {nf.startup_end_s:g} s with the chamber held (the "
                    "program moves it from power-on: those cycles are under ramping)")
        return f"no cycle ends within {nf.startup_end_s:g} s of power-on"
    if name == "ramping":
        return "the program moves the chamber only between north-finding cycles"
    if longest <= nf.stable_start_s:
        return (f"the runs ({longest:g} s) end before the stable stage starts "
                f"({nf.stable_start_s:g} s)")
    held = " with the chamber held" if name == "held" else ""
    return f"no cycle starts after {nf.stable_start_s:g} s{held}"
