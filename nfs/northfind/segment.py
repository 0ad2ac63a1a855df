"""Split a run into dwells and north-finding cycles.

A *dwell* is a stretch of samples at one turntable angle theta_k with ``moving == 0``; a
*cycle* is one pass through the position schedule (e.g. 0, 90, 180, 270, or the
forward-then-reverse 0, 90, 180, 270, 270, 180, 90, 0 of docs/physics.md section 5).

How dwells are found
--------------------
1. Stationary blocks: maximal runs of samples with ``moving == 0`` (and finite position)
   whose position changes by at most ``position_tol_deg`` from one sample to the next.
2. A block may hold several dwells at the same angle when no move (or a zero-length move)
   separates them, as the (270, 270) pair of a forward-then-reverse cycle, or the last
   position of a cycle and the first of the next. Such a block lasts about m dwells: it is
   split into m = round(duration / dwell_s) dwells of equal duration (at least 1). The dwell
   time is ``dwell_s`` when given, otherwise the median block duration (valid when most
   dwells are separated by moves, as in every usual schedule).

How dwells are grouped into cycles
----------------------------------
- With a schedule (``positions_deg``): the dwells are scanned in time order; wherever the
  next len(schedule) dwell angles match the schedule (modulo 360, within
  ``position_tol_deg``) they form a cycle and the scan jumps past them, otherwise the scan
  moves on by one dwell (a partial cycle at the start or the end is left out).
- Without a schedule: the first dwell is taken to start a cycle and the schedule is the
  shortest period P <= n/2 of the sequence of dwell angles (angle[i] == angle[i + P] for every
  i); when there is no such period the whole sequence is one cycle. A schedule that repeats
  itself within one cycle (0, 180, 0, 180) is thus read as the shorter one; pass
  ``positions_deg`` to say otherwise.

``settle_s`` drops the first seconds of every dwell (turntable ringing after a move); it is
applied to every dwell alike, including the second of a pair without a move, so that the
time symmetry of a forward-then-reverse cycle is kept.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nfs.constants import POSITION_TOL_DEG
from nfs.errors import NfsError
from nfs.northfind.solve import wrap_deg_180, wrap_deg_360

__all__ = ["Dwell", "Cycle", "segment_cycles", "find_dwells"]


@dataclass(frozen=True)
class Dwell:
    """One dwell: the samples used at one turntable position."""

    theta_deg: float
    """Turntable angle theta_k: circular mean of ``position_deg`` over the dwell, in
    [0, 360) [deg]."""
    start: int
    """Index of the first sample used."""
    stop: int
    """One past the index of the last sample used."""
    t_start_s: float
    """Time of the first sample used [s]."""
    t_end_s: float
    """Time of the last sample used [s]."""

    @property
    def index(self) -> slice:
        """The samples of the dwell, as a slice into the run's columns."""
        return slice(self.start, self.stop)


@dataclass(frozen=True)
class Cycle:
    """One north-finding cycle: consecutive dwells following the position schedule."""

    dwells: tuple[Dwell, ...]
    """The dwells in time order."""

    @property
    def t_start_s(self) -> float:
        """Time of the first sample used in the cycle [s]."""
        return self.dwells[0].t_start_s

    @property
    def t_end_s(self) -> float:
        """Time of the last sample used in the cycle [s]."""
        return self.dwells[-1].t_end_s

    @property
    def theta_deg(self) -> np.ndarray:
        """Turntable angle of each dwell [deg]."""
        return np.array([d.theta_deg for d in self.dwells])


def dwell_samples(start, stop):
    """Sample indices of consecutive index ranges [start_i, stop_i) and the range of each.

    Returns ``(idx, owner)``: ``values[idx]`` are the samples of all ranges one after the
    other and ``owner[j]`` is the range of ``idx[j]`` (for ``np.bincount`` reductions).
    """
    start = np.asarray(start, dtype=np.intp).ravel()
    lengths = np.asarray(stop, dtype=np.intp).ravel() - start
    owner = np.repeat(np.arange(start.size), lengths)
    offsets = np.cumsum(lengths) - lengths
    return start[owner] + (np.arange(owner.size) - offsets[owner]), owner


def _blocks(time_s, position_deg, moving, position_tol_deg):
    """Start and stop indices of the stationary blocks."""
    still = (np.asarray(moving) == 0) & np.isfinite(position_deg) & np.isfinite(time_s)
    jump = np.abs(wrap_deg_180(position_deg[1:] - position_deg[:-1])) > position_tol_deg
    # a block starts where a still sample follows a non-still one, or the position jumps
    start = still.copy()
    start[1:] &= ~still[:-1] | jump
    stop = still.copy()
    stop[:-1] &= ~still[1:] | jump
    return np.flatnonzero(start), np.flatnonzero(stop) + 1


