"""What a candidate does to the heading: the start-up heading RMSE north-finding the measured
rate minus the fitted model drift, without and with the candidate.

Computed for the top :data:`HEADING_TOP` candidates of the ranking and every significant one
(:func:`with_heading`), pooled over the runs (:func:`nfs.diagnose.columns.startup_heading_rmse`):

- a gyro candidate: the model drift with the model's and the candidate's coefficients
  fitted together;
- an accelerometer candidate: its axis's error enters the heading through the drift (the x
  axis: the north finder's vertical-rate removal; the y axis: not at all), added to the
  model drift with the model's own coefficients;
- a thermal candidate: the linearised thermal refit (one Gauss-Newton step, within the fit
  bounds) with the candidate, then the drift refit on its node temperatures
  (:class:`ThermalDrift`), beside the same step without the candidate; NaN where that step
  leaves the network unphysical.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable, Mapping, Sequence

import numpy as np

from ..errors import ThermalError
from ..instrument import Instrument
from ..run import Run
from .candidate_score import ScoredCandidate
from .columns import (PreparedRun, ThermalDesign, candidate_columns, prepare_runs,
                     refit_heading_rmse, startup_heading_rmse, thermal_step_instrument)
from .result import CandidateScore

__all__ = ["HEADING_TOP", "ThermalDrift", "with_heading"]

#: Heading RMSE is computed for this many top-ranked candidates (and every significant one).
HEADING_TOP = 5


@dataclass
class ThermalDrift:
    """The drift channel after the one-step thermal refit, without a thermal candidate or
    with one added (each computed once: it replays every run)."""

    inst: Instrument
    """The model."""
    ts: ThermalDesign
    """Its thermometer channel linearised at its thermal parameters."""
    beta_model: np.ndarray
    """The model's step on the thermometer channel without a candidate."""
    runs: Sequence[Run]
    """The measured runs."""
    decimate_s: float
    """Window of the drift means [s]."""
    start_c: Mapping[str, np.ndarray]
    """Each run's node temperatures at power-on [degC]."""
    cache: dict[str, list[PreparedRun]] = field(default_factory=dict)
    """The prepared runs with each candidate, by label."""

    def without(self) -> list[PreparedRun]:
        """The runs on the drift channel of the thermal step without a candidate."""
        return prepare_runs(thermal_step_instrument(self.inst, self.ts, self.beta_model),
                            self.runs, self.decimate_s, start_c=self.start_c)[0]

    def of(self, s: ScoredCandidate) -> list[PreparedRun]:
        """The runs on the drift channel of the thermal step with candidate ``s`` added."""
        if s.candidate.label not in self.cache:
            pm = len(self.ts.paths)
            self.cache[s.candidate.label] = prepare_runs(thermal_step_instrument(
                self.inst, self.ts, s.beta[:pm], s.candidate, s.beta[pm:]), self.runs,
                self.decimate_s, start_c=self.start_c)[0]
        return self.cache[s.candidate.label]


def _heading_or_nan(f: Callable[[], float]) -> float:
    """A heading RMSE after a linearised thermal step, or NaN where that step leaves the
    network unphysical (a capacity through zero: the node temperatures are not finite)."""
    try:
        v = float(f())
    except (np.linalg.LinAlgError, FloatingPointError, ValueError, ThermalError):
        return math.nan
    return v if math.isfinite(v) else math.nan


def _model_drift(preps: Sequence[PreparedRun], beta: np.ndarray) -> list[np.ndarray]:
    """The model drift at full rate with coefficients ``beta``, per run [deg/h]."""
    return [p.offset_full + p.X_full @ beta for p in preps]


def _accelerometer_heading(s: ScoredCandidate, preps: list[PreparedRun], bare: Instrument,
                           beta_model: np.ndarray) -> float:
    """Heading RMSE with an accelerometer candidate's error added to the model drift [deg]."""
    k = len(s.candidate.coefficients)
    full = candidate_columns(s.candidate, s.shapes, preps, bare, full=True)
    model_full = [p.offset_full + p.X_full @ beta_model + f @ s.beta[-k:]
                  for p, f in zip(preps, full)]
    return startup_heading_rmse(preps, model_full)


def _gyro_heading(s: ScoredCandidate, preps: list[PreparedRun], bare: Instrument) -> float:
    """Heading RMSE with the model drift refitted with a gyro candidate [deg]."""
    pm = preps[0].X.shape[1]
    full = candidate_columns(s.candidate, s.shapes, preps, bare, full=True)
    model_full = [p.offset_full + p.X_full @ s.beta[:pm] + f @ s.beta[pm:]
                  for p, f in zip(preps, full)]
    return startup_heading_rmse(preps, model_full)


def with_heading(scored: Sequence[ScoredCandidate], preps: list[PreparedRun], bare: Instrument,
                 beta_model: np.ndarray, thermal: ThermalDrift | None,
                 top: int = HEADING_TOP) -> list[CandidateScore]:
    """The scores of the ranked candidates ``scored``, the first ``top`` and every
    significant one with their heading RMSE before and after (module docstring).

    ``preps``: the runs on the drift channel, ``beta_model`` the model's drift coefficients
    there, ``bare`` the instrument the candidates' columns are evaluated on; ``thermal``:
    the thermal step of the thermal candidates (None when there are none).
    """
    chosen = [i < top or s.score.significant for i, s in enumerate(scored)]
    fast = [s.candidate.channel != "thermometers" for s in scored]
    h_before = h_before_t = None
    if any(c and f for c, f in zip(chosen, fast)):
        h_before = startup_heading_rmse(preps, _model_drift(preps, beta_model))
    if any(c and not f for c, f in zip(chosen, fast)):
        h_before_t = _heading_or_nan(lambda: refit_heading_rmse(thermal.without()))
    out = []
    for s, c in zip(scored, chosen):
        sc = s.score
        if c and s.candidate.kind == "accelerometer":
            sc = replace(sc, heading_rmse_before_deg=h_before,
                         heading_rmse_after_deg=_accelerometer_heading(s, preps, bare,
                                                                       beta_model))
        elif c and s.candidate.channel == "drift_dph":
            sc = replace(sc, heading_rmse_before_deg=h_before,
                         heading_rmse_after_deg=_gyro_heading(s, preps, bare))
        elif c:
            sc = replace(sc, heading_rmse_before_deg=h_before_t,
                         heading_rmse_after_deg=_heading_or_nan(
                             lambda: refit_heading_rmse(thermal.of(s))))
        out.append(sc)
    return out
