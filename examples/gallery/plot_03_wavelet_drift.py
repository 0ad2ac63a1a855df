"""
Separating the drift from the gyro output with wavelets
=======================================================

A compensator is trained on the drift, which no instrument measures directly: the gyro
output less the Earth-rate projection at each turntable position is the drift plus the
gyro's noise. :func:`nfs.denoise.separate_drift` bridges the turntable moves and keeps
what is slower than the wavelet cutoff (512 s by default). In a simulation the true thermal
drift is known, so the separation can be checked against it.
"""

import matplotlib.pyplot as plt

from nfs.denoise import separate_drift
import nfs

scenario = nfs.load_scenario(None, {"start_temperatures_c": [-32.0], "repeats": 1,
                                "duration_s": 7200.0})
sim = nfs.run_scenario(scenario).simulations[0]
sep = separate_drift(sim.run)
t_min = sep.time_s / 60.0

# the true thermal drift: the sum of every effect term; the gyro's own bias (and its slow
# bias-instability wander) comes on top, so the true drift is shifted by the mean
# difference over the last 30 minutes to lie on the separated one
true_dph = sim.drift_dph
offset = (sep.drift_dph - true_dph)[-1800:].mean()

fig, ax = plt.subplots(figsize=(7.5, 4.5))
ax.plot(t_min, sep.filled_drift_dph, color="0.75", lw=0.5,
        label="gyro output - Earth rate, moves bridged [deg/h]")
ax.plot(t_min, sep.drift_dph, "C0", lw=1.5, label="wavelet-separated drift [deg/h]")
ax.plot(t_min, true_dph + offset, "C3--", lw=1.2,
        label=f"true thermal drift, shifted by {offset:.4f} deg/h [deg/h]")
ax.set_xlabel("time since power-on [min]")
ax.set_ylabel("gyro drift [deg/h]")
ax.set_title("Drift separation of a -32 C start-up (db4, cutoff 512 s)")
ax.set_ylim(sep.drift_dph.min() - 0.1, sep.drift_dph.max() + 0.1)
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()
