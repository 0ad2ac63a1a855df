"""Multiposition north finding (docs/physics.md section 5).

- :mod:`~nfs.northfind.solve`: heading from the mean rates of one cycle (least squares, the
  two-position method) and tilt correction;
- :mod:`~nfs.northfind.segment`: dwells and cycles of a run;
- :mod:`~nfs.northfind.level`: exact levelling with both accelerometers;
- :mod:`~nfs.northfind.known_bias`: the heading with the biases known, down to one position;
- :mod:`~nfs.northfind.heading`: north-find a whole run and score the heading by stage;
- :mod:`~nfs.northfind.budget`: the error budget in closed form;
- :mod:`~nfs.northfind.time_to_spec`: time to spec, when after power-on the heading stays in spec;
- :mod:`~nfs.northfind.synthetic`: an ideal run from the section 5 rate model, for checks.
"""

from nfs.northfind.budget import (east_tilt_error_deg, indexing_error_deg,
                                  linear_drift_error_deg, rate_error_heading_deg,
                                  tilt_model_error_deg, white_noise_floor_deg)
from nfs.northfind.heading import NorthFindResult, StageRMSE, heading_rmse, north_find
from nfs.northfind.known_bias import KnownBiasHeading, north_find_known_bias
from nfs.northfind.segment import Cycle, Dwell, find_dwells, segment_cycles
from nfs.northfind.solve import (HeadingSolution, solve_heading, tilt_correct, wrap_deg_180,
                                 wrap_deg_360)
from nfs.northfind.time_to_spec import rolling_rmse_deg, run_time_to_spec_s, time_to_spec_s
from nfs.northfind.synthetic import synthetic_run

__all__ = [
    "HeadingSolution",
    "solve_heading",
    "tilt_correct",
    "wrap_deg_180",
    "wrap_deg_360",
    "Dwell",
    "Cycle",
    "find_dwells",
    "segment_cycles",
    "NorthFindResult",
    "north_find",
    "StageRMSE",
    "heading_rmse",
    "KnownBiasHeading",
    "north_find_known_bias",
    "white_noise_floor_deg",
    "rate_error_heading_deg",
    "linear_drift_error_deg",
    "east_tilt_error_deg",
    "indexing_error_deg",
    "tilt_model_error_deg",
    "time_to_spec_s",
    "rolling_rmse_deg",
    "run_time_to_spec_s",
    "synthetic_run",
]
