"""How long a job will run, and what it will write or hold, before it starts.

A scenario with ``repeats = 5000`` asks ``nfs simulate`` for 35,000 runs: about 80 minutes
and 42 GB.  Before a job that may be long (``nfs simulate``, ``nfs table``, ``nfs sweep``)
the command states the runs, the time and the disk (or, for a table, the memory that holds
its runs), and past :data:`JOB_LIMITS` it refuses unless told ``--yes``.

How the figures are estimated:

- runs and samples are counted from the scenario (a run's samples: duration x sample rate,
  plus a chamber program's unpowered soak, which is simulated too);
- the time from a timed calibration on this machine (:func:`calibrate`): the first runs of
  the job (:data:`CALIBRATION_SAMPLES` samples at least), simulated together as the job
  simulates them, written as the job writes them (``nfs simulate``: files and record, in a
  temporary folder) or north-found (a table, a sweep), give seconds per sample, multiplied
  by the job's samples.  A long job stacks more runs in one thermal march than the
  calibration's few, so that part is an upper bound (``nfs simulate`` took 1.0x the
  estimate for 98 runs of 1300 samples, 0.8x for 140 of 9000); a table's training of its
  compensators is not in it (said in the line);
- the disk from the calibration's files: CSV bytes per row and sidecar bytes per run;
- a table's memory from the bytes of the calibration's simulation results (every
  intermediate is kept: :class:`nfs.ModelChainResult`), per sample.

A job so small that even a slow machine finishes it within :data:`JOB_NOTICE` is neither
calibrated nor announced (:func:`might_exceed`).
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
import time
from dataclasses import dataclass

import numpy as np

from ..compensate.settings import CompensationSettings
from ..docfields import document_fields
from ..errors import NfsError
from ..experiment import iter_simulate_runs
from ..io.measurement import write_run
from ..io.resume import Journal
from ..northfind import north_find
from ..scenario import Scenario
from .startup_study import test_scenario, train_scenario

__all__ = ["JobLimits", "JOB_LIMITS", "JOB_NOTICE", "CALIBRATION_SAMPLES", "Calibration",
           "JobEstimate", "JobTooBig", "calibrate", "run_samples", "might_exceed",
           "estimate_runs", "estimate_table", "table_scenarios", "check_job", "gate_job",
           "ignored_keys"]


@document_fields
@dataclass(frozen=True)
class JobLimits:
    """Thresholds of a job's figures."""

    seconds: float
    """Estimated time [s]."""
    disk_bytes: float
    """Bytes written [B]."""
    memory_bytes: float
    """Bytes held at once [B]."""


#: Past any of these a command refuses to start without ``--yes`` (the one place they are
#: set): 10 min, 2 GB written, 4 GB held.
JOB_LIMITS = JobLimits(seconds=600.0, disk_bytes=2e9, memory_bytes=4e9)

#: Past any of these a command states its estimate before it starts: 1 min, 200 MB, 1 GB.
JOB_NOTICE = JobLimits(seconds=60.0, disk_bytes=2e8, memory_bytes=1e9)

#: Samples the calibration simulates at least (whole runs: 3 runs of 2.5 h at 1 Hz,
#: about 0.3 s here).
CALIBRATION_SAMPLES = 20_000

#: What no machine this package runs on is slower than, per sample, to rule out a job as
#: short without calibrating: simulated and written [s] (measured here: 13 us), and bytes
#: of a CSV row [B] (138 B for the default instrument's 11 columns), a result held [B].
_SLOW_S_PER_SAMPLE = 1e-4
_WIDE_ROW_BYTES = 400.0
_HELD_BYTES = 2000.0

class JobTooBig(NfsError):
    """A job past :data:`JOB_LIMITS`, refused before it starts (``--yes`` runs it)."""


@document_fields
@dataclass(frozen=True)
class Calibration:
    """Costs per sample measured on this machine (:func:`calibrate`)."""

    samples: int
    """Samples the calibration simulated."""
    simulate_s: float
    """Seconds per sample to simulate and format the CSV file [s]."""
    northfind_s: float
    """Seconds per sample to north-find [s]."""
    csv_bytes: float
    """Bytes per row of the runs' CSV files [B] (0 unless written)."""
    sidecar_bytes: float
    """Bytes of a run's sidecar ``NAME.toml`` [B] (0 unless written)."""
    held_bytes: float
    """Bytes per sample a simulation result holds (arrays of every stage) [B]."""


