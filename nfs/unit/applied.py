"""What adding an effect to a unit's model did: the new model, its fit, before and after."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..docfields import document_fields
from ..fit.fit_result import FitResult
from ..instrument import Instrument
from ..io.records import from_record, to_record

__all__ = ["Applied", "APPLIED_SCHEMA"]

#: The JSON schema of :meth:`Applied.to_dict`.
APPLIED_SCHEMA = "nfs-applied/1"


@document_fields
@dataclass(frozen=True)
class Applied:
    """An effect added to the model and the model refitted (:meth:`nfs.UnitChain.apply`)."""

    label: str
    """The effect added: ``name`` or ``name:target``."""
    instrument: Instrument
    """The new model: the one before with the effect, every free number refitted."""
    fit: FitResult
    """The fit that made it (its errors, prior shifts and warnings)."""
    rms_before: dict[str, float]
    """Residual RMS per channel of the model before (thermometers [K], ``drift_dph``
    [deg/h], accelerometers [g])."""
    rms_after: dict[str, float]
    """The same with the effect added."""
    heading_rmse_before_deg: float
    """Start-up heading RMSE with the model before's compensation [deg]."""
    heading_rmse_after_deg: float
    """The same with the new model [deg]."""
    support: str = ""
    """What the diagnosis this followed found for the effect, in words (empty: none)."""
    supported: bool | None = None
    """Whether that diagnosis found it significant (None: not scored or no diagnosis)."""
    warnings: tuple[str, ...] = field(default_factory=tuple)
    """What the user should know: the effect added against its diagnosis, the fit's own."""

    def summary(self, source: str = "") -> str:
        """The change in a few lines: what was added (and, with ``source``, which
        diagnosis said so), each channel's RMS and the heading."""
        said = f"{source}: {self.support}" if source and self.support else self.support
        lines = [f"added {self.label}" + (f" ({said})" if said else "") + "; refitted:",
                 self.fit.summary()]
        for ch, after in self.rms_after.items():
            before = self.rms_before.get(ch, math.nan)
            lines.append(f"- {ch}: residual RMS {before:.4g} -> {after:.4g}")
        lines.append(f"- start-up heading RMSE {self.heading_rmse_before_deg:.4f} -> "
                     f"{self.heading_rmse_after_deg:.4f} deg")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """Every field as JSON-ready data (:mod:`nfs.io.records`; schema
        :data:`APPLIED_SCHEMA`)."""
        return to_record(self, APPLIED_SCHEMA)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Applied":
        """The result :meth:`to_dict` wrote."""
        return from_record(cls, data, APPLIED_SCHEMA)
