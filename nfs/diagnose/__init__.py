"""Which registered effect a fitted model is missing, with one answer.

- :mod:`~nfs.diagnose.candidates`: the registered effects (and where they act) that could be
  missing; their design matrices (:mod:`~nfs.diagnose.columns`,
  :mod:`~nfs.diagnose.acc_columns`);
- :mod:`~nfs.diagnose.candidate_score`: each candidate scored run by run (the clustered tests
  of :mod:`nfs.scoring.run_stats`); :mod:`~nfs.diagnose.ranking`: the ranking and its ties;
  :mod:`~nfs.diagnose.candidate_heading`: the heading RMSE each would give;
- :mod:`~nfs.diagnose.smoother`: node temperatures estimated from the measured thermometers
  (Kalman filter and smoother through the model's network), for the drift candidates;
- :mod:`~nfs.diagnose.drift_structure`: the drift's structure; :mod:`~nfs.diagnose.unexplained`:
  what is left;
- :mod:`~nfs.diagnose.missing_effect`: the diagnosis (:func:`diagnose`) and its result
  (:mod:`~nfs.diagnose.result`: :class:`Diagnosis`, :class:`Answer`);
- :mod:`~nfs.diagnose.apply`: adding the named effect to the model and fitting it.

The fit lives in :mod:`nfs.fit`, the comparison in :mod:`nfs.comparison`; the names that were
importable from here before the move (``fit_model``, ``compare``, ...) still are, with a
:class:`DeprecationWarning`, for one release.
"""

from ..errors import moved_names
from .apply import apply_candidate, fit_candidate
from .candidates import candidates
from .missing_effect import diagnose
from .result import Answer, Diagnosis, candidate_finding
from .smoother import RunSmoothing, smooth_runs

__all__ = ["Diagnosis", "Answer", "apply_candidate", "fit_candidate", "candidates", "diagnose",
           "candidate_finding", "RunSmoothing", "smooth_runs"]

#: Names that moved out of this package -> the module that has them now.
_MOVED = {
    **dict.fromkeys(["FitResult", "default_free", "fit_model", "write_fitted_model",
                     "ParameterError", "default_bounds", "expand_paths", "get_param",
                     "list_params", "set_params", "ThermalAdequacy", "thermal_adequacy",
                     "structural_alternatives", "Refinement",
                     "fit_unit", "refine_structure"], "nfs.fit"),
    "Comparison": "nfs.comparison", "compare": "nfs.comparison",
    "write_report": "nfs.report.compare_report",
}

__getattr__ = moved_names('nfs.diagnose', _MOVED)
