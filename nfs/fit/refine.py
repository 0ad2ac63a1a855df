"""A thermal structure that fits the unit: generic alternatives adopted in a chain.

A lumped network is never the unit's (a coil of many radial layers lumped into two nodes, a
thermometer that sits between parts, another path for the heat).  When the fitted network
misses a thermometer by more than :data:`REFINE_FACTOR` (2x) its noise floor
sqrt(noise_c^2 + quantum_c^2 / 12), the drift candidates of the diagnosis would be scored
on node temperatures the thermometers contradict, and the misfit blamed on whatever
candidate follows it.  So :func:`fit_unit` refines the structure before the drift stage:

1. the generic alternatives of the current network (one more node, a free link, a
   thermometer that sits elsewhere: :func:`nfs.fit.adequacy.structural_alternatives`)
   are scored on the leave-one-start-temperature-out thermometer residual
   (:func:`nfs.fit.adequacy.thermal_adequacy`);
2. the best one is adopted when it pays: its held-out RMS lower than the current
   structure's by more than :data:`~nfs.fit.alternative_score.CV_DROP` and lower run by
   run (a paired one-sided t test over the runs,
   :func:`~nfs.fit.alternative_score.better_run_by_run`):
   a structure change is a claim about the unit, held to the standard of a named effect;
3. the adopted structure is checked again in full (the screening linearises the held-out
   fit; a change whose full check does not lower the held-out residual by
   :data:`~nfs.fit.alternative_score.CV_DROP` is dropped and the chain stops there);
4. repeated on the new structure until every thermometer's held-out residual is within the
   factor, no alternative pays, or :data:`MAX_STEPS` changes were made;
5. a lumped coil is then tried wound in layers (:mod:`nfs.fit.wound_alternative`), by
   :func:`fit_unit` whatever the thermometers' misfit, since the thermometers see the coil's
   faces and the gyro its whole radial field: kept where the held-out thermometers are no
   worse and the drift agrees (:func:`_drift_refuses`).

The two stages of :func:`nfs.fit.calibration.fit_model` then run on the structure it ended
with (the new numbers free beside the default set), so the drift is fitted and, later,
candidates are scored on node temperatures consistent with it.  The result says which
changes were made and what each bought (:class:`Refinement`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence


from ..docfields import document_fields
from ..instrument import Instrument
from ..io.records import record
from ..run import Run
from .adequacy import ThermalAdequacy, structural_alternatives, thermal_adequacy
from .alternative_score import BEATS_ALPHA, CV_DROP, better_run_by_run
from .calibration import check_fit_keywords, fit_model, one_blas_thread
from .fit_result import FitResult
from .free_set import default_free
from .params import expand_paths, get_param, list_params
from .wound_alternative import WOUND_KIND, can_wind, wound_coil
from .start_state import StartModel
from .thermal_residual import DEFAULT_START
from .thermometer_cv import STAGE_WORDS

__all__ = ["REFINE_FACTOR", "MAX_STEPS", "StructureStep", "Refinement", "refine_structure",
           "fit_unit"]

#: A thermometer missed by more than this many noise floors calls for another structure.
REFINE_FACTOR = 2.0
#: Most changes of the structure in one refinement.
MAX_STEPS = 3


@document_fields
@dataclass(frozen=True)
class StructureStep:
    """One change of the thermal structure and what it bought."""

    name: str
    """The alternative adopted (e.g. ``link coil_inner-electronics``)."""
    kind: str
    """Its kind (:attr:`nfs.fit.structure.StructuralAlternative.kind`: ``split``,
    ``link``, ``wound`` ...)."""
    description: str
    """What it changes, in one sentence."""
    params: dict[str, float]
    """Its fitted new numbers {path: value}."""
    cv_rms_before_k: float
    """Held-out RMS of the three thermometers before the change [K]."""
    cv_rms_after_k: float
    """The same after it [K]."""
    worst_before: float
    """The worst thermometer's held-out residual before, in noise floors."""
    worst_after: float
    """The same after."""


