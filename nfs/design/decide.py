"""Decide between rivals on the runs taken: the likelihood ratio, and how sure it is.

Two rivals a and b fitted to the same runs predict the recorded numbers mu_a and mu_b
(:mod:`nfs.design.predict`, each replaying every run from its own start states).  In the
noise the runs show (:mod:`nfs.design.noise_level`: the sensor noise raised per channel,
a constant per channel and run free), the log-likelihood ratio of the measured numbers y is

    Lambda = (|P (y - mu_b) / sigma|^2 - |P (y - mu_a) / sigma|^2) / 2,

positive when the runs lie closer to a.  If a is the unit, Lambda ~ N(D / 2, D) with D the
squared separation of the two predictions (:mod:`nfs.design.separation`, here without
parameter draws: both rivals are at their fit), so the rule

    name a when Lambda >= LAMBDA_NAME, name b when Lambda <= -LAMBDA_NAME, else a tie,

names the wrong rival with probability Phi(-s / 2 - LAMBDA_NAME / s) and decides right
with probability Phi(s / 2 - LAMBDA_NAME / s), s = sqrt(D).  :data:`LAMBDA_NAME` = 2
(a likelihood ratio of e^2 = 7.4; 2 Lambda = 4 is "positive" evidence on the scale of Kass
and Raftery 1995, J. Am. Stat. Assoc. 90(430) 773, where 2 ln K from 2 to 6 is): at the default
design margin s = 3 a designed run decides right with probability 0.80 and wrong with 0.015
(:func:`decision_rates`; the rates measured on simulated runs are in
tests/design/test_decide.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import combinations
from typing import Sequence

import numpy as np
from scipy.stats import norm

from ..diagnose.result import Answer
from ..instrument import Instrument
from ..run import Run
from .predict import CHANNELS
from .replay import replay_runs_taken
from .rivals import MODEL, Rival, rival_models, rivals_from_diagnosis
from .separation import RivalPrediction, separation

__all__ = ["Decision", "Settlement", "decide", "decision_rates", "settle_tie", "LAMBDA_NAME"]

#: |Lambda| a decision needs (module docstring).
LAMBDA_NAME = 2.0


def decision_rates(s: float, threshold: float = LAMBDA_NAME) -> tuple[float, float]:
    """(P(the right rival named), P(the wrong one named)) at separation ``s`` [noise
    standard deviations] (module docstring)."""
    if not s > 0:
        return 0.0, 0.0
    return (float(norm.cdf(s / 2.0 - threshold / s)),
            float(norm.cdf(-s / 2.0 - threshold / s)))


@dataclass(frozen=True)
class Decision:
    """What the runs say between two rivals."""

    a: str
    """The first rival's label."""
    b: str
    """The second rival's label."""
    llr: float
    """Lambda: log-likelihood ratio of a over b on the runs (module docstring)."""
    separation_sigma: float
    """s = sqrt(D) of the two fitted rivals' predictions of the runs."""
    noise_factors: dict[str, float]
    """The factors the sensor noise was raised by, per channel."""
    by_channel: dict[str, float]
    """Lambda of each channel alone."""

    @property
    def winner(self) -> str | None:
        """The rival named, or None (a tie)."""
        if self.llr >= LAMBDA_NAME:
            return self.a
        if self.llr <= -LAMBDA_NAME:
            return self.b
        return None

    @property
    def text(self) -> str:
        """The decision in one sentence."""
        p_right, p_wrong = decision_rates(self.separation_sigma)
        ratio = f"likelihood ratio e^{abs(self.llr):.1f}"
        if self.winner is None:
            return (f"the runs cannot decide between {self.a} and {self.b} ({ratio}, "
                    f"their predictions {self.separation_sigma:.1f} noise standard "
                    f"deviations apart; a decision needs e^{LAMBDA_NAME:g}): nfs design")
        loser = self.b if self.winner == self.a else self.a
        return (f"the runs favour {self.winner} over {loser} ({ratio}; the predictions "
                f"{self.separation_sigma:.1f} noise standard deviations apart, where this "
                f"rule names the wrong one with probability {p_wrong:.2g})")

    def to_dict(self) -> dict:
        return {"a": self.a, "b": self.b, "llr": self.llr, "winner": self.winner,
                "separation_sigma": self.separation_sigma,
                "noise_factors": dict(self.noise_factors), "by_channel": dict(self.by_channel),
                "text": self.text}


