"""Is the model's thermal structure adequate?  The structural alternatives of
:mod:`nfs.fit.structure` (and, for a lumped coil, :mod:`nfs.fit.wound_alternative`) scored
against the model, and a verdict.  :func:`structural_alternatives` is their default list.

:func:`thermal_adequacy` refits the model's thermal stage on the runs and takes its
leave-one-start-temperature-out thermometer residual (:mod:`nfs.fit.thermometer_cv`),
then screens every structural alternative and fits the best few
(:mod:`nfs.fit.alternative_score`).

Adequacy.  Per thermometer and stage (start-up: t < ``startup_s`` = 3600 s after power-on;
stable: after) the model's held-out (CV) residual RMS is compared with the thermometer's
noise floor sqrt(noise_c^2 + quantum_c^2 / 12) [K] from the instrument: white noise plus a
rounding error of variance q^2/12 (the pseudo-quantisation-noise model of Widrow and Kollar,
"Quantization Noise", Cambridge University Press, 2008; only approximate here, the 0.01 K
noise dithers the 0.0625 K quantum weakly, which the 1.5x factor covers).  The floor is
not measured from the residual's high-frequency part: with the default 0.0625 K quantum and
0.01 K noise, consecutive samples of a slowly moving temperature round to the same level,
so a difference-based estimate comes out far below the true per-sample error.  The
structure is adequate when every channel is within :data:`ADEQUACY_FACTOR` (1.5x) of its
floor, times what sampling allows on the channel's n knots, and no structural alternative
beats the model (its CV RMS lower by more than :data:`~nfs.fit.alternative_score.CV_DROP`).
Sampling: with the structure right, the held-out residuals are the thermometer's noise, and
n sum(r^2) / (n floor^2) follows chi^2_n / n, whose :data:`ADEQUACY_QUANTILE` quantile
bounds the squared ratio noise alone gives; the limit is therefore 1.5 sqrt(chi^2_{n,
0.99} / n) (1.95x on 30 knots, a 5-minute stable stage of three runs at 30 s; 1.55x on
3000).  The 1.5x factor is the model error allowed; the square root, the sampling error of
an RMS on few knots, without which a short run's stable stage fails on noise alone.

:func:`beats_structure` says whether a thermal candidate beats the model and the best
structural alternative, pooled and run by run (the diagnosis names a thermal candidate only
then); :func:`structure_rival` names the rival it does not beat.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

from scipy.stats import chi2

from ..docfields import document_fields
from ..errors import NfsError
from ..instrument import Instrument
from ..run import Run
from .alternative_score import (BEATS_ALPHA, CV_DROP, AlternativeScore, better_run_by_run,
                                score_alternative)
from .start_state import StartModel
from .structure import (StructuralAlternative, free_link, housing_node, insert_node,
                        neighbours, split_node, tec_set_point, thermometer_weight)
from .thermal_residual import DEFAULT_START
from .wound_alternative import can_wind, wound_coil
from .thermometer_cv import (ADEQUACY_STAGES, STAGE_WORDS, ChordModel, ThermometerProblem,
                             chord_refit, sum_of_squares)

__all__ = ["ChannelFit", "ThermalAdequacy", "thermal_adequacy", "beats_structure",
           "structural_alternatives",
           "structure_rival", "MODEL_RIVAL", "ADEQUACY_FACTOR", "ADEQUACY_QUANTILE", "STARTUP_S",
           "DEFAULT_DECIMATE_S", "REFINE_TOP"]

#: A channel is adequate when its residual RMS is within this factor of its noise floor
#: (times the sampling allowance of :data:`ADEQUACY_QUANTILE`).
ADEQUACY_FACTOR = 1.5
#: Quantile of chi^2_n / n that bounds a channel's squared RMS ratio under noise alone.
ADEQUACY_QUANTILE = 0.99
#: End of the start-up stage [s] after power-on (docs/physics.md section 1: 30-90 min).
STARTUP_S = 3600.0
#: Default spacing of the residual grid [s].
DEFAULT_DECIMATE_S = 30.0
#: Alternatives fitted to convergence after the one-step screening.
REFINE_TOP = 4


@dataclass(frozen=True)
class ChannelFit:
    """The model's thermometer residual in one stage against the thermometer's floor."""

    thermometer: str
    """``fog``, ``acc_x`` or ``acc_y``."""
    stage: str
    """``start-up`` (t < startup_s after power-on) or ``stable``."""
    rms_k: float
    """Residual RMS of the model after its thermal refit on all runs (in-sample) [K]."""
    cv_rms_k: float
    """RMS of the held-out residual (leave-one-start-temperature-out) [K]: what the
    verdict uses, since the model's free parameters can absorb a wrong structure in-sample
    at the price of values that do not carry over to another start temperature."""
    floor_k: float
    """Noise floor sqrt(noise_c^2 + quantum_c^2 / 12) [K]."""
    n_knots: int
    """Residuals it rests on."""
    factor: float
    """The adequacy factor the ratio is held to."""

    @property
    def ratio(self) -> float:
        """cv_rms_k / floor_k."""
        return self.cv_rms_k / self.floor_k if self.floor_k > 0 else math.inf

    @property
    def limit(self) -> float:
        """The ratio allowed: factor sqrt(chi^2_{n, q} / n) on the channel's n knots
        (module docstring; q = :data:`ADEQUACY_QUANTILE`)."""
        if self.n_knots <= 0:
            return math.inf
        return self.factor * math.sqrt(chi2.ppf(ADEQUACY_QUANTILE, self.n_knots)
                                       / self.n_knots)

    @property
    def adequate(self) -> bool:
        """ratio <= limit (a channel without knots counts as adequate)."""
        return self.n_knots == 0 or self.ratio <= self.limit


@document_fields
@dataclass(frozen=True)
class ThermalAdequacy:
    """Does the model's thermal structure fit the thermometers?"""

    channels: tuple[ChannelFit, ...]
    """Per thermometer and stage: residual RMS against the floor."""
    factor: float
    """A channel is adequate when its RMS is within this factor of its floor."""
    adequate: bool
    """Every channel adequate and no structural alternative beats the model."""
    cv_rms_k: float
    """The model's own CV RMS [K] (:mod:`nfs.fit.thermometer_cv`)."""
    alternatives: tuple[AlternativeScore, ...]
    """Every alternative scored, best CV first."""
    best: AlternativeScore | None
    """The structural alternative (kind != effect) with the lowest CV RMS, or None."""
    model: Instrument = field(repr=False, compare=False)
    """The model after its thermal refit."""
    message: str = ""
    """A sentence a user can act on."""
    time_s: float = 0.0
    """Wall time [s]."""
    n_evaluations: int = 0
    """Thermometer residual evaluations (network solves of all runs) it took."""
    cv_sse_by_run: tuple[float, ...] = ()
    """The model's held-out squared residual summed over each run's knots [K^2]."""

    @property
    def worst(self) -> ChannelFit:
        """The channel with the largest ratio to its floor."""
        return max(self.channels, key=lambda c: c.ratio if c.n_knots else -1.0)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return {"adequate": self.adequate, "factor": self.factor, "cv_rms_k": self.cv_rms_k,
                "message": self.message, "time_s": self.time_s,
                "n_evaluations": self.n_evaluations,
                "channels": [{"thermometer": c.thermometer, "stage": c.stage,
                              "rms_k": c.rms_k, "cv_rms_k": c.cv_rms_k,
                              "floor_k": c.floor_k, "ratio": c.ratio,
                              "n_knots": c.n_knots, "adequate": c.adequate}
                             for c in self.channels],
                "best": None if self.best is None else self.best.name,
                "alternatives": [a.to_dict() for a in self.alternatives]}