@document_fields
@record
@dataclass(frozen=True)
class Refinement:
    """The structure :func:`refine_structure` ended with."""

    instrument: Instrument
    """The refined model (the input when no change paid)."""
    steps: tuple[StructureStep, ...]
    """The changes adopted, in order."""
    adequacy: ThermalAdequacy
    """The check of the final structure."""
    stopped: str
    """Why the chain stopped, in words."""

    def summary(self) -> str:
        """One line per change, then why it stopped."""
        lines = [f"structure: {s.name} ({', '.join(f'{k} = {v:.4g}' for k, v in s.params.items())}"
                 f"): held-out thermometers {s.cv_rms_before_k * 1e3:.1f} -> "
                 f"{s.cv_rms_after_k * 1e3:.1f} mK, worst {s.worst_before:.1f}x -> "
                 f"{s.worst_after:.1f}x its floor" for s in self.steps]
        return "\n".join(lines + [f"structure: {self.stopped}"])

    def to_dict(self) -> dict[str, Any]:
        return {"steps": [{"name": s.name, "kind": s.kind, "description": s.description,
                           "params": dict(s.params), "cv_rms_before_k": s.cv_rms_before_k,
                           "cv_rms_after_k": s.cv_rms_after_k, "worst_before": s.worst_before,
                           "worst_after": s.worst_after} for s in self.steps],
                "stopped": self.stopped}


def refine_structure(inst: Instrument, runs: Sequence[Run], *, factor: float = REFINE_FACTOR,
                     max_steps: int = MAX_STEPS, decimate_s: float = 10.0,
                     start_state: StartModel | None = DEFAULT_START,
                     exclude_kinds: Sequence[str] = ()) -> Refinement:
    """Adopt, in a chain, the generic structural alternatives that pay (module docstring).

    ``inst`` should be thermally fitted to ``runs`` already (each check polishes it).
    ``exclude_kinds``: kinds of alternative not to try (``wound``: a coil the drift has
    refused wound).
    """
    model = inst
    steps: list[StructureStep] = []
    excluded = tuple(exclude_kinds)

    def alternatives(m: Instrument):
        return [a for a in structural_alternatives(m) if a.kind not in excluded]

    def check(m: Instrument) -> ThermalAdequacy:
        return thermal_adequacy(m, runs, decimate_s=decimate_s, start_state=start_state,
                                alternatives=alternatives)

    ad = check(model)
    while True:
        worst = ad.worst.ratio
        if worst <= factor:
            stopped = (f"every thermometer within {factor:g}x its noise floor held out "
                       f"(worst {ad.worst.thermometer} {STAGE_WORDS[ad.worst.stage]}, {worst:.1f}x)")
            break
        if len(steps) >= max_steps:
            stopped = (f"{max_steps} changes made; {ad.worst.thermometer} {STAGE_WORDS[ad.worst.stage]} "
                       f"still {worst:.1f}x its floor")
            break
        best = ad.best
        if best is None or not better_run_by_run(best.cv_rms_after_k, best.cv_sse_by_run,
                                                 ad.cv_rms_k, ad.cv_sse_by_run, CV_DROP,
                                                 BEATS_ALPHA):
            stopped = (f"no generic alternative pays on held-out runs (best: "
                       f"{'none' if best is None else best.name}); {ad.worst.thermometer} "
                       f"{STAGE_WORDS[ad.worst.stage]} stays {worst:.1f}x its floor")
            break
        new = check(best.instrument)
        if not new.cv_rms_k < (1.0 - CV_DROP) * ad.cv_rms_k:
            # the screening linearised the held-out fit; checked in full, the change does
            # not pay (a stiff pair of links, say): keep the structure as it was
            stopped = (f"{best.name} looked better linearised but not when checked in full "
                       f"(held-out {ad.cv_rms_k * 1e3:.1f} -> {new.cv_rms_k * 1e3:.1f} mK); "
                       f"{ad.worst.thermometer} {STAGE_WORDS[ad.worst.stage]} stays {worst:.1f}x its floor")
            break
        steps.append(StructureStep(name=best.name, kind=best.kind, description=best.description,
                                   params=dict(best.params), cv_rms_before_k=ad.cv_rms_k,
                                   cv_rms_after_k=new.cv_rms_k, worst_before=worst,
                                   worst_after=new.worst.ratio))
        model, ad = new.model, new
    return Refinement(instrument=model, steps=tuple(steps), adequacy=ad, stopped=stopped)


