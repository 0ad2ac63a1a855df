"""The cheapest run that tells every pair of rivals apart.

For every experiment of the grid (:class:`nfs.design.space.Space`) each rival predicts the
run at its fitted parameters and at ``n_draws`` draws of them
(:mod:`nfs.rivals.predict`), and every pair's separation (:mod:`nfs.rivals.separation`)
is computed on every prefix of the record (a run of length T is the first T of a longer
one): the experiment's cost is the chamber hours of the shortest prefix on which the
*worst* pair reaches the margin.  The cheapest experiment of the grid is then refined
locally: its continuous knobs (T0 within the runs' range, the off time of a power cycle,
the time of the event, the size of a ramp) are moved half a grid step each way, the
turntable's dwell and a ramp's rate halved and doubled, for two rounds, and a neighbour replaces it when it is cheaper (or as cheap and more separating).
When no experiment reaches the margin, the design says so and proposes the one that
separates the worst pair best at the longest record.

``current_separation`` scores the runs already taken the same way (each rival replaying
them from its own start states): a tie there is what the design exists to break.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from itertools import combinations
from typing import Callable, Sequence

import numpy as np

from ..errors import NfsError
from ..conditions import RunConditions
from ..ranges import TEMPERATURE_RANGE_C, find
from ..io.records import RecordError, encode, from_record
from ..run import Run
from ..rivals.noise_level import scaled
from ..rivals.predict import PREDICT_STEP_S, noise_sigma
from ..rivals.replay import predict_rival, replay_runs_taken
from ..rivals.models import Rival
from ..rivals.separation import MARGIN_SIGMA, RivalPrediction, Separation, separation
from .space import Experiment, Space, base_conditions, default_space

__all__ = ["Design", "Trial", "design_experiment", "current_separation",
           "N_DRAWS", "DESIGN_SCHEMA"]

#: The JSON schema of :meth:`Design.to_dict`.
DESIGN_SCHEMA = "nfs-design/1"

#: Parameter draws per rival and experiment.
N_DRAWS = 8


@dataclass(frozen=True)
class Trial:
    """One experiment tried: the shortest record that reaches the margin, if any."""

    experiment: Experiment
    """At the duration found (or the longest tried)."""
    worst_sigma: float
    """Separation of the worst pair at that duration [noise standard deviations]."""
    met: bool
    """The worst pair reached the margin."""
    stage: str = "grid"
    """``grid`` or ``refine``."""


@dataclass(frozen=True)
class Design:
    """The proposed run and what it decides."""

    rivals: tuple[Rival, ...]
    """The rivals, in order."""
    experiment: Experiment
    """The proposed run."""
    proposed: dict[tuple[int, int], Separation]
    """Separation of every pair (i, j) on the proposed run."""
    current: dict[tuple[int, int], Separation]
    """Separation of every pair on the runs already taken."""
    margin_sigma: float
    """The margin asked for [noise standard deviations]."""
    noise_factors: dict[str, float]
    """The factor each channel's sensor noise is raised by, from the runs taken
    (:mod:`nfs.rivals.noise_level`)."""
    open_pairs: tuple[tuple[int, int], ...]
    """The pairs the run had to separate: those the runs taken leave below the margin
    (every pair when the runs taken separate them all)."""
    met: bool
    """Every pair reaches the margin on the proposed run."""
    trials: tuple[Trial, ...]
    """Every experiment tried, grid and refinement."""
    predictions: dict[str, RivalPrediction] = field(default_factory=dict, repr=False,
                                                    metadata={"record": False})
    """Each rival's prediction of the proposed run (label -> prediction), for the figure."""
    sigma: dict[str, np.ndarray] = field(default_factory=dict, repr=False,
                                         metadata={"record": False})
    """The noise of the proposed run's numbers, by channel."""
    time_s: float = 0.0
    """Wall time of the search [s]."""

    def pair_label(self, ij: tuple[int, int]) -> str:
        i, j = ij
        return f"{self.rivals[i].label} vs {self.rivals[j].label}"

    @property
    def decided_already(self) -> bool:
        """The runs taken separate every pair by the margin already."""
        return all(v.sigma >= self.margin_sigma for v in self.current.values())

    @property
    def verdict(self) -> str:
        """One sentence an engineer acts on."""
        worst = min(self.proposed[k].sigma for k in self.open_pairs)
        now = min(self.current[k].sigma for k in self.open_pairs)
        e = self.experiment
        which = ("every pair of rivals" if len(self.open_pairs) == len(self.proposed) else
                 ", ".join(self.pair_label(k) for k in self.open_pairs))
        if self.decided_already:
            return (f"the runs taken separate every pair of rivals by {now:.1f} noise "
                    f"standard deviations or more, beyond the {self.margin_sigma:g}-sigma "
                    "margin: no run is needed (nfs diagnose decides between them); a run "
                    f"that would on its own ({e.hours:.1f} chamber hours): {e.describe()}")
        if self.met:
            return (f"run this ({e.hours:.1f} chamber hours): {e.describe()}; it separates "
                    f"{which} by at least {worst:.1f} noise standard deviations "
                    f"(the runs taken: {now:.1f}), beyond the {self.margin_sigma:g}-sigma "
                    "margin")
        return (f"no run in the searched space separates every pair by "
                f"{self.margin_sigma:g} sigma; the best ({e.hours:.1f} chamber hours: "
                f"{e.describe()}) reaches {worst:.1f} (the runs taken: {now:.1f}): widen "
                "the space (longer runs, other start temperatures) or accept the tie")

    def to_dict(self) -> dict:
        """JSON-ready form (``design.json``): the run, the separations by pair and the
        verdict for a reader, and under ``record`` every field for :meth:`from_dict`
        (:mod:`nfs.io.records`; the rivals' predictions for the figure are left out).  Schema
        :data:`DESIGN_SCHEMA`."""
        return {
            "schema": DESIGN_SCHEMA,
            "rivals": [r.to_dict() for r in self.rivals],
            "experiment": self.experiment.to_dict(), "hours": self.experiment.hours,
            "margin_sigma": self.margin_sigma, "met": self.met, "verdict": self.verdict,
            "open_pairs": [self.pair_label(k) for k in self.open_pairs],
            "noise_factors": dict(self.noise_factors),
            "current_separation": {self.pair_label(k): v.to_dict()
                                   for k, v in self.current.items()},
            "proposed_separation": {self.pair_label(k): v.to_dict()
                                    for k, v in self.proposed.items()},
            "trials": [{"stage": t.stage, "worst_sigma": t.worst_sigma, "met": t.met,
                        **t.experiment.to_dict()} for t in self.trials],
            "time_s": self.time_s,
            "record": encode(self)}

    @classmethod
    def from_dict(cls, data: dict) -> "Design":
        """The design :meth:`to_dict` wrote (``design.json``), without the predictions."""
        if not isinstance(data, dict) or "record" not in data:
            raise RecordError("not a design written by nfs design (no 'record')")
        return from_record(cls, {"schema": data.get("schema"), **data["record"]},
                           DESIGN_SCHEMA)


