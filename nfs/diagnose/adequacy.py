"""Is the model's thermal structure adequate?  The structural alternatives of
:mod:`nfs.diagnose.structure` scored against the model, and a verdict.

Scoring (:func:`thermal_adequacy`).  The thermometer residual is that of the thermal stage
of :func:`nfs.diagnose.fit.fit_model` (model readings minus ``temp_fog_c``, ``temp_acc_x_c``,
``temp_acc_y_c`` at knots every ``decimate_s``), evaluated by :func:`nfs.diagnose.thermal_residual.thermal_residual_parts`.

1. The model's own thermal stage (:func:`~nfs.diagnose.fit.default_free`, 20 parameters
   for the default instrument) is refined from the given values by Gauss-Newton steps with
   the Jacobian J_0 frozen (a chord method; forward differences, one residual evaluation
   per parameter).  When the refit moves the model far (its sum of squares falls by more
   than 10 %: the model was not fitted to these runs) J_0 is computed again at the refitted
   point.  A model fitted by ``nfs fit`` is only polished.
2. Each alternative's new numbers theta (positive capacities and conductances in log) are
   screened by one bounded Gauss-Newton step of all numbers from the alternative's start,
   with Z = [J_0, d r / d theta] (1 + k evaluations).  The ``refine_top`` best are then
   fitted: theta by variable projection, min |(I - J_0 J_0^+) r(theta)|^2
   (:func:`scipy.optimize.least_squares`, bounded: the model's parameters enter through
   the frozen J_0), then up to three chord steps of all numbers together, each kept only if
   the evaluated residual falls.  This is why the check costs a fraction of the model's
   own thermal fit: a full refit of the 20 model parameters per alternative would cost
   that fit again for every alternative.
3. Score: leave-one-start-temperature-out cross-validated RMS of the three thermometers
   [K], pooled (runs with the same start temperature are held out together).  The refit
   per fold is one bounded Gauss-Newton step of all numbers on the residual linearised at
   the all-runs fit, r + Z beta, from per-run Gram matrices (the linear approximation of
   leave-one-out, Hastie, Tibshirani and Friedman, "The Elements of Statistical Learning",
   2nd ed., 2009, section 7.10; Efron and Tibshirani, "An Introduction to the Bootstrap",
   1993, chapter 11).  Checked against the exact CV, fit_model refitting every fold: with a
   hidden 0.3 W/K link on 4 start temperatures, 34.9 vs 34.1 mK for the model and 20.8
   vs 20.6 mK for the link alternative (tests/diagnose/test_structure.py).  In each fold,
   directions of the column-scaled Gram matrix whose eigenvalue is below 1e-6 of the
   largest are not fitted (a truncated-SVD solve): the other start temperatures do not
   determine them, and fitting them would let one fold's noise swing the held-out
   prediction (leaving out the 54 C run leaves the TEC slope above its set point, c_c, to
   the 28 C run alone).  A CV, not an information criterion: the thermometer noise
   floor is known, but a wrong structure is absorbed *in-sample* by the model's 20 free
   parameters (with a hidden 0.3 W/K link, the default refitted to 4 start temperatures
   sits at 1.0x its floor in-sample and 1.7x out of sample), so only the held-out
   residual shows it.  The same score for the model and every alternative; an alternative
   beats the model when its CV RMS is lower by more than :data:`CV_DROP`.

Adequacy.  Per thermometer and stage (start-up: t < ``startup_s`` = 3600 s after power-on;
stable: after) the model's held-out (CV) residual RMS is compared with the thermometer's
noise floor sqrt(noise_c^2 + quantum_c^2 / 12) [K] from the instrument: white noise plus a
rounding error of variance q^2/12 (the pseudo-quantisation-noise model of Widrow and Kollar,
"Quantization Noise", Cambridge University Press, 2008; only approximate here, the 0.01 K
noise dithers the 0.0625 K quantum weakly, which the 1.5x factor covers).  The floor is
not measured from the residual's high-frequency part: with the default 0.0625 K quantum and
0.01 K noise, consecutive samples of a slowly moving temperature round to the same level,
so a difference-based estimate comes out far below the true per-sample error.  The
structure is adequate when every channel is within :data:`ADEQUACY_FACTOR` (1.5x) of its
floor and no structural alternative beats the model.

:func:`beats_structure` says whether a thermal candidate beats the model and the best
structural alternative, pooled and run by run (the diagnosis names a thermal candidate only
then), and
:func:`one_sided` tests a physically one-sided coefficient (heat power >= 0 W, lag >= 0 s).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np
from scipy.optimize import least_squares, lsq_linear
from scipy.stats import norm, ttest_1samp

from ..docfields import document_fields
from ..effects.thermometer import THERMOMETERS
from ..errors import NfsError
from ..instrument import Instrument
from ..io.measurement import Run
from .fit import default_free
from .start_state import StartModel
from .thermal_residual import DEFAULT_START, prepare_thermal, thermal_residual_parts
from .params import fit_bounds, get_param, set_params
from .structure import StructuralAlternative, structural_alternatives

__all__ = ["AlternativeScore", "ChannelFit", "ThermalAdequacy", "OneSided", "thermal_adequacy",
           "beats_structure", "better_run_by_run", "structure_rival", "MODEL_RIVAL",
           "one_sided", "ADEQUACY_FACTOR", "BEATS_ALPHA", "CV_DROP", "STARTUP_S",
           "DEFAULT_DECIMATE_S", "REFINE_TOP", "STAGES"]

#: A channel is adequate when its residual RMS is within this factor of its noise floor.
ADEQUACY_FACTOR = 1.5
#: Relative drop of the CV RMS an alternative must exceed to beat the model.
CV_DROP = 0.05
#: Level of the one-sided paired test by which a thermal candidate beats the structure.
BEATS_ALPHA = 0.05
#: End of the start-up stage [s] after power-on (docs/physics.md section 1: 30-90 min).
STARTUP_S = 3600.0
#: Default spacing of the residual grid [s].
DEFAULT_DECIMATE_S = 30.0
#: Alternatives fitted to convergence after the one-step screening.
REFINE_TOP = 4
#: The two stages of a run.
STAGES = ("start-up", "stable")

_EIG_TOL = 1e-6


# ---------------------------------------------------------------------------------------------
# Results

@dataclass(frozen=True)
class ChannelFit:
    """The model's thermometer residual in one stage against the thermometer's floor."""

    thermometer: str
    """``fog``, ``acc_x`` or ``acc_y``."""
    stage: str
    """``start-up`` (t < startup_s after power-on) or ``stable``."""
    rms_k: float
    """Residual RMS of the model after its thermal refit on all runs (in-sample) [K]."""
    cv_rms_k: float
    """RMS of the held-out residual (leave-one-start-temperature-out) [K]: what the
    verdict uses, since the model's free parameters can absorb a wrong structure in-sample
    at the price of values that do not carry over to another start temperature."""
    floor_k: float
    """Noise floor sqrt(noise_c^2 + quantum_c^2 / 12) [K]."""
    n_knots: int
    """Residuals it rests on."""
    factor: float
    """The adequacy factor the ratio is held to."""

    @property
    def ratio(self) -> float:
        """cv_rms_k / floor_k."""
        return self.cv_rms_k / self.floor_k if self.floor_k > 0 else math.inf

    @property
    def adequate(self) -> bool:
        """ratio <= factor (a channel without knots counts as adequate)."""
        return self.n_knots == 0 or self.ratio <= self.factor


@dataclass(frozen=True)
class AlternativeScore:
    """What one alternative changes and what it gains."""

    name: str
    """Name of the alternative."""
    kind: str
    """``split``, ``insert``, ``link``, ``thermometer``, ``tec`` or ``effect``."""
    description: str
    """One sentence: what it changes."""
    params: dict[str, float]
    """Fitted new numbers {path: value}."""
    cv_rms_before_k: float
    """Leave-one-start-temperature-out CV RMS of the three thermometers, model [K]."""
    cv_rms_after_k: float
    """The same with the alternative [K]."""
    rms_before_k: dict[str, dict[str, float]]
    """Model residual RMS {thermometer: {stage: K}}."""
    rms_after_k: dict[str, dict[str, float]]
    """Residual RMS with the alternative {thermometer: {stage: K}}."""
    cv_channels_before_k: dict[str, dict[str, float]]
    """Held-out residual RMS of the model {thermometer: {stage: K}}."""
    cv_channels_after_k: dict[str, dict[str, float]]
    """Held-out residual RMS with the alternative {thermometer: {stage: K}}."""
    refined: bool
    """True: fitted (variable projection, then chord steps) and its RMS evaluated; False:
    screened only (one linearised Gauss-Newton step from its start; its numbers and RMS
    are those of the linearised residual)."""
    instrument: Instrument = field(repr=False, compare=False)
    """The fitted alternative instrument (the model's parameters moved with it)."""
    cv_sse_by_run: tuple[float, ...] = ()
    """Held-out squared residual summed over each run's knots, with the alternative [K^2]
    (the pairs :func:`beats_structure` tests)."""

    @property
    def cv_drop(self) -> float:
        """Relative drop of the CV RMS."""
        return 1.0 - self.cv_rms_after_k / self.cv_rms_before_k

    @property
    def beats_model(self) -> bool:
        """cv_drop > :data:`CV_DROP`."""
        return self.cv_drop > CV_DROP

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return {"name": self.name, "kind": self.kind, "description": self.description,
                "params": dict(self.params), "cv_rms_before_k": self.cv_rms_before_k,
                "cv_rms_after_k": self.cv_rms_after_k, "cv_drop": self.cv_drop,
                "beats_model": self.beats_model, "refined": self.refined,
                "rms_before_k": {k: dict(v) for k, v in self.rms_before_k.items()},
                "rms_after_k": {k: dict(v) for k, v in self.rms_after_k.items()},
                "cv_channels_before_k": {k: dict(v)
                                         for k, v in self.cv_channels_before_k.items()},
                "cv_channels_after_k": {k: dict(v)
                                        for k, v in self.cv_channels_after_k.items()}}


@document_fields
@dataclass(frozen=True)
class ThermalAdequacy:
    """Does the model's thermal structure fit the thermometers?"""

    channels: tuple[ChannelFit, ...]
    """Per thermometer and stage: residual RMS against the floor."""
    factor: float
    """A channel is adequate when its RMS is within this factor of its floor."""
    adequate: bool
    """Every channel adequate and no structural alternative beats the model."""
    cv_rms_k: float
    """The model's own CV RMS [K] (module docstring)."""
    alternatives: tuple[AlternativeScore, ...]
    """Every alternative scored, best CV first."""
    best: AlternativeScore | None
    """The structural alternative (kind != effect) with the lowest CV RMS, or None."""
    model: Instrument = field(repr=False, compare=False)
    """The model after its thermal refit."""
    message: str = ""
    """A sentence a user can act on."""
    time_s: float = 0.0
    """Wall time [s]."""
    n_evaluations: int = 0
    """Thermometer residual evaluations (network solves of all runs) it took."""
    cv_sse_by_run: tuple[float, ...] = ()
    """The model's held-out squared residual summed over each run's knots [K^2]."""

    @property
    def worst(self) -> ChannelFit:
        """The channel with the largest ratio to its floor."""
        return max(self.channels, key=lambda c: c.ratio if c.n_knots else -1.0)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return {"adequate": self.adequate, "factor": self.factor, "cv_rms_k": self.cv_rms_k,
                "message": self.message, "time_s": self.time_s,
                "n_evaluations": self.n_evaluations,
                "channels": [{"thermometer": c.thermometer, "stage": c.stage,
                              "rms_k": c.rms_k, "cv_rms_k": c.cv_rms_k,
                              "floor_k": c.floor_k, "ratio": c.ratio,
                              "n_knots": c.n_knots, "adequate": c.adequate}
                             for c in self.channels],
                "best": None if self.best is None else self.best.name,
                "alternatives": [a.to_dict() for a in self.alternatives]}


# ---------------------------------------------------------------------------------------------
# The residual, its labels and the linear machinery

class _Problem:
    """The prepared runs, the label of every residual (thermometer, stage) and their groups."""

    def __init__(self, runs: Sequence[Run], decimate_s: float, startup_s: float,
                 start: StartModel | None = DEFAULT_START):
        self.data = [prepare_thermal(r, decimate_s) for r in runs]
        self.start = start
        self.cols = tuple(THERMOMETERS.values())
        self.names = tuple(THERMOMETERS)
        self.labels: list[tuple[np.ndarray, np.ndarray]] = []
        for rd in self.data:
            which, stable = [], []
            for i, col in enumerate(self.cols):
                t = rd.t_knot[rd.mask[col]] - rd.t_knot[0]
                which.append(np.full(t.size, i))
                stable.append(t >= startup_s)
            self.labels.append((np.concatenate(which), np.concatenate(stable)))
        t0 = [round(rd.t0_c, 1) for rd in self.data]
        keys = sorted(set(t0))
        self.group = np.array([keys.index(k) for k in t0], dtype=int)
        self.n_eval = 0

    def resid(self, inst: Instrument) -> list[np.ndarray]:
        """Model minus measured, the three thermometers stacked, per run [K]."""
        return self.resid_many([inst])[0]

    def resid_many(self, insts: Sequence[Instrument]) -> list[list[np.ndarray]]:
        """:meth:`resid` of instruments of one structure, solved as one stack."""
        self.n_eval += len(insts)
        return [[np.concatenate([parts[c][i] for c in self.cols]) for i in range(len(self.data))]
                for parts in thermal_residual_parts(insts, self.data, self.start)]

    def rms(self, r: list[np.ndarray]) -> dict[str, dict[str, float]]:
        """RMS [K] per thermometer and stage."""
        out: dict[str, dict[str, float]] = {}
        for i, name in enumerate(self.names):
            out[name] = {}
            for s, stage in enumerate(STAGES):
                x = np.concatenate([ri[(w == i) & (st == bool(s))]
                                    for ri, (w, st) in zip(r, self.labels)])
                out[name][stage] = float(np.sqrt(np.mean(x * x))) if x.size else math.nan
        return out

    def counts(self) -> dict[str, dict[str, int]]:
        """Residuals per thermometer and stage."""
        return {name: {stage: int(sum(np.sum((w == i) & (st == bool(s)))
                                      for w, st in self.labels))
                       for s, stage in enumerate(STAGES)} for i, name in enumerate(self.names)}

    def linear_fit(self, r: list[np.ndarray], Z: list[np.ndarray], lo: np.ndarray,
                   hi: np.ndarray, folds: bool = True
                   ) -> tuple[float, np.ndarray, list[np.ndarray]]:
        """Leave-one-start-temperature-out CV of the linearised residual r + Z beta.

        Returns (CV RMS [K], beta of all runs, held-out residual per run).  beta minimises
        |r + Z beta| over all runs within lo <= beta <= hi (the parameters' box); per group
        g, beta_-g minimises it over the other groups within the same box (the one-step
        refit per fold) and the held-out error is r_g + Z_g beta_-g, pooled over all
        groups.  Per-run Gram matrices make a fold cost one small bounded solve.  With
        ``folds`` False only beta is computed (CV NaN, no held-out residual).
        """
        scale = np.sqrt(sum(np.sum(z * z, axis=0) for z in Z))
        scale = np.where(scale > 0, scale, 1.0)
        n_g = int(self.group.max()) + 1
        p = Z[0].shape[1]
        G, h = np.zeros((n_g, p, p)), np.zeros((n_g, p))
        n = 0
        for g, ri, zi in zip(self.group, r, Z):
            zs = zi / scale
            G[g] += zs.T @ zs
            h[g] -= zs.T @ ri
            n += ri.size
        lo_s, hi_s = lo * scale, hi * scale
        beta = _bounded_solve(G.sum(0), h.sum(0), lo_s, hi_s)
        if not folds:
            return math.nan, beta / scale, []
        held: list[np.ndarray] = [np.empty(0)] * len(r)
        for g in range(n_g):
            step = _bounded_solve(G.sum(0) - G[g], h.sum(0) - h[g], lo_s, hi_s) / scale
            for i in np.flatnonzero(self.group == g):
                held[i] = r[i] + Z[i] @ step
        return math.sqrt(_sse(held) / n), beta / scale, held


def _bounded_solve(G: np.ndarray, h: np.ndarray, lo: np.ndarray, hi: np.ndarray
                   ) -> np.ndarray:
    """argmin beta^T G beta - 2 h^T beta within [lo, hi] (G symmetric, maybe singular).

    Written as the bounded least-squares problem |A beta - b|^2 with G = A^T A, A^T b = h
    from the eigen-decomposition of G (directions with eigenvalue below ``_EIG_TOL`` of the
    largest dropped: the data do not determine them; module docstring, item 3), solved by
    :func:`scipy.optimize.lsq_linear` when the unbounded solution leaves the box.
    """
    s, v = np.linalg.eigh(G)
    keep = s > _EIG_TOL * max(s.max(), 0.0) if s.size else s > 0
    if not keep.any():
        return np.clip(np.zeros(h.size), lo, hi)
    root = np.sqrt(s[keep])
    a = root[:, None] * v[:, keep].T
    b = (v[:, keep].T @ h) / root
    free = np.linalg.lstsq(a, b, rcond=None)[0]
    if np.all(free >= lo) and np.all(free <= hi):
        return free
    return lsq_linear(a, b, bounds=(lo, hi), method="bvls").x


def _jacobian(prob: _Problem, build: Callable[[np.ndarray], Instrument], x: np.ndarray,
              r0: list[np.ndarray], steps: np.ndarray) -> list[np.ndarray]:
    """Forward differences d r / d x per run, the moved instruments solved as one stack."""
    cols: list[list[np.ndarray]] = [[] for _ in r0]
    moved_all = []
    for j, hj in enumerate(steps):
        xj = x.copy()
        xj[j] += hj
        moved_all.append(build(xj))
    for hj, moved in zip(steps, prob.resid_many(moved_all) if moved_all else []):
        for i, (m, b) in enumerate(zip(moved, r0)):
            cols[i].append((m - b) / hj)
    return [np.column_stack(c) if c else np.zeros((b.size, 0)) for c, b in zip(cols, r0)]


def _sse(r: list[np.ndarray]) -> float:
    return float(sum(ri @ ri for ri in r))


class _Transform:
    """Numbers with a positive lower bound (capacities, conductances) are fitted in log:
    their steps are then relative, the same for 0.05 W/K and 3500 J/K."""

    def __init__(self, start: Sequence[float], bounds: Sequence[tuple[float, float]]):
        self.log = np.array([lo > 0 for lo, _ in bounds], dtype=bool)
        self.lo = np.array([lo for lo, _ in bounds], dtype=float)
        self.hi = np.array([hi for _, hi in bounds], dtype=float)
        self.ulo, self.uhi = self.to_u(self.lo), self.to_u(self.hi)
        self.u0 = self.to_u(np.clip(np.array(start, dtype=float), self.lo, self.hi))

    def to_u(self, v: np.ndarray) -> np.ndarray:
        return np.where(self.log, np.log(np.where(self.log, v, 1.0)), v)

    def to_v(self, u: np.ndarray) -> np.ndarray:
        u = np.clip(u, self.ulo, self.uhi)
        return np.where(self.log, np.exp(u), u)

    def steps(self, u: np.ndarray) -> np.ndarray:
        """Forward-difference steps, inward from the upper bound."""
        h = np.where(self.log, 1e-3, 1e-3 * np.maximum(self.hi - self.lo, 1e-9))
        return np.where(u + h > self.uhi, -h, h)


@dataclass
class _Model:
    """The model after its chord refit, with its frozen Jacobian."""

    inst: Instrument
    paths: list[str]
    x: np.ndarray          # fitted values of the paths
    bounds: np.ndarray     # (n, 2) fit bounds of the paths
    r: list[np.ndarray]
    J: list[np.ndarray]
    Q: np.ndarray          # orthonormal basis of the column space of the stacked J

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of a step of the model parameters from x."""
        return self.bounds[:, 0] - self.x, self.bounds[:, 1] - self.x

    def moved(self, inst: Instrument, step: np.ndarray) -> Instrument:
        """``inst`` with the model parameters moved by ``step`` (within their bounds)."""
        if not self.paths:
            return inst
        return set_params(inst, {p: float(np.clip(get_param(inst, p) + d, lo, hi))
                                 for p, d, (lo, hi) in zip(self.paths, step, self.bounds)})

    def project(self, r: np.ndarray) -> np.ndarray:
        """(I - Q Q^T) r: the part of r the model's own parameters cannot absorb."""
        return r - self.Q @ (self.Q.T @ r) if self.Q.size else r


def _fit_model(prob: _Problem, inst: Instrument, chord_steps: int = 4) -> _Model:
    """Chord (frozen-Jacobian Gauss-Newton) refit of the model's default free thermal set.

    When the refit moved the model far (its residual sum of squares fell by more than
    10 %: the model was not fitted to these runs), the Jacobian is computed again at the
    refitted point and the chord steps repeated, so that the frozen Jacobian the
    alternatives and the CV rely on belongs to the fitted model.
    """
    paths = default_free(inst, ("thermal",))
    bounds = np.array([fit_bounds(inst, p) for p in paths], dtype=float).reshape(-1, 2)

    def build(x):
        return set_params(inst, dict(zip(paths, np.clip(x, bounds[:, 0], bounds[:, 1]))))

    x = np.array([get_param(inst, p) for p in paths])
    r = prob.resid(inst)
    for _ in range(2):
        sse_start = _sse(r)
        steps = np.array([1e-3 * abs(v) if v else 1e-3 for v in x])
        steps = np.where(x + steps > bounds[:, 1], -steps, steps)
        J = _jacobian(prob, build, x, r, steps)
        Js = np.vstack(J)
        scale = np.sqrt(np.sum(Js * Js, axis=0))
        scale = np.where(scale > 0, scale, 1.0)
        u, sv, vt = np.linalg.svd(Js / scale, full_matrices=False)
        good = sv > 1e-10 * sv[0] if sv.size else sv > 0
        Q = u[:, good]
        pinv = (vt[good].T / sv[good]) @ u[:, good].T / scale[:, None]
        for _ in range(chord_steps):
            x_new = np.clip(x + pinv @ -np.concatenate(r), bounds[:, 0], bounds[:, 1])
            r_new = prob.resid(build(x_new))
            gain = _sse(r) - _sse(r_new)
            if gain <= 0:
                break
            x, r = x_new, r_new
            if gain < 1e-3 * _sse(r):
                break
        if _sse(r) > 0.9 * sse_start:
            break
    return _Model(build(x), paths, x, bounds, r, J, Q)


def _score(prob: _Problem, model: _Model, alt: StructuralAlternative, refine: bool,
           cv_model: float, rms_model: dict, max_nfev: int,
           u_start: np.ndarray | None = None, chord_steps: int = 3
           ) -> tuple[AlternativeScore, np.ndarray]:
    """Screen or fit one alternative; (score, its fitted u).

    Screening: the residual and its Jacobian at the start u_0 (1 + k evaluations); the
    alternative's numbers and the model's move by the bounded linear fit, the CV and the
    RMS are those of the linearised residual.  Refinement: variable projection from
    ``u_start`` (at most ``max_nfev`` evaluations besides the Jacobians), then up to
    ``chord_steps`` chord steps of all numbers, each kept when the evaluated residual falls;
    the CV is taken on the residual linearised at the last evaluated point.
    """
    tr = _Transform(alt.start, alt.bounds)

    def build(u):
        return alt.build(tr.to_v(u))

    u = tr.u0 if u_start is None else np.clip(u_start, tr.ulo, tr.uhi)
    if refine:
        res = least_squares(lambda uu: model.project(np.concatenate(prob.resid(build(uu)))),
                            u, bounds=(tr.ulo, tr.uhi), method="trf", x_scale="jac",
                            diff_step=1e-3, max_nfev=max_nfev, ftol=1e-4, xtol=1e-4)
        u = res.x
    r_a = prob.resid(build(u))
    Ja = _jacobian(prob, build, u, r_a, tr.steps(u))
    Z = [np.hstack([jm, ja]) for jm, ja in zip(model.J, Ja)]
    lo_m, hi_m = model.box()
    lo = np.concatenate([lo_m, tr.ulo - u])
    hi = np.concatenate([hi_m, tr.uhi - u])
    hi = np.maximum(hi, lo + 1e-12)
    cv, beta, held = prob.linear_fit(r_a, Z, lo, hi)
    n_m = len(model.paths)
    u_fit = np.clip(u + beta[n_m:], tr.ulo, tr.uhi)
    final = model.moved(build(u_fit), beta[:n_m])
    r_f = [ri + zi @ beta for ri, zi in zip(r_a, Z)]
    if refine:
        # chord steps of all the numbers (model's and alternative's) with the frozen
        # Jacobian Z, each accepted while it lowers the evaluated residual; the CV is then
        # taken from the evaluated all-runs fit
        r_f, final, u_fit, shift = r_a, build(u), u, np.zeros(beta.size)
        for _ in range(chord_steps):
            _, step, _ = prob.linear_fit(r_f, Z, lo - shift,
                                         np.maximum(hi - shift, lo - shift + 1e-12), folds=False)
            new_shift = shift + step
            u_new = np.clip(u + new_shift[n_m:], tr.ulo, tr.uhi)
            cand = model.moved(build(u_new), new_shift[:n_m])
            r_c = prob.resid(cand)
            if _sse(r_c) >= _sse(r_f) * (1.0 - 1e-3):
                if _sse(r_c) < _sse(r_f):
                    r_f, final, u_fit, shift = r_c, cand, u_new, new_shift
                break
            r_f, final, u_fit, shift = r_c, cand, u_new, new_shift
        cv, _, held = prob.linear_fit(r_f, Z, lo - shift,
                                      np.maximum(hi - shift, lo - shift + 1e-12))
    params = {p: float(v) for p, v in zip(alt.free, tr.to_v(u_fit))}
    score = AlternativeScore(
        name=alt.name, kind=alt.kind, description=alt.description, params=params,
        cv_rms_before_k=cv_model, cv_rms_after_k=cv, rms_before_k=rms_model[0],
        rms_after_k=prob.rms(r_f), cv_channels_before_k=rms_model[1],
        cv_channels_after_k=prob.rms(held), refined=refine, instrument=final,
        cv_sse_by_run=tuple(_sse([h]) for h in held))
    return score, u_fit


# ---------------------------------------------------------------------------------------------
# The verdict

def _floor_k(inst: Instrument, name: str) -> float:
    m = inst.thermometers[name]
    return math.sqrt(m.noise_c ** 2 + m.quantum_c ** 2 / 12.0)


def _advice(best: AlternativeScore) -> str:
    """What to change in the model for the best alternative, in words."""
    v = list(best.params.values())
    if best.kind == "link":
        a, b = best.name.split(" ", 1)[1].split("-", 1)
        return (f"add a [[thermal.links]] between {a} and {b} of about {v[0]:.3g} W/K "
                "(or the physical path it stands for)")
    if best.kind == "split":
        node = best.name.split(" ", 1)[1]
        return (f"give {node} an inner part: split it into two nodes linked by about "
                f"{v[0]:.3g} W/K (a layer or a mass the model lumps together)")
    if best.kind == "insert":
        return (f"put a node of about {v[0]:.3g} J/K on the path ({v[1]:.3g} and {v[2]:.3g} "
                "W/K on either side)")
    if best.kind == "thermometer":
        path = next(iter(best.params))
        t, node = path[len("thermometers."):].split(".nodes.", 1)
        return (f"check where the {t} thermometer sits: it reads as if {100 * v[0]:.0f} % of "
                f"it were {node} ([thermometers.{t}] nodes)")
    if best.kind == "tec":
        return (f"set the TEC law's set point T_set to about {v[0]:.3g} C "
                "([[effects]] tec_power)")
    return f"add {best.name}"


def _message(channels: Sequence[ChannelFit], structural: Sequence[AlternativeScore],
             factor: float, improves: bool) -> str:
    """The verdict in one sentence: where the structure fails, the best fix, what to do."""
    worst = max(channels, key=lambda c: c.ratio if c.n_knots else -1.0)
    who = "FOG" if worst.thermometer == "fog" else worst.thermometer
    head = (f"the {who} thermometer residual (held out by start temperature) in the "
            f"{worst.stage} stage is {worst.ratio:.1f}x its floor ({worst.floor_k:.3f} K)")
    n_alt = len(structural)
    if worst.ratio <= factor and not improves:
        return (f"the thermal structure fits: every thermometer residual is within "
                f"{factor:g}x its floor in both stages (worst: {head[4:]}); none of {n_alt} "
                "generic structural alternatives beats it")
    if not improves:
        return (f"{head}: the thermal structure does not fit there, and none of {n_alt} "
                "generic alternatives (one more node, a free link, the FOG thermometer "
                "elsewhere) does better; check the TEC law, the chamber record and the "
                "thermometer channels")
    best = structural[0]
    after = best.cv_channels_after_k[worst.thermometer][worst.stage] / worst.floor_k
    lead = (f"{head}: the thermal structure does not fit there" if worst.ratio > factor else
            f"{head}, yet a structural alternative lowers the CV RMS by "
            f"{100 * best.cv_drop:.0f} %")
    out = (f"{lead}; the best alternative, {best.name}, brings it to {after:.1f}x "
           f"(CV RMS {1000 * best.cv_rms_before_k:.1f} -> {1000 * best.cv_rms_after_k:.1f} "
           f"mK); consider: {_advice(best)}")
    tied = [s.name for s in structural[1:]
            if s.cv_rms_after_k < best.cv_rms_after_k / (1.0 - CV_DROP)]
    if tied:
        out += f" (as good within {100 * CV_DROP:g} %: {', '.join(tied)})"
    return (out + ". Until the structure fits, a thermal candidate (a heat source, a lag) "
            "is named only if it beats this alternative")


def thermal_adequacy(inst: Instrument, runs: Sequence[Run],
                     alternatives: Sequence[StructuralAlternative]
                     | Callable[[Instrument], Sequence[StructuralAlternative]] | None = None, *,
                     decimate_s: float = DEFAULT_DECIMATE_S, factor: float = ADEQUACY_FACTOR,
                     startup_s: float = STARTUP_S, refine_top: int = REFINE_TOP,
                     max_nfev: int = 6, start_state: StartModel | None = DEFAULT_START
                     ) -> ThermalAdequacy:
    """Is the thermal structure of ``inst`` adequate for ``runs``? (module docstring).

    Parameters
    ----------
    inst : Instrument
        The model, best already fitted (``nfs fit``); its thermal stage is polished here.
    runs : sequence of Run
        Measured runs with at least two distinct start temperatures.
    alternatives : sequence of StructuralAlternative, or a callable, optional
        Default :func:`structural_alternatives` of the refitted model.  A callable is
        called with the refitted model and returns the alternatives (the way to add named
        candidates, ``lambda m: structural_alternatives(m) + [effect_alternative(m,
        "heat_source", "coil_outer")]``); a sequence is used as given, so it should be
        built on a fitted model.  Kind ``effect`` alternatives are scored but never
        ``best``.
    decimate_s : float
        Spacing of the residual grid [s].
    factor : float
        A channel is adequate when its RMS is within ``factor`` of its floor.
    startup_s : float
        End of the start-up stage [s] after power-on.
    refine_top : int
        How many of the screened alternatives are fitted to convergence.
    max_nfev : int
        Residual evaluations of each refinement (Jacobian evaluations not counted).
    start_state : StartModel or None
        Each run's start estimated with the model (:mod:`nfs.diagnose.start_state`, in
        every residual, the held-out runs' too: a new run's soak is not known either);
        None: the runs were soaked exactly at T0 (the check then has more power: a
        structural error can no longer hide in the starts).

    Raises
    ------
    NfsError
        Fewer than two start temperatures, a run without the thermometer columns.
    """
    t_start = time.perf_counter()
    runs = list(runs)
    if not decimate_s > 0:
        raise NfsError(f"thermal_adequacy: decimate_s must be > 0, got {decimate_s}")
    if not factor >= 1.0:
        raise NfsError(f"thermal_adequacy: factor must be >= 1, got {factor}")
    prob = _Problem(runs, decimate_s, startup_s, start_state)
    if len(set(prob.group)) < 2:
        raise NfsError("thermal_adequacy needs runs at two start temperatures at least "
                       "(leave-one-start-temperature-out validation); got "
                       + (", ".join(f"{r.meta.start_temperature_c:g} C" for r in runs)
                          or "no runs"))
    model = _fit_model(prob, inst)
    cv_model, _, held = prob.linear_fit(model.r, model.J, *model.box())
    rms_model = (prob.rms(model.r), prob.rms(held))
    counts = prob.counts()
    channels = tuple(ChannelFit(name, stage, rms_model[0][name][stage],
                                rms_model[1][name][stage], _floor_k(model.inst, name),
                                counts[name][stage], factor)
                     for name in prob.names for stage in STAGES)
    if alternatives is None:
        alts = structural_alternatives(model.inst)
    elif callable(alternatives):
        alts = list(alternatives(model.inst))
    else:
        alts = list(alternatives)
    screened = []
    for alt in alts:
        s, u = _score(prob, model, alt, False, cv_model, rms_model, max_nfev)
        screened.append((alt, s, u))
    order = sorted(range(len(screened)), key=lambda i: screened[i][1].cv_rms_after_k)
    scores = [s for _, s, _ in screened]
    for i in order[:refine_top]:
        alt, s, u = screened[i]
        scores[i], _ = _score(prob, model, alt, True, cv_model, rms_model, max_nfev, u)
    scores.sort(key=lambda s: s.cv_rms_after_k)
    structural = [s for s in scores if s.kind != "effect"]
    best = structural[0] if structural else None
    improves = best is not None and best.beats_model
    adequate = all(c.adequate for c in channels) and not improves
    message = _message(channels, structural, factor, improves)
    return ThermalAdequacy(channels=channels, factor=factor, adequate=adequate,
                           cv_rms_k=cv_model, alternatives=tuple(scores), best=best,
                           model=model.inst, message=message,
                           time_s=time.perf_counter() - t_start, n_evaluations=prob.n_eval,
                           cv_sse_by_run=tuple(_sse([h]) for h in held))


#: The name :func:`structure_rival` gives the model itself.
MODEL_RIVAL = "the model"


def structure_rival(candidate: AlternativeScore, adequacy: ThermalAdequacy,
                    margin: float = 0.0, alpha: float = BEATS_ALPHA) -> str | None:
    """The rival a thermal candidate does not beat, or None when it beats them all.

    The rival is whichever of the model (:data:`MODEL_RIVAL`) and its structural
    alternatives has the lowest CV RMS.  The candidate beats it when (a) its CV RMS is below
    ``(1 - margin)`` times the rival's and (b) its held-out squared residual is smaller run
    by run: the paired per-run log-ratios are tested one-sided against zero with a t test
    at ``alpha`` (:func:`better_run_by_run`), runs being the independent units (as the drift candidates' run-level
    statistics; a rank test would need 5 runs to reach 5 % at all).  A pooled CV RMS a
    fraction of a percent lower, won on some runs and lost on others, is a tie, not a named
    effect.  The candidate's residual must be the same as the alternatives' (the three
    thermometers at the knots, leave-one-start-temperature-out); :func:`effect_alternative`
    scores a candidate that way.
    """
    refs = [(adequacy.cv_rms_k, adequacy.cv_sse_by_run, MODEL_RIVAL)] + [
        (s.cv_rms_after_k, s.cv_sse_by_run, s.name) for s in adequacy.alternatives
        if s.kind != "effect"]
    ref_cv, ref_sse, rival = min(refs, key=lambda r: r[0])
    return None if better_run_by_run(candidate.cv_rms_after_k, candidate.cv_sse_by_run,
                                     ref_cv, ref_sse, margin, alpha) else rival


def better_run_by_run(cv_rms_k: float, cv_sse_by_run: Sequence[float], ref_cv_rms_k: float,
                      ref_sse_by_run: Sequence[float], margin: float = 0.0,
                      alpha: float = BEATS_ALPHA) -> bool:
    """Is one structure's held-out residual lower than a reference's, pooled (by more than
    ``margin``) and run by run?

    Run by run: the paired per-run log-ratios ln(SSE_ref / SSE) of the held-out squared
    residual, one-sided t test at ``alpha``.  On the log scale a run whose misfit is ten
    times another's weighs the same when both improve by the same factor (the differences
    of the squared residual would let the worst run's scatter hide four runs that all
    improve threefold or more).
    """
    if not (math.isfinite(cv_rms_k) and cv_rms_k < (1.0 - margin) * ref_cv_rms_k):
        return False
    ref = np.asarray(ref_sse_by_run, dtype=float)
    new = np.asarray(cv_sse_by_run, dtype=float)
    if new.size != ref.size or new.size < 2 or np.any(new <= 0) or np.any(ref <= 0):
        return False
    d = np.log(ref / new)
    if not np.any(d > 0):
        return False
    if np.all(d > 0) and np.ptp(d) == 0:   # no spread: the t statistic is undefined
        return True
    return bool(ttest_1samp(d, 0.0, alternative="greater").pvalue < alpha)


def beats_structure(candidate: AlternativeScore, adequacy: ThermalAdequacy,
                    margin: float = 0.0, alpha: float = BEATS_ALPHA) -> bool:
    """Does a thermal candidate beat the model and every structural alternative, pooled and
    run by run? (:func:`structure_rival` is None)."""
    return structure_rival(candidate, adequacy, margin, alpha) is None


# ---------------------------------------------------------------------------------------------
# One-sided physics

@dataclass(frozen=True)
class OneSided:
    """A coefficient that physics keeps on one side of a bound, tested on that side."""

    estimate: float
    """The unconstrained fitted value."""
    stderr: float
    """Its standard error."""
    lower: float
    """The physical lower bound (0 W for a heat source, 0 s for a lag)."""
    z: float
    """(estimate - lower) / stderr."""
    p_value: float
    """One-sided p-value of H0: value <= lower against H1: value > lower, 1 - Phi(z)."""
    constrained: float
    """The constrained estimate max(estimate, lower)."""
    alpha: float
    """Significance level."""

    @property
    def significant(self) -> bool:
        """p_value < alpha (never for an estimate at or below the bound: p >= 0.5)."""
        return self.p_value < self.alpha

    @property
    def at_bound(self) -> bool:
        """The data push the coefficient to the unphysical side."""
        return self.estimate <= self.lower


def one_sided(estimate: float, stderr: float, *, lower: float = 0.0,
              alpha: float = 0.01) -> OneSided:
    """One-sided test and constrained fit of a coefficient with a physical lower bound.

    z = (theta_hat - lower) / se, p = 1 - Phi(z) (the one-sided Wald test; for the
    likelihood-ratio test on the boundary the null distribution is the 50:50 mixture of
    chi^2_0 and chi^2_1, which gives the same p for theta_hat > lower: Self and Liang,
    J. Am. Stat. Assoc. 82 (1987) 605, theorem 2 case 1; Chernoff, Ann. Math. Stat. 25
    (1954) 573).  A negative estimate of a heat power has p >= 0.5: never significant.
    The constrained estimate is the clamp max(theta_hat, lower), the exact minimiser of
    the quadratic (Gauss-Newton) cost in theta with the other coefficients profiled out.

    Raises NfsError for a non-finite estimate or a negative or NaN standard error.
    """
    est, se = float(estimate), float(stderr)
    if not math.isfinite(est):
        raise NfsError(f"one_sided: the estimate must be finite, got {estimate}")
    if not se >= 0.0:
        raise NfsError(f"one_sided: the standard error must be >= 0, got {stderr}")
    d = est - lower
    if se == 0.0:
        z = math.inf if d > 0 else (-math.inf if d < 0 else 0.0)
    else:
        z = d / se
    p = float(norm.sf(z))
    return OneSided(estimate=est, stderr=se, lower=float(lower), z=z, p_value=p,
                    constrained=max(est, float(lower)), alpha=float(alpha))
