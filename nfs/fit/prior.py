"""The table of ranges as a Gaussian prior on the free parameters of a fit (maximum a posteriori).

Each free parameter p gets a Gaussian prior whose centre and width come from its row in the
one table of ranges (:mod:`nfs.ranges`), the typical range of real units being the prior's
one-sigma band, not from the value the fit starts from: a fit that starts from another fit's
result (a model file that is itself a fit, a refinement, a candidate's refit) meets the same
prior, so a chain of fits cannot walk.  :func:`nfs.fit.calibration.fit_model` appends one
residual row per parameter to its data rows, which are divided by their noise level, so the
cost 0.5 sum r^2 is half the negative log posterior (up to a constant) and its minimum is the
maximum a posteriori (MAP) estimate (Tarantola 2005, *Inverse Problem Theory*, sec. 3.2: the
least-squares misfit of a Gaussian problem is the data term plus the prior term).  A
parameter the data do not determine then stays inside what real units have instead of
running to a bound.  The row of parameter p with typical range [lo, hi]:

- a positive quantity (a capacity, a conductance, a lag, a positive coefficient; lo > 0):
  log-normal, the typical range being +-1 sigma on the log,

      r_p = (ln p - ln sqrt(lo hi)) / sigma_ln,   sigma_ln = ln(hi / lo) / 2       [-]

- a magnitude (a coefficient whose sign a winding or a direction sets) or a quantity whose
  typical range starts at 0 (a passive node's power, a bias): centred on 0,

      r_p = p / hi                                                               [-]

- any other range (a signed coefficient): r_p = (p - (lo + hi)/2) / ((hi - lo)/2).

Exceptions, each with its reason: a thermometer offset is centred on the soak anchor
(:func:`nfs.fit.soak.anchor_offsets`); the coil's radii and height come from its drawing
(5 % of the file's value, :data:`PRIOR_WIDTHS`); an effect parameter with no row in the
table of ranges (an effect a user registered without one) falls back on
:data:`EFFECT_PRIOR_WIDTHS`, centred on the start value; any other path without a row gets
no prior.  A caller overrides any of them with
``prior={pattern: width}`` (a number: an absolute width in the parameter's unit around the
start value; a string ``"30%"``: relative to the start value) and scales them all with
``prior_scale``; ``prior_scale=inf`` or ``prior=None`` switches the prior off.
"""

from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from .. import ranges
from ..errors import NfsError
from .params import effect_unit

__all__ = ["PriorWidth", "PRIOR_WIDTHS", "EFFECT_PRIOR_WIDTHS", "FROM_DRAWING", "Prior",
           "range_prior", "build_prior"]


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


#: Priors centred on the file's value, by parameter path pattern: what a unit's drawing gives
#: (a measured length, not a spread over units).  Every other built-in parameter has a row in
#: the table of ranges (:func:`range_prior`).
PRIOR_WIDTHS: dict[str, PriorWidth] = {
    "coil.*_radius_m": PriorWidth(0.05, True, 1e-3, "the coil's drawing: radii known"),
    "coil.height_m": PriorWidth(0.05, True, 1e-3, "the coil's drawing: height known"),
}

#: Prior widths of effect parameters by the parameter's unit, for an effect parameter the
#: table of ranges has no row for (an effect a user registered): the coefficients of the drift
#: effects weakly, several times the range docs/physics.md gives them (docs/effects.md lists
#: the units).
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
    log: np.ndarray | None = None
    """True where the prior is on ln p (a positive quantity): :attr:`centre` is then the
    median [unit of the parameter] and :attr:`sigma` the width of ln p [-]; None: all
    linear."""

    @property
    def is_log(self) -> np.ndarray:
        """:attr:`log` as a boolean array (False everywhere when None)."""
        return (np.zeros(len(self.paths), dtype=bool) if self.log is None
                else np.asarray(self.log, dtype=bool))

    def _transformed(self, x: np.ndarray) -> np.ndarray:
        """x, with ln x where the prior is on the log (x clipped above 0 there)."""
        x = np.array(x, dtype=float)
        lg = self.is_log
        x[lg] = np.log(np.maximum(x[lg], 1e-300))
        return x

    def _centre_t(self) -> np.ndarray:
        c = np.array(self.centre, dtype=float)
        lg = self.is_log
        c[lg] = np.log(c[lg])
        return c

    @property
    def active(self) -> np.ndarray:
        """Parameters that have a finite prior."""
        return np.isfinite(self.sigma) & (self.sigma > 0)

    def rows(self, x: np.ndarray) -> np.ndarray:
        """The prior residual rows (module docstring) of the parameters with a finite width:
        (x - p0) / sigma, or (ln x - ln p0) / sigma on the log."""
        a = self.active
        return (self._transformed(x)[a] - self._centre_t()[a]) / self.sigma[a]

    def jacobian(self, x: np.ndarray | None = None) -> np.ndarray:
        """d rows / d x at ``x``, shape (n_active, n) (``x`` is needed only for log rows:
        d/dx ln x = 1/x)."""
        a = self.active
        d = 1.0 / self.sigma
        lg = self.is_log
        if lg[a].any():
            if x is None:
                raise NfsError("Prior.jacobian: a prior on the log needs the point x")
            d = d.copy()
            d[lg] = d[lg] / np.maximum(np.asarray(x, dtype=float)[lg], 1e-300)
        return np.eye(len(self.paths))[a] * d[a][:, None]

    def shift(self, x: np.ndarray) -> dict[str, float]:
        """How far ``x`` lies from each prior's centre, in prior widths (on the log for a
        log prior; NaN where there is no prior)."""
        xt, ct = self._transformed(x), self._centre_t()
        out = {}
        for i, p in enumerate(self.paths):
            s = self.sigma[i]
            out[p] = float((xt[i] - ct[i]) / s) if math.isfinite(s) and s > 0 else math.nan
        return out

    def linear_sigma(self) -> np.ndarray:
        """Each width in the parameter's unit: sigma, or for a log prior the half-width
        p0 (exp(sigma) - exp(-sigma)) / 2 of its one-sigma band."""
        s = np.array(self.sigma, dtype=float)
        lg = self.is_log & np.isfinite(s)
        s[lg] = self.centre[lg] * np.sinh(s[lg])
        return s

    def subset(self, paths: Sequence[str]) -> "Prior":
        """The prior of ``paths`` (a subset of :attr:`paths`)."""
        idx = [self.paths.index(p) for p in paths]
        return Prior(tuple(paths), self.centre[idx], self.sigma[idx],
                     tuple(self.reason[i] for i in idx), self.is_log[idx])

    def with_centre(self, path: str, centre: float, sigma: float, reason: str) -> "Prior":
        """The prior with one parameter re-centred on a linear Gaussian (e.g. on the soak
        anchor)."""
        i = self.paths.index(path)
        c, s, r, lg = self.centre.copy(), self.sigma.copy(), list(self.reason), self.is_log.copy()
        c[i], s[i], r[i], lg[i] = centre, sigma, reason, False
        return Prior(self.paths, c, s, tuple(r), lg)


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