def _pairs(n: int) -> list[tuple[int, int]]:
    return list(combinations(range(n), 2))


def _separations(preds: Sequence[RivalPrediction], sigma, pairs=None
                 ) -> dict[tuple[int, int], Separation]:
    return {(i, j): separation(preds[i], preds[j], sigma)
            for i, j in (_pairs(len(preds)) if pairs is None else pairs)}


def current_separation(rivals: Sequence[Rival], runs: Sequence[Run], *, n_draws: int = N_DRAWS,
                       seed: int = 0) -> tuple[dict[tuple[int, int], Separation],
                                               dict[str, float]]:
    """Every pair's separation on the runs already taken, each rival replaying them from
    its own start states, in the noise the runs show; and that noise's factors
    (:func:`nfs.rivals.replay.replay_runs_taken`)."""
    taken = replay_runs_taken(rivals, runs, n_draws=n_draws, rng=np.random.default_rng(seed))
    return _separations(taken.predictions, taken.sigma), taken.factors


def _shortest(exp: Experiment, preds: Sequence[RivalPrediction], space: Space,
              ref_inst, margin: float, factors: dict[str, float], pairs
              ) -> tuple[Experiment, float, bool]:
    """The shortest prefix of ``exp`` on which the worst of ``pairs`` reaches ``margin``;
    else the longest, with its worst separation."""
    worst = -1.0
    # the noise of every number of the longest record: a prefix's is its first numbers
    full = scaled(noise_sigma(ref_inst, preds[0].mean[0]), factors)
    for d in space.durations_s(exp):
        cut = [p.until(d) for p in preds]
        sigma = [{c: v[: cut[0].mean[0].values[c].size] for c, v in full.items()}]
        w = min(s.sigma for s in _separations(cut, sigma, pairs).values())
        worst = w
        if w >= margin:
            return exp.with_duration(float(d)), w, True
    return exp.with_duration(space.max_duration_s), worst, False


