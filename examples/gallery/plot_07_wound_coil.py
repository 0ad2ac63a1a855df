"""
The wound coil: how the winding pattern decides the Shupe bias
==============================================================

The default instrument's coil is wound: 1 km of fibre in 64 layers on a spool, its winding 8
thermal layers of the network (``[coil]``). Its Shupe bias is the temperature rate of the
layers integrated along the fibre, weighted by the distance from the fibre's midpoint; which
stretch of fibre lies on which layer is the winding pattern (``shupe_winding``,
:doc:`../physics`, "The wound coil"). The same coil, the same temperatures, four patterns: a
helical winding answers to the mean heating rate of a layer's neighbourhood, a dipole (AB..)
to the radial gradient's rate, a quadrupole (ABBA..) to that rate at the outer face only,
N/2 = 32 times less than the dipole, and an octupole (ABBABAAB..) cancels that too.

The unit is powered on at 17 C, the electronics warm the coil's outer face, and after two
hours the chamber ramps by +20 K at 1 K/min. The bias of each pattern is evaluated on the one
simulated state (the effect on the thermal solution a run keeps).
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import nfs

SCENARIO = """start_temperatures_c = [17.0]
duration_s = 14400.0
[chamber]
program = [
  { hold_s = 7200.0 },
  { ramp_to_c = 37.0, rate_c_per_min = 1.0 },
  { hold_s = 6000.0 },
]
"""
with tempfile.TemporaryDirectory() as tmp:
    path = Path(tmp) / "ramp.toml"
    path.write_text(SCENARIO)
    scenario = nfs.load_scenario(path).nominal()
sim = nfs.run_scenario(scenario).simulations[0]
t_min = sim.thermal.time_s / 60.0
coil = scenario.instrument.coil

# the thermo-optic Shupe term alone (no stress term, no asymmetry), one pattern at a time
bias = {}
for pattern in ("helical", "dipole", "quadrupole", "octupole"):
    effect = nfs.make_effect("shupe_winding", {"L": 1000.0, "D": coil.mean_diameter_m,
                                               "N_opt": 64, "pattern": pattern})
    bias[pattern] = effect.spec.function(sim.context, **effect.params)

fig, (ax_t, ax_log, ax_lin) = plt.subplots(3, 1, figsize=(7.5, 9.0), sharex=True)
spool_side = sim.thermal.node(coil.layer_names[0])
for name in coil.layer_names[1:]:
    ax_t.plot(t_min, sim.thermal.node(name) - spool_side, lw=1.0,
              label=f"{name} minus coil_1 [K]")
ax_t.set_ylabel("layer temperature minus\nthe spool-side layer's [K]")
ax_t.set_title("The winding's 8 thermal layers (coil_8 at the outer face)")
ax_t.legend(fontsize=7, ncol=2, loc="upper left")

for pattern, b in bias.items():
    ax_log.semilogy(t_min, np.abs(b), lw=1.0, label=f"{pattern} winding, |Shupe bias| [deg/h]")
ax_log.set_ylim(1e-6, None)
ax_log.set_ylabel("|Shupe bias| [deg/h]")
ax_log.set_title("The same coil wound four ways (log scale: factors of ten apart)")
ax_log.legend(fontsize=8, loc="upper right")

for pattern in ("quadrupole", "octupole"):
    ax_lin.plot(t_min, bias[pattern], lw=1.0, label=f"{pattern} winding, Shupe bias [deg/h]")
ax_lin.axhline(0.0, color="0.6", lw=0.5)
ax_lin.axvspan(120.0, 140.0, color="0.9", label="chamber ramp, +20 K at 1 K/min")
ax_lin.set_xlabel("time since power-on [min]")
ax_lin.set_ylabel("Shupe bias [deg/h]")
ax_lin.set_title("Quadrupole and octupole on a linear scale")
ax_lin.legend(fontsize=8, loc="lower right")
fig.tight_layout()
plt.show()

# %%
# Over the ramp the dipole integrates about 18 times the quadrupole's bias, with the other
# sign: of the order of N/3 = 21, what a slab ramped at one face gives (its parabolic
# profile; N/2 for a linear one; tests/effects/test_winding.py checks both closed forms).
# The quadrupole trades the dipole's response to the whole gradient for a response to the
# gradient at the fibre's ends, the outer face: heat arriving there (the electronics', after
# power-on) moves a quadrupole, heat arriving at the hub barely does.
ramp = (t_min >= 120.0) & (t_min < 200.0)
ratio = np.sum(bias["dipole"][ramp]) / np.sum(bias["quadrupole"][ramp])
print(f"dipole / quadrupole over the ramp: {ratio:.1f} (N/3 = {64 / 3:.1f})")
