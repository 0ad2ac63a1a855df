"""An ideal north-finder run built from the rate model of docs/physics.md section 5.

For checking the north-finding chain against closed forms (tests, benchmarks): the gyro sees
only the Earth-rate projection with turntable tilt, a constant bias, an optional drift
b(t) and optional white noise. It is not the simulator (no thermal network, no named
effects).

Model, per dwell at turntable angle theta_k: the table is tilted exactly by the pitch
alpha_N and the roll alpha_E (:func:`nfs.effects.geometry.tilt_matrix`), and the x axis,
whose horizontal projection has the azimuth psi at theta = 0, has azimuth A_k and
elevation e_k at theta_k (A_k = psi + theta_k and e_k = alpha_N cos A_k + alpha_E sin A_k
to first order, docs/physics.md section 4):

    gyro  = Omega_ie cos L cos A_k cos e_k + Omega_ie sin L sin e_k + b + drift(t) + noise
    acc_x = sin e_k,   acc_y = sin(elevation of y)

White noise has the standard deviation (ARW * 60) sqrt(fs) deg/h per sample (docs/physics.md
section 3). Samples while moving carry the Earth-rate projection at the interpolated angle
(no table rate): north finding does not use them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from nfs.effects.geometry import Geometry
from nfs.errors import NfsError
from nfs.run import Run, RunMeta
from nfs.sensors import earth_rate_along_axis_dph

__all__ = ["synthetic_run"]


def synthetic_run(*, heading_deg: float, latitude_deg: float = 30.0,
                  positions_deg: Sequence[float] = (0.0, 90.0, 180.0, 270.0),
                  dwell_s: float = 150.0, move_s: float = 10.0, n_cycles: int | None = None,
                  duration_s: float | None = None, sample_rate_hz: float = 1.0,
                  tilt_north_deg: float = 0.0, tilt_east_deg: float = 0.0,
                  bias_dph: float = 0.0,
                  drift_dph: Callable[[np.ndarray], np.ndarray] | None = None,
                  arw_deg_per_rth_h: float = 0.0, skip_null_moves: bool = True,
                  name: str = "synthetic",
                  random_state: int | np.random.Generator | None = None) -> Run:
    """Build an ideal multiposition run (see the module docstring for the model).

    The run starts with the first dwell of the first cycle at t = 0; each later dwell is
    preceded by a move of ``move_s``, except between two dwells at the same angle when
    ``skip_null_moves`` (then the dwells touch, as in the (270, 270) pair of a
    forward-then-reverse cycle).

    Parameters
    ----------
    heading_deg : float
        True heading psi [deg].
    latitude_deg : float
        Latitude L [deg].
    positions_deg : sequence of float
        Schedule of one cycle [deg].
    dwell_s, move_s : float
        Time at each position and per move [s]; rounded to whole samples.
    n_cycles : int, optional
        Number of complete cycles; or give ``duration_s`` (the last cycle may be partial).
    duration_s : float, optional
        Length of the run [s].
    sample_rate_hz : float
        Sample rate fs [Hz].
    tilt_north_deg, tilt_east_deg : float
        Turntable tilt alpha_N (pitch, north edge up), alpha_E (roll, east edge up) [deg],
        applied as an exact rotation.
    bias_dph : float
        Constant gyro bias b [deg/h].
    drift_dph : callable, optional
        drift(time_s) -> rate [deg/h] added to the gyro.
    arw_deg_per_rth_h : float
        Angle random walk [deg/sqrt(h)] of white rate noise.
    skip_null_moves : bool
        No move between consecutive dwells at the same angle.
    name : str
        Run name.
    random_state : int or numpy.random.Generator, optional
        Seed of the noise.

    Returns
    -------
    Run
    """
    if (n_cycles is None) == (duration_s is None):
        raise NfsError("give exactly one of n_cycles and duration_s")
    fs = float(sample_rate_hz)
    n_dwell = int(round(dwell_s * fs))
    n_move = int(round(move_s * fs))
    sched = np.asarray(positions_deg, dtype=float)
    if n_dwell < 1 or sched.size == 0:
        raise NfsError("need dwell_s * sample_rate_hz >= 1 and a non-empty schedule")
    if n_cycles is not None:
        n_samples = None
        angles = np.tile(sched, n_cycles)
    else:
        n_samples = int(round(duration_s * fs))
        angles = np.resize(sched, n_samples // n_dwell + 1)  # more dwells than fit
    prev = np.concatenate(([angles[0]], angles[:-1]))
    step = np.mod(angles - prev + 180.0, 360.0) - 180.0  # shortest way round
    moves = np.where((np.abs(step) < 1e-9) & skip_null_moves, 0, n_move)
    moves[0] = 0
    seg_len = moves + n_dwell
    if n_samples is not None:
        keep = int(np.searchsorted(np.cumsum(seg_len), n_samples, side="left")) + 1
        angles, prev, step = angles[:keep], prev[:keep], step[:keep]
        moves, seg_len = moves[:keep], seg_len[:keep]
    owner = np.repeat(np.arange(angles.size), seg_len)
    pos_in_seg = np.arange(owner.size) - (np.cumsum(seg_len) - seg_len)[owner]
    is_move = pos_in_seg < moves[owner]
    frac = np.where(is_move, (pos_in_seg + 1) / np.maximum(moves[owner] + 1, 1), 1.0)
    position = np.mod(prev[owner] + frac * step[owner], 360.0)
    if n_samples is not None:
        position, is_move = position[:n_samples], is_move[:n_samples]
    n = position.size
    time_s = np.arange(n) / fs

    axes = Geometry(time_s=time_s, position_deg=position, moving=is_move,
                    positions_deg=tuple(float(p) for p in sched), heading_deg=heading_deg,
                    rng=np.random.default_rng(0), theta_deg=position,
                    tilt_north_deg=tilt_north_deg, tilt_east_deg=tilt_east_deg,
                    exact_tilt=True).azimuth_elevation()
    (azimuth, e_x), (_, e_y) = axes["x"], axes["y"]
    gyro = earth_rate_along_axis_dph(azimuth, e_x, latitude_deg) + bias_dph
    if drift_dph is not None:
        gyro = gyro + np.asarray(drift_dph(time_s), dtype=float)
    if arw_deg_per_rth_h > 0:
        rng = np.random.default_rng(random_state)
        gyro = gyro + rng.normal(0.0, arw_deg_per_rth_h * 60.0 * math.sqrt(fs), n)
    temp = np.full(n, 25.0)
    columns = {
        "time_s": time_s, "position_deg": position, "moving": is_move.astype(float),
        "gyro_dph": gyro, "acc_x_g": np.sin(np.radians(e_x)), "acc_y_g": np.sin(np.radians(e_y)),
        "temp_fog_c": temp, "temp_acc_x_c": temp.copy(), "temp_acc_y_c": temp.copy(),
    }
    meta = RunMeta(latitude_deg=latitude_deg, start_temperature_c=25.0,
                   true_heading_deg=heading_deg,
                   sample_rate_hz=fs, positions_deg=tuple(float(p) for p in sched),
                   dwell_s=n_dwell / fs, move_s=n_move / fs, instrument="ideal (synthetic)")
    return Run(name=name, columns=columns, meta=meta)
