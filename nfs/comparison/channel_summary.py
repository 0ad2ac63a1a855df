"""One channel over all runs, and where the model fails on it, in words.

A channel whose pooled residual RMS is within :data:`CONSISTENT_RATIO` times its noise floor
(in every stage) is "consistent with noise".  Otherwise its failure is put into words from
three statistics:

- *when*: the fraction of the excess residual energy sum(r^2 - floor^2) in the first N minutes
  after power-on, pooled over the runs; "concentrated in the first N min" when at least half
  of it lies in a span of at most a third of the run;
- *T0*: the correlation over the runs of the excess RMS sqrt(max(rms^2 - floor^2, 0)) with
  |T0 - 25 C| and with T0 (needs 3 runs at 3 start temperatures);
- *positions*: the per-position biases of every run (:func:`nfs.comparison.channel_residual.
  position_test`); "follows the turntable positions" when the spread (RMS) of the
  per-position means is :data:`POSITION_RATIO` times their standard error or more, pooled
  over the runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..constants import T_REF_C
from .channel_residual import COMPARISON_STAGES, ChannelRun, ChannelSpec
from .heading import json_value

__all__ = ["CONSISTENT_RATIO", "POSITION_RATIO", "T0_CORRELATION", "T0_VARIATION",
           "EARLY_SPANS_MIN", "ChannelSummary", "summarise", "format_sig"]

#: A residual RMS up to this multiple of the noise floor is "consistent with noise".
CONSISTENT_RATIO = 1.5
#: Spread of the per-position biases, in standard errors, from which a residual "follows the
#: turntable positions" (about 1 under the null hypothesis).
POSITION_RATIO = 3.0
#: |correlation| over the runs from which a residual is said to scale with T0 ...
T0_CORRELATION = 0.8
#: ... provided the per-run excess RMS varies by at least this coefficient of variation.
T0_VARIATION = 0.3
#: Spans after power-on tried for "concentrated in the first N min" [min].
EARLY_SPANS_MIN = (5.0, 10.0, 15.0, 20.0, 30.0, 45.0, 60.0)


@dataclass(frozen=True)
class ChannelSummary:
    """One channel over all runs, and where it fails in words."""

    channel: str
    """Channel key."""
    unit: str
    """Unit of the residual."""
    stages: dict[str, tuple[float, float]]
    """Per stage: (pooled residual RMS, pooled noise floor) [channel unit]."""
    ratio: float
    """Pooled residual RMS / noise floor over the whole runs."""
    stage_ratios: dict[str, float]
    """Pooled residual RMS / noise floor per stage."""
    consistent: bool
    """Every stage's ratio <= CONSISTENT_RATIO."""
    early_fraction: dict[float, float]
    """Span N [min] -> fraction of the excess residual energy in the first N minutes."""
    early_span_min: float | None
    """The shortest span that holds half the excess energy, if it is early (else None)."""
    corr_abs_t0: float
    """Correlation over the runs of the excess RMS with |T0 - 25 C| (NaN if undefined)."""
    corr_t0: float
    """Correlation over the runs of the excess RMS with T0 (NaN if undefined)."""
    t0_variation: float
    """Coefficient of variation of the per-run excess RMS."""
    position_ratio: float
    """Pooled spread of the per-position biases / their standard error."""
    sentence: str
    """Where it fails, in words."""

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (NaN as null)."""
        return {"channel": self.channel, "unit": self.unit,
                "stages": {k: {"rms": json_value(r), "floor": json_value(f)}
                           for k, (r, f) in self.stages.items()},
                "ratio": json_value(self.ratio),
                "stage_ratios": {k: json_value(v) for k, v in self.stage_ratios.items()},
                "consistent": self.consistent,
                "early_fraction": {f"{k:g}": json_value(v) for k, v in self.early_fraction.items()},
                "early_span_min": json_value(self.early_span_min),
                "corr_abs_t0": json_value(self.corr_abs_t0), "corr_t0": json_value(self.corr_t0),
                "t0_variation": json_value(self.t0_variation),
                "position_ratio": json_value(self.position_ratio), "sentence": self.sentence}


def format_sig(v: float, digits: int = 3) -> str:
    """``v`` to ``digits`` significant digits, ``nan`` for None or a non-finite value."""
    return "nan" if v is None or not math.isfinite(v) else f"{v:.{digits}g}"


def _fmt_value(v: float, unit: str) -> str:
    """A value with its unit; specific forces in micro-g."""
    if unit == "g":
        return f"{format_sig(v * 1e6, 3)} ug"
    return f"{format_sig(v, 3)} {unit}"


def _corr(x: np.ndarray, y: np.ndarray) -> float:
    """Pearson correlation over the finite pairs (NaN: fewer than 3, or no spread)."""
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return math.nan
    return float(np.corrcoef(x, y)[0, 1])


_STAGE_WORDS = {"startup": "start-up stage", "stable": "stable stage", "all": "whole runs"}


def _ratio(rms: float, floor: float) -> float:
    """rms / floor (inf for a residual over a zero floor, 1 for none; NaN if undefined)."""
    if not (math.isfinite(rms) and math.isfinite(floor)):
        return math.nan
    return rms / floor if floor > 0 else (math.inf if rms > 0 else 1.0)


def _pooled_stages(runs: Sequence[ChannelRun]) -> dict[str, tuple[float, float]]:
    """Per stage: (residual RMS, noise floor) pooled over the runs' points [channel unit]."""
    stages = {}
    for s in COMPARISON_STAGES:
        num = sum(cr.stages[s].n * cr.stages[s].rms ** 2 for cr in runs if cr.stages[s].n)
        fl = sum(cr.stages[s].n * cr.stages[s].floor_rms ** 2 for cr in runs if cr.stages[s].n)
        n = sum(cr.stages[s].n for cr in runs)
        stages[s] = ((math.sqrt(num / n), math.sqrt(fl / n)) if n else (math.nan, math.nan))
    return stages


