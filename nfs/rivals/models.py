"""Rival models: the explanations a diagnosis could not tell apart, each fitted to the runs.

A rival is the model with one explanation added and refitted to the runs already taken,
with its parameter uncertainty (:class:`Rival`).  Explanations, by label:

``model``
    the model as given (fitted already: ``nfs fit``), its parameters' uncertainty from a
    refit of its drift stage;
``EFFECT`` or ``EFFECT:TARGET``
    a registered effect added and refitted (:func:`nfs.diagnose.fit_candidate`: the drift
    stage for a gyro or accelerometer effect, both stages for a thermal or thermometer one);
    heat at a node no thermometer reads (``heat_source:coil_inner``) is fitted where it shows,
    :func:`unseen_heat_rival`;
``a rate term on every node``
    the discretised Shupe integral, ``shupe_rate`` on every node of the network with its
    own coefficient, the drift stage refitted (:mod:`nfs.diagnose.drift_structure`);
a structural alternative's name (``fog thermometer share of electronics``, ``split
coil_inner``, ``link electronics-coil_inner``, ...)
    the change of the thermal structure of :func:`nfs.fit.structural_alternatives`,
    its new numbers fitted on the thermometers (:func:`nfs.fit.thermal_adequacy`), then
    both stages of the model refitted on the new structure.

Parameter uncertainty.  Each stage of the refit gives the standard errors and the
correlation matrix of its free parameters (the linearised posterior,
:mod:`nfs.fit.stage`); :meth:`Rival.draws` samples the parameters from that Gaussian,
stage by stage, clipped to the fit's box.  A parameter the runs do not determine (infinite
standard error) is drawn from its prior when it has one, else held.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from ..effects import get_effect, make_effect
from ..errors import EffectError, NfsError
from ..instrument import Instrument
from ..run import Run
from ..diagnose.apply import fit_candidate
from ..diagnose.candidates import FAST_KINDS, targets
from ..diagnose.columns import model_drift_paths
from ..diagnose.result import RATE_ALTERNATIVE
from ..fit import (default_free, fit_model, get_param, set_params, structural_alternatives,
                   thermal_adequacy)
from ..fit.calibration import check_fit_keywords
from ..fit.fit_result import FitResult
from ..fit.thermal_residual import DEFAULT_START

__all__ = ["Rival", "MODEL", "RATE_ALTERNATIVE", "check_label", "rival_model", "rival_models",
           "unseen_nodes", "unseen_heat_rival"]

#: The label of the model as given.
MODEL = "model"
#: Thermal effects whose one power heats one node, fitted as :func:`unseen_heat_rival` when
#: no thermometer reads their node.
HEAT_EFFECTS = ("heat_source", "motor_heat")
#: Start of an unseen heat's power [W]: inside the few tenths of a W to a few W of heat a
#: coil or a motor releases (docs/physics.md section 2); the drift stage moves it.
UNSEEN_HEAT_START_W = 0.5


@dataclass(frozen=True)
class Rival:
    """One explanation of the runs, fitted, with its parameter uncertainty."""

    label: str
    """The explanation (module docstring)."""
    description: str
    """One sentence: what it adds or changes."""
    instrument: Instrument
    """The fitted instrument."""
    fit: FitResult | None
    """The fit that made it (standard errors, correlations, priors); None: no uncertainty."""
    n_added: int = 0
    """How many numbers it fits beyond the model as given (the new effect's coefficients,
    the rate term's one per node, the structural alternative's new numbers): the price a
    decision charges it (:mod:`nfs.rivals.evidence`)."""
    thermal_refit: bool = False
    """Whether its fit refits the thermal stage (a thermal or thermometer effect, a
    structural alternative) rather than the drift stage alone."""
    rejected: str = ""
    """What the runs asked of it that is not physical and was not granted, in words (a heat
    source's power whose sign the drift rejects, held at 0 W); empty when nothing."""

    def draws(self, n: int, rng: np.random.Generator) -> list[Instrument]:
        """``n`` instruments with parameters drawn from the fit's linearised posterior
        (module docstring); the fitted instrument itself when there is no fit."""
        if self.fit is None or n <= 0:
            return [self.instrument] * max(n, 0)
        fr = self.fit
        blocks = []
        for stage in fr.stages.values():
            paths = [p for p in stage.free if p in fr.params]
            if not paths:
                continue
            sd = np.array([_width(fr, p) for p in paths])
            corr = (np.asarray(stage.correlation, dtype=float)
                    if stage.correlation is not None else np.eye(len(paths)))
            idx = [list(stage.free).index(p) for p in paths]
            corr = corr[np.ix_(idx, idx)]
            # the determined parameters keep their correlations; a prior-only one is drawn
            # alone (its correlation rows are zero)
            corr = corr + np.diag(np.where(np.diag(corr) == 0.0, 1.0, 0.0))
            cov = corr * np.outer(sd, sd)
            blocks.append((paths, _factor(cov)))
        out = []
        for _ in range(n):
            values: dict[str, float] = {}
            for paths, chol in blocks:
                x = chol @ rng.standard_normal(len(paths))
                for p, dx in zip(paths, x):
                    lo, hi = fr.bounds.get(p, (-math.inf, math.inf))
                    values[p] = float(np.clip(fr.params[p] + dx, lo, hi))
            out.append(set_params(self.instrument, values))
        return out

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready summary: label, description, fitted parameters and errors."""
        fr = self.fit
        return {"label": self.label, "description": self.description,
                "instrument": self.instrument.name, "n_added": self.n_added,
                "params": {} if fr is None else {p: float(v) for p, v in fr.params.items()},
                "stderr": {} if fr is None else {p: (float(v) if math.isfinite(v) else None)
                                                 for p, v in fr.stderr.items()}}


def _width(fr: FitResult, path: str) -> float:
    """The standard deviation a draw takes for ``path``: its standard error, else its
    prior width, else 0 (held)."""
    se = fr.stderr.get(path, math.inf)
    if math.isfinite(se):
        return float(se)
    prior = fr.prior_sigma.get(path, math.inf)
    return float(prior) if math.isfinite(prior) else 0.0


def _factor(cov: np.ndarray) -> np.ndarray:
    """A square root L of a covariance (L L^T = cov), through its eigendecomposition so that a
    semi-definite one (rounding) is accepted."""
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    return v * np.sqrt(np.clip(w, 0.0, None))


def _rate_rival(inst: Instrument, runs: Sequence[Run], **fit_kw) -> Rival:
    """``shupe_rate`` on every node with its own coefficient, the drift stage refitted (a
    wound coil's faces, not its interior layers, whose rates are all but collinear)."""
    added = []
    have = {e.label for e in inst.effects}
    for node in inst.target_nodes:
        e = make_effect("shupe_rate", {"k_s": 0.0, "node": node})
        if e.label not in have:
            added.append(e)
    new = inst.with_effects(list(inst.effects) + added)
    free = model_drift_paths(inst) + [f"effects.{e.label}.k_s" for e in added]
    fr = fit_model(new, runs, free=free, stages=("drift",), **fit_kw)
    return Rival(RATE_ALTERNATIVE, "a Shupe rate term on every node of the network (the "
                 "discretised Shupe integral), coefficients fitted", fr.instrument, fr,
                 len(added))


def _structure_rival(inst: Instrument, runs: Sequence[Run], label: str, alt,
                     **fit_kw) -> Rival:
    """A structural alternative: its numbers fitted on the thermometers, then both stages."""
    start_state = fit_kw.get("start_state", DEFAULT_START)
    ad = thermal_adequacy(inst, runs, alternatives=[alt], start_state=start_state)
    scored = next((a for a in ad.alternatives if a.name == label), None)
    changed = scored.instrument if scored is not None else alt.build(alt.start)
    fr = fit_model(changed, runs, free=default_free(changed), **fit_kw)
    return Rival(label, alt.description, fr.instrument, fr, len(alt.free), True)


def unseen_nodes(inst: Instrument) -> tuple[str, ...]:
    """The nodes of ``inst`` that no thermometer reads (weight 0 in every one): where heat
    shows only through what it does to the gyro."""
    read = {n for th in inst.thermometers.values() for n, w in th.nodes.items() if w != 0.0}
    return tuple(n for n in inst.target_nodes if n not in read)


def _drift_cost(fr: FitResult) -> float:
    """The cost of a fit's drift stage in the channels' stated noise, its prior rows
    included (:attr:`nfs.fit.stage.StageReport.stated_cost`): what two fits of the same
    numbers are compared by when the decisions read the dwell channels."""
    return fr.stages["drift"].stated_cost


def unseen_heat_rival(inst: Instrument, runs: Sequence[Run], label: str, **fit_kw) -> Rival:
    """Heat ``label`` (``heat_source:NODE`` or ``motor_heat:NODE``) at a node no thermometer
    reads, its power P [W] fitted on both the thermometers and the drift.

    Such heat reaches the thermometers only through the node's neighbours, while the drift
    sees its rate P / C at power-on (C [J/K] the node's capacity).  Fitted as every thermal
    effect is (:func:`nfs.diagnose.fit_candidate`: the thermal stage on the thermometers,
    P among its numbers), P takes up whatever misfit the network leaves at the neighbours
    (seen on units the model does not describe: -4 W at the inner coil, the coil's capacity
    pushed to a tenth) and may never meet the drift.  So the two stages are also solved the
    other way round, from the drift:

    1. the drift stage with P and the model's drift coefficients free (the network replayed
       at each step), from P = :data:`UNSEEN_HEAT_START_W`;
    2. both stages with P held: the thermometers refit the network around the heat (the
       power the model's fit had put elsewhere moves), the node's capacity C, so the heat's
       time constant, free among the network's numbers inside its prior from the table of
       ranges (:mod:`nfs.fit.prior`: the typical range one sigma of a log-normal), which
       keeps it from the bound a refit without a prior pushed it to.  Measured on the
       default instrument, three 1 h runs of its nominal world: 0.5 W at the spool gives
       P 0.60 +- 0.05 W, C 73 +- 28 J/K for 110 (P the same with C held); 1 W at the board
       P 1.5 +- 0.8 W, C 378 +- 11 J/K for 380 (C held: P 0.3 +- 3.7 W).

    The two fits have the same numbers; the one with the lower cost of its drift stage
    (:func:`_drift_cost`) is the rival: it refits the thermal stage, so a decision against a
    rival that does not reads the dwell channels alone (:func:`nfs.rivals.decide.pair_channels`),
    and the fit kept is the one that explains them best, the thermometers having had their
    say on the network in both.  (On 2 of 7 units of the independent generator with heat in
    the coil both fits lose to the model as it is on the drift, by e^32 and e^127: the
    model's two-node coil does not describe their heat.)  A heat source is a source: a fit with
    P < 0 is no such explanation and is not kept (the drift-first one is then held at
    P = 0).  The drift-first fit's P carries the standard error of step 1 (its
    draws hold P).  The price is one number.
    """
    name, _, node = label.partition(":")
    e = make_effect(name, {"node": node, "power": UNSEEN_HEAT_START_W})
    current = inst.with_effects(list(inst.effects) + [e])
    power = f"effects.{e.label}.power"
    held = (power,)

    first = fit_model(current, runs, free=model_drift_paths(current) + [power],
                      stages=("drift",), **fit_kw)
    p_se = float(first.stderr.get(power, math.inf))
    start = first.instrument
    rejected = ""
    if first.params[power] < 0.0:
        rejected = (f"the drift asks for {first.params[power]:.3g} +- {p_se:.2g} W at {node} "
                    "(heat taken away: a sink, not a source), held at 0 W")
        start, p_se = set_params(current, {power: 0.0}), math.inf
    around = fit_model(start, runs, free=[p for p in default_free(start) if p not in held],
                       **fit_kw)
    fits = [replace(around, params={**around.params, power: get_param(start, power)},
                    stderr={**around.stderr, power: p_se})]
    usual = fit_candidate(inst, runs, name, node, **_apply_kw(fit_kw))
    if usual.params[power] >= 0.0:
        fits.append(usual)
    fr = min(fits, key=_drift_cost)
    return Rival(label, f"adds {name} at {node}, where no thermometer sits: its power fitted "
                 "on the thermometers and the drift", fr.instrument, fr, 1, True,
                 rejected if fr is fits[0] else "")


def check_label(inst: Instrument, runs: Sequence[Run], label: str) -> None:
    """Raise :class:`~nfs.errors.NfsError` naming what ``label`` can be, before any fit,
    when it is no explanation of ``inst`` on ``runs`` (module docstring)."""
    if label in (MODEL, RATE_ALTERNATIVE):
        return
    alts = [a.name for a in structural_alternatives(inst)]
    if label in alts:
        return
    name, _, target = label.partition(":")
    try:
        spec = get_effect(name)
    except EffectError:
        raise NfsError(
            f"rival '{label}' is no explanation nfs design knows: give '{MODEL}', an effect "
            f"as EFFECT or EFFECT:TARGET (nfs effects), '{RATE_ALTERNATIVE}', or a "
            f"structural alternative of this model ({', '.join(sorted(alts))})") from None
    valid = targets(spec, inst, runs)
    if (target or None) not in valid:
        shown = ", ".join("(none)" if v is None else v for v in valid) or "(none)"
        raise NfsError(f"rival '{label}': effect '{name}' has no target "
                       f"'{target or '(none)'}' on this model; valid targets: {shown}")
    if any(e.name == name and e.target_value == (target or None) for e in inst.effects):
        raise NfsError(f"rival '{label}': the model has it already (a rival adds an "
                       f"explanation the model lacks; '{MODEL}' is the model as it is)")


def rival_model(inst: Instrument, runs: Sequence[Run], label: str, **fit_kw) -> Rival:
    """The rival of one explanation ``label`` (module docstring), fitted to ``runs``.

    ``fit_kw`` go to :func:`nfs.fit.fit_model` (``start_state``, ``decimate_s``).

    Raises
    ------
    NfsError
        ``label`` names no effect, target or structural alternative of ``inst``; the
        message lists what it can be.
    """
    check_fit_keywords(fit_kw, "rival_model")
    runs = list(runs)
    if label == MODEL:
        fr = fit_model(inst, runs, free=model_drift_paths(inst), stages=("drift",),
                       **fit_kw)
        return Rival(MODEL, "the model as given", inst, fr)
    if label == RATE_ALTERNATIVE:
        return _rate_rival(inst, runs, **fit_kw)
    alts = {a.name: a for a in structural_alternatives(inst)}
    if label in alts:
        return _structure_rival(inst, runs, label, alts[label], **fit_kw)
    name, _, target = label.partition(":")
    try:
        get_effect(name)
    except EffectError:
        raise NfsError(
            f"rival '{label}' is no explanation nfs design knows: give '{MODEL}', an effect "
            f"as EFFECT or EFFECT:TARGET, '{RATE_ALTERNATIVE}', or a structural alternative "
            f"of this model ({', '.join(sorted(alts))})") from None
    if name in HEAT_EFFECTS and target in unseen_nodes(inst):
        return unseen_heat_rival(inst, runs, label, **fit_kw)
    fr = fit_candidate(inst, runs, name, target or None, **_apply_kw(fit_kw))
    own = f"effects.{label}."
    return Rival(label, f"adds the effect {label}, refitted", fr.instrument, fr,
                 sum(1 for p in fr.params if p.startswith(own)),
                 get_effect(name).kind not in FAST_KINDS)


def _apply_kw(fit_kw: dict) -> dict:
    return {k: v for k, v in fit_kw.items() if k in ("decimate_s", "start_state")}


def rival_models(inst: Instrument, runs: Sequence[Run], labels: Sequence[str],
                 **fit_kw) -> list[Rival]:
    """:func:`rival_model` of each label (at least two, all different)."""
    check_fit_keywords(fit_kw, "rival_models")
    labels = list(labels)
    if len(labels) < 2:
        raise NfsError(f"a design needs at least two rivals, got {len(labels)}: "
                       + (", ".join(labels) or "(none)"))
    if len(set(labels)) != len(labels):
        raise NfsError("the rivals must differ; got " + ", ".join(labels))
    for lab in labels:            # every label checked before the first fit
        check_label(inst, runs, lab)
    return [rival_model(inst, runs, lab, **fit_kw) for lab in labels]
