"""Tests of the threshold rules and noise level of nfs.denoise.thresholds.

Each test names its oracle: the rule's closed form on a hand-computable case, a brute-force
minimisation written out with loops, or Stein's unbiasedness checked by Monte Carlo."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.denoise import (
    MAD_TO_SIGMA,
    THRESHOLD_RULES,
    bayes_shrink_threshold,
    mad_sigma,
    sure_risk,
    sure_threshold,
    visu_threshold,
    wavelet_denoise,
)
from nfs.errors import InputError, NfsError


def _sure_by_definition(t: float, x: list[float]) -> float:
    """SURE(t; x) = m - 2 #{|x_i| <= t} + sum min(|x_i|, t)^2, written out term by term."""
    m = len(x)
    count = 0
    total = 0.0
    for xi in x:
        if abs(xi) <= t:
            count += 1
        total += min(abs(xi), t) ** 2
    return m - 2 * count + total


# --------------------------------------------------------------------------------------------
# VisuShrink


def test_visu_threshold_is_sigma_sqrt_2_ln_n():
    # Closed form (Donoho & Johnstone 1994): T = sigma sqrt(2 ln n).
    assert visu_threshold(2.0, 1000) == pytest.approx(2.0 * math.sqrt(2.0 * math.log(1000)),
                                                      rel=1e-15)
    assert visu_threshold(0.5, 1) == 0.0
    with pytest.raises(InputError):
        visu_threshold(1.0, 0)


def test_visu_rule_in_the_denoiser_uses_the_record_length():
    # Closed form: every level's threshold is sigma_hat sqrt(2 ln n), n the record length.
    x = 0.01 * np.random.default_rng(5).standard_normal(3000)
    res = wavelet_denoise(x, level=5, rule="visu")
    expected = res.sigma * math.sqrt(2.0 * math.log(3000))
    assert res.thresholds == pytest.approx((expected,) * 5, rel=1e-12)


# --------------------------------------------------------------------------------------------
# SURE

SMALL = [0.1, -0.4, 2.5, 0.8, -3.1, 0.05, 1.2, -0.3, 0.6, -1.9]


def test_sure_risk_matches_its_definition():
    # Oracle: the formula written out with a loop.
    for t in (0.0, 0.05, 0.3, 0.8, 1.0, 2.5, 4.0):
        assert sure_risk(t, np.array(SMALL)) == pytest.approx(_sure_by_definition(t, SMALL),
                                                              abs=1e-12)


def test_sure_threshold_minimises_stein_risk_by_brute_force():
    # Oracle: brute-force minimisation of SURE over a fine grid of t in [0, sqrt(2 ln m)] and
    # over the data points themselves (SURE drops by 2 at each |x_i|, so its minimum sits on
    # one of them or at 0): the pure SURE threshold reaches the smallest risk found.
    t_u = math.sqrt(2.0 * math.log(len(SMALL)))
    grid = list(np.linspace(0.0, t_u, 20001)) + [abs(v) for v in SMALL if abs(v) <= t_u]
    risks = [_sure_by_definition(t, SMALL) for t in grid]
    t = sure_threshold(np.array(SMALL), 1.0, hybrid=False)
    assert _sure_by_definition(t, SMALL) == pytest.approx(min(risks), abs=1e-12)
    assert t == grid[int(np.argmin(risks))]
    # Invariant: the threshold scales with sigma (x = d / sigma).
    assert sure_threshold(0.7 * np.array(SMALL), 0.7, hybrid=False) == pytest.approx(0.7 * t)


def test_sure_risk_is_unbiased_by_monte_carlo():
    # Oracle: Stein (1981): E SURE(t; x) = E ||eta_t(x) - mu||^2 for x ~ N(mu, I).
    rng = np.random.default_rng(11)
    mu = np.concatenate((np.zeros(40), np.full(10, 3.0), np.linspace(-2, 2, 14)))
    t = 1.3
    draws = 4000
    x = mu + rng.standard_normal((draws, mu.size))
    loss = np.sum((np.sign(x) * np.maximum(np.abs(x) - t, 0.0) - mu) ** 2, axis=1)
    risk = np.array([sure_risk(t, row) for row in x])
    se = np.std(loss - risk) / math.sqrt(draws)
    assert abs(np.mean(risk) - np.mean(loss)) < 4 * se


def test_sure_hybrid_falls_back_to_universal_on_a_sparse_level():
    # Closed form of the hybrid rule (Donoho & Johnstone 1995): when
    # (sum x^2 - m) / m <= (log2 m)^1.5 / sqrt(m), T = sigma sqrt(2 ln m).
    rng = np.random.default_rng(3)
    d = 0.2 * rng.standard_normal(256)
    d[:2] = 1.0                                  # two 5-sigma spikes in noise: sparse
    x = d / 0.2
    m = d.size
    assert (np.sum(x * x) - m) / m <= math.log2(m) ** 1.5 / math.sqrt(m)
    assert sure_threshold(d, 0.2) == pytest.approx(0.2 * math.sqrt(2 * math.log(m)), rel=1e-15)


