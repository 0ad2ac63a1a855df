"""Decide between rivals on the runs taken, and how sure it is.

Two rivals a and b fitted to the same runs predict the recorded numbers mu_a and mu_b
(:mod:`nfs.rivals.predict`, each replaying every run from its own start states).  In the
noise the runs show (:mod:`nfs.rivals.noise_level`: the sensor noise raised per channel, a
constant per channel and run free), :mod:`nfs.rivals.evidence` gives the log-likelihood
ratio Lambda of a over b, Lambda_adj: Lambda less the price of the numbers the rival it
leans to fits beyond the other, and Vuong's statistic Z = Lambda_adj / sqrt(V) with a variance V that allows
for model error correlated along the runs (at least D, the squared separation of the two
predictions).  The rule

    name a when Lambda_adj >= LAMBDA_NAME and Z >= Z_NAME (b: both <= minus them),
    else a tie,

asks two things.  Lambda_adj >= :data:`LAMBDA_NAME` = 2 is a likelihood ratio of e^2 = 7.4
(2 Lambda = 4 is "positive" evidence on the scale of Kass and Raftery 1995, J. Am. Stat.
Assoc. 90(430) 773).  Z >= :data:`Z_NAME` = 1.645 is Vuong's one-sided 5 % test that a is
closer to the unit than b, which holds where neither rival is the unit: a likelihood ratio
alone assumes one of them is, and on units the model does not describe it names a rival
for differences that the runs' own model error makes.

If a is the unit and the noise is what the runs show (V = D = s^2, no price), Lambda ~
N(s^2 / 2, s^2): the rule decides right with probability Phi(s/2 - max(LAMBDA_NAME / s,
Z_NAME)) and names the wrong rival with probability Phi(-s/2 - max(LAMBDA_NAME / s,
Z_NAME)) (:func:`decision_rates`; at s = 3: 0.44 and 0.0012, at s = 5: 0.81 and 0.0001;
measured on simulated runs in tests/design/test_decide.py).

Every decision of a tie (:func:`settle_tie`) puts the model as it is beside the tied
explanations: an explanation is added only when it beats the model too.  Two rivals of
which only one refits the thermal stage are compared on the dwell channels alone
(:func:`pair_channels`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import combinations
from typing import Sequence

import numpy as np
from scipy.stats import norm

from ..diagnose.result import Answer, Diagnosis
from ..fit.calibration import check_fit_keywords
from ..fit.structure import positive_parameter
from ..scoring.intervals import positive_interval
from ..effects.thermometer import THERMOMETERS
from ..instrument import Instrument
from ..run import Run
from .evidence import Evidence, evidence
from .predict import CHANNELS
from .replay import replay_runs_taken
from ..io.records import from_record, to_record
from .models import MODEL, RATE_ALTERNATIVE, Rival, rival_models

__all__ = ["Decision", "Settlement", "decide", "decision_rates", "settle_tie", "settlement",
           "tie_labels", "LAMBDA_NAME", "Z_NAME", "SETTLEMENT_SCHEMA"]

#: The JSON schema of :meth:`Settlement.to_dict`.
SETTLEMENT_SCHEMA = "nfs-settlement/1"

#: Lambda_adj a decision needs (module docstring).
LAMBDA_NAME = 2.0
#: Vuong's Z a decision needs: the one-sided 5 % point of N(0, 1) (module docstring).
Z_NAME = 1.6448536269514722


def decision_rates(s: float, threshold: float = LAMBDA_NAME,
                   z: float = Z_NAME) -> tuple[float, float]:
    """(P(the right rival named), P(the wrong one named)) at separation ``s`` [noise
    standard deviations] (module docstring)."""
    if not s > 0:
        return 0.0, 0.0
    need = max(threshold / s, z)
    return float(norm.cdf(s / 2.0 - need)), float(norm.cdf(-s / 2.0 - need))


@dataclass(frozen=True)
class Decision:
    """What the runs say between two rivals."""

    #: Properties written beside the fields (:mod:`nfs.io.records`).
    DERIVED = ("winner", "separation_sigma", "text")

    a: str
    """The first rival's label."""
    b: str
    """The second rival's label."""
    evidence: Evidence
    """Lambda, its price, its variance and Z (:mod:`nfs.rivals.evidence`)."""
    noise_factors: dict[str, float]
    """The factors the sensor noise was raised by, per channel."""

    @property
    def separation_sigma(self) -> float:
        """s = sqrt(D) of the two fitted rivals' predictions of the numbers the decision
        read."""
        return math.sqrt(self.evidence.d2)

    @property
    def llr(self) -> float:
        """Lambda: the log-likelihood ratio of a over b on the runs."""
        return self.evidence.llr

    @property
    def by_channel(self) -> dict[str, float]:
        """Lambda of each channel alone."""
        return self.evidence.by_channel

    @property
    def winner(self) -> str | None:
        """The rival named, or None (a tie)."""
        e = self.evidence
        if e.adjusted >= LAMBDA_NAME and e.z >= Z_NAME:
            return self.a
        if e.adjusted <= -LAMBDA_NAME and e.z <= -Z_NAME:
            return self.b
        return None

    @property
    def text(self) -> str:
        """The decision in one sentence."""
        e = self.evidence
        _, p_wrong = decision_rates(self.separation_sigma)
        lean = self.a if e.llr >= 0.0 else self.b
        paid = e.price if e.llr >= 0.0 else -e.price
        price = (f", e^{abs(e.adjusted):.1f} after the price of the {paid:g} numbers it "
                 "fits beyond the other" if paid > 0 else "")
        said = (f"likelihood ratio e^{abs(e.llr):.1f} for {_words(lean)}{price}; Vuong's Z "
                f"{abs(e.z):.1f} with the model error along the runs counted")
        if self.winner is None:
            return (f"the runs cannot decide between {_words(self.a)} and {_words(self.b)} "
                    f"({said}; their predictions {self.separation_sigma:.1f} noise standard "
                    f"deviations apart; a decision needs e^{LAMBDA_NAME:g} and Z "
                    f"{Z_NAME:.3g}): nfs design")
        loser = self.b if self.winner == self.a else self.a
        return (f"the runs favour {_words(self.winner)} over {_words(loser)} ({said}; the "
                f"predictions {self.separation_sigma:.1f} noise standard deviations apart, "
                f"where this rule names the wrong one with probability {p_wrong:.2g})")

    def to_dict(self) -> dict:
        e = self.evidence
        return {"a": self.a, "b": self.b, "llr": e.llr, "price": e.price,
                "llr_adjusted": e.adjusted, "variance": e.variance, "z": e.z,
                "winner": self.winner, "separation_sigma": self.separation_sigma,
                "noise_factors": dict(self.noise_factors), "by_channel": dict(e.by_channel),
                "text": self.text}


