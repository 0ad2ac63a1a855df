"""Model against measurements: fit a model to runs, compare, diagnose the missing effect.

- :mod:`~nfs.diagnose.params`: named parameter paths into an instrument (what is free);
- :mod:`~nfs.diagnose.fit`: two-stage calibration (thermal, drift) with the starting model as
  a prior (:mod:`~nfs.diagnose.prior`), the soak anchor of the thermometer offsets
  (:mod:`~nfs.diagnose.soak`), the level solve (:mod:`~nfs.diagnose.sensor_fit`), the gyro
  noise from the Allan deviation (:mod:`~nfs.diagnose.noise_fit`), the least-squares core
  (:mod:`~nfs.diagnose.stage`) and advice for parameters at a bound
  (:mod:`~nfs.diagnose.bound_advice`);
- :mod:`~nfs.diagnose.smoother`: node temperatures estimated from the measured thermometers
  (Kalman filter and smoother through the model's network);
- :mod:`~nfs.diagnose.start_state`: each run's node temperatures at power-on (an
  unfinished soak), estimated with the thermal fit;
- :mod:`~nfs.diagnose.structure` and :mod:`~nfs.diagnose.adequacy`: generic alternatives of
  the thermal structure and the verdict on the model's; :mod:`~nfs.diagnose.refine`: the
  alternatives that pay adopted in a chain (:func:`fit_unit`);
- :mod:`~nfs.diagnose.compare`: the model beside measured runs, channel by channel, with
  "where it fails" in words; :mod:`~nfs.diagnose.compare_report`: its report and figures;
- :mod:`~nfs.diagnose.diagnose`: which registered effect the model is missing, ranked, and
  adding it; its candidates (:mod:`~nfs.diagnose.candidates`), design matrices
  (:mod:`~nfs.diagnose.design`), run-level statistics (:mod:`~nfs.diagnose.stats`:
  clustered tests, grouped CV, Holm), :mod:`~nfs.diagnose.apply` and
  :mod:`~nfs.diagnose.unexplained`.
"""

from .compare import Comparison, compare
from .compare_report import write_report
from .diagnose import Diagnosis, apply_candidate, candidates, diagnose
from .fit import FitResult, default_free, fit_model, write_fitted_model
from .adequacy import ThermalAdequacy, thermal_adequacy
from .refine import Refinement, fit_unit, refine_structure
from .result import Answer, candidate_finding
from .params import (ParameterError, default_bounds, expand_paths, get_param, list_params,
                     set_params)
from .smoother import RunSmoothing, smooth_runs
from .structure import structural_alternatives

__all__ = ["Comparison", "compare", "write_report", "Diagnosis", "apply_candidate",
           "candidates", "diagnose", "FitResult", "default_free", "fit_model",
           "write_fitted_model", "ParameterError", "default_bounds", "expand_paths",
           "get_param", "list_params", "set_params", "ThermalAdequacy", "thermal_adequacy",
           "RunSmoothing", "smooth_runs", "structural_alternatives", "candidate_finding",
           "Answer", "Refinement", "fit_unit", "refine_structure"]
