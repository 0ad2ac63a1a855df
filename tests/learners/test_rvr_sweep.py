"""One evidence sweep of the RVR (Tipping 2001 eq. (12)-(13)): the posterior mean and the
diagonal of its covariance, computed in place by LAPACK, against the closed form by explicit
inversion; and the sweep leaves its inputs untouched (the sweeps reuse Phi^T Phi)."""

import numpy as np

from nfs.learners.rvr import RVRRegressor


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


def test_sweep_falls_back_to_the_eigen_decomposition():
    # Oracle: a singular H (alpha = 0 on a rank-deficient Phi^T Phi) fails the Cholesky
    # factorisation; the eigen-decomposition with floored eigenvalues still gives finite
    # values, and the inputs are untouched although the failed factorisation ran in place.
    PtP, Ptt, _ = _problem()
    PtP = np.outer(PtP[0], PtP[0])                    # rank one
    alpha = np.zeros(PtP.shape[0])
    before = PtP.copy()
    mu, diag = RVRRegressor._posterior_diag(PtP, Ptt, alpha, 1.0)
    assert np.all(np.isfinite(mu)) and np.all(np.isfinite(diag)) and np.all(diag > 0)
    assert np.array_equal(PtP, before)
