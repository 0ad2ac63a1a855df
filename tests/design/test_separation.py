"""Closed forms of nfs.rivals.separation.separation on hand-made predictions.

Oracles: D = sum (d_i / s_i)^2 without draws or nuisance; the (1/s^2-weighted) mean of each
channel and run removed with the nuisance; for draws, the Woodbury form against the dense
Mahalanobis distance d^T (S + U U^T)^-1 d (numpy.linalg.solve), and with the nuisance the
generalised-least-squares form d^T [W - W C (C^T W C)^-1 C^T W] d, W = (S + U U^T)^-1 (the
constants C integrated out); and the algebra: symmetry, per-channel entries, E[LLR] = D / 2,
additivity over runs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.rivals.predict import CHANNELS, Prediction
from nfs.rivals.separation import RivalPrediction, separation


def _pred(values: dict[str, np.ndarray]) -> Prediction:
    """A prediction with the given numbers (times a minute apart, 150 s spans)."""
    v = {c: np.asarray(x, dtype=float) for c, x in values.items()}
    return Prediction(v, {c: 60.0 * np.arange(1, x.size + 1) for c, x in v.items()},
                      {c: np.full(x.size, 150.0) for c, x in v.items()})


def _sizes(rng, channels=CHANNELS, lo=4, hi=12):
    return {c: int(rng.integers(lo, hi)) for c in channels}


def _random(rng, sizes, scale=1.0):
    return {c: scale * rng.standard_normal(n) for c, n in sizes.items()}


def _sigma(rng, sizes):
    return {c: rng.uniform(0.3, 3.0, n) for c, n in sizes.items()}


def _flat(d: dict, channels) -> np.ndarray:
    return np.concatenate([np.asarray(d[c], dtype=float) for c in channels])


# ---- no draws ---------------------------------------------------------------------------

def test_no_draws_no_nuisance_is_the_sum_of_squared_whitened_differences():
    rng = np.random.default_rng(1)
    sizes = _sizes(rng)
    va, vb, sg = _random(rng, sizes), _random(rng, sizes), _sigma(rng, sizes)
    sep = separation(RivalPrediction([_pred(va)]), RivalPrediction([_pred(vb)]), [sg],
                     nuisance=False)
    want = sum(float(np.sum(((va[c] - vb[c]) / sg[c]) ** 2)) for c in CHANNELS)
    assert sep.sigma ** 2 == pytest.approx(want, rel=1e-12)
    assert sep.n_numbers == sum(sizes.values())
    for c in CHANNELS:
        assert sep.by_channel[c] ** 2 == pytest.approx(
            float(np.sum(((va[c] - vb[c]) / sg[c]) ** 2)), rel=1e-12)


def test_nuisance_equal_sigma_removes_each_channels_mean():
    rng = np.random.default_rng(2)
    sizes = _sizes(rng)
    va, vb = _random(rng, sizes), _random(rng, sizes)
    s = 0.7
    sg = {c: np.full(n, s) for c, n in sizes.items()}
    sep = separation(RivalPrediction([_pred(va)]), RivalPrediction([_pred(vb)]), [sg],
                     nuisance=True)
    want = 0.0
    for c in CHANNELS:
        d = va[c] - vb[c]
        want += float(np.sum((d - d.mean()) ** 2)) / s ** 2
    assert sep.sigma ** 2 == pytest.approx(want, rel=1e-12)
    # and the nuisance does remove something here
    raw = separation(RivalPrediction([_pred(va)]), RivalPrediction([_pred(vb)]), [sg],
                     nuisance=False)
    assert raw.sigma > sep.sigma * (1.0 + 1e-6)


def test_nuisance_a_constant_difference_separates_nothing():
    rng = np.random.default_rng(3)
    sizes = _sizes(rng)
    va, sg = _random(rng, sizes), _sigma(rng, sizes)
    offsets = {c: float(rng.uniform(-5.0, 5.0)) for c in CHANNELS}
    vb = {c: va[c] + offsets[c] for c in CHANNELS}
    sep = separation(RivalPrediction([_pred(va)]), RivalPrediction([_pred(vb)]), [sg],
                     nuisance=True)
    assert sep.sigma == pytest.approx(0.0, abs=1e-6)
    raw = separation(RivalPrediction([_pred(va)]), RivalPrediction([_pred(vb)]), [sg],
                     nuisance=False)
    assert raw.sigma > 1.0


def test_nuisance_unequal_sigma_removes_the_weighted_mean():
    rng = np.random.default_rng(4)
    sizes = {"drift_dph": 9, "temp_fog_c": 7}
    chans = list(sizes)
    va, vb = _random(rng, sizes), _random(rng, sizes)
    sg = {c: rng.uniform(0.2, 4.0, n) for c, n in sizes.items()}
    sep = separation(RivalPrediction([_pred(va)]), RivalPrediction([_pred(vb)]), [sg],
                     channels=chans, nuisance=True)
    want, unweighted = 0.0, 0.0
    for c in chans:
        d, s = va[c] - vb[c], sg[c]
        dbar = np.sum(d / s ** 2) / np.sum(1.0 / s ** 2)
        want += float(np.sum(((d - dbar) / s) ** 2))
        unweighted += float(np.sum(((d - d.mean()) / s) ** 2))
    assert sep.sigma ** 2 == pytest.approx(want, rel=1e-12)
    # the weighting matters for these numbers (the test could tell the two apart)
    assert abs(want - unweighted) > 1e-3 * want
    assert set(sep.by_channel) == set(chans)


# ---- draws ------------------------------------------------------------------------------

def test_one_draw_direction_closed_form():
    """Two draws at mean +- sigma u / sqrt(2): whitened columns +-u / sqrt(2) ... times
    sqrt(2) from 1 / sqrt(K - 1) = 1, so M M^T = u u^T.  A difference d = c sigma u gives
    D = |z|^2 - (u.z)^2 / (1 + |u|^2) = |z|^2 / (1 + |u|^2)."""
    rng = np.random.default_rng(5)
    chans = ["drift_dph", "acc_x_g", "temp_fog_c"]
    sizes = {c: 8 for c in chans}
    sg = _sigma(rng, sizes)
    u = _random(rng, sizes)
    mean_a = _random(rng, sizes, scale=3.0)
    for c_len in (0.3, 1.0, 4.0):
        mean_b = {c: mean_a[c] - c_len * sg[c] * u[c] for c in chans}
        draws = [[_pred({c: mean_a[c] + sign * sg[c] * u[c] / math.sqrt(2.0)
                         for c in chans})] for sign in (1.0, -1.0)]
        a = RivalPrediction([_pred(mean_a)], draws)
        b = RivalPrediction([_pred(mean_b)])
        sep = separation(a, b, [sg], channels=chans, nuisance=False)
        uu = _flat(u, chans)
        z = c_len * uu
        closed = z @ z - (uu @ z) ** 2 / (1.0 + uu @ uu)
        assert sep.sigma ** 2 == pytest.approx(closed, rel=1e-9)
        assert sep.sigma ** 2 == pytest.approx((z @ z) / (1.0 + uu @ uu), rel=1e-9)
        # the draws on b instead of a: the same (the spread is of the difference)
        a2 = RivalPrediction([_pred(mean_a)])
        draws_b = [[_pred({c: mean_b[c] + sign * sg[c] * u[c] / math.sqrt(2.0)
                           for c in chans})] for sign in (1.0, -1.0)]
        b2 = RivalPrediction([_pred(mean_b)], draws_b)
        assert separation(a2, b2, [sg], channels=chans, nuisance=False).sigma ** 2 == \
            pytest.approx(closed, rel=1e-9)
        # without the draws: |z|^2, larger
        plain = separation(a2, b, [sg], channels=chans, nuisance=False)
        assert plain.sigma ** 2 == pytest.approx(z @ z, rel=1e-12)
        assert plain.sigma > sep.sigma


def _dense_case(rng, k_a, k_b, n_runs=1, chans=CHANNELS):
    """Random rivals with k_a and k_b draws over n_runs runs; returns (a, b, sigma, d, S, U,
    groups) with d, S, U stacked as separation stacks them (run-major, then channel)."""
    sizes = [_sizes(rng, chans, 3, 8) for _ in range(n_runs)]
    sg = [_sigma(rng, s) for s in sizes]
    mean_a = [_random(rng, s, 2.0) for s in sizes]
    mean_b = [_random(rng, s, 2.0) for s in sizes]

    def draws(mean, k):
        return [[_pred({c: m[c] + rng.uniform(0.2, 1.5) * rng.standard_normal(m[c].size)
                        * sgr[c] for c in chans}) for m, sgr in zip(mean, sg)]
                for _ in range(k)]

    da, db = draws(mean_a, k_a), draws(mean_b, k_b)
    a = RivalPrediction([_pred(m) for m in mean_a], da)
    b = RivalPrediction([_pred(m) for m in mean_b], db)

    def stack(preds):
        return np.concatenate([p.values[c] for p in preds for c in chans])

    d = stack(a.mean) - stack(b.mean)
    S = np.diag(np.concatenate([s[c] for s in sg for c in chans]) ** 2)
    cols = []
    for r in (a, b):
        k = len(r.draws)
        if k >= 2:
            cols += [(stack(dr) - stack(r.mean)) / math.sqrt(k - 1) for dr in r.draws]
    U = np.column_stack(cols) if cols else np.zeros((d.size, 0))
    groups = np.concatenate([np.full(s[c], g) for g, (s, c) in
                             enumerate((s, c) for s in sizes for c in chans)])
    return a, b, sg, d, S, U, groups


@pytest.mark.parametrize("seed,k_a,k_b", [(10, 2, 2), (11, 3, 0), (12, 2, 3), (13, 4, 4)])
def test_draws_match_the_dense_mahalanobis_distance(seed, k_a, k_b):
    rng = np.random.default_rng(seed)
    a, b, sg, d, S, U, _ = _dense_case(rng, k_a, k_b)
    sep = separation(a, b, sg, nuisance=False)
    dense = float(d @ np.linalg.solve(S + U @ U.T, d))
    assert sep.sigma ** 2 == pytest.approx(dense, rel=1e-9)
    assert sep.sigma ** 2 < float(d @ np.linalg.solve(S, d))   # draws only blur


@pytest.mark.parametrize("seed,k_a,k_b,n_runs", [(20, 3, 2, 1), (21, 2, 4, 2)])
def test_draws_with_nuisance_match_the_constants_integrated_out(seed, k_a, k_b, n_runs):
    """With the nuisance, D = d^T [W - W C (C^T W C)^-1 C^T W] d, W = (S + U U^T)^-1, C the
    indicator of each channel and run (the constants given a flat prior)."""
    rng = np.random.default_rng(seed)
    a, b, sg, d, S, U, groups = _dense_case(rng, k_a, k_b, n_runs)
    sep = separation(a, b, sg, nuisance=True)
    W = np.linalg.inv(S + U @ U.T)
    C = (groups[:, None] == np.arange(groups.max() + 1)[None, :]).astype(float)
    R = W - W @ C @ np.linalg.solve(C.T @ W @ C, C.T @ W)
    assert sep.sigma ** 2 == pytest.approx(float(d @ R @ d), rel=1e-9)


# ---- algebra ----------------------------------------------------------------------------

@pytest.mark.parametrize("nuisance", [False, True])
def test_symmetry_by_channel_and_expected_llr(nuisance):
    rng = np.random.default_rng(30)
    a, b, sg, *_ = _dense_case(rng, 3, 2, n_runs=2)
    ab = separation(a, b, sg, nuisance=nuisance)
    ba = separation(b, a, sg, nuisance=nuisance)
    assert ab.sigma == pytest.approx(ba.sigma, rel=1e-12)
    assert ab.sigma > 0.5
    for c in CHANNELS:
        assert ab.by_channel[c] == pytest.approx(ba.by_channel[c], rel=1e-12)
        alone = separation(a, b, sg, channels=[c], nuisance=nuisance)
        assert ab.by_channel[c] == pytest.approx(alone.sigma, rel=1e-12)
        assert alone.by_channel == {c: pytest.approx(alone.sigma, rel=1e-12)}
    assert ab.expected_llr == pytest.approx(ab.sigma ** 2 / 2.0, rel=1e-12)
    assert ab.to_dict()["expected_log_likelihood_ratio"] == ab.expected_llr


def test_two_runs_add_without_draws():
    """Stacked runs: D = D_run1 + D_run2, the nuisance a constant per channel *and run*
    (the runs' offsets differ, so a constant per channel only would leave more)."""
    rng = np.random.default_rng(40)
    s1, s2 = _sizes(rng), _sizes(rng)
    a1, a2 = _random(rng, s1), _random(rng, s2)
    b1 = {c: a1[c] + 0.3 * rng.standard_normal(n) + 4.0 for c, n in s1.items()}
    b2 = {c: a2[c] + 0.3 * rng.standard_normal(n) - 3.0 for c, n in s2.items()}
    g1, g2 = _sigma(rng, s1), _sigma(rng, s2)
    for nuisance in (False, True):
        both = separation(RivalPrediction([_pred(a1), _pred(a2)]),
                          RivalPrediction([_pred(b1), _pred(b2)]), [g1, g2],
                          nuisance=nuisance)
        one = separation(RivalPrediction([_pred(a1)]), RivalPrediction([_pred(b1)]), [g1],
                         nuisance=nuisance)
        two = separation(RivalPrediction([_pred(a2)]), RivalPrediction([_pred(b2)]), [g2],
                         nuisance=nuisance)
        assert both.sigma ** 2 == pytest.approx(one.sigma ** 2 + two.sigma ** 2, rel=1e-12)
        assert both.n_numbers == one.n_numbers + two.n_numbers
    # a constant per channel across both runs would not remove the -7 between the runs
    pooled = 0.0
    for c in CHANNELS:
        d = np.concatenate([a1[c] - b1[c], a2[c] - b2[c]])
        s = np.concatenate([g1[c], g2[c]])
        dbar = np.sum(d / s ** 2) / np.sum(1.0 / s ** 2)
        pooled += float(np.sum(((d - dbar) / s) ** 2))
    assert pooled > 2.0 * both.sigma ** 2


def test_until_keeps_the_prefix():
    rng = np.random.default_rng(50)
    sizes = {c: 10 for c in CHANNELS}
    va, vb, sg = _random(rng, sizes), _random(rng, sizes), {c: np.ones(10) for c in CHANNELS}
    a = RivalPrediction([_pred(va)], [[_pred(va)], [_pred(vb)]]).until(300.0)
    assert all(a.mean[0].values[c].size == 5 for c in CHANNELS)
    assert all(d[0].values[c].size == 5 for d in a.draws for c in CHANNELS)
    b = RivalPrediction([_pred(vb)]).until(300.0)
    sep = separation(a, b, [{c: s[:5] for c, s in sg.items()}], nuisance=False)
    assert sep.n_numbers == 5 * len(CHANNELS)
