"""nfs: start-up experiments on fiber-optic-gyroscope north finders.

What a user scripts with is here, at the top (the ``nfs`` command calls the same)::

    import nfs
    scenario = nfs.load_scenario("startup_7temps")            # a file or a built-in name
    result = nfs.ModelChain(scenario).run_model()             # simulate -> north-find ->
    print(result.markdown)                                    #   compensate -> table
    chain = nfs.UnitChain("default", "runs/")                 # a model and a unit's runs
    fit = chain.fit()                                         # the model fitted to them
    finding = chain.diagnose(decide=True)                     # which effect is missing
    print(finding.verdict)                                    #   (then chain.apply, design)

The pipeline, by subpackage (each imports only those before it): :mod:`thermal` (lumped
network) -> :mod:`nfs.sensors`, :mod:`nfs.effects` (named drift effects), :mod:`nfs.noise` ->
:mod:`nfs.instrument`, :mod:`nfs.variability`, :mod:`nfs.chamber` -> :mod:`nfs.experiment`
(simulate runs, :class:`nfs.run.Run`) -> :mod:`nfs.northfind`, :mod:`nfs.denoise` ->
:mod:`nfs.learners`, :mod:`nfs.compensate` -> :mod:`nfs.scenario`, :mod:`nfs.config` ->
:mod:`nfs.scoring` -> :mod:`nfs.studies` -> :mod:`nfs.report` -> :mod:`nfs.chain`,
:mod:`nfs.sweep`; beside them, measurements -> :mod:`nfs.fit` -> :mod:`nfs.comparison` ->
:mod:`nfs.diagnose` -> :mod:`nfs.rivals` -> :mod:`nfs.design`.
:mod:`nfs.io` reads and writes files; :mod:`nfs.cli` is the ``nfs`` command.

The names below load on first use (SPEC 1 lazy loading, as SciPy and scikit-image do):
``import nfs`` stays quick, so ``nfs --help`` does not pay for scikit-learn and matplotlib.
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version

from .errors import (USER_ERRORS, EffectError, InputError, MeasurementError, NfsError,
                     ScenarioError, ThermalError)

try:
    __version__ = version("nfs-startup")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

#: Public name -> the module that defines it.
_PUBLIC = {
    # scenarios, instruments, runs
    "Scenario": "nfs.scenario", "load_scenario": "nfs.config.scenario",
    "Instrument": "nfs.instrument", "load_instrument": "nfs.instrument",
    "WoundCoil": "nfs.coil", "make_effect": "nfs.effects",
    "Run": "nfs.run", "RunMeta": "nfs.run",
    "read_run": "nfs.io.measurement", "read_runs": "nfs.io.measurement",
    "write_run": "nfs.io.measurement",
    "import_log": "nfs.io.log_import", "read_mapping": "nfs.io.log_mapping",
    # the chain and its stages
    "simulate_run": "nfs.experiment", "simulate_runs": "nfs.experiment",
    "RunConditions": "nfs.conditions", "SimulationResult": "nfs.experiment",
    "simulate_to_folder": "nfs.studies.runs_folder",
    "run_scenario": "nfs.studies.scenario_runs", "north_find": "nfs.northfind",
    "separate_drift": "nfs.denoise",
    "CompensationSettings": "nfs.compensate.settings",
    "train_compensator": "nfs.compensate", "load_compensator": "nfs.compensate",
    "ModelChain": "nfs.chain", "ModelChainResult": "nfs.chain",
    "HeadingTable": "nfs.scoring.heading_table",
    # measurements against the model
    "fit_model": "nfs.fit", "fit_unit": "nfs.fit", "compare": "nfs.comparison",
    "UnitChain": "nfs.unit", "FitResult": "nfs.fit", "Comparison": "nfs.comparison",
    "allan_of_runs": "nfs.comparison", "AllanReport": "nfs.comparison",
    "Diagnosis": "nfs.diagnose", "Finding": "nfs.rivals", "Settlement": "nfs.rivals",
    "Applied": "nfs.unit", "Design": "nfs.design",
    # many cells
    "load_sweep": "nfs.sweep", "run_sweep": "nfs.sweep",
}

__all__ = ["__version__", "NfsError", "InputError", "MeasurementError", "ScenarioError",
           "EffectError", "ThermalError", "USER_ERRORS", *_PUBLIC]


#: Subpackages reachable as attributes (``nfs.design.default_space``) without an import.
_SUBPACKAGES = ("fit", "comparison", "diagnose", "rivals", "design", "unit", "effects",
                "compensate", "northfind", "denoise", "learners", "scoring", "report",
                "studies", "sweep", "io", "noise", "sensors", "config")


def __getattr__(name: str):
    """Load a public name from its module, or a subpackage, on first use (PEP 562)."""
    if name in _SUBPACKAGES:
        return import_module(f"nfs.{name}")
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'nfs' has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