def _fallback_width(inst, path: str) -> PriorWidth:
    if path.startswith("effects."):
        unit = effect_unit(inst, path)
        return EFFECT_PRIOR_WIDTHS.get(unit, _NO_PRIOR)
    for pat, w in PRIOR_WIDTHS.items():
        if fnmatch.fnmatchcase(path, pat):
            return w
    return _NO_PRIOR


#: Parameters a unit's drawing gives: their prior stays on the file's value.
FROM_DRAWING = tuple(PRIOR_WIDTHS)


def range_prior(path: str, start: float) -> tuple[float, float, bool, str] | None:
    """The prior of ``path`` from its row in the table of ranges (module docstring): (centre
    [unit], sigma [unit, or of ln p], on the log, reason), or None where the table has no
    usable row (or the parameter comes from the unit's drawing)."""
    if any(fnmatch.fnmatchcase(path, pat) for pat in FROM_DRAWING):
        return None
    row = ranges.find(path)
    if row is None:
        return None
    lo, hi = (float(v) for v in row.typical)
    typical = f"typical {row.typical_text()} ({row.source})"
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo and not (row.magnitude or lo == 0):
        return None
    if row.magnitude or lo == 0.0:
        return (0.0, hi, False, f"table of ranges: 0 +- {hi:g}, {typical}") if hi > 0 else None
    if lo > 0 and start > 0:
        return (math.sqrt(lo * hi), math.log(hi / lo) / 2.0, True,
                f"table of ranges: log-normal, {typical} = +-1 sigma")
    return ((lo + hi) / 2.0, (hi - lo) / 2.0, False,
            f"table of ranges: {typical} = +-1 sigma")


def build_prior(inst, paths: Sequence[str], start: Mapping[str, float],
                prior: Mapping[str, float | str] | None = None,
                prior_scale: float = 1.0) -> Prior:
    """The prior of ``paths``: from the table of ranges (module docstring), ``prior``
    overriding it.

    Parameters
    ----------
    inst : Instrument
        The model (effect parameters' units are looked up in it for the fallback widths).
    paths : sequence of str
        Free parameter paths (canonical, as :func:`~nfs.fit.params.expand_paths` gives).
    start : mapping
        Start value of each path: the centre of an override's or a fallback's prior, and
        which form a positive quantity's prior takes (a start of 0, a term switched off,
        keeps a linear prior).
    prior : mapping of str to float or str, optional
        Overrides {path or glob pattern: width}, centred on the start value; a number is an
        absolute width in the parameter's unit, ``"N%"`` a width relative to the start
        value, ``inf`` no prior.  Patterns are tried in the mapping's order before the table.
    prior_scale : float
        Every width is multiplied by it (> 0; inf: no prior at all).

    Returns
    -------
    Prior
    """
    if not prior_scale > 0:
        raise NfsError(f"prior_scale must be > 0 (inf: no prior), got {prior_scale}")
    user = [(pat, _parse_width(pat, w)) for pat, w in (prior or {}).items()]
    centre, sigma, reason, log = [], [], [], []
    for p in paths:
        v = float(start[p])
        row = next((w for pat, w in user if fnmatch.fnmatchcase(p, pat) or pat == p), None)
        table = None if row is not None else range_prior(p, v)
        if table is not None:
            c, s, lg, why = table
        else:
            row = row or _fallback_width(inst, p)
            c, s, lg, why = v, row.sigma(v), False, row.reason
        centre.append(c)
        sigma.append(s * prior_scale)
        reason.append(why)
        log.append(lg)
    return Prior(tuple(paths), np.array(centre, dtype=float), np.array(sigma, dtype=float),
                 tuple(reason), np.array(log, dtype=bool))
