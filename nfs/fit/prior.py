"""The preset as a Gaussian prior on the free parameters of a fit (maximum a posteriori).

Each free parameter p with start value p0 (the preset) gets a Gaussian prior of width
sigma_p.  :func:`nfs.fit.calibration.fit_model` appends one residual row per parameter,

    r_p = (p - p0) / sigma_p                                           [-]

to its data rows, which are divided by their noise level, so the cost 0.5 sum r^2 is half the
negative log posterior (up to a constant) and its minimum is the maximum a posteriori (MAP)
estimate (Tarantola 2005, *Inverse Problem Theory*, sec. 3.2: the least-squares misfit of a
Gaussian problem is the data term plus the prior term).  A parameter the data do not
determine then stays at its prior instead of running to a bound.

The widths live in one table, :data:`PRIOR_WIDTHS` (parameter paths) and
:data:`EFFECT_PRIOR_WIDTHS` (effect parameters, by unit), each with its reason.  A caller
overrides any of them with ``prior={pattern: width}`` (a number: an absolute width in the
parameter's unit; a string ``"30%"``: relative to the start value) and scales them all with
``prior_scale``; ``prior_scale=inf`` or ``prior=None`` switches the prior off.
"""

from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ..errors import NfsError
from .params import effect_unit

__all__ = ["PriorWidth", "PRIOR_WIDTHS", "EFFECT_PRIOR_WIDTHS", "Prior", "build_prior"]


@dataclass(frozen=True)
class PriorWidth:
    """One row of the prior table."""

    width: float
    """The width: relative to the start value (``relative``) or absolute [unit of the
    parameter]; inf for no prior."""
    relative: bool
    """True: sigma = width |p0|."""
    zero_width: float
    """Absolute width used instead when a relative width meets a start value of 0."""
    reason: str
    """Why this width."""

    def sigma(self, value: float) -> float:
        """The absolute width sigma [unit of the parameter] at start value ``value``."""
        if not self.relative:
            return self.width
        return self.width * abs(value) if value != 0.0 else self.zero_width


#: Prior widths by parameter path pattern (first match wins).  Positive physical quantities
#: get relative widths: docs/physics.md gives each node's capacity, each conductance and each power
#: as a range spanning a factor 2-3 (est.), so 50 % of the preset is one sigma of that range.
PRIOR_WIDTHS: dict[str, PriorWidth] = {
    "thermal.nodes.*.capacity_j_per_k": PriorWidth(
        0.5, True, 100.0, "docs/physics.md ranges span x2-2.5 (e.g. coil outer 40-100 J/K)"),
    "thermal.nodes.*.power_w": PriorWidth(
        0.5, True, 1.0, "docs/physics.md ranges span x2-2.5 (board 3-8 W, QFA 0.3-0.6 W)"),
    "thermal.links.*.conductance_w_per_k": PriorWidth(
        0.5, True, 0.1, "docs/physics.md ranges span x4-6 (components to housing 0.3-2 W/K); "
                        "50 % keeps the preset's network shape"),
    "coil.heat_capacity_j_per_m3_k": PriorWidth(
        0.2, True, 3e5, "a potted winding's volumetric heat capacity: silica 1.6e6, acrylate "
                        "and epoxy 1.7-2.2e6 J/(m^3 K)"),
    "coil.conductivity_w_per_m_k": PriorWidth(
        0.5, True, 0.1, "a potted winding conducts 0.2-0.5 W/(m K) across its layers: x2.5"),
    "coil.*_contacts.*": PriorWidth(
        0.5, True, 0.1, "a face's contacts, as the network's links"),
    "coil.*": PriorWidth(0.05, True, 1e-3, "the coil's drawing: radii and height known"),
    "thermometers.*.lag_s": PriorWidth(
        0.5, True, 30.0, "docs/physics.md: tau 10-60 s"),
    "thermometers.*.offset_c": PriorWidth(
        1.0, False, 1.0, "wide: a thermometer's offset is anchored by the soak (every node at "
                         "T0 at power-on), not by the preset"),
    "thermometers.*": PriorWidth(1.0, True, 0.01, "noise figures: a factor 2 either way"),
    "gyro.bias_dph": PriorWidth(1.0, False, 1.0, "wide: the constant bias is free to be "
                                                 "anything the runs say [deg/h]"),
    "gyro.scale_factor": PriorWidth(1e-3, False, 1e-3, "1000 ppm: far above a FOG's "
                                                       "scale-factor error"),
    "gyro.*": PriorWidth(1.0, True, 1e-3, "noise coefficients: a factor 2 either way"),
    "accelerometers.bias_*": PriorWidth(0.01, False, 0.01, "wide: 10 mg, above a QFA's "
                                                           "bias of a few mg [g]"),
    "accelerometers.*": PriorWidth(1.0, True, 1.0, "noise figures: a factor 2 either way"),
    "turntable.tilt_*": PriorWidth(1.0, False, 1.0, "wide: 1 deg, the whole fit box"),
}

