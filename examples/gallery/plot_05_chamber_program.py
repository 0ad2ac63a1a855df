"""
A chamber program: hold, ramp down, hold, ramp up
=================================================

``[chamber] program`` runs the chamber through steps after power-on; here the program of
the user guide's example (:doc:`../scenarios`): 1800 s at 25 C, 1 C/min down to 10 C, 1800 s,
0.5 C/min back to 25 C, 1800 s. The chamber air, the unit's thermometers and the FOG drift
follow it; the chamber is linear between samples in the exact thermal solution.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import nfs

# a complete scenario file (every other key from the built-in default)
SCENARIO = """start_temperatures_c = [25.0]
[chamber]
program = [
  { hold_s = 1800.0 },
  { ramp_to_c = 10.0, rate_c_per_min = 1.0 },
  { hold_s = 1800.0 },
  { ramp_to_c = 25.0, rate_c_per_min = 0.5 },
  { hold_s = 1800.0 },
]
"""
with tempfile.TemporaryDirectory() as tmp:
    path = Path(tmp) / "program.toml"
    path.write_text(SCENARIO)
    scenario = nfs.load_scenario(path)
sim = nfs.run_scenario(scenario).simulations[0]
run = sim.run
t_min = run["time_s"] / 60.0

fig, (ax_t, ax_d) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True)
ax_t.plot(t_min, run["temp_chamber_c"], "k", lw=1.5, label="chamber air, temp_chamber_c [degC]")
ax_t.plot(t_min, run["temp_fog_c"], label="FOG thermometer, temp_fog_c [degC]")
ax_t.plot(t_min, run["temp_acc_x_c"], label="x accelerometer thermometer [degC]")
ax_t.set_ylabel("temperature [degC]")
ax_t.set_title("Chamber program from T0 = 25 C (8100 s)")
ax_t.legend(fontsize=8)
ax_d.plot(t_min, sim.drift_dph, "C3", label="thermal drift of the FOG [deg/h]")
ax_d.set_xlabel("time since power-on [min]")
ax_d.set_ylabel("gyro drift [deg/h]")
ax_d.legend(fontsize=8)
fig.tight_layout()
plt.show()