# ---------------------------------------------------------------------------------------------
# The verdict

def _floor_k(inst: Instrument, name: str) -> float:
    m = inst.thermometers[name]
    return math.sqrt(m.noise_c ** 2 + m.quantum_c ** 2 / 12.0)


def _advice(best: AlternativeScore) -> str:
    """What to change in the model for the best alternative, in words."""
    v = list(best.params.values())
    if best.kind == "link":
        a, b = best.name.split(" ", 1)[1].split("-", 1)
        return (f"add a [[thermal.links]] between {a} and {b} of about {v[0]:.3g} W/K "
                "(or the physical path it stands for)")
    if best.kind == "split":
        node = best.name.split(" ", 1)[1]
        return (f"give {node} an inner part: split it into two nodes linked by about "
                f"{v[0]:.3g} W/K (a layer or a mass the model lumps together)")
    if best.kind == "insert":
        return (f"put a node of about {v[0]:.3g} J/K on the path ({v[1]:.3g} and {v[2]:.3g} "
                "W/K on either side)")
    if best.kind == "thermometer":
        path = next(iter(best.params))
        t, node = path[len("thermometers."):].split(".nodes.", 1)
        return (f"check where the {t} thermometer sits: it reads as if {100 * v[0]:.0f} % of "
                f"it were {node} ([thermometers.{t}] nodes)")
    if best.kind == "tec":
        return (f"set the TEC law's set point T_set to about {v[0]:.3g} C "
                "([[effects]] tec_power)")
    return f"add {best.name}"


