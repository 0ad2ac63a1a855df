"""The model's thermometer residual over a set of runs, linearised for the structure check.

:class:`ThermometerProblem` holds the runs on the knots of the thermal stage of
:func:`nfs.fit.calibration.fit_model` (model readings minus ``temp_fog_c``, ``temp_acc_x_c``,
``temp_acc_y_c`` every ``decimate_s``, evaluated by
:func:`nfs.fit.thermal_residual.thermal_residual_parts`), labels every residual by
thermometer and stage (start-up: t < ``startup_s`` after power-on; stable: after) and groups
the runs by start temperature.

1. The model's own thermal stage (:func:`~nfs.fit.free_set.default_free`) is refined
   from the given values by Gauss-Newton steps with the Jacobian J_0 frozen (a chord method;
   forward differences, one residual evaluation per parameter; :func:`chord_refit`).  When
   the refit moves the model far (its sum of squares falls by more than 10 %: the model was
   not fitted to these runs) J_0 is computed again at the refitted point.  A model fitted by
   ``nfs fit`` is only polished.
2. Score (:meth:`ThermometerProblem.linear_fit`): leave-one-start-temperature-out
   cross-validated RMS of the three thermometers [K], pooled (runs with the same start
   temperature are held out together).  The refit per fold is one bounded Gauss-Newton step
   of all numbers on the residual linearised at the all-runs fit, r + Z beta, from per-run
   Gram matrices (the linear approximation of leave-one-out, Hastie, Tibshirani and
   Friedman, "The Elements of Statistical Learning", 2nd ed., 2009, section 7.10; Efron and
   Tibshirani, "An Introduction to the Bootstrap", 1993, chapter 11); the tests check it
   against the exact CV, fit_model refitting every fold.  In each fold, directions of the
   column-scaled Gram matrix whose eigenvalue is below 1e-6 of the largest are not fitted (a
   truncated-SVD solve, :func:`bounded_solve`): the other start temperatures do not
   determine them, and fitting them would let one fold's noise swing the held-out
   prediction (leaving out the only run that starts above a TEC's set point leaves the
   slope there, c_c, to runs that barely reach it).  A CV, not an information criterion:
   the thermometer noise floor is known, but a wrong structure is absorbed *in-sample* by
   the model's free parameters, at the price of values that do not carry over to another
   start temperature, so only the held-out residual shows it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from scipy.optimize import lsq_linear

from ..effects.thermometer import THERMOMETERS
from ..instrument import Instrument
from ..run import Run
from .free_set import default_free
from .params import fit_bounds, get_param, list_params, set_params
from .start_state import StartModel
from .thermal_residual import DEFAULT_START, prepare_thermal, thermal_residual_parts

__all__ = ["ADEQUACY_STAGES", "STAGE_WORDS",
           "ThermometerProblem", "bounded_solve", "residual_jacobian",
           "sum_of_squares", "ChordModel", "chord_refit"]

#: The two stages of a run.
ADEQUACY_STAGES = ("startup", "stable")

#: The stages in words.
STAGE_WORDS = {"startup": "start-up", "stable": "stable"}

_EIG_TOL = 1e-6


class ThermometerProblem:
    """The prepared runs, the label of every residual (thermometer, stage) and their groups.

    ``data``: each run on the knots (:func:`~nfs.fit.thermal_residual.prepare_thermal`);
    ``labels``: per run, the thermometer index and the stable-stage flag of every residual;
    ``group``: the CV group of every run (its start temperature, to 0.1 K); ``n_eval``: the
    instruments evaluated so far (network solves of all runs).
    """

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
            for s, stage in enumerate(ADEQUACY_STAGES):
                x = np.concatenate([ri[(w == i) & (st == bool(s))]
                                    for ri, (w, st) in zip(r, self.labels)])
                out[name][stage] = float(np.sqrt(np.mean(x * x))) if x.size else math.nan
        return out

    def counts(self) -> dict[str, dict[str, int]]:
        """Residuals per thermometer and stage."""
        return {name: {stage: int(sum(np.sum((w == i) & (st == bool(s)))
                                      for w, st in self.labels))
                       for s, stage in enumerate(ADEQUACY_STAGES)} for i, name in enumerate(self.names)}

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
        beta = bounded_solve(G.sum(0), h.sum(0), lo_s, hi_s)
        if not folds:
            return math.nan, beta / scale, []
        held: list[np.ndarray] = [np.empty(0)] * len(r)
        for g in range(n_g):
            step = bounded_solve(G.sum(0) - G[g], h.sum(0) - h[g], lo_s, hi_s) / scale
            for i in np.flatnonzero(self.group == g):
                held[i] = r[i] + Z[i] @ step
        return math.sqrt(sum_of_squares(held) / n), beta / scale, held


def bounded_solve(G: np.ndarray, h: np.ndarray, lo: np.ndarray, hi: np.ndarray
                  ) -> np.ndarray:
    """argmin beta^T G beta - 2 h^T beta within [lo, hi] (G symmetric, maybe singular).

    Written as the bounded least-squares problem |A beta - b|^2 with G = A^T A, A^T b = h
    from the eigen-decomposition of G (directions with eigenvalue below ``_EIG_TOL`` of the
    largest dropped: the data do not determine them; module docstring, item 2), solved by
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


