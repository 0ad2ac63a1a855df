"""Tests of nfs.noise.generators: white noise and the gyro's ARW, BI and RRW.

Each test names its oracle.  Records are seeded and a few 1e5 samples long, long enough that
the Allan deviation at the taus used is known to about 1 %."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.errors import InputError
from nfs.noise import (
    BI_FLOOR_FACTOR,
    GyroNoise,
    allan_deviation,
    angle_random_walk_noise_dph,
    bias_instability_adev_dph,
    bias_instability_band_s,
    bias_instability_noise_dph,
    fit_noise_coefficients,
    gyro_noise_dph,
    rate_random_walk_noise_dph,
    white_noise,
)

N_LONG = 2**19          # 524288 samples: 6 days at 1 Hz, ~0.1 s to generate


def _fit(y: np.ndarray, fs: float):
    res = allan_deviation(y, fs)
    return res, fit_noise_coefficients(res.taus_s, res.adev, adev_rel_err=res.adev_rel_err)


# ---------------------------------------------------------------------------------------------
# angle random walk

@pytest.mark.parametrize("seed", [1, 2])
def test_gyro_fitted_arw_matches_setting_within_5_percent(seed: int) -> None:
    # Oracle: the setting. A seeded 2^19-sample record at 1 Hz of the full generator
    # (N 0.0005 deg/sqrt(h), B 0.003 deg/h, K 0.0005 deg/h/sqrt(h)); the Allan deviation at
    # tau = 1 s is known to 0.1 %, so both the fit and the slope reading must give N within 5 %.
    n_set = 0.0005
    y = gyro_noise_dph(N_LONG, 1.0, arw_deg_per_rth_h=n_set, bias_instability_dph=0.003,
                       rrw_deg_per_h_per_rth_h=0.0005, rng=np.random.default_rng(seed))
    _, fit = _fit(y, 1.0)
    assert fit.arw_deg_per_rth_h == pytest.approx(n_set, rel=0.05)
    assert fit.arw_slope_deg_per_rth_h == pytest.approx(n_set, rel=0.05)
    # the floor is there too (B within 20 %: the fit's flat term over the whole curve)
    assert fit.bias_instability_dph == pytest.approx(0.003, rel=0.20)


def test_arw_per_sample_std_is_60_n_sqrt_fs() -> None:
    # Oracle: docs/physics.md section 3, per-sample std (N 60) sqrt(fs) deg/h; the sample std of
    # 2^19 normals is within 0.5 % (its relative error is 1/sqrt(2 n) = 0.1 %).
    fs, n_set = 10.0, 0.001
    y = angle_random_walk_noise_dph(N_LONG, fs, n_set, rng=np.random.default_rng(5))
    assert np.std(y) == pytest.approx(60.0 * n_set * math.sqrt(fs), rel=0.005)


# ---------------------------------------------------------------------------------------------
# rate random walk

@pytest.mark.parametrize("seed", [3, 4])
def test_rrw_alone_fitted_k_within_10_percent(seed: int) -> None:
    # Oracle: the setting, via sigma(tau) = K sqrt(tau_h / 3) (IEEE Std 952-2020 Annex C).
    k_set = 0.01
    y = rate_random_walk_noise_dph(N_LONG, 1.0, k_set, rng=np.random.default_rng(seed))
    _, fit = _fit(y, 1.0)
    assert fit.rrw_deg_per_h_per_rth_h == pytest.approx(k_set, rel=0.10)
    assert fit.rrw_slope_deg_per_h_per_rth_h == pytest.approx(k_set, rel=0.10)


def test_rrw_short_taus_follow_the_discrete_closed_form() -> None:
    # Oracle: closed form of the sampled random walk, (K/60)^2 (2 m^2 + 1) / (6 m fs),
    # over m <= 64 where the estimate is tight (3 relative errors, and at most 5 %).
    fs, k_set = 2.0, 0.02
    y = rate_random_walk_noise_dph(N_LONG, fs, k_set, rng=np.random.default_rng(8))
    ms = np.array([1, 2, 4, 8, 16, 32, 64])
    res = allan_deviation(y, fs, taus=ms / fs)
    expected = (k_set / 60.0) * np.sqrt((2 * ms**2 + 1) / (6 * ms * fs))
    ratio = res.adev / expected - 1.0
    assert np.all(np.abs(ratio) <= np.maximum(3 * res.adev_rel_err, 0.05))


# ---------------------------------------------------------------------------------------------
# bias instability

@pytest.mark.parametrize("fs, t_c", [(1.0, 3600.0), (10.0, 100.0), (1.0, 1e5), (100.0, 7.0)])
def test_bi_closed_form_is_flat_within_5_percent_over_its_band(fs: float, t_c: float) -> None:
    # Oracle: the documented band (2/fs, T_c/3), flat to 5 % of sqrt(2 ln2/pi) B
    # (IEEE Std 952-2020 Annex C), and 11 % over (1/fs, T_c).
    b = 0.004
    lo, hi = bias_instability_band_s(fs, t_c)
    assert (lo, hi) == (2.0 / fs, t_c / 3.0)
    m = np.unique(np.rint(np.geomspace(lo * fs, hi * fs, 400)))
    adev = bias_instability_adev_dph(m / fs, fs, b, correlation_time_s=t_c)
    assert np.max(np.abs(adev / (BI_FLOOR_FACTOR * b) - 1.0)) <= 0.05
    m = np.unique(np.rint(np.geomspace(1.0, t_c * fs, 400)))
    adev = bias_instability_adev_dph(m / fs, fs, b, correlation_time_s=t_c)
    assert np.max(np.abs(adev / (BI_FLOOR_FACTOR * b) - 1.0)) <= 0.11


def test_bi_closed_form_limits() -> None:
    # Oracle: limits. Far above T_c the bounded process averages like white noise (slope
    # -1/2); sqrt(2 ln 2 / pi) = 0.6643 (IEEE Std 952-2020 Annex C).
    assert BI_FLOOR_FACTOR == pytest.approx(0.6643, abs=1e-4)
    taus = np.array([1e7, 4e7])
    adev = bias_instability_adev_dph(taus, 1.0, 0.003, correlation_time_s=1000.0)
    assert adev[1] / adev[0] == pytest.approx(0.5, rel=1e-3)


@pytest.mark.parametrize("seed", [5, 6])
def test_bi_alone_floor_within_15_percent_over_band(seed: int) -> None:
    # Oracle: the flicker floor 0.6643 B over the documented band (2/fs .. T_c/3), within 15 %
    # for every octave tau in the band; the simulated curve follows the generator's own
    # closed form (within 10 % where the estimate's relative error is below 5 %); the fitted
    # B is within 15 %.
    fs, b, t_c = 1.0, 0.003, 3600.0
    y = bias_instability_noise_dph(N_LONG, fs, b, correlation_time_s=t_c,
                                   rng=np.random.default_rng(seed))
    res, fit = _fit(y, fs)
    lo, hi = bias_instability_band_s(fs, t_c)
    band = (res.taus_s >= lo) & (res.taus_s <= hi)
    assert np.count_nonzero(band) >= 9
    assert np.all(np.abs(res.adev[band] / (BI_FLOOR_FACTOR * b) - 1.0) <= 0.15)
    tight = res.adev_rel_err < 0.05
    theory = bias_instability_adev_dph(res.taus_s[tight], fs, b, correlation_time_s=t_c)
    np.testing.assert_allclose(res.adev[tight], theory, rtol=0.10)
    # the weighted fit's flat term reads B; the classic minimum, taken over the whole curve,
    # would not (this process alone falls again beyond T_c), so read it over the band
    assert fit.bias_instability_dph == pytest.approx(b, rel=0.15)
    in_band = fit_noise_coefficients(res.taus_s[band], res.adev[band],
                                     adev_rel_err=res.adev_rel_err[band])
    assert in_band.bias_instability_floor_dph == pytest.approx(b, rel=0.15)


def test_bi_starts_stationary() -> None:
    # Oracle: invariant. The components start from their stationary distribution, so the
    # variance over realisations at the first sample equals that at a late sample
    # (400 realisations: a 14 % one-sigma spread of each variance; allow 45 %).
    fs, b = 1.0, 0.003
    runs = np.array([bias_instability_noise_dph(2000, fs, b, correlation_time_s=3600.0,
                                                rng=np.random.default_rng(s))[[0, -1]]
                     for s in range(400)])
    v_first, v_last = runs.var(axis=0)
    assert v_first == pytest.approx(v_last, rel=0.45)


# ---------------------------------------------------------------------------------------------
# white noise: the density convention round-trips through the Allan deviation

@pytest.mark.parametrize("sided, allan_factor, std_factor", [
    ("one", 1.0 / math.sqrt(2.0), math.sqrt(0.5)),
    ("two", 1.0, 1.0),
])
def test_white_noise_density_round_trips_through_allan(sided: str, allan_factor: float,
                                                        std_factor: float) -> None:
    # Oracle: the documented convention. One-sided density D (data sheet: rms D sqrt(B) in a
    # band B): per-sample std D sqrt(fs/2), sigma_A(tau) = D / sqrt(2 tau); two-sided:
    # D sqrt(fs), D / sqrt(tau).  Here a QFA's 20 ug/sqrt(Hz) at 100 Hz, in g.
    fs, density = 100.0, 20e-6
    y = white_noise(N_LONG, fs, density, rng=np.random.default_rng(9), sided=sided)
    assert np.std(y) == pytest.approx(density * std_factor * math.sqrt(fs), rel=0.005)
    res = allan_deviation(y, fs)
    expected = allan_factor * density / np.sqrt(res.taus_s)
    assert np.all(np.abs(res.adev / expected - 1.0) <= 3.0 * res.adev_rel_err)
    # read back: density = sigma_A(tau) sqrt(tau) / allan_factor at the best-known tau
    assert res.adev[0] * math.sqrt(res.taus_s[0]) / allan_factor == pytest.approx(density,
                                                                                   rel=0.01)


def test_arw_is_two_sided_white_noise_of_density_60_n() -> None:
    # Oracle: invariant (one code path). ARW N is white_noise(sided="two") of 60 N.
    a = angle_random_walk_noise_dph(1000, 2.0, 0.0005, rng=np.random.default_rng(1))
    b = white_noise(1000, 2.0, 0.03, rng=np.random.default_rng(1), sided="two")
    np.testing.assert_array_equal(a, b)


# ---------------------------------------------------------------------------------------------
# determinism and ablation

def test_same_seed_same_bytes_different_seed_different() -> None:
    # Oracle: invariant (style.md practice 10).
    kw = dict(arw_deg_per_rth_h=0.0005, bias_instability_dph=0.003,
              rrw_deg_per_h_per_rth_h=0.001)
    a = gyro_noise_dph(5000, 1.0, rng=np.random.default_rng(42), **kw)
    b = gyro_noise_dph(5000, 1.0, rng=np.random.default_rng(42), **kw)
    c = gyro_noise_dph(5000, 1.0, rng=np.random.default_rng(43), **kw)
    assert a.tobytes() == b.tobytes()
    assert a.tobytes() != c.tobytes()
    assert not np.any(a == c)
    for fn, args in [(white_noise, (5000, 1.0, 1.0)),
                     (bias_instability_noise_dph, (5000, 1.0, 0.003)),
                     (rate_random_walk_noise_dph, (5000, 1.0, 0.01))]:
        assert fn(*args, rng=np.random.default_rng(1)).tobytes() == \
            fn(*args, rng=np.random.default_rng(1)).tobytes()
        assert fn(*args, rng=np.random.default_rng(1)).tobytes() != \
            fn(*args, rng=np.random.default_rng(2)).tobytes()


def test_switching_a_term_off_leaves_the_others_unchanged() -> None:
    # Oracle: invariant. Each term has its own child stream, so the full record is exactly
    # the sum of the records with one term each, for the same seed (ablation).
    full = gyro_noise_dph(3000, 1.0, arw_deg_per_rth_h=0.0005, bias_instability_dph=0.003,
                          rrw_deg_per_h_per_rth_h=0.001, rng=np.random.default_rng(7))
    parts = [gyro_noise_dph(3000, 1.0, arw_deg_per_rth_h=n, bias_instability_dph=b,
                            rrw_deg_per_h_per_rth_h=k, rng=np.random.default_rng(7))
             for n, b, k in [(0.0005, 0, 0), (0, 0.003, 0), (0, 0, 0.001)]]
    np.testing.assert_array_equal(full, (parts[0] + parts[1]) + parts[2])


def test_gyro_noise_dataclass_calls_the_function() -> None:
    # Oracle: invariant (one code path), and the dataclass is frozen.
    gn = GyroNoise(arw_deg_per_rth_h=0.0005, bias_instability_dph=0.003,
                   rrw_deg_per_h_per_rth_h=0.001, correlation_time_s=1800.0)
    a = gn.generate(2000, 1.0, np.random.default_rng(3))
    b = gyro_noise_dph(2000, 1.0, arw_deg_per_rth_h=0.0005, bias_instability_dph=0.003,
                       rrw_deg_per_h_per_rth_h=0.001, correlation_time_s=1800.0,
                       rng=np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    with pytest.raises(AttributeError):
        gn.arw_deg_per_rth_h = 1.0  # type: ignore[misc]


def test_zero_samples_and_zero_coefficients() -> None:
    assert gyro_noise_dph(0, 1.0, arw_deg_per_rth_h=0.0005, bias_instability_dph=0.003,
                          rng=np.random.default_rng(0)).shape == (0,)
    np.testing.assert_array_equal(
        gyro_noise_dph(10, 1.0, arw_deg_per_rth_h=0.0, rng=np.random.default_rng(0)),
        np.zeros(10))


# ---------------------------------------------------------------------------------------------
# errors

def test_bad_arguments_are_input_errors() -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(InputError, match="arw_deg_per_rth_h"):
        gyro_noise_dph(10, 1.0, arw_deg_per_rth_h=-1.0, rng=rng)
    with pytest.raises(InputError, match="rng must be a numpy.random.Generator"):
        gyro_noise_dph(10, 1.0, arw_deg_per_rth_h=0.0005, rng=42)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="correlation_time_s must be >= 100"):
        gyro_noise_dph(10, 1.0, arw_deg_per_rth_h=0.0005, bias_instability_dph=0.003,
                       correlation_time_s=50.0, rng=rng)
    with pytest.raises(InputError, match="sided"):
        white_noise(10, 1.0, 1.0, rng=rng, sided="both")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="n_samples"):
        white_noise(2.5, 1.0, 1.0, rng=rng)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="sample_rate_hz"):
        white_noise(10, -1.0, 1.0, rng=rng)
    with pytest.raises(InputError, match="bias_instability_dph"):
        GyroNoise(arw_deg_per_rth_h=0.0005, bias_instability_dph=math.nan)
