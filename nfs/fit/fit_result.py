"""The result of :func:`nfs.fit.calibration.fit_model`: the fitted instrument, an honest account
of the fit, and the TOML file a user reads and edits."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..docfields import document_fields
from ..instrument import Instrument
from ..io.atomic import atomic_write_text
from ..io.records import from_record, record, to_record
from .departures import canonical_key
from .noise_fit import GyroNoiseEstimate
from .soak import SoakAnchor
from .stage import StageReport

__all__ = ["FitResult", "write_fitted_model", "FIT_SCHEMA"]

#: The JSON schema of :meth:`FitResult.to_dict`.
FIT_SCHEMA = "nfs-fit/1"


@record
@document_fields
@dataclass(frozen=True)
class FitResult:
    """The fitted instrument and an honest account of the fit."""

    instrument: Instrument
    """The fitted instrument."""
    initial: Instrument
    """The instrument the fit started from."""
    params: dict[str, float]
    """Fitted value of every free parameter {path: value}."""
    initial_params: dict[str, float]
    """Starting value of every free parameter."""
    stderr: dict[str, float]
    """Standard error {path: value} from the Jacobian (inf: not identifiable)."""
    bounds: dict[str, tuple[float, float]]
    """The box each parameter was kept in."""
    at_bound: tuple[str, ...]
    """Parameters that ended on a bound (the fit wanted to go further)."""
    unidentifiable: dict[str, str]
    """Parameters the runs cannot determine, with the reason."""
    stages: dict[str, StageReport]
    """Report of each stage run, by name."""
    rms_before: dict[str, float]
    """Residual RMS per channel with the initial parameters of its stage (thermometers [K],
    ``drift_dph`` [deg/h], ``acc_x_g``/``acc_y_g`` [g]); the drift stage starts from the
    thermally fitted model."""
    rms_after: dict[str, float]
    """Residual RMS per channel after the fit."""
    warnings: tuple[str, ...] = ()
    """Everything a user should know: no convergence, bounds hit, one run, ..."""
    prior_centre: dict[str, float] = field(default_factory=dict)
    """Centre p0 of each parameter's Gaussian prior (the preset, or the soak anchor for a
    thermometer offset); empty without a prior."""
    prior_sigma: dict[str, float] = field(default_factory=dict)
    """Width sigma_p of each prior [unit of the parameter]; inf: no prior on it."""
    prior_shift: dict[str, float] = field(default_factory=dict)
    """(fitted - p0) / sigma_p: how far the data moved each parameter, in prior widths."""
    bound_advice: dict[str, str] = field(default_factory=dict)
    """For each parameter at a bound: what the bound says about the model's structure."""
    departures: dict[str, str] = field(default_factory=dict)
    """For each fitted parameter beyond its typical range in the table of ranges: one line
    with its value, error, the range and the structure it points to
    (:func:`nfs.fit.departures.departures`)."""
    soak: SoakAnchor | None = None
    """The thermometer offsets read from the soak at power-on (None: not used)."""
    noise: GyroNoiseEstimate | None = None
    """Gyro noise fitted to the Allan deviation of the drift residual at rest, with the curve
    (None: the drift stage did not run or ``fit_noise`` was off)."""
    start_c: dict[str, np.ndarray] = field(default_factory=dict)
    """Each run's node temperatures at power-on [degC] {run name: (n_nodes,)}, as the thermal
    stage estimated them (:mod:`nfs.fit.start_state`); empty: every node at T0."""
    start_amplitudes_c: dict[str, np.ndarray] = field(default_factory=dict)
    """Each run's start amplitudes a [K] (slow modes, then the fast remainder u)."""
    structure: Any = None
    """The refinement of the thermal structure (:class:`nfs.fit.refine.Refinement`)
    when :func:`nfs.fit.refine.fit_unit` tried one; None otherwise."""

    @property
    def converged(self) -> dict[str, bool]:
        """Convergence of each stage."""
        return {k: s.converged for k, s in self.stages.items()}

    @property
    def cost(self) -> dict[str, float]:
        """Final cost of each stage."""
        return {k: s.cost for k, s in self.stages.items()}

    @property
    def n_residuals(self) -> dict[str, int]:
        """Number of residuals of each stage."""
        return {k: s.n_residuals for k, s in self.stages.items()}

    def to_dict(self) -> dict[str, Any]:
        """Every field as JSON-ready data (:mod:`nfs.io.records`; the instruments as TOML)."""
        return to_record(self, FIT_SCHEMA)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "FitResult":
        """The fit :meth:`to_dict` wrote."""
        return from_record(cls, data, FIT_SCHEMA)

    def summary(self) -> str:
        """A few lines of text: each parameter with its error, flags and warnings."""
        lines = []
        for p in self.params:
            value, start, flags = _parameter(self, p)
            lines.append(f"{value} ({start})" + "".join(f" ({f})" for f in flags))
        if self.noise is not None:
            n = self.noise
            lines.append(f"gyro noise from the Allan deviation of the drift residual: "
                         f"N = {n.arw_deg_per_rth_h:.3g} deg/sqrt(h), "
                         f"B = {n.bias_instability_dph:.3g} deg/h, "
                         f"K = {n.rrw_deg_per_h_per_rth_h:.3g} deg/h/sqrt(h)")
        for ch in self.rms_after:
            lines.append(f"rms {ch}: {self.rms_before.get(ch, math.nan):.4g} -> "
                         f"{self.rms_after[ch]:.4g}")
        if self.structure is not None:
            lines.append(self.structure.summary())
        if self.departures:
            lines.append(f"{len(self.departures)} of {len(self.params)} fitted values beyond "
                         "their typical range (what each points to):")
            lines += [f"  {d}" for d in self.departures.values()]
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def _parameter(result: FitResult, p: str) -> tuple[str, str, list[str]]:
    """One fitted parameter in words: ``"path = value +- error"``, ``"start value[, how
    far the data moved it in prior widths]"`` and its flags (at bound, not identifiable)."""
    shift = result.prior_shift.get(p, math.nan)
    moved = f", {shift:+.2f} sigma from the prior's centre" if math.isfinite(shift) else ""
    flags = [f for f, on in (("at bound", p in result.at_bound),
                             ("not identifiable", p in result.unidentifiable)) if on]
    return (f"{p} = {result.params[p]:.6g} +- {result.stderr.get(p, math.nan):.3g}",
            f"start {result.initial_params[p]:.6g}{moved}", flags)


