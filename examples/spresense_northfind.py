"""Does our single-axis north finder agree with Sony's gyrocompass tool on real data?

Data: ../shared/data/spresense-gyrocompass (see its README): a MEMS IMU (Spresense
CXD5602PWBIMU) logged for about 30 s at each of 8 nominal headings 45 deg apart. The
publisher's tool fits a circle to the per-file means of (gx, gy) (two axes, no tilt
correction); we use the x gyro alone, as a single-axis FOG north finder would, with the
package's multiposition least squares and tilt correction from the x accelerometer.

The 8 files become ONE run (``nfs-measurement/1`` columns): the dwells are concatenated in
time with a gap of ``gap_s`` between files (no samples in the gap, so ``moving`` stays 0 and
the dwells are told apart by the change of ``position_deg``); ``position_deg`` is the nominal
angle of the file name (clockwise seen from above, so the x azimuth is psi + theta);
``gyro_dph`` is gx in deg/h, ``acc_x_g``/``acc_y_g`` are ax/ay over standard gravity, and the
three thermometer columns all hold the board temperature.

Latitude: the site is not published. Omega_h = Omega_ie cos L is what the fit measures, so
L = arccos(Omega_h / Omega_ie) from our own fit, iterated with the tilt correction (which is
the only place L enters) until it settles. The publisher's radius 12.107 deg/h implies
L = 36.4 deg; ours lands within the noise of that (a MEMS gyro's scale factor and the noise
of 8 short dwells leave Omega_h uncertain by about 0.5 deg/h, i.e. about 3 deg of L).

Bias: with tilt correction our b excludes the vertical Earth rate Omega_v * mean(f_x) that the
board's tilt (and the accelerometer's bias) puts into the publisher's bias, about 0.2 deg/h
here; the script prints the uncorrected fit too, which is the publisher's model.

Run: ``python examples/spresense_northfind.py [DATA_FOLDER]``.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from nfs.constants import OMEGA_IE_DPH, STANDARD_GRAVITY_M_S2
import nfs
from nfs.northfind import NorthFindResult, wrap_deg_360

#: Default data folder: <repo>/../shared/data/spresense-gyrocompass.
DATA_DIR = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "spresense-gyrocompass"

#: Nominal angle of each file [deg] (from the file names).
NOMINAL_DEG = (0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0)

#: Timestamp counter frequency [Hz] and wrap (README: 19.2 MHz ticks, wraps at 2^32).
TICK_HZ = 19.2e6
TICK_WRAP = 2 ** 32

RAD_S_TO_DPH = math.degrees(1.0) * 3600.0


@dataclass(frozen=True)
class PublisherResult:
    """The publisher's reference result (data README, 'Reference result')."""

    direction_y_deg: tuple[float, ...] = (1.64, 45.77, 86.42, 140.97, 185.77, 224.73,
                                          272.23, 317.52)
    """Direction of y per file [deg]."""
    bias_x_dph: float = -10.93
    """Gyro bias x [deg/h]."""
    radius_dph: float = 12.107
    """Circle radius, the horizontal Earth rate [deg/h]."""

    @property
    def heading_x_deg(self) -> float:
        """Azimuth of x at position 0: circular mean of (direction_y_k - nominal_k) + 90 [deg]."""
        d = np.radians(np.asarray(self.direction_y_deg) - np.asarray(NOMINAL_DEG))
        return float(wrap_deg_360(math.degrees(math.atan2(np.sin(d).mean(),
                                                          np.cos(d).mean())) + 90.0))

    @property
    def latitude_deg(self) -> float:
        """L implied by the radius [deg]."""
        return math.degrees(math.acos(self.radius_dph / OMEGA_IE_DPH))


PUBLISHER = PublisherResult()


def read_log(path: str | Path) -> dict[str, np.ndarray]:
    """Read one log: time [s] from the wrapped tick counter, temperature [degC], gyro [rad/s]
    (n, 3), accelerometer [m/s^2] (n, 3)."""
    text = Path(path).read_text().split()
    words = np.array([[int(w, 16) for w in line.split(",")] for line in text], dtype=np.uint64)
    ticks = np.mod(np.diff(words[:, 0].astype(np.int64)), TICK_WRAP)
    time_s = np.concatenate(([0.0], np.cumsum(ticks) / TICK_HZ))
    values = words[:, 1:].astype(np.uint32).view(np.float32).astype(float)  # IEEE-754 bits
    return {"time_s": time_s, "temp_c": values[:, 0], "gyro_rad_s": values[:, 1:4],
            "acc_m_s2": values[:, 4:7]}


def load_logs(folder: str | Path = DATA_DIR) -> list[dict[str, np.ndarray]]:
    """The 8 logs in order of nominal angle."""
    folder = Path(folder)
    return [read_log(folder / f"log_imu_{int(a):03d}deg.txt") for a in NOMINAL_DEG]


