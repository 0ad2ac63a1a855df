"""Tests of nfs.noise.covariance: the covariance of window means of the gyro's rate noise and
the whitening by its Cholesky factor.

Oracles: the sample-level covariance of the generator's recursions summed by brute force, the
package's own closed-form Allan variances (an independent derivation), the ARW closed form
(60 N)^2 fs / m, and a seeded Monte Carlo of :func:`nfs.noise.gyro_noise_dph`."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.errors import InputError
from nfs.noise import (
    bias_instability_adev_dph,
    cholesky_lower,
    gyro_noise_dph,
    rest_window_segments,
    segment_sum_covariance,
    whiten,
    window_mean_covariance,
)
from nfs.noise.generators import bias_instability_poles


def _sample_covariance(n: int, fs: float, arw: float, b: float, k: float,
                       t_c: float) -> np.ndarray:
    """Covariance [(deg/h)^2] of n samples of the generator, written sample by sample from
    its recursions: white (60 N)^2 fs delta_ij; AR(1) components q^2 phi^|i-j|; random walk
    (K/60)^2 / fs (min(i, j) + 1)."""
    i = np.arange(n)
    cov = (60.0 * arw) ** 2 * fs * np.eye(n)
    times_s, q2_per_b2 = bias_instability_poles(fs, t_c)
    for t_k in times_s:
        phi = math.exp(-1.0 / (fs * t_k))
        cov += b * b * q2_per_b2 * phi ** np.abs(i[:, None] - i[None, :])
    cov += (k / 60.0) ** 2 / fs * (np.minimum(i[:, None], i[None, :]) + 1.0)
    return cov


def test_window_mean_covariance_equals_brute_force_sum_over_samples() -> None:
    # Oracle: A Sigma_y A^T with Sigma_y the sample-level covariance of the generator's
    # recursions (white + five AR(1) components + random walk) and A the averaging matrix,
    # summed over every sample pair.  The windows cover the awkward cases: adjacent, separated
    # by a gap, overlapping, far apart, and one window of three segments (cut by moves).
    # The closed forms must agree to rounding (1e-12 relative).
    fs, arw, b, k, t_c = 2.0, 0.0004, 0.003, 0.002, 200.0
    starts = np.array([0, 10, 25, 40, 47, 100, 300, 150, 5, 390])
    lengths = np.array([10, 10, 5, 3, 10, 20, 40, 50, 20, 10])
    window = np.array([0, 1, 2, 2, 3, 4, 5, 6, 7, 2])
    avg = np.zeros((8, 400))
    for a, m, w in zip(starts, lengths, window):
        avg[w, a:a + m] += 1.0
    avg /= avg.sum(axis=1, keepdims=True)
    expected = avg @ _sample_covariance(400, fs, arw, b, k, t_c) @ avg.T
    got = window_mean_covariance(starts, lengths, fs, arw_deg_per_rth_h=arw,
                                 bias_instability_dph=b, rrw_deg_per_h_per_rth_h=k,
                                 correlation_time_s=t_c, window=window)
    assert np.max(np.abs(got - expected)) <= 1e-12 * np.max(np.abs(expected))
    np.testing.assert_array_equal(got, got.T)


def test_white_noise_alone_gives_60n_squared_fs_over_m_on_the_diagonal() -> None:
    # Oracle: docs/physics.md section 3, per-sample std (60 N) sqrt(fs), so an m-sample mean of
    # white noise has the variance (60 N)^2 fs / m and disjoint windows are uncorrelated.
    fs, arw = 4.0, 0.0007
    lengths = np.array([10, 40, 7])
    cov = window_mean_covariance(np.array([0, 10, 200]), lengths, fs, arw_deg_per_rth_h=arw)
    np.testing.assert_allclose(np.diag(cov), (60.0 * arw) ** 2 * fs / lengths, rtol=1e-14)
    assert np.count_nonzero(cov - np.diag(np.diag(cov))) == 0


@pytest.mark.parametrize("m", [1, 10, 300])
def test_adjacent_windows_give_the_closed_form_allan_variance(m: int) -> None:
    # Oracle: the Allan variance is Var(mean) - Cov(adjacent means) for a stationary process;
    # bias_instability_adev_dph derives it from the same AR(1) sums by another route (one
    # closed formula per component, not segment pairs); both must agree to 1e-12.
    fs, b = 1.0, 0.002
    cov = window_mean_covariance(np.array([0, m]), np.array([m, m]), fs,
                                 arw_deg_per_rth_h=0.0, bias_instability_dph=b)
    avar = cov[0, 0] - cov[0, 1]
    assert avar == pytest.approx(bias_instability_adev_dph(np.array([m / fs]), fs, b)[0] ** 2,
                                 rel=1e-12)


def test_rate_random_walk_gives_its_documented_allan_variance_and_grows_with_time() -> None:
    # Oracle: rate_random_walk_noise_dph's docstring, Allan variance (K/60)^2 (2 m^2 + 1) /
    # (6 m fs) for m-sample windows (half the mean square difference of adjacent means, which
    # does not depend on where the pair sits); and the variance of the first m-sample mean,
    # (K/60)^2 / fs (m + 1)(2 m + 1) / (6 m) from sum_{i,j<m} (min(i,j) + 1) = m(m+1)(2m+1)/6.
    fs, k, m = 2.0, 0.01, 20
    s2 = (k / 60.0) ** 2 / fs
    for start in (0, 1000):
        cov = window_mean_covariance(np.array([start, start + m]), np.array([m, m]), fs,
                                     arw_deg_per_rth_h=0.0, rrw_deg_per_h_per_rth_h=k)
        avar = 0.5 * (cov[0, 0] + cov[1, 1] - 2.0 * cov[0, 1])
        assert avar == pytest.approx((k / 60.0) ** 2 * (2 * m * m + 1) / (6 * m * fs),
                                     rel=1e-9)
    first = window_mean_covariance(np.array([0]), np.array([m]), fs, arw_deg_per_rth_h=0.0,
                                   rrw_deg_per_h_per_rth_h=k)
    assert first[0, 0] == pytest.approx(s2 * (m + 1) * (2 * m + 1) / (6 * m), rel=1e-12)
    assert cov[0, 0] > 10 * first[0, 0]     # not stationary: later windows vary more


def test_covariance_matches_a_monte_carlo_of_the_generator() -> None:
    # Oracle: 2000 seeded records of gyro_noise_dph (N 0.0003 deg/sqrt(h), B 0.002 deg/h,
    # K 0.003 deg/h/sqrt(h), 1 Hz, T_c 600 s), reduced to 10-s window means at rest in 50-s
    # dwells separated by 10-s moves (a move cuts no window here; one window of two
    # segments spans a move).  Whitened by the closed-form covariance the window means must
    # have identity covariance: the mean of u^2 is 1 within 4 sigma (sigma = sqrt(2 / (R n)))
    # and each neighbour correlation E[u_i u_{i+1}] and the far pair E[u_0 u_last] are 0
    # within 4 sigma (1 / sqrt(R)).
    fs, n_samples, reps = 1.0, 600, 2000
    kw = dict(arw_deg_per_rth_h=0.0003, bias_instability_dph=0.002,
              rrw_deg_per_h_per_rth_h=0.003, correlation_time_s=600.0)
    t = np.arange(n_samples)
    rest = np.flatnonzero(t % 60 < 50)
    label = rest // 10
    label[(rest >= 300) & (rest < 305)] = 28   # 280-289 and 300-304: one window, 2 segments
    starts, lengths, window = rest_window_segments(rest, label)
    assert window.max() + 1 == len(np.unique(label)) and starts.size == window.max() + 2
    low = cholesky_lower(window_mean_covariance(starts, lengths, fs, window=window, **kw))
    counts = np.bincount(window, weights=lengths)
    rng = np.random.default_rng(20261123)
    u = np.empty((reps, counts.size))
    for r in range(reps):
        y = gyro_noise_dph(n_samples, fs, rng=rng, **kw)
        csum = np.concatenate([[0.0], np.cumsum(y)])
        sums = np.bincount(window, weights=csum[starts + lengths] - csum[starts])
        u[r] = whiten(sums / counts, factor=low)
    n_w = counts.size
    assert np.mean(u**2) == pytest.approx(1.0, abs=4.0 * math.sqrt(2.0 / (reps * n_w)))
    assert np.max(np.abs(np.mean(u[:, 1:] * u[:, :-1], axis=0))) < 4.0 / math.sqrt(reps)
    assert abs(np.mean(u[:, 0] * u[:, -1])) < 4.0 / math.sqrt(reps)
    # unwhitened, neighbours are correlated (bias instability, RRW) as the closed form says
    means = u @ low.T
    cov = low @ low.T
    rho = cov[0, 1] / math.sqrt(cov[0, 0] * cov[1, 1])
    assert rho > 0.1
    assert np.corrcoef(means[:, 0], means[:, 1])[0, 1] == pytest.approx(
        rho, abs=4.0 / math.sqrt(reps))


def test_segments_of_samples_at_rest_split_at_moves_and_renumber_windows() -> None:
    # Oracle: counted by hand.  Samples 0-4 and 8-9 in window 7 (a move at 5-7), 10-19 in
    # window 9: three segments, windows renumbered 0, 0, 1.
    idx = np.r_[0:5, 8:10, 10:20]
    lab = np.r_[[7] * 7, [9] * 10]
    starts, lengths, window = rest_window_segments(idx, lab)
    np.testing.assert_array_equal(starts, [0, 8, 10])
    np.testing.assert_array_equal(lengths, [5, 2, 10])
    np.testing.assert_array_equal(window, [0, 0, 1])


def test_whitening_inverts_the_cholesky_factor() -> None:
    # Oracle: the invariant L^-1 (L x) = x, for a vector and for columns.
    cov = window_mean_covariance(np.arange(0, 200, 10), np.full(20, 10), 1.0,
                                 arw_deg_per_rth_h=0.0003, bias_instability_dph=0.002)
    low = cholesky_lower(cov)
    np.testing.assert_allclose(low @ low.T, cov, rtol=1e-12, atol=1e-20)
    x = np.random.default_rng(3).standard_normal((20, 3))
    np.testing.assert_allclose(whiten(low @ x, cov), x, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(whiten(low @ x[:, 0], factor=low), x[:, 0], rtol=1e-9, atol=1e-9)


def test_segment_sums_of_one_segment_give_its_variance_times_m_squared() -> None:
    # Oracle: the invariant Var(sum) = m^2 Var(mean) between the two public functions.
    kw = dict(arw_deg_per_rth_h=0.0005, bias_instability_dph=0.004, rrw_deg_per_h_per_rth_h=0.01)
    s = segment_sum_covariance(np.array([30]), np.array([25]), 1.0, **kw)
    w = window_mean_covariance(np.array([30]), np.array([25]), 1.0, **kw)
    assert s[0, 0] == pytest.approx(625.0 * w[0, 0], rel=1e-14)


@pytest.mark.parametrize("starts, lengths, window, match", [
    ([0, 10], [10], None, "same length"),
    ([-1], [10], None, ">= 0"),
    ([0], [0], None, ">= 1 sample"),
    ([0.5], [10], None, "whole numbers"),
    ([0, 10], [10, 10], [0, 2], "none missing"),
    ([0, 10], [10, 10], [0], "one integer label"),
])
def test_bad_windows_raise_input_error(starts, lengths, window, match) -> None:
    # Oracle: the house rule, bad input raises InputError naming what is wrong.
    with pytest.raises(InputError, match=match):
        window_mean_covariance(np.array(starts), np.array(lengths), 1.0,
                               arw_deg_per_rth_h=0.0003, window=window)


def test_bad_covariances_and_noise_coefficients_raise_input_error() -> None:
    # Oracle: the house rule; a matrix that is not positive definite or not symmetric, a
    # negative coefficient and a too-short T_c are named.
    with pytest.raises(InputError, match="positive definite"):
        cholesky_lower(np.array([[1.0, 2.0], [2.0, 1.0]]))
    with pytest.raises(InputError, match="symmetric"):
        cholesky_lower(np.array([[1.0, 0.5], [0.0, 1.0]]))
    with pytest.raises(InputError, match="arw_deg_per_rth_h"):
        window_mean_covariance(np.array([0]), np.array([10]), 1.0, arw_deg_per_rth_h=-1.0)
    with pytest.raises(InputError, match="correlation_time_s"):
        window_mean_covariance(np.array([0]), np.array([10]), 1.0, arw_deg_per_rth_h=0.0,
                               bias_instability_dph=0.002, correlation_time_s=10.0)
    with pytest.raises(InputError, match="exactly one"):
        whiten(np.zeros(2))
    with pytest.raises(InputError, match="non-decreasing"):
        rest_window_segments(np.array([0, 1, 2]), np.array([1, 0, 0]))
