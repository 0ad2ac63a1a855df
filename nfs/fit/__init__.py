"""Fit a model to a unit's measured runs: the calibration and its thermal structure.

The room a change of the fit's thermal structure stays in:

- :mod:`~nfs.fit.params`: named parameter paths into an instrument (what is free);
  :mod:`~nfs.fit.free_set`: the stages of the fit and what each frees by default;
- :mod:`~nfs.fit.calibration`: two-stage calibration (thermal, drift) with the prior of
  :mod:`~nfs.fit.prior`, the soak anchor of the thermometer offsets (:mod:`~nfs.fit.soak`),
  the level solve (:mod:`~nfs.fit.sensor_fit`), the gyro noise from the Allan deviation
  (:mod:`~nfs.fit.noise_fit`), the least-squares core (:mod:`~nfs.fit.stage`) and advice for
  parameters at a bound or beyond their typical range (:mod:`~nfs.fit.departures`); its residuals
  (:mod:`~nfs.fit.thermal_residual`, :mod:`~nfs.fit.drift_residual`), its result and file
  (:mod:`~nfs.fit.fit_result`) and its warnings (:mod:`~nfs.fit.departures`);
- :mod:`~nfs.fit.start_state`: each run's node temperatures at power-on (an unfinished soak);
- :mod:`~nfs.fit.structure` and :mod:`~nfs.fit.wound_alternative` (a lumped coil wound in
  layers), and :mod:`~nfs.fit.adequacy`: alternatives of the thermal structure and the
  verdict on the model's, scored on the held-out thermometer residual
  (:mod:`~nfs.fit.thermometer_cv`, :mod:`~nfs.fit.alternative_score`);
  :mod:`~nfs.fit.refine`: the alternatives that pay adopted in a chain (:func:`fit_unit`).
"""

from .adequacy import ThermalAdequacy, thermal_adequacy
from .calibration import fit_model
from .fit_result import FitResult, write_fitted_model
from .free_set import default_free
from .params import (ParameterError, default_bounds, expand_paths, get_param, list_params,
                     set_params)
from .refine import Refinement, fit_unit, refine_structure
from .wound_alternative import wound_coil
from .adequacy import structural_alternatives

__all__ = ["FitResult", "default_free", "fit_model", "write_fitted_model", "ParameterError",
           "default_bounds", "expand_paths", "get_param", "list_params", "set_params",
           "ThermalAdequacy", "thermal_adequacy", "structural_alternatives", "Refinement", "fit_unit",
           "refine_structure", "wound_coil"]
