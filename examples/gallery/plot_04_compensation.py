"""
A compensator trained on a small scenario: heading error before and after
=========================================================================

The study behind ``nfs table``, cut small: least squares on the thermometers' features
(``LS``: Tao et al. (2019), cubic least squares) is trained on one start-up per start
temperature and applied to other start-ups of the same unit (a different seed), which are
then north-found again. The start-up cycles of cold starts improve most: there the drift
moves fastest.
"""

import matplotlib.pyplot as plt
import numpy as np

import nfs

settings = nfs.CompensationSettings(methods=("ls",), test_repeats=1, n_jobs=1)
chain = nfs.ModelChain.from_scenario(
    None, {"start_temperatures_c": [-32.0, -5.0, 28.0, 54.0]}, settings=settings)
result = chain.run_model()             # simulate -> north-find -> compensate -> table
scenario, study = result.scenario, result.study
before = study.test.northfind
after = study.results["LS"].northfind
startup_end_s = scenario.northfind.startup_end_s

fig, (ax, ax_b) = plt.subplots(1, 2, figsize=(9.0, 4.5), width_ratios=[3, 2])
nf0, nf1 = before[0], after[0]                       # T0 = -32 C
t_min = np.asarray(nf0.t_end_s) / 60.0
ax.plot(t_min, np.abs(nf0.error_deg), "o--", color="C0", label="uncompensated [deg]")
ax.plot(t_min, np.abs(nf1.error_deg), "s-", color="C1", label="LS-compensated [deg]")
ax.axvline(startup_end_s / 60.0, color="0.5", lw=0.8,
           label=f"end of start-up stage ({startup_end_s:g} s)")
ax.set_xlabel("end of north-finding cycle, time since power-on [min]")
ax.set_ylabel("|heading error| [deg]")
ax.set_title("T0 = -32 C: each cycle")
ax.legend(fontsize=8)


def startup_rmse_deg(nf):
    e = np.asarray(nf.error_deg)[np.asarray(nf.t_end_s) <= startup_end_s]
    return float(np.sqrt(np.mean(e ** 2)))


temps = scenario.start_temperatures_c
x = np.arange(len(temps))
ax_b.bar(x - 0.2, [startup_rmse_deg(n) for n in before], 0.4, color="C0",
         label="uncompensated [deg]")
ax_b.bar(x + 0.2, [startup_rmse_deg(n) for n in after], 0.4, color="C1",
         label="LS-compensated [deg]")
ax_b.set_xticks(x, [f"{t:g}" for t in temps])
ax_b.set_xlabel("start temperature T0 [C]")
ax_b.set_ylabel("start-up heading RMSE [deg]")
ax_b.set_title("Start-up stage, by T0")
ax_b.legend(fontsize=8)
fig.suptitle("LS compensation: trained on 4 start-ups, tested on 4 others")
fig.tight_layout()
plt.show()

# %%
# The heading table of this small study (one test start-up per temperature, so its
# intervals are wide; ``nfs table`` uses five):
print(study.heading_table().to_markdown().split("\n\n")[0])
