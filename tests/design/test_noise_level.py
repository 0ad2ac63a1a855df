"""nfs.rivals.noise_level.excess_factors on hand-made residuals.

Oracles: white residuals of the stated sigma give a factor of 1, of twice the stated sigma 2;
an AR(1) residual of lag-1 correlation rho and the stated marginal sigma carries the
information of white noise of variance (1 + rho) / (1 - rho) (Bayley and Hammersley 1946),
2 at rho = 0.6; the factor is never below 1; a constant per run is free (the nuisance); the
factors of several rivals average their squares.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.rivals.noise_level import excess_factors, scaled
from nfs.rivals.predict import CHANNELS, Prediction
from nfs.rivals.separation import RivalPrediction

N_RUN = 1000          # numbers per channel and run; two runs: 2000 per channel


def _pred(values):
    v = {c: np.asarray(x, dtype=float) for c, x in values.items()}
    return Prediction(v, {c: 60.0 * np.arange(x.size) for c, x in v.items()},
                      {c: np.full(x.size, 150.0) for c, x in v.items()})


def _ar1(rng, n, rho):
    """Unit-variance AR(1) of lag-1 correlation rho (started in its stationary law)."""
    e = rng.standard_normal(n)
    x = np.empty(n)
    x[0] = e[0]
    k = math.sqrt(1.0 - rho ** 2)
    for i in range(1, n):
        x[i] = rho * x[i - 1] + k * e[i]
    return x


def _case(rng, unit_residual, n_runs=2, n=N_RUN, offsets=False, equal_sigma=False):
    """(measured, [rival], sigma): the rival's numbers random, the measured ones the rival's
    plus sigma times ``unit_residual(rng, n)``; sigma differs number to number (unless
    ``equal_sigma``); ``offsets``: plus a constant per channel and run."""
    measured, means, sigma = [], [], []
    for r in range(n_runs):
        mu = {c: rng.normal(0.0, 10.0, n) for c in CHANNELS}
        sg = {c: (np.full(n, 1.3) if equal_sigma else rng.uniform(0.5, 2.0, n)) * 10.0 ** -k
              for k, c in enumerate(CHANNELS)}
        y = {c: mu[c] + sg[c] * unit_residual(rng, n)
             + (rng.uniform(-50, 50) * sg[c].mean() if offsets else 0.0) for c in CHANNELS}
        measured.append(_pred(y))
        means.append(_pred(mu))
        sigma.append(sg)
    return measured, [RivalPrediction(means)], sigma


def test_white_residual_of_the_stated_sigma_gives_one():
    rng = np.random.default_rng(1)
    f = excess_factors(*_case(rng, lambda g, n: g.standard_normal(n)))
    assert set(f) == set(CHANNELS)
    for c in CHANNELS:
        assert 1.0 <= f[c] <= 1.1, (c, f[c])


def test_white_residual_of_twice_the_sigma_gives_two():
    rng = np.random.default_rng(2)
    f = excess_factors(*_case(rng, lambda g, n: 2.0 * g.standard_normal(n)))
    for c in CHANNELS:
        assert f[c] == pytest.approx(2.0, rel=0.10), (c, f[c])


def test_ar1_residual_counts_its_correlation():
    rho = 0.6
    want = math.sqrt((1.0 + rho) / (1.0 - rho))          # = 2
    rng = np.random.default_rng(3)
    f = excess_factors(*_case(rng, lambda g, n: _ar1(g, n, rho)))
    for c in CHANNELS:
        assert f[c] == pytest.approx(want, rel=0.15), (c, f[c])
    # white noise of the same marginal sigma: about 1, not 2 (the correlation is what counts)
    rng = np.random.default_rng(3)
    white = excess_factors(*_case(rng, lambda g, n: g.standard_normal(n)))
    assert all(white[c] < 1.2 for c in CHANNELS)


@pytest.mark.parametrize("scale,rho", [(0.3, 0.0), (0.3, -0.8), (0.3, 0.6), (0.0, 0.0)])
def test_a_factor_is_never_below_one(scale, rho):
    """Residuals smaller than the sensor noise (white, anti-correlated or correlated), or
    none at all: the factor is 1."""
    rng = np.random.default_rng(4)
    f = excess_factors(*_case(rng, lambda g, n: scale * _ar1(g, n, rho)))
    for c in CHANNELS:
        assert f[c] == 1.0, (c, f[c])


def test_anti_correlation_is_clipped_to_white():
    """rho < 0 counts as 0: twice the noise, anti-correlated, still gives 2 (unclipped,
    4 (1 - 0.8) / (1 + 0.8) < 1 would give 1)."""
    rng = np.random.default_rng(8)
    f = excess_factors(*_case(rng, lambda g, n: 2.0 * _ar1(g, n, -0.8)))
    for c in CHANNELS:
        assert f[c] == pytest.approx(2.0, rel=0.10), (c, f[c])


def test_a_constant_per_run_is_free():
    """Equal sigma within a channel: a constant of up to 50 sigma per channel and run added
    to the residual changes nothing (kept, it would give a factor of about 30)."""
    rng = np.random.default_rng(5)
    plain = excess_factors(*_case(rng, lambda g, n: 2.0 * g.standard_normal(n),
                                  equal_sigma=True))
    rng = np.random.default_rng(5)
    shifted = excess_factors(*_case(rng, lambda g, n: 2.0 * g.standard_normal(n),
                                    offsets=True, equal_sigma=True))
    for c in CHANNELS:
        # the offsets draw one more number per channel and run, so the residuals differ
        assert shifted[c] == pytest.approx(2.0, rel=0.10), (c, shifted[c])
        assert plain[c] == pytest.approx(2.0, rel=0.10)


def test_a_constant_per_run_is_free_with_unequal_sigma():
    """A residual that is exactly a constant per run (the nuisance the separation and
    decide._llr leave free) shows no excess noise, whatever the sigma of each number."""
    n = 40
    mu = np.linspace(0.0, 1.0, n)
    sg = np.where(np.arange(n) < n // 2, 1.0, 2.0)     # e.g. two dwell lengths
    measured = [_pred({"drift_dph": mu + 5.0})]
    rival = RivalPrediction([_pred({"drift_dph": mu})])
    f = excess_factors(measured, [rival], [{"drift_dph": sg}])
    assert f["drift_dph"] == 1.0


def test_rivals_average_their_squared_factors():
    """One rival fits to the noise, the other leaves 1.7 times it: f^2 = (1 + 1.7^2) / 2."""
    rng = np.random.default_rng(6)
    measured, [good], sigma = _case(rng, lambda g, n: g.standard_normal(n))
    bad = RivalPrediction([_pred({c: m.values[c] - 1.7 * sg[c] * rng.standard_normal(
        m.values[c].size) for c in CHANNELS}) for m, sg in zip(measured, sigma)])
    # the bad rival's residual: measured - bad = 1.7 sigma e2, variance 1.7^2 sigma^2
    f = excess_factors(measured, [good, bad], sigma)
    want = math.sqrt((1.0 + 1.7 ** 2) / 2.0)
    for c in CHANNELS:
        assert f[c] == pytest.approx(want, rel=0.08), (c, f[c])
    # exactly: the mean of each rival's own squared factor (both above 1 here)
    f_good = excess_factors(measured, [good], sigma)
    f_bad = excess_factors(measured, [bad], sigma)
    for c in CHANNELS:
        assert f_good[c] > 1.0 and f_bad[c] == pytest.approx(1.7, rel=0.12)
        assert f[c] ** 2 == pytest.approx((f_good[c] ** 2 + f_bad[c] ** 2) / 2.0, rel=1e-12)


def test_missing_and_short_channels_give_one_and_nan_is_dropped():
    rng = np.random.default_rng(7)
    measured, preds, sigma = _case(rng, lambda g, n: 2.0 * g.standard_normal(n), n_runs=1)
    m = measured[0]
    vals = dict(m.values)
    del vals["acc_y_g"]                              # a channel the run did not record
    vals["temp_acc_x_c"] = vals["temp_acc_x_c"][:2]  # fewer than 3 numbers: skipped
    y = vals["drift_dph"].copy()
    y[::10] = np.nan                                 # dropped, not propagated
    vals["drift_dph"] = y
    short = {"temp_acc_x_c": 2}
    mean = preds[0].mean[0]
    mv = {c: (v[:short[c]] if c in short else v) for c, v in mean.values.items()}
    sg = {c: (v[:short[c]] if c in short else v) for c, v in sigma[0].items()}
    f = excess_factors([_pred(vals)], [RivalPrediction([_pred(mv)])], [sg])
    assert f["acc_y_g"] == 1.0
    assert f["temp_acc_x_c"] == 1.0
    assert math.isfinite(f["drift_dph"])
    assert f["drift_dph"] == pytest.approx(2.0, rel=0.12)


def test_scaled_multiplies_each_channel():
    sg = {"drift_dph": np.array([1.0, 2.0]), "acc_x_g": np.array([3.0])}
    out = scaled(sg, {"drift_dph": 2.5})
    np.testing.assert_array_equal(out["drift_dph"], [2.5, 5.0])
    np.testing.assert_array_equal(out["acc_x_g"], [3.0])