@document_fields
@dataclass(frozen=True)
class JobEstimate:
    """A job's size, estimated before it starts."""

    command: str
    """The command, e.g. ``nfs simulate``."""
    runs: int
    """Runs simulated."""
    samples: int
    """Samples simulated over all runs (a chamber program's soak included)."""
    seconds: float
    """Estimated time [s]."""
    disk_bytes: float
    """Bytes written [B]."""
    memory_bytes: float
    """Bytes held at once [B] (0: the runs stream through)."""
    how: str
    """How the figures were estimated, and what they leave out."""

    def exceeds(self, limits: JobLimits) -> list[str]:
        """The figures past ``limits``, in words (empty: none)."""
        out = []
        if self.seconds > limits.seconds:
            out.append(f"{_duration(limits.seconds)}")
        if self.disk_bytes > limits.disk_bytes:
            out.append(f"{_size(limits.disk_bytes)} written")
        if self.memory_bytes > limits.memory_bytes:
            out.append(f"{_size(limits.memory_bytes)} held in memory")
        return out

    def line(self) -> str:
        """One line: runs, time, disk (and memory), and how they were estimated."""
        parts = [f"about {_duration(self.seconds)}"]
        if self.disk_bytes:
            parts.append(f"{_size(self.disk_bytes)} on disk")
        if self.memory_bytes:
            parts.append(f"{_size(self.memory_bytes)} of memory")
        return (f"{self.command}: {self.runs} runs ({self.samples:.3g} samples), "
                + ", ".join(parts) + f" ({self.how})")


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _size(n: float) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


def run_samples(conditions, *, soak: bool = True) -> list[int]:
    """Samples of each run of ``conditions`` (a scenario's
    :meth:`~nfs.scenario.Scenario.conditions`): its record (its CSV rows) and (``soak``) a
    chamber program's unpowered soak, which is simulated too."""
    return [int(round(c.duration_s * c.sample_rate_hz))
            + (int(math.ceil(c.soak_s * c.sample_rate_hz - 1e-9)) if soak else 0)
            for c in conditions]


def table_scenarios(scenario: Scenario, settings: CompensationSettings | None = None,
                    compensate: bool = True) -> list[Scenario]:
    """The scenarios whose runs ``nfs table`` simulates (:class:`nfs.ModelChain`): the
    test start-ups (``compensation.test_repeats`` per temperature by each test unit) and,
    with compensation, the training start-ups; under ``protocol = "cycles"`` the scenario's
    own runs (``repeats``)."""
    s = settings or scenario.compensation or CompensationSettings()
    if not compensate:
        return [test_scenario(scenario, s)]
    if s.protocol == "cycles":
        return [scenario]
    return [train_scenario(scenario, s), test_scenario(scenario, s)]


def might_exceed(samples: int, limits: JobLimits = JOB_NOTICE, *, rows: bool = True,
                 held: bool = False) -> bool:
    """False when ``samples`` are sure to stay within ``limits`` on a slow machine (no
    calibration needed); ``rows``: the samples are written, ``held``: kept in memory."""
    return (samples * _SLOW_S_PER_SAMPLE > limits.seconds
            or (rows and samples * _WIDE_ROW_BYTES > limits.disk_bytes)
            or (held and samples * _HELD_BYTES > limits.memory_bytes))


def _held(obj, seen: set) -> int:
    """Bytes of the NumPy arrays reachable from ``obj`` (dataclasses, dicts, sequences),
    each buffer counted once."""
    if isinstance(obj, np.ndarray):
        base = obj if obj.base is None else obj.base
        if id(base) in seen or not isinstance(base, np.ndarray):
            return 0
        seen.add(id(base))
        return base.nbytes
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return sum(_held(getattr(obj, f.name), seen) for f in dataclasses.fields(obj))
    if isinstance(obj, dict):
        return sum(_held(v, seen) for v in obj.values())
    if isinstance(obj, (list, tuple)):
        return sum(_held(v, seen) for v in obj)
    return 0


