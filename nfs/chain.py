"""The chain of a start-up experiment: simulate -> north-find -> compensate -> table.

In the manner of pvlib's ``ModelChain``: a :class:`ModelChain` holds a scenario and the
compensation settings, :meth:`ModelChain.run_model` runs every stage, and the
:class:`ModelChainResult` keeps every intermediate, so a user can look at the simulated runs
(node temperatures, each drift term), the north-finding cycles, the trained compensators and
the table, and write the same files ``nfs table`` writes::

    import nfs
    chain = nfs.ModelChain.from_scenario("startup_7temps", compensate=False)
    result = chain.run_model()
    result.table.row("before").mean_deg           # start-up heading RMSE [deg]
    result.runs.simulations[0].thermal.temperature_c   # node temperatures, first run [degC]
    result.write("out")                           # heading_rmse.md, .csv, .json, .png

The protocol of the scenario's ``[compensation]`` decides what the table is: ``start-ups``
(the heading table over test start-ups, :mod:`nfs.studies.startup_study`), ``cycles`` or
``runs`` (the drift table, :mod:`nfs.studies.cycle_study`), ``parameters`` (the parameter
table, :mod:`nfs.studies.parameter_study`); with ``compensate=False`` the uncompensated rows
of the heading table alone (before, stable, floor).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from .compensate import get_method
from .compensate.settings import CompensationSettings
from .config.scenario import load_scenario
from .docfields import document_fields
from .report.compensation import write_study
from .report.cycle_report import cycle_table_markdown, write_cycle_study
from .report.parameter_report import parameter_table_markdown, write_parameter_study
from .report.table_files import write_table
from .scenario import Scenario
from .scoring.heading_table import HeadingTable
from .studies.cycle_study import run_cycle_study, run_runs_study
from .studies.parameter_study import run_parameter_study
from .studies.scenario_runs import (ScenarioResult, run_scenario, stage_errors_by_temperature,
                                    stage_names, uncompensated_table)
from .studies.startup_study import run_study, table_provenance, test_scenario

__all__ = ["ModelChain", "ModelChainResult"]

#: A progress callback ``progress(i, n, what)``: step ``i`` of ``n``, what is being done.
ProgressCallback = Callable[[int, int, str], None]


@document_fields
@dataclass(frozen=True)
class ModelChainResult:
    """Every intermediate of one :meth:`ModelChain.run_model`."""

    scenario: Scenario
    """The scenario the chain ran."""
    settings: CompensationSettings
    """The compensation settings it ran with (the scenario's, with the chain's changes)."""
    compensated: bool
    """False when only the uncompensated rows were computed."""
    provenance: dict
    """Scenario file, seeds, package and library versions: what reproduces the table."""
    runs: ScenarioResult | None = None
    """The test start-ups, simulated (node temperatures, drift terms, sensor outputs) and
    north-found (every cycle's heading), for the uncompensated chain; a study keeps its own
    in ``study``."""
    study: Any = None
    """The study that trained and scored the compensators
    (:class:`~nfs.studies.CompensationStudy`, :class:`~nfs.studies.CycleStudy` or
    :class:`~nfs.studies.ParameterStudy`), None without compensation."""
    table: HeadingTable | None = None
    """The heading-RMSE table [deg] by start temperature with 95 % intervals (None for a
    drift or parameter table, which the study holds)."""
    markdown: str = ""
    """The table as ``nfs table`` prints it."""
    title: str = ""
    """The title of the table's figure."""

    def write(self, out_dir: str | Path, *, json_path: str | Path | None = None) -> list[Path]:
        """Write the table's files into ``out_dir`` (as ``nfs table -o``), each atomically;
        return the paths written."""
        protocol = self.settings.protocol
        if not self.compensated:
            return write_table(self.table, out_dir, json_path=json_path, title=self.title)
        if protocol in ("cycles", "runs"):
            return write_cycle_study(self.study, out_dir, json_path=json_path,
                                     title=self.title, provenance=self.provenance)
        if protocol == "parameters":
            return write_parameter_study(self.study, out_dir, json_path=json_path,
                                         title=self.title, provenance=self.provenance)
        return write_study(self.study, out_dir, json_path=json_path, title=self.title,
                           table=self.table)


@dataclass
class ModelChain:
    """Simulate a scenario's start-ups, north-find them, train and apply the compensators and
    score them in a table.

    Parameters
    ----------
    scenario : Scenario
        The experiment (:func:`nfs.load_scenario`).
    settings : CompensationSettings, optional
        How compensators are trained and compared; default the scenario's ``[compensation]``
        (or the defaults when it has none).
    compensate : bool
        False: only the uncompensated rows (before, stable, floor) of the heading table, on
        the start-ups the full table would test on.
    progress : callable, optional
        ``progress(i, n, what)`` after each step.
    """

    scenario: Scenario
    settings: CompensationSettings | None = None
    compensate: bool = True
    progress: ProgressCallback | None = None
    results: ModelChainResult | None = field(default=None, init=False)
    """The result of the last :meth:`run_model` (None before)."""

    @classmethod
    def from_scenario(cls, path_or_name: str | Path | None = None,
                      overrides: dict[str, Any] | None = None, **kwargs) -> "ModelChain":
        """A chain for a scenario file or built-in scenario name (default: the built-in
        default scenario), with optional dotted-key ``overrides`` (as a sweep's axes:
        ``{"latitude_deg": 45.0}``); ``kwargs`` go to :class:`ModelChain`."""
        return cls(load_scenario(path_or_name, overrides or {}), **kwargs)

    def _settings(self) -> CompensationSettings:
        if self.settings is not None:
            return self.settings
        return self.scenario.compensation or CompensationSettings()

    def table_rows(self) -> tuple[str, ...] | None:
        """The rows of the heading table :meth:`run_model` makes, in its order, known before
        any work (what ``nfs table --baseline`` checks a baseline against): the
        uncompensated start-up stage, a row per compensation method (its row label in the
        method registry), the later stages (``stable``, or ``held`` and ``ramping`` under a
        chamber program that moves) and the white-noise ``floor``; None when the chain
        makes a drift or parameter table instead (protocol ``cycles``, ``runs`` or
        ``parameters``)."""
        s = self._settings()
        if self.compensate and s.protocol != "start-ups":
            return None
        first, *later = stage_names(test_scenario(self.scenario, s))
        methods = [get_method(m).name for m in s.methods] if self.compensate else []
        return (first, *methods, *later, "floor")

    def run_model(self) -> ModelChainResult:
        """Run every stage; the result is also kept in :attr:`results`."""
        sc, s = self.scenario, self._settings()
        provenance = table_provenance(sc, s, compensated=self.compensate)
        title = f"{sc.name}: heading RMSE by start temperature"
        if not self.compensate:
            runs = run_scenario(test_scenario(sc, s), progress=self.progress)
            errors = stage_errors_by_temperature(runs)
            table = uncompensated_table(runs, errors).with_intervals(errors,
                                                                    random_state=sc.seed)
            table = dataclasses.replace(table, provenance=provenance)
            res = ModelChainResult(sc, s, False, provenance, runs=runs, table=table,
                                   markdown=table.to_markdown(), title=title)
        elif s.protocol in ("cycles", "runs"):
            run = run_cycle_study if s.protocol == "cycles" else run_runs_study
            study = run(sc, s, progress=self.progress)
            res = ModelChainResult(sc, s, True, provenance, study=study,
                                   markdown=cycle_table_markdown(study),
                                   title=f"{sc.name}: drift table of the {s.protocol}")
        elif s.protocol == "parameters":
            study = run_parameter_study(sc, s, progress=self.progress)
            res = ModelChainResult(sc, s, True, provenance, study=study,
                                   markdown=parameter_table_markdown(study),
                                   title=f"{sc.name}: parameter-level compensation")
        else:
            study = run_study(sc, s, progress=self.progress)
            table = dataclasses.replace(study.heading_table(), provenance=provenance)
            res = ModelChainResult(sc, s, True, provenance, study=study, table=table,
                                   markdown=table.to_markdown(), title=title)
        self.results = res
        return res
