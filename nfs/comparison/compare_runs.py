"""Model against measurement, channel by channel: where the model fails.

For every measured run the model is simulated beside it on the run's own time base,
turntable motion, start temperature T0, latitude, heading and chamber
(:func:`nfs.experiment.conditions_from_run`), and each channel is set against the model's
prediction:

==================  ==========================================================================
channel             residual r = measured - model
==================  ==========================================================================
``temp_fog_c``,     thermometer reading minus the model's noise-free reading (sensed node
``temp_acc_x_c``,   temperature through the thermometer's lag and offset, without noise or
``temp_acc_y_c``    quantisation) [degC], every sample at rest
``gyro_drift_dph``  separate_drift(measured).drift_dph - separate_drift(noise-free model
                    run).drift_dph [deg/h]: the model's deterministic prediction through the
                    same wavelet separation, with the measured run's thresholds
``acc_x_g``,        dwell mean of the measured specific force minus the dwell mean of the
``acc_y_g``         model's noise-free one [g], one point per dwell
==================  ==========================================================================

The sign is measured minus model throughout, so a positive bias is what the model lacks.

Noise floor (what the residual would be if the model were right), per sample, squared:

- thermometers: noise_c^2 + quantum_c^2 / 12 of the model's thermometer (white noise plus
  uniform rounding error);
- gyro drift: the model is simulated twice with independent noise (seeds ``(seed, k, SALT,
  0)`` and ``(seed, k, SALT, 1)`` for run k); each separated drift d_a, d_b is the
  deterministic prediction plus one realisation of the noise that leaks through the
  denoiser, so (d_a - d_b)^2 / 2 estimates the variance of a measured run about the
  prediction when the model is right, bias instability and ARW included (an estimate from
  the wavelet noise alone would miss the bias instability, which no denoiser can tell from
  drift);
- accelerometers: sigma^2 / n for a dwell of n samples, sigma the per-sample noise estimated
  from the measured run itself (standard deviation of first differences within the dwells over
  sqrt(2)).

Each channel of each run gets its statistics by stage and turntable position
(:mod:`nfs.comparison.channel_residual`); over the runs, the channel is consistent with noise or
its failure is put into words (:mod:`nfs.comparison.channel_summary`); the heading RMSE gets a
verdict of its own (:mod:`nfs.comparison.heading`).  For the figures, each dwell's bias and
each cycle's heading error are kept against time, measured and predicted
(:mod:`nfs.comparison.dwell_traces`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Mapping, Sequence

import numpy as np

from ..docfields import document_fields
from ..denoise import separate_drift
from ..effects.thermometer import THERMOMETERS
from ..errors import MeasurementError, NfsError
from ..conditions import chamber_assumption, conditions_from_run
from ..experiment import simulate_run
from ..instrument import Instrument
from ..run import Run, run_caveats
from ..northfind import heading_rmse, north_find
from ..io.records import RecordError, encode, from_record
from .channel_residual import CHANNELS, ChannelRun, ChannelSpec, StageBounds, channel_run
from .channel_summary import POSITION_RATIO, ChannelSummary, format_sig, summarise
from .dwell_traces import DwellBias, HeadingTrace, dwell_bias, heading_trace
from .heading import (HEADING_ALPHA, HeadingComparison, RunHeading, heading_comparison,
                      json_value)
from ..fit.start_state import StartModel
from ..fit.thermal_residual import DEFAULT_START, start_states

__all__ = ["SEED_SALT", "Comparison", "compare", "noise_free", "COMPARISON_SCHEMA"]

#: The JSON schema of :meth:`Comparison.to_dict`.
COMPARISON_SCHEMA = "nfs-comparison/1"

#: Entropy word that keeps the model's noise streams apart from a scenario's own
#: ``(seed, i_temp, repeat)`` streams, so a model never replays a run's noise exactly.
SEED_SALT = 0xC0DE

_BASE_COLUMNS = ("time_s", "position_deg", "moving")
_THERMOMETER_OF = {col: name for name, col in THERMOMETERS.items()}


@document_fields
@dataclass(frozen=True)
class Comparison:
    """The model against a set of runs (:func:`compare`)."""

    model_name: str
    """Name of the compared instrument model."""
    run_names: tuple[str, ...]
    """The runs, in the order given."""
    start_temperatures_c: tuple[float, ...]
    """T0 of each run [degC]."""
    settings: dict[str, Any]
    """seed, startup_end_s, stable_start_s, window_s."""
    per_run: dict[str, tuple[ChannelRun, ...]]
    """Channel key -> one :class:`ChannelRun` per run."""
    summaries: dict[str, ChannelSummary]
    """Channel key -> :class:`ChannelSummary`."""
    headings: tuple[RunHeading, ...]
    """Heading RMSE per run."""
    heading: HeadingComparison | None = None
    """The heading's own verdict over the runs
    (:func:`~nfs.comparison.heading.heading_comparison`)."""
    assumptions: tuple[str, ...] = ()
    """What the comparison assumed where the runs do not say (a missing chamber record), and
    what the reader was asked to accept in them (:func:`nfs.run.run_caveats`)."""
    dwell_biases: tuple[DwellBias, ...] = ()
    """Per run: each dwell's mean gyro rate less the Earth-rate projection, measured and as
    the model predicts it, with the noise of a dwell mean (:mod:`nfs.comparison.dwell_traces`)."""
    heading_traces: tuple[HeadingTrace, ...] = ()
    """Per run: each cycle's heading error, measured and as the model predicts it."""

    def sentences(self) -> list[str]:
        """"Where it fails", one sentence per channel, in channel order."""
        return [self.summaries[c.key].sentence for c in CHANNELS if c.key in self.summaries]

    @property
    def heading_pooled(self) -> dict[str, float]:
        """RMS over the runs of each heading RMSE column [deg]."""
        out = {}
        for k in ("measured_startup_deg", "measured_stable_deg", "model_startup_deg",
                  "model_stable_deg"):
            v = np.array([getattr(h, k) for h in self.headings], dtype=float)
            v = v[np.isfinite(v)]
            out[k] = float(np.sqrt(np.mean(v * v))) if v.size else math.nan
        return out

    def heading_sentence(self) -> str:
        """Measured against predicted heading RMSE, in words, with the heading's verdict."""
        p = self.heading_pooled
        text = (f"heading RMSE start-up: measured {format_sig(p['measured_startup_deg'])} deg, "
                f"model {format_sig(p['model_startup_deg'])} deg; stable: measured "
                f"{format_sig(p['measured_stable_deg'])} deg, model "
                f"{format_sig(p['model_stable_deg'])} deg (RMS over {len(self.headings)} "
                "run(s))")
        if self.heading is None:
            return text
        drift = self.summaries.get("gyro_drift_dph")
        positions = bool(drift is not None and math.isfinite(drift.position_ratio)
                         and drift.position_ratio >= POSITION_RATIO)
        return text + "; " + self.heading.sentence(
            None if drift is None else drift.consistent, positions)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form: the statistics and sentences for a reader (NaN as null), and
        under ``record`` every field for :meth:`from_dict` (:mod:`nfs.io.records`; no traces:
        the runs and the model reproduce them).  Schema :data:`COMPARISON_SCHEMA`."""
        return {"schema": COMPARISON_SCHEMA,
            "model": self.model_name,
            "runs": [{"name": n, "start_temperature_c": json_value(t)}
                     for n, t in zip(self.run_names, self.start_temperatures_c)],
            "settings": {k: json_value(v) for k, v in self.settings.items()},
            "residual": "measured - model",
            "channels": {k: {"summary": self.summaries[k].to_dict(),
                             "runs": [cr.to_dict() for cr in self.per_run[k]]}
                         for k in self.summaries},
            "heading": {"runs": [h.to_dict() for h in self.headings],
                        "pooled": {k: json_value(v) for k, v in self.heading_pooled.items()},
                        **({} if self.heading is None else self.heading.to_dict()),
                        "sentence": self.heading_sentence()},
            "sentences": self.sentences(),
            "assumptions": list(self.assumptions),
            "record": encode(self),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Comparison":
        """The comparison :meth:`to_dict` wrote (``nfs compare --json``), without traces."""
        if not isinstance(data, dict) or "record" not in data:
            raise RecordError("not a comparison written by nfs compare --json "
                              "(no 'record')")
        return from_record(cls, {"schema": data.get("schema"), **data["record"]},
                           COMPARISON_SCHEMA)


def noise_free(inst: Instrument) -> Instrument:
    """The instrument without gyro, accelerometer and thermometer noise or quantisation: its
    simulated channels are the model's expectation (aux channels are left as they are)."""
    g = replace(inst.gyro, arw_deg_per_rth_h=0.0, bias_instability_dph=0.0,
                rrw_deg_per_h_per_rth_h=0.0)
    a = replace(inst.accelerometers, noise_ug_per_rth_hz=0.0)
    th = {k: replace(v, noise_c=0.0, quantum_c=0.0) for k, v in inst.thermometers.items()}
    return replace(inst, gyro=g, accelerometers=a, thermometers=th)


