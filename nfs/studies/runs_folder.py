"""A scenario's runs written into a folder, with the units that made them (``nfs simulate``).

The folder holds every run as ``NAME.csv`` + ``NAME.toml`` (:func:`nfs.write_run`), each unit
that made them as ``unit_00.toml``, ``unit_01.toml``, ... (:meth:`nfs.Scenario.unit_instrument`,
:mod:`nfs.io.unit_files`: with unit-to-unit variability the unit's values are drawn, and a
fit of its runs is to be set beside them, not beside the scenario's instrument), and the
manifest ``nfs-manifest.json``, which names the unit files; each run's sidecar names its
unit's file (``unit_file``).

The folder is written run by run, each run recorded as it lands (:mod:`nfs.io.resume`): an
interrupted :func:`simulate_to_folder` leaves a partial folder that the same scenario (the
same hash: its instrument, seed and repeats too) resumes, simulating only the runs not
recorded.  Runs are seeded, so a resumed folder holds the same bytes as one written at once.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..docfields import document_fields
from ..experiment import iter_simulate_runs
from ..instrument import Instrument
from ..io.atomic import atomic_write_text
from ..io.measurement import write_run
from ..io.outdir import OutputFolder
from ..io.provenance import scenario_provenance, sha256_of_text
from ..io.unit_files import UNIT_SIDECAR_KEY, unit_entry, unit_file_name, unit_file_text
from ..scenario import Scenario

__all__ = ["SimulatedFolder", "scenario_job", "check_runs_folder", "simulate_to_folder",
           "unit_file_instrument"]


@document_fields
@dataclass(frozen=True)
class SimulatedFolder:
    """What :func:`simulate_to_folder` wrote."""

    path: Path
    """The folder."""
    runs: tuple[Path, ...]
    """Every run's ``NAME.csv``, in the scenario's order (resumed ones included)."""
    units: dict[int, Instrument]
    """{unit: the instrument it is} of the units that made the runs, drawn
    (:meth:`~nfs.scenario.Scenario.unit_instrument`): the values a fit should find."""
    unit_files: dict[int, Path]
    """{unit: its file} (``unit_00.toml``, ...), each loading back to ``units[unit]``
    (:func:`unit_file_instrument`)."""
    resumed: int
    """Runs an interrupted call had already written (0: the folder written anew)."""
    manifest: Path
    """The folder's ``nfs-manifest.json``."""


def scenario_job(scenario: Scenario) -> str:
    """The job of a scenario's runs folder: SHA-256 of the scenario's hash and its
    instrument's (:func:`~nfs.io.provenance.scenario_provenance`), so that a partial folder is
    resumed only by the same scenario (seed and repeats included), wherever its file lies."""
    prov = scenario_provenance(scenario)
    return sha256_of_text(f"runs/1 {prov['sha256']} {prov['instrument']['sha256']}")


def _run_files(name: str) -> tuple[str, str]:
    return f"{name}.csv", f"{name}.toml"


def check_runs_folder(scenario: Scenario, path, *, overwrite: bool = False,
                resume: bool | None = None, command: str = "simulate") -> OutputFolder:
    """The output folder of ``scenario``'s runs, checked before any work
    (:class:`~nfs.io.outdir.OutputFolder`, its job :func:`scenario_job`): a partial folder of
    the same scenario is resumed (``resume``: None: then; True: resume or refuse; False:
    write anew)."""
    expected = {unit_file_name(u) for u in scenario.drawn_units()}
    for cond in scenario.conditions():
        expected.update(_run_files(cond.name))
    return OutputFolder(path, command, overwrite=overwrite, job=scenario_job(scenario),
                        resume=resume, expected=frozenset(expected))


def unit_file_instrument(inst: Instrument, unit: int) -> Instrument:
    """The instrument a unit file holds: ``inst`` named ``<name>_unit_00`` (a drawn unit is
    not the preset it was drawn from, and reports compare models by name), every value
    ``inst``'s."""
    return dataclasses.replace(inst, name=f"{inst.name}_unit_{unit:02d}")


def _write_unit(scenario: Scenario, unit: int, inst: Instrument, folder: Path) -> Path:
    """Write unit ``unit``'s file (that it reads back to the same instrument, bit for bit,
    is the tests' to check: tests/io/test_runs_folder.py)."""
    named = unit_file_instrument(inst, unit)
    text = unit_file_text(named.to_toml(), unit=unit, scenario=scenario.name,
                          drawn=scenario.variability.describe())
    path = folder / unit_file_name(unit)
    atomic_write_text(path, text)
    return path


def simulate_to_folder(scenario: Scenario, folder, *,
                       progress: Callable[[int, int, str], None] | None = None,
                       arguments: list[str] | None = None) -> SimulatedFolder:
    """Simulate every run of ``scenario`` into ``folder`` with its unit files and manifest
    (module docstring), resuming a partial folder of the same scenario.

    Parameters
    ----------
    scenario : Scenario
        The experiment (:func:`nfs.load_scenario`).
    folder : OutputFolder or path
        The folder, checked before any work by :func:`check_runs_folder` (a path is checked
        here, with its defaults: a folder of another command or of unknown files is
        refused).
    progress : callable, optional
        ``progress(i, n, name)`` before each run simulated (``n``: the runs left).
    arguments : list of str, optional
        The command line recorded in the manifest.

    Returns
    -------
    SimulatedFolder
    """
    if not isinstance(folder, OutputFolder):
        folder = check_runs_folder(scenario, folder)
    out = folder.path
    inputs = {"scenario": scenario_provenance(scenario)}
    folder.begin(arguments=arguments, inputs=inputs)
    units = scenario.drawn_units()
    unit_files = {}
    for u, inst in units.items():
        unit_files[u] = out / unit_file_name(u)
        if unit_file_name(u) not in folder.done:
            folder.record([_write_unit(scenario, u, inst, out)])
    conds = scenario.conditions()
    left = [c for c in conds if not all(f in folder.done for f in _run_files(c.name))]
    for sim in iter_simulate_runs(scenario.instrument, left, progress=progress):
        run = sim.run
        meta = dataclasses.replace(run.meta, extra={
            **run.meta.extra, UNIT_SIDECAR_KEY: unit_file_name(sim.conditions.unit)})
        csv = write_run(dataclasses.replace(run, meta=meta), out)
        folder.record([csv, csv.with_suffix(".toml")])
    if progress is not None:
        progress(len(left), len(left), "done")
    drawn = scenario.variability.per_unit
    n_runs = {u: 0 for u in units}
    for c in conds:
        n_runs[c.unit] += 1
    manifest = folder.finish(arguments=arguments, inputs=inputs,
                             units=[unit_entry(u, scenario.name, drawn, n_runs[u])
                                    for u in units])
    return SimulatedFolder(path=out, runs=tuple(out / f"{c.name}.csv" for c in conds),
                           units=units, unit_files=unit_files,
                           resumed=len(conds) - len(left), manifest=manifest)