#: The channels read at the turntable's dwells (the gyro's drift, the accelerometers).
DWELL_CHANNELS = tuple(c for c in CHANNELS if c not in THERMOMETERS.values())


def pair_channels(a: Rival, b: Rival) -> tuple[str, ...]:
    """The channels a decision between ``a`` and ``b`` reads: every channel when both
    refit the thermal stage or neither does; the dwell channels alone when only one does.
    A free number in a refitted thermal stage (a heat source's power) takes up on the
    thermometers whatever heat the model lacks, a thermal misfit that the other rival's
    fixed thermal stage keeps: a gain that says nothing about the question put (seen on
    units the model does not describe: a 3 W heat source in the coil beat a turn-on
    transient by e^301 on the thermometers and lost by e^6 on the drift).  The
    thermometers' own question, whether the thermal structure is right, is the
    diagnosis's (:mod:`nfs.fit.adequacy`)."""
    return CHANNELS if a.thermal_refit == b.thermal_refit else DWELL_CHANNELS


def decide(rivals: Sequence[Rival], runs: Sequence[Run]) -> list[Decision]:
    """The decision between every pair of ``rivals`` on ``runs`` (module docstring), each
    on the channels :func:`pair_channels` gives."""
    taken = replay_runs_taken(rivals, list(runs))
    preds = [p.mean for p in taken.predictions]
    measured, sigma, factors = taken.measured, taken.sigma, taken.factors
    out = []
    for i, j in combinations(range(len(rivals)), 2):
        chans = pair_channels(rivals[i], rivals[j])
        ev = evidence(measured, preds[i], preds[j], sigma, chans,
                      price=rivals[i].n_added - rivals[j].n_added)
        out.append(Decision(rivals[i].label, rivals[j].label, ev, factors))
    return out


