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