def _message(channels: Sequence[ChannelFit], structural: Sequence[AlternativeScore],
             factor: float, improves: bool) -> str:
    """The verdict in one sentence: where the structure fails, the best fix, what to do."""
    worst = max(channels, key=lambda c: c.ratio if c.n_knots else -1.0)
    who = "FOG" if worst.thermometer == "fog" else worst.thermometer
    head = (f"the {who} thermometer residual (held out by start temperature) in the "
            f"{STAGE_WORDS[worst.stage]} stage is {worst.ratio:.1f}x its floor "
            f"({worst.floor_k:.3f} K)")
    n_alt = len(structural)
    if all(c.adequate for c in channels) and not improves:
        return (f"the thermal structure fits: every thermometer residual is within "
                f"{factor:g}x its floor in both stages, allowing for the sampling of few "
                f"knots (worst: {head[4:]}, limit {worst.limit:.2f}x); none of {n_alt} "
                "generic structural alternatives beats it")
    failing = [c for c in channels if not c.adequate]
    if failing:
        worst = max(failing, key=lambda c: c.ratio / c.limit)
        who = "FOG" if worst.thermometer == "fog" else worst.thermometer
        head = (f"the {who} thermometer residual (held out by start temperature) in the "
                f"{STAGE_WORDS[worst.stage]} stage is {worst.ratio:.1f}x its floor "
                f"({worst.floor_k:.3f} K; limit {worst.limit:.2f}x on {worst.n_knots} knots)")
    if not improves:
        return (f"{head}: the thermal structure does not fit there, and none of {n_alt} "
                "generic alternatives (one more node, a free link, the FOG thermometer "
                "elsewhere) does better; check the TEC law, the chamber record and the "
                "thermometer channels")
    best = structural[0]
    after = best.cv_channels_after_k[worst.thermometer][worst.stage] / worst.floor_k
    lead = (f"{head}: the thermal structure does not fit there" if not worst.adequate else
            f"{head}, yet a structural alternative lowers the CV RMS by "
            f"{100 * best.cv_drop:.0f} %")
    out = (f"{lead}; the best alternative, {best.name}, brings it to {after:.1f}x "
           f"(CV RMS {1000 * best.cv_rms_before_k:.1f} -> {1000 * best.cv_rms_after_k:.1f} "
           f"mK); consider: {_advice(best)}")
    tied = [s.name for s in structural[1:]
            if s.cv_rms_after_k < best.cv_rms_after_k / (1.0 - CV_DROP)]
    if tied:
        out += f" (as good within {100 * CV_DROP:g} %: {', '.join(tied)})"
    return (out + ". Until the structure fits, a thermal candidate (a heat source, a lag) "
            "is named only if it beats this alternative")


def _score_alternatives(prob: ThermometerProblem, model: ChordModel,
                        alts: Sequence[StructuralAlternative], cv_model: float,
                        rms_model: tuple[dict, dict], refine_top: int, max_nfev: int
                        ) -> list[AlternativeScore]:
    """Every alternative screened, the ``refine_top`` best refined; best CV RMS first."""
    screened = []
    for alt in alts:
        s, u = score_alternative(prob, model, alt, False, cv_model, rms_model, max_nfev)
        screened.append((alt, s, u))
    order = sorted(range(len(screened)), key=lambda i: screened[i][1].cv_rms_after_k)
    scores = [s for _, s, _ in screened]
    for i in order[:refine_top]:
        alt, s, u = screened[i]
        scores[i], _ = score_alternative(prob, model, alt, True, cv_model, rms_model, max_nfev,
                                         u)
    scores.sort(key=lambda s: s.cv_rms_after_k)
    return scores