def _check_run(run: Run) -> None:
    """Raise MeasurementError naming the first column of ``run`` the comparison needs and
    lacks."""
    for col in _BASE_COLUMNS + tuple(c.column for c in CHANNELS):
        if col not in run.columns:
            what = next((c.label for c in CHANNELS if c.column == col), "turntable motion")
            raise MeasurementError(
                f"run '{run.name}' has no column '{col}', which the comparison needs "
                f"({what})", file=run.path, column=col)


def _run_seed(seed, k: int, role: int) -> tuple[int, ...]:
    """The noise seed of the model's simulation ``role`` (0, 1: noisy; 2: noise-free) of run
    ``k``: ``(seed..., k, SEED_SALT, role)``."""
    base = tuple(seed) if isinstance(seed, (tuple, list)) else (int(seed),)
    return (*base, k, SEED_SALT, role)

# --------------------------------------------------------------------------------------------
# One run: one scorer per kind of channel


def _thermometer_channel(spec: ChannelSpec, inst: Instrument, run: Run, expect: Run,
                         t: np.ndarray, pos: np.ndarray, rest: np.ndarray,
                         cycles: Sequence[Any], bounds: StageBounds) -> ChannelRun:
    """A thermometer: every sample at rest against the model's noise-free reading, floor
    noise_c^2 + quantum_c^2 / 12 [K^2]."""
    th = inst.thermometers[_THERMOMETER_OF[spec.column]]
    meas = np.asarray(run[spec.column], dtype=float)
    mod = np.asarray(expect[spec.column], dtype=float)
    f2 = np.full(t.shape, th.noise_c ** 2 + th.quantum_c ** 2 / 12.0)
    ok = rest & np.isfinite(meas)
    return channel_run(spec, run, t, pos, meas, mod, f2, ok, cycles,
                       np.where(ok, meas - mod, np.nan), bounds)