@dataclass(frozen=True)
class _Early:
    """When the excess residual energy lies, pooled over the runs."""

    fraction: dict[float, float]
    """Span N [min] -> fraction of the excess energy in the first N minutes."""
    span_min: float | None
    """The shortest span holding half of it, if at most a third of the run."""
    total: float
    """The excess energy sum(r^2 - floor^2) [channel unit^2]."""
    duration_s: float
    """The longest run's last point [s]."""


def _early_energy(runs: Sequence[ChannelRun]) -> _Early:
    """*when* (module docstring): the excess energy in the first N minutes after power-on."""
    duration = max((float(cr.time_s[-1]) for cr in runs if cr.time_s.size), default=0.0)
    total = sum(float(np.sum(cr.residual ** 2 - cr.floor_sq)) for cr in runs)
    early: dict[float, float] = {}
    span = None
    for n_min in EARLY_SPANS_MIN:
        part = sum(float(np.sum((cr.residual ** 2 - cr.floor_sq)[cr.time_s < 60.0 * n_min]))
                   for cr in runs)
        early[n_min] = float(np.clip(part / total, 0.0, 1.0)) if total > 0 else math.nan
        if (span is None and total > 0 and early[n_min] >= 0.5
                and 60.0 * n_min <= duration / 3.0):
            span = n_min
    return _Early(early, span, total, duration)


def _t0_scaling(runs: Sequence[ChannelRun]) -> tuple[float, float, float, np.ndarray]:
    """*T0* (module docstring): (correlation of the per-run excess RMS with |T0 - 25 C|,
    with T0, its coefficient of variation, the excess RMS of each run)."""
    t0 = np.array([cr.start_temperature_c for cr in runs], dtype=float)
    exc = np.array([math.sqrt(max(cr.stages["all"].rms ** 2 - cr.stages["all"].floor_rms ** 2,
                                  0.0)) for cr in runs])
    c_abs, c_t0 = _corr(np.abs(t0 - T_REF_C), exc), _corr(t0, exc)
    variation = float(np.std(exc) / np.mean(exc)) if np.mean(exc) > 0 else 0.0
    return c_abs, c_t0, variation, exc


def _position_spread(runs: Sequence[ChannelRun]) -> tuple[float, float]:
    """*positions* (module docstring): (pooled spread of the per-position biases / their
    standard error, the pooled spread [channel unit])."""
    spreads = np.array([cr.position_test.spread for cr in runs], dtype=float)
    uncs = np.array([cr.position_test.uncertainty for cr in runs], dtype=float)
    ok = np.isfinite(spreads) & np.isfinite(uncs) & (uncs > 0)
    pos_ratio = (float(np.sqrt(np.mean(spreads[ok] ** 2)) / np.sqrt(np.mean(uncs[ok] ** 2)))
                 if ok.any() else math.nan)
    pos_spread = float(np.sqrt(np.mean(spreads[ok] ** 2))) if ok.any() else math.nan
    return pos_ratio, pos_spread