def structural_alternatives(inst: Instrument) -> list[StructuralAlternative]:
    """The small default list of generic alternatives of ``inst``'s thermal structure.

    Core nodes: the coil nodes, the source (electronics), every other powered node that
    carries no accelerometer (the board) and the housing (largest conductance to the
    chamber).  Splits: each coil node, the housing and the powered non-source nodes.
    Inserts: between each node of the FOG thermometer and the housing.  Links: every pair of
    core nodes not yet linked.  Thermometer: the FOG thermometer's share of each neighbour
    of its nodes, and of its first node; each accelerometer thermometer's share of each
    neighbour of its nodes (the mount it sits on).  The TEC law's set point, when the model
    has one.  A lumped coil whose two nodes are linked: the coil wound in 8 layers
    (:func:`~nfs.fit.wound_alternative.wound_coil`).  For the lumped preset: 4 splits,
    2 inserts, 4 links, 5 thermometer shares, the TEC set point and the wound coil.
    """
    net = inst.network
    g = inst.gyro
    housing = housing_node(inst)
    acc = set(inst.accelerometers.nodes.values())
    coil = [n for n in (g.coil_outer, g.coil_inner) if n]
    # a wound coil's layers are resolved already and their links are its own numbers
    # (nfs.coil): they are linked to, not split or cut
    layers = set(inst.coil.layer_names) if inst.coil is not None else set()
    powered = [n.name for n in net.nodes
               if n.power_w > 0 and n.name not in acc and n.name != g.source]
    shell = [housing] if housing else []
    core = list(dict.fromkeys(coil + [g.source] + powered + shell))
    out = [split_node(inst, n) for n in dict.fromkeys(coil + shell + powered)
           if n not in layers]
    fog_nodes = list(inst.thermometers["fog"].nodes)
    if housing:
        out += [insert_node(inst, n, housing) for n in fog_nodes
                if n != housing and n not in layers
                and any({l.a, l.b} == {n, housing} for l in inst.own_parts[1])]
    linked = {frozenset((l.a, l.b)) for l in net.links}
    for i, a in enumerate(core):
        for b in core[i + 1:]:
            if frozenset((a, b)) not in linked and not {a, b} <= layers:
                out.append(free_link(inst, a, b))
    # a thermometer sits on a face of a wound coil, never inside the winding
    inside = set(inst.coil.layer_names[1:-1]) if inst.coil is not None else set()
    near = [m for n in fog_nodes for m in neighbours(net, n)
            if m not in fog_nodes and m not in inside]
    out += [thermometer_weight(inst, "fog", m) for m in dict.fromkeys(near)]
    if len(fog_nodes) > 1:
        out.append(thermometer_weight(inst, "fog", fog_nodes[0]))
    for name, model in inst.thermometers.items():   # an accelerometer's on its mount
        if name == "fog":
            continue
        own = list(model.nodes)
        out += [thermometer_weight(inst, name, m) for m in dict.fromkeys(
            m for n in own for m in neighbours(net, n) if m not in own and m not in inside)]
    if any(e.name == "tec_power" for e in inst.effects):
        out.append(tec_set_point(inst))
    if can_wind(inst):
        out.append(wound_coil(inst))
    return out


