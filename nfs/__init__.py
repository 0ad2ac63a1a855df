"""nfs: start-up experiments on fiber-optic-gyroscope north finders.

The pipeline, by subpackage: :mod:`thermal` (lumped network) -> :mod:`nfs.sensors` and
:mod:`nfs.effects` (named drift effects) -> :mod:`nfs.noise` -> :mod:`nfs.denoise` ->
:mod:`nfs.compensate` -> :mod:`nfs.northfind` -> :mod:`nfs.report`; :mod:`nfs.experiment`
simulates runs (many together, their thermal states stacked), :mod:`nfs.studies.scenario_runs` runs
a scenario end to end and :mod:`nfs.cli` is the ``nfs`` command.
"""

from importlib.metadata import PackageNotFoundError, version

from .errors import (EffectError, InputError, MeasurementError, NfsError, ScenarioError,
                     ThermalError)

try:
    __version__ = version("nfs-startup")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

__all__ = ["__version__", "NfsError", "InputError", "MeasurementError", "ScenarioError",
           "EffectError", "ThermalError"]