def fit_unit(inst: Instrument, runs: Sequence[Run], *, refine: bool = True,
             factor: float = REFINE_FACTOR, max_steps: int = MAX_STEPS,
             **fit_kwargs) -> FitResult:
    """Fit ``inst`` to a unit's runs (:func:`nfs.fit.calibration.fit_model`), check its thermal
    structure on held-out runs and, where it misses a thermometer by more than ``factor``
    floors, refine it (:func:`refine_structure`) and fit both stages again on the structure
    it ended with.  In sample the check would rarely fire: a network of twenty free numbers
    takes up a wrong structure where it was fitted (with parameters pushed far, which the
    fit reports), and only another start temperature shows it.  A model whose coil is two
    lumped nodes is then tried with its coil wound in layers
    (:func:`~nfs.fit.wound_alternative.wound_coil`), kept where the held-out thermometers are
    no worse and the drift agrees (module docstring, step 5); the structure's ``stopped``
    says which.

    ``fit_kwargs`` go to :func:`~nfs.fit.calibration.fit_model`.  The result's ``structure``
    holds the :class:`Refinement` (None without a thermal stage or with ``refine=False``);
    its ``initial`` stays ``inst``.
    """
    check_fit_keywords(fit_kwargs, "fit_unit")
    runs = list(runs)
    result = fit_model(inst, runs, **fit_kwargs)
    stages = tuple(fit_kwargs.get("stages", ("thermal", "drift")))
    if (not refine or "thermal" not in stages
            or len({r.meta.start_temperature_c for r in runs}) < 2):
        return result
    start_state = fit_kwargs.get("start_state", DEFAULT_START)
    refine_pinned = one_blas_thread(refine_structure)   # as the fit (nfs.fit.calibration)
    decimate_s = fit_kwargs.get("decimate_s", 10.0)
    ref = refine_pinned(result.instrument, runs, factor=factor, max_steps=max_steps,
                 start_state=start_state, decimate_s=decimate_s,
                 exclude_kinds=(WOUND_KIND,))
    base_free = fit_kwargs.pop("free", None)
    again = _refit(ref, runs, base_free, stages, fit_kwargs)
    if "drift" in stages and can_wind((again or result).instrument):
        wound, ref = one_blas_thread(_try_wound)(
            again or result, ref, runs, base_free, stages, fit_kwargs,
            start_state=start_state, decimate_s=decimate_s)
        again = wound or again
    if again is None:
        warn = () if ref.adequacy.worst.adequate else (f"thermal {ref.stopped}",)
        return replace(result, structure=ref, warnings=result.warnings + warn)
    return replace(again, initial=inst, structure=ref)


