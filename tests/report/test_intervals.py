"""The two-level bootstrap of RMSE tables, its paired comparisons and Holm's adjustment.

Oracles: coverage of the true RMSE by the 95 % intervals on draws from a known distribution
of cycle errors (Gaussian, a start-up effect of standard deviation tau shared by the cycles
of a start-up plus cycle noise sigma: true RMSE sqrt(tau^2 + sigma^2)); a zero difference
between identical rows; Holm's adjustment by hand (Holm 1979).
"""

import math

import numpy as np
import pytest

from nfs.scoring.intervals import (ClusterBootstrap, bc_interval, cluster_bootstrap, compare_rows, holm)

R, N, COLS = 5, 5, 7          # start-ups per column, cycles per start-up, start temperatures


def _draw(rng, tau, sigma, cols=COLS, r=R, n=N):
    return [[rng.normal(0.0, tau) + rng.normal(0.0, sigma, n) for _ in range(r)]
            for _ in range(cols)]


@pytest.mark.parametrize("tau, sigma", [(0.0, 1.0), (0.5, 1.0)])
def test_intervals_cover_the_true_rmse(tau, sigma):
    # 200 seeded trials of a 7-column table, 5 start-ups x 5 cycles per column: the cells'
    # and the row mean's 95 % intervals hold the truth in 90-99 % of them.
    truth = math.hypot(tau, sigma)
    cell_hits = row_hits = 0
    trials = 200
    for seed in range(trials):
        rng = np.random.default_rng(seed)
        boot = cluster_bootstrap([_draw(rng, tau, sigma)], n_boot=1000, random_state=seed)
        ci = boot.cell_intervals()[0]
        cell_hits += np.count_nonzero((ci[:, 0] <= truth) & (truth <= ci[:, 1]))
        lo, hi = boot.row_intervals()[0]
        row_hits += lo <= truth <= hi
    cell_cover = cell_hits / (trials * COLS)
    row_cover = row_hits / trials
    assert 0.90 <= cell_cover <= 0.99, cell_cover
    assert 0.90 <= row_cover <= 0.99, row_cover


def test_point_estimates_are_the_pooled_rmse_and_same_seed_same_replicates():
    rng = np.random.default_rng(1)
    errors = [_draw(rng, 0.3, 1.0, cols=3), _draw(rng, 0.3, 2.0, cols=3)]
    errors[0][1][2] = np.append(errors[0][1][2], np.nan)       # a failed cycle is left out
    a = cluster_bootstrap(errors, n_boot=200, random_state=4)
    b = cluster_bootstrap(errors, n_boot=200, random_state=4)
    np.testing.assert_array_equal(a.cell_replicates, b.cell_replicates)
    for i in range(2):
        for j in range(3):
            e = np.concatenate(errors[i][j])
            e = e[np.isfinite(e)]
            assert a.cells[i, j] == pytest.approx(np.sqrt(np.mean(e * e)), rel=1e-12)
    assert a.row_means[1] == pytest.approx(np.mean(a.cells[1]))
    ci = a.cell_intervals()
    assert np.all(ci[..., 0] <= a.cells) and np.all(a.cells <= ci[..., 1])


def test_identical_rows_are_not_distinguishable():
    rng = np.random.default_rng(2)
    row = _draw(rng, 0.3, 1.0)
    boot = cluster_bootstrap([row, [list(c) for c in row]], n_boot=500, random_state=0)
    (c,) = compare_rows(boot, ["A", "B"], [("A", "B")])
    assert c.difference_deg == 0.0 and c.ci_low_deg == 0.0 == c.ci_high_deg
    assert c.p_value == 1.0 and not c.distinguishable
    assert "not distinguishable" in c.sentence()


def test_same_distribution_rarely_distinguishable_and_a_clear_gap_always():
    # Two compensators whose cycle errors come from one distribution (independent draws on
    # the same start-ups) are called distinguishable in about 5 % of trials at most; a
    # compensator with 1.5x the error of another is called distinguishable every time.
    same = clear = 0
    for seed in range(60):
        rng = np.random.default_rng(100 + seed)
        base = _draw(rng, 0.3, 1.0)
        twin = _draw(rng, 0.3, 1.0)
        worse = [[1.5 * c for c in col] for col in base]
        boot = cluster_bootstrap([base, twin, worse], n_boot=1000, random_state=seed)
        comp = compare_rows(boot, ["base", "twin", "worse"], [("base", "twin")])
        same += comp[0].distinguishable
        comp = compare_rows(boot, ["base", "twin", "worse"], [("worse", "base")])
        clear += comp[0].distinguishable and comp[0].difference_deg > 0
    assert same <= 6, same
    assert clear == 60


