"""Tests of nfs.denoise.wavelet: the wavelet denoiser, its level and its record ends.

Each test names its oracle. The "known drift" is a smooth start-up-like drift

    s(t) = 0.02 exp(-t/600) + 0.005 (1 - exp(-t/2400))   [deg/h], 9000 s at 1 Hz,

plus seeded white noise of 0.024 deg/h per sample (an ARW of 0.0004 deg/sqrt(h) at 1 Hz:
0.0004 * 60 * sqrt(1 Hz)). Its error budget: at level J the approximation keeps the
n / 2^J coarsest of n orthonormal coefficients, so white noise leaves sigma / sqrt(2^J) per
sample in it, 0.024 / 16 = 0.0015 deg/h at J = 8; the thresholded details add little (visu
removes pure-noise coefficients with high probability) and the drift's own details below the
threshold are tiny. Bound used: 0.002 deg/h in the interior.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.denoise import (
    BOUNDARIES,
    cutoff_for_level,
    edge_span_samples,
    level_for_cutoff,
    wavelet_denoise,
)
from nfs.errors import InputError

N = 9000
T_S = np.arange(N, dtype=float)
TRUTH = 0.02 * np.exp(-T_S / 600.0) + 0.005 * (1.0 - np.exp(-T_S / 2400.0))
SIGMA = 0.0004 * 60.0 * math.sqrt(1.0)          # 0.024 deg/h per sample


def noisy(seed: int) -> np.ndarray:
    return TRUTH + SIGMA * np.random.default_rng(seed).standard_normal(N)


def rms(v: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(v))))


# --------------------------------------------------------------------------------------------
# level


def test_level_for_cutoff_dyadic_bands():
    # Closed form: level J keeps periods > 2^(J+1) samples; 512 s at 1 Hz is level 8.
    assert level_for_cutoff(512.0, 1.0) == 8
    assert level_for_cutoff(1024.0, 1.0) == 9
    assert level_for_cutoff(512.0, 2.0) == 9
    assert level_for_cutoff(256.0, 1.0) == 7
    assert level_for_cutoff(600.0, 1.0) == 8          # nearest dyadic cutoff on a log scale
    assert cutoff_for_level(8, 1.0) == 512.0
    for j in range(1, 12):
        assert level_for_cutoff(cutoff_for_level(j, 4.0), 4.0) == j
    with pytest.raises(InputError):
        level_for_cutoff(0.0, 1.0)
    with pytest.raises(InputError):
        level_for_cutoff(2.0, 1.0)                    # below level 1


def test_edge_span_is_the_support_of_the_coarsest_functions():
    # Closed form: (L - 1)(2^J - 1) samples; db4 (L = 8) at level 8 is 1785.
    assert edge_span_samples(8, 8) == 1785
    res = wavelet_denoise(noisy(0), cutoff_period_s=512.0)
    assert res.level == 8 and res.edge_samples == 1785 and res.edge_s == 1785.0
    res2 = wavelet_denoise(noisy(0), cutoff_period_s=512.0, sample_rate_hz=2.0)
    assert res2.level == 9 and res2.edge_s == pytest.approx(7 * 511 / 2.0)


def test_exactly_one_of_cutoff_and_level():
    with pytest.raises(InputError):
        wavelet_denoise(noisy(0))
    with pytest.raises(InputError):
        wavelet_denoise(noisy(0), cutoff_period_s=512.0, level=8)


def test_level_beyond_the_record_is_refused():
    with pytest.raises(InputError, match="level 9"):
        wavelet_denoise(np.zeros(300), level=9, boundary="symmetric")


# --------------------------------------------------------------------------------------------
# perfect reconstruction (PyWavelets' invariant)


@pytest.mark.parametrize("boundary", ["smooth-extend", "symmetric", "reflect", "smooth",
                                      "antireflect", "periodization", "zero"])
@pytest.mark.parametrize("wavelet", ["db4", "sym8", "coif3"])
def test_zero_threshold_reconstructs_the_record(boundary, wavelet):
    # Invariant: DWT then inverse DWT with every coefficient kept returns x (to round-off),
    # whatever the extension, so the cropping of the padded record is exact.
    x = noisy(1)[:5001]                               # odd length on purpose
    res = wavelet_denoise(x, level=6, wavelet=wavelet, rule="none", boundary=boundary)
    assert np.max(np.abs(res.signal - x)) < 1e-10
    assert np.max(np.abs(res.noise)) < 1e-10
    assert res.thresholds == (0.0,) * 6


def test_given_thresholds_shrink_a_second_record_like_the_first():
    # Invariants: a record's own thresholds given back reproduce its denoising exactly;
    # zeros keep every coefficient (the record back); a noise-free record shrunk with a
    # noisy record's thresholds loses what the noisy one lost of the signal, not nothing
    # (soft thresholding is not linear: with its own, near-zero thresholds it keeps it all).
    x = noisy(3)
    res = wavelet_denoise(x, level=8)
    again = wavelet_denoise(x, level=8, thresholds=res.thresholds)
    np.testing.assert_array_equal(again.signal, res.signal)
    assert again.rule == "fixed" and again.thresholds == res.thresholds
    zero = wavelet_denoise(x, level=8, thresholds=[0.0] * 8)
    assert np.max(np.abs(zero.signal - x)) < 1e-10
    square = 0.012 * np.sign(np.sin(2 * np.pi * T_S / 640.0))    # a position-following term
    clean_own = wavelet_denoise(TRUTH + square, level=8).signal
    clean_theirs = wavelet_denoise(TRUTH + square, level=8, thresholds=res.thresholds).signal
    noisy_sq = np.mean([wavelet_denoise(noisy(s) + square, level=8).signal
                        for s in range(4, 12)], axis=0)
    mid = slice(1000, N - 1000)
    assert rms((clean_theirs - noisy_sq)[mid]) < 0.5 * rms((clean_own - noisy_sq)[mid])
    # the second guess behind edge_error_estimate (the other boundary) takes its own
    # thresholds from the rule, not the first pass's
    kw = dict(level=8, rule="sure", sigma_per_level=True, boundary="periodization")
    res = wavelet_denoise(x[:3000], **kw)
    alt = wavelet_denoise(x[:3000], **{**kw, "boundary": "smooth-extend"}).signal
    floor = res.sigma / math.sqrt(2.0 ** 8)
    e = res.edge_samples
    want = math.sqrt(floor ** 2 + np.mean((res.signal - alt)[:e] ** 2))
    assert res.edge_error_estimate[0] == pytest.approx(want, rel=1e-12)
    with pytest.raises(InputError, match="thresholds must be 8"):
        wavelet_denoise(x, level=8, thresholds=[0.1] * 7)
    with pytest.raises(InputError, match="thresholds must be 8"):
        wavelet_denoise(x, level=8, thresholds=[0.1] * 7 + [math.nan])


# --------------------------------------------------------------------------------------------
# the known drift


def test_known_drift_interior_error_edges_and_noise_level():
    # Oracle: the known drift s(t). Interior bound 0.002 deg/h from the budget in the module
    # docstring (0.0015 expected); ends reported separately, bound 0.003 deg/h over each
    # edge span (the end fit's variance adds to the interior's); sigma within 5 % of 0.024.
    x = noisy(2024)
    res = wavelet_denoise(x, cutoff_period_s=512.0)
    k = res.edge_samples
    err = res.signal - TRUTH
    interior, start, end = rms(err[k:N - k]), rms(err[:k]), rms(err[N - k:])
    print(f"\nknown drift, db4 level 8: interior {interior:.5f}, first {res.edge_s:g} s "
          f"{start:.5f}, last {res.edge_s:g} s {end:.5f} deg/h; estimate "
          f"{res.edge_error_estimate[0]:.5f}/{res.edge_error_estimate[1]:.5f}")
    assert interior < 0.002
    assert start < 0.003 and end < 0.003
    assert res.sigma == pytest.approx(SIGMA, rel=0.05)
    np.testing.assert_allclose(res.noise, x - res.signal, rtol=0, atol=0)
    # the expected white-noise leak sigma / 16 is the right size (not an accident of 0.002)
    assert 0.5 * SIGMA / 16 < interior < 1.3 * SIGMA / 16


def test_edge_error_is_measured_and_estimated():
    # Oracle: the known drift over 10 seeds. The RMS error over each edge span stays within
    # 1.6x the interior's, and edge_error_estimate is within a factor 2 of the measured
    # RMS error of each end (it is an indicator, not a bound).
    ratios_start, ratios_end, est_start, est_end = [], [], [], []
    for seed in range(10):
        res = wavelet_denoise(noisy(seed), level=8)
        k = res.edge_samples
        err = res.signal - TRUTH
        interior = rms(err[k:N - k])
        ratios_start.append(rms(err[:k]) / interior)
        ratios_end.append(rms(err[N - k:]) / interior)
        est_start.append(res.edge_error_estimate[0] / rms(err[:k]))
        est_end.append(res.edge_error_estimate[1] / rms(err[N - k:]))
    print(f"\nedge / interior RMS error: start {np.mean(ratios_start):.2f}, "
          f"end {np.mean(ratios_end):.2f}; estimate / measured: start "
          f"{np.mean(est_start):.2f}, end {np.mean(est_end):.2f}")
    assert np.mean(ratios_start) < 1.6 and np.mean(ratios_end) < 1.6
    assert 0.5 < np.mean(est_start) < 2.0 and 0.5 < np.mean(est_end) < 2.0


def test_boundary_modes_compared():
    # Oracle: the known drift over 10 seeds; the choice of "smooth-extend" (see the comment in
    # wavelet.py) rests on its first- and last-300-s errors being the smallest of the modes.
    rows = {}
    for boundary in ("smooth-extend", "symmetric", "reflect", "antireflect", "smooth",
                     "periodization"):
        first, last, interior = [], [], []
        for seed in range(10):
            res = wavelet_denoise(noisy(seed), level=8, boundary=boundary)
            err = res.signal - TRUTH
            k = res.edge_samples
            first.append(rms(err[:300]))
            last.append(rms(err[-300:]))
            interior.append(rms(err[k:N - k]))
        rows[boundary] = (np.mean(first), np.mean(last), np.mean(interior))
    print("\nboundary        first 300 s   last 300 s   interior  [deg/h]")
    for boundary, (f, l, i) in rows.items():
        print(f"{boundary:14s}  {f:.5f}       {l:.5f}      {i:.5f}")
    best = rows.pop("smooth-extend")
    for boundary, (f, l, _) in rows.items():
        assert best[0] <= f and best[1] <= l, boundary


def test_the_level_matters_more_than_the_family():
    # Oracle: the known drift. db4 / sym8 / coif3 at level 8 differ far less than db4 at
    # levels 4 (white noise left in the approximation: sigma / 4 per sample) and 11 (sigma / 45;
    # this drift is smooth enough that its details above 512 s survive the threshold).
    x = noisy(7)
    family = [rms(wavelet_denoise(x, level=8, wavelet=w).signal - TRUTH)
              for w in ("db4", "sym8", "coif3")]
    levels = [rms(wavelet_denoise(x, level=j, wavelet="db4").signal - TRUTH) for j in (4, 11)]
    family_spread = max(family) - min(family)
    level_spread = max(levels) - min(levels)
    print(f"\nfamily (db4, sym8, coif3 @ 8): {np.round(family, 5)}; "
          f"db4 @ 4, 11: {np.round(levels, 5)}")
    assert family_spread < 0.2 * level_spread


def test_a_large_step_is_kept_sharp():
    # Oracle: a step of 0.2 deg/h (8 sigma) at t = 4500 s. The thresholded details keep it:
    # 100 s from the step the error is a fraction of what the level-8 approximation alone
    # (all details dropped, a plain low-pass) leaves.
    step = np.where(T_S < 4500.0, 0.0, 0.2)
    x = step + SIGMA * np.random.default_rng(0).standard_normal(N)
    res = wavelet_denoise(x, level=8)
    away = np.abs(T_S - 4500.0) > 100.0
    # a threshold above every coefficient zeroes all details: the approximation alone
    lowpass = wavelet_denoise(x, level=8, rule=lambda d, s, n: float(np.max(np.abs(d))) + 1.0)
    err_kept = np.max(np.abs(res.signal - step)[away])
    err_lowpass = np.max(np.abs(lowpass.signal - step)[away])
    assert err_kept < 0.5 * err_lowpass
    assert err_kept < 0.02


def test_trusted_mask_keeps_bridged_gaps_out_of_the_noise_level():
    # Oracle: white noise of known sigma in which 30 of every 160 samples were replaced by a
    # straight line (as separate_drift bridges the turntable moves): without the mask the
    # median of |d_1| falls and sigma is underestimated; with it sigma is within 3 %.
    rng = np.random.default_rng(12)
    x = SIGMA * rng.standard_normal(N)
    bridged = (np.arange(N) % 160) >= 130
    x[bridged] = 0.0
    plain = wavelet_denoise(x, level=8).sigma
    masked = wavelet_denoise(x, level=8, trusted=~bridged).sigma
    assert plain < 0.93 * SIGMA
    assert masked == pytest.approx(SIGMA, rel=0.03)


def test_sigma_per_level_follows_coloured_noise():
    # Oracle: for white noise every level's MAD estimate is near sigma; for red noise (a
    # first-order autoregression, phi = 0.9, whose spectrum rises toward low frequency) the
    # per-level sigma rises with the level.
    rng = np.random.default_rng(21)
    white = wavelet_denoise(SIGMA * rng.standard_normal(2 ** 15), level=5,
                            sigma_per_level=True)
    assert white.sigma_per_level == pytest.approx((SIGMA,) * 5, rel=0.1)
    e = rng.standard_normal(2 ** 15)
    red = np.empty_like(e)
    red[0] = e[0]
    for i in range(1, e.size):
        red[i] = 0.9 * red[i - 1] + e[i]
    res = wavelet_denoise(red, level=5, sigma_per_level=True)
    assert all(np.diff(res.sigma_per_level) > 0)


def test_input_errors_name_the_fault():
    x = noisy(0)
    with pytest.raises(InputError, match="non-finite value at sample 3"):
        wavelet_denoise(np.where(np.arange(N) == 3, np.nan, x), level=8)
    with pytest.raises(InputError, match="smooth-extend"):
        wavelet_denoise(x, level=8, boundary="mirror-ish")
    with pytest.raises(InputError, match="soft"):
        wavelet_denoise(x, level=8, mode="firm")
    with pytest.raises(InputError, match="wavelet"):
        wavelet_denoise(x, level=8, wavelet="morl")     # continuous: no DWT
    assert "smooth-extend" in BOUNDARIES


def test_deterministic():
    # Invariant: the same record gives bitwise the same result (speed: benchmarks/).
    x = noisy(3)
    a = wavelet_denoise(x, level=8)
    b = wavelet_denoise(x, level=8)
    assert np.array_equal(a.signal, b.signal) and a.thresholds == b.thresholds