#: Prior widths of effect parameters by the parameter's unit: the coefficients of the drift
#: effects weakly, several times the range docs/physics.md gives them (docs/effects.md lists the
# units).
EFFECT_PRIOR_WIDTHS: dict[str, PriorWidth] = {
    "W/K": PriorWidth(0.5, True, 0.05, "TEC slopes 0.02-0.04 / 0.05-0.1 W/K: x2 ranges"),
    "W": PriorWidth(2.0, False, 2.0, "an extra heat source or motor heat of a few W"),
    "deg/h": PriorWidth(0.2, False, 0.2, "amplitudes (turn-on 0.005-0.05 deg/h): 4x the range"),
    "deg/h/K": PriorWidth(0.01, False, 0.01, "b1 0.0005-0.003 deg/h/K: 3x the range"),
    "deg/h/K^2": PriorWidth(1e-3, False, 1e-3, "b2 (no docs/physics.md range): 7x the preset"),
    "deg/h per K/min": PriorWidth(3.0, False, 3.0, "k_r 0.1-1 deg/h per K/min: 3x the range"),
    "deg/h per K*K/min": PriorWidth(0.1, False, 0.1, "k_p (no range): 15x the preset"),
    "g/K": PriorWidth(2e-4, False, 2e-4, "QFA bias 10-50 ug/K: 4x the range"),
    "1/K": PriorWidth(3e-3, False, 3e-3, "scale factor 17-800 ppm/K: 4x the range"),
    "s": PriorWidth(0.5, True, 60.0, "effect time constants (turn-on 1-5 min): x2-5 ranges"),
    "m": PriorWidth(0.5, False, 0.5, "a winding's asymmetric length (a few cm): 10x it"),
    "K": PriorWidth(0.5, True, 1.0, "temperature periods: a factor 2"),
    "degC": PriorWidth(5.0, False, 5.0, "set points: a few kelvin"),
    "deg": PriorWidth(180.0, False, 180.0, "an azimuth: anywhere"),
    "rad": PriorWidth(math.pi, False, math.pi, "a phase: anywhere"),
}

_NO_PRIOR = PriorWidth(math.inf, False, math.inf, "no entry in the prior table: no prior")


