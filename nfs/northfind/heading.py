"""North-find a whole run, cycle by cycle, and score its heading by stage.

The chain (docs/physics.md section 5): dwells and cycles (:mod:`nfs.northfind.segment`) -> mean
gyro rate and mean x specific force of every dwell -> tilt correction -> least squares per
cycle (:mod:`nfs.northfind.solve`) -> heading psi and its error against the true heading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nfs.constants import POSITION_TOL_DEG
from nfs.docfields import document_fields
from nfs.errors import MeasurementError, NfsError
from nfs.run import Run
from nfs.northfind.segment import Cycle, dwell_samples, find_dwells, segment_cycles
from nfs.northfind.level import LEVEL_UP, gravity_and_biases, level_heading, level_two_position
from nfs.northfind.solve import (distinct_angles, remove_vertical_rate, solve_heading,
                                 solve_xyb_stack, wrap_deg_180, wrap_deg_360)

__all__ = ["NorthFindResult", "north_find", "StageRMSE", "heading_rmse"]


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


@document_fields
@dataclass(frozen=True)
class NorthFindResult:
    """North-finding result of one run: one entry per cycle (arrays are read-only)."""

    run_name: str
    """Name of the run."""
    cycles: tuple[Cycle, ...]
    """The cycles, with their dwells and sample ranges."""
    t_start_s: np.ndarray
    """Time of the first sample used in each cycle [s]."""
    t_end_s: np.ndarray
    """Time of the last sample used in each cycle [s]."""
    heading_deg: np.ndarray
    """Heading psi of each cycle: azimuth of the x axis at theta = 0, in [0, 360) [deg]."""
    error_deg: np.ndarray
    """heading_deg - true_heading_deg wrapped to [-180, 180) [deg]; NaN when the true
    heading is unknown."""
    bias_dph: np.ndarray
    """Gyro bias b fitted in each cycle [deg/h] (with tilt correction, less the vertical
    Earth rate of the x accelerometer's constant reading: :mod:`nfs.northfind.level`)."""
    horizontal_rate_dph: np.ndarray
    """Horizontal Earth rate sqrt(X^2 + Y^2) fitted in each cycle [deg/h]."""
    residual_dph: np.ndarray
    """RMS of the fit residuals over the positions of each cycle [deg/h]."""
    theta_deg: np.ndarray
    """Turntable angle theta_k of each dwell, shape (n_cycles, n_positions) [deg]."""
    rate_dph: np.ndarray
    """Mean gyro rate w_k of each dwell before tilt correction, (n_cycles, n_positions) [deg/h]."""
    acc_x_g: np.ndarray
    """Mean x specific force f_x = sin e_k of each dwell, (n_cycles, n_positions) [g]
    (NaN when tilt correction is off and the run has no acc_x_g)."""
    true_heading_deg: float | None
    """The run's true heading [deg], if known."""
    latitude_deg: float
    """Latitude L used for tilt correction [deg]."""
    tilt_correction: bool
    """Whether the rates were tilt-corrected."""
    ambiguous: bool = False
    """True when two-position cycles left the sign of psi unresolved (see solve_heading)."""
    up_table: np.ndarray | None = None
    """U_T, the up unit vector in the table frame (x_T, y_T at theta = 0, z_T down) of each
    cycle, (n_cycles, 3), fitted from both accelerometers (:mod:`nfs.northfind.level`);
    (0, 0, -1) when tilt correction is off."""
    acc_y_g: np.ndarray | None = None
    """Mean y specific force of each dwell, (n_cycles, n_positions) [g] (NaN when tilt
    correction is off and the run has no acc_y_g)."""
    acc_bias_g: np.ndarray | None = None
    """Accelerometer biases (b_x, b_y) fitted with U_T in each cycle, (n_cycles, 2) [g]
    (NaN when tilt correction is off)."""
    n_missing: dict[str, int] | None = None
    """Samples inside the dwells with no value, by column (``gyro_dph``, ``acc_x_g``,
    ``acc_y_g``): left out of their dwell means (a dwell without any is NaN)."""

    @property
    def n_cycles(self) -> int:
        """Number of cycles."""
        return len(self.cycles)


def _column(run: Run, name: str) -> np.ndarray:
    try:
        return np.asarray(run.columns[name], dtype=float)
    except KeyError:
        raise MeasurementError(f"run '{run.name}' has no column '{name}' (columns: "
                               f"{', '.join(run.columns)})", file=run.path,
                               column=name) from None


def _dwell_means(values: np.ndarray, idx: np.ndarray, owner: np.ndarray,
                 n: int) -> tuple[np.ndarray, int]:
    """Mean of the finite values over each dwell (NaN for a dwell without one), and how
    many of the dwells' values are not finite."""
    v = values[idx]
    ok = np.isfinite(v)
    count = np.bincount(owner, ok, minlength=n)
    total = np.bincount(owner, np.where(ok, v, 0.0), minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    return means, int(v.size - np.count_nonzero(ok))


#: The last segmentation of :func:`north_find`, (inputs, (cycles, idx, owner)): the runs of
#: a batch (a sweep's cells, a study's start-ups) share their time base and turntable
#: motion, so a batch is segmented once.  The inputs are kept as copies and compared in full
#: (a run with another motion is segmented anew); the cycles are frozen, the index arrays
#: read-only, so the runs share them safely.
_LAST_SEGMENTS: list = [None]


def _segments(time_s: np.ndarray, position_deg: np.ndarray, moving: np.ndarray,
              positions_deg, dwell_s, settle_s: float, position_tol_deg: float):
    """(cycles, idx, owner) of a run: :func:`segment_cycles` and the dwells' samples
    (:func:`dwell_samples`), remembered for the next run with the same motion
    (:data:`_LAST_SEGMENTS`)."""
    key = (None if positions_deg is None else tuple(positions_deg), dwell_s, settle_s,
           position_tol_deg)
    last = _LAST_SEGMENTS[0]
    if last is not None:
        (k, t, p, m), found = last
        if (k == key and t.shape == time_s.shape and np.array_equal(t, time_s)
                and np.array_equal(p, position_deg, equal_nan=True)
                and np.array_equal(m, moving, equal_nan=True)):
            return found
    cycles = tuple(segment_cycles(time_s, position_deg, moving, positions_deg,
                                  dwell_s=dwell_s, settle_s=settle_s,
                                  position_tol_deg=position_tol_deg))
    dwells = [d for c in cycles for d in c.dwells]
    idx, owner = dwell_samples([d.start for d in dwells], [d.stop for d in dwells])
    idx.flags.writeable = owner.flags.writeable = False
    found = (cycles, idx, owner)
    _LAST_SEGMENTS[0] = ((key, time_s.copy(), position_deg.copy(), moving.copy()), found)
    return found


def north_find(run: Run, *, tilt_correction: bool = True, settle_s: float = 0.0,
               gyro_column: str = "gyro_dph", heading_hint_deg: float | None = None,
               position_tol_deg: float = POSITION_TOL_DEG) -> NorthFindResult:
    """North-find every complete cycle of a run (docs/physics.md section 5).

    Per dwell: the mean gyro rate w_k and the mean readings of both accelerometers. Per
    cycle: least squares of w_k - Omega_ie sin L f_x,k = X cos theta_k - Y sin theta_k + b,
    and of the accelerometers for the up vector U_T in the table frame; the heading is
    levelled exactly with U_T (:mod:`nfs.northfind.level`: any tilt, to rounding, for a
    rigid table).
    Without tilt correction the table is taken as level: psi = atan2(Y, X).  Two positions
    180 deg apart: the two-position method of :func:`~nfs.northfind.level.level_two_position`
    (latitude known; the sign of psi + theta_a from ``heading_hint_deg``, else the cycles
    are marked ambiguous).

    Before exact levelling the fit was w_k - Omega_ie sin L f_x,k = cos e_k (X cos theta_k -
    Y sin theta_k) + b with sin e_k = f_x,k (exact for docs/physics.md section 4's first-order
    tilt model); the two differ at second order in the tilt
    (:func:`~nfs.northfind.budget.tilt_model_error_deg`).

    Parameters
    ----------
    run : Run
        The run; uses ``time_s``, ``position_deg``, ``moving``, the gyro column,
        ``acc_x_g`` and ``acc_y_g``, and from the metadata ``latitude_deg``, ``positions_deg``,
        ``dwell_s``
        and ``true_heading_deg``.
    tilt_correction : bool
        Level with the accelerometers (else the table is taken as level).
    settle_s : float
        Time dropped at the start of every dwell [s].
    gyro_column : str
        Column holding the rate about x [deg/h] (e.g. a compensated output).
    heading_hint_deg : float, optional
        Approximate heading that resolves the sign of a two-position schedule.
    position_tol_deg : float
        Angle tolerance of :func:`segment_cycles` [deg].

    Returns
    -------
    NorthFindResult

    Raises
    ------
    MeasurementError
        A column is missing, or the run holds no complete cycle.
    NfsError
        The schedule cannot determine psi.
    """
    meta = run.meta
    time_s = _column(run, "time_s")
    gyro = _column(run, gyro_column)
    cycles, idx, owner = _segments(time_s, _column(run, "position_deg"),
                                   _column(run, "moving"), meta.positions_deg, meta.dwell_s,
                                   settle_s, position_tol_deg)
    if not cycles:
        n_dwells = len(find_dwells(time_s, run.columns["position_deg"], run.columns["moving"],
                                   dwell_s=meta.dwell_s, settle_s=settle_s,
                                   position_tol_deg=position_tol_deg))
        sched = "recovered" if meta.positions_deg is None else list(meta.positions_deg)
        raise MeasurementError(f"run '{run.name}': no complete north-finding cycle "
                               f"({n_dwells} dwells found, schedule {sched})", file=run.path)
    n_cyc, n_pos = len(cycles), len(cycles[0].dwells)
    dwells = [d for c in cycles for d in c.dwells]
    shape = (n_cyc, n_pos)
    theta = np.array([d.theta_deg for d in dwells]).reshape(shape)
    rate, bad = _dwell_means(gyro, idx, owner, len(dwells))
    rate = rate.reshape(shape)
    missing = {gyro_column: bad}
    acc = {}
    for col in ("acc_x_g", "acc_y_g"):
        if tilt_correction or col in run.columns:
            means, missing[col] = _dwell_means(_column(run, col), idx, owner, len(dwells))
            acc[col] = means.reshape(shape)
        else:
            acc[col] = np.full(shape, np.nan)
    acc_x, acc_y = acc["acc_x_g"], acc["acc_y_g"]

    theta_rad = np.radians(theta)
    bias = np.full((n_cyc, 2), np.nan)
    if tilt_correction:
        up, bias[:, 0], bias[:, 1] = gravity_and_biases(theta_rad, acc_x, acc_y)
        y, _ = remove_vertical_rate(rate, acc_x, meta.latitude_deg)
    else:
        up, y = np.tile(LEVEL_UP, (n_cyc, 1)), rate

    x_dph, y_dph, b_dph, omh, rms, psi = (np.full(n_cyc, np.nan) for _ in range(6))
    ok = np.all(np.isfinite(y), axis=1) & np.all(np.isfinite(up), axis=1)
    ambiguous = False
    distinct = distinct_angles(theta_rad[0], math.radians(position_tol_deg))
    if len(distinct) >= 3:
        if np.any(ok):
            x_dph[ok], y_dph[ok], b_dph[ok], rms[ok] = solve_xyb_stack(theta_rad[ok], y[ok])
            psi[ok], omh[ok] = level_heading(x_dph[ok], y_dph[ok], up[ok])
        psi = np.degrees(psi)
    elif len(distinct) == 2 and abs(abs(math.remainder(distinct[1] - distinct[0], 2 * math.pi))
                                    - math.pi) <= math.radians(position_tol_deg):
        if np.any(ok):
            p, omh[ok], b_dph[ok], rms[ok], ambiguous = level_two_position(
                theta_rad[ok], y[ok], up[ok], meta.latitude_deg, heading_hint_deg)
            psi[ok] = np.degrees(p)
            x_dph[ok], y_dph[ok] = omh[ok] * np.cos(p), omh[ok] * np.sin(p)
    else:  # the error message of solve_heading names what is missing
        solve_heading(theta[0], rate[0], latitude_deg=meta.latitude_deg,
                      angle_tol_deg=position_tol_deg)
    heading = wrap_deg_360(psi)
    true = meta.true_heading_deg
    error = (np.full(n_cyc, np.nan) if true is None
             else wrap_deg_180(np.asarray(heading) - true))
    return NorthFindResult(
        run_name=run.name, cycles=tuple(cycles),
        t_start_s=_frozen([c.t_start_s for c in cycles]),
        t_end_s=_frozen([c.t_end_s for c in cycles]),
        heading_deg=_frozen(heading), error_deg=_frozen(error), bias_dph=_frozen(b_dph),
        horizontal_rate_dph=_frozen(omh), residual_dph=_frozen(rms),
        theta_deg=_frozen(theta), rate_dph=_frozen(rate), acc_x_g=_frozen(acc_x),
        true_heading_deg=true, latitude_deg=float(meta.latitude_deg),
        tilt_correction=bool(tilt_correction), ambiguous=bool(ambiguous),
        up_table=_frozen(up), acc_y_g=_frozen(acc_y), acc_bias_g=_frozen(bias),
        n_missing={k: v for k, v in missing.items() if v})


@document_fields
@dataclass(frozen=True)
class StageRMSE:
    """Heading RMSE of the start-up and the stable stage of a run (the FOG start-up paper, Table 3)."""

    startup_deg: float
    """RMS heading error of the cycles ending within the start-up stage [deg] (NaN if none)."""
    stable_deg: float
    """RMS heading error of the cycles starting in the stable stage [deg] (NaN if none)."""
    n_startup: int
    """Number of start-up cycles with a finite error."""
    n_stable: int
    """Number of stable cycles with a finite error."""


def heading_rmse(result: NorthFindResult, *, startup_end_s: float = 3600.0,
                 stable_start_s: float = 5400.0) -> StageRMSE:
    """RMS heading error by stage.

    Start-up: cycles with ``t_end_s <= startup_end_s`` (ending within the first
    ``startup_end_s`` after power-on). Stable: cycles with ``t_start_s >= stable_start_s``.
    Cycles in between belong to neither; cycles with a NaN error (no data) are left out.

    Raises
    ------
    NfsError
        When the run's true heading is unknown (no error to score).
    """
    if result.true_heading_deg is None:
        raise NfsError(f"run '{result.run_name}' has no true_heading_deg: its heading error "
                       "cannot be scored")
    err = np.asarray(result.error_deg)
    fin = np.isfinite(err)
    up = fin & (np.asarray(result.t_end_s) <= startup_end_s)
    st = fin & (np.asarray(result.t_start_s) >= stable_start_s)

    def rms(mask):
        return float(np.sqrt(np.mean(err[mask] ** 2))) if np.any(mask) else math.nan

    return StageRMSE(rms(up), rms(st), int(up.sum()), int(st.sum()))

