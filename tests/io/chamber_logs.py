"""A chamber log of three files written from a run the package simulates, for the tests of
``nfs import`` (tests/io/test_import_*.py).

The log, as a test engineer's loggers leave it:

- ``gyro.csv``: 10 Hz, absolute time stamps (``%Y-%m-%d %H:%M:%S.%f``), ';' separated with
  a decimal comma, the rate in mdeg/h, the turntable's angle and moving flag, the
  accelerometers in m/s^2;
- ``thermometers.csv``: 1 Hz (every tenth gyro sample), times in ms from power-on, ','
  separated, the three built-in thermometers in kelvin;
- ``chamber.csv``: 0.1 Hz (every hundredth), times in minutes, tab separated after a
  two-line preamble, the chamber air in degC.

Every value is written in its shortest exact text (``repr``; a decimal comma is the same
digits), so what the import reads is bitwise what was simulated, up to the unit conversions.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np

import nfs
from nfs.config.scenario import load_scenario

POWER_ON = dt.datetime(2024, 3, 1, 8, 0, 0)
G = 9.80665
KELVIN = 273.15

SCENARIO = """name = "log"
seed = 3
start_temperatures_c = [{t0!r}]
duration_s = 1300.0
sample_rate_hz = 10.0
latitude_deg = 30.0
true_heading_deg = 40.0
[schedule]
positions_deg = [0.0, 90.0, 180.0, 270.0]
dwell_s = 150.0
move_s = 10.0
[chamber]
program = [{{ hold_s = 300.0 }}, {{ ramp_to_c = {t1!r}, rate_c_per_min = 1.0 }},
           {{ hold_s = 3000.0 }}]
"""

MAPPING = """[run]
name = "{name}"
latitude_deg = 30.0
start_temperature_c = {t0!r}
true_heading_deg = 40.0
positions_deg = [0.0, 90.0, 180.0, 270.0]
dwell_s = 150.0
move_s = 10.0

[sources.gyro]
file = "gyro.csv"
separator = ";"
decimal = ","
time = "Timestamp"
time_format = "%Y-%m-%d %H:%M:%S.%f"
columns.gyro_dph = {{ column = "Rate_mdph", unit = "mdeg/h" }}
columns.position_deg = "Table_deg"
columns.moving = "Moving"
columns.acc_x_g = {{ column = "AccX_ms2", unit = "m/s^2" }}
columns.acc_y_g = {{ column = "AccY_ms2", unit = "m/s^2" }}

[sources.thermometers]
file = "thermometers.csv"
time = "t_ms"
time_unit = "ms"
columns.temp_fog_c = {{ column = "T_fog_K", unit = "K" }}
columns.temp_acc_x_c = {{ column = "T_accx_K", unit = "K" }}
columns.temp_acc_y_c = {{ column = "T_accy_K", unit = "K" }}

[sources.chamber]
file = "chamber.csv"
separator = "\\t"
skip_rows = 2
time = "Minutes"
time_unit = "min"
columns.temp_chamber_c = "Air"
"""


def simulate(folder: Path, t0: float = -20.0):
    """A 1300 s run at 10 Hz from ``t0``, the chamber ramping +10 K after 300 s."""
    path = folder / f"scenario_{t0:g}.toml"
    path.write_text(SCENARIO.format(t0=t0, t1=t0 + 10.0))
    sc = load_scenario(path)
    return nfs.simulate_run(sc.instrument, sc.conditions()[0]).run


def _text(v: float, comma: bool = False) -> str:
    s = repr(float(v)) if np.isfinite(v) else ""
    return s.replace(".", ",") if comma else s


def write_log(run, folder: Path) -> Path:
    """The three files of the module docstring and their mapping ``log.toml``."""
    folder.mkdir(parents=True, exist_ok=True)
    c, t = run.columns, run.columns["time_s"]
    rows = ["Timestamp;Rate_mdph;Table_deg;Moving;AccX_ms2;AccY_ms2"]
    for k in range(t.size):
        stamp = POWER_ON + dt.timedelta(microseconds=round(float(t[k]) * 1e6))
        rows.append(";".join([stamp.strftime("%Y-%m-%d %H:%M:%S.%f"),
                              _text(c["gyro_dph"][k] * 1000.0, True),
                              _text(c["position_deg"][k], True), str(int(c["moving"][k])),
                              _text(c["acc_x_g"][k] * G, True),
                              _text(c["acc_y_g"][k] * G, True)]))
    (folder / "gyro.csv").write_text("\n".join(rows) + "\n")
    rows = ["t_ms,T_fog_K,T_accx_K,T_accy_K"]
    for k in range(0, t.size, 10):
        rows.append(",".join([str(round(float(t[k]) * 1000.0))]
                             + [_text(c[n][k] + KELVIN)
                                for n in ("temp_fog_c", "temp_acc_x_c", "temp_acc_y_c")]))
    (folder / "thermometers.csv").write_text("\n".join(rows) + "\n")
    rows = ["# climate chamber VT 4002, air temperature", "# exported 2024-03-01", "Minutes\tAir"]
    for k in range(0, t.size, 100):
        rows.append(f"{_text(t[k] / 60.0)}\t{_text(c['temp_chamber_c'][k])}")
    (folder / "chamber.csv").write_text("\n".join(rows) + "\n")
    mapping = folder / "log.toml"
    mapping.write_text(MAPPING.format(name=run.name, t0=run.meta.start_temperature_c))
    return mapping
