"""The gyro's noise read from its runs, dwell by dwell, beside the values the instrument states.

The turntable holds the gyro at one position for a dwell (60-180 s); within a dwell the gyro
is at rest, the Earth rate's projection on its axis is constant, and the overlapping Allan
deviation (NIST SP 1065, Riley 2008, eq. (11)), which ignores a constant, reads the gyro's
noise from the raw ``gyro_dph``.  :func:`allan_of_runs` cuts every run into dwells as the
north finder does (:func:`nfs.northfind.find_dwells` with the run's ``dwell_s`` and the same
``settle_s``: the samples the north finder drops after each move are dropped here too), splits
a dwell at a missing sample, computes each dwell's Allan deviation up to a quarter of the
dwell, pools them (:mod:`nfs.noise.pooled`, eq. (1): every second difference of every dwell)
and fits the angle random walk N, bias instability B and rate random walk K
(:func:`nfs.noise.fit_noise_coefficients`, IEEE Std 952-2020 Annex C: the -1/2, 0 and +1/2
slopes) with percentile-bootstrap intervals over the dwells
(:func:`nfs.noise.pooled.fit_pooled_noise`).

Which taus the fit uses, and why.  In a start-up the coil warms and the gyro's bias moves
within a dwell: a rate ramp R [deg/h/s] adds R tau / sqrt(2) to the Allan deviation (IEEE Std
952-2020 Annex C), and at a dwell's long-tau end in the first hour that is thermal drift, not
noise.  So a dwell that starts within the start-up hour (t < :data:`STARTUP_S` = 3600 s after
power-on, the part ``nfs fit`` leaves out of its noise too: :data:`nfs.fit.noise_fit.NOISE_FROM_S`)
enters the fit only up to tau = dwell / 10 (:data:`STARTUP_TAU_FRACTION`); a later dwell up to
dwell / 4 (:data:`TAU_FRACTION`: four averages of the longest tau in every dwell).  Measured on
the default instrument's simulated start-ups (T0 = -32, 17, 54 C, 150 s dwells, 1 Hz): the
Allan deviation of the first quarter hour's dwells at tau = 64 s is 1.07-1.54 times that of
the dwells after the first hour, at tau = 16 s 0.93-1.05 times.  The figure
(:func:`nfs.report.allan_figure.plot_allan`) draws the start-up dwells' whole curves in grey,
so the drift shows.

Within a dwell of 150 s, the taus stop at about 40 s, short of the minimum of a gyro of
N = 0.0003 deg/sqrt(h), B = 0.002 deg/h (near 3 min): N is read well, B from the bend at the
long end, K hardly at all (its interval is an upper bound).  ``nfs fit`` reads the noise
from the drift residual of the whole run instead (:mod:`nfs.fit.noise_fit`), which reaches
longer taus but needs the model's drift.

The stated values are the instrument's ``gyro.arw_deg_per_rth_h``,
``gyro.bias_instability_dph`` and ``gyro.rrw_deg_per_h_per_rth_h`` (the same parameters
``nfs fit`` sets from its noise fit): of the model given, else of the built-in preset the
runs' sidecars name (``instrument = "default"``, what ``nfs simulate`` writes), else of the
default instrument (:func:`stated_instrument`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..docfields import document_fields
from ..errors import InputError
from ..instrument import Instrument, load_instrument, preset_names
from ..io.unit_files import UNIT_SIDECAR_KEY
from ..io.records import from_record, record, to_record
from ..noise.allan import AllanResult
from ..noise.pooled import (MIN_RECORD_SAMPLES, NoiseFitIntervals, PooledAllan,
                            fit_pooled_noise, pooled_allan)
from ..northfind import find_dwells
from ..run import Run
from ..fit.noise_fit import NOISE_FROM_S

__all__ = ["ALLAN_SCHEMA", "STARTUP_S", "STARTUP_TAU_FRACTION", "TAU_FRACTION", "AllanReport",
           "allan_of_runs", "stated_instrument"]

#: The JSON schema of :meth:`AllanReport.to_dict`.
ALLAN_SCHEMA = "nfs-allan/1"

#: Dwells that start before this time after power-on [s] are in the start-up.
STARTUP_S = NOISE_FROM_S

#: A start-up dwell enters the fit up to tau = this fraction of its length.
STARTUP_TAU_FRACTION = 0.1

#: A later dwell enters the fit (and every dwell's curve is drawn) up to tau = this fraction
#: of its length.
TAU_FRACTION = 0.25

#: The three terms: (words, symbol, field, unit); the field is the name of the value in
#: :class:`~nfs.noise.NoiseFit` and :class:`~nfs.instrument.GyroModel`, its interval in
#: :class:`~nfs.noise.pooled.NoiseFitIntervals` is named in ``_INTERVAL``.
TERMS = (
    ("angle random walk", "N", "arw_deg_per_rth_h", "deg/sqrt(h)"),
    ("bias instability", "B", "bias_instability_dph", "deg/h"),
    ("rate random walk", "K", "rrw_deg_per_h_per_rth_h", "deg/h/sqrt(h)"),
)
_FIELD = {sym: name for _, sym, name, _ in TERMS}
_INTERVAL = {"N": "arw_interval_deg_per_rth_h", "B": "bias_instability_interval_dph",
             "K": "rrw_interval_deg_per_h_per_rth_h"}


@record
@document_fields
@dataclass(frozen=True)
class AllanReport:
    """Every dwell's Allan deviation, N, B, K fitted with intervals, and the stated values
    (:func:`allan_of_runs`)."""

    run_names: tuple[str, ...]
    """The runs, in the order given."""
    sample_rate_hz: float
    """Sample rate fs of the runs [Hz]."""
    dwell_run: tuple[int, ...]
    """Index into ``run_names`` of each dwell (a dwell split at a missing sample counts as
    two)."""
    dwell_start_s: np.ndarray
    """Time of each dwell's first sample used, from power-on [s], (S,)."""
    dwell_theta_deg: np.ndarray
    """Turntable angle of each dwell [deg], (S,)."""
    dwell_samples: np.ndarray
    """Samples of each dwell, (S,)."""
    dwell_fit_max_tau_s: np.ndarray
    """Longest tau at which each dwell enters the fit [s], (S,) (module docstring)."""
    taus_s: np.ndarray
    """Averaging times tau [s], (T,)."""
    dwell_adev_dph: np.ndarray
    """Overlapping Allan deviation of each dwell's gyro [deg/h], (S, T); NaN beyond a
    quarter of the dwell."""
    noise: NoiseFitIntervals
    """N, B, K fitted to the pooled curve, with their intervals."""
    stated_arw_deg_per_rth_h: float
    """N the instrument states [deg/sqrt(h)]."""
    stated_bias_instability_dph: float
    """B the instrument states [deg/h]."""
    stated_rrw_deg_per_h_per_rth_h: float
    """K the instrument states [deg/h/sqrt(h)]."""
    stated_source: str
    """Where the stated values come from, in words."""
    settle_s: float
    """Seconds dropped at the start of every dwell (as the north finder's ``settle_s``)."""
    startup_s: float
    """Dwells starting before this time [s] enter the fit only up to dwell/10."""
    seed: int
    """Seed of the bootstrap."""
    n_left_out: int = 0
    """Stretches of a dwell shorter than 8 samples (between missing samples, or a run that
    stops just after a move), left out."""

    @property
    def pooled_allan(self) -> PooledAllan:
        """The dwells' curves as :class:`nfs.noise.pooled.PooledAllan`."""
        return PooledAllan(taus_s=self.taus_s, sample_rate_hz=self.sample_rate_hz,
                           record_adev=self.dwell_adev_dph, record_samples=self.dwell_samples,
                           pool_max_tau_s=self.dwell_fit_max_tau_s)

    @property
    def pooled(self) -> AllanResult:
        """The pooled curve the fit used [deg/h], with its relative errors."""
        return self.pooled_allan.pooled()

    @property
    def startup_pooled(self) -> AllanResult | None:
        """The start-up dwells' curves pooled whole, up to a quarter of each dwell (not
        what the fit used: it shows the drift at their long-tau end); None without one."""
        early = self.dwell_start_s < self.startup_s
        if not early.any():
            return None
        return PooledAllan(taus_s=self.taus_s, sample_rate_hz=self.sample_rate_hz,
                           record_adev=self.dwell_adev_dph[early],
                           record_samples=self.dwell_samples[early],
                           pool_max_tau_s=np.full(int(early.sum()), np.inf)).pooled()

    @property
    def n_startup_dwells(self) -> int:
        """Dwells that start within the start-up (``startup_s``)."""
        return int(np.count_nonzero(self.dwell_start_s < self.startup_s))

    def fitted(self, symbol: str) -> tuple[float, tuple[float, float]]:
        """(value, interval) of N, B or K as fitted [its unit]."""
        return (float(getattr(self.noise.fit, _FIELD[symbol])),
                getattr(self.noise, _INTERVAL[symbol]))

    def stated(self, symbol: str) -> float:
        """N, B or K as the instrument states it [its unit]."""
        return float(getattr(self, "stated_" + _FIELD[symbol]))

    def taus_note(self) -> str:
        """Which taus the fit used and why, in one sentence."""
        used = self.noise.taus_s
        span = f"{used[0]:g}-{used[-1]:g} s" if used.size else "none"
        n = len(self.dwell_run)
        early = self.n_startup_dwells
        return (f"fit to the pooled Allan deviation of {n} dwell(s) of {len(self.run_names)} "
                f"run(s) at tau {span}: every dwell up to a quarter of its length, the "
                f"{early} dwell(s) that start within {self.startup_s:g} s of power-on only up "
                f"to a tenth of it (there the start-up's thermal drift within a dwell, a rate "
                f"ramp, raises the long-tau end: drift, not noise)")

    def verdict(self, symbol: str) -> str:
        """Whether the stated value of N, B or K lies within the fitted interval, in words."""
        value, (lo, hi) = self.fitted(symbol)
        s = self.stated(symbol)
        if not (math.isfinite(lo) and math.isfinite(hi)):
            return "no interval (fewer than 8 dwells)"
        if lo <= s <= hi:
            return "stated value within the interval"
        return "stated value " + ("below" if s < lo else "above") + " the interval"

    def table(self) -> str:
        """N, B, K fitted [interval] against stated, as a Markdown table."""
        pct = f"{100 * self.noise.level:g} %"
        lines = [f"| term | fitted | {pct} interval | stated | unit | stated vs fitted |",
                 "|---|---:|---:|---:|---|---|"]
        for words, sym, _, unit in TERMS:
            value, (lo, hi) = self.fitted(sym)
            lines.append(f"| {sym} ({words}) | {_num(value)} | [{_num(lo)}, {_num(hi)}] | "
                         f"{_num(self.stated(sym))} | {unit} | {self.verdict(sym)} |")
        return "\n".join(lines)

    def summary(self) -> str:
        """The table, which taus the fit used and why, and where the stated values come
        from."""
        return "\n".join([self.table(), "", self.taus_note() + ".",
                          f"stated: {self.stated_source}.",
                          "intervals: percentile bootstrap over the dwells "
                          f"({self.noise.n_boot} resamples, seed {self.seed})."])

    def to_dict(self) -> dict[str, Any]:
        """Every field as JSON-ready data (:mod:`nfs.io.records`), schema
        :data:`ALLAN_SCHEMA`, with the table and the note on the taus for a reader."""
        return {**to_record(self, ALLAN_SCHEMA), "summary": self.summary().splitlines()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "AllanReport":
        """The report :meth:`to_dict` wrote (``allan.json``; its ``summary`` and a
        ``provenance`` beside the fields are for a reader)."""
        if isinstance(data, dict):
            data = {k: v for k, v in data.items() if k not in ("summary", "provenance")}
        return from_record(cls, data, ALLAN_SCHEMA)


def _num(v: float) -> str:
    return "n/a" if not math.isfinite(v) else f"{v:.3g}"


def stated_instrument(runs: Sequence[Run], model: Instrument | str | None = None
                      ) -> tuple[Instrument, str]:
    """The instrument whose stated noise the runs are set against, and where it comes from.

    Parameters
    ----------
    runs : sequence of Run
        The runs (their sidecars' ``instrument``).
    model : Instrument or str, optional
        The model (an instrument, a preset name or a TOML file); default: the unit file
        beside the runs that every run's sidecar names (``unit_file``: the unit a simulation
        drew, :mod:`nfs.io.unit_files`), else the built-in preset the runs' sidecars name,
        else the default instrument.

    Returns
    -------
    (Instrument, str)
        The instrument and the source in words.

    Raises
    ------
    InputError
        The runs name different built-in presets and no model is given.
    """
    if isinstance(model, Instrument):
        return model, f"the model '{model.name}'"
    if model is not None:
        inst = load_instrument(model)
        return inst, f"the model {model} ('{inst.name}')"
    units = {(r.path.parent / str(r.meta.extra[UNIT_SIDECAR_KEY])) if r.path is not None
             else None for r in runs if r.meta.extra.get(UNIT_SIDECAR_KEY)}
    if len(units) == 1 and len(runs) and all(r.meta.extra.get(UNIT_SIDECAR_KEY) for r in runs):
        unit = next(iter(units))
        if unit is not None and unit.is_file():
            return load_instrument(unit), (f"the unit that made the runs, {unit.name} beside "
                                           "them (as its simulation drew it)")
    named = sorted({r.meta.instrument for r in runs if r.meta.instrument is not None})
    presets = [n for n in named if n in preset_names()]
    if len(presets) > 1:
        first = next(r for r in runs if r.meta.instrument == presets[1])
        raise InputError(f"the runs name different instruments ({', '.join(presets)}): give "
                         "the one whose stated noise they are set against (--model)",
                         file=first.path, key="instrument")
    if presets:
        return load_instrument(presets[0]), (f"the built-in instrument '{presets[0]}' the "
                                             "runs' sidecars name")
    note = (f" (the runs name '{named[0]}', which is no built-in preset; give its TOML "
            "with --model)" if named else " (the runs name no instrument)")
    return load_instrument("default"), "the default instrument" + note


def _sample_rate_hz(runs: Sequence[Run]) -> float:
    """The common sample rate of the runs [Hz] (1 / the median sample interval)."""
    rates = []
    for r in runs:
        t = np.asarray(r["time_s"], dtype=float)
        if t.size < 2:
            raise InputError(f"run '{r.name}' has fewer than 2 samples", file=r.path,
                             column="time_s")
        rates.append(1.0 / float(np.median(np.diff(t))))
    for r, fs in zip(runs, rates):
        if abs(fs - rates[0]) > 1e-6 * rates[0]:
            raise InputError(f"run '{r.name}' is sampled at {fs:g} Hz, run '{runs[0].name}' "
                             f"at {rates[0]:g} Hz: the dwells' Allan deviations are pooled at "
                             "one sample rate", file=r.path, column="time_s")
    return rates[0]


def _stretches(values: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) of every run of finite values."""
    ok = np.concatenate([[False], np.isfinite(values), [False]])
    edges = np.flatnonzero(np.diff(ok.astype(np.int8)))
    return list(zip(edges[::2], edges[1::2]))


def allan_of_runs(runs: Sequence[Run], *, stated: tuple[Instrument, str] | None = None,
                  settle_s: float = 0.0, startup_s: float = STARTUP_S, level: float = 0.95,
                  n_boot: int = 400, seed: int = 0) -> AllanReport:
    """The overlapping Allan deviation of every dwell's gyro at rest, N, B and K fitted with
    their intervals, and the values the instrument states (module docstring).

    Parameters
    ----------
    runs : sequence of Run
        The runs (``time_s``, ``position_deg``, ``moving``, ``gyro_dph`` [deg/h]), at one
        sample rate.
    stated : (Instrument, str), optional
        The instrument whose stated N, B, K to set beside the fit and where it comes from,
        in words, as :func:`stated_instrument` gives them (default:
        ``stated_instrument(runs)``; a model file: ``stated_instrument(runs, "m.toml")``).
    settle_s : float
        Seconds dropped at the start of every dwell [s], as the north finder's ``settle_s``
        (default 0, the north finder's).
    startup_s : float
        Dwells starting before this time after power-on [s] enter the fit only up to a tenth
        of their length.
    level : float
        Confidence level of the intervals.
    n_boot : int
        Bootstrap resamples of the dwells.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    AllanReport

    Raises
    ------
    InputError
        No runs, a missing column, runs at different sample rates, no dwell of 8 samples, or
        the runs name different instruments and ``stated`` is not given.
    """
    runs = list(runs)
    if not runs:
        raise InputError("allan_of_runs needs at least one run")
    for r in runs:
        for col in ("time_s", "position_deg", "moving", "gyro_dph"):
            if col not in r.columns:
                raise InputError(f"run '{r.name}' has no column '{col}', which the Allan "
                                 "deviation of its dwells needs", file=r.path, column=col)
    inst, source = stated_instrument(runs) if stated is None else stated
    fs = _sample_rate_hz(runs)
    records, owner, start, theta, limit = [], [], [], [], []
    left_out = 0
    for k, r in enumerate(runs):
        t = np.asarray(r["time_s"], dtype=float)
        gyro = np.asarray(r["gyro_dph"], dtype=float)
        for d in find_dwells(t, r["position_deg"], r["moving"], dwell_s=r.meta.dwell_s,
                             settle_s=settle_s):
            for a, b in _stretches(gyro[d.index]):
                if b - a < MIN_RECORD_SAMPLES:
                    left_out += 1
                    continue
                t0 = float(t[d.start + a])
                records.append(gyro[d.start + a:d.start + b])
                owner.append(k)
                start.append(t0)
                theta.append(d.theta_deg)
                frac = STARTUP_TAU_FRACTION if t0 < startup_s else TAU_FRACTION
                limit.append(frac * (b - a) / fs)
    if not records:
        raise InputError(f"no dwell of {MIN_RECORD_SAMPLES} samples at rest with a gyro "
                         f"reading in {len(runs)} run(s)", file=runs[0].path)
    pooled = pooled_allan(records, fs, max_fraction=TAU_FRACTION,
                          pool_max_tau_s=np.array(limit))
    noise = fit_pooled_noise(pooled, level=level, n_boot=n_boot,
                             rng=np.random.default_rng(seed))
    g = inst.gyro
    return AllanReport(
        run_names=tuple(r.name for r in runs), sample_rate_hz=fs, dwell_run=tuple(owner),
        dwell_start_s=np.array(start), dwell_theta_deg=np.array(theta),
        dwell_samples=pooled.record_samples, dwell_fit_max_tau_s=np.array(limit),
        taus_s=pooled.taus_s, dwell_adev_dph=pooled.record_adev, noise=noise,
        stated_arw_deg_per_rth_h=float(g.arw_deg_per_rth_h),
        stated_bias_instability_dph=float(g.bias_instability_dph),
        stated_rrw_deg_per_h_per_rth_h=float(g.rrw_deg_per_h_per_rth_h),
        stated_source=source, settle_s=float(settle_s), startup_s=float(startup_s),
        seed=int(seed), n_left_out=left_out)
