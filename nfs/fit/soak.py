"""Thermometer offsets anchored by the soak before power-on.

A start-up run begins with the unpowered instrument soaked in the chamber at T0 until uniform
(docs/physics.md section 1): at t = 0 every node, so every thermometer's sensed temperature, is at
T0.  A thermometer's reading there is T0 + offset (+ noise, quantisation).  Over the first W
seconds (:data:`DEFAULT_WINDOW_S`) the instrument already warms; the model predicts the shape
of that warming, w(t) = m(t) - T0 with m the model's noise-free, offset-free reading through
the thermometer's lag, but the unit may warm faster or slower than the model (a preset is not
the unit).  So each run's readings y are fitted by linear least squares with

    y(t) = T0 + offset + a w(t),    t < W                                           [degC]

(a free: the model's shape, the unit's amplitude), and the offset is averaged over the runs.
Fitting 60 s of 1 Hz readings beats down the white noise; the quantisation step (0.0625 K) is
dithered by the noise and by the warming, and averaging over the runs (each at another T0)
spreads the remaining rounding error.  A run whose estimate lies more than ``tolerance_k``
from 0 was most likely not soaked (or its T0 in the header is wrong): it is reported by name
and left out of the anchor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Mapping, Sequence

import numpy as np

import thermal

from ..effects.thermometer import THERMOMETERS
from ..errors import InputError
from ..conditions import conditions_from_run
from ..heat import thermal_power
from ..instrument import Instrument
from ..run import Run
from ..sensors import thermometer_reading
from .prior import Prior
from .start_state import StartModel, soak_history, start_basis, start_prior

__all__ = ["DEFAULT_WINDOW_S", "DEFAULT_SOAK_TOLERANCE_K", "SoakAnchor", "soak_offsets",
           "anchor_offsets"]

#: Length of the window after power-on whose readings anchor the offsets [s].
DEFAULT_WINDOW_S = 60.0

#: A run whose first readings sit further than this from T0 (after the model's warming) was
#: not soaked [K].
DEFAULT_SOAK_TOLERANCE_K = 2.0

_RNG = np.random.default_rng(0)   # never drawn from: the model reading is noise-free


@dataclass(frozen=True)
class SoakAnchor:
    """Thermometer offsets read from the first seconds of soaked runs."""

    offset_c: dict[str, float]
    """Offset of each thermometer (``fog``, ``acc_x``, ``acc_y``) [K], mean over the soaked
    runs; absent when no run was soaked."""
    stderr_c: dict[str, float]
    """Standard error of each offset [K]: the scatter over runs / sqrt(runs), floored at the
    quantisation and noise limit of the readings averaged."""
    per_run: dict[str, dict[str, float]]
    """{run name: {thermometer: offset estimate [K]}}, every run."""
    unsoaked: tuple[str, ...]
    """Runs whose first readings disagree with T0 by more than the tolerance."""
    window_s: float
    """The window after power-on averaged [s]."""
    warnings: tuple[str, ...]
    """One line per run that was not soaked."""


def _model_readings(inst: Instrument, run: Run, n: int) -> dict[str, np.ndarray]:
    """Noise-free, offset-free model readings of the first n samples of ``run``."""
    cond = conditions_from_run(run)
    t = cond.time_s[:n]
    moving = np.asarray(run["moving"], dtype=float)[:n] > 0.5
    powered = cond.powered(t)
    power, _, _ = thermal_power(inst, t, moving, powered)
    ambient = cond.start_temperature_c if cond.chamber_c is None else cond.chamber_c(t)
    th = thermal.simulate(inst.network, t, ambient_c=ambient,
                          initial_c=cond.start_temperature_c, power_w=power,
                          ambient_hold="first-order")
    out = {}
    for name in THERMOMETERS:
        model = replace(inst.thermometers[name], noise_c=0.0, quantum_c=0.0, offset_c=0.0)
        transforms = [(lambda y, e=e: e.spec.function(y, t, **e.params))
                      for e in inst.effects
                      if e.spec.kind == "thermometer" and e.params.get("thermometer") == name]
        sensed = model.sensed(th.temperature_c, tuple(th.node_names))
        out[name] = thermometer_reading(sensed, t, model, _RNG, transforms)
    return out


def _start_spread(inst: Instrument, run: Run, start: StartModel | None
                  ) -> dict[str, tuple[float, float]]:
    """Per thermometer, the prior (centre, standard deviation) [K] of what the run's start
    puts on its sensed temperature at power-on (:mod:`nfs.fit.start_state`)."""
    if start is None:
        return {name: (0.0, 0.0) for name in THERMOMETERS}
    net = inst.network
    basis = start_basis(net, start.n_slow, start.fast)
    centre, width = start_prior(net, basis, run.meta.start_temperature_c, soak_history(run),
                                start)
    out = {}
    for name in THERMOMETERS:
        seen = inst.thermometers[name].sensed(basis.T, net.node_names)   # (k,)
        out[name] = (float(seen @ centre), float(np.sqrt(np.sum((seen * width) ** 2))))
    return out


def soak_offsets(inst: Instrument, runs: Sequence[Run], *, window_s: float = DEFAULT_WINDOW_S,
                 tolerance_k: float = DEFAULT_SOAK_TOLERANCE_K,
                 start: StartModel | None = None) -> SoakAnchor:
    """Each thermometer's offset from the first ``window_s`` of every run (module docstring).

    Parameters
    ----------
    inst : Instrument
        The model whose shape of warming over the window is fitted (its amplitude is free).
    runs : sequence of Run
        Runs with ``time_s``, ``moving`` and the three thermometer columns.
    window_s : float
        Window after power-on [s] (> 0; at least one sample is used).
    tolerance_k : float
        A run whose estimate of any thermometer exceeds this in magnitude is reported as not
        soaked and left out [K].
    start : StartModel, optional
        The start of each run is not T0 everywhere but estimated by the fit
        (:mod:`nfs.fit.start_state`): each run's estimate has the prior centre of its
        start's sensed deviation taken off, and the anchor's standard error takes in the
        prior's spread of it, averaged over the runs (without a soak history the anchor is
        then a weak one, as it should be: an unfinished soak looks like an offset at
        power-on).

    Returns
    -------
    SoakAnchor
    """
    if not window_s > 0:
        raise InputError(f"soak window must be > 0 s, got {window_s}")
    per_run: dict[str, dict[str, float]] = {}
    n_used: dict[str, int] = {}
    spread: dict[str, dict[str, tuple[float, float]]] = {}
    unsoaked, warnings = [], []
    for run in runs:
        for col in ("time_s", "moving", *THERMOMETERS.values()):
            if col not in run.columns:
                raise InputError(f"run '{run.name}' has no column '{col}', which the soak "
                                 "anchor of the thermometer offsets needs", file=run.path,
                                 column=col)
        t = np.asarray(run["time_s"], dtype=float)
        n = max(1, int(np.count_nonzero(t - t[0] < window_s)))
        model = _model_readings(inst, run, n)
        spread[run.name] = _start_spread(inst, run, start)
        est = {}
        t0_c = run.meta.start_temperature_c
        for name, col in THERMOMETERS.items():
            y = np.asarray(run[col], dtype=float)[:n]
            ok = np.isfinite(y)
            if not ok.any():
                est[name] = math.nan
                continue
            warming = model[name][ok] - t0_c
            # columns 1 and w(t); lstsq gives the plain mean when the model predicts no warming
            design = np.column_stack([np.ones(warming.size), warming])
            coef, *_ = np.linalg.lstsq(design, y[ok] - t0_c, rcond=None)
            est[name] = float(coef[0]) - spread[run.name][name][0]
        per_run[run.name] = est
        n_used[run.name] = n
        bad = {k: v for k, v in est.items() if abs(v) > tolerance_k}
        if bad:
            unsoaked.append(run.name)
            worst = max(bad, key=lambda k: abs(bad[k]))
            warnings.append(
                f"run '{run.name}' was not soaked at T0 = {run.meta.start_temperature_c:g} C: "
                f"its {worst} thermometer starts {bad[worst]:+.2f} K from the model's soaked "
                f"reading (tolerance {tolerance_k:g} K); left out of the offset anchor")
    offset, stderr = {}, {}
    soaked = [r for r in per_run if r not in unsoaked]
    for name in THERMOMETERS:
        vals = np.array([per_run[r][name] for r in soaked])
        vals = vals[np.isfinite(vals)]
        if not vals.size:
            continue
        m = inst.thermometers[name]
        n_samples = float(np.mean([n_used[r] for r in soaked]))
        # floor: the rounding error of a reading that sits still within one step is not
        # beaten down by averaging over one run, only over runs (q / sqrt(12) each)
        floor = math.hypot(m.quantum_c / math.sqrt(12.0),
                           m.noise_c / math.sqrt(n_samples)) / math.sqrt(vals.size)
        scatter = float(np.std(vals, ddof=1) / math.sqrt(vals.size)) if vals.size > 1 else 0.0
        start_sd = math.sqrt(float(np.mean([spread[r][name][1] ** 2 for r in soaked]))
                             / vals.size)
        offset[name] = float(np.mean(vals))
        stderr[name] = math.hypot(max(scatter, floor), start_sd)
    return SoakAnchor(offset_c=offset, stderr_c=stderr, per_run=per_run,
                      unsoaked=tuple(unsoaked), window_s=float(window_s),
                      warnings=tuple(warnings))


def anchor_offsets(prior: Prior, start: Mapping[str, float], anchor: SoakAnchor,
                   prior_scale: float = 1.0) -> tuple[Prior, dict[str, float]]:
    """``prior`` and ``start`` with each free thermometer offset centred on the soak anchor.

    The prior width of an anchored offset becomes the anchor's standard error (times
    ``prior_scale``), and the fit starts there.  Offsets the anchor has no value for (no
    soaked run) keep the prior they had.
    """
    start = dict(start)
    for name, off in anchor.offset_c.items():
        path = f"thermometers.{name}.offset_c"
        if path in prior.paths:
            prior = prior.with_centre(
                path, off, anchor.stderr_c[name] * prior_scale,
                f"soak anchor: mean of the first {anchor.window_s:g} s of "
                f"{len(anchor.per_run) - len(anchor.unsoaked)} soaked run(s) minus T0")
            start[path] = off
    return prior, start