def test_sure_hybrid_uses_sure_on_a_dense_level():
    # Closed form of the hybrid rule: dense level -> min(t_SURE, t_u), here the SURE minimiser.
    rng = np.random.default_rng(4)
    d = rng.standard_normal(512) + np.where(np.arange(512) % 2 == 0, 2.0, -2.0)
    x = np.abs(d)
    m = d.size
    assert (np.sum(x * x) - m) / m > math.log2(m) ** 1.5 / math.sqrt(m)
    assert sure_threshold(d, 1.0) == pytest.approx(
        min(sure_threshold(d, 1.0, hybrid=False), math.sqrt(2 * math.log(m))), rel=1e-15)
    assert sure_threshold(d, 1.0) < math.sqrt(2 * math.log(m))


# --------------------------------------------------------------------------------------------
# BayesShrink


def test_bayes_shrink_on_a_hand_computed_case():
    # Closed form (Chang, Yu & Vetterli 2000): T = sigma^2 / sqrt(mean(d^2) - sigma^2).
    d = np.array([3.0, -4.0, 0.0, 0.0])          # mean(d^2) = 25/4
    assert bayes_shrink_threshold(d, 1.0) == pytest.approx(1.0 / math.sqrt(6.25 - 1.0),
                                                           rel=1e-15)
    assert bayes_shrink_threshold(d, 2.0) == pytest.approx(4.0 / math.sqrt(6.25 - 4.0),
                                                           rel=1e-15)


def test_bayes_shrink_on_pure_noise_zeroes_the_level():
    # The paper's rule: sigma_y <= sigma -> T = max |d| (every coefficient set to zero).
    d = np.array([0.5, -0.2, 0.1, -0.7])          # mean(d^2) = 0.1975 < 1
    assert bayes_shrink_threshold(d, 1.0) == 0.7


# --------------------------------------------------------------------------------------------
# registry and noise level


def test_registry_names_and_unknown_rule_lists_the_valid_ones():
    assert {"none", "visu", "sure", "bayes"} <= set(THRESHOLD_RULES)
    x = np.zeros(512)
    with pytest.raises(NfsError) as err:
        wavelet_denoise(x, level=3, rule="minimax")
    for name in ("visu", "sure", "bayes"):
        assert name in str(err.value)


def test_a_users_rule_plugs_in_like_a_built_in_one():
    # Invariant: a custom rule rule(detail, sigma, n) is called per level; here T = 3 sigma.
    x = 0.05 * np.random.default_rng(2).standard_normal(2048)

    def three_sigma(detail, sigma, n_samples):
        return 3.0 * sigma

    res = wavelet_denoise(x, level=4, rule=three_sigma)
    assert res.rule == "three_sigma"
    assert res.thresholds == pytest.approx((3.0 * res.sigma,) * 4, rel=1e-15)


def test_mad_sigma_closed_form_and_gaussian_consistency():
    # Closed form: median(|d|) / 0.6745; and consistency for Gaussian d (Donoho 1995).
    assert mad_sigma([1.0, -2.0, 3.0, -4.0, 5.0]) == pytest.approx(3.0 / MAD_TO_SIGMA)
    assert MAD_TO_SIGMA == pytest.approx(0.6745, abs=1e-4)
    d = 0.3 * np.random.default_rng(8).standard_normal(200_000)
    assert mad_sigma(d) == pytest.approx(0.3, rel=0.01)


def test_rules_in_the_denoiser_match_their_functions():
    # Invariant: the thresholds the denoiser reports for "sure" and "bayes" are
    # sure_threshold / bayes_shrink_threshold of the coefficients the denoiser hands to a rule
    # (recorded here by a user rule), and rule "none" gives zero everywhere.
    x = np.sin(np.arange(4096) / 200.0) + 0.1 * np.random.default_rng(9).standard_normal(4096)
    seen = []

    def recorder(detail, sigma, n_samples):
        seen.append((np.array(detail), sigma))
        return 0.0

    wavelet_denoise(x, level=4, rule=recorder)
    seen = seen[:4]   # the first pass; a second one estimates the edge error
    for rule, fn in (("sure", sure_threshold), ("bayes", bayes_shrink_threshold)):
        res = wavelet_denoise(x, level=4, rule=rule)
        assert res.thresholds == pytest.approx([fn(d, s) for d, s in seen], rel=1e-15)
        assert len(set(np.round(res.thresholds, 12))) > 1   # level-adaptive
    assert wavelet_denoise(x, level=4, rule="none").thresholds == (0.0,) * 4
