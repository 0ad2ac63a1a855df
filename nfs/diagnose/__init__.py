"""Model against measurements: fit a model to runs, compare, diagnose the missing effect.

- :mod:`~nfs.diagnose.params`: named parameter paths into an instrument (what is free);
- :mod:`~nfs.diagnose.fit`: two-stage bounded least-squares calibration (thermal, drift);
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
from .params import (ParameterError, default_bounds, expand_paths, get_param, list_params,
                     set_params)

__all__ = ["Comparison", "compare", "write_report", "Diagnosis", "apply_candidate",
           "candidates", "diagnose", "FitResult", "default_free", "fit_model",
           "write_fitted_model", "ParameterError", "default_bounds", "expand_paths",
           "get_param", "list_params", "set_params"]