def _drift_channel(spec: ChannelSpec, run: Run, noisy: tuple[Run, Run], expect: Run,
                   t: np.ndarray, pos: np.ndarray, cycles: Sequence[Any],
                   bounds: StageBounds) -> ChannelRun:
    """The gyro drift: the separated drift of the measurement against the noise-free
    model's, shrunk with the measurement's thresholds; floor (d_a - d_b)^2 / 2 of the two
    ``noisy`` model runs [(deg/h)^2]."""
    d_meas = separate_drift(run)
    d_a = separate_drift(noisy[0]).drift_dph
    d_b = separate_drift(noisy[1]).drift_dph
    # the noise-free model shrunk with the measurement's thresholds: its own (near
    # zero) would keep what the measurement's shrinkage took off a position-
    # dependent term, and the residual would show it (wavelet_denoise, thresholds)
    meas = d_meas.drift_dph
    mod = separate_drift(expect, thresholds=d_meas.denoise.thresholds).drift_dph
    ok = ~d_meas.interpolated
    return channel_run(spec, run, t, pos, meas, mod, 0.5 * (d_a - d_b) ** 2, ok, cycles,
                       np.where(ok, meas - mod, np.nan), bounds)


def _dwell_channel(spec: ChannelSpec, run: Run, expect: Run, rest: np.ndarray,
                   cycles: Sequence[Any], bounds: StageBounds) -> ChannelRun:
    """An accelerometer: one point per dwell (its mean), floor sigma^2 / n with sigma the
    per-sample noise from the measured first differences within the dwells [g^2]."""
    meas_s = np.asarray(run[spec.column], dtype=float)
    mod_s = np.asarray(expect[spec.column], dtype=float)
    dwells = [d for c in cycles for d in c.dwells]
    tm, pm, mm, om, f2 = [], [], [], [], []
    diffs = []
    for d in dwells:
        seg = meas_s[d.start:d.stop]
        ok = np.isfinite(seg)
        if ok.sum() < 2:
            continue
        tm.append(0.5 * (d.t_start_s + d.t_end_s))
        pm.append(d.theta_deg)
        mm.append(seg[ok].mean())
        om.append(mod_s[d.start:d.stop][ok].mean())
        f2.append(ok.sum())
        diffs.append(np.diff(seg[ok]))
    n_pts = np.asarray(f2, dtype=float)
    dd = np.concatenate(diffs) if diffs else np.array([])
    sigma2 = float(np.var(dd) / 2.0) if dd.size > 1 else math.nan
    tm_a = np.asarray(tm, dtype=float)
    mask = np.ones(tm_a.shape, dtype=bool)
    return channel_run(
        spec, run, tm_a, np.asarray(pm, dtype=float), np.asarray(mm, dtype=float),
        np.asarray(om, dtype=float), sigma2 / np.maximum(n_pts, 1), mask, cycles,
        np.where(rest, meas_s - mod_s, np.nan), bounds)