def write_fitted_model(result: FitResult, path: str | Path) -> Path:
    """Write the fitted instrument as a TOML file a user can read and edit.

    A header comment lists every fitted parameter with its standard error and start value,
    the parameters at a bound or not identifiable, each stage's convergence, and the values
    beyond their typical range with what each points to; a ``[fit]`` table lists the latter
    (``departures``), so that the file loads with one line about them, not one per value.  Written
    atomically (:func:`nfs.io.atomic.atomic_write_text`).
    """
    path = Path(path)
    lines = [f"# Instrument fitted by nfs.fit.fit_model from '{result.initial.name}'.",
             "# Fitted parameters (value +- standard error; start value):"]
    for p in result.params:
        value, start, flags = _parameter(result, p)
        flag = f"  [{', '.join(f.upper() for f in flags)}]" if flags else ""
        lines.append(f"#   {value}; {start}{flag}")
    if result.noise is not None:
        n = result.noise
        lines.append(f"# gyro noise from the Allan deviation of the drift residual at rest: "
                     f"arw {n.arw_deg_per_rth_h:.3g}, bias instability "
                     f"{n.bias_instability_dph:.3g}, rrw {n.rrw_deg_per_h_per_rth_h:.3g}")
    for s, rep in result.stages.items():
        lines.append(f"# {s} stage: {'converged' if rep.converged else 'NOT CONVERGED'} "
                     f"after {rep.nfev} evaluations, cost {rep.cost:.6g} on "
                     f"{rep.n_residuals} residuals")
    for ch, v in result.rms_after.items():
        lines.append(f"# residual RMS {ch}: {result.rms_before.get(ch, math.nan):.4g} -> {v:.4g}")
    if result.structure is not None:
        lines += [f"# {line}" for line in result.structure.summary().splitlines()]
    if result.departures:
        lines.append(f"# {len(result.departures)} fitted values beyond their typical range "
                     "(what each points to; listed in [fit] departures, so that loading this "
                     "file says so once):")
        lines += [f"#   {d}" for d in result.departures.values()]
    for w in result.warnings:
        lines.append(f"# warning: {w}")
    toml = result.instrument.to_toml().rstrip("\n") + "\n"
    if result.departures:
        keys = ", ".join(f'"{canonical_key(p)}"' for p in result.departures)
        toml += ("\n[fit]\n# values the fit put beyond their typical range, stated above\n"
                 f"departures = [{keys}]\n")
    atomic_write_text(path, "\n".join(lines) + "\n" + toml)
    return path
