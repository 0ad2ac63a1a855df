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

__all__ = ["REQUIRED_COLUMNS", "NO_MISSING_COLUMNS", "RunMeta", "Run"]

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

    def __getitem__(self, column: str) -> np.ndarray:
        return self.columns[column]

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return len(self.columns["time_s"])
