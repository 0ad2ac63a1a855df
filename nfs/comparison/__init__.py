"""The model beside a unit's measured runs, channel by channel, and where it fails.

- :mod:`~nfs.comparison.compare_runs`: the model simulated on each run's conditions beside the
  measurement (:func:`compare`, :class:`Comparison`);
- :mod:`~nfs.comparison.channel_residual`: the residual of each channel and its RMS;
- :mod:`~nfs.comparison.channel_summary`: "where it fails" in words;
- :mod:`~nfs.comparison.heading`: the heading's verdict with its interval;
- :mod:`~nfs.comparison.dwell_traces`: each dwell's bias and each cycle's heading error
  against time, measured and predicted, for the figures;
- :mod:`~nfs.comparison.allan_runs`: the gyro's noise read from the runs dwell by dwell, N, B,
  K with their intervals beside the instrument's stated values (:func:`allan_of_runs`,
  ``nfs allan``).

The report and figures are rendered by :mod:`nfs.report.compare_report`.
"""

from .allan_runs import AllanReport, allan_of_runs, stated_instrument
from .compare_runs import Comparison, compare

__all__ = ["Comparison", "compare", "AllanReport", "allan_of_runs", "stated_instrument"]
