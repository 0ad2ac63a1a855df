"""Design the run that tells rival explanations apart (model discrimination).

When a diagnosis ends in a tie (:mod:`nfs.diagnose`), the runs taken cannot tell two
explanations apart.  This package finds the cheapest chamber run that would:

- :mod:`~nfs.design.rivals`: each explanation becomes a fitted model with its parameter
  uncertainty (:class:`Rival`);
- :mod:`~nfs.design.space`: the experiments a chamber and a turntable can run (start
  temperature, a power cycle or a chamber ramp, the run's length) and their chamber hours;
- :mod:`~nfs.design.predict`: what a rival predicts a run records, and the noise of each
  recorded number;
- :mod:`~nfs.design.separation`: how far apart two rivals' predictions are in noise
  standard deviations (the expected log-likelihood ratio, with parameter uncertainty);
- :mod:`~nfs.design.search`: the grid, then a local refinement, for the cheapest run that
  separates every pair by the margin (:func:`design_experiment`);
- :mod:`~nfs.design.report`: the designed run as a scenario file, a report with its figure
  and ``design.json``.
"""

from .predict import Prediction, noise_sigma, predict, quiet
from .rivals import MODEL, RATE_ALTERNATIVE, Rival, rival_model, rival_models, rivals_from_diagnosis
from .search import Design, Trial, current_separation, design_experiment
from .separation import MARGIN_SIGMA, RivalPrediction, Separation, separation
from .space import Experiment, Space, default_space

__all__ = ["Prediction", "noise_sigma", "predict", "quiet", "MODEL", "RATE_ALTERNATIVE",
           "Rival", "rival_model", "rival_models", "rivals_from_diagnosis", "Design", "Trial",
           "current_separation", "design_experiment", "MARGIN_SIGMA", "RivalPrediction",
           "Separation", "separation", "Experiment", "Space", "default_space"]
