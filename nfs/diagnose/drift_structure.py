"""The drift's thermal structure against a generic alternative: a rate term on every node.

Shupe (1980, Appl. Opt. 19(5) 654): the non-reciprocal phase of a fiber coil is a weighted
integral over the fiber of the local temperature rate, Omega_S = sum over the coil of
w(l) dT(l)/dt.  A lumped model carries it as a few named terms (``shupe_rate`` on the coil,
``shupe_gradient`` on its radial difference, ``shupe_product``); a real coil's weighting
and its internal temperature field are never the model's, and even with node temperatures
consistent with the thermometers (:mod:`nfs.diagnose.smoother`) the part of the drift that
follows the temperature field with another weighting is left in the residual.  There it is
fitted by whatever candidate has a similar time course, typically a ``turn_on_transient``
(the rates are largest right after power-on) or a ``shupe_rate`` on some other node.

The generic alternative is the discretised Shupe integral itself: a rate term on every node,

    drift += sum_i k_i dT_i/dt        [deg/h; k_i in deg/h per K/min, dT_i/dt in K/min]

on the same node temperatures as the candidates.  Every drift candidate is also tested with
the alternative's columns in the model (Holm over the drift candidates).  One that stays
significant there has a direction of its own (an azimuth term, a scale factor, an auxiliary
channel): it is named plainly.  One that does not is *tied* with the alternative: the runs
cannot tell the named effect from a Shupe weighting the model lacks, and the verdict says so
beside the name.  The tie is not a rejection: right after power-on every node's rate decays
like a turn-on transient, so a genuine electronic transient is often tied too, even where
the model's structure is the unit's; only knowledge of the unit (a coil whose windings the
model lumps, a source whose warm-up is known) breaks it.  ``shupe_rate`` on any node lies in the
alternative's span: the message names the best of them as the first thing to try.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..docfields import document_fields
from .columns import PreparedRun
from ..fit.drift_residual import window_means
from ..scoring.run_stats import RunGrams, augmented_grams, clustered_fit, group_cv_rms

__all__ = ["DriftStructure", "rate_columns", "beyond_alternative"]

_S_PER_MIN = 60.0


@document_fields
@dataclass(frozen=True)
class DriftStructure:
    """The drift's thermal structure set against a rate term on every node."""

    nodes: tuple[str, ...]
    """The nodes of the alternative's rate terms."""
    cv_rms_model: float
    """Leave-one-start-temperature-out RMS of the drift window means, the model [deg/h]."""
    cv_rms_alternative: float
    """The same with a rate term on every node [deg/h]."""
    tied: tuple[str, ...] = ()
    """Candidates significant against the model alone but not beyond the alternative."""
    best_rate: str | None = None
    """The ``shupe_rate`` candidate of largest held-out drop (the first thing to try)."""

    @property
    def cv_drop(self) -> float:
        """Relative drop of the held-out RMS with the alternative."""
        return 1.0 - self.cv_rms_alternative / self.cv_rms_model

    @property
    def adequate(self) -> bool:
        """No significant candidate is tied with the alternative."""
        return not self.tied

    @property
    def message(self) -> str:
        """What fails and what to try, in one sentence."""
        if self.adequate:
            return (f"the drift's thermal structure holds (a rate term on every node drops "
                    f"the held-out RMS by {100 * self.cv_drop:.0f} % and no significant "
                    f"candidate is tied with it)")
        return self.tie_message(self.tied)

    def tie_message(self, labels: Sequence[str]) -> str:
        """The tie of the candidates ``labels`` with the alternative, in one sentence."""
        try_ = f" (try {self.best_rate} first)" if self.best_rate else ""
        # A transient at power-on is also what heat released inside the coil, where no
        # thermometer sits, makes of the gyro (a Shupe transient of the coil's own warming).
        heat = ("; a power-on transient is also the drift of heat released inside the coil "
                "that no thermometer sees (a heat_source at the coil)"
                if any(str(lb).startswith("turn_on_transient") for lb in labels) else "")
        return (", ".join(labels) + " tied with a rate term on every node (held-out RMS "
                f"-{100 * self.cv_drop:.0f} %): these runs cannot tell "
                + ("it" if len(labels) == 1 else "them")
                + " from a Shupe weighting the model lacks" + try_ + heat)

    def to_dict(self) -> dict[str, Any]:
        return {"alternative": "a rate term on every node", "nodes": list(self.nodes),
                "cv_rms_model": self.cv_rms_model,
                "cv_rms_alternative": self.cv_rms_alternative, "cv_drop": self.cv_drop,
                "adequate": self.adequate, "tied": list(self.tied),
                "best_rate": self.best_rate, "message": self.message}


def rate_columns(preps: Sequence[PreparedRun]) -> tuple[tuple[str, ...], list[np.ndarray]]:
    """(node names, per run the window means of every node's rate dT_i/dt [K/min])."""
    nodes = tuple(preps[0].ctx.node_names)
    return nodes, [np.column_stack([window_means(p.rd, _S_PER_MIN * p.ctx.rate_c_per_s[:, j])
                                    for j in range(len(nodes))]) for p in preps]


def beyond_alternative(base: RunGrams, ys: Sequence[np.ndarray], Xs: Sequence[np.ndarray],
                       grid: Sequence[tuple[dict[str, float], list[np.ndarray]]],
                       groups: np.ndarray, sign: int = 0) -> tuple[float, float]:
    """A candidate tested with the alternative in the model.

    ``base``: the Gram matrices of the model's and the alternative's columns ``Xs``;
    ``grid``: the candidate's columns at each grid point of its shapes.  Returns (p-value
    of its coefficients, Bonferroni over the grid points; held-out RMS with it, the grid
    point chosen in each fold)."""
    pm = Xs[0].shape[1]
    designs = [augmented_grams(base, ys, Xs, cols) for _, cols in grid]
    k = grid[0][1][0].shape[1]
    p = min(clustered_fit(g).test(list(range(pm, pm + k)), sign)[1] for g in designs)
    return min(1.0, len(designs) * p), group_cv_rms(designs, groups)[0]