def _llr(y, mu_a, mu_b, sigma, channels) -> tuple[float, dict[str, float]]:
    """Lambda over the runs, and per channel (constants per channel and run projected)."""
    by = {}
    for c in channels:
        total = 0.0
        for yr, ar, br, sr in zip(y, mu_a, mu_b, sigma):
            w = 1.0 / np.maximum(sr[c], 1e-300)
            ok = np.isfinite(yr.values[c])
            ra = (yr.values[c] - ar.values[c])[ok] * w[ok]
            rb = (yr.values[c] - br.values[c])[ok] * w[ok]
            if ra.size == 0:
                continue
            ww = w[ok] * w[ok]
            # the constant projected out in the 1/sigma^2 metric (as in separation.py)
            ra = ra - w[ok] * (np.sum(w[ok] * ra) / np.sum(ww))
            rb = rb - w[ok] * (np.sum(w[ok] * rb) / np.sum(ww))
            total += 0.5 * float(rb @ rb - ra @ ra)
        by[c] = total
    return float(sum(by.values())), by


def decide(rivals: Sequence[Rival], runs: Sequence[Run]) -> list[Decision]:
    """The decision between every pair of ``rivals`` on ``runs`` (module docstring)."""
    taken = replay_runs_taken(rivals, list(runs))
    preds = [p.mean for p in taken.predictions]
    measured, sigma, factors = taken.measured, taken.sigma, taken.factors
    out = []
    for i, j in combinations(range(len(rivals)), 2):
        llr, by = _llr(measured, preds[i], preds[j], sigma, CHANNELS)
        sep = separation(RivalPrediction(preds[i]), RivalPrediction(preds[j]), sigma)
        out.append(Decision(rivals[i].label, rivals[j].label, llr, sep.sigma, factors, by))
    return out



#: z of the two-sided 95 % interval of a fitted coefficient.
_Z95 = 1.959963984540054


def winner_interval(r: Rival, diagnosis: dict, factor: float = 1.0
                    ) -> dict[str, tuple[float, float]]:
    """95 % interval of each coefficient of the winner's new effect: the diagnosis's own
    (a t interval from the covariance clustered by run, :mod:`nfs.diagnose.stats`) when it
    scored the effect; else the rival fit's standard error, which takes the residual as
    white, times ``factor`` (the excess the runs show on the effect's channel,
    :mod:`nfs.design.noise_level`)."""
    effect, _, target = r.label.partition(":")
    for row in (diagnosis or {}).get("ranking") or []:
        if row.get("effect") == effect and (row.get("target") or "") == target \
                and row.get("interval"):
            return {k: (float(v[0]), float(v[1])) for k, v in row["interval"].items()}
    if r.fit is None:
        return {}
    prefix = f"effects.{r.label}."
    out = {}
    for p, v in r.fit.params.items():
        if p.startswith(prefix):
            se = factor * r.fit.stderr.get(p, float("inf"))
            out[p[len(prefix):]] = (v - _Z95 * se, v + _Z95 * se)
    return out


def _interval_text(r: Rival, interval: dict[str, tuple[float, float]]) -> str:
    """The new effect's fitted coefficients with their 95 % intervals."""
    if r.fit is None:
        return ""
    prefix = f"effects.{r.label}."
    parts = []
    for p, v in r.fit.params.items():
        if not p.startswith(prefix):
            continue
        name = p[len(prefix):]
        lo, hi = interval.get(name, (float("nan"), float("nan")))
        if np.isfinite(lo) and np.isfinite(hi):
            parts.append(f"{name} = {v:.3g} [{lo:.3g}, {hi:.3g}]")
        else:
            parts.append(f"{name} = {v:.3g} (not determined)")
    return "; ".join(parts)