def spresense_run(logs: list[dict[str, np.ndarray]], *, latitude_deg: float,
                  gap_s: float = 5.0) -> nfs.Run:
    """One run from the 8 logs (see the module docstring)."""
    cols: dict[str, list[np.ndarray]] = {k: [] for k in (
        "time_s", "position_deg", "moving", "gyro_dph", "acc_x_g", "acc_y_g", "temp_fog_c")}
    t0 = 0.0
    for angle, log in zip(NOMINAL_DEG, logs):
        n = log["time_s"].size
        cols["time_s"].append(t0 + log["time_s"])
        cols["position_deg"].append(np.full(n, angle))
        cols["moving"].append(np.zeros(n))
        cols["gyro_dph"].append(log["gyro_rad_s"][:, 0] * RAD_S_TO_DPH)
        cols["acc_x_g"].append(log["acc_m_s2"][:, 0] / STANDARD_GRAVITY_M_S2)
        cols["acc_y_g"].append(log["acc_m_s2"][:, 1] / STANDARD_GRAVITY_M_S2)
        cols["temp_fog_c"].append(log["temp_c"])
        t0 += log["time_s"][-1] + gap_s
    columns = {k: np.concatenate(v) for k, v in cols.items()}
    columns["temp_acc_x_c"] = columns["temp_fog_c"].copy()
    columns["temp_acc_y_c"] = columns["temp_fog_c"].copy()
    meta = nfs.RunMeta(latitude_deg=latitude_deg,
                       start_temperature_c=float(columns["temp_fog_c"][0]),
                       positions_deg=NOMINAL_DEG,
                       instrument="Sony Spresense CXD5602PWBIMU (MEMS)")
    return nfs.Run(name="spresense-gyrocompass", columns=columns, meta=meta)


def north_find_spresense(logs: list[dict[str, np.ndarray]], *, max_iter: int = 10
                         ) -> tuple[nfs.Run, NorthFindResult]:
    """North-find the run, with L from the fitted Omega_h (fixed point, see module docstring)."""
    run = spresense_run(logs, latitude_deg=0.0)
    result = nfs.north_find(run, tilt_correction=False)
    for _ in range(max_iter):
        omega_h = float(result.horizontal_rate_dph[0])
        lat = math.degrees(math.acos(min(1.0, omega_h / OMEGA_IE_DPH)))
        run = replace(run, meta=replace(run.meta, latitude_deg=lat))
        previous, result = result, nfs.north_find(run)
        if abs(result.horizontal_rate_dph[0] - previous.horizontal_rate_dph[0]) < 1e-9:
            break
    return run, result


def standard_error_dph(values: np.ndarray, n_batches: int = 32) -> float:
    """Standard error of the mean of a correlated series by batch means [same unit].

    The samples come in bursts of about 4 at 1 kHz every 30 ms, so they are not independent;
    batches of about 130 samples (about 1 s) are."""
    batches = np.array_split(np.asarray(values, dtype=float), n_batches)
    means = np.array([b.mean() for b in batches])
    return float(means.std(ddof=1) / math.sqrt(n_batches))


def dwell_standard_error_dph(logs: list[dict[str, np.ndarray]]) -> float:
    """Noise sigma_w of one dwell's mean gx [deg/h]: RMS over the files of the batch-means
    standard error."""
    se = [standard_error_dph(log["gyro_rad_s"][:, 0] * RAD_S_TO_DPH) for log in logs]
    return float(np.sqrt(np.mean(np.square(se))))


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    folder = Path(argv[0]) if argv else DATA_DIR
    if not folder.is_dir():
        print(f"no data folder {folder} (expected ../shared/data/spresense-gyrocompass)")
        return 1
    logs = load_logs(folder)
    run, res = north_find_spresense(logs)
    sigma_w = dwell_standard_error_dph(logs)
    n = len(NOMINAL_DEG)
    omega_h = float(res.horizontal_rate_dph[0])
    sig_psi = math.degrees(math.sqrt(2.0 / n) * sigma_w / omega_h)
    sig_b = sigma_w / math.sqrt(n)
    sig_h = math.sqrt(2.0 / n) * sigma_w
    print(f"Spresense gyrocompass data, {run.n_samples} samples in 8 dwells; "
          f"noise of one dwell mean sigma_w = {sigma_w:.2f} deg/h")
    print(f"{'':34s}{'ours (x gyro only)':>22s}{'publisher (gx, gy)':>22s}")
    print(f"{'heading of x at position 0 [deg]':34s}{res.heading_deg[0]:>14.2f} +- {sig_psi:4.2f}"
          f"{PUBLISHER.heading_x_deg:>22.2f}")
    print(f"{'horizontal Earth rate [deg/h]':34s}{omega_h:>14.3f} +- {sig_h:4.2f}"
          f"{PUBLISHER.radius_dph:>22.3f}")
    print(f"{'gyro bias x [deg/h]':34s}{res.bias_dph[0]:>14.3f} +- {sig_b:4.2f}"
          f"{PUBLISHER.bias_x_dph:>22.3f}")
    raw = nfs.north_find(run, tilt_correction=False)  # the publisher's model
    print(f"{'  same, no tilt correction':34s}{raw.bias_dph[0]:>14.3f} +- {sig_b:4.2f}")
    print(f"{'latitude from Omega_h [deg]':34s}{run.meta.latitude_deg:>22.2f}"
          f"{PUBLISHER.latitude_deg:>22.2f}")
    print(f"{'fit residual RMS [deg/h]':34s}{res.residual_dph[0]:>22.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
