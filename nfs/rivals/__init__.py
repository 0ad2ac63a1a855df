"""Rival explanations of a unit's runs, what each predicts, and the verdict between them.

Shared by the diagnosis's settlement of a tie (``nfs diagnose --decide``) and the design of
the run that would break it (:mod:`nfs.design`):

- :mod:`~nfs.rivals.models`: each explanation becomes a fitted model with its parameter
  uncertainty (:class:`Rival`);
- :mod:`~nfs.rivals.predict`: what a rival predicts a run records, and the noise of each
  recorded number; :mod:`~nfs.rivals.noise_level`: the noise a unit's runs show;
- :mod:`~nfs.rivals.separation`: how far apart two rivals' predictions are in noise standard
  deviations (the expected log-likelihood ratio, with parameter uncertainty);
- :mod:`~nfs.rivals.replay`: each rival replaying the runs already taken from its own start
  states; :mod:`~nfs.rivals.evidence`: the evidence of recorded runs between two rivals;
- :mod:`~nfs.rivals.decide`: the verdict between rivals on recorded runs and the settlement
  of a tie (:class:`Settlement`); :mod:`~nfs.rivals.finding`: the diagnosis and its
  settlement as one answer (:class:`Finding`).
"""

from .decide import Decision, Settlement, decide, settle_tie
from .finding import Finding, rivals_from_diagnosis
from .models import MODEL, RATE_ALTERNATIVE, Rival, rival_model, rival_models
from .predict import Prediction, noise_sigma, predict, quiet
from .separation import MARGIN_SIGMA, RivalPrediction, Separation, separation

__all__ = ["Finding", "Decision", "Settlement", "decide", "settle_tie", "MODEL", "RATE_ALTERNATIVE",
           "Rival", "rival_model", "rival_models", "rivals_from_diagnosis", "Prediction",
           "noise_sigma", "predict", "quiet", "MARGIN_SIGMA", "RivalPrediction", "Separation",
           "separation"]