def _try_wound(fitted: FitResult, ref: Refinement, runs: Sequence[Run], base_free, stages,
               fit_kwargs, *, start_state, decimate_s) -> tuple[FitResult | None, Refinement]:
    """The lumped coil of ``fitted`` wound in layers (:func:`wound_coil`), kept where the
    held-out thermometers and the drift say so (module docstring, step 5): its numbers fitted
    on the thermometers, kept when their held-out RMS is not above the lumped coil's by
    :data:`~nfs.fit.alternative_score.CV_DROP`; then both stages fitted, kept when the drift
    agrees (:func:`_drift_refuses`).  Returns (the wound fit or None, the refinement with the
    step added or the reason it was not)."""
    alt = wound_coil(fitted.instrument)
    ad = thermal_adequacy(fitted.instrument, runs, alternatives=[alt], decimate_s=decimate_s,
                          start_state=start_state)
    scored = next(a for a in ad.alternatives if a.name == alt.name)
    if scored.cv_rms_after_k > (1.0 + CV_DROP) * ad.cv_rms_k:
        return None, replace(ref, stopped=(
            f"{ref.stopped}; the coil wound in layers misses the held-out thermometers "
            f"({ad.cv_rms_k * 1e3:.1f} -> {scored.cv_rms_after_k * 1e3:.1f} mK): kept lumped"))
    have = set(list_params(scored.instrument))     # the lumped coil's numbers are gone
    had = set(list_params(fitted.instrument))
    wound_default = default_free(scored.instrument, stages)
    free = (wound_default if base_free is None
            else [p for p in expand_paths(fitted.instrument, list(base_free)) if p in have]
            + [p for p in wound_default if p not in had])   # shupe_winding's, the coil's
    free = list(dict.fromkeys(free + [p for p in scored.params if p not in free]))
    wound = fit_model(scored.instrument, runs, free=free, **fit_kwargs)
    refused = _drift_refuses(fitted, wound)
    if refused:
        return None, replace(ref, stopped=f"{ref.stopped}; {refused}")
    after = thermal_adequacy(wound.instrument, runs, alternatives=[], decimate_s=decimate_s,
                             start_state=start_state)
    step = StructureStep(name=alt.name, kind=WOUND_KIND, description=alt.description,
                         params={p: get_param(wound.instrument, p) for p in scored.params},
                         cv_rms_before_k=ad.cv_rms_k, cv_rms_after_k=after.cv_rms_k,
                         worst_before=ad.worst.ratio, worst_after=after.worst.ratio)
    return wound, replace(ref, instrument=wound.instrument, steps=ref.steps + (step,),
                          adequacy=after, stopped=(
                              f"{ref.stopped}; the coil wound in layers: the drift agrees "
                              f"(drift cost {fitted.stages['drift'].stated_cost:.1f} -> "
                              f"{wound.stages['drift'].stated_cost:.1f})"))


def _refit(ref: Refinement, runs: Sequence[Run], base_free, stages, fit_kwargs
           ) -> FitResult | None:
    """Both stages fitted again on the structure ``ref`` ended with, its new numbers free
    beside the default set (or ``base_free``); None when it made no change."""
    if not ref.steps:
        return None
    new_paths = [p for s in ref.steps for p in s.params
                 if not (p.startswith("thermometers.") and ".nodes." in p)]
    free = (default_free(ref.instrument, stages) if base_free is None
            else expand_paths(ref.instrument, list(base_free)))
    free = list(dict.fromkeys(free + [p for p in new_paths if p not in free]))
    return fit_model(ref.instrument, runs, free=free, **fit_kwargs)


def _drift_refuses(lumped: FitResult, wound: FitResult) -> str:
    """Why the drift refuses a wound coil the thermometers adopted, in words; empty when it
    agrees.

    The thermometers see the coil's faces; the gyro reads its whole radial field through the
    Shupe integral.  The wound fit is kept when its drift stage explains the gyro's dwells
    better than the lumped fit's by Akaike's criterion: cost_w + k_w < cost_l + k_l, the
    stages' costs 0.5 chi^2 in the channels' stated noise with their prior rows
    (:attr:`nfs.fit.stage.StageReport.stated_cost`) and k their free numbers (Akaike 1974,
    IEEE Trans. Autom. Control 19(6) 716: AIC = 2k + chi^2)."""
    a, b = lumped.stages["drift"], wound.stages["drift"]
    aic_l = a.stated_cost + len(a.free)
    aic_w = b.stated_cost + len(b.free)
    if aic_w < aic_l:
        return ""
    return (f"the coil wound in layers fits the held-out thermometers as well but not the drift "
            f"(drift cost {b.stated_cost:.1f} with {len(b.free)} numbers against "
            f"{a.stated_cost:.1f} with {len(a.free)} lumped): kept lumped")