def test_holm_by_hand():
    # sorted 0.01, 0.03, 0.04, 0.2 -> 4 x 0.01, 3 x 0.03, max(2 x 0.04, 0.09), 0.2
    np.testing.assert_allclose(holm([0.01, 0.04, 0.03, 0.2]), [0.04, 0.09, 0.09, 0.2])
    out = holm([0.5, math.nan, 0.6])
    assert math.isnan(out[1]) and out[0] == 1.0 and out[2] == 1.0


def test_compare_rows_adjusts_over_the_pairs_and_drops_duplicates():
    rng = np.random.default_rng(5)
    rows = [_draw(rng, 0.2, s) for s in (1.0, 1.2, 2.0)]
    boot = cluster_bootstrap(rows, n_boot=800, random_state=1)
    comps = compare_rows(boot, ["a", "b", "c"], [("a", "c"), ("c", "a"), ("b", "c"),
                                                    ("a", "b")])
    assert [(c.method_a, c.method_b) for c in comps] == [("a", "c"), ("b", "c"), ("a", "b")]
    np.testing.assert_allclose([c.p_adjusted for c in comps], holm([c.p_value for c in comps]))
    d = comps[0].to_dict()
    assert set(d) >= {"method_a", "method_b", "difference_deg", "ci_low_deg", "ci_high_deg",
                      "p_adjusted", "distinguishable"}


def test_bc_interval_of_a_symmetric_distribution_is_the_percentile_interval():
    b = np.linspace(-1.0, 1.0, 4001)
    lo, hi = bc_interval(b, 0.0)
    assert lo == pytest.approx(-0.95, abs=1e-3) and hi == pytest.approx(0.95, abs=1e-3)
    assert all(math.isnan(v) for v in bc_interval(np.array([np.nan]), 1.0))


def test_empty_cells_are_nan():
    boot = ClusterBootstrap(cells=np.array([[np.nan, 1.0]]),
                            cell_replicates=np.array([[[np.nan] * 3, [1.0, 0.9, 1.1]]]))
    assert boot.row_means[0] == 1.0
    assert np.all(np.isnan(boot.cell_intervals()[0, 0]))


def test_a_seed_spread_larger_than_the_gap_is_not_distinguishable():
    # Method b is 5 % worse than the shown training of method a on every cycle of the same
    # start-ups: as two trained models they differ.  Trained with three seeds whose errors
    # scale by 0.9, 1.0 and 1.2, method a cannot be told from b: the comparison draws a
    # seed per replicate.  The rows' own intervals do not depend on the variants.
    rng = np.random.default_rng(7)
    a = _draw(rng, 0.3, 1.0)
    b = [[1.05 * c for c in col] for col in a]
    seeds = [[[f * c for c in col] for col in a] for f in (0.9, 1.0, 1.2)]
    plain = cluster_bootstrap([a, b], n_boot=2000, random_state=3)
    mixed = cluster_bootstrap([a, b], variants=[seeds, None], n_boot=2000, random_state=3)
    np.testing.assert_array_equal(plain.cell_replicates, mixed.cell_replicates)
    (c_plain,) = compare_rows(plain, ["a", "b"], [("a", "b")])
    (c_mixed,) = compare_rows(mixed, ["a", "b"], [("a", "b")])
    assert c_plain.difference_deg == c_mixed.difference_deg < 0
    assert c_plain.distinguishable and not c_mixed.distinguishable
    assert c_mixed.ci_low_deg < 0 < c_mixed.ci_high_deg


def test_an_interval_holds_its_estimate_when_the_replicates_pile_up_on_one_side():
    # Oracle (invariant): low <= estimate <= high.  The R^2 of a constant prediction c on
    # test data y, -n (ybar - c)^2 / SST <= 0, with c the training mean close to ybar: block
    # replicates pile up on one side, z0 beyond z_0.975, and the uncorrected BC interval
    # (Efron & Tibshirani eq. (14.10)) lay entirely on the other side of the estimate.
    rng = np.random.default_rng(3)
    y = np.sin(np.linspace(0.0, 6.0, 60)) + rng.normal(0.0, 0.1, 60)
    c = y.mean() + 1e-3
    est = -y.size * (y.mean() - c) ** 2 / np.sum((y - y.mean()) ** 2)
    idx = rng.integers(0, y.size, (2000, y.size))
    ys = y[idx]
    reps = -y.size * (ys.mean(axis=1) - c) ** 2 / np.sum(
        (ys - ys.mean(axis=1, keepdims=True)) ** 2, axis=1)
    assert np.mean(reps < est) > 0.975           # the case the correction cannot carry
    lo, hi = bc_interval(reps, est)
    assert lo <= est <= hi and lo < hi
    # the estimate beyond every replicate: the bound on its side is the estimate
    lo, hi = bc_interval(np.linspace(1.0, 2.0, 500), 3.0)
    assert hi == 3.0 and 1.0 <= lo < 3.0
    lo, hi = bc_interval(np.linspace(1.0, 2.0, 500), 0.5)
    assert lo == 0.5 and 0.5 < hi <= 2.0
