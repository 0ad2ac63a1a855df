"""
Thermal network: a step response against exp(-t/RC)
====================================================

The thermal network is solved exactly over held inputs with the matrix exponential. A single
node of capacity C linked to the chamber by a conductance G answers a step of the chamber
air by T(t) = T_step (1 - exp(-t / RC)), RC = C / G: the closed form the solver must
reproduce to rounding. A second node behind the first shows the lag a buried coil has.
"""

import matplotlib.pyplot as plt
import numpy as np

import thermal

capacity_j_per_k, conductance_w_per_k = 400.0, 2.0        # RC = 200 s
rc_s = capacity_j_per_k / conductance_w_per_k
network = thermal.Network(
    (thermal.Node("housing", capacity_j_per_k), thermal.Node("coil", 200.0)),
    (thermal.Link("housing", thermal.CHAMBER, conductance_w_per_k),
     thermal.Link("housing", "coil", 1.0)))
time_s = np.arange(0.0, 1500.0, 5.0)
step_c = 10.0
res = thermal.simulate(network, time_s, ambient_c=step_c, initial_c=0.0)

# the single node alone, for the closed form
single = thermal.Network((thermal.Node("housing", capacity_j_per_k),),
                         (thermal.Link("housing", thermal.CHAMBER, conductance_w_per_k),))
one = thermal.simulate(single, time_s, ambient_c=step_c, initial_c=0.0)
closed = step_c * (1.0 - np.exp(-time_s / rc_s))

fig, (ax, ax_r) = plt.subplots(2, 1, figsize=(7.5, 6.0), sharex=True,
                               gridspec_kw={"height_ratios": [3, 1]})
ax.plot(time_s, one.node("housing"), "C0", lw=2.5, alpha=0.6,
        label="one node, exact solver [degC]")
ax.plot(time_s, closed, "k--", lw=1.2, label=f"10 C (1 - exp(-t/RC)), RC = {rc_s:g} s")
ax.plot(time_s, res.node("housing"), "C1", label="two nodes: housing [degC]")
ax.plot(time_s, res.node("coil"), "C2", label="two nodes: coil behind the housing [degC]")
ax.axvline(rc_s, color="0.6", lw=0.8, label="t = RC")
ax.set_ylabel("node temperature [degC]")
ax.set_title("Step of the chamber air from 0 to 10 C at t = 0")
ax.legend(fontsize=8)
ax_r.plot(time_s, one.node("housing") - closed, "C0")
ax_r.set_xlabel("time [s]")
ax_r.set_ylabel("solver - closed form [K]")
fig.tight_layout()
plt.show()

print(f"largest difference from the closed form: {np.abs(one.node('housing') - closed).max():.2e} K")
