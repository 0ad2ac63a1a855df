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

on the same node temperatures as the candidates.  A drift candidate is named only when it
is significant beyond this alternative (its coefficients tested with the alternative's
columns in the model, Holm over the drift candidates) and it still drops the held-out RMS
there: a candidate that only stands for a misweighted Shupe term is then not named, and the
verdict says that the drift's thermal structure is what fails.  A missing effect of another
kind (an azimuth term, a scale factor, an auxiliary channel, a T x dT product, an electronic
turn-on transient faster than the thermal rates) keeps its own direction and is named.
``shupe_rate`` on any node lies in the alternative's span: the structural message names the
best of them as the first thing to try.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .design import PreparedRun
from .fit import _block
from .stats import RunGrams, augmented_grams, clustered_fit, group_cv_rms

__all__ = ["DriftStructure", "rate_columns", "beyond_alternative"]

_S_PER_MIN = 60.0


@dataclass(frozen=True)
class DriftStructure:
    """The drift's thermal structure set against a rate term on every node."""

    nodes: tuple[str, ...]
    """The nodes of the alternative's rate terms."""
    cv_rms_model: float
    """Leave-one-start-temperature-out RMS of the drift window means, the model [deg/h]."""
    cv_rms_alternative: float
    """The same with a rate term on every node [deg/h]."""
    explained: tuple[str, ...] = ()
    """Candidates significant against the model alone but not beyond the alternative."""
    best_rate: str | None = None
    """The ``shupe_rate`` candidate of largest held-out drop (the first thing to try)."""

    @property
    def cv_drop(self) -> float:
        """Relative drop of the held-out RMS with the alternative."""
        return 1.0 - self.cv_rms_alternative / self.cv_rms_model

    @property
    def adequate(self) -> bool:
        """No candidate was significant only because the model's Shupe weighting is wrong."""
        return not self.explained

    @property
    def message(self) -> str:
        """What fails and what to try, in one sentence."""
        if self.adequate:
            return (f"the drift's thermal structure holds (a rate term on every node drops "
                    f"the held-out RMS by {100 * self.cv_drop:.0f} % and explains no "
                    f"significant candidate)")
        try_ = (f"; try {self.best_rate} or shupe_gradient between other nodes"
                if self.best_rate else "")
        return (f"the drift follows the node temperature rates with a weighting the model's "
                f"Shupe terms lack (a rate term on every node drops the held-out RMS by "
                f"{100 * self.cv_drop:.0f} %) and that explains "
                + ", ".join(self.explained) + try_
                + ", or refine the coil's thermal structure, before adding an effect")

    def to_dict(self) -> dict[str, Any]:
        return {"alternative": "a rate term on every node", "nodes": list(self.nodes),
                "cv_rms_model": self.cv_rms_model,
                "cv_rms_alternative": self.cv_rms_alternative, "cv_drop": self.cv_drop,
                "adequate": self.adequate, "explained": list(self.explained),
                "best_rate": self.best_rate, "message": self.message}


def rate_columns(preps: Sequence[PreparedRun]) -> tuple[tuple[str, ...], list[np.ndarray]]:
    """(node names, per run the window means of every node's rate dT_i/dt [K/min])."""
    nodes = tuple(preps[0].ctx.node_names)
    return nodes, [np.column_stack([_block(p.rd, _S_PER_MIN * p.ctx.rate_c_per_s[:, j])
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
