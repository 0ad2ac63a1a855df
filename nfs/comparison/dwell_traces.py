"""Two traces of a run beside the model's, for the comparison's figures: each dwell's bias
and each cycle's heading error against time.

- :class:`DwellBias` (:func:`dwell_bias`): each dwell's mean gyro rate less the Earth-rate
  projection on its axis (:func:`nfs.denoise.earth_rate_projection_dph`),

      b_j = mean over dwell j of (gyro - K Omega_ie (cos L cos A cos e + sin L sin e))   [deg/h]

  measured, and as the noise-free model predicts it on the same dwells; its 1-sigma noise
  is that of a dwell mean under the model's noise, from the model's two noisy runs a and b
  (independent noise, :mod:`nfs.comparison.compare_runs`): sqrt(mean_j (b_a,j - b_b,j)^2 / 2),
  angle random walk, bias instability and rate random walk together.
- :class:`HeadingTrace` (:func:`heading_trace`): the north finder's heading error of every
  cycle against the time the cycle ends (when its heading is output), measured and as the
  noise-free model predicts it, its 1-sigma noise from the two noisy runs the same way.

The dwells are the north finder's (complete cycles, :func:`nfs.northfind.north_find`); the
model's runs share the measured run's time base and motion, so one dwell is the same samples
in all of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..denoise import earth_rate_projection_dph
from ..docfields import document_fields
from ..northfind import NorthFindResult
from ..run import Run

__all__ = ["DwellBias", "HeadingTrace", "dwell_bias", "heading_trace"]


@document_fields
@dataclass(frozen=True)
class DwellBias:
    """Each dwell's gyro bias of one run, measured and as the model predicts it
    (:func:`dwell_bias`)."""

    run_name: str
    """Name of the run."""
    start_temperature_c: float
    """T0 of the run [degC]."""
    time_s: np.ndarray
    """Mid-time of each dwell from power-on [s]."""
    theta_deg: np.ndarray
    """Turntable angle of each dwell [deg]."""
    measured_dph: np.ndarray
    """Mean measured gyro rate less the Earth-rate projection, per dwell [deg/h]."""
    model_dph: np.ndarray
    """The same of the model's noise-free run [deg/h]."""
    noise_dph: float
    """1-sigma noise of a dwell mean under the model's noise [deg/h]."""


@document_fields
@dataclass(frozen=True)
class HeadingTrace:
    """The heading error of every cycle of one run, measured and as the model predicts it
    (:func:`heading_trace`)."""

    run_name: str
    """Name of the run."""
    start_temperature_c: float
    """T0 of the run [degC]."""
    time_s: np.ndarray
    """End of each cycle from power-on [s] (when its heading is output)."""
    measured_deg: np.ndarray
    """North-finding heading error of the measured run, per cycle [deg]."""
    model_deg: np.ndarray
    """The same of the model's noise-free run [deg]."""
    noise_deg: float
    """1-sigma heading noise of a cycle under the model's noise [deg]."""


def _dwell_means(run: Run, dwells: Sequence) -> np.ndarray:
    """Mean of gyro - projection over each dwell [deg/h] (finite samples; NaN for none)."""
    x = np.asarray(run["gyro_dph"], dtype=float) - earth_rate_projection_dph(run)
    out = np.full(len(dwells), np.nan)
    for j, d in enumerate(dwells):
        v = x[d.index]
        v = v[np.isfinite(v)]
        if v.size:
            out[j] = v.mean()
    return out


def _twin_noise(a: np.ndarray, b: np.ndarray) -> float:
    """sqrt(mean((a - b)^2) / 2) over the finite pairs: the 1-sigma noise of one draw."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    d = d[np.isfinite(d)]
    return float(np.sqrt(np.mean(d * d) / 2.0)) if d.size else math.nan


def _on_cycles(nf: NorthFindResult, other: NorthFindResult) -> np.ndarray:
    """The heading errors of ``other`` on the cycles of ``nf`` (the same end time; NaN for a
    cycle ``other`` lacks)."""
    t, t_other = np.asarray(nf.t_end_s, dtype=float), np.asarray(other.t_end_s, dtype=float)
    out = np.full(t.shape, np.nan)
    if t_other.size:
        i = np.clip(np.searchsorted(t_other, t), 0, t_other.size - 1)
        same = np.isclose(t_other[i], t)
        out[same] = np.asarray(other.error_deg, dtype=float)[i[same]]
    return out


def dwell_bias(run: Run, expect: Run, noisy: tuple[Run, Run],
               nf: NorthFindResult) -> DwellBias:
    """Each dwell's bias of ``run`` beside the noise-free model run ``expect``, its noise
    from the model's ``noisy`` pair (module docstring), on the dwells of ``nf`` (the
    measured run's north finding)."""
    dwells = [d for c in nf.cycles for d in c.dwells]
    return DwellBias(
        run_name=run.name, start_temperature_c=float(run.meta.start_temperature_c),
        time_s=np.array([0.5 * (d.t_start_s + d.t_end_s) for d in dwells]),
        theta_deg=np.array([d.theta_deg for d in dwells]),
        measured_dph=_dwell_means(run, dwells), model_dph=_dwell_means(expect, dwells),
        noise_dph=_twin_noise(_dwell_means(noisy[0], dwells), _dwell_means(noisy[1], dwells)))


def heading_trace(run: Run, nf: NorthFindResult, nf_expect: NorthFindResult,
                  nf_noisy: tuple[NorthFindResult, NorthFindResult]) -> HeadingTrace:
    """The heading error of every cycle of ``run`` (its north finding ``nf``) beside the
    noise-free model's (``nf_expect``), the noise from the model's noisy pair (module
    docstring)."""
    return HeadingTrace(
        run_name=run.name, start_temperature_c=float(run.meta.start_temperature_c),
        time_s=np.asarray(nf.t_end_s, dtype=float),
        measured_deg=np.asarray(nf.error_deg, dtype=float),
        model_deg=_on_cycles(nf, nf_expect),
        noise_deg=_twin_noise(_on_cycles(nf, nf_noisy[0]), _on_cycles(nf, nf_noisy[1])))
