"""From the scored candidates to the ranking: significance, order, what the top one explains.

- **Significant** (:func:`significance`) = Holm's step-down over all scored candidates of
  every channel (Holm 1979, Scand. J. Statist. 6(2) 65) rejects the candidate at ``alpha``
  AND its cross-validated RMS drops.
- A drift candidate is also tested beyond a rate term on every node
  (:mod:`nfs.diagnose.drift_structure`, Holm over the drift candidates,
  :func:`beyond_rate_terms`); a significant one that does not stand beyond it is *tied*
  with that alternative.
- A significant thermal candidate must also beat the model's generic structural
  alternatives, pooled and run by run (:func:`nfs.fit.adequacy.structure_rival`,
  :func:`structure_rivals`); otherwise it is not significant and the rival is named.
- Order (:func:`rank`): significant thermometer candidates first (a missing thermal effect
  also shows in the drift, a missing gyro effect never shows in the thermometers), then the
  other significant ones, then the rest, unphysical ones last; within each group by the
  relative CV drop.
- One effect usually makes several targets significant (a coil-temperature term on every
  node whose temperature follows the coil's): every other significant candidate is
  refitted with the top one in the model, and if it then drops the CV RMS by less than
  :data:`CV_DROP` it is marked ``explained_by`` the top one (:func:`explained_by_top`).  This
  5 % is a practical threshold of "adds something of its own", not a test; significance does
  not use it.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Mapping, Sequence

import numpy as np

from ..instrument import Instrument
from ..fit.adequacy import MODEL_RIVAL, ThermalAdequacy, structure_rival
from ..fit.alternative_score import AlternativeScore
from .candidate_heading import ThermalDrift
from .candidate_score import ResidualChannel, ScoredCandidate
from .columns import candidate_columns
from .drift_structure import DriftStructure
from .result import CandidateScore
from ..scoring.intervals import holm
from ..scoring.run_stats import group_cv_rms, run_grams
from ..fit.structure import physical_lower

__all__ = ["CV_DROP", "significance", "beyond_rate_terms", "structure_rivals", "is_physical",
           "rank_key", "rank", "explained_by_top"]

#: A significant candidate is ``explained_by`` the top one when, refitted with the top one
#: in the model, it drops the CV RMS by less than this fraction (not used for significance).
CV_DROP = 0.05


def significance(scored: Sequence[ScoredCandidate], alpha: float) -> list[ScoredCandidate]:
    """Every candidate with its Holm-adjusted p-value and ``significant`` = Holm rejects it
    at ``alpha`` and its CV RMS drops."""
    adj = holm([s.score.wald_p for s in scored])
    reject = adj <= alpha
    return [replace(s, score=replace(
        s.score, holm_p=float(a), significant=bool(r and s.score.cv_rms_after
                                                   < s.score.cv_rms_before)))
            for s, r, a in zip(scored, reject, adj)]


def beyond_rate_terms(scored: Sequence[ScoredCandidate],
                      beyond: Mapping[str, tuple[float, float]], nodes: tuple[str, ...],
                      cv_rms_model: float, cv_rms_alternative: float, alpha: float
                      ) -> tuple[DriftStructure, list[ScoredCandidate]]:
    """The drift's structure against a rate term on every node, and the candidates with
    their p-value beyond it.

    ``beyond``: per drift candidate label, (p-value with the rate terms in the model,
    Bonferroni over its grid; held-out RMS), Holm-adjusted here over the drift candidates;
    ``cv_rms_model`` / ``cv_rms_alternative``: the held-out RMS of the drift window means
    without and with the rate terms [deg/h].  A significant candidate whose adjusted
    p-value is above ``alpha`` is tied with the alternative.
    """
    labels = list(beyond)
    holm_beyond = dict(zip(labels, holm([beyond[b][0] for b in labels])))
    rate_drops = {s.candidate.label: s.score.cv_drop for s in scored
                  if s.candidate.effect == "shupe_rate"}
    structure = DriftStructure(
        nodes=nodes, cv_rms_model=cv_rms_model, cv_rms_alternative=cv_rms_alternative,
        tied=tuple(s.candidate.label for s in scored if s.score.significant
                   and holm_beyond.get(s.candidate.label, 0.0) > alpha),
        best_rate=max(rate_drops, key=rate_drops.get) if rate_drops else None)
    return structure, [replace(s, score=replace(
        s.score, beyond_structure_p=float(holm_beyond[s.candidate.label])))
        if s.candidate.label in beyond else s for s in scored]


def structure_rivals(scored: Sequence[ScoredCandidate], adequacy: ThermalAdequacy,
                     effect_alternatives: Mapping[str, AlternativeScore]
                     ) -> list[ScoredCandidate]:
    """Every significant thermal candidate held to the structure's rivals: significant only
    when it beats the model and every structural alternative pooled and run by run
    (:func:`nfs.fit.adequacy.structure_rival`, scored as ``effect_alternatives`` by
    label), else ``structure_tie`` names the alternative it does not beat."""
    out = list(scored)
    for i, s in enumerate(out):
        if s.candidate.channel != "thermometers" or not s.score.significant:
            continue
        alt = effect_alternatives.get(s.candidate.label)
        r = MODEL_RIVAL if alt is None else structure_rival(alt, adequacy)
        out[i] = replace(s, score=replace(
            s.score, significant=r is None,
            structure_tie=None if r in (None, MODEL_RIVAL) else r))
    return out


def is_physical(sc: CandidateScore) -> bool:
    """No coefficient below its physical bound (a heat power or a lag below 0)."""
    for k, v in sc.coefficient.items():
        lo = physical_lower(sc.effect, k)
        if lo is not None and v < lo:
            return False
    return True


def rank_key(s: ScoredCandidate) -> tuple:
    """Significant thermometer candidates first (a missing thermal effect also shows in the
    drift, a missing gyro effect never in the thermometers), then significant drift and
    accelerometer ones, then the rest, unphysical ones last; within each group by the
    relative drop of the CV RMS."""
    sc = s.score
    group = (0 if sc.channel == "thermometers" else 1) if sc.significant else \
        (2 if sc.physical else 3)
    return group, sc.cv_rms_after / sc.cv_rms_before


def rank(scored: Sequence[ScoredCandidate]) -> list[ScoredCandidate]:
    """The candidates with ``physical`` set (:func:`is_physical`), in ranking order
    (:func:`rank_key`; a stable sort)."""
    out = [replace(s, score=replace(s.score, physical=is_physical(s.score))) for s in scored]
    out.sort(key=rank_key)
    return out


def explained_by_top(ranking: list[CandidateScore], scored: list[ScoredCandidate],
                     groups: np.ndarray, channels: Mapping[str, ResidualChannel],
                     bare: Instrument, thermal: ThermalDrift | None) -> list[CandidateScore]:
    """Mark the significant candidates that the top significant one explains.

    Each other significant candidate is refitted with the top one in the model; when its own
    CV drop over model + top is below :data:`CV_DROP`, it adds nothing the top one does not
    explain and gets ``explained_by`` = the top's label.  A drift candidate under a thermal
    top one is refitted on the drift of the thermal model with the top one added
    (:meth:`ThermalDrift.of <nfs.diagnose.candidate_heading.ThermalDrift.of>`).
    ``channels``: each residual channel by name (``drift_dph``, ``acc_x_g``, ...,
    ``thermometers``); ``groups``: the CV group of each run.
    """
    sig = [i for i, s in enumerate(ranking) if s.significant]
    if len(sig) < 2:
        return ranking
    by = {(s.candidate.effect, s.candidate.target): s for s in scored}
    top = by[(ranking[sig[0]].effect, ranking[sig[0]].target)]
    label = top.candidate.label
    top_ch = channels[top.candidate.channel]
    own = {top.candidate.channel: ((top_ch.ys, top_ch.Xs), top.cols)}
    preps = None
    if top.candidate.channel == "thermometers" and any(
            ranking[i].channel == "drift_dph" for i in sig[1:]):
        preps = thermal.of(top)
        own["drift_dph"] = (([p.y for p in preps], [p.X for p in preps]), None)
    out = list(ranking)
    for i in sig[1:]:
        s = ranking[i]
        if s.channel not in own:
            continue
        (ys, Xs), top_cols = own[s.channel]
        X_top = Xs if top_cols is None else [np.hstack([X, t]) for X, t in zip(Xs, top_cols)]
        rec = by[(s.effect, s.target)]
        cols = rec.cols if top_cols is not None else candidate_columns(
            rec.candidate, rec.shapes, preps, bare)
        cv_top = group_cv_rms([run_grams(ys, X_top)], groups)[0]
        Z = [np.hstack([X, cc]) for X, cc in zip(X_top, cols)]
        if group_cv_rms([run_grams(ys, Z)], groups)[0] > (1.0 - CV_DROP) * cv_top:
            out[i] = replace(s, explained_by=label)
    return out
