"""Model against measurements: fit a model to runs, compare, diagnose the missing effect.

- :mod:`~nfs.diagnose.params`: named parameter paths into an instrument (what is free);
  :mod:`~nfs.diagnose.free_set`: the stages of the fit and what each frees by default;
- :mod:`~nfs.diagnose.fit`: two-stage calibration (thermal, drift) with the starting model as
  a prior (:mod:`~nfs.diagnose.prior`), the soak anchor of the thermometer offsets
  (:mod:`~nfs.diagnose.soak`), the level solve (:mod:`~nfs.diagnose.sensor_fit`), the gyro
  noise from the Allan deviation (:mod:`~nfs.diagnose.noise_fit`), the least-squares core
  (:mod:`~nfs.diagnose.stage`) and advice for parameters at a bound
  (:mod:`~nfs.diagnose.bound_advice`); its residuals (:mod:`~nfs.diagnose.thermal_residual`,
  :mod:`~nfs.diagnose.drift_residual`), its result and file
  (:mod:`~nfs.diagnose.fit_result`) and its warnings (:mod:`~nfs.diagnose.fit_warnings`);
- :mod:`~nfs.diagnose.smoother`: node temperatures estimated from the measured thermometers
  (Kalman filter and smoother through the model's network);
- :mod:`~nfs.diagnose.start_state`: each run's node temperatures at power-on (an
  unfinished soak), estimated with the thermal fit;
- :mod:`~nfs.diagnose.structure` and :mod:`~nfs.diagnose.adequacy`: generic alternatives of
  the thermal structure and the verdict on the model's, scored on the held-out thermometer
  residual (:mod:`~nfs.diagnose.thermometer_cv`, :mod:`~nfs.diagnose.alternative_score`);
  :mod:`~nfs.diagnose.refine`: the alternatives that pay adopted in a chain
  (:func:`fit_unit`);
- :mod:`~nfs.diagnose.comparison`: the model beside measured runs, channel by channel
  (:mod:`~nfs.diagnose.channel_residual`), with "where it fails" in words
  (:mod:`~nfs.diagnose.channel_summary`) and the heading's verdict
  (:mod:`~nfs.diagnose.heading`); :mod:`~nfs.diagnose.compare_report`: its report and
  figures;
- :mod:`~nfs.diagnose.missing_effect`: which registered effect the model is missing
  (:func:`diagnose`); its candidates (:mod:`~nfs.diagnose.candidates`), design matrices
  (:mod:`~nfs.diagnose.columns`, :mod:`~nfs.diagnose.acc_columns`), scores
  (:mod:`~nfs.diagnose.candidate_score`, run-level statistics in
  :mod:`~nfs.diagnose.stats`: clustered tests, grouped CV, Holm), ranking
  (:mod:`~nfs.diagnose.ranking`), heading RMSE (:mod:`~nfs.diagnose.candidate_heading`),
  the drift's structure (:mod:`~nfs.diagnose.drift_structure`), what is left
  (:mod:`~nfs.diagnose.unexplained`), the result (:mod:`~nfs.diagnose.result`) and adding
  the effect (:mod:`~nfs.diagnose.apply`).
"""

from .adequacy import ThermalAdequacy, thermal_adequacy
from .apply import apply_candidate, fit_candidate
from .candidates import candidates
from .compare_report import write_report
from .comparison import Comparison, compare
from .fit import fit_model
from .fit_result import FitResult, write_fitted_model
from .free_set import default_free
from .missing_effect import diagnose
from .params import (ParameterError, default_bounds, expand_paths, get_param, list_params,
                     set_params)
from .refine import Refinement, fit_unit, refine_structure
from .result import Answer, Diagnosis, candidate_finding
from .smoother import RunSmoothing, smooth_runs
from .structure import structural_alternatives

__all__ = ["Comparison", "compare", "write_report", "Diagnosis", "apply_candidate", "fit_candidate",
           "candidates", "diagnose", "FitResult", "default_free", "fit_model",
           "write_fitted_model", "ParameterError", "default_bounds", "expand_paths",
           "get_param", "list_params", "set_params", "ThermalAdequacy", "thermal_adequacy",
           "RunSmoothing", "smooth_runs", "structural_alternatives", "candidate_finding",
           "Answer", "Refinement", "fit_unit", "refine_structure"]
