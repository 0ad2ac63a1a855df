"""What :func:`nfs.diagnose.diagnose` returns: the scored candidates and the verdict."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..docfields import document_fields
from ..io.records import encode, from_record, to_record
from ..fit.adequacy import ThermalAdequacy
from .candidates import Candidate
from .drift_structure import DriftStructure
from ..fit.fit_result import FitResult

__all__ = ["ANSWER_KINDS", "Answer", "CandidateScore", "Diagnosis", "candidate_finding",
           "label_of", "DIAGNOSIS_SCHEMA", "DESIGN_ADVICE"]

#: The JSON schema of :meth:`Diagnosis.to_dict`.
DIAGNOSIS_SCHEMA = "nfs-diagnosis/1"

#: What a tie's answer advises: the run that would break it.
DESIGN_ADVICE = "a run that would tell them apart: nfs design"

#: The kinds of :class:`Answer`, one per diagnosis.
ANSWER_KINDS = ("add", "tie", "nothing", "unexplained", "undetermined")


@document_fields
@dataclass(frozen=True)
class Answer:
    """The one thing a diagnosis tells an engineer to do."""

    kind: str
    """``add``: add the one effect in ``labels``; ``tie``: these runs cannot tell the
    explanations in ``labels`` apart (a run that would: ``nfs design``); ``nothing``: the
    residual is noise, nothing beyond it; ``unexplained``: the residual is not noise but no
    library effect explains it; ``undetermined``: these runs cannot determine it (``text``
    says why)."""
    labels: tuple[str, ...]
    """Effect labels (``name`` or ``name:target``) or structural alternatives' names."""
    text: str
    """One sentence in words."""
    reason: str = ""
    """The finding alone, without the advice that follows it in ``text`` (a tie's "these
    runs cannot tell apart: ..." without "a run that would ...: nfs design"); empty when
    ``text`` is all finding."""

    @property
    def statement(self) -> str:
        """What the runs say, without the advice (``reason``, else ``text``)."""
        return self.reason or self.text

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "labels": list(self.labels), "text": self.text,
                "reason": self.reason}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Answer":
        """The answer :meth:`to_dict` wrote."""
        return cls(str(data["kind"]), tuple(data.get("labels") or ()), str(data["text"]),
                   str(data.get("reason") or ""))


#: The drift's generic structural alternative (:mod:`nfs.diagnose.drift_structure`).
RATE_ALTERNATIVE = "a rate term on every node"


def _coef(s: "CandidateScore") -> str:
    """Each coefficient with its 95 % interval."""
    return ", ".join(f"{k} = {v:.3g} [{s.interval[k][0]:.3g}, {s.interval[k][1]:.3g}]"
                     for k, v in s.coefficient.items() if k in s.interval)


def label_of(effect: str, target: str | None) -> str:
    """``effect`` or ``effect:target``."""
    return effect if target is None else f"{effect}:{target}"


