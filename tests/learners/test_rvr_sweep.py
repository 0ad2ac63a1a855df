"""One evidence sweep of the RVR (Tipping 2001 eq. (12)-(13)): the posterior mean and the
diagonal of its covariance, computed in place by LAPACK, against the closed form by explicit
inversion; the sweep leaves its inputs untouched (the sweeps reuse Phi^T Phi); a singular H
is factorised with a diagonal loading at the level of its rounding errors, and the eigen-
decomposition is the last resort."""

import numpy as np
import pytest

import nfs.learners.rvr as rvr
from nfs.learners.rvr import RVRRegressor, _cholesky, _lower_inverse


def _problem(n=40, seed=2):
    rng = np.random.default_rng(seed)
    Phi = np.hstack([np.ones((n, 1)), np.exp(-rng.uniform(0.0, 3.0, (n, n)))])
    t = rng.standard_normal(n)
    return Phi.T @ Phi, Phi.T @ t, rng.uniform(0.1, 10.0, n + 1)


def test_sweep_is_the_closed_form_posterior():
    # Oracle: Sigma = (beta Phi^T Phi + diag(alpha))^-1, mu = beta Sigma Phi^T t, by
    # numpy.linalg.inv on a well-conditioned problem (seeded).
    PtP, Ptt, alpha = _problem()
    beta = 3.0
    before = PtP.copy(), Ptt.copy(), alpha.copy()
    mu, diag = RVRRegressor._posterior_diag(PtP, Ptt, alpha, beta)
    Sigma = np.linalg.inv(beta * PtP + np.diag(alpha))
    np.testing.assert_allclose(diag, np.diag(Sigma), rtol=1e-9)
    np.testing.assert_allclose(mu, beta * Sigma @ Ptt, rtol=1e-8, atol=1e-10)
    for a, b in zip(before, (PtP, Ptt, alpha)):
        assert np.array_equal(a, b)


def _singular():
    PtP, Ptt, _ = _problem()
    return np.outer(PtP[0], PtP[0]), Ptt, np.zeros(PtP.shape[0])   # rank one, alpha = 0


def test_singular_h_is_factorised_with_a_loading_at_rounding_level():
    # Oracle: H = beta Phi^T Phi + diag(alpha) of rank one fails the plain Cholesky
    # factorisation; the factor returned is that of H + delta I with delta among LOADINGS x
    # n eps max H_ii (L L^T - H is delta on the diagonal to 5 %, its rounding errors off the
    # diagonal below a tenth of delta), and the sweep's values are finite with the inputs
    # untouched although the factorisations ran in place.
    PtP, Ptt, alpha = _singular()
    before = PtP.copy()
    L = _cholesky(PtP, alpha, 1.0)
    assert L is not None
    L = np.tril(L)
    excess = L @ L.T - PtP
    n = PtP.shape[0]
    unit = n * np.finfo(float).eps * PtP.diagonal().max()
    delta = excess.diagonal().mean()
    assert 0.95 * unit <= delta <= max(rvr.LOADINGS) * unit * 1.05
    np.testing.assert_allclose(excess.diagonal(), delta, rtol=0.05)
    assert np.abs(excess - np.diag(excess.diagonal())).max() < 0.1 * delta
    mu, diag = RVRRegressor._posterior_diag(PtP, Ptt, alpha, 1.0)
    assert np.all(np.isfinite(mu)) and np.all(np.isfinite(diag)) and np.all(diag > 0)
    assert np.array_equal(PtP, before)


def test_sweep_falls_back_to_the_eigen_decomposition(monkeypatch):
    # Oracle: with no loading allowed, the singular H fails every factorisation; the eigen-
    # decomposition with floored eigenvalues still gives finite values, and the inputs are
    # untouched although the failed factorisation ran in place.
    monkeypatch.setattr(rvr, "LOADINGS", (0.0,))
    PtP, Ptt, alpha = _singular()
    before = PtP.copy()
    assert _cholesky(PtP, alpha, 1.0) is None
    mu, diag = RVRRegressor._posterior_diag(PtP, Ptt, alpha, 1.0)
    assert np.all(np.isfinite(mu)) and np.all(np.isfinite(diag)) and np.all(diag > 0)
    mu2, Sigma = RVRRegressor._posterior(PtP, Ptt, alpha, 1.0)
    assert np.all(np.isfinite(mu2)) and np.all(np.isfinite(Sigma))
    assert np.array_equal(PtP, before)