@dataclass(frozen=True)
class Settlement:
    """A diagnosis's tie put to the runs: one answer."""

    answer: Answer
    """``add`` the winner (its coefficients' intervals in the text), or still ``tie``."""
    decisions: tuple[Decision, ...]
    """Every pair's decision."""
    rivals: tuple[Rival, ...]
    """The rivals fitted."""
    interval: dict[str, tuple[float, float]] = field(default_factory=dict)
    """95 % interval of each coefficient of the winner's new effect
    (:func:`winner_interval`); empty without a winner."""

    def to_dict(self) -> dict:
        return {"answer": self.answer.to_dict(),
                "interval": {k: list(v) for k, v in self.interval.items()},
                "decisions": [d.to_dict() for d in self.decisions],
                "rivals": [r.to_dict() for r in self.rivals]}


def settle_tie(diagnosis: dict, inst: Instrument, runs: Sequence[Run], *,
               labels: Sequence[str] | None = None, **fit_kw) -> Settlement | None:
    """Put a diagnosis's tie (``diagnosis``: :meth:`nfs.diagnose.Diagnosis.to_dict`) to the
    runs: fit each tied explanation (:func:`nfs.design.rivals.rival_models`) and decide
    (:func:`decide`).  A rival that wins every pair it is in gives the answer ``add`` it,
    with its coefficients' 95 % intervals; otherwise the tie stands, with the weakest
    pair's likelihood ratio.  None when the diagnosis is no tie.

    ``labels``: the explanations to put to the runs instead of the tie's (the rivals a run
    was designed for, :func:`nfs.design.design_experiment`: after that run, the diagnosis
    may tie other candidates, but the question the run was made to answer is theirs); the
    diagnosis then need not be a tie.
    """
    answer = (diagnosis or {}).get("answer") or {}
    if labels is None:
        if answer.get("kind") != "tie":
            return None
        labels = rivals_from_diagnosis(diagnosis)
    labels = list(labels)
    rivals = rival_models(inst, runs, labels, **fit_kw)
    decisions = decide(rivals, runs)
    # the rival that wins every pair it is in (with two rivals: the pair's winner)
    wins = [r.label for r in rivals
            if all(d.winner == r.label for d in decisions if r.label in (d.a, d.b))]
    if wins:
        win = wins[0]
        r = next(x for x in rivals if x.label == win)
        others = ", ".join(x.label for x in rivals if x.label != win)
        lr = min(abs(d.llr) for d in decisions if win in (d.a, d.b))
        kind = next((e.spec.kind for e in r.instrument.effects if e.label == win), "thermal")
        channel = "drift_dph" if kind == "gyro" else "temp_fog_c"
        factor = max(d.noise_factors.get(channel, 1.0) for d in decisions)
        interval = winner_interval(r, diagnosis, factor)
        coef = _interval_text(r, interval)
        what = "keep the model as it is" if win == MODEL else f"add {win}"
        text = (f"{what}" + (f" ({coef})" if coef else "")
                + f": the runs decide the tie with {others} (likelihood ratio e^{lr:.1f}, "
                f"a decision needs e^{LAMBDA_NAME:g})")
        return Settlement(Answer("add" if win != MODEL else "nothing", (win,), text),
                          tuple(decisions), tuple(rivals), interval)
    d = min(decisions, key=lambda x: abs(x.llr))
    head = (answer.get("text", "").split("; a run that would")[0]
            if answer.get("kind") == "tie" else
            f"these runs cannot tell apart: {', '.join(labels)}")
    text = head + f"; put to the runs, {d.text}"
    return Settlement(Answer("tie", tuple(labels), text), tuple(decisions), tuple(rivals))
