"""The rivals beside the runs already taken: their replays and the noise the runs show.

Both the design (what the runs taken separate already, :mod:`nfs.design.search`) and the
decision (which rival the runs favour, :mod:`nfs.rivals.decide`) need the same thing: each
rival's prediction of every run taken, replayed on the run's own samples from the rival's
own start states (:func:`nfs.rivals.predict.predict`, ``native``), the measured numbers
reduced the same way, and the sensor noise raised to what the runs show
(:mod:`nfs.rivals.noise_level`).  :func:`replay_runs_taken` computes it once.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..conditions import RunConditions, conditions_from_run
from ..run import Run
from .noise_level import excess_factors, scaled
from .predict import Prediction, noise_sigma, predict, reduce_run
from .models import Rival
from .separation import RivalPrediction

__all__ = ["RunsTaken", "predict_rival", "replay_runs_taken"]


def predict_rival(rival: Rival, conds: Sequence[RunConditions], n_draws: int,
                  rng: np.random.Generator, *, native: bool = False) -> RivalPrediction:
    """``rival``'s predictions of the runs ``conds`` at its fit and at ``n_draws`` draws of
    its parameters (``native``: on the runs' own samples)."""
    mean = [predict(rival.instrument, c, native=native) for c in conds]
    draws = [[predict(inst, c, native=native) for c in conds]
             for inst in rival.draws(n_draws, rng)]
    return RivalPrediction(mean, draws)


@dataclass(frozen=True)
class RunsTaken:
    """The runs taken, as the rivals see them."""

    predictions: list[RivalPrediction]
    """Each rival's replay of every run (at its fit, and its draws when asked for)."""
    measured: list[Prediction]
    """The numbers of every run, reduced as a prediction is."""
    sigma: list[dict[str, np.ndarray]]
    """The noise of every run's numbers, raised by :attr:`factors`."""
    factors: dict[str, float]
    """The factor each channel's sensor noise is raised by."""


def replay_runs_taken(rivals: Sequence[Rival], runs: Sequence[Run], *, n_draws: int = 0,
                      rng: np.random.Generator | None = None) -> RunsTaken:
    """Every rival's replay of ``runs`` from its own start states, and the noise they show
    (module docstring); ``n_draws`` parameter draws per rival (from ``rng``)."""
    rng = np.random.default_rng(0) if rng is None else rng
    preds = []
    for r in rivals:
        start = r.fit.start_c if r.fit is not None else {}
        conds = [conditions_from_run(run, initial_c=start.get(run.name)) for run in runs]
        preds.append(predict_rival(r, conds, n_draws, rng, native=True))
    measured = [reduce_run(run) for run in runs]
    sensor = [noise_sigma(rivals[0].instrument, m) for m in measured]
    factors = excess_factors(measured, preds, sensor)
    return RunsTaken(preds, measured, [scaled(s, factors) for s in sensor], factors)
