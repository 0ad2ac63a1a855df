"""Run-level statistics of the candidate scores: clustered inference, grouped CV, Holm,
one-sided tests.

Every candidate of :mod:`nfs.diagnose.missing_effect` is a linear least-squares problem over runs,
y_r = Z_r beta + e_r (r = 1..G runs; y_r the run's residual window means or thermometer
readings, Z_r the model's columns beside the candidate's).  Within a run the errors are
strongly autocorrelated (bias instability, a slowly wandering thermal residual), between
runs they are independent.  Everything here is therefore computed from the per-run Gram
matrices G_r = Z_r^T Z_r, h_r = Z_r^T y_r, y_r^T y_r (:class:`RunGrams`), and every
distribution has run-level degrees of freedom:

- :func:`clustered_fit`: pooled least squares beta = (sum G_r)^-1 sum h_r with the
  cluster-robust ("sandwich") covariance, one cluster per run (Liang & Zeger 1986,
  Biometrika 73(1) 13); the run's score is h_r - G_r beta.  The small-sample correction is
  CR2 (Bell & McCaffrey 2002, Survey Methodology 28(2) 169; Cameron & Miller 2015,
  J. Human Resources 50(2) 317, sec. VI.B): the score of run r is multiplied by
  (I - H_rr)^-1/2, H_rr the run's block of the hat matrix, and since
  Z_r^T f(H_rr) = f(G_r A^-1) Z_r^T (A = sum G_r) this needs only p x p matrices.
- :meth:`ClusteredFit.test`: Wald test of a set of coefficients.  One coefficient: t with
  the Bell-McCaffrey degrees of freedom (Cameron & Miller 2015, sec. VI.D; capped at G - 1),
  two- or one-sided; k coefficients: Hotelling's T^2 approximation F(k, eta - k + 1)
  (Pustejovsky & Tipton 2018, J. Bus. Econ. Stat. 36(4) 672), eta the smallest
  Bell-McCaffrey dof of the k coefficients (at most G - 1; Cameron & Miller's F(k, G - 1)
  ignores that the covariance itself rests on G runs, and a TEC's slopes on fewer).
- :func:`group_cv_rms`: leave-one-group-out RMS (a group: the runs of one start
  temperature); with several candidate designs (the grid points of a shape parameter) each
  fold chooses the design on its training runs only.
- :func:`one_sided`: the one-sided test and constrained estimate of a coefficient that
  physics keeps above a bound (a heat power >= 0 W, a lag >= 0 s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.stats import f as f_dist, norm, t as t_dist

from ..errors import NfsError

__all__ = ["RunGrams", "run_grams", "augmented_grams", "solve", "ClusteredFit", "clustered_fit",
           "group_cv_rms", "OneSided", "one_sided"]

#: Largest per-run leverage eigenvalue kept in the CR2 correction (a run that alone
#: determines a direction has leverage 1 there, and its (1 - leverage)^-1/2 is unbounded).
_MAX_LEVERAGE = 1.0 - 1e-8
#: Relative eigenvalue below which a direction of the scaled Gram matrix is dropped.
_RCOND = 1e-12


@dataclass(frozen=True)
class RunGrams:
    """Per-run sufficient statistics of the linear problem y_r = Z_r beta + e_r."""

    gram: np.ndarray
    """G_r = Z_r^T Z_r, shape (n_runs, p, p)."""
    moment: np.ndarray
    """h_r = Z_r^T y_r, shape (n_runs, p)."""
    yy: np.ndarray
    """y_r^T y_r, shape (n_runs,)."""
    n: np.ndarray
    """Samples per run, shape (n_runs,)."""

    def take(self, index: np.ndarray) -> "RunGrams":
        """The runs ``index`` (repeats allowed: a resample of whole runs)."""
        return RunGrams(self.gram[index], self.moment[index], self.yy[index], self.n[index])

    def sse(self, beta: np.ndarray) -> np.ndarray:
        """Residual sum of squares of each run at ``beta`` (beta of shape (p,) or (k, p))."""
        b = np.atleast_2d(beta)
        out = (self.yy[None, :] - 2.0 * np.einsum("rp,kp->kr", self.moment, b)
               + np.einsum("kp,rpq,kq->kr", b, self.gram, b))
        return out[0] if np.ndim(beta) == 1 else out


def run_grams(ys: Sequence[np.ndarray], Zs: Sequence[np.ndarray]) -> RunGrams:
    """The per-run Gram matrices of targets ``ys`` and designs ``Zs`` (one of each per run)."""
    return RunGrams(np.array([Z.T @ Z for Z in Zs]),
                    np.array([Z.T @ y for Z, y in zip(Zs, ys)]),
                    np.array([float(y @ y) for y in ys]),
                    np.array([y.size for y in ys], dtype=float))


def augmented_grams(base: RunGrams, ys: Sequence[np.ndarray], Xs: Sequence[np.ndarray],
                    cols: Sequence[np.ndarray]) -> RunGrams:
    """The Gram matrices of [X_r, C_r] from those of X_r (``base``): only the blocks of the
    added columns C_r are computed (X_r^T C_r, C_r^T C_r, C_r^T y_r)."""
    XC = np.array([X.T @ C for X, C in zip(Xs, cols)])
    CC = np.array([C.T @ C for C in cols])
    Cy = np.array([C.T @ y for C, y in zip(cols, ys)])
    gram = np.concatenate([np.concatenate([base.gram, XC], 2),
                           np.concatenate([np.swapaxes(XC, 1, 2), CC], 2)], 1)
    return RunGrams(gram, np.concatenate([base.moment, Cy], 1), base.yy, base.n)


def solve(gram: np.ndarray, moment: np.ndarray) -> np.ndarray:
    """Minimum-norm solution of the normal equations gram beta = moment (stacks allowed).

    The columns are scaled to unit diagonal first: the drift columns differ by orders of
    magnitude (a constant, T dT/dt in K^2/min, an aux current in mA), and a pseudo-inverse
    on the raw Gram matrix would cut directions by scale rather than by collinearity.
    """
    d = np.sqrt(np.einsum("...ii->...i", gram))
    d = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    scaled = gram * d[..., :, None] * d[..., None, :]
    b = np.linalg.pinv(scaled, rcond=_RCOND, hermitian=True) @ (moment * d)[..., None]
    return b[..., 0] * d


def _sym_power(S: np.ndarray, fn) -> np.ndarray:
    """fn applied to the eigenvalues of symmetric matrices ``S`` (stacks allowed)."""
    lam, U = np.linalg.eigh(S)
    return (U * fn(lam)[..., None, :]) @ np.swapaxes(U, -1, -2)


@dataclass(frozen=True)
class ClusteredFit:
    """Pooled least-squares fit over runs with its CR2 cluster-robust covariance."""

    beta: np.ndarray
    """Coefficients, shape (p,)."""
    cov: np.ndarray
    """CR2 covariance of ``beta``, one cluster per run, shape (p, p)."""
    n_clusters: int
    """G, the number of runs (repeats of a resampled run count as clusters)."""
    a_inv_half: np.ndarray
    """A^-1/2 (A = sum G_r), in the column scaling ``scale`` (for the dof)."""
    ms: np.ndarray
    """(I - S_r)^-1/2 S_r per run, S_r = A^-1/2 G_r A^-1/2 (scaled columns)."""
    q: np.ndarray
    """(I - S_r)^-1 S_r per run (scaled columns)."""
    scale: np.ndarray
    """Column scaling d (the scaled column j is column j times d_j)."""

    def dof(self, c: np.ndarray) -> float:
        """Bell-McCaffrey degrees of freedom of the contrast c^T beta under iid working
        errors: nu = (tr B)^2 / tr(B^2), B the G x G matrix of Bell & McCaffrey (2002,
        eq. (9)), here (from the run blocks of I - H) B_gh = delta_gh d^T Q_g d - v_g^T v_h
        with d = A^-1/2 c, v_g = (I - S_g)^-1/2 S_g d.  Capped at G - 1."""
        d = self.a_inv_half @ (np.asarray(c, dtype=float) * self.scale)
        v = self.ms @ d
        B = np.diag(np.einsum("p,rpq,q->r", d, self.q, d)) - v @ v.T
        tr, tr2 = float(np.trace(B)), float(np.sum(B * B))
        g1 = float(self.n_clusters - 1)
        return min(tr * tr / tr2, g1) if tr2 > 0 else g1

    def test(self, idx: Sequence[int], sign: int = 0) -> tuple[float, float, float]:
        """Wald test that ``beta[idx]`` = 0: (statistic, p-value, degrees of freedom).

        One coefficient: t = b / se against Student's t with :meth:`dof` degrees of freedom,
        two-sided (``sign`` = 0) or one-sided toward ``sign`` (+1: the alternative b > 0).
        Several (k): Hotelling's approximation, F = (eta - k + 1) / (eta k) b^T V^-1 b
        against F(k, eta - k + 1), eta the smallest dof of the k coefficients (<= G - 1).
        """
        idx = list(idx)
        b = self.beta[idx]
        V = self.cov[np.ix_(idx, idx)]
        k = len(idx)
        if k == 1:
            se = math.sqrt(max(float(V[0, 0]), 0.0))
            c = np.zeros(self.beta.size)
            c[idx[0]] = 1.0
            nu = self.dof(c)
            if se == 0.0 or not np.isfinite(se):
                return 0.0, 1.0, nu
            t = float(b[0]) / se
            p = float(2.0 * t_dist.sf(abs(t), nu)) if sign == 0 else float(
                t_dist.sf(sign * t, nu))
            return t, p, nu
        # Hotelling's T^2 approximation with eta degrees of freedom in the covariance:
        # F = (eta - k + 1) / (eta k) W ~ F(k, eta - k + 1) (Pustejovsky & Tipton 2018,
        # J. Bus. Econ. Stat. 36(4) 672, sec. 3.2), with eta the smallest Bell-McCaffrey
        # dof of the k coefficients: conservative when one coefficient rests on few runs (a
        # TEC's heating and cooling slopes each act on the runs on one side of its set point)
        eta = min(self.dof(np.eye(self.beta.size)[i]) for i in idx)
        w = float(b @ np.linalg.pinv(V, hermitian=True) @ b)
        d2 = eta - k + 1.0
        if d2 <= 0.0:
            return 0.0, 1.0, d2
        F = d2 / (eta * k) * w
        return F, float(f_dist.sf(F, k, d2)), d2

    def se(self) -> np.ndarray:
        """Standard errors of ``beta``."""
        return np.sqrt(np.maximum(np.diag(self.cov), 0.0))

    def half_width(self, j: int, level: float = 0.95) -> float:
        """Half-width of the t interval of ``beta[j]`` (Bell-McCaffrey dof)."""
        c = np.zeros(self.beta.size)
        c[j] = 1.0
        return float(t_dist.ppf(0.5 + level / 2.0, self.dof(c)) * self.se()[j])


def clustered_fit(grams: RunGrams) -> ClusteredFit:
    """Pooled least squares over the runs of ``grams`` with the CR2 covariance (module
    docstring): V = A^-1 (sum_r s~_r s~_r^T) A^-1, s~_r = (I - G_r A^-1)^-1/2 (h_r - G_r beta),
    computed in the scaled columns as A^-1/2 (I - S_r)^-1/2 A^-1/2 s_r."""
    G, h = grams.gram, grams.moment
    A = G.sum(0)
    d = np.sqrt(np.diag(A))
    d = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    Gs = G * d[None, :, None] * d[None, None, :]
    hs = h * d[None, :]
    As = Gs.sum(0)
    lam, U = np.linalg.eigh(As)
    keep = lam > _RCOND * max(float(lam.max()), 0.0)
    Uk = U[:, keep]
    a_inv_half = (Uk / np.sqrt(lam[keep])) @ Uk.T
    a_inv = (Uk / lam[keep]) @ Uk.T
    beta_s = a_inv @ hs.sum(0)
    score = hs - Gs @ beta_s
    S = a_inv_half @ Gs @ a_inv_half
    mu, W = np.linalg.eigh(S)
    mu = np.clip(mu, 0.0, _MAX_LEVERAGE)
    Wt = np.swapaxes(W, -1, -2)
    M = (W * (1.0 - mu)[:, None, :] ** -0.5) @ Wt
    u = np.einsum("pq,rqs,st,rt->rp", a_inv_half, M, a_inv_half, score)
    cov_s = u.T @ u
    ms = (W * (mu * (1.0 - mu) ** -0.5)[:, None, :]) @ Wt
    q = (W * (mu / (1.0 - mu))[:, None, :]) @ Wt
    return ClusteredFit(beta=beta_s * d, cov=cov_s * np.outer(d, d), n_clusters=len(G),
                        a_inv_half=a_inv_half, ms=ms, q=q, scale=d)


def group_cv_rms(designs: Sequence[RunGrams], groups: np.ndarray,
                 weights: np.ndarray | None = None) -> tuple[float, np.ndarray]:
    """Leave-one-group-out RMS of the held-out residual, with the design chosen in each fold.

    ``designs`` are the Gram matrices of alternative designs on the same targets (one per grid
    point of a candidate's shape parameters; one design: no choice).  In each fold (one
    distinct group held out) every design is fitted on the training runs, the one with the
    smallest training SSE is kept and predicts the held-out runs; the held-out SSE is pooled
    over folds: rms = sqrt(sum SSE_out / sum n_out).  ``weights`` are run multiplicities (a
    resample of whole runs).  Returns (rms, index of the chosen design in each fold).
    """
    groups = np.asarray(groups)
    w = np.ones(len(groups)) if weights is None else np.asarray(weights, dtype=float)
    folds = np.unique(groups[w > 0])
    out = np.where((groups[None, :] == folds[:, None]) & (w > 0), w, 0.0)   # (F, R)
    train = np.where(out > 0, 0.0, w[None, :])
    ok = train.sum(1) > 0
    out, train = out[ok], train[ok]
    sse_out, sse_train = [], []
    for g in designs:  # all folds of a design at once
        beta = solve(np.einsum("fr,rpq->fpq", train, g.gram), train @ g.moment)
        sse = g.sse(beta)                                                     # (F, R)
        sse_out.append(np.sum(sse * out, 1))
        sse_train.append(np.sum(sse * train, 1))
    best = np.argmin(np.array(sse_train), axis=0)                             # (F,)
    tot = float(np.array(sse_out)[best, np.arange(best.size)].sum())
    cnt = float(np.sum(out @ designs[0].n))
    chosen = best
    rms = math.sqrt(max(tot, 0.0) / cnt) if cnt else math.nan
    return rms, np.array(chosen, dtype=int)


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
