"""Add a candidate effect to a model and refit it (``nfs diagnose --apply NAME[:TARGET]``)."""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from ..effects import get_effect
from ..errors import NfsError
from ..instrument import Instrument
from ..run import Run
from .candidates import FAST_KINDS, Candidate, effect_of, split_parameters, targets
from .columns import (PreparedRun, bare_instrument, fit_shapes, model_drift_paths,
                     prepare_runs, startup_heading_rmse)
from ..fit.start_state import StartModel
from ..fit.thermal_residual import DEFAULT_START, start_states
from ..fit.drift_residual import drift_context, model_drift_dph, prepare_drift
from ..fit.calibration import DEFAULT_DECIMATE_S, fit_model
from ..fit.fit_result import FitResult
from ..fit.free_set import default_free

__all__ = ["apply_candidate", "fit_candidate"]

#: Start value of a thermal effect's time constant [s] (the thermal fit refines it).
_THERMAL_STARTS = {"tau": 20.0}


def fit_candidate(inst: Instrument, runs: Sequence[Run], name: str,
                  target: str | None = None, *, decimate_s: float = DEFAULT_DECIMATE_S,
                  start_state: StartModel | None = DEFAULT_START,
                  start_c: Mapping[str, np.ndarray] | None = None) -> FitResult:
    """Add effect ``name`` (on ``target``) to ``inst`` and refit: the fit (its
    ``instrument`` the new model), as :func:`apply_candidate` does without its before/after
    report (what a rival of :mod:`nfs.design` needs).  ``start_c``: the start states of
    ``inst`` estimated already (a fit's); a gyro or accelerometer effect leaves the network
    as it is, so they serve its drift fit too."""
    runs = list(runs)
    if not runs:
        raise NfsError("a candidate needs runs to be fitted to: none given")
    spec = get_effect(name)  # EffectError (an NfsError) listing the valid names
    valid = targets(spec, inst, runs)
    if target not in valid:
        shown = ", ".join("(none)" if v is None else v for v in valid) or "(none)"
        raise NfsError(f"effect '{name}' has no target '{target}'; valid targets: {shown}")
    if any(e.name == name and e.target_value == target for e in inst.effects):
        raise NfsError(f"the model already has '{name}'" + (f" on '{target}'" if target else ""))
    coefs, shapes, missing = split_parameters(spec)
    c = Candidate(name, target, spec.kind, tuple(coefs), tuple(shapes), tried=True)
    starts: dict[str, float] = {k: 0.0 for k in coefs}
    if spec.kind in FAST_KINDS:
        if start_c is None:
            start_c = start_states(inst, runs, decimate_s, start_state)
        preps, _ = prepare_runs(inst, runs, decimate_s, start_c=start_c)
        best, _ = fit_shapes(c, preps, bare_instrument(inst))
        starts.update(best)
    else:
        for s in shapes:
            starts[s] = _THERMAL_STARTS.get(s, (spec.parameter(s).grid or (1.0,))[0])
    e = effect_of(c, starts)
    new = inst.with_effects(list(inst.effects) + [e])
    new_paths = [f"effects.{e.label}.{p}" for p in coefs + shapes]
    if spec.kind in FAST_KINDS:
        result = fit_model(new, runs, free=model_drift_paths(inst) + new_paths, stages=("drift",),
                           decimate_s=decimate_s, start_state=start_state, start_c=start_c)
    else:
        free = list(dict.fromkeys(default_free(new) + new_paths))
        result = fit_model(new, runs, free=free, stages=("thermal", "drift"),
                           decimate_s=decimate_s, start_state=start_state)
    return result


def apply_candidate(inst: Instrument, runs: Sequence[Run], name: str,
                    target: str | None = None, *, decimate_s: float = DEFAULT_DECIMATE_S,
                    start_state: StartModel | None = DEFAULT_START,
                    start_c: Mapping[str, np.ndarray] | None = None
                    ) -> tuple[Instrument, FitResult, dict[str, Any]]:
    """Add effect ``name`` (on ``target``) to ``inst``, refit, and report before/after.

    Gyro and accelerometer effects: the drift stage refits the model's drift coefficients and
    the new effect's coefficients and shape parameters (shapes started at the best point of
    their registered grids, :func:`~nfs.diagnose.candidates.shape_grid`).  Thermal and
    thermometer effects: both stages, default free set plus the new effect's
    parameters.  Returns (new instrument, FitResult, report) where the report holds
    ``rms_before``/``rms_after`` per channel (before = the model as given) and the pooled
    start-up ``heading_rmse_before_deg``/``heading_rmse_after_deg``.  Each run's start is
    estimated as :func:`fit_model` does (``start_state``).

    Raises NfsError for an unknown effect or target (listing the valid ones) or an effect
    the model already has on that target.
    """
    runs = list(runs)
    result = fit_candidate(inst, runs, name, target, decimate_s=decimate_s,
                           start_state=start_state, start_c=start_c)
    fitted = result.instrument
    start_c = result.start_c or start_states(fitted, runs, decimate_s, start_state)

    def heading(model: Instrument) -> float:
        preps_m = []
        full = []
        for run in runs:
            rd = prepare_drift(run, decimate_s, False, "raw")
            ctx = drift_context(model, rd, start_c.get(run.name))
            p = PreparedRun(run, rd, ctx, rd.cond.latitude_deg, rd.measured["drift_dph"],
                      np.zeros(0), np.zeros((0, 0)), np.zeros((0, 0)))
            preps_m.append(p)
            full.append(model_drift_dph(model, ctx, p.lat))
        return startup_heading_rmse(preps_m, full)

    report = {"effect": name, "target": target, "rms_before": dict(result.rms_before),
              "rms_after": dict(result.rms_after),
              "heading_rmse_before_deg": heading(inst),
              "heading_rmse_after_deg": heading(fitted), "warnings": list(result.warnings)}
    return fitted, result, report