def calibrate(scenario: Scenario, *, northfind: bool = False, write: bool = False,
              min_samples: int = CALIBRATION_SAMPLES, conditions=None) -> Calibration:
    """Time the first runs of ``scenario`` (``min_samples`` samples at least, whole runs)
    on this machine: simulated together, (``write``) each written as the job writes it,
    its files and its record (:func:`~nfs.io.measurement.write_run`,
    :class:`~nfs.io.resume.Journal`), into a temporary folder removed at once, and
    (``northfind``) north-found (module docstring).  ``conditions``: the scenario's, when
    at hand."""
    conds = scenario.conditions() if conditions is None else conditions
    k, n = 0, 0
    while k < len(conds) and n < min_samples:
        n += run_samples(conds[k:k + 1])[0]
        k += 1
    t0 = time.perf_counter()
    sims = list(iter_simulate_runs(scenario.instrument, conds[:k]))
    csv_bytes = sidecar_bytes = 0
    if write:
        with tempfile.TemporaryDirectory(prefix="nfs-calibration-") as tmp:
            journal = Journal(tmp)
            for sim in sims:
                csv = write_run(sim.run, tmp)
                journal.append([csv, csv.with_suffix(".toml")])
                csv_bytes += csv.stat().st_size
                sidecar_bytes += csv.with_suffix(".toml").stat().st_size
    simulate_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    if northfind:
        for sim in sims:
            north_find(sim.run, tilt_correction=scenario.northfind.tilt_correction,
                       settle_s=scenario.northfind.settle_s)
    northfind_s = time.perf_counter() - t0
    rows = sum(sim.run.columns["time_s"].size for sim in sims)
    return Calibration(samples=n, simulate_s=simulate_s / n, northfind_s=northfind_s / n,
                       csv_bytes=csv_bytes / rows, sidecar_bytes=sidecar_bytes / k,
                       held_bytes=_held(sims, set()) / n)


def estimate_runs(command: str, scenarios: list[Scenario], *, write: bool = False,
                  hold: bool = False, northfind: bool = False, extra_bytes: float = 0.0,
                  leaves_out: str = "", skip=frozenset()) -> JobEstimate:
    """The estimate of a job that simulates the runs of ``scenarios`` (``write``: as
    measurement files; ``hold``: keeping every result; ``northfind``: north-finding each),
    calibrated on the first of them (:func:`calibrate`).  ``extra_bytes``: bytes written
    besides the runs; ``leaves_out``: what the time does not count, in words; ``skip``:
    names of runs already made (a folder resumed)."""
    conds = [[c for c in sc.conditions() if c.name not in skip] for sc in scenarios]
    if not any(conds):
        return JobEstimate(command, 0, 0, 0.0, 0.0, 0.0, "every run is made")
    samples = [n for cs in conds for n in run_samples(cs)]
    total = int(sum(samples))
    first = next(k for k, cs in enumerate(conds) if cs)
    cal = calibrate(scenarios[first], northfind=northfind, write=write,
                    conditions=conds[first])
    rows = sum(n for cs in conds for n in run_samples(cs, soak=False))
    seconds = total * (cal.simulate_s + (cal.northfind_s if northfind else 0.0))
    disk = rows * cal.csv_bytes + len(samples) * cal.sidecar_bytes
    how = (f"time from {cal.samples} samples simulated"
           + (" and written" if write else "") + (" and north-found" if northfind else "")
           + f" here: {1e6 * (cal.simulate_s + cal.northfind_s):.3g} us per sample")
    if write:
        how += f"; disk {cal.csv_bytes:.0f} B per CSV row"
    if hold:
        how += f"; memory {cal.held_bytes:.0f} B per sample held"
    if leaves_out:
        how += f"; {leaves_out}"
    return JobEstimate(command=command, runs=len(samples), samples=total, seconds=seconds,
                       disk_bytes=disk + extra_bytes,
                       memory_bytes=total * cal.held_bytes if hold else 0.0, how=how)


