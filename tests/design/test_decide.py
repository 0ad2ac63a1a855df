"""nfs.design.decide: the decision rule's rates, closed form and Monte Carlo.

Oracles: right = Phi(s/2 - L/s), wrong = Phi(-s/2 - L/s) (scipy.stats.norm), L = LAMBDA_NAME;
on the linear-Gaussian model y = mu_b + e, e ~ N(0, sigma^2), Lambda = e^T P d - D / 2 ~
N(-D/2, D), so the rate of naming a (Lambda >= L) is the wrong rate and the rate of naming b
(Lambda <= -L) the right rate, within binomial 3-sigma over seeded draws.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from nfs.design.decide import LAMBDA_NAME, Decision, _llr, decision_rates
from nfs.design.predict import Prediction
from nfs.design.separation import RivalPrediction, separation

CHANS = ("drift_dph", "temp_fog_c", "acc_x_g")


def _pred(values):
    v = {c: np.asarray(x, dtype=float) for c, x in values.items()}
    return Prediction(v, {c: 60.0 * np.arange(x.size) for c, x in v.items()},
                      {c: np.full(x.size, 150.0) for c, x in v.items()})


@pytest.mark.parametrize("s", [0.5, 1.0, 2.0, 3.0, 4.5, 8.0])
def test_rates_closed_form(s):
    right, wrong = decision_rates(s)
    assert right == pytest.approx(norm.cdf(s / 2.0 - LAMBDA_NAME / s), rel=1e-12)
    assert wrong == pytest.approx(norm.cdf(-s / 2.0 - LAMBDA_NAME / s), rel=1e-12)
    assert 0.0 < wrong < right < 1.0
    # another threshold
    r1, w1 = decision_rates(s, threshold=1.0)
    assert r1 == pytest.approx(norm.cdf(s / 2.0 - 1.0 / s), rel=1e-12)
    assert w1 == pytest.approx(norm.cdf(-s / 2.0 - 1.0 / s), rel=1e-12)


def test_rates_at_the_margin_match_the_docstring():
    right, wrong = decision_rates(3.0)
    assert right == pytest.approx(0.80, abs=0.005)
    assert wrong == pytest.approx(0.015, abs=0.0005)


def test_rates_monotonicity():
    s = np.linspace(0.05, 12.0, 400)
    right = np.array([decision_rates(x)[0] for x in s])
    wrong = np.array([decision_rates(x)[1] for x in s])
    assert np.all(np.diff(right) > 0)                     # right grows with s
    # wrong peaks at s = sqrt(2 L) (d/ds (-s/2 - L/s) = 0) and falls beyond
    peak = math.sqrt(2.0 * LAMBDA_NAME)
    assert np.all(np.diff(wrong[s > peak]) < 0)
    assert np.all(np.diff(wrong[s < peak]) > 0)
    assert right[-1] > 0.99 and wrong[-1] < 1e-6
    assert decision_rates(0.0) == (0.0, 0.0)
    assert decision_rates(-1.0) == (0.0, 0.0)


def test_winner_follows_the_threshold():
    def d(llr):
        return Decision("a", "b", llr, 3.0, {}, {})
    assert d(LAMBDA_NAME).winner == "a"
    assert d(LAMBDA_NAME - 1e-9).winner is None
    assert d(-LAMBDA_NAME).winner == "b"
    assert d(-LAMBDA_NAME + 1e-9).winner is None
    assert "favour a" in d(5.0).text and "cannot decide" in d(0.3).text


def _model(rng, target_s=3.0):
    """Two runs, three channels: mu_a, mu_b, sigma per run with s = target_s (nuisance on)."""
    mu_a, mu_b, sigma = [], [], []
    for n in (14, 20):
        ma = {c: rng.normal(0.0, 5.0, n) for c in CHANS}
        shape = {c: rng.standard_normal(n) + 1.5 for c in CHANS}    # not constant
        sg = {c: rng.uniform(0.5, 2.0, n) for c in CHANS}
        mu_a.append(ma)
        mu_b.append(shape)   # the difference's shape, scaled below
        sigma.append(sg)
    # scale the difference so that s = target_s
    diff = [{c: sh[c] * sg[c] for c in CHANS} for sh, sg in zip(mu_b, sigma)]

    def sep(k):
        a = RivalPrediction([_pred(m) for m in mu_a])
        b = RivalPrediction([_pred({c: m[c] - k * d[c] for c in CHANS})
                             for m, d in zip(mu_a, diff)])
        return separation(a, b, sigma, channels=CHANS, nuisance=True).sigma
    k = target_s / sep(1.0)
    mb = [{c: m[c] - k * d[c] for c in CHANS} for m, d in zip(mu_a, diff)]
    return [_pred(m) for m in mu_a], [_pred(m) for m in mb], sigma, sep(k)


def test_llr_by_hand():
    """One y: Lambda = (|P (y - mu_b) / s|^2 - |P (y - mu_a) / s|^2) / 2, P the weighted
    constant per channel and run removed; and the per-channel entries add up."""
    rng = np.random.default_rng(1)
    pa, pb, sigma, _ = _model(rng)
    y = [_pred({c: b.values[c] + sg[c] * rng.standard_normal(b.values[c].size)
                for c in CHANS}) for b, sg in zip(pb, sigma)]
    lam, by = _llr(y, pa, pb, sigma, CHANS)
    want = 0.0
    for yr, ar, br, sg in zip(y, pa, pb, sigma):
        for c in CHANS:
            w = 1.0 / sg[c]
            for mu, sign in ((br, 0.5), (ar, -0.5)):
                r = (yr.values[c] - mu.values[c]) * w
                r = r - w * np.sum(w * r) / np.sum(w * w)
                want += sign * float(r @ r)
    assert lam == pytest.approx(want, rel=1e-10)
    assert lam == pytest.approx(sum(by.values()), rel=1e-12)
    # a constant added to a channel of one run changes nothing (projected out)
    y2 = [_pred({c: v + (7.0 if c == "drift_dph" else 0.0) for c, v in yr.values.items()})
          for yr in y]
    assert _llr(y2, pa, pb, sigma, CHANS)[0] == pytest.approx(lam, rel=1e-9, abs=1e-9)
    # swapping the rivals flips the sign
    assert _llr(y, pb, pa, sigma, CHANS)[0] == pytest.approx(-lam, rel=1e-12)


def test_monte_carlo_rates_of_the_rule():
    rng = np.random.default_rng(2024)
    pa, pb, sigma, s = _model(rng, 3.0)
    assert s == pytest.approx(3.0, rel=1e-9)
    right, wrong = decision_rates(s)
    n = 4000
    lam = np.empty(n)
    for k in range(n):
        y = [_pred({c: b.values[c] + sg[c] * rng.standard_normal(b.values[c].size)
                    for c in CHANS}) for b, sg in zip(pb, sigma)]
        lam[k] = _llr(y, pa, pb, sigma, CHANS)[0]
    named_a = float(np.mean(lam >= LAMBDA_NAME))      # b is the truth: a is wrong
    named_b = float(np.mean(lam <= -LAMBDA_NAME))
    for rate, p in ((named_a, wrong), (named_b, right)):
        assert abs(rate - p) <= 3.0 * math.sqrt(p * (1.0 - p) / n), (rate, p)
    # Lambda ~ N(-D/2, D)
    d2 = s ** 2
    assert lam.mean() == pytest.approx(-d2 / 2.0, abs=3.0 * s / math.sqrt(n))
    assert lam.var() == pytest.approx(d2, rel=0.07)