@document_fields
@dataclass(frozen=True)
class CandidateScore:
    """What one candidate explains."""

    #: Properties written beside the fields (:mod:`nfs.io.records`).
    DERIVED = ("cv_drop",)

    effect: str
    """Registry name."""
    target: str | None
    """Target (node, axis, channel) or None."""
    significant: bool
    """Holm rejects "every coefficient is 0" at the family-wise alpha AND the CV RMS drops."""
    cv_rms_before: float
    """Leave-one-start-temperature-out RMS of the held-out residual, model alone (drift
    window means [deg/h] or thermometers [K], see ``channel``)."""
    cv_rms_after: float
    """The same with the candidate (its shape chosen on each fold's training runs)."""
    correlation: float
    """Partial correlation of the baseline residual with the candidate's signature."""
    coefficient: dict[str, float]
    """Fitted candidate parameters (coefficients and shapes)."""
    interval: dict[str, tuple[float, float]]
    """95 % t intervals from the CR2 covariance clustered by run."""
    wald_p: float
    """p-value of the clustered Wald test that every coefficient is 0, Bonferroni over the
    ``n_grid`` shape grid points it was chosen from."""
    holm_p: float
    """``wald_p`` adjusted by Holm's step-down over all scored candidates."""
    dof: float
    """Denominator degrees of freedom of the test (run level, at most runs - 1)."""
    n_grid: int
    """Grid points of the shape parameters the test paid for (1: no shape)."""
    inclusion_frequency: float
    """Fraction of run resamples where the CV RMS drops and the clustered test rejects at
    alpha (descriptive)."""
    heading_rmse_before_deg: float | None = None
    """Start-up heading RMSE with the baseline model's compensation [deg] (None: not run)."""
    heading_rmse_after_deg: float | None = None
    """The same with the candidate added [deg]."""
    explained_by: str | None = None
    """Label of the top significant candidate when that one explains this one too (its CV
    drop over the model plus the top candidate is below :data:`nfs.diagnose.ranking.CV_DROP`)."""
    channel: str = "drift_dph"
    """Residual the CV RMS is taken on: ``drift_dph`` (window means, deg/h), ``acc_x_g`` /
    ``acc_y_g`` (an accelerometer's window means, g) or ``thermometers`` (the three
    thermometers at the knots, K)."""
    beyond_structure_p: float | None = None
    """A drift candidate's p-value with a rate term on every node in the model, Holm over the
    drift candidates (:mod:`nfs.diagnose.drift_structure`); above alpha the candidate is
    tied with that alternative; None when not checked."""
    structure_tie: str | None = None
    """A thermal candidate significant against the model that does not beat this structural
    alternative pooled and run by run (:func:`nfs.fit.adequacy.structure_rival`): the
    runs cannot tell the two apart, and the candidate is not significant; None otherwise."""
    physical: bool = True
    """False when a coefficient lies below its physical bound (a negative heat power or
    lag, :func:`nfs.fit.structure.physical_lower`): never ranked above a physical one."""
    sign_rejected_p: float | None = None
    """For a coefficient physics keeps on one side (a heat power,
    :data:`nfs.diagnose.candidate_score.ONE_SIDED`): the p-value of the same clustered test
    toward the other side, Bonferroni over the shape grid.  Small: the runs ask for what
    the effect cannot give (heat taken away: a sink, which no heat source is), and the
    diagnosis says so; None for a two-sided coefficient."""

    @property
    def cv_drop(self) -> float:
        """Relative drop of the CV RMS."""
        return 1.0 - self.cv_rms_after / self.cv_rms_before

    def to_dict(self) -> dict[str, Any]:
        """Every field, and the CV drop, as JSON-ready data (:mod:`nfs.io.records`)."""
        return encode(self)