def thermal_adequacy(inst: Instrument, runs: Sequence[Run],
                     alternatives: Sequence[StructuralAlternative]
                     | Callable[[Instrument], Sequence[StructuralAlternative]] | None = None, *,
                     decimate_s: float = DEFAULT_DECIMATE_S, factor: float = ADEQUACY_FACTOR,
                     startup_s: float = STARTUP_S, refine_top: int = REFINE_TOP,
                     max_nfev: int = 6, start_state: StartModel | None = DEFAULT_START
                     ) -> ThermalAdequacy:
    """Is the thermal structure of ``inst`` adequate for ``runs``? (module docstring).

    Parameters
    ----------
    inst : Instrument
        The model, best already fitted (``nfs fit``); its thermal stage is polished here.
    runs : sequence of Run
        Measured runs with at least two distinct start temperatures.
    alternatives : sequence of StructuralAlternative, or a callable, optional
        Default :func:`structural_alternatives` of the refitted model.  A callable is
        called with the refitted model and returns the alternatives (the way to add named
        candidates, ``lambda m: structural_alternatives(m) + [effect_alternative(m,
        "heat_source", "coil_outer")]``); a sequence is used as given, so it should be
        built on a fitted model.  Kind ``effect`` alternatives are scored but never
        ``best``.
    decimate_s : float
        Spacing of the residual grid [s].
    factor : float
        A channel is adequate when its RMS is within ``factor`` of its floor.
    startup_s : float
        End of the start-up stage [s] after power-on.
    refine_top : int
        How many of the screened alternatives are fitted to convergence.
    max_nfev : int
        Residual evaluations of each refinement (Jacobian evaluations not counted).
    start_state : StartModel or None
        Each run's start estimated with the model (:mod:`nfs.fit.start_state`, in
        every residual, the held-out runs' too: a new run's soak is not known either);
        None: the runs were soaked exactly at T0 (the check then has more power: a
        structural error can no longer hide in the starts).

    Raises
    ------
    NfsError
        Fewer than two start temperatures, a run without the thermometer columns.
    """
    t_start = time.perf_counter()
    runs = list(runs)
    if not decimate_s > 0:
        raise NfsError(f"thermal_adequacy: decimate_s must be > 0, got {decimate_s}")
    if not factor >= 1.0:
        raise NfsError(f"thermal_adequacy: factor must be >= 1, got {factor}")
    prob = ThermometerProblem(runs, decimate_s, startup_s, start_state)
    if len(set(prob.group)) < 2:
        raise NfsError("thermal_adequacy needs runs at two start temperatures at least "
                       "(leave-one-start-temperature-out validation); got "
                       + (", ".join(f"{r.meta.start_temperature_c:g} C" for r in runs)
                          or "no runs"))
    model = chord_refit(prob, inst)
    cv_model, _, held = prob.linear_fit(model.r, model.J, *model.box())
    rms_model = (prob.rms(model.r), prob.rms(held))
    counts = prob.counts()
    channels = tuple(ChannelFit(name, stage, rms_model[0][name][stage],
                                rms_model[1][name][stage], _floor_k(model.inst, name),
                                counts[name][stage], factor)
                     for name in prob.names for stage in ADEQUACY_STAGES)
    if alternatives is None:
        alts = structural_alternatives(model.inst)
    elif callable(alternatives):
        alts = list(alternatives(model.inst))
    else:
        alts = list(alternatives)
    scores = _score_alternatives(prob, model, alts, cv_model, rms_model, refine_top, max_nfev)
    structural = [s for s in scores if s.kind != "effect"]
    best = structural[0] if structural else None
    improves = best is not None and best.beats_model
    adequate = all(c.adequate for c in channels) and not improves
    message = _message(channels, structural, factor, improves)
    return ThermalAdequacy(channels=channels, factor=factor, adequate=adequate,
                           cv_rms_k=cv_model, alternatives=tuple(scores), best=best,
                           model=model.inst, message=message,
                           time_s=time.perf_counter() - t_start, n_evaluations=prob.n_eval,
                           cv_sse_by_run=tuple(sum_of_squares([h]) for h in held))


#: The name :func:`structure_rival` gives the model itself.
MODEL_RIVAL = "the model"


def structure_rival(candidate: AlternativeScore, adequacy: ThermalAdequacy,
                    margin: float = 0.0, alpha: float = BEATS_ALPHA) -> str | None:
    """The rival a thermal candidate does not beat, or None when it beats them all.

    The rival is whichever of the model (:data:`MODEL_RIVAL`) and its structural
    alternatives has the lowest CV RMS.  The candidate beats it when (a) its CV RMS is below
    ``(1 - margin)`` times the rival's and (b) its held-out squared residual is smaller run
    by run: the paired per-run log-ratios are tested one-sided against zero with a t test
    at ``alpha`` (:func:`~nfs.fit.alternative_score.better_run_by_run`), runs being
    the independent units (as the drift candidates' run-level statistics; a rank test would
    need 5 runs to reach 5 % at all).  A pooled CV RMS a fraction of a percent lower, won on
    some runs and lost on others, is a tie, not a named effect.  The candidate's residual
    must be the same as the alternatives' (the three thermometers at the knots,
    leave-one-start-temperature-out); :func:`~nfs.fit.structure.effect_alternative`
    scores a candidate that way.
    """
    refs = [(adequacy.cv_rms_k, adequacy.cv_sse_by_run, MODEL_RIVAL)] + [
        (s.cv_rms_after_k, s.cv_sse_by_run, s.name) for s in adequacy.alternatives
        if s.kind != "effect"]
    ref_cv, ref_sse, rival = min(refs, key=lambda r: r[0])
    return None if better_run_by_run(candidate.cv_rms_after_k, candidate.cv_sse_by_run,
                                     ref_cv, ref_sse, margin, alpha) else rival


def beats_structure(candidate: AlternativeScore, adequacy: ThermalAdequacy,
                    margin: float = 0.0, alpha: float = BEATS_ALPHA) -> bool:
    """Does a thermal candidate beat the model and every structural alternative, pooled and
    run by run? (:func:`structure_rival` is None)."""
    return structure_rival(candidate, adequacy, margin, alpha) is None
