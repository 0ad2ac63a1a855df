"""Tests of nfs.scoring.run_stats: clustered inference from per-run Gram matrices.

Oracles: the N-space formulas of CR2 and of the Bell-McCaffrey degrees of freedom (Bell &
McCaffrey 2002; Cameron & Miller 2015, sec. VI), evaluated directly with the n x n hat
matrix blocks; a brute-force leave-one-group-out loop; Holm's procedure by hand; and a true
null (the size of the test on autocorrelated within-run errors must be its nominal level).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import sqrtm
from scipy.signal import lfilter

from nfs.scoring.run_stats import clustered_fit, group_cv_rms, run_grams, solve
from nfs.scoring.intervals import holm


def _problem(rng, sizes=(40, 55, 30, 70, 45), p=4, phi=0.9):
    Zs, ys = [], []
    for n in sizes:
        t = np.arange(n) / n
        Z = np.column_stack([np.ones(n), t, t ** 2 * rng.normal(1, 0.5),
                             rng.standard_normal(n)])[:, :p] * [1.0, 10.0, 1e3, 0.1][:p]
        e = np.zeros(n)
        for k in range(1, n):  # AR(1) errors within a run
            e[k] = phi * e[k - 1] + rng.standard_normal()
        ys.append(Z @ np.arange(1.0, p + 1) + e)
        Zs.append(Z)
    return ys, Zs


def _brute(ys, Zs, c):
    """CR2 covariance and BM dof with the hat matrix in sample space."""
    Z, y = np.vstack(Zs), np.concatenate(ys)
    Ainv = np.linalg.inv(Z.T @ Z)
    beta = Ainv @ Z.T @ y
    H = Z @ Ainv @ Z.T
    idx = np.cumsum([0] + [len(v) for v in ys])
    meat = 0.0
    cols = []
    I_H = np.eye(len(y)) - H
    for g in range(len(ys)):
        sl = slice(idx[g], idx[g + 1])
        Ag = np.real(sqrtm(np.linalg.inv(np.eye(idx[g + 1] - idx[g]) - H[sl, sl])))
        s = Zs[g].T @ Ag @ (y[sl] - Zs[g] @ beta)
        meat = meat + np.outer(s, s)
        cols.append(I_H[:, sl] @ Ag @ Zs[g] @ Ainv @ c)
    Gm = np.column_stack(cols)
    lam = np.linalg.eigvalsh(Gm.T @ Gm)
    return beta, Ainv @ meat @ Ainv, lam.sum() ** 2 / (lam ** 2).sum()


def test_cr2_and_bell_mccaffrey_dof_match_the_sample_space_formulas():
    """Oracle: CR2 and the BM dof computed with the n x n hat-matrix blocks; the p x p
    route (Z_r^T f(H_rr) = f(G_r A^-1) Z_r^T) must agree to rounding."""
    rng = np.random.default_rng(1)
    ys, Zs = _problem(rng)
    fit = clustered_fit(run_grams(ys, Zs))
    for j in range(4):
        c = np.eye(4)[j]
        beta, cov, nu = _brute(ys, Zs, c)
        np.testing.assert_allclose(fit.beta, beta, rtol=1e-8)
        np.testing.assert_allclose(fit.cov, cov, rtol=1e-6, atol=1e-12 * np.abs(cov).max())
        assert fit.dof(c) == pytest.approx(min(nu, 4.0), rel=1e-6)


def test_clustered_t_test_has_its_nominal_size_on_autocorrelated_runs():
    """Oracle: a true null.  7 runs of 100 AR(1) errors (phi = 0.95) with a smooth regressor
    whose coefficient is 0: the CR2 t test rejects at 5 % in 5 % of 2000 draws (binomial
    s.e. 0.5 %; [3.5, 6.5] %), while the iid Wald test rejects far more often."""
    rng = np.random.default_rng(7)
    rej, rej_iid, n_rep = 0, 0, 2000
    for _ in range(n_rep):
        ys, Zs = [], []
        for g in range(7):
            n = 100
            x = np.cumsum(rng.standard_normal(n)) / 10.0
            e = lfilter([1.0], [1.0, -0.95], rng.standard_normal(n))  # AR(1)
            Zs.append(np.column_stack([np.ones(n), x]))
            ys.append(1.0 + e)
        g = run_grams(ys, Zs)
        fit = clustered_fit(g)
        rej += fit.test([1])[1] < 0.05
        A = g.gram.sum(0)
        s2 = float(g.sse(fit.beta).sum()) / (g.n.sum() - 2)
        rej_iid += abs(fit.beta[1]) / np.sqrt(s2 * np.linalg.inv(A)[1, 1]) > 1.96
    assert 0.035 <= rej / n_rep <= 0.065, rej / n_rep
    assert rej_iid / n_rep > 0.3


def test_group_cv_chooses_the_design_on_training_runs():
    """Oracle: a brute-force loop over folds (fit every design on the training runs with
    lstsq on the stacked samples, keep the best training SSE, predict the held-out group)."""
    rng = np.random.default_rng(3)
    ys, Zs = _problem(rng, sizes=(30, 35, 40, 45, 50, 55))
    groups = np.array([0, 0, 1, 2, 2, 3])
    designs = [Zs, [Z[:, :3] for Z in Zs], [Z[:, [0, 1, 3]] for Z in Zs]]
    rms, chosen = group_cv_rms([run_grams(ys, D) for D in designs], groups)
    tot, cnt, picks = 0.0, 0, []
    for grp in np.unique(groups):
        tr = [i for i in range(6) if groups[i] != grp]
        te = [i for i in range(6) if groups[i] == grp]
        fits = []
        for D in designs:
            b = np.linalg.lstsq(np.vstack([D[i] for i in tr]),
                                np.concatenate([ys[i] for i in tr]), rcond=None)[0]
            fits.append((sum(float(np.sum((ys[i] - D[i] @ b) ** 2)) for i in tr), b, D))
        k = int(np.argmin([f[0] for f in fits]))
        picks.append(k)
        b, D = fits[k][1], fits[k][2]
        tot += sum(float(np.sum((ys[i] - D[i] @ b) ** 2)) for i in te)
        cnt += sum(ys[i].size for i in te)
    assert rms == pytest.approx(np.sqrt(tot / cnt), rel=1e-8)
    assert list(chosen) == picks


def test_solve_is_scale_invariant():
    """Oracle: lstsq on the stacked samples, with columns of scale 1 and 1e6."""
    rng = np.random.default_rng(4)
    Z = rng.standard_normal((50, 3)) * [1.0, 1e6, 1e-3]
    y = rng.standard_normal(50)
    np.testing.assert_allclose(solve(Z.T @ Z, Z.T @ y),
                               np.linalg.lstsq(Z, y, rcond=None)[0], rtol=1e-8)


def test_holm_by_hand():
    """Oracle: Holm (1979) by hand: p = (0.01, 0.04, 0.03, 0.005), alpha = 0.05:
    0.005 <= 0.05/4, 0.01 <= 0.05/3, 0.03 > 0.05/2 stops; adjusted p 0.03, 0.06, 0.06, 0.02."""
    adj = holm([0.01, 0.04, 0.03, 0.005])
    assert list(adj <= 0.05) == [True, False, False, True]
    np.testing.assert_allclose(adj, [0.03, 0.06, 0.06, 0.02])