@pytest.mark.parametrize("n", [1, 63, 64, 65, 200, 341])
def test_blocked_triangular_inverse_is_the_inverse(n):
    # Oracle: L^-1 L = I for the Cholesky factor of a well-conditioned SPD matrix (seeded),
    # at orders below, at and above the leaf where LAPACK's trtri takes over; the result is
    # lower triangular.
    rng = np.random.default_rng(n)
    A = rng.standard_normal((n, n))
    L = np.linalg.cholesky(A @ A.T + n * np.eye(n))
    Li, info = _lower_inverse(np.asfortranarray(L))
    assert info == 0
    assert np.array_equal(Li, np.tril(Li))
    np.testing.assert_allclose(Li @ L, np.eye(n), atol=1e-12)


def _one_input(n=120, seed=5):
    rng = np.random.default_rng(seed)
    x = np.sort(rng.uniform(-2.0, 2.0, n))[:, None]
    return x, np.sin(2.0 * x[:, 0]) + 0.05 * rng.standard_normal(n)


def test_kernel_factor_reproduces_the_kernel_to_its_tolerance():
    # Oracle: the pivoted Cholesky factor's residual K - B B^T is positive semi-definite
    # with every entry at most RANK_TOL (a wide kernel of one input: rank far below n).
    x, _ = _one_input()
    K = np.exp(-(x - x.T) ** 2 / (2.0 * 1.5**2))
    B = rvr._kernel_factor(K)
    assert B.shape[1] < 20
    resid = K - B @ B.T
    assert np.abs(resid).max() <= rvr.RANK_TOL * 1.01
    assert np.linalg.eigvalsh(resid).min() > -1e-13


def test_low_rank_sweep_is_the_closed_form_posterior():
    # Oracle: Sigma = (beta F F^T + diag(alpha))^-1 and mu = beta Sigma F c by numpy.linalg.inv
    # for a seeded F of rank 6 < M = 30 (Phi^T Phi = F F^T, Phi^T t = F c); g_i = 1 - alpha_i
    # Sigma_ii; and the full Sigma with the same mu.
    rng = np.random.default_rng(7)
    F, c = rng.standard_normal((30, 6)), rng.standard_normal(6)
    alpha, beta = rng.uniform(0.1, 10.0, 30), 3.0
    Sigma = np.linalg.inv(beta * F @ F.T + np.diag(alpha))
    mu, g = rvr._low_rank_sweep(F, c, alpha, beta)
    np.testing.assert_allclose(g, 1.0 - alpha * np.diag(Sigma), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(mu, beta * Sigma @ F @ c, rtol=1e-8, atol=1e-10)
    mu2, Sigma2 = rvr._low_rank_sweep(F, c, alpha, beta, full=True)
    assert np.array_equal(mu, mu2)
    np.testing.assert_allclose(Sigma2, Sigma, rtol=1e-8, atol=1e-12)


def test_low_rank_basis_factors_phi():
    # Oracle: Phi = [1, K] with K = B B^T exactly: Phi^T Phi = F F^T, Phi^T t = F c and
    # ||t - Phi w||^2 = e2 + ||c - F^T w||^2 for a seeded w.
    rng = np.random.default_rng(3)
    B, t, w = rng.standard_normal((25, 4)), rng.standard_normal(25), rng.standard_normal(26)
    Phi = np.hstack([np.ones((25, 1)), B @ B.T])
    F, c, e2 = rvr._low_rank_basis(B, t)
    np.testing.assert_allclose(F @ F.T, Phi.T @ Phi, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(F @ c, Phi.T @ t, rtol=1e-10, atol=1e-10)
    assert np.isclose(np.sum((t - Phi @ w) ** 2), e2 + np.sum((c - F.T @ w) ** 2), rtol=1e-10)


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")
def test_fit_on_the_kernel_factor_is_the_exact_fit(monkeypatch):
    # Oracle: the same RVR fitted with the sweeps on H itself (LOW_RANK_SHARE 0: the factor
    # never used): the same relevance vectors, and predictions within 1e-6 of the target's
    # STD (the factor reproduces the kernel to RANK_TOL, 1e-8).
    x, y = _one_input()
    fast = RVRRegressor(sigma=1.0, max_iter=40, tol=1e-2, alpha_threshold=1e6).fit(x, y)
    monkeypatch.setattr(rvr, "LOW_RANK_SHARE", 0.0)
    exact = RVRRegressor(sigma=1.0, max_iter=40, tol=1e-2, alpha_threshold=1e6).fit(x, y)
    assert np.array_equal(fast.relevance_indices_, exact.relevance_indices_)
    np.testing.assert_allclose(fast.predict(x), exact.predict(x), rtol=0, atol=1e-6 * y.std())
    _, s_fast = fast.predict(x, return_std=True)
    _, s_exact = exact.predict(x, return_std=True)
    np.testing.assert_allclose(s_fast, s_exact, rtol=1e-4)
