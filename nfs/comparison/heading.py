"""The heading's own verdict: measured against predicted heading RMSE over the runs.

A model can be within the noise on the drift channel in RMS and still miss what the north
finder sees: a bias that follows the turntable positions does not cancel in a cycle, and a
small one is diluted in the drift's RMS.  So :func:`nfs.comparison.compare_runs.compare` sets the
measured heading RMSE of every run beside the model's and gives the heading a verdict of its
own (:func:`heading_comparison`), with an interval from the run-to-run scatter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from scipy.stats import t as student_t

from ..docfields import document_fields
from ..scoring.intervals import holm

__all__ = ["HEADING_ALPHA", "RunHeading", "HeadingComparison", "heading_comparison",
           "json_value"]

#: Family-wise level of the heading's verdict (two stages, Holm).
HEADING_ALPHA = 0.05


def json_value(v):
    """``v`` for JSON: NaN and infinities as None, NumPy numbers as Python ones."""
    if v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, (int, np.integer)):
        return int(v)
    try:
        f = float(v)
    except (TypeError, ValueError):
        return v
    return f if math.isfinite(f) else None



@dataclass(frozen=True)
class RunHeading:
    """Heading RMSE of a run, measured and as the model predicts it [deg]."""

    run_name: str
    """Name of the run."""
    start_temperature_c: float
    """T0 [degC]."""
    measured_startup_deg: float
    """North-finding the measured run, start-up cycles."""
    measured_stable_deg: float
    """... stable cycles."""
    model_startup_deg: float
    """North-finding the model's run, start-up cycles."""
    model_stable_deg: float
    """... stable cycles."""

    def to_dict(self) -> dict[str, Any]:
        return {k: json_value(v) for k, v in vars(self).items()}


@document_fields
@dataclass(frozen=True)
class HeadingComparison:
    """Measured against predicted heading RMSE over the runs, per stage.

    Per run r and stage, L_r = ln(measured RMSE / model RMSE), the model being one noisy
    simulation of the run (so that, if the model is right, L_r is symmetric about 0); over
    the runs the mean of L with a t interval from the run-to-run scatter (n - 1 degrees of
    freedom), the two stages' tests Holm-adjusted together.  ``ratio`` = exp(mean L).
    """

    ratio: dict[str, float]
    """Stage (``startup``, ``stable``) -> geometric mean of measured / model over the runs."""
    interval: dict[str, tuple[float, float]]
    """Stage -> 95 % t interval of that ratio."""
    p_value: dict[str, float]
    """Stage -> Holm-adjusted p-value of "the ratio is 1" (t test on L, two-sided)."""
    n_runs: dict[str, int]
    """Stage -> runs with a finite RMSE in both."""
    consistent: bool
    """No stage's ratio differs from 1 at ``alpha`` after Holm (also True with < 2 runs)."""
    alpha: float = HEADING_ALPHA
    """Family-wise level of the verdict."""

    def sentence(self, drift_consistent: bool | None = None,
                 drift_positions: bool = False) -> str:
        """The verdict in words; when the drift channel is within noise while the heading is
        not, what that means."""
        parts = []
        for st, word in (("startup", "start-up"), ("stable", "stable")):
            if self.n_runs.get(st, 0) >= 2 and math.isfinite(self.ratio[st]):
                lo, hi = self.interval[st]
                parts.append(f"{word} measured/model {self.ratio[st]:.2f}x [{lo:.2f}, {hi:.2f}]"
                             f" (p {self.p_value[st]:.2g})")
        if not parts:
            return "heading: fewer than 2 runs with a heading RMSE: no verdict"
        text = "heading RMSE " + ", ".join(parts)
        if self.consistent:
            return text + ": consistent with the model."
        worse = [st for st in self.ratio if self.p_value.get(st, 1.0) <= self.alpha]
        more = all(self.ratio[st] > 1.0 for st in worse)
        text += (": the model " + ("underestimates" if more else "overestimates")
                 + " the heading error")
        if drift_consistent:
            text += (": the gyro drift residual is within its noise floor in RMS, but the "
                     "north finder sees all of what the model misses "
                     + ("in the part of the drift that follows the turntable positions "
                        "(see the drift channel's per-position biases)" if drift_positions
                        else "within each cycle, where a small bias that changes from one "
                        "dwell to the next does not cancel")
                     + ", so the heading shows it first")
        return text + "."

    def to_dict(self) -> dict[str, Any]:
        return {"consistent": self.consistent, "alpha": self.alpha,
                "ratio": {k: json_value(v) for k, v in self.ratio.items()},
                "interval": {k: [json_value(a), json_value(b)] for k, (a, b) in self.interval.items()},
                "p_value": {k: json_value(v) for k, v in self.p_value.items()},
                "n_runs": dict(self.n_runs)}


def heading_comparison(headings: Sequence["RunHeading"], alpha: float = 0.05
                       ) -> HeadingComparison:
    """:class:`HeadingComparison` of per-run heading RMSEs."""
    ratio, interval, raw, n_runs = {}, {}, {}, {}
    for st in ("startup", "stable"):
        m = np.array([getattr(h, f"measured_{st}_deg") for h in headings], dtype=float)
        p = np.array([getattr(h, f"model_{st}_deg") for h in headings], dtype=float)
        ok = np.isfinite(m) & np.isfinite(p) & (m > 0) & (p > 0)
        x = np.log(m[ok] / p[ok])
        n_runs[st] = int(x.size)
        if x.size < 2:
            ratio[st], interval[st], raw[st] = math.nan, (math.nan, math.nan), 1.0
            continue
        mean = float(np.mean(x))
        se = float(np.std(x, ddof=1) / math.sqrt(x.size))
        q = float(student_t.ppf(0.975, x.size - 1))
        ratio[st] = math.exp(mean)
        interval[st] = (math.exp(mean - q * se), math.exp(mean + q * se))
        raw[st] = (float(2 * student_t.sf(abs(mean) / se, x.size - 1)) if se > 0
                   else (0.0 if mean else 1.0))
    stages = list(raw)
    adj = holm([raw[st] for st in stages])
    p_value = {st: float(a) for st, a in zip(stages, adj)}
    consistent = all(p_value[st] > alpha for st in stages)
    return HeadingComparison(ratio=ratio, interval=interval, p_value=p_value,
                             n_runs=n_runs, consistent=consistent, alpha=alpha)


