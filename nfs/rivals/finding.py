"""A diagnosis and the settlement of its tie, as one finding with one answer.

``nfs diagnose --decide`` (and :meth:`nfs.UnitChain.diagnose` with ``decide=True``) puts a
tie to the runs (:func:`nfs.rivals.decide.settle_tie`).  What an engineer acts on is then one
answer: the settlement's when there is one, else the diagnosis's; the diagnosis's own tie is
kept beside it (``tie``), since the run that would break it is designed for those rivals.
:class:`Finding` is that document: what ``nfs diagnose --json`` writes and what
``nfs diagnose --apply --diagnosis`` and ``nfs design --diagnosis`` read.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from ..diagnose.result import Answer, Diagnosis
from ..errors import NfsError
from ..io.records import RecordError, decode, encode
from .decide import Settlement
from .models import MODEL

__all__ = ["Finding", "FINDING_SCHEMA", "rivals_from_diagnosis", "rivals_of"]

#: The JSON schema of :meth:`Finding.to_dict`.
FINDING_SCHEMA = "nfs-finding/1"


@dataclass(frozen=True)
class Finding:
    """A diagnosis with the settlement of its tie (None: not put to the runs)."""

    #: Properties written beside the fields (:mod:`nfs.io.records`): the one answer in words.
    DERIVED = ("answer", "verdict", "tie")

    diagnosis: Diagnosis
    """The ranked candidates, the structure checks and the diagnosis's own answer."""
    settlement: Settlement | None = None
    """The tie (or the rivals a user named) put to the runs; None when not asked or when
    the diagnosis was no tie."""
    provenance: dict[str, Any] | None = None
    """Model, runs and seeds that reproduce it (what the command line adds)."""

    @property
    def answer(self) -> Answer:
        """The one answer: the settlement's when the tie was put to the runs."""
        return self.diagnosis.answer if self.settlement is None else self.settlement.answer

    @property
    def verdict(self) -> str:
        """The one answer in one sentence."""
        return self.answer.text

    @property
    def tie(self) -> Answer | None:
        """The diagnosis's own tie when a settlement answered it (None otherwise)."""
        return None if self.settlement is None else self.diagnosis.answer

    def rivals(self) -> list[str]:
        """The explanations these runs could not tell apart (:func:`rivals_from_diagnosis`)."""
        return rivals_from_diagnosis(self)

    def support_for(self, effect: str, target: str | None = None
                    ) -> tuple[bool | None, str]:
        """What the diagnosis found for one candidate (:meth:`Diagnosis.support_for`)."""
        return self.diagnosis.support_for(effect, target)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready data (:mod:`nfs.io.records`; schema :data:`FINDING_SCHEMA`): the
        diagnosis's fields at the top (``ranking``, ``not_tried``, ``unexplained``, ...), then
        ``settlement`` and ``provenance``, and the one answer: ``answer``, ``verdict`` and,
        when a settlement answered a tie, the diagnosis's own ``tie``."""
        return {"schema": FINDING_SCHEMA, **encode(self.diagnosis),
                "settlement": encode(self.settlement), "provenance": encode(self.provenance),
                "answer": encode(self.answer), "verdict": self.verdict,
                "tie": encode(self.tie)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Finding":
        """The finding :meth:`to_dict` wrote (``nfs diagnose --json``)."""
        if not isinstance(data, dict):
            raise RecordError("expected a JSON object written by nfs diagnose --json")
        if data.get("schema", FINDING_SCHEMA) != FINDING_SCHEMA:
            raise RecordError(f"schema {data.get('schema')!r}, expected {FINDING_SCHEMA!r}")
        fields = {f.name for f in dataclasses.fields(Diagnosis)}
        diagnosis = decode({k: v for k, v in data.items() if k in fields}, Diagnosis,
                           "diagnosis")
        return cls(diagnosis, decode(data.get("settlement"), Settlement | None, "settlement"),
                   data.get("provenance"))


def rivals_from_diagnosis(found: Finding | Diagnosis) -> list[str]:
    """The labels a diagnosis could not tell apart.

    A tie gives its explanations (when the tie was put to the runs and it stands, the
    rivals it left standing; when the runs decided it, the diagnosis's own tie, the question
    a designed run would answer); an answer that names one effect gives that effect against
    the model as given (is the effect there at all?).  Anything else has nothing to decide:
    :class:`~nfs.errors.NfsError` saying so.
    """
    return rivals_of(found.answer, found.tie if isinstance(found, Finding) else None)


def rivals_of(answer: Answer, tie: Answer | None = None) -> list[str]:
    """The rivals an ``answer`` leaves to decide (:func:`rivals_from_diagnosis`); ``tie``:
    the diagnosis's own tie when the answer is a settlement's."""
    if answer.kind != "tie" and tie is not None:
        answer = tie
    labels = list(answer.labels)
    if answer.kind == "tie" and len(labels) >= 2:
        return labels
    if answer.kind == "add" and labels:
        return [MODEL, labels[0]]
    raise NfsError(f"the diagnosis ({answer.kind}) leaves no tie to decide: "
                   f"{answer.text}".rstrip(": ") + "; name the rivals with --rivals A B")