@document_fields
@dataclass(frozen=True)
class Diagnosis:
    """The ranked candidates and what is left unexplained."""

    #: Properties written beside the fields (:mod:`nfs.io.records`): the one answer in words.
    DERIVED = ("answer", "verdict")

    ranking: tuple[CandidateScore, ...]
    """Scored candidates: significant thermometer ones first, then the other significant
    ones, then the rest, unphysical ones last; within each group by relative CV drop."""
    not_tried: tuple[Candidate, ...]
    """Candidates not scored, each with its reason."""
    unexplained: dict[str, Any]
    """Ljung-Box test of the baseline residual and its cross-correlation with every channel."""
    baseline: FitResult | None
    """The model's own drift refit (:func:`~nfs.fit.calibration.fit_model`, drift stage); None
    when the diagnosis failed."""
    time_s: float
    """Wall time [s]."""
    alpha: float = 0.05
    """Family-wise error rate of the significance rule."""
    thermal_structure: ThermalAdequacy | None = None
    """Does the model's thermal structure fit the thermometers (per thermometer and stage,
    against its noise floor), and the generic structural alternatives it was set against
    (:func:`nfs.fit.adequacy.thermal_adequacy`); None when not checked."""
    node_temperatures: dict[str, Any] | None = None
    """Where the drift candidates' node temperatures came from (``source``: ``smoothed`` or
    ``model``) and, smoothed, the unmodelled-heat scale q [W^2/s], whether it is
    significant (the thermometers need heat the network does not give) and the thermometer
    residual RMS of the smoothed states [K]."""
    drift_structure: DriftStructure | None = None
    """The drift's thermal structure against a rate term on every node, and the significant
    drift candidates tied with it (:mod:`nfs.diagnose.drift_structure`); None when not
    checked."""
    failure: str | None = None
    """Why these runs cannot determine the answer (an ill-conditioned fit), or None."""
    coil_nodes: tuple[str, ...] = ()
    """The model's coil nodes (outer, inner): where heat that no thermometer sees would
    give the gyro a turn-on transient."""

    @property
    def significant(self) -> list[CandidateScore]:
        return [s for s in self.ranking if s.significant]

    @property
    def answer(self) -> Answer:
        """The one answer (:class:`Answer`): add the top significant candidate that no other
        explains; or a tie when that candidate does not stand beyond a rate term on every
        node, or when a thermal candidate fits the thermometers no better than a change of
        structure; or nothing beyond noise; or a residual no library effect explains; or
        that these runs cannot determine it."""
        if self.failure:
            return Answer("undetermined", (),
                          f"cannot be determined from these runs: {self.failure}")
        own = [s for s in self.significant if s.explained_by is None]
        ds = self.drift_structure
        if own:
            top = own[0]
            lab = label_of(top.effect, top.target)
            if ds is not None and lab in ds.tied:
                heat = (f"heat_source:{self.coil_nodes[-1]}"
                        if top.effect == "turn_on_transient" and self.coil_nodes else None)
                also = ("" if heat is None else
                        f", nor from heat released inside the coil ({heat}), where no "
                        "thermometer sits")
                return _tie((lab, RATE_ALTERNATIVE) + ((heat,) if heat else ()),
                            f"these runs cannot tell apart: {lab} ({_coef(top)}; Holm p "
                            f"{top.holm_p:.2g} against the model) and {RATE_ALTERNATIVE} "
                            f"(p beyond it {top.beyond_structure_p:.2g}){also}: right "
                            "after power-on every node's rate decays like a transient")
            if top.effect == "turn_on_transient" and self.coil_nodes:
                heat = f"heat_source:{self.coil_nodes[-1]}"
                return _tie((lab, heat),
                            f"these runs cannot tell apart: {lab} ({_coef(top)}; Holm p "
                            f"{top.holm_p:.2g}) and heat released inside the coil "
                            f"({heat}), where no thermometer sits: both give the gyro the "
                            "same decay after power-on at every start temperature, so no "
                            "soak-and-start run separates them",
                            "a run that would (a power cycle): nfs design")
            text = (f"add {lab} ({_coef(top)}; Holm p {top.holm_p:.2g}, CV RMS "
                    f"-{100 * top.cv_drop:.0f} % on {top.channel})")
            if len(own) > 1:
                text += ("; then diagnose again (also significant on their own: "
                         + ", ".join(label_of(s.effect, s.target) for s in own[1:]) + ")")
            return Answer("add", (lab,), text)
        ties = [s for s in self.ranking if s.structure_tie]
        if ties:
            s = ties[0]
            lab = label_of(s.effect, s.target)
            return _tie((lab, s.structure_tie),
                        f"these runs cannot tell apart: {lab} ({_coef(s)}; Holm p "
                        f"{s.holm_p:.2g} against the model) and {s.structure_tie}, which "
                        "fits the thermometers as well run by run")
        why = self._not_noise()
        if not why:
            return Answer("nothing", (), "nothing beyond noise: no candidate is significant, "
                                         "the drift residual is consistent with the gyro "
                                         "noise model and the thermal structure fits")
        return Answer("unexplained", (), "no library effect explains what is left: "
                      + "; ".join(why) + " (see 'unexplained' for the channels it follows)")

    def _not_noise(self) -> list[str]:
        """What says the residual is more than noise, in words (empty: nothing)."""
        out = []
        lb = (self.unexplained or {}).get("ljung_box") or {}
        if lb and lb.get("consistent") is False:
            out.append(f"the drift residual is not the gyro noise (Ljung-Box p "
                       f"{lb.get('p_value', float('nan')):.2g}, variance ratio "
                       f"{lb.get('variance_ratio', float('nan')):.3g})")
        ts = self.thermal_structure
        if ts is not None and not ts.adequate:
            out.append("thermal structure: " + ts.message)
        out += self._sinks()
        return out

    def _sinks(self) -> list[str]:
        """One-sided candidates whose other side the runs ask for, Bonferroni over the
        ranking (:attr:`CandidateScore.sign_rejected_p`), in words."""
        n = max(len(self.ranking), 1)
        out = []
        for s in self.ranking:
            if s.sign_rejected_p is not None and s.sign_rejected_p < self.alpha / n:
                lab = label_of(s.effect, s.target)
                out.append(f"the runs ask for {lab} with {_coef(s)} (p {s.sign_rejected_p:.2g} "
                           "for that sign): heat taken away, which no heat source gives; a "
                           "heat path or a structure the model lacks")
        return out

    @property
    def verdict(self) -> str:
        """The answer in one sentence (:attr:`answer`)."""
        return self.answer.text

    def support_for(self, effect: str, target: str | None = None
                    ) -> tuple[bool | None, str]:
        """What this diagnosis found for one candidate: (significant, a sentence);
        significant is None when it was not scored (:func:`candidate_finding`)."""
        return candidate_finding(self, effect, target)

    def to_dict(self) -> dict[str, Any]:
        """Every field as JSON-ready data, with the answer and verdict beside them
        (:mod:`nfs.io.records`; schema :data:`DIAGNOSIS_SCHEMA`)."""
        return to_record(self, DIAGNOSIS_SCHEMA)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Diagnosis":
        """The diagnosis :meth:`to_dict` wrote (``nfs diagnose --json``); its answer is
        recomputed from the fields."""
        return from_record(cls, data, DIAGNOSIS_SCHEMA)


