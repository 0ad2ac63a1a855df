"""Tests of nfs.noise.pooled: the Allan deviation of many short records, pooled, and the
bootstrap intervals of N, B, K.  Each test names its oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.errors import InputError
from nfs.noise import (fit_pooled_noise, gyro_noise_dph,
                       half_octave_taus_s, pooled_allan)
from nfs.noise.pooled import MIN_BOOTSTRAP_RECORDS, MIN_RECORD_SAMPLES


def _dwells(x: np.ndarray, n_dwells: int, dwell: int = 150, period: int = 160) -> list:
    """A 4-position schedule's records: ``dwell`` samples at rest of every ``period``."""
    return list(x[:n_dwells * period].reshape(n_dwells, period)[:, :dwell])


def test_half_octave_taus():
    # Oracle: m = round(2^(k/2)) without duplicates, up to N/2 = 75 samples.
    assert half_octave_taus_s(150, 1.0).tolist() == [1, 2, 3, 4, 6, 8, 11, 16, 23, 32, 45, 64]
    assert half_octave_taus_s(150, 10.0).tolist() == pytest.approx(
        [0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.1, 1.6, 2.3, 3.2, 4.5, 6.4])


def test_pooled_is_every_second_difference_of_every_record():
    # Oracle: eq. (1) written out: the sum of the squared second differences of the phase of
    # every record, over 2 tau^2 times their count (no second difference across records).
    rng = np.random.default_rng(3)
    recs = [rng.standard_normal(n) + 5.0 for n in (40, 57, 64)]
    p = pooled_allan(recs, 2.0).pooled()
    for tau, adev, count in zip(p.taus_s, p.adev, p.n_clusters):
        m = int(round(tau * 2.0))
        total, n = 0.0, 0
        for r in recs:
            if m > len(r) // 4:
                continue
            x = np.concatenate([[0.0], np.cumsum(r - r.mean()) / 2.0])
            d2 = x[2 * m:] - 2.0 * x[m:len(x) - m] + x[:len(x) - 2 * m]
            total += float(np.dot(d2, d2))
            n += d2.size
        assert count == n
        assert adev == pytest.approx(math.sqrt(total / (2.0 * tau * tau * n)), rel=1e-12)


def test_pool_limit_keeps_a_record_out_beyond_its_tau():
    # Oracle: with one record allowed only to 2 s, the pooled curve beyond 2 s is the other
    # record's own curve, to rounding; up to 2 s it lies between the two.
    rng = np.random.default_rng(4)
    recs = [rng.standard_normal(200), 3.0 * rng.standard_normal(200)]
    pa = pooled_allan(recs, 1.0, pool_max_tau_s=np.array([np.inf, 2.0]))
    p = pa.pooled()
    assert p.taus_s.tolist() == [1, 2, 3, 4, 6, 8, 11, 16, 23, 32, 45]   # to 200/4 samples
    beyond = p.taus_s > 2.0
    own = pa.record_adev[0, :p.taus_s.size]
    assert np.allclose(p.adev[beyond], own[beyond], rtol=1e-12)
    lo, hi = np.sort(pa.record_adev[:, :2], axis=0)
    assert np.all((lo <= p.adev[~beyond]) & (p.adev[~beyond] <= hi))


def test_white_noise_of_known_arw_gives_n_within_its_interval():
    # Oracle: white rate noise of N = 0.0003 deg/sqrt(h) has sigma(tau) = 60 N / sqrt(tau)
    # [deg/h] (IEEE Std 952-2020 Annex C); cut into 120 dwells of 150 s at 1 Hz, the pooled
    # curve follows that line within 4 of its relative errors, and the fitted N's interval
    # holds 0.0003 and is a few per cent wide.
    n_arw = 3e-4
    x = gyro_noise_dph(120 * 160, 1.0, arw_deg_per_rth_h=n_arw, bias_instability_dph=0.0,
                       rrw_deg_per_h_per_rth_h=0.0, rng=np.random.default_rng(11))
    pa = pooled_allan(_dwells(x, 120), 1.0)
    p = pa.pooled()
    line = 60.0 * n_arw / np.sqrt(p.taus_s)
    assert np.all(np.abs(p.adev / line - 1.0) < 4.0 * p.adev_rel_err)
    res = fit_pooled_noise(pa, rng=np.random.default_rng(0))
    lo, hi = res.arw_interval_deg_per_rth_h
    assert lo <= n_arw <= hi
    assert lo <= res.fit.arw_deg_per_rth_h <= hi
    assert (hi - lo) / n_arw < 0.05
    assert res.bias_instability_interval_dph[0] == 0.0        # no bias instability: from 0
    assert res.taus_s.tolist() == [1, 2, 3, 4, 6, 8, 11, 16, 23, 32]   # up to 150/4 s
    assert res.n_records == 120 and res.n_boot == 400 and res.level == 0.95


