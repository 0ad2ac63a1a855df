"""Tests of nfs.noise.allan: the overlapping Allan deviation and the fit of N, B, K.

Each test names its oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.errors import InputError
from nfs.noise import (
    BI_FLOOR_FACTOR,
    allan_deviation,
    allan_relative_error,
    fit_noise_coefficients,
    octave_taus_s,
)


def _slow_overlapping_adev(y: np.ndarray, fs: float, m: int) -> tuple[float, int]:
    """Direct definition: half the mean squared difference of every pair of adjacent,
    overlapping m-sample averages (NIST SP 1065 section 5.2.4, written out with loops)."""
    n = len(y)
    means = [sum(y[i:i + m]) / m for i in range(n - m + 1)]
    diffs = [(means[i + m] - means[i]) ** 2 for i in range(n - 2 * m + 1)]
    return math.sqrt(0.5 * sum(diffs) / len(diffs)), len(diffs)


def test_matches_direct_definition_for_every_m() -> None:
    # Oracle: the defining formula evaluated directly (O(N m), loops), to 1e-12.
    rng = np.random.default_rng(7)
    y = 3.0 + rng.standard_normal(101) + np.linspace(0, 0.5, 101)
    fs = 4.0
    ms = np.arange(1, 101 // 2 + 1)
    res = allan_deviation(y, fs, taus=ms / fs)
    for m, adev, n_clusters, tau in zip(ms, res.adev, res.n_clusters, res.taus_s):
        ref, n_ref = _slow_overlapping_adev(list(y), fs, int(m))
        assert tau == m / fs
        assert n_clusters == n_ref
        assert adev == pytest.approx(ref, rel=1e-12, abs=0.0)


def test_linear_ramp_gives_r_tau_over_sqrt2() -> None:
    # Oracle: closed form. A rate ramp y = R t has adjacent tau-averages exactly R tau apart,
    # so sigma(tau) = R tau / sqrt(2) (IEEE Std 952-2020 Annex C, rate ramp).
    fs, ramp = 2.0, 0.05                      # [Hz], [deg/h per s]
    t = np.arange(4000) / fs
    res = allan_deviation(17.0 + ramp * t, fs)
    np.testing.assert_allclose(res.adev, ramp * res.taus_s / math.sqrt(2.0), rtol=1e-9)


def test_constant_rate_is_ignored_on_a_long_record() -> None:
    # Oracle: invariant. The Allan variance ignores a constant (here the Earth rate), and the
    # mean removal keeps round-off out on 1e6 samples.
    rng = np.random.default_rng(3)
    y = 0.03 * rng.standard_normal(1_000_000)
    a = allan_deviation(y, 1.0)
    b = allan_deviation(y + 15.041067, 1.0)
    np.testing.assert_allclose(b.adev, a.adev, rtol=1e-9)


def test_white_noise_follows_sigma_over_sqrt_m_within_confidence() -> None:
    # Oracle: closed form. White noise of per-sample std s has sigma(tau) = s / sqrt(tau fs);
    # each estimate within 3 of its relative errors 1/sqrt(2(N/m - 1)).
    rng = np.random.default_rng(11)
    fs, s, n = 10.0, 0.2, 200_000
    res = allan_deviation(s * rng.standard_normal(n), fs)
    expected = s / np.sqrt(res.taus_s * fs)
    assert np.all(np.abs(res.adev / expected - 1.0) <= 3.0 * res.adev_rel_err)
    # the short taus are known to better than 1 %: the check is not vacuous
    assert abs(res.adev[0] / expected[0] - 1.0) < 0.01


def test_default_taus_are_octaves_up_to_half_the_record() -> None:
    # Oracle: the documented default, m = 1, 2, 4, ... <= N/2.
    res = allan_deviation(np.random.default_rng(0).standard_normal(1000), 2.0)
    np.testing.assert_array_equal(res.taus_s,
                                  np.array([1, 2, 4, 8, 16, 32, 64, 128, 256]) / 2.0)
    np.testing.assert_array_equal(res.n_clusters, 1000 - 2 * res.taus_s * 2.0 + 1)
    np.testing.assert_array_equal(octave_taus_s(1000, 2.0), res.taus_s)


def test_requested_taus_are_rounded_to_whole_samples() -> None:
    # Oracle: the documented rounding m = round(tau fs), order kept.
    y = np.random.default_rng(0).standard_normal(100)
    res = allan_deviation(y, 10.0, taus=[0.52, 0.1, 1.04])
    np.testing.assert_allclose(res.taus_s, [0.5, 0.1, 1.0])


@pytest.mark.parametrize("taus", [[0.01], [5.1], [math.nan]])
def test_tau_out_of_range_is_an_input_error(taus: list[float]) -> None:
    # Oracle: 1 <= m <= N/2 is required; the message names the offending tau.
    with pytest.raises(InputError, match=r"taus\[0\]"):
        allan_deviation(np.zeros(100), 10.0, taus=taus)


def test_bad_records_are_input_errors() -> None:
    with pytest.raises(InputError, match="index 3"):
        allan_deviation(np.array([0.0, 1.0, 2.0, np.nan, 1.0]), 1.0)
    with pytest.raises(InputError, match="at least 2"):
        allan_deviation(np.array([1.0]), 1.0)
    with pytest.raises(InputError, match="1-D"):
        allan_deviation(np.zeros((3, 3)), 1.0)
    with pytest.raises(InputError, match="sample_rate_hz"):
        allan_deviation(np.zeros(10), 0.0)


def test_relative_error_formula() -> None:
    # Oracle: 1/sqrt(2(N/m - 1)) (IEEE Std 952-2020 Annex C; El-Sheimy et al. 2008).
    np.testing.assert_allclose(allan_relative_error(1000, np.array([1, 10, 500])),
                               [1 / math.sqrt(2 * 999), 1 / math.sqrt(2 * 99), 1 / math.sqrt(2)])


# ---------------------------------------------------------------------------------------------
# fit

def _model_adev(taus_s: np.ndarray, n: float, b: float, k: float) -> np.ndarray:
    """IEEE 952 model written independently of the package: tau converted to hours."""
    tau_h = taus_s / 3600.0
    # sigma in deg/h: N / sqrt(tau_h), 0.6643 B, K sqrt(tau_h / 3)
    return np.sqrt(n**2 / tau_h + (math.sqrt(2 * math.log(2) / math.pi) * b) ** 2
                   + k**2 * tau_h / 3.0)


def test_fit_recovers_noise_free_model_exactly() -> None:
    # Oracle: closed form. The exact model curve (in hours, written separately from the
    # package's seconds-based fit) must give back N, B, K.
    taus = np.geomspace(0.1, 1e5, 40)
    n, b, k = 0.0005, 0.003, 0.02
    fit = fit_noise_coefficients(taus, _model_adev(taus, n, b, k))
    assert fit.arw_deg_per_rth_h == pytest.approx(n, rel=1e-6)
    assert fit.bias_instability_dph == pytest.approx(b, rel=1e-6)
    assert fit.rrw_deg_per_h_per_rth_h == pytest.approx(k, rel=1e-6)
    np.testing.assert_allclose(fit.adev_model_dph(taus), _model_adev(taus, n, b, k), rtol=1e-6)


def test_classic_readings_on_pure_slopes() -> None:
    # Oracle: closed form. On a pure -1/2 line the reading at 1 h is N; on a pure +1/2 line the
    # reading at 3 h is K; a flat line reads B = floor / 0.6643; absent slopes read NaN.
    taus = np.geomspace(1.0, 1e4, 30)
    arw_only = fit_noise_coefficients(taus, _model_adev(taus, 0.0007, 0.0, 0.0))
    assert arw_only.arw_slope_deg_per_rth_h == pytest.approx(0.0007, rel=1e-12)
    assert math.isnan(arw_only.rrw_slope_deg_per_h_per_rth_h)
    rrw_only = fit_noise_coefficients(taus, _model_adev(taus, 0.0, 0.0, 0.05))
    assert rrw_only.rrw_slope_deg_per_h_per_rth_h == pytest.approx(0.05, rel=1e-12)
    assert math.isnan(rrw_only.arw_slope_deg_per_rth_h)
    flat = fit_noise_coefficients(taus, np.full(taus.size, 0.002))
    assert flat.bias_instability_floor_dph == pytest.approx(0.002 / BI_FLOOR_FACTOR)
    assert flat.bias_instability_dph == pytest.approx(0.002 / BI_FLOOR_FACTOR)
    assert flat.arw_deg_per_rth_h == pytest.approx(0.0, abs=1e-9)
    assert flat.rrw_deg_per_h_per_rth_h == pytest.approx(0.0, abs=1e-9)


def test_fit_ignores_unusable_points_and_checks_shapes() -> None:
    taus = np.geomspace(1.0, 1e4, 10)
    adev = _model_adev(taus, 0.0005, 0.003, 0.0)
    adev[3] = np.nan
    fit = fit_noise_coefficients(taus, adev)
    assert fit.arw_deg_per_rth_h == pytest.approx(0.0005, rel=1e-6)
    with pytest.raises(InputError, match="one length"):
        fit_noise_coefficients(taus, adev[:-1])
    with pytest.raises(InputError, match="at least 3"):
        fit_noise_coefficients(taus[:2], adev[:2])