def _heading_rmse_deg(nf, bounds: StageBounds) -> tuple[float, float]:
    """(start-up, stable) heading RMSE of a north-finding result [deg]."""
    s = heading_rmse(nf, startup_end_s=bounds.startup_end_s,
                     stable_start_s=bounds.stable_start_s)
    return s.startup_deg, s.stable_deg


def _compare_run(inst: Instrument, clean: Instrument, run: Run, k: int, seed,
                 bounds: StageBounds, start_c: np.ndarray | None
                 ) -> tuple[dict[str, ChannelRun], RunHeading, DwellBias, HeadingTrace]:
    """Run ``k`` beside the model (two noisy simulations and a noise-free one, started at
    ``start_c``): every channel, the heading RMSE measured and predicted, each dwell's bias
    and each cycle's heading error (:mod:`nfs.comparison.dwell_traces`)."""
    sim_a, sim_b, expect = (simulate_run(model, conditions_from_run(
        run, seed=_run_seed(seed, k, role), initial_c=start_c))
        for model, role in ((inst, 0), (inst, 1), (clean, 2)))
    expect = expect.run

    t = np.asarray(run["time_s"], dtype=float)
    pos = np.asarray(run["position_deg"], dtype=float)
    rest = np.asarray(run["moving"], dtype=float) == 0.0
    nf_meas = north_find(run)
    nf_model = north_find(sim_a.run)
    cycles = list(nf_meas.cycles)
    out: dict[str, ChannelRun] = {}
    for spec in CHANNELS:
        if spec.kind == "thermometer":
            out[spec.key] = _thermometer_channel(spec, inst, run, expect, t, pos, rest, cycles,
                                                 bounds)
        elif spec.kind == "gyro":
            out[spec.key] = _drift_channel(spec, run, (sim_a.run, sim_b.run), expect, t, pos,
                                           cycles, bounds)
        else:  # accelerometer: dwell means
            out[spec.key] = _dwell_channel(spec, run, expect, rest, cycles, bounds)

    (mu, ms), (pu, ps) = _heading_rmse_deg(nf_meas, bounds), _heading_rmse_deg(nf_model, bounds)
    heading = RunHeading(run.name, float(run.meta.start_temperature_c), mu, ms, pu, ps)
    noisy = (sim_a.run, sim_b.run)
    return (out, heading, dwell_bias(run, expect, noisy, nf_meas),
            heading_trace(run, nf_meas, north_find(expect),
                          (nf_model, north_find(sim_b.run))))


