"""
One start-up: node temperatures and drift terms
===============================================

A north finder soaked at -32 C is powered on in a chamber held at -32 C. Its own heat warms
the coil, the housing and the sensors at different rates, and each named drift effect of the
FOG follows its own temperature signal. Every stage of the simulation is kept in the result:
here the node temperatures of the thermal network and each gyro drift term separately.
"""

import matplotlib.pyplot as plt

import nfs

# the built-in default scenario, cut to one start temperature and two hours
scenario = nfs.load_scenario(None, {"start_temperatures_c": [-32.0], "repeats": 1,
                                "duration_s": 7200.0})
result = nfs.run_scenario(scenario)
sim = result.simulations[0]
t_min = sim.thermal.time_s / 60.0

fig, (ax_t, ax_d) = plt.subplots(2, 1, figsize=(7.5, 7.0), sharex=True)
for name in sim.thermal.node_names:
    ax_t.plot(t_min, sim.thermal.node(name), label=name)
ax_t.set_ylabel("node temperature [degC]")
ax_t.set_title("Start-up at T0 = -32 C: thermal network nodes")
ax_t.legend(fontsize=8, ncol=2)

for name, term in sim.gyro_terms_dph.items():
    ax_d.plot(t_min, term, label=f"{name} [deg/h]")
ax_d.plot(t_min, sim.drift_dph, "k", lw=1.5, label="sum: thermal drift [deg/h]")
ax_d.axhline(0.0, color="0.6", lw=0.5)
ax_d.set_xlabel("time since power-on [min]")
ax_d.set_ylabel("gyro drift term [deg/h]")
ax_d.set_title("Each named drift effect of the FOG")
ax_d.legend(fontsize=8)
fig.tight_layout()
plt.show()

# %%
# The coil's radial temperature gradient changes fastest in the first minutes, so the
# Shupe-type terms dominate the start-up; the static bias against temperature
# (``bias_temperature``) is a small part of the drift. Each term is a registered effect
# (``nfs effects`` lists them; :doc:`../effects` gives their equations).