def _better(a: Trial, b: Trial | None) -> bool:
    """Is trial ``a`` a better proposal than ``b``?"""
    if b is None:
        return True
    if a.met != b.met:
        return a.met
    if a.met:
        return (a.experiment.hours, -a.worst_sigma) < (b.experiment.hours, -b.worst_sigma)
    return a.worst_sigma > b.worst_sigma


#: Dwells the refinement tries [s]: long enough for a dwell mean, short enough for a
#: north-finding cycle within minutes (docs/physics.md section 5: 60-180 s).
MIN_DWELL_S, MAX_DWELL_S = 30.0, 600.0


#: The shortest power cycle a refinement proposes [s]: the table of ranges' typical shortest
#: (a unit whose supply drops for less is a glitch, not a warm restart).
SHORTEST_OFF_S = find("chamber.program.power_off_s").typical[0]


def _neighbours(e: Experiment, space: Space, t_range: tuple[float, float],
                base_dwell_s: float) -> list[Experiment]:
    """Half a grid step each way along every continuous knob of ``e`` (module docstring),
    and the turntable's dwell halved and doubled, a ramp's rate too."""
    out = []
    temps = sorted(space.start_temperatures_c)
    step_t = (max(temps) - min(temps)) / max(len(temps) - 1, 1) / 2.0 if len(temps) > 1 else 0
    for dt in (-step_t, step_t):
        t0 = e.start_temperature_c + dt
        if dt and t_range[0] <= t0 <= t_range[1]:
            kw = {}
            if e.event == "ramp":
                kw["ramp_to_c"] = float(np.clip(e.ramp_to_c + dt, *TEMPERATURE_RANGE_C))
                if kw["ramp_to_c"] == t0:
                    continue
            out.append(replace(e, start_temperature_c=t0, **kw))
    for f in (0.5, 1.5):
        ev = e.event_s * f
        out.append(replace(e, event_s=ev))
    if e.event == "power_off":
        for f in (0.5, 1.5):
            if min(e.off_times_s()) * f < SHORTEST_OFF_S:
                continue
            if e.cycles == 1 or max(e.off_times_s()) * f < e.every_s:
                second = None if e.power_off_2_s is None else e.power_off_2_s * f
                out.append(replace(e, power_off_s=e.power_off_s * f, power_off_2_s=second))
    for f in (0.5, 2.0):              # the turntable's dwell (the schedule's own first)
        # in whole steps of the prediction's clock, so that it stays coarse
        dwell = PREDICT_STEP_S * round((base_dwell_s if e.dwell_s is None else e.dwell_s)
                                       * f / PREDICT_STEP_S)
        if MIN_DWELL_S <= dwell <= MAX_DWELL_S:
            out.append(replace(e, dwell_s=dwell))
    if e.event == "ramp":
        for f in (0.5, 2.0):
            out.append(replace(e, rate_c_per_min=e.rate_c_per_min * f))
        for f in (0.5, 1.5):
            to = float(np.clip(e.start_temperature_c + (e.ramp_to_c - e.start_temperature_c)
                               * f, *TEMPERATURE_RANGE_C))
            if to != e.start_temperature_c:
                out.append(replace(e, ramp_to_c=to))
    return [x.with_duration(space.max_duration_s) for x in out
            if x.event_end_s < space.max_duration_s and space.durations_s(x).size]


