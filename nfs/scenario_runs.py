"""A whole scenario: simulate every run (stacked, :func:`~nfs.experiment.simulate_runs`),
north-find each, and tabulate the uncompensated heading RMSE by start temperature."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from .docfields import document_fields
from .experiment import SimulationResult, simulate_runs
from .variability import describe_units

__all__ = ["ScenarioResult", "run_scenario", "run_scenarios", "northfind_runs", "stage_errors",
           "floor_deg", "uncompensated_table"]


@document_fields
@dataclass(frozen=True)
class ScenarioResult:
    """Every run of a scenario, simulated and north-found."""

    scenario: Any
    """The :class:`~nfs.io.scenario.Scenario`."""
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
    from .northfind import north_find
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


def stage_errors(result, settings) -> tuple[np.ndarray, np.ndarray]:
    """Heading errors of a NorthFindResult's start-up and stable cycles [deg]."""
    err = np.asarray(result.error_deg)
    up = np.asarray(result.t_end_s) <= settings.startup_end_s
    st = np.asarray(result.t_start_s) >= settings.stable_start_s
    return err[up], err[st]


def _two_positions(schedule) -> bool:
    """True for a schedule of two distinct turntable angles."""
    return len({round(float(p) % 360.0, 9) for p in schedule.positions_deg}) == 2


def floor_deg(scenario) -> float:
    """White-noise floor of the scenario's schedule (:func:`~nfs.northfind.white_noise_floor_deg`):
    sqrt(2/N) (ARW/sqrt(dwell)) / Omega_h, or for two positions 180 deg apart
    (ARW/sqrt(dwell)) / (sqrt(2 v) Omega_h |sin(psi + theta_a)|) at the scenario's heading."""
    from .northfind import white_noise_floor_deg
    sched = scenario.schedule
    if _two_positions(sched):
        return white_noise_floor_deg(scenario.instrument.gyro.arw_deg_per_rth_h,
                                     sched.dwell_s, 2, scenario.latitude_deg,
                                     heading_deg=scenario.true_heading_deg,
                                     first_position_deg=sched.positions_deg[0],
                                     visits=len(sched.cycle_positions_deg) // 2)
    return white_noise_floor_deg(scenario.instrument.gyro.arw_deg_per_rth_h, sched.dwell_s,
                                 len(sched.cycle_positions_deg), scenario.latitude_deg)


def uncompensated_table(res: ScenarioResult):
    """Rows ``before`` (start-up, uncompensated), ``stable`` and ``floor`` by T0."""
    from .report import HeadingTable, TableRow, pooled_rmse
    sc = res.scenario
    before, stable = [], []
    for i in range(len(sc.start_temperatures_c)):
        errs = [stage_errors(res.northfind[k], sc.northfind) for k in res.runs_at(i)]
        before.append(pooled_rmse(e[0] for e in errs))
        stable.append(pooled_rmse(e[1] for e in errs))
    n_t = len(sc.start_temperatures_c)
    fl = floor_deg(sc)
    nf = sc.northfind
    two = _two_positions(sc.schedule)
    floor_note = ("(ARW / sqrt(dwell)) / (sqrt(N) Omega_ie cos L |sin(psi + theta_1)|) at the "
                  "true heading (two positions; the true heading is the hint that picks the "
                  "sign of each cycle's solution)" if two else
                  "sqrt(2/N) (ARW / sqrt(dwell)) / (Omega_ie cos L)")
    notes = (
        f"Heading RMSE [deg], {sc.repeats} run(s) per start temperature, seed {sc.seed}, "
        f"latitude {sc.latitude_deg:g} deg, {len(sc.schedule.cycle_positions_deg)}-position "
        f"{sc.schedule.order} schedule, dwell {sc.schedule.dwell_s:g} s, "
        f"move {sc.schedule.move_s:g} s.",
        f"before: start-up stage (cycles ending within {nf.startup_end_s:g} s), uncompensated; "
        f"stable: cycles starting after {nf.stable_start_s:g} s; floor: white-noise limit "
        f"{floor_note}.",
    )
    var = sc.variability
    if sc.units > 1 or var.active:
        notes += (f"Start-ups made by {describe_units(sc.units, sc.unit_ids)}; variability "
                  f"{var.describe()}.",)
    rows = (TableRow("before", tuple(before)), TableRow("stable", tuple(stable)),
            TableRow("floor", (fl,) * n_t))
    return HeadingTable(tuple(sc.start_temperatures_c), rows, notes)