def estimate_table(scenario: Scenario, settings: CompensationSettings | None = None,
                   compensate: bool = True) -> JobEstimate:
    """The estimate of ``nfs table`` (:class:`nfs.ModelChain`): the runs of
    :func:`table_scenarios` simulated, north-found and held in memory (the chain's result
    keeps them); the compensators' training is not counted."""
    s = settings or scenario.compensation or CompensationSettings()
    leaves_out = ""
    if compensate:
        leaves_out = (f"the training of {len(s.methods)} method(s) (budget {s.budget}, "
                      f"{s.tuner_seeds} tuner seed(s)) comes on top")
    return estimate_runs("nfs table", table_scenarios(scenario, s, compensate), hold=True,
                         northfind=True, leaves_out=leaves_out)


def check_job(estimate: JobEstimate, *, yes: bool = False, limits: JobLimits = JOB_LIMITS,
              fewer: str = "") -> None:
    """Raise :class:`JobTooBig` (one line, the figures) when ``estimate`` is past
    ``limits`` and ``yes`` is not given; ``fewer``: how to ask for fewer runs, in words."""
    over = estimate.exceeds(limits)
    if over and not yes:
        raise JobTooBig(f"{estimate.line()}: over " + " and ".join(over)
                        + "; give --yes to run it" + (f" ({fewer})" if fewer else ""))


def gate_job(make_estimate, samples: int, *, yes: bool = False, rows: bool = True,
             held: bool = False, fewer: str = "") -> JobEstimate | None:
    """The estimate of a job of ``samples`` samples that may pass :data:`JOB_NOTICE`
    (:func:`might_exceed`; ``rows``, ``held``: as there), made by ``make_estimate()`` and
    checked against :data:`JOB_LIMITS` (:func:`check_job`); None for a job sure to be
    short, which is neither calibrated nor announced.  A caller states a returned
    estimate past :data:`JOB_NOTICE` before it starts."""
    if not might_exceed(samples, rows=rows, held=held):
        return None
    estimate = make_estimate()
    check_job(estimate, yes=yes, fewer=fewer)
    return estimate


def ignored_keys(scenario: Scenario, command: str, settings: CompensationSettings | None = None,
                 compensate: bool = True) -> list[str]:
    """One line per count of ``scenario`` that ``command`` (``"simulate"`` or ``"table"``)
    does not use although the scenario sets it away from its default, saying what the
    command uses instead.

    ``nfs simulate`` makes ``repeats`` start-ups per temperature and ignores
    ``[compensation]``; ``nfs table`` makes ``compensation.test_repeats`` test start-ups per
    temperature by each test unit and ``train_repeats`` training ones
    (:func:`table_scenarios`), and ignores ``repeats``, except under
    ``protocol = "cycles"``, which runs the scenario's own runs and ignores the other two.
    """
    file = scenario.path.name if scenario.path is not None else "the built-in scenario"
    s = settings or scenario.compensation or CompensationSettings()
    default = CompensationSettings()
    out = []
    if command == "simulate":
        for key, value, dflt in (("test_repeats", s.test_repeats, default.test_repeats),
                                 ("train_repeats", s.train_repeats, default.train_repeats)):
            if value != dflt:
                out.append(f"{file}: [compensation] {key} = {value} is ignored by nfs "
                           f"simulate, which writes repeats = {scenario.repeats} start-up(s) "
                           "per start temperature (the table's start-ups are nfs table's)")
        return out
    uses_repeats = compensate and s.protocol == "cycles"
    test = s.test_repeats or scenario.repeats
    if not uses_repeats and scenario.repeats not in (1, test):
        train = (f" and {s.train_repeats} training start-up(s) by each training unit "
                 "(compensation.train_repeats)" if compensate else "")
        out.append(f"{file}: repeats = {scenario.repeats} is ignored by nfs table, which "
                   f"makes {test} test start-up(s) per start temperature by each test unit "
                   f"(compensation.test_repeats){train}; nfs table --repeats N sets the "
                   "test start-ups")
    if uses_repeats:
        for key, value, dflt in (("test_repeats", s.test_repeats, default.test_repeats),
                                 ("train_repeats", s.train_repeats, default.train_repeats)):
            if value != dflt:
                out.append(f"{file}: [compensation] {key} = {value} is ignored by nfs table "
                           "under protocol = \"cycles\", which trains on cycle 1 and tests "
                           f"on the other cycles of repeats = {scenario.repeats} run(s) per "
                           "start temperature")
    return out
