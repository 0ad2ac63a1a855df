"""The indexing turntable: position schedule and the tilt of its axis (docs/physics.md 4, 5)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import NfsError

__all__ = ["ORDERS", "Schedule", "turntable_motion", "axis_elevation_deg"]

#: Position orders: ``sequential`` repeats theta_1..theta_N; ``forward-reverse`` runs
#: theta_1..theta_N then theta_N..theta_1 (cancels a linear drift exactly, docs/physics.md 5).
ORDERS = ("sequential", "forward-reverse")


@dataclass(frozen=True)
class Schedule:
    """A north-finding schedule: which positions, how long at each, how long to move."""

    positions_deg: tuple[float, ...]
    """theta_k, the turntable angles of one pass [deg]."""
    dwell_s: float
    """Time at each position [s]."""
    move_s: float
    """Time for each move between positions [s] (also between two dwells at one angle)."""
    order: str = "sequential"
    """One of :data:`ORDERS`."""

    def __post_init__(self) -> None:
        if len(self.positions_deg) == 0:
            raise NfsError("schedule: the position list is empty")
        if self.order not in ORDERS:
            raise NfsError(f"schedule: order '{self.order}' is not one of {', '.join(ORDERS)}")
        if not self.dwell_s > 0:
            raise NfsError(f"schedule: dwell_s must be > 0, got {self.dwell_s}")
        if not self.move_s >= 0:
            raise NfsError(f"schedule: move_s must be >= 0, got {self.move_s}")

    @property
    def cycle_positions_deg(self) -> tuple[float, ...]:
        """The angles of one north-finding cycle in the order visited [deg]."""
        p = tuple(float(x) for x in self.positions_deg)
        return p + p[::-1] if self.order == "forward-reverse" else p

    @property
    def step_s(self) -> float:
        """Delta, time from the start of one dwell to the start of the next [s]."""
        return self.dwell_s + self.move_s

    @property
    def cycle_s(self) -> float:
        """Duration of one cycle [s]."""
        return self.step_s * len(self.cycle_positions_deg)


def turntable_motion(schedule: Schedule, time_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Turntable angle theta(t) [deg, in [0, 360)] and the moving flag at each sample.

    Cycles run back to back from t = 0: dwell at theta_1 for dwell_s, move for move_s to
    theta_2 at constant speed, ... and after the last angle of a cycle, move to the first
    angle of the next.  A move turns by the signed difference of the angles (no wrap: the
    table rewinds, as a cable-limited indexer does); between two equal angles the table holds
    still for move_s with the flag set (settling), so every step lasts dwell_s + move_s.
    """
    t = np.asarray(time_s, dtype=float)
    angles = np.asarray(schedule.cycle_positions_deg)
    n = len(angles)
    step = schedule.step_s
    k = np.floor(t / step).astype(np.int64)           # global step index
    tau = t - k * step                                 # time inside the step
    start = angles[k % n]
    end = angles[(k + 1) % n]
    moving = tau >= schedule.dwell_s
    frac = np.where(moving, (tau - schedule.dwell_s) / max(schedule.move_s, 1e-300), 0.0)
    theta = np.mod(start + frac * (end - start), 360.0)
    return theta, moving


def axis_elevation_deg(azimuth_deg: np.ndarray, tilt_north_deg: float,
                       tilt_east_deg: float) -> np.ndarray:
    """Elevation of a horizontal-on-table axis of azimuth A on a tilted turntable [deg].

    e = alpha_N cos A + alpha_E sin A (small-angle, docs/physics.md section 4): alpha_N and
    alpha_E are the tilts of the table toward north and east (the north / east edge up).
    """
    a = np.radians(azimuth_deg)
    return tilt_north_deg * np.cos(a) + tilt_east_deg * np.sin(a)
