"""
The gyro's noise, dwell by dwell: the Allan deviation beside the stated values
==============================================================================

A north finder holds its gyro still only for a dwell at each turntable position, so the
gyro's noise comes as many short records. ``nfs allan`` (here :func:`nfs.comparison.allan_of_runs`)
computes the overlapping Allan deviation of every dwell's gyro at rest, pools them, fits the
angle random walk N (slope -1/2), bias instability B (flat) and rate random walk K (slope +1/2)
with bootstrap intervals over the dwells, and sets them beside the values the instrument
states. In a start-up the coil warms within a dwell, and the long-tau end of a dwell in the
first hour is thermal drift, not noise: those dwells enter the fit only up to a tenth of
their length.

Three start-ups of the default instrument (N = 0.0003 deg/sqrt(h), B = 0.002 deg/h, K = 0),
2.5 h each, 150 s dwells at 1 Hz. N comes back to a per cent; within 150 s dwells B shows
only at the long end (its interval is wide) and K hardly at all (an upper bound).
"""

import dataclasses

import matplotlib.pyplot as plt

import nfs
from nfs.report import plot_allan

scenario = dataclasses.replace(nfs.load_scenario().nominal(),
                               start_temperatures_c=(-32.0, 17.0, 54.0))
model = scenario.instrument
runs = [nfs.simulate_run(model, cond).run for cond in scenario.conditions()]

report = nfs.allan_of_runs(runs)            # what `nfs allan runs/` prints and draws
print(report.summary())

plot_allan(report, fig=plt.figure())
plt.show()
