"""
A chamber log in three files, brought in with nfs import
========================================================

A test engineer's start-up run rarely comes as one ``nfs-measurement/1`` file: the gyro's
logger writes the rate and the turntable at 10 Hz with time stamps, the unit's built-in
thermometers come at 1 Hz with milliseconds since power-on, the chamber's controller writes
its air temperature every 10 s in minutes, each with its own separator, decimal mark and
units. A small TOML mapping names them (:doc:`../measurement-format`, "Chamber logs: nfs
import"), and :func:`nfs.import_log` (the ``nfs import`` command) puts them on the gyro's
time base by each column's stated method, here linear interpolation for the temperatures;
a gap would be refused, not filled.

The log here is written from a run the package simulates (a 20 min start-up from -20 C, the
chamber ramping 10 K after 5 min), so the imported run can be set beside the truth.
"""

import datetime as dt
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import nfs

SCENARIO = """start_temperatures_c = [-20.0]
duration_s = 1200.0
sample_rate_hz = 10.0
[chamber]
program = [{ hold_s = 300.0 }, { ramp_to_c = -10.0, rate_c_per_min = 1.0 }, { hold_s = 900.0 }]
"""

MAPPING = """[run]
name = "unit7_T-20C"
latitude_deg = 30.26
start_temperature_c = -20.0
true_heading_deg = 212.7
positions_deg = [0.0, 90.0, 180.0, 270.0]
dwell_s = 150.0
move_s = 10.0

[sources.gyro]                 # 10 Hz, time stamps, ';' and a decimal comma, mdeg/h
file = "gyro.csv"
separator = ";"
decimal = ","
time = "Timestamp"
time_format = "%Y-%m-%d %H:%M:%S.%f"
columns.gyro_dph = { column = "Rate", unit = "mdeg/h" }
columns.position_deg = "Table"
columns.moving = "Moving"
columns.acc_x_g = "AccX"
columns.acc_y_g = "AccY"

[sources.thermometers]         # 1 Hz, ms since power-on, kelvin
file = "thermometers.csv"
time = "t_ms"
time_unit = "ms"
columns.temp_fog_c = { column = "T_FOG", unit = "K" }
columns.temp_acc_x_c = { column = "T_QFA_X", unit = "K" }
columns.temp_acc_y_c = { column = "T_QFA_Y", unit = "K" }

[sources.chamber]              # every 10 s, minutes, degC
file = "chamber.csv"
time = "Minutes"
time_unit = "min"
columns.temp_chamber_c = "Air"
"""


def number(value, decimal="."):
    """A value's shortest exact text, with the logger's decimal mark."""
    return repr(float(value)).replace(".", decimal)


def write_log(run, folder):
    """The three files of one start-up, as three loggers would leave them."""
    c, t = run.columns, run.columns["time_s"]
    start = dt.datetime(2024, 3, 1, 8, 0, 0)
    rows = ["Timestamp;Rate;Table;Moving;AccX;AccY"] + [
        ";".join([(start + dt.timedelta(seconds=float(t[k]))).strftime("%Y-%m-%d %H:%M:%S.%f"),
                  number(1000.0 * c["gyro_dph"][k], ","), number(c["position_deg"][k], ","),
                  str(int(c["moving"][k])), number(c["acc_x_g"][k], ","),
                  number(c["acc_y_g"][k], ",")])
        for k in range(t.size)]
    (folder / "gyro.csv").write_text("\n".join(rows) + "\n")
    rows = ["t_ms,T_FOG,T_QFA_X,T_QFA_Y"] + [
        ",".join([str(round(1000 * t[k]))] + [number(c[name][k] + 273.15) for name in
                                               ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c")])
        for k in range(0, t.size, 10)]
    (folder / "thermometers.csv").write_text("\n".join(rows) + "\n")
    rows = ["Minutes,Air"] + [f"{number(t[k] / 60.0)},{number(c['temp_chamber_c'][k])}"
                              for k in range(0, t.size, 100)]
    (folder / "chamber.csv").write_text("\n".join(rows) + "\n")
    (folder / "log.toml").write_text(MAPPING)
    return folder / "log.toml"


with tempfile.TemporaryDirectory() as tmp:
    folder = Path(tmp)
    (folder / "scenario.toml").write_text(SCENARIO)
    scenario = nfs.load_scenario(folder / "scenario.toml")
    truth = nfs.simulate_run(scenario.instrument, scenario.conditions()[0]).run
    mapping = write_log(truth, folder)
    print((folder / "gyro.csv").read_text().splitlines()[1])
    print((folder / "thermometers.csv").read_text().splitlines()[1])
    run = nfs.import_log(mapping)                    # what nfs import writes as NAME.csv/.toml
    logged = {name: np.loadtxt(folder / f"{name}.csv", delimiter=",", skiprows=1)
              for name in ("thermometers", "chamber")}

for line in run.meta.extra["imported"]["resampling"]:
    print("resampling:", line)
fog_error = np.max(np.abs(run["temp_fog_c"] - truth["temp_fog_c"]))
print(f"largest FOG thermometer difference from the truth: {fog_error:.4f} K "
      "(one 0.0625 K quantum: the truth steps between two 1 Hz samples)")

t_min = run["time_s"] / 60.0
fig, (ax_g, ax_t) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, layout="constrained")
ax_g.plot(t_min, run["gyro_dph"], "C0", lw=0.5,
          label="gyro_dph, 10 Hz as logged (mdeg/h -> deg/h); the turntable's four positions")
ax_g.set(ylabel="gyro rate [deg/h]", ylim=(-15.0, 19.0),
         title="Three files on the gyro's time base: run 'unit7_T-20C'")
ax_g.legend(fontsize=8, loc="upper left")
ax_t.plot(t_min, run["temp_chamber_c"], "k", lw=1.2,
          label="temp_chamber_c, linear onto the gyro's times [degC]")
ax_t.plot(logged["chamber"][:, 0], logged["chamber"][:, 1], "ko", ms=3, mfc="none",
          label="chamber log, every 10 s [degC]")
ax_t.plot(t_min, run["temp_fog_c"], "C3", lw=1.2,
          label="temp_fog_c, linear onto the gyro's times [degC]")
ax_t.plot(logged["thermometers"][::20, 0] / 60000.0, logged["thermometers"][::20, 1] - 273.15,
          "C3o", ms=3, mfc="none",
          label="FOG thermometer log, 1 Hz (every 20th shown) [K - 273.15]")
ax_t.set(xlabel="time since power-on [min]", ylabel="temperature [degC]")
ax_t.legend(fontsize=8, loc="upper left")
plt.show()