def residual_jacobian(prob: ThermometerProblem, build: Callable[[np.ndarray], Instrument],
                      x: np.ndarray,
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


def sum_of_squares(r: list[np.ndarray]) -> float:
    """Sum of the squared residuals of every run [K^2]."""
    return float(sum(ri @ ri for ri in r))


@dataclass
class ChordModel:
    """The model after its chord refit, with its frozen Jacobian."""

    inst: Instrument
    """The refitted model."""
    paths: list[str]
    """Its free thermal parameters."""
    x: np.ndarray
    """Their fitted values."""
    bounds: np.ndarray
    """(n, 2) fit bounds of the paths."""
    r: list[np.ndarray]
    """Model minus measured per run, the three thermometers stacked [K]."""
    J: list[np.ndarray]
    """The frozen Jacobian d r / d x per run."""
    Q: np.ndarray
    """Orthonormal basis of the column space of the stacked J."""

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of a step of the model parameters from x."""
        return self.bounds[:, 0] - self.x, self.bounds[:, 1] - self.x

    def kept(self, inst: Instrument) -> np.ndarray:
        """Which of the model's parameters ``inst`` still has (bool per path): an alternative
        that rebuilds a part (a lumped coil wound, :mod:`nfs.fit.wound_alternative`)
        replaces that part's numbers by its own."""
        names = set(list_params(inst))
        return np.array([p in names for p in self.paths], dtype=bool)

    def moved(self, inst: Instrument, step: np.ndarray) -> Instrument:
        """``inst`` with the model parameters it has (:meth:`kept`) moved by ``step``
        (within their bounds)."""
        if not self.paths:
            return inst
        keep = self.kept(inst)
        return set_params(inst, {p: float(np.clip(get_param(inst, p) + d, lo, hi))
                                 for p, d, (lo, hi), k in zip(self.paths, step, self.bounds,
                                                              keep) if k})

    def project(self, r: np.ndarray) -> np.ndarray:
        """(I - Q Q^T) r: the part of r the model's own parameters cannot absorb."""
        return r - self.Q @ (self.Q.T @ r) if self.Q.size else r


def chord_refit(prob: ThermometerProblem, inst: Instrument, chord_steps: int = 4) -> ChordModel:
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
        sse_start = sum_of_squares(r)
        steps = np.array([1e-3 * abs(v) if v else 1e-3 for v in x])
        steps = np.where(x + steps > bounds[:, 1], -steps, steps)
        J = residual_jacobian(prob, build, x, r, steps)
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
            gain = sum_of_squares(r) - sum_of_squares(r_new)
            if gain <= 0:
                break
            x, r = x_new, r_new
            if gain < 1e-3 * sum_of_squares(r):
                break
        if sum_of_squares(r) > 0.9 * sse_start:
            break
    return ChordModel(build(x), paths, x, bounds, r, J, Q)