def test_bootstrap_is_seeded():
    # Oracle: the same generator seed gives the same intervals, another seed other ones.
    x = gyro_noise_dph(20 * 160, 1.0, arw_deg_per_rth_h=3e-4, bias_instability_dph=2e-3,
                       rrw_deg_per_h_per_rth_h=0.0, rng=np.random.default_rng(1))
    pa = pooled_allan(_dwells(x, 20), 1.0)
    a = fit_pooled_noise(pa, n_boot=50, rng=np.random.default_rng(5))
    b = fit_pooled_noise(pa, n_boot=50, rng=np.random.default_rng(5))
    c = fit_pooled_noise(pa, n_boot=50, rng=np.random.default_rng(6))
    assert a.arw_interval_deg_per_rth_h == b.arw_interval_deg_per_rth_h
    assert a.arw_interval_deg_per_rth_h != c.arw_interval_deg_per_rth_h


def test_too_few_records_give_no_interval():
    # Oracle: fewer records than MIN_BOOTSTRAP_RECORDS: the fit, and NaN intervals.
    rng = np.random.default_rng(2)
    pa = pooled_allan([rng.standard_normal(150) for _ in range(MIN_BOOTSTRAP_RECORDS - 1)], 1.0)
    res = fit_pooled_noise(pa, rng=np.random.default_rng(0))
    assert math.isfinite(res.fit.arw_deg_per_rth_h)
    assert all(math.isnan(v) for v in res.arw_interval_deg_per_rth_h)


def test_bad_input_is_one_located_error():
    with pytest.raises(InputError, match="record 1 must be 1-D with at least"):
        pooled_allan([np.zeros(20), np.zeros(MIN_RECORD_SAMPLES - 1)], 1.0)
    with pytest.raises(InputError, match="at least one record"):
        pooled_allan([], 1.0)
    with pytest.raises(InputError, match="max_fraction"):
        pooled_allan([np.zeros(20)], 1.0, max_fraction=0.6)
    pa = pooled_allan([np.random.default_rng(0).standard_normal(40)] * 8, 1.0)
    with pytest.raises(InputError, match="level"):
        fit_pooled_noise(pa, level=1.5, rng=np.random.default_rng(0))
    with pytest.raises(InputError, match="rng must be"):
        fit_pooled_noise(pa, rng=0)


@pytest.mark.slow
def test_interval_coverage_on_many_seeds():
    # Oracle: the module docstring's measurement, repeated on 60 seeds of 40 dwells: the 95 %
    # intervals hold N = 0.0003 in at least 85 % and B = 0.002 in at least 75 % of the sets
    # (binomial spread of 60 sets at 0.93 and 0.86: about 3 and 4.5 %).
    hits_n = hits_b = 0
    for seed in range(60):
        x = gyro_noise_dph(40 * 160, 1.0, arw_deg_per_rth_h=3e-4, bias_instability_dph=2e-3,
                           rrw_deg_per_h_per_rth_h=0.0, rng=np.random.default_rng(seed))
        res = fit_pooled_noise(pooled_allan(_dwells(x, 40), 1.0),
                               rng=np.random.default_rng(10_000 + seed))
        lo, hi = res.arw_interval_deg_per_rth_h
        hits_n += lo <= 3e-4 <= hi
        lo, hi = res.bias_instability_interval_dph
        hits_b += lo <= 2e-3 <= hi
    assert hits_n >= 0.85 * 60 and hits_b >= 0.75 * 60, (hits_n, hits_b)
