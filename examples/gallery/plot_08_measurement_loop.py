"""
The measurement loop: fit, compare, diagnose, add the effect, diagnose again
============================================================================

A unit's chamber runs and the default model, worked as an engineer works a unit with
:class:`nfs.UnitChain`: fit the model, set it beside the runs, ask which registered effect
it lacks, add what the answer names, and ask again. The unit here has a magnetic (Faraday)
bias, m cos(A - D_mag) with m = 0.012 deg/h and D_mag = 40 deg, that the model lacks; it
follows the turntable's position, so the model's gyro residual keeps a pattern at the four
positions until the effect is added. Every step returns a typed result (``to_dict`` writes
it as JSON), and the next step takes it as it is.
"""

import dataclasses

import matplotlib.pyplot as plt

import nfs

# the unit: the default instrument with a magnetic bias the model lacks; four start-ups
model = nfs.load_instrument("default")
truth = model.with_effects([*model.effects,
                            nfs.make_effect("magnetic", {"m": 0.012, "D_mag": 40.0})])
scenario = dataclasses.replace(nfs.load_scenario().nominal(), duration_s=7200.0,
                               start_temperatures_c=(-20.0, 0.0, 20.0, 40.0))
runs = [nfs.simulate_run(truth, cond).run for cond in scenario.conditions()]

# the loop

chain = nfs.UnitChain(model, runs)
chain.fit()
before = chain.compare()
finding = chain.diagnose()
print("diagnosis:", finding.verdict)
applied = chain.apply(finding.answer.labels[0])          # what the answer names
after, again = chain.compare(), chain.diagnose()
print("then:", again.verdict)

fig, ax = plt.subplots(figsize=(7.5, 4.0), layout="constrained")
for comparison, label in ((before, "model fitted"), (after, f"with {applied.label} added")):
    run = comparison.per_run["gyro_drift_dph"][1]
    ax.plot(run.time_s / 60.0, run.measured - run.model, ".", ms=3, label=label)
ax.set(xlabel="time since power-on [min]", ylabel="gyro drift: measured - model [deg/h]",
       title=f"Run at {runs[1].meta.start_temperature_c:g} C: the position pattern goes")
ax.legend(fontsize=8)
plt.show()