# --------------------------------------------------------------------------------------------
# Over the runs


def compare(inst: Instrument, runs: Sequence[Run], *, seed=0, startup_end_s: float = 3600.0,
            stable_start_s: float = 5400.0, window_s: float = 600.0,
            start_state: StartModel | None = DEFAULT_START,
            start_c: Mapping[str, np.ndarray] | None = None) -> Comparison:
    """Set the model ``inst`` beside every measured run, channel by channel.

    Each run is replayed on its own (time base, motion, T0, latitude, heading, chamber), so
    runs with different latitudes or schedules can be compared in one set.

    Parameters
    ----------
    inst : Instrument
        The model (e.g. a fitted one).
    runs : sequence of Run
        The measured runs; each needs ``time_s``, ``position_deg``, ``moving``, ``gyro_dph``,
        ``acc_x_g``, ``acc_y_g`` and the three thermometer columns, and a true heading.
    seed : int or tuple of int
        Root of the model's noise; run k uses ``(seed, k, SEED_SALT, role)``.
    startup_end_s, stable_start_s : float
        Start-up stage t < startup_end_s; stable stage t >= stable_start_s [s]. The heading
        RMSE uses :func:`nfs.northfind.heading_rmse` with the same bounds.
    window_s : float
        Length of the window of the worst residual [s].
    start_state : StartModel or None
        Each run's node temperatures at power-on are estimated from its thermometers
        through the model (:func:`nfs.fit.thermal_residual.start_states`: an
        unfinished soak, a unit off its air) and the model starts there; None: at T0.
    start_c : mapping {run name: node temperatures [degC]}, optional
        The start states already estimated for this model (a fit's
        :attr:`~nfs.fit.FitResult.start_c`): used as they are, not estimated again.

    Returns
    -------
    Comparison

    Raises
    ------
    NfsError
        No runs, a run missing a needed column (the message names run and column), a run
        without a true heading or without a complete north-finding cycle.
    """
    runs = list(runs)
    if not runs:
        raise NfsError("compare needs at least one run")
    if not window_s > 0:
        raise NfsError(f"window_s must be > 0, got {window_s}")
    for run in runs:
        _check_run(run)
    bounds = StageBounds(startup_end_s=float(startup_end_s),
                         stable_start_s=float(stable_start_s), window_s=float(window_s))
    clean = noise_free(inst)
    if start_c is not None:
        starts = dict(start_c)
    else:
        starts = start_states(inst, runs) if start_state is not None else {}
    per_run: dict[str, list[ChannelRun]] = {c.key: [] for c in CHANNELS}
    headings, biases, traces = [], [], []
    for k, run in enumerate(runs):
        chans, heading, bias, trace = _compare_run(inst, clean, run, k, seed, bounds,
                                                   starts.get(run.name))
        for key, cr in chans.items():
            per_run[key].append(cr)
        headings.append(heading)
        biases.append(bias)
        traces.append(trace)
    summaries = {c.key: summarise(c, per_run[c.key]) for c in CHANNELS}
    settings = {"seed": str(seed), "startup_end_s": bounds.startup_end_s,
                "stable_start_s": bounds.stable_start_s, "window_s": bounds.window_s}
    return Comparison(
        model_name=inst.name, run_names=tuple(r.name for r in runs),
        start_temperatures_c=tuple(float(r.meta.start_temperature_c) for r in runs),
        settings=settings, per_run={k: tuple(v) for k, v in per_run.items()},
        summaries=summaries, headings=tuple(headings),
        heading=heading_comparison(headings, HEADING_ALPHA),
        assumptions=tuple(a for a in (chamber_assumption(runs), *run_caveats(runs)) if a),
        dwell_biases=tuple(biases), heading_traces=tuple(traces))