def design_experiment(rivals: Sequence[Rival], runs: Sequence[Run],
                      base: RunConditions | None = None, space: Space | None = None, *,
                      margin_sigma: float = MARGIN_SIGMA, n_draws: int = N_DRAWS,
                      seed: int = 0, refine_rounds: int = 2,
                      progress: Callable[[str], None] | None = None) -> Design:
    """The cheapest experiment of ``space`` separating every pair of ``rivals`` by
    ``margin_sigma`` (module docstring).  ``base``: the site, heading, schedule and sample
    rate of the proposed run (default: those of the runs taken,
    :func:`~nfs.design.space.base_conditions`); ``space``: the experiments searched
    (default: :func:`~nfs.design.space.default_space` of the runs)."""
    t_start = time.perf_counter()
    base = base_conditions(runs) if base is None else base
    space = default_space(runs) if space is None else space
    rivals = list(rivals)
    if len(rivals) < 2:
        raise NfsError("a design needs at least two rivals, got "
                       + (", ".join(r.label for r in rivals) or "none")
                       + " (the runs taken decide already: nothing to design)")
    ref = rivals[0].instrument
    if progress is not None:
        progress("the runs taken: each rival's replay and the noise they show")
    current, factors = current_separation(rivals, runs, n_draws=n_draws, seed=seed)
    # the pairs the runs taken leave below the margin are what the run must separate
    # (all of them when the runs separate every pair already: the cheapest run that
    # would on its own)
    open_pairs = [k for k, v in current.items() if v.sigma < margin_sigma] or list(current)
    rng = np.random.default_rng(seed)
    trials: list[Trial] = []
    cache: dict[Experiment, list[RivalPrediction]] = {}

    def evaluate(exp: Experiment, stage: str) -> Trial:
        exp = exp.with_duration(space.max_duration_s)
        if exp not in cache:
            cond = exp.conditions(base)
            cache[exp] = [predict_rival(r, [cond], n_draws, rng) for r in rivals]
        found, worst, met = _shortest(exp, cache[exp], space, ref, margin_sigma, factors,
                                      open_pairs)
        t = Trial(found, worst, met, stage)
        trials.append(t)
        return t

    grid = space.experiments()
    best: Trial | None = None
    for k, exp in enumerate(grid):
        if progress is not None:
            progress(f"experiment {k + 1}/{len(grid)}: {exp.describe()}")
        t = evaluate(exp, "grid")
        if _better(t, best):
            best = t
    t_range = (min(space.start_temperatures_c), max(space.start_temperatures_c))
    for _ in range(refine_rounds):
        improved = False
        for exp in _neighbours(best.experiment, space, t_range, base.schedule.dwell_s):
            if exp.with_duration(space.max_duration_s) in cache:
                continue
            if progress is not None:
                progress(f"refining: {exp.describe()}")
            t = evaluate(exp, "refine")
            if _better(t, best):
                best, improved = t, True
        if not improved:
            break
    chosen = best.experiment
    full = cache[chosen.with_duration(space.max_duration_s)]
    cut = [p.until(chosen.duration_s) for p in full]
    sigma = scaled(noise_sigma(ref, cut[0].mean[0]), factors)
    proposed = _separations(cut, [sigma])
    return Design(rivals=tuple(rivals), experiment=chosen, proposed=proposed,
                  current=current, margin_sigma=margin_sigma, noise_factors=factors,
                  open_pairs=tuple(open_pairs), met=best.met,
                  trials=tuple(trials),
                  predictions={r.label: p for r, p in zip(rivals, cut)}, sigma=sigma,
                  time_s=time.perf_counter() - t_start)
