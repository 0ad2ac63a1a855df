"""Design the run that tells rival explanations apart (model discrimination).

When a diagnosis ends in a tie (:mod:`nfs.diagnose`), the runs taken cannot tell two
explanations apart. The rivals and what each predicts are :mod:`nfs.rivals`; this package
finds the cheapest chamber run that would separate them:

- :mod:`~nfs.design.space`: the experiments a chamber and a turntable can run (start
  temperature, a power cycle or a chamber ramp, the run's length) and their chamber hours;
- :mod:`~nfs.design.search`: the grid, then a local refinement, for the cheapest run that
  separates every pair by the margin (:func:`design_experiment`).

The designed run's scenario file, report and figure are written by
:mod:`nfs.report.design_report`. The names of :mod:`nfs.rivals` that were importable from
here before still are, with a :class:`DeprecationWarning`, for one release.
"""

from ..errors import moved_names
from .search import Design, Trial, current_separation, design_experiment
from .space import Experiment, Space, base_conditions, default_space

__all__ = ["Design", "Trial", "current_separation", "design_experiment", "Experiment", "Space",
           "base_conditions", "default_space"]

_MOVED = dict.fromkeys(["Prediction", "noise_sigma", "predict", "quiet", "MODEL",
                        "RATE_ALTERNATIVE", "Rival", "rival_model", "rival_models",
                        "rivals_from_diagnosis", "MARGIN_SIGMA", "RivalPrediction",
                        "Separation", "separation"], "nfs.rivals")

__getattr__ = moved_names('nfs.design', _MOVED)