@dataclass(frozen=True)
class Prior:
    """The Gaussian prior of one set of free parameters (in their order)."""

    paths: tuple[str, ...]
    """The parameters."""
    centre: np.ndarray
    """Prior mean p0 of each [unit of the parameter]."""
    sigma: np.ndarray
    """Prior width sigma_p of each [unit of the parameter]; inf: no prior on it."""
    reason: tuple[str, ...]
    """Where each width came from."""

    @property
    def active(self) -> np.ndarray:
        """Parameters that have a finite prior."""
        return np.isfinite(self.sigma) & (self.sigma > 0)

    def rows(self, x: np.ndarray) -> np.ndarray:
        """The prior residual rows (x - p0) / sigma of the parameters with a finite width."""
        a = self.active
        return (np.asarray(x, dtype=float)[a] - self.centre[a]) / self.sigma[a]

    def jacobian(self) -> np.ndarray:
        """d rows / d x, shape (n_active, n)."""
        a = self.active
        return np.eye(len(self.paths))[a] / self.sigma[a][:, None]

    def shift(self, x: np.ndarray) -> dict[str, float]:
        """(x - p0) / sigma of each parameter (NaN where there is no prior)."""
        out = {}
        for i, p in enumerate(self.paths):
            s = self.sigma[i]
            out[p] = float((x[i] - self.centre[i]) / s) if math.isfinite(s) and s > 0 else math.nan
        return out

    def subset(self, paths: Sequence[str]) -> "Prior":
        """The prior of ``paths`` (a subset of :attr:`paths`)."""
        idx = [self.paths.index(p) for p in paths]
        return Prior(tuple(paths), self.centre[idx], self.sigma[idx],
                     tuple(self.reason[i] for i in idx))

    def with_centre(self, path: str, centre: float, sigma: float, reason: str) -> "Prior":
        """The prior with one parameter re-centred (e.g. on the soak anchor)."""
        i = self.paths.index(path)
        c, s, r = self.centre.copy(), self.sigma.copy(), list(self.reason)
        c[i], s[i], r[i] = centre, sigma, reason
        return Prior(self.paths, c, s, tuple(r))


def _parse_width(pattern: str, width) -> PriorWidth:
    if isinstance(width, str) and width.strip().endswith("%"):
        try:
            rel = float(width.strip()[:-1]) / 100.0
        except ValueError:
            raise NfsError(f"prior width '{width}' for '{pattern}' is not a number or "
                           "a percentage") from None
        return PriorWidth(rel, True, math.inf, f"prior={{'{pattern}': '{width}'}}")
    try:
        w = float(width)
    except (TypeError, ValueError):
        raise NfsError(f"prior width {width!r} for '{pattern}' is not a number or a "
                       "percentage such as '30%'") from None
    if not w > 0:
        raise NfsError(f"prior width for '{pattern}' must be > 0 (inf: no prior), got {w}")
    return PriorWidth(w, False, w, f"prior={{'{pattern}': {w:g}}}")


def _table_width(inst, path: str) -> PriorWidth:
    if path.startswith("effects."):
        unit = effect_unit(inst, path)
        return EFFECT_PRIOR_WIDTHS.get(unit, _NO_PRIOR)
    for pat, w in PRIOR_WIDTHS.items():
        if fnmatch.fnmatchcase(path, pat):
            return w
    return _NO_PRIOR


def build_prior(inst, paths: Sequence[str], start: Mapping[str, float],
                prior: Mapping[str, float | str] | None = None,
                prior_scale: float = 1.0) -> Prior:
    """The prior of ``paths``: centred on ``start``, widths from the table and ``prior``.

    Parameters
    ----------
    inst : Instrument
        The model (effect parameters' units are looked up in it).
    paths : sequence of str
        Free parameter paths (canonical, as :func:`~nfs.fit.params.expand_paths` gives).
    start : mapping
        Start value p0 of each path: the prior's centre.
    prior : mapping of str to float or str, optional
        Overrides {path or glob pattern: width}; a number is an absolute width in the
        parameter's unit, ``"N%"`` a width relative to p0, ``inf`` no prior.  Patterns are
        tried in the mapping's order before the table.
    prior_scale : float
        Every width is multiplied by it (> 0; inf: no prior at all).

    Returns
    -------
    Prior
    """
    if not prior_scale > 0:
        raise NfsError(f"prior_scale must be > 0 (inf: no prior), got {prior_scale}")
    user = [(pat, _parse_width(pat, w)) for pat, w in (prior or {}).items()]
    centre, sigma, reason = [], [], []
    for p in paths:
        row = next((w for pat, w in user if fnmatch.fnmatchcase(p, pat) or pat == p), None)
        if row is None:
            row = _table_width(inst, p)
        v = float(start[p])
        centre.append(v)
        sigma.append(row.sigma(v) * prior_scale)
        reason.append(row.reason)
    return Prior(tuple(paths), np.array(centre, dtype=float), np.array(sigma, dtype=float),
                 tuple(reason))