#: z of the two-sided 95 % interval of a fitted coefficient.
_Z95 = 1.959963984540054


def winner_interval(r: Rival, diagnosis: Diagnosis | None, factor: float = 1.0
                    ) -> dict[str, tuple[float, float]]:
    """95 % interval of each coefficient of the winner's new effect: the diagnosis's own
    (a t interval from the covariance clustered by run, :mod:`nfs.scoring.run_stats`) when it
    scored the effect; else the rival fit's standard error, which takes the residual as
    white, times ``factor`` (the excess the runs show on the effect's channel,
    :mod:`nfs.rivals.noise_level`)."""
    effect, _, target = r.label.partition(":")
    for row in () if diagnosis is None else diagnosis.ranking:
        if row.effect == effect and (row.target or "") == target and row.interval:
            return {k: (float(v[0]), float(v[1])) for k, v in row.interval.items()}
    if r.fit is None:
        return {}
    prefix = f"effects.{r.label}."
    out = {}
    for p, v in r.fit.params.items():
        if p.startswith(prefix):
            name, h = p[len(prefix):], _Z95 * factor * r.fit.stderr.get(p, float("inf"))
            # a positive quantity's interval on its log: no negative time constant or power
            out[name] = (positive_interval(v, h) if positive_parameter(effect, name)
                         else (v - h, v + h))
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

    #: Properties written beside the fields (:mod:`nfs.io.records`).
    DERIVED = ("standing_labels",)

    answer: Answer
    """``add`` the winner (its coefficients' intervals in the text), ``nothing`` (the model
    as it is won), ``unexplained`` (a change of structure won), or still ``tie``."""
    decisions: tuple[Decision, ...]
    """Every pair's decision."""
    rivals: tuple[Rival, ...]
    """The rivals fitted."""
    interval: dict[str, tuple[float, float]] = field(default_factory=dict)
    """95 % interval of each coefficient of the winner's new effect
    (:func:`winner_interval`); empty without a winner."""

    @property
    def standing(self) -> tuple[Rival, ...]:
        """The rivals a tie leaves standing (none beaten by another): the rivals a run
        should be designed for (:func:`nfs.design.design_experiment`); the winner alone
        after a decision."""
        keep = set(self.answer.labels) or {MODEL}
        return tuple(r for r in self.rivals if r.label in keep)

    @property
    def standing_labels(self) -> tuple[str, ...]:
        """The labels of :attr:`standing`."""
        return tuple(r.label for r in self.standing)

    def to_dict(self) -> dict:
        """Every field as JSON-ready data, the rivals' fitted instruments as TOML
        (:mod:`nfs.io.records`; schema :data:`SETTLEMENT_SCHEMA`)."""
        return to_record(self, SETTLEMENT_SCHEMA)

    @classmethod
    def from_dict(cls, data: dict) -> "Settlement":
        """The settlement :meth:`to_dict` wrote."""
        return from_record(cls, data, SETTLEMENT_SCHEMA)


def tie_labels(diagnosis: Diagnosis) -> list[str]:
    """The explanations a diagnosis's tie names (empty when its answer is no tie)."""
    answer = diagnosis.answer
    return list(answer.labels) if answer.kind == "tie" else []


def settle_tie(diagnosis: Diagnosis | None, inst: Instrument, runs: Sequence[Run], *,
               labels: Sequence[str] | None = None, **fit_kw) -> Settlement | None:
    """Put a diagnosis's tie (:class:`nfs.diagnose.Diagnosis`) to the runs: fit each tied explanation and the model as it is
    (:func:`nfs.rivals.models.rival_models`) and decide every pair (:func:`decide`).

    One answer:

    - a rival that wins every pair it is in: ``add`` it, with its coefficients' 95 %
      intervals; ``nothing`` when it is the model as it is; ``unexplained`` when it is a
      change of structure (a rate term on every node, a structural alternative) rather
      than one effect;
    - otherwise a ``tie`` of the rivals no other beats, with the weakest pair's evidence.

    None when the diagnosis is no tie.

    ``labels``: the explanations to put to the runs instead of the tie's (the rivals a run
    was designed for, :func:`nfs.design.design_experiment`: after that run, the diagnosis
    may tie other candidates, but the question the run was made to answer is theirs); the
    diagnosis then need not be a tie.
    """
    check_fit_keywords(fit_kw, "settle_tie")
    if labels is None:
        labels = [] if diagnosis is None else tie_labels(diagnosis)
        if len(labels) < 2:
            return None
    labels = list(labels)
    put = labels + ([] if MODEL in labels else [MODEL])
    rivals = rival_models(inst, runs, put, **fit_kw)
    return settlement(rivals, decide(rivals, runs), diagnosis, labels)


