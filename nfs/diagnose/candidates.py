"""The candidates of :func:`nfs.diagnose.diagnose`: every registered effect the model lacks.

A candidate is one effect on one target (a node, an accelerometer axis, a thermometer, a
measured ``aux_*`` column).  Its float parameters split into *coefficients* (entering the
model linearly, started at 0) and *shape* parameters (time constants, angles, periods, and
parameters registered with ``shape=True`` such as shupe_stress's c_m:
:attr:`~nfs.effects.Parameter.nonlinear`), chosen on the grid each effect registers for
them (:attr:`~nfs.effects.Parameter.grid`, :func:`shape_grid`) or held at their default.
Thermal and thermometer candidates are linearised at zero, so their time constants become
coefficients (:mod:`nfs.diagnose.columns`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Sequence

from .. import ranges
from ..effects import available_effects, get_effect, make_effect
from ..effects.registry import EffectInstance, EffectSpec
from ..effects.thermometer import THERMOMETERS
from ..instrument import Instrument
from ..run import Run

__all__ = ["Candidate", "candidates", "FAST_KINDS", "CONSTANT_HEAT", "shape_grid",
           "target_parameter", "split_parameters", "aux_columns", "targets", "effect_of"]

#: Kinds scored on window means at rest (gyro: the drift; accelerometer: its own axis's
#: readings); the others on the thermometers.
FAST_KINDS = ("gyro", "accelerometer")

_FIXED_UNITS = ("degC", "channel unit")


@dataclass(frozen=True)
class Candidate:
    """One effect on one target that the model lacks."""

    effect: str
    """Registry name."""
    target: str | None
    """Value of the effect's target parameter (node, axis, thermometer, channel) or None."""
    kind: str
    """The effect's kind (gyro, accelerometer, thermal, thermometer)."""
    coefficients: tuple[str, ...]
    """Parameters that enter linearly (start 0)."""
    shapes: tuple[str, ...]
    """Nonlinear parameters, chosen on their registered grids (:func:`shape_grid`)."""
    tried: bool
    """False when :func:`~nfs.diagnose.diagnose` does not score it (see ``reason``)."""
    reason: str = ""
    """Why it is not tried."""

    @property
    def label(self) -> str:
        """``effect`` or ``effect:target``."""
        return self.effect if self.target is None else f"{self.effect}:{self.target}"

    @property
    def channel(self) -> str:
        """Where it is scored: ``drift_dph``, ``acc_x_g`` / ``acc_y_g`` (an accelerometer
        effect, on its axis's readings) or ``thermometers`` (the three, in K)."""
        if self.kind == "accelerometer":
            return f"acc_{self.target}_g"
        return "drift_dph" if self.kind in FAST_KINDS else "thermometers"


def target_parameter(spec: EffectSpec) -> str | None:
    """The parameter that says where ``spec`` acts: its declared target, or ``channel`` for
    an effect (a user's) with a ``channel`` name parameter and no declared target."""
    if spec.target is not None:
        return spec.target
    if any(p.name == "channel" and p.type is str for p in spec.parameters):
        return "channel"
    return None


def split_parameters(spec: EffectSpec) -> tuple[list[str], list[str], list[str]]:
    """(coefficients, shapes, parameters without a start value) of ``spec``: a required
    parameter of a fixed unit, or a shape parameter with neither a grid nor a default."""
    coefs, shapes, missing = [], [], []
    for p in spec.parameters:
        if p.type is not float or p.name == spec.target:
            continue
        if p.unit in _FIXED_UNITS:
            if p.required:
                missing.append(p.name)
        elif p.nonlinear:
            if p.grid is None and p.default is None:
                missing.append(p.name)
            else:
                shapes.append(p.name)
        else:
            coefs.append(p.name)
    return coefs, shapes, missing


def aux_columns(runs: Sequence[Run]) -> tuple[list[str], dict[str, list[str]]]:
    """(``aux_*`` columns present in every run, {column: runs that lack it} for the others)."""
    names = list(dict.fromkeys(c for r in runs for c in r.columns if c.startswith("aux_")))
    full = [c for c in names if all(c in r.columns for r in runs)]
    partial = {c: [r.name for r in runs if c not in r.columns] for c in names if c not in full}
    return full, partial


def targets(spec: EffectSpec, inst: Instrument, runs: Sequence[Run]) -> list[str | None]:
    """The targets of ``spec`` a candidate can take with ``inst`` and ``runs``."""
    t = target_parameter(spec)
    if t is None:
        return [None]
    if t == "node":
        par = spec.parameter(t)
        return ([None] if not par.required else []) + list(inst.target_nodes)
    if t == "axis":
        return ["x", "y"]
    if t == "thermometer":
        return list(THERMOMETERS)
    if t == "channel":
        return list(aux_columns(runs)[0])
    opt = spec.parameter(t).optional
    return [None] if opt else []


