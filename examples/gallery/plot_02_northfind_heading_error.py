"""
North-finding a start-up: heading error per cycle
=================================================

The turntable indexes the FOG through four positions (150 s dwell each); every cycle gives
one heading by least squares. Right after power-on the drift changes within a cycle and the
heading is poor; once the unit has warmed, the error falls to the white-noise floor of the
schedule. Two start temperatures, two hours each.
"""

import matplotlib.pyplot as plt
import numpy as np

import nfs
from nfs.studies import floor_deg

scenario = nfs.load_scenario(None, {"start_temperatures_c": [-32.0, 28.0], "repeats": 1,
                                "duration_s": 7200.0})
result = nfs.run_scenario(scenario)
floor = floor_deg(scenario)
settings = scenario.northfind

fig, ax = plt.subplots(figsize=(7.5, 4.5))
for t0, nf in zip(scenario.start_temperatures_c, result.northfind):
    t_end_min = np.asarray(nf.t_end_s) / 60.0
    ax.plot(t_end_min, nf.error_deg, "o-", ms=4, label=f"T0 = {t0:g} C: heading error [deg]")
for sign in (1, -1):
    ax.axhline(sign * floor, color="0.4", ls="--",
               label=f"white-noise floor +-{floor:.4f} deg" if sign > 0 else None)
ax.axvline(settings.startup_end_s / 60.0, color="C3", lw=0.8,
           label=f"end of start-up stage ({settings.startup_end_s:g} s)")
ax.axvline(settings.stable_start_s / 60.0, color="C2", lw=0.8,
           label=f"start of stable stage ({settings.stable_start_s:g} s)")
ax.set_xlabel("end of north-finding cycle, time since power-on [min]")
ax.set_ylabel("heading error, estimated - true [deg]")
ax.set_title("Heading error of each north-finding cycle")
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()

# %%
# The heading RMSE of a stage pools these cycle errors (``nfs table`` prints it by start
# temperature):
for t0, nf in zip(scenario.start_temperatures_c, result.northfind):
    e = np.asarray(nf.error_deg)
    t_end = np.asarray(nf.t_end_s)
    startup = e[t_end <= settings.startup_end_s]
    print(f"T0 = {t0:6.1f} C: start-up RMSE {np.sqrt(np.mean(startup ** 2)):.4f} deg "
          f"over {startup.size} cycles")