def settlement(rivals: Sequence[Rival], decisions: Sequence[Decision],
               diagnosis: Diagnosis | None = None,
               labels: Sequence[str] | None = None) -> Settlement:
    """The one answer of the ``decisions`` between ``rivals`` (:func:`settle_tie`);
    ``labels``: the explanations asked about (the diagnosis's tie), for the words."""
    answer = None if diagnosis is None else diagnosis.answer
    labels = [r.label for r in rivals if r.label != MODEL] if labels is None else list(labels)
    # the rival that wins every pair it is in
    wins = [r for r in rivals
            if all(d.winner == r.label for d in decisions if r.label in (d.a, d.b))]
    if wins:
        return _settled(wins[0], rivals, decisions, diagnosis)
    beaten = {d.b if d.winner == d.a else d.a for d in decisions if d.winner is not None}
    standing = [r.label for r in rivals if r.label not in beaten] or [r.label for r in rivals]
    weakest = min((d for d in decisions if d.a in standing and d.b in standing),
                  key=lambda x: abs(x.evidence.z), default=decisions[0])
    out = [r.label for r in rivals if r.label in beaten]
    head = (answer.statement
            if answer is not None and answer.kind == "tie" and set(standing) == set(labels)
            else
            "these runs cannot tell apart: " + " and ".join(_words(x) for x in standing)
            + (f" ({', '.join(_words(x) for x in out)}: ruled out, another fits the runs "
               "better)" if out else ""))
    text = head + f"; put to the runs, {weakest.text}" + _rejected(rivals)
    return Settlement(Answer("tie", tuple(standing), text), tuple(decisions), tuple(rivals))


def _rejected(rivals: Sequence[Rival]) -> str:
    """What the runs asked of the rivals that is not physical, in words (empty: nothing)."""
    said = [f"{r.label}: {r.rejected}" for r in rivals if r.rejected]
    return "" if not said else " (" + "; ".join(said) + ")"


def _words(label: str) -> str:
    """A rival's label as the sentence says it."""
    return "the model as it is" if label == MODEL else label


def _settled(r: Rival, rivals: Sequence[Rival], decisions: Sequence[Decision],
             diagnosis: Diagnosis | None) -> Settlement:
    """The settlement won by ``r``: its answer, in words."""
    win = r.label
    others = ", ".join(_words(x.label) for x in rivals if x.label != win)
    mine = [d for d in decisions if win in (d.a, d.b)]
    weakest = min(mine, key=lambda x: abs(x.evidence.z))
    why = (f"the runs decide between it and {others} (weakest: likelihood ratio "
           f"e^{abs(weakest.evidence.adjusted):.1f} after the price of its numbers, Vuong's "
           f"Z {abs(weakest.evidence.z):.1f}; a decision needs e^{LAMBDA_NAME:g} and Z "
           f"{Z_NAME:.3g})")
    if win == MODEL:
        return Settlement(Answer("nothing", (), f"keep the model as it is: {why}"
                                 + _rejected(rivals)), tuple(decisions), tuple(rivals))
    spec = next((e.spec for e in r.instrument.effects if e.label == win), None)
    if spec is None or win == RATE_ALTERNATIVE:
        # a change of structure fits better than any one effect: what is missing is the
        # model's structure, not a library effect
        text = (f"no single effect: {win} ({r.description}) fits the runs better; "
                f"{why}: revise the model's structure rather than add one effect")
        return Settlement(Answer("unexplained", (win,), text), tuple(decisions),
                          tuple(rivals))
    channel = "drift_dph" if spec.kind == "gyro" else "temp_fog_c"
    factor = max(d.noise_factors.get(channel, 1.0) for d in decisions)
    interval = winner_interval(r, diagnosis, factor)
    coef = _interval_text(r, interval)
    text = f"add {win}" + (f" ({coef})" if coef else "") + f": {why}"
    return Settlement(Answer("add", (win,), text), tuple(decisions), tuple(rivals), interval)