def find_dwells(time_s, position_deg, moving, *, dwell_s: float | None = None,
                settle_s: float = 0.0, position_tol_deg: float = POSITION_TOL_DEG) -> list[Dwell]:
    """All dwells of a run in time order (steps 1 and 2 of the module docstring).

    Parameters are those of :func:`segment_cycles`.
    """
    time_s = np.asarray(time_s, dtype=float)
    position_deg = np.asarray(position_deg, dtype=float)
    moving = np.asarray(moving)
    n = time_s.size
    if position_deg.size != n or moving.size != n:
        raise NfsError(f"time_s, position_deg and moving must have the same length; got "
                       f"{n}, {position_deg.size}, {moving.size}")
    if settle_s < 0:
        raise NfsError(f"settle_s must be >= 0, got {settle_s}")
    if dwell_s is not None and not dwell_s > 0:
        raise NfsError(f"dwell_s must be > 0, got {dwell_s}")
    if n < 2:
        return []
    dt = float(np.median(np.diff(time_s)))
    starts, stops = _blocks(time_s, position_deg, moving, position_tol_deg)
    if starts.size == 0:
        return []
    durations = time_s[stops - 1] - time_s[starts] + dt
    tau = float(np.median(durations)) if dwell_s is None else float(dwell_s)
    counts = np.maximum(1, np.rint(durations / tau).astype(int))

    # split blocks holding several dwells into equal parts by time (time_s increases)
    blk = np.repeat(np.arange(starts.size), counts)
    j = np.arange(blk.size) - (np.cumsum(counts) - counts)[blk]
    d_t0 = time_s[starts][blk] + durations[blk] * j / counts[blk]
    d_start = np.maximum(starts[blk], np.searchsorted(time_s, d_t0 - 1e-9 * dt, side="left"))
    d_stop = np.where(j == counts[blk] - 1, stops[blk], np.append(d_start[1:], 0))
    if settle_s > 0:
        t_first = d_t0 + settle_s
        moved = np.maximum(d_start, np.searchsorted(time_s, t_first - 1e-9 * dt, side="left"))
        if np.any(moved >= d_stop):
            k = int(np.argmax(moved >= d_stop))
            raise NfsError(f"settle_s = {settle_s} s leaves no sample in the dwell starting at "
                           f"t = {time_s[d_start[k]]:g} s")
        d_start = moved

    # circular mean of the position over each dwell, relative to its first sample
    ref = position_deg[d_start]
    idx, owner = dwell_samples(d_start, d_stop)
    rel = wrap_deg_180(position_deg[idx] - ref[owner])
    theta = wrap_deg_360(ref + np.bincount(owner, rel) / (d_stop - d_start))
    return [Dwell(float(th), int(a), int(b), float(time_s[a]), float(time_s[b - 1]))
            for th, a, b in zip(theta, d_start, d_stop)]


def _same_angles(a, b, tol):
    return bool(np.all(np.abs(wrap_deg_180(np.asarray(a) - np.asarray(b))) <= tol))


def _period(theta, tol):
    """Shortest period P <= n/2 of a sequence of angles, or n when there is none."""
    n = len(theta)
    for p in range(1, n // 2 + 1):
        if _same_angles(theta[p:], theta[:-p], tol):
            return p
    return n


def segment_cycles(time_s, position_deg, moving, positions_deg=None, *,
                   dwell_s: float | None = None, settle_s: float = 0.0,
                   position_tol_deg: float = POSITION_TOL_DEG) -> list[Cycle]:
    """Find the dwells of a run and group them into north-finding cycles.

    See the module docstring for the rules (blocks, splitting of same-angle blocks,
    matching to the schedule or recovering it).

    Parameters
    ----------
    time_s : array_like
        Sample times [s], increasing.
    position_deg : array_like
        Turntable angle of each sample [deg].
    moving : array_like
        1 while the turntable moves, 0 at rest.
    positions_deg : sequence of float, optional
        The schedule of one cycle [deg] (``RunMeta.positions_deg``); recovered from the
        dwells when not given.
    dwell_s : float, optional
        Time at each position [s] (``RunMeta.dwell_s``); used to split blocks that hold
        several dwells. Estimated as the median block duration when not given.
    settle_s : float
        Time dropped at the start of every dwell [s].
    position_tol_deg : float
        Tolerance on angles [deg]: a larger step between consecutive samples ends a block;
        dwell angles match the schedule within it.

    Returns
    -------
    list of Cycle
        Complete cycles in time order (possibly empty).
    """
    dwells = find_dwells(time_s, position_deg, moving, dwell_s=dwell_s, settle_s=settle_s,
                         position_tol_deg=position_tol_deg)
    if not dwells:
        return []
    theta = np.array([d.theta_deg for d in dwells])
    if positions_deg is None:
        p = _period(theta, position_tol_deg)
        return [Cycle(tuple(dwells[i:i + p])) for i in range(0, len(dwells) - p + 1, p)]
    sched = np.asarray(positions_deg, dtype=float).ravel()
    if sched.size == 0:
        raise NfsError("positions_deg is empty")
    n_pos = sched.size
    cycles = []
    i = 0
    while i + n_pos <= len(dwells):
        if _same_angles(theta[i:i + n_pos], sched, position_tol_deg):
            cycles.append(Cycle(tuple(dwells[i:i + n_pos])))
            i += n_pos
        else:
            i += 1
    return cycles

