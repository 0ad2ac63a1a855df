"""What a rival predicts a run will record, and how noisy each recorded number is.

A rival's prediction of a run is its noise-free simulation (:func:`quiet`: every noise and
quantum of its sensors zeroed, no variability) reduced to the numbers a fit reads
(:class:`Prediction`), by channel:

``drift_dph``
    the drift's mean over every dwell at rest while powered [deg/h]: the gyro less the Earth
    rate along its axis (:func:`nfs.denoise.earth_rate_projection_dph`, the drift every fit
    reads; the gyro itself for a run without a true heading);
``acc_x_g``, ``acc_y_g``
    each accelerometer's mean over the same dwells [g];
``temp_fog_c``, ``temp_acc_x_c``, ``temp_acc_y_c``
    the three thermometers every ``reading_s`` while powered [degC].

The noise of each number (:func:`noise_sigma`) comes from the model's sensor noise:

- a dwell mean of the gyro over T seconds: sigma^2 = (60 N)^2 / T + B^2 [(deg/h)^2], N the
  angle random walk [deg/sqrt(h)] (IEEE Std 952-2020, the Allan deviation N / sqrt(tau)),
  B the bias instability taken whole on every dwell (the flicker floor of the Allan
  deviation is 0.664 B; its slow wander is not white, so counting it whole per dwell keeps
  the separation on the safe side);
- a dwell mean of an accelerometer: sigma = n / sqrt(2 T) [g], n the one-sided white noise
  density (:func:`nfs.noise.white_noise`);
- one thermometer reading: sigma^2 = noise^2 + q^2 / 12 [K^2], white noise and the rounding
  to the quantum q.

The simulation runs on a coarser clock than the instrument's (:data:`PREDICT_STEP_S` when
the schedule's dwell and move are multiples of it): the predictions are dwell means and
readings a minute apart, smooth on that scale; the noise is counted at the instrument's
own sample rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..denoise import earth_rate_projection_dph
from ..effects.thermometer import THERMOMETERS
from ..conditions import RunConditions
from ..experiment import simulate_run
from ..instrument import Instrument

__all__ = ["Prediction", "CHANNELS", "predict", "reduce_run", "quiet", "noise_sigma",
           "PREDICT_STEP_S", "READING_S"]

#: Channels of a prediction, in order.
CHANNELS = ("drift_dph", "acc_x_g", "acc_y_g", *THERMOMETERS.values())
#: Sample interval of the prediction's simulation [s].
PREDICT_STEP_S = 5.0
#: Interval between the thermometer readings a prediction keeps [s].
READING_S = 60.0


@dataclass(frozen=True)
class Prediction:
    """The numbers a fit reads from one run, by channel (module docstring)."""

    values: dict[str, np.ndarray]
    """Channel -> predicted numbers."""
    time_s: dict[str, np.ndarray]
    """Channel -> time of each number from power-on [s] (a dwell's end, a reading's time)."""
    span_s: dict[str, np.ndarray]
    """Channel -> the time each number averages [s] (a dwell's length; 0 for a reading)."""

    def until(self, t_end_s: float) -> "Prediction":
        """The numbers recorded by ``t_end_s`` (a shorter run is a prefix of a longer one)."""
        keep = {c: t <= t_end_s + 1e-9 for c, t in self.time_s.items()}
        return Prediction({c: v[keep[c]] for c, v in self.values.items()},
                          {c: t[keep[c]] for c, t in self.time_s.items()},
                          {c: s[keep[c]] for c, s in self.span_s.items()})


def quiet(inst: Instrument) -> Instrument:
    """``inst`` without sensor noise or quantisation: its prediction of a run."""
    g = replace(inst.gyro, arw_deg_per_rth_h=0.0, bias_instability_dph=0.0,
                rrw_deg_per_h_per_rth_h=0.0)
    a = replace(inst.accelerometers, noise_ug_per_rth_hz=0.0)
    th = {k: replace(v, noise_c=0.0, quantum_c=0.0) for k, v in inst.thermometers.items()}
    aux = tuple(replace(c, noise=0.0, walk_per_rth_s=0.0) for c in inst.aux)
    return replace(inst, gyro=g, accelerometers=a, thermometers=th, aux=aux)


def _step_s(cond: RunConditions) -> float:
    """The prediction's sample interval for ``cond``'s schedule."""
    s = cond.schedule
    whole = all(abs(x / PREDICT_STEP_S - round(x / PREDICT_STEP_S)) < 1e-9
                for x in (s.dwell_s, s.move_s))
    return PREDICT_STEP_S if whole else 1.0 / cond.sample_rate_hz


def _dwells(moving: np.ndarray, powered: np.ndarray) -> list[tuple[int, int]]:
    """(first, one past last) sample of every stretch at rest while powered."""
    ok = (~moving) & powered
    edges = np.diff(np.concatenate([[0], ok.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def reduce_run(run, step_s: float | None = None) -> Prediction:
    """The numbers a fit reads from a run (module docstring): dwell means of the gyro and
    the accelerometers at rest while powered, thermometer readings every
    :data:`READING_S`.  ``step_s``: the run's sample interval (None: from its time axis)."""
    t = np.asarray(run["time_s"], dtype=float)
    if step_s is None:
        step_s = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    moving = np.asarray(run["moving"], dtype=float) > 0.5
    powered = (np.asarray(run.columns["powered"], dtype=float) > 0.5
               if "powered" in run.columns else np.ones(t.size, dtype=bool))
    dw = _dwells(moving, powered)
    values, times, spans = {}, {}, {}
    gyro = np.asarray(run["gyro_dph"], dtype=float)
    if run.meta.true_heading_deg is not None:
        with np.errstate(invalid="ignore"):
            gyro = gyro - earth_rate_projection_dph(run)
    for ch in ("drift_dph", "acc_x_g", "acc_y_g"):
        x = gyro if ch == "drift_dph" else np.asarray(run[ch], dtype=float)
        values[ch] = np.array([np.nanmean(x[a:b]) if np.isfinite(x[a:b]).any() else np.nan
                               for a, b in dw])
        times[ch] = np.array([t[b - 1] for a, b in dw])
        spans[ch] = np.array([(b - a) * step_s for a, b in dw])
    every = max(1, int(round(READING_S / step_s)))
    idx = np.flatnonzero(powered)
    idx = idx[(np.round((t[idx] - t[0]) / step_s).astype(int) % every) == 0]
    for col in THERMOMETERS.values():
        values[col] = np.asarray(run[col], dtype=float)[idx]
        times[col] = t[idx]
        spans[col] = np.zeros(idx.size)
    return Prediction(values, times, spans)


def predict(inst: Instrument, cond: RunConditions, *, native: bool = False) -> Prediction:
    """``inst``'s noise-free prediction of the run ``cond`` (module docstring).

    ``native``: on the run's own samples (a replayed run, number for number the same
    reduction as its measurement) instead of the coarser clock.
    """
    model = quiet(inst)
    if native:
        c = replace(cond, variability=None, seed=0)
        step = 1.0 / cond.sample_rate_hz
    else:
        step = _step_s(cond)
        c = replace(cond, sample_rate_hz=1.0 / step, variability=None, seed=0)
        if c.motion is not None:          # a replayed run: its own samples, thinned
            k = max(1, int(round(step * cond.sample_rate_hz)))
            t, pos, mov = (np.asarray(x)[::k] for x in c.motion)
            c = replace(c, motion=(t, pos, mov))
            step = float(np.median(np.diff(t))) if t.size > 1 else step
    return reduce_run(simulate_run(model, c).run, step)


def noise_sigma(inst: Instrument, pred: Prediction) -> dict[str, np.ndarray]:
    """Standard deviation of each number of ``pred`` under ``inst``'s sensor noise
    (module docstring), by channel."""
    g, a = inst.gyro, inst.accelerometers
    out = {}
    span = np.maximum(pred.span_s["drift_dph"], 1e-9)
    out["drift_dph"] = np.sqrt((60.0 * g.arw_deg_per_rth_h) ** 2 / span
                               + g.bias_instability_dph ** 2)
    for ch in ("acc_x_g", "acc_y_g"):
        out[ch] = a.noise_ug_per_rth_hz * 1e-6 / np.sqrt(2.0 * np.maximum(pred.span_s[ch],
                                                                          1e-9))
    for name, col in THERMOMETERS.items():
        m = inst.thermometers[name]
        out[col] = np.full(pred.values[col].shape,
                           math.sqrt(m.noise_c ** 2 + m.quantum_c ** 2 / 12.0))
    return out
