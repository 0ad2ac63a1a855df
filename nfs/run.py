"""The run: named sample columns of one start-up and the metadata the samples do not say.

The bottom of every flow: the simulator makes runs, the measurement format
(:mod:`nfs.io.measurement`, ``nfs-measurement/1``) reads and writes them, north finding,
compensation, fitting and diagnosis read them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .docfields import document_fields

__all__ = ["REQUIRED_COLUMNS", "NO_MISSING_COLUMNS", "RunMeta", "Run", "run_caveats"]

#: Required CSV columns, in the order the writer puts them first.
REQUIRED_COLUMNS: tuple[str, ...] = (
    "time_s", "position_deg", "moving", "gyro_dph", "acc_x_g", "acc_y_g",
    "temp_fog_c", "temp_acc_x_c", "temp_acc_y_c",
)

#: Required columns that may not hold a missing value (NaN): they place a sample in time
#: and in the turntable schedule.
NO_MISSING_COLUMNS: tuple[str, ...] = ("time_s", "position_deg", "moving")


@document_fields
@dataclass(frozen=True)
class RunMeta:
    """What the samples of a run do not say (``NAME.toml``)."""

    latitude_deg: float
    """Latitude L of the site [deg]."""
    start_temperature_c: float
    """The chamber's soak temperature T0 before power-on [degC]."""
    true_heading_deg: float | None = None
    """Azimuth of the FOG axis at turntable position 0 [deg], clockwise from north, if known."""
    sample_rate_hz: float | None = None
    """Nominal sample rate [Hz], if given."""
    positions_deg: tuple[float, ...] | None = None
    """The indexing sequence of one north-finding cycle [deg], if given."""
    dwell_s: float | None = None
    """Time at each position [s], if given."""
    move_s: float | None = None
    """Time to move between positions [s], if given."""
    duration_s: float | None = None
    """Length of the record the logger was set to make [s], if given: a run whose rows
    cover less is partial (:mod:`nfs.io.completeness`)."""
    instrument: str | None = None
    """Free text naming the instrument."""
    extra: dict = field(default_factory=dict)
    """Any other keys of the TOML file, kept and passed along."""


@document_fields
@dataclass(frozen=True)
class Run:
    """One start-up run: named sample columns plus metadata.

    ``columns`` maps each CSV column name to a float array (``moving`` as 0.0/1.0), in file
    order; every array has the same length.
    """

    name: str
    """The stem of the files (``NAME``)."""
    columns: dict[str, np.ndarray]
    """Column name -> samples."""
    meta: RunMeta
    """Metadata from ``NAME.toml``."""
    path: Path | None = None
    """The ``NAME.csv`` this run was read from, if any."""
    caveats: tuple[str, ...] = ()
    """What the reader accepted because it was asked to (a partial run, missing samples),
    one sentence each; every output made from the run states them (:func:`run_caveats`)."""

    def __getitem__(self, column: str) -> np.ndarray:
        return self.columns[column]

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return len(self.columns["time_s"])


def run_caveats(runs) -> list[str]:
    """Every caveat of *runs* (:attr:`Run.caveats`), each prefixed with its run's name, in
    the order given: the sentences an output made from the runs must state."""
    return [f"run '{run.name}': {c}" for run in runs for c in run.caveats]
