"""What one structural alternative gains over the model, and whether one structure's held-out
residual beats another's.

An alternative of :mod:`nfs.fit.structure` (a new node, a free link, a thermometer that
sits elsewhere, ...) adds a few new numbers theta to the model (positive capacities and
conductances in log: their steps are then relative).  :func:`score_alternative` scores it on the
linearised thermometer residual of :mod:`nfs.fit.thermometer_cv`:

- screening: one bounded Gauss-Newton step of all numbers from the alternative's start, with
  Z = [J_0, d r / d theta] (1 + k evaluations);
- refinement (the best few after screening): theta by variable projection,
  min |(I - J_0 J_0^+) r(theta)|^2 (:func:`scipy.optimize.least_squares`, bounded: the
  model's parameters enter through the frozen J_0), then up to three chord steps of all
  numbers together, each kept only if the evaluated residual falls.  This is why the check
  costs a fraction of the model's own thermal fit: a full refit of the model's parameters
  per alternative would cost that fit again for every alternative.

The score is the leave-one-start-temperature-out CV RMS of the three thermometers, the same
for the model and every alternative; an alternative beats the model when its CV RMS is lower
by more than :data:`CV_DROP`.  :func:`better_run_by_run` asks more of a structure that is to
replace another: a lower pooled CV RMS and a lower held-out residual run by run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import ttest_1samp

from ..instrument import Instrument
from .structure import StructuralAlternative
from .thermometer_cv import (ChordModel, ThermometerProblem, residual_jacobian,
                             sum_of_squares)

__all__ = ["AlternativeScore", "score_alternative", "better_run_by_run", "CV_DROP",
           "BEATS_ALPHA"]

#: Relative drop of the CV RMS an alternative must exceed to beat the model.
CV_DROP = 0.05
#: Level of the one-sided paired test by which a structure beats another run by run.
BEATS_ALPHA = 0.05


@dataclass(frozen=True)
class AlternativeScore:
    """What one alternative changes and what it gains."""

    name: str
    """Name of the alternative."""
    kind: str
    """``split``, ``insert``, ``link``, ``thermometer``, ``tec`` or ``effect``."""
    description: str
    """One sentence: what it changes."""
    params: dict[str, float]
    """Fitted new numbers {path: value}."""
    cv_rms_before_k: float
    """Leave-one-start-temperature-out CV RMS of the three thermometers, model [K]."""
    cv_rms_after_k: float
    """The same with the alternative [K]."""
    rms_before_k: dict[str, dict[str, float]]
    """Model residual RMS {thermometer: {stage: K}}."""
    rms_after_k: dict[str, dict[str, float]]
    """Residual RMS with the alternative {thermometer: {stage: K}}."""
    cv_channels_before_k: dict[str, dict[str, float]]
    """Held-out residual RMS of the model {thermometer: {stage: K}}."""
    cv_channels_after_k: dict[str, dict[str, float]]
    """Held-out residual RMS with the alternative {thermometer: {stage: K}}."""
    refined: bool
    """True: fitted (variable projection, then chord steps) and its RMS evaluated; False:
    screened only (one linearised Gauss-Newton step from its start; its numbers and RMS
    are those of the linearised residual)."""
    instrument: Instrument | None = field(repr=False, compare=False,
                                          metadata={"record": False})
    """The fitted alternative instrument (the model's parameters moved with it); an
    alternative not refined holds its start values, which need not be a valid instrument, so
    it is not written to JSON (None when read back: :mod:`nfs.io.records`)."""
    cv_sse_by_run: tuple[float, ...] = ()
    """Held-out squared residual summed over each run's knots, with the alternative [K^2]
    (the pairs :func:`better_run_by_run` tests)."""

    @property
    def cv_drop(self) -> float:
        """Relative drop of the CV RMS."""
        return 1.0 - self.cv_rms_after_k / self.cv_rms_before_k

    @property
    def beats_model(self) -> bool:
        """cv_drop > :data:`CV_DROP`."""
        return self.cv_drop > CV_DROP

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return {"name": self.name, "kind": self.kind, "description": self.description,
                "params": dict(self.params), "cv_rms_before_k": self.cv_rms_before_k,
                "cv_rms_after_k": self.cv_rms_after_k, "cv_drop": self.cv_drop,
                "beats_model": self.beats_model, "refined": self.refined,
                "rms_before_k": {k: dict(v) for k, v in self.rms_before_k.items()},
                "rms_after_k": {k: dict(v) for k, v in self.rms_after_k.items()},
                "cv_channels_before_k": {k: dict(v)
                                         for k, v in self.cv_channels_before_k.items()},
                "cv_channels_after_k": {k: dict(v)
                                        for k, v in self.cv_channels_after_k.items()}}


class _LogScale:
    """Numbers with a positive lower bound (capacities, conductances) are fitted in log:
    their steps are then relative, the same for 0.05 W/K and 3500 J/K."""

    def __init__(self, start: Sequence[float], bounds: Sequence[tuple[float, float]]):
        self.log = np.array([lo > 0 for lo, _ in bounds], dtype=bool)
        self.lo = np.array([lo for lo, _ in bounds], dtype=float)
        self.hi = np.array([hi for _, hi in bounds], dtype=float)
        self.ulo, self.uhi = self.to_u(self.lo), self.to_u(self.hi)
        self.u0 = self.to_u(np.clip(np.array(start, dtype=float), self.lo, self.hi))

    def to_u(self, v: np.ndarray) -> np.ndarray:
        """The fitted numbers u of values v (log where the lower bound is positive)."""
        return np.where(self.log, np.log(np.where(self.log, v, 1.0)), v)

    def to_v(self, u: np.ndarray) -> np.ndarray:
        """The values v of fitted numbers u, clipped to the bounds."""
        u = np.clip(u, self.ulo, self.uhi)
        return np.where(self.log, np.exp(u), u)

    def steps(self, u: np.ndarray) -> np.ndarray:
        """Forward-difference steps, inward from the upper bound."""
        h = np.where(self.log, 1e-3, 1e-3 * np.maximum(self.hi - self.lo, 1e-9))
        return np.where(u + h > self.uhi, -h, h)


def score_alternative(prob: ThermometerProblem, model: ChordModel, alt: StructuralAlternative,
                      refine: bool,
                      cv_model: float, rms_model: dict, max_nfev: int,
                      u_start: np.ndarray | None = None, chord_steps: int = 3
                      ) -> tuple[AlternativeScore, np.ndarray]:
    """Screen or fit one alternative; (score, its fitted u).

    Screening: the residual and its Jacobian at the start u_0 (1 + k evaluations); the
    alternative's numbers and the model's move by the bounded linear fit, the CV and the
    RMS are those of the linearised residual.  Refinement: variable projection from
    ``u_start`` (at most ``max_nfev`` evaluations besides the Jacobians), then up to
    ``chord_steps`` chord steps of all numbers, each kept when the evaluated residual falls;
    the CV is taken on the residual linearised at the last evaluated point.
    """
    tr = _LogScale(alt.start, alt.bounds)

    def build(u):
        return alt.build(tr.to_v(u))

    u = tr.u0 if u_start is None else np.clip(u_start, tr.ulo, tr.uhi)
    if refine:
        res = least_squares(lambda uu: model.project(np.concatenate(prob.resid(build(uu)))),
                            u, bounds=(tr.ulo, tr.uhi), method="trf", x_scale="jac",
                            diff_step=1e-3, max_nfev=max_nfev, ftol=1e-4, xtol=1e-4)
        u = res.x
    r_a = prob.resid(build(u))
    Ja = residual_jacobian(prob, build, u, r_a, tr.steps(u))
    keep = model.kept(alt.instrument).astype(float)   # columns of numbers the alternative has
    Z = [np.hstack([jm * keep, ja]) for jm, ja in zip(model.J, Ja)]
    lo_m, hi_m = model.box()
    lo = np.concatenate([lo_m, tr.ulo - u])
    hi = np.concatenate([hi_m, tr.uhi - u])
    hi = np.maximum(hi, lo + 1e-12)
    cv, beta, held = prob.linear_fit(r_a, Z, lo, hi)
    n_m = len(model.paths)
    u_fit = np.clip(u + beta[n_m:], tr.ulo, tr.uhi)
    final = model.moved(build(u_fit), beta[:n_m])
    r_f = [ri + zi @ beta for ri, zi in zip(r_a, Z)]
    if refine:
        # chord steps of all the numbers (model's and alternative's) with the frozen
        # Jacobian Z, each accepted while it lowers the evaluated residual; the CV is then
        # taken from the evaluated all-runs fit
        r_f, final, u_fit, shift = r_a, build(u), u, np.zeros(beta.size)
        for _ in range(chord_steps):
            _, step, _ = prob.linear_fit(r_f, Z, lo - shift,
                                         np.maximum(hi - shift, lo - shift + 1e-12), folds=False)
            new_shift = shift + step
            u_new = np.clip(u + new_shift[n_m:], tr.ulo, tr.uhi)
            cand = model.moved(build(u_new), new_shift[:n_m])
            r_c = prob.resid(cand)
            if sum_of_squares(r_c) >= sum_of_squares(r_f) * (1.0 - 1e-3):
                if sum_of_squares(r_c) < sum_of_squares(r_f):
                    r_f, final, u_fit, shift = r_c, cand, u_new, new_shift
                break
            r_f, final, u_fit, shift = r_c, cand, u_new, new_shift
        cv, _, held = prob.linear_fit(r_f, Z, lo - shift,
                                      np.maximum(hi - shift, lo - shift + 1e-12))
    params = {p: float(v) for p, v in zip(alt.free, tr.to_v(u_fit))}
    score = AlternativeScore(
        name=alt.name, kind=alt.kind, description=alt.description, params=params,
        cv_rms_before_k=cv_model, cv_rms_after_k=cv, rms_before_k=rms_model[0],
        rms_after_k=prob.rms(r_f), cv_channels_before_k=rms_model[1],
        cv_channels_after_k=prob.rms(held), refined=refine, instrument=final,
        cv_sse_by_run=tuple(sum_of_squares([h]) for h in held))
    return score, u_fit


def better_run_by_run(cv_rms_k: float, cv_sse_by_run: Sequence[float], ref_cv_rms_k: float,
                      ref_sse_by_run: Sequence[float], margin: float = 0.0,
                      alpha: float = BEATS_ALPHA) -> bool:
    """Is one structure's held-out residual lower than a reference's, pooled (by more than
    ``margin``) and run by run?

    Run by run: the paired per-run log-ratios ln(SSE_ref / SSE) of the held-out squared
    residual, one-sided t test at ``alpha``.  On the log scale a run whose misfit is ten
    times another's weighs the same when both improve by the same factor (the differences
    of the squared residual would let the worst run's scatter hide four runs that all
    improve threefold or more).
    """
    if not (math.isfinite(cv_rms_k) and cv_rms_k < (1.0 - margin) * ref_cv_rms_k):
        return False
    ref = np.asarray(ref_sse_by_run, dtype=float)
    new = np.asarray(cv_sse_by_run, dtype=float)
    if new.size != ref.size or new.size < 2 or np.any(new <= 0) or np.any(ref <= 0):
        return False
    d = np.log(ref / new)
    if not np.any(d > 0):
        return False
    if np.all(d > 0) and np.ptp(d) == 0:   # no spread: the t statistic is undefined
        return True
    return bool(ttest_1samp(d, 0.0, alternative="greater").pvalue < alpha)