def _t0_words(c_abs: float, c_t0: float, variation: float, n_runs: int) -> list[str]:
    """How the excess scales with T0, in words (empty: no correlation defined)."""
    if variation >= T0_VARIATION and math.isfinite(c_abs) and c_abs >= T0_CORRELATION \
            and c_abs >= abs(c_t0):
        return [f"growing with |T0 - 25 C| (correlation {c_abs:.2f} over {n_runs} runs)"]
    if variation >= T0_VARIATION and math.isfinite(c_t0) and abs(c_t0) >= T0_CORRELATION:
        return [f"{'growing' if c_t0 > 0 else 'falling'} with T0 (correlation "
                f"{c_t0:.2f} over {n_runs} runs)"]
    if variation >= T0_VARIATION and math.isfinite(c_abs) and c_abs <= -T0_CORRELATION:
        return [f"largest near 25 C (correlation with |T0 - 25 C| {c_abs:.2f} over "
                f"{n_runs} runs)"]
    if math.isfinite(c_abs):
        return [f"not scaling with T0 (correlation with |T0 - 25 C| {c_abs:.2f}, "
                f"with T0 {c_t0:.2f})"]
    return []


def summarise(spec: ChannelSpec, runs: Sequence[ChannelRun]) -> ChannelSummary:
    """Channel ``spec`` over its ``runs``: pooled RMS against the floor per stage, and where
    it fails in words (module docstring)."""
    stages = _pooled_stages(runs)
    rms, floor = stages["all"]
    ratios = {s: _ratio(*stages[s]) for s in COMPARISON_STAGES}
    ratio = ratios["all"]
    worst = max(("startup", "stable"), key=lambda s: ratios[s] if math.isfinite(ratios[s])
                else -1.0)
    consistent = bool(max(v for v in ratios.values() if math.isfinite(v)) <= CONSISTENT_RATIO
                      if any(math.isfinite(v) for v in ratios.values()) else True)
    early = _early_energy(runs)
    span = early.span_min
    c_abs, c_t0, variation, exc = _t0_scaling(runs)
    pos_ratio, pos_spread = _position_spread(runs)

    head = (f"{spec.label} ({spec.key}) residual {_fmt_value(rms, spec.unit)} RMS, "
            f"{ratio:.1f}x the noise floor ({_fmt_value(floor, spec.unit)})")
    if math.isfinite(ratios[worst]) and ratios[worst] > max(ratio, CONSISTENT_RATIO):
        head += (f"; {_STAGE_WORDS[worst]} {_fmt_value(stages[worst][0], spec.unit)} RMS, "
                 f"{ratios[worst]:.1f}x its floor")
    if consistent:
        sentence = head + ": consistent with noise."
    else:
        parts = []
        if span is not None:
            parts.append(f"concentrated in the first {span:g} min after power-on "
                         f"({100 * early.fraction[span]:.0f}% of the excess residual energy "
                         f"in {100 * 60 * span / early.duration_s:.0f}% of the time)")
        elif early.total > 0:
            last = EARLY_SPANS_MIN[-1]
            parts.append(f"spread over the run ({100 * early.fraction[last]:.0f}% of the "
                         f"excess residual energy in the first {last:g} min)")
        parts += _t0_words(c_abs, c_t0, variation, int(np.isfinite(exc).sum()))
        if math.isfinite(pos_ratio) and pos_ratio >= POSITION_RATIO:
            parts.append(f"following the turntable positions (per-position bias spread "
                         f"{_fmt_value(pos_spread, spec.unit)}, {pos_ratio:.1f}x its "
                         f"uncertainty)")
        elif math.isfinite(pos_ratio):
            parts.append(f"not following the turntable positions (per-position bias spread "
                         f"{pos_ratio:.1f}x its uncertainty)")
        sentence = head + ", " + ", ".join(parts) + "."
    return ChannelSummary(
        channel=spec.key, unit=spec.unit, stages=stages, ratio=float(ratio),
        stage_ratios=ratios,
        consistent=consistent, early_fraction=early.fraction, early_span_min=span,
        corr_abs_t0=c_abs, corr_t0=c_t0, t0_variation=variation, position_ratio=pos_ratio,
        sentence=sentence)