#: Effects that add a constant power at their node.
CONSTANT_HEAT = ("heat_source",)


def _idle_dissipating_part(node) -> bool:
    """A part the table of ranges says always dissipates (its typical power starts above
    0 W: electronics, a board, a QFA) whose power a fit took to 0 W.  A heat source at a
    part with power of its own is that power again, which the diagnosis's span check finds
    (:func:`nfs.diagnose.columns.same_signature` against the fit's free set); at 0 W the
    power is not in that free set (:func:`nfs.fit.default_free` frees non-zero powers), so
    the check cannot see it and the candidate would name what the fit's prior held back."""
    if node.power_w != 0.0:
        return False
    row = ranges.find(f"thermal.nodes.{node.name}.power_w")
    return row is not None and row.typical[0] > 0.0


def candidates(inst: Instrument, runs: Sequence[Run]) -> list[Candidate]:
    """Every registered effect on every target that ``inst`` does not have.

    Targets: ``node`` -> every thermal node (a wound coil's faces, not its interior layers:
    :attr:`~nfs.instrument.Instrument.target_nodes`), and None (the effect's default node, e.g. the
    coil mean) when the node parameter is optional; ``axis`` -> x, y; ``thermometer`` ->
    fog, acc_x, acc_y; ``channel`` -> every ``aux_*`` column present in all runs, declared
    under the model's ``[[aux]]`` or not (a column missing from some runs gives a candidate
    with ``tried = False`` naming those runs).  Thermal and thermometer candidates are
    linearised at zero: their time constants [s] become coefficients.  Candidates
    :func:`~nfs.diagnose.diagnose` cannot score (parameters without a start value) have
    ``tried = False``.
    """
    present = set()
    for e in inst.effects:
        tp = target_parameter(e.spec)
        present.add((e.name, None if tp is None else e.params.get(tp)))
    _, partial = aux_columns(runs)
    idle = {n.name for n in inst.network.nodes if _idle_dissipating_part(n)}
    out = []
    for name in available_effects():
        spec = get_effect(name)
        if spec.kind == "null":
            continue
        coefs, shapes, missing = split_parameters(spec)
        if spec.kind not in FAST_KINDS:
            # linearised at zero (module docstring): time constants become coefficients
            coefs, shapes = coefs + [s for s in shapes if spec.parameter(s).unit == "s"], []
        for target in targets(spec, inst, runs):
            if (name, target) in present:
                continue
            reason = ""
            if spec.kind == "geometry":
                reason = ("a geometry effect: it moves the sensor axes, which the drift and "
                          "thermal fits do not model")
            elif missing:
                reason = _missing_reason(spec, missing)
            elif not coefs:
                reason = "no linear coefficient to fit"
            elif name in CONSTANT_HEAT and target in idle:
                reason = (f"{target} always dissipates power of its own "
                          f"(thermal.nodes.{target}.power_w, which the fit took to 0 W): a "
                          f"constant extra power there is that power")
            out.append(Candidate(name, target, spec.kind, tuple(coefs), tuple(shapes),
                                 tried=not reason, reason=reason))
        if target_parameter(spec) == "channel":
            for col, lacking in partial.items():
                out.append(Candidate(name, col, spec.kind, tuple(coefs), tuple(shapes),
                                     tried=False, reason=(
                                         f"column '{col}' is missing from run(s) "
                                         + ", ".join(lacking))))
    return out


def _missing_reason(spec: EffectSpec, missing: Sequence[str]) -> str:
    """Why ``spec`` is not tried when ``missing`` (of :func:`split_parameters`) have no start
    value, saying how to fix it: a shape parameter wants a grid."""
    grids = [m for m in missing if spec.parameter(m).unit not in _FIXED_UNITS]
    starts = [m for m in missing if m not in grids]
    parts = ([f"no start value for {', '.join(starts)}"] if starts else []) + [
        f"register a grid for parameter {m} of effect {spec.name}: "
        f"Parameter('{m}', '{spec.parameter(m).unit}', ..., grid=(...))" for m in grids]
    return "; ".join(parts)


def shape_grid(c: Candidate) -> list[dict[str, float]]:
    """The grid points of the shape parameters of ``c`` ([{}] when it has none): the
    product of each one's registered grid (:attr:`~nfs.effects.Parameter.grid`), or its
    default when it has none."""
    spec = get_effect(c.effect)
    pars = [spec.parameter(s) for s in c.shapes]
    values = [p.grid if p.grid is not None else (p.default,) for p in pars]
    return [dict(zip(c.shapes, v)) for v in itertools.product(*values)]


def effect_of(c: Candidate, values: dict[str, float]) -> EffectInstance:
    """The effect instance of candidate ``c`` with parameter ``values``."""
    params = dict(values)
    if c.target is not None:
        params[target_parameter(get_effect(c.effect))] = c.target
    return make_effect(c.effect, params)