def _tie(labels: tuple[str, ...], reason: str, advice: str = DESIGN_ADVICE) -> Answer:
    """A tie: the finding, then the advice of the run that would break it."""
    return Answer("tie", labels, f"{reason}; {advice}", reason)


def candidate_finding(diagnosis: Diagnosis, effect: str, target: str | None
                      ) -> tuple[bool | None, str]:
    """What a diagnosis found for one candidate: (significant, a sentence).

    ``significant`` is None when the candidate was not scored (the sentence gives the
    reason, or says that the diagnosis did not consider it).
    """
    label = effect + (f":{target}" if target else "")
    ranking = diagnosis.ranking
    for rank, row in enumerate(ranking, 1):
        if row.effect == effect and row.target == target:
            sig = bool(row.significant)
            what = "significant" if sig else "not significant"
            extra = f"; explained by {row.explained_by}" if row.explained_by else ""
            bs = row.beyond_structure_p
            if sig and bs is not None and bs > diagnosis.alpha:
                extra += f"; tied with a rate term on every node (p beyond it {bs:.2g})"
            return sig, (f"'{label}' is {what} (Holm p = {row.holm_p:.2g}, CV RMS "
                         f"{row.cv_rms_before:.4g} -> {row.cv_rms_after:.4g} "
                         f"{_unit(row.channel)}, rank {rank} of {len(ranking)}{extra})")
    for c in diagnosis.not_tried:
        if c.effect == effect and c.target == target:
            return None, f"'{label}' was not scored: {c.reason}"
    return None, f"'{label}' was not among the candidates the diagnosis scored"


def _unit(channel: str | None) -> str:
    return {"drift_dph": "deg/h", "acc_x_g": "g", "acc_y_g": "g", "thermometers": "K"}.get(
        channel or "", "")
