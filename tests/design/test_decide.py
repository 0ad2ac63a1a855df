"""nfs.rivals.decide and nfs.rivals.evidence: the rule's rates, closed form and Monte Carlo.

Oracles: right = Phi(s/2 - max(L/s, z)), wrong = Phi(-s/2 - max(L/s, z)) (scipy.stats.norm),
L = LAMBDA_NAME, z = Z_NAME; on the linear-Gaussian model y = mu_b + e, e ~ N(0, sigma^2),
Lambda = e^T P d - D / 2 ~ N(-D/2, D), so the rate of naming a is the wrong rate and the rate
of naming b at most the right rate (the long-run variance counted is at least D), within
binomial 3-sigma over seeded draws.  Where neither rival is the unit and both are equally
close (y their midpoint plus a strongly autocorrelated model error that the noise sigma does
not describe), Vuong's Z is N(0, 1): the rule names one with a rate near 2 x 5 %, where a
likelihood ratio alone names one in most draws.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from nfs.rivals.decide import LAMBDA_NAME, Z_NAME, Decision, decision_rates
from nfs.rivals.evidence import Evidence, bartlett_bandwidth, evidence, long_run_variance
from nfs.rivals.noise_level import excess_factors, scaled
from nfs.rivals.predict import Prediction
from nfs.rivals.separation import RivalPrediction, separation

CHANS = ("drift_dph", "temp_fog_c", "acc_x_g")


def _pred(values, grid=None):
    v = {c: np.asarray(x, dtype=float) for c, x in values.items()}
    # each channel its own times unless a shared grid is asked for
    times = {c: (60.0 * np.arange(x.size) if grid else 60.0 * np.arange(x.size) + 0.1 * k)
             for k, (c, x) in enumerate(v.items())}
    return Prediction(v, times, {c: np.full(x.size, 150.0) for c, x in v.items()})


def _need(s):
    return max(LAMBDA_NAME / s, Z_NAME)


@pytest.mark.parametrize("s", [0.5, 1.0, 2.0, 3.0, 4.5, 8.0])
def test_rates_closed_form(s):
    right, wrong = decision_rates(s)
    assert right == pytest.approx(norm.cdf(s / 2.0 - _need(s)), rel=1e-12)
    assert wrong == pytest.approx(norm.cdf(-s / 2.0 - _need(s)), rel=1e-12)
    assert 0.0 < wrong < right < 1.0
    # other thresholds
    r1, w1 = decision_rates(s, threshold=1.0, z=0.0)
    assert r1 == pytest.approx(norm.cdf(s / 2.0 - 1.0 / s), rel=1e-12)
    assert w1 == pytest.approx(norm.cdf(-s / 2.0 - 1.0 / s), rel=1e-12)


def test_rates_match_the_docstring():
    assert Z_NAME == pytest.approx(norm.ppf(0.95), rel=1e-12)
    right, wrong = decision_rates(3.0)
    assert right == pytest.approx(0.44, abs=0.005)
    assert wrong == pytest.approx(0.0008, abs=0.00005)
    right, wrong = decision_rates(5.0)
    assert right == pytest.approx(0.80, abs=0.005)
    assert wrong < 2e-5


def test_rates_monotonicity():
    s = np.linspace(0.05, 12.0, 400)
    right = np.array([decision_rates(x)[0] for x in s])
    wrong = np.array([decision_rates(x)[1] for x in s])
    assert np.all(np.diff(right) > 0)                     # right grows with s
    # wrong peaks where L / s = z, s = L / z, and falls beyond
    peak = LAMBDA_NAME / Z_NAME
    assert np.all(np.diff(wrong[s > peak]) < 0)
    assert np.all(np.diff(wrong[s < peak]) > 0)
    assert right[-1] > 0.99 and wrong[-1] < 1e-6
    assert decision_rates(0.0) == (0.0, 0.0)
    assert decision_rates(-1.0) == (0.0, 0.0)


def test_winner_needs_both_the_ratio_and_z():
    def d(llr, var=1.0, price=0.0):
        return Decision("a", "b", Evidence(llr, 9.0, price, var, {}), {})
    assert d(LAMBDA_NAME).winner == "a"                          # z = 2 >= 1.645
    assert d(LAMBDA_NAME - 1e-9).winner is None
    assert d(-LAMBDA_NAME).winner == "b"
    assert d(-LAMBDA_NAME + 1e-9).winner is None
    assert d(5.0, var=(5.0 / Z_NAME) ** 2 * 1.0001).winner is None   # z just short
    assert d(5.0, var=(5.0 / Z_NAME) ** 2 * 0.9999).winner == "a"
    assert d(5.0, price=3.5).winner is None                     # 5 - 3.5 < 2
    assert d(5.0, price=-3.5).winner == "a"                     # b fits more numbers
    # fewer numbers win nothing by themselves: b leans ahead by 1.2 with 5 more numbers
    assert d(-1.2, price=-5.0).evidence.adjusted == 0.0
    assert d(-1.2, price=-5.0).winner is None
    assert d(-9.0, price=-5.0).evidence.adjusted == pytest.approx(-4.0, rel=1e-12)
    assert d(-9.0, price=-5.0).winner == "b"
    assert ("e^9.0 for b, e^4.0 after the price of the 5 numbers it fits"
            in d(-9.0, price=-5.0).text), d(-9.0, price=-5.0).text
    assert "price" not in d(5.0, price=-3.5).text
    assert "favour a" in d(5.0).text and "cannot decide" in d(0.3).text
    assert d(5.0, var=4.0).evidence.z == pytest.approx(2.5, rel=1e-12)


def test_bandwidth_closed_form():
    for rho, n in ((0.5, 100), (0.9, 150), (0.97, 1000)):
        alpha = 4 * rho ** 2 / ((1 - rho) ** 2 * (1 + rho) ** 2)
        assert bartlett_bandwidth(rho, n) == min(n - 1, math.ceil(1.1447 * (alpha * n) ** (1 / 3)))
    assert bartlett_bandwidth(0.999, 1000) == bartlett_bandwidth(0.97, 1000)   # clipped
    assert bartlett_bandwidth(0.0, 100) == 0 and bartlett_bandwidth(-0.3, 100) == 0
    assert bartlett_bandwidth(0.9, 1) == 0


def test_long_run_variance_of_an_ar1():
    """Var(sum x) of an AR(1) of unit innovations: n / (1 - rho)^2 for long series."""
    rng = np.random.default_rng(7)
    rho, n = 0.8, 200_000
    e = rng.standard_normal(n)
    x = np.empty(n)
    x[0] = e[0] / math.sqrt(1 - rho ** 2)
    for i in range(1, n):
        x[i] = rho * x[i - 1] + e[i]
    want = n / (1 - rho) ** 2
    got = long_run_variance(x, bartlett_bandwidth(rho, n))
    assert got == pytest.approx(want, rel=0.06)
    # lag 0 alone is the plain sum of squares; a white series needs no lags
    assert long_run_variance(x, 0) == pytest.approx(float(x @ x), rel=1e-12)
    # by hand: 3 + 2 (2/3)(-2) + 2 (1/3)(1) = 1
    assert long_run_variance(np.array([1.0, -1.0, 1.0]), 2) == pytest.approx(1.0, rel=1e-12)


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


def _lam(y, pa, pb, sigma, price=0.0):
    return evidence(y, pa, pb, sigma, CHANS, price=price)


def test_llr_by_hand():
    """One y: Lambda = (|P (y - mu_b) / s|^2 - |P (y - mu_a) / s|^2) / 2, P the weighted
    constant per channel and run removed; and the per-channel entries add up."""
    rng = np.random.default_rng(1)
    pa, pb, sigma, s = _model(rng)
    y = [_pred({c: b.values[c] + sg[c] * rng.standard_normal(b.values[c].size)
                for c in CHANS}) for b, sg in zip(pb, sigma)]
    ev = _lam(y, pa, pb, sigma)
    want = 0.0
    for yr, ar, br, sg in zip(y, pa, pb, sigma):
        for c in CHANS:
            w = 1.0 / sg[c]
            for mu, sign in ((br, 0.5), (ar, -0.5)):
                r = (yr.values[c] - mu.values[c]) * w
                r = r - w * np.sum(w * r) / np.sum(w * w)
                want += sign * float(r @ r)
    assert ev.llr == pytest.approx(want, rel=1e-10)
    assert ev.llr == pytest.approx(sum(ev.by_channel.values()), rel=1e-12)
    assert ev.d2 == pytest.approx(s ** 2, rel=1e-10)
    assert ev.variance >= ev.d2
    # a constant added to a channel of one run changes nothing (projected out)
    y2 = [_pred({c: v + (7.0 if c == "drift_dph" else 0.0) for c, v in yr.values.items()})
          for yr in y]
    assert _lam(y2, pa, pb, sigma).llr == pytest.approx(ev.llr, rel=1e-9, abs=1e-9)
    # swapping the rivals flips the sign, and the price moves Lambda_adj only
    assert _lam(y, pb, pa, sigma).llr == pytest.approx(-ev.llr, rel=1e-12)
    want = max(ev.llr - 3.0, 0.0) if ev.llr >= 0 else ev.llr     # a pays, only if ahead
    assert _lam(y, pa, pb, sigma, price=3.0).adjusted == pytest.approx(want, rel=1e-12)
    want = ev.llr if ev.llr >= 0 else min(ev.llr + 3.0, 0.0)     # b pays, only if ahead
    assert _lam(y, pa, pb, sigma, price=-3.0).adjusted == pytest.approx(want, rel=1e-12)


def test_monte_carlo_rates_of_the_rule():
    rng = np.random.default_rng(2024)
    pa, pb, sigma, s = _model(rng, 5.0)
    assert s == pytest.approx(5.0, rel=1e-9)
    right, wrong = decision_rates(s)
    n = 4000
    named = []
    lam = np.empty(n)
    for k in range(n):
        y = [_pred({c: b.values[c] + sg[c] * rng.standard_normal(b.values[c].size)
                    for c in CHANS}) for b, sg in zip(pb, sigma)]
        ev = _lam(y, pa, pb, sigma)
        lam[k] = ev.llr
        named.append(Decision("a", "b", ev, {}).winner)
    named_a = named.count("a") / n          # b is the truth: a is wrong
    named_b = named.count("b") / n
    assert named_a <= wrong + 3.0 * math.sqrt(max(wrong, 1.0 / n) / n)
    # the long-run variance counted is at least D: at most the closed form, and not far
    # below it (white noise: the estimate is D plus its sampling error)
    assert right - 0.06 <= named_b <= right + 3.0 * math.sqrt(right * (1.0 - right) / n), \
        (named_b, right)
    # Lambda ~ N(-D/2, D)
    d2 = s ** 2
    assert lam.mean() == pytest.approx(-d2 / 2.0, abs=3.0 * s / math.sqrt(n))
    assert lam.var() == pytest.approx(d2, rel=0.07)


def _ar1(rng, n, rho, scale):
    e = rng.standard_normal(n) * scale
    x = np.empty(n)
    x[0] = e[0] / math.sqrt(1.0 - rho ** 2)
    for i in range(1, n):
        x[i] = rho * x[i - 1] + e[i]
    return x


def test_neither_rival_the_unit_false_alarm_rate():
    """y = the rivals' midpoint + slow model error (AR(1), rho 0.95) that the sensor noise
    does not describe, the noise raised by the excess the residuals show as the decision
    does (nfs.rivals.noise_level): both rivals equally close, Z ~ N(0, 1).  The rule names
    one in at most 10 % of draws (two one-sided 5 % tests; measured 5 %); the likelihood
    ratio alone (Lambda >= 2) names one far more often."""
    rng = np.random.default_rng(11)
    n_runs, n = 4, 150
    t = np.arange(n) / n
    sigma = [{c: np.ones(n) for c in CHANS} for _ in range(n_runs)]
    pa = [_pred({c: 3.0 * np.exp(-t / 0.2) * (1 + 0.3 * k) for k, c in enumerate(CHANS)})
          for _ in range(n_runs)]
    pb = [_pred({c: -3.0 * np.exp(-t / 0.2) * (1 + 0.3 * k) for k, c in enumerate(CHANS)})
          for _ in range(n_runs)]
    draws = 400
    new = old = 0
    for _ in range(draws):
        y = [_pred({c: _ar1(rng, n, 0.95, 1.0) for c in CHANS}) for _ in range(n_runs)]
        f = excess_factors(y, [RivalPrediction(pa), RivalPrediction(pb)], sigma)
        ev = _lam(y, pa, pb, [scaled(sg, f) for sg in sigma])
        new += Decision("a", "b", ev, {}).winner is not None
        old += abs(ev.llr) >= LAMBDA_NAME
    assert new / draws <= 0.10, new / draws
    assert old / draws >= 2.0 * new / draws + 0.1, (old / draws, new / draws)


def test_price_keeps_a_rival_fitted_to_noise_out():
    """Rival a = the model plus k = 5 coefficients fitted to pure noise (in-sample): Lambda =
    chi^2_5 / 2.  With the price the rule names a almost never (chi^2_5 >= 27: 5e-5); without
    it, about 5 %."""
    rng = np.random.default_rng(5)
    n, k, draws = 120, 5, 2000
    basis = rng.standard_normal((n, k))
    basis -= basis.mean(axis=0)                   # orthogonal to the run's constant
    q, _ = np.linalg.qr(basis)
    sigma = [{"drift_dph": np.ones(n)}]
    zero = [_pred({"drift_dph": np.zeros(n)})]
    with_price = without = 0
    for _ in range(draws):
        e = rng.standard_normal(n)
        fit = q @ (q.T @ e)
        y = [_pred({"drift_dph": e})]
        pa = [_pred({"drift_dph": fit})]
        ev = evidence(y, pa, zero, sigma, ("drift_dph",), price=k)
        assert ev.llr == pytest.approx(0.5 * float(fit @ fit), rel=1e-9)
        with_price += Decision("a", "b", ev, {}).winner == "a"
        bare = evidence(y, pa, zero, sigma, ("drift_dph",))
        without += Decision("a", "b", bare, {}).winner == "a"
    assert with_price / draws <= 0.003
    assert without / draws >= 0.02


def test_channels_sharing_times_count_common_error_once():
    """Two channels with the same numbers on one grid: their scores add before the long-run
    variance (4x one channel's); on different grids they count as independent (2x)."""
    rng = np.random.default_rng(3)
    n = 60
    err = 3.0 * rng.standard_normal(n)     # 3x the noise: the long-run variance ~9 D
    dif = np.linspace(1.0, -1.0, n) ** 2
    chans = ("temp_fog_c", "temp_acc_x_c")

    def var(grid):
        y = [_pred({c: err for c in chans}, grid=grid)]
        pa = [_pred({c: dif for c in chans}, grid=grid)]
        pb = [_pred({c: -dif for c in chans}, grid=grid)]
        sg = [{c: np.ones(n) for c in chans}]
        return evidence(y, pa, pb, sg, chans)
    one = evidence([_pred({"temp_fog_c": err})], [_pred({"temp_fog_c": dif})],
                   [_pred({"temp_fog_c": -dif})], [{"temp_fog_c": np.ones(n)}],
                   ("temp_fog_c",))
    shared, apart = var(True), var(False)
    assert shared.llr == pytest.approx(2 * one.llr, rel=1e-12)
    assert apart.llr == pytest.approx(2 * one.llr, rel=1e-12)
    assert shared.variance >= apart.variance
    assert one.variance > one.d2     # the long-run variance counted, not the floor D
    assert shared.variance == pytest.approx(4 * one.variance, rel=1e-9)
    assert apart.variance == pytest.approx(2 * one.variance, rel=1e-9)
