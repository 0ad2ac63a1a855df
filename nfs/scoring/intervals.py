"""Uncertainty of RMSE tables: a two-level (cluster) bootstrap, paired comparisons, Holm.

A table cell is the pooled RMSE of the heading errors of several start-ups (the clusters),
each contributing a few north-finding cycles::

    RMSE_j = sqrt( sum_{r,k} e_{rk}^2 / n_j )        (start-ups r at column j, cycles k)

and a row's mean is the mean of its cells over the columns (start temperatures).  Errors of
one start-up are correlated (they share its drift residual and its bias instability), so the
start-up, not the cycle, is the unit that is resampled.

Estimator (Davison & Hinkley 1997, *Bootstrap Methods and their Application*, section 3.8,
strategy "resample both stages"): in every replicate and every column j, draw R_j start-ups
with replacement out of the column's R_j; inside each drawn start-up, draw its n_r cycle slots
with replacement out of its n_r; the replicate cell is the pooled RMSE of the drawn errors,
the replicate row mean the mean of its replicate cells.  Resampling the second stage as well
as the first adds the within-start-up variance once more, which offsets the low variance of a
first stage of only five clusters.  Coverage of the 95 % intervals on Gaussian cycle errors
(a start-up effect of standard deviation tau shared by its cycles, cycle noise sigma; 5
start-ups x 5 cycles per column; 200 trials; ``tests/report/test_intervals.py``):

======================  =====  ==========================
tau / sigma             cells  row mean of 7 columns
======================  =====  ==========================
0 (independent cycles)  95 %   97 %
0.5                     94 %   96 %
1                       88 %   90 %
3                       77 %   84 %
======================  =====  ==========================

(resampling the start-ups alone, percentile intervals: about 78 % and 85 % at tau = sigma).  Five start-ups cannot
measure a start-up effect much larger than the cycle noise: no bootstrap of them can.

Interval: the bias-corrected percentile interval (Efron 1981; Efron & Tibshirani 1993,
*An Introduction to the Bootstrap*, eq. (14.10) without acceleration)::

    z0 = Phi^-1( #{theta* < theta_hat} / B ),   [ G^-1(Phi(2 z0 + z_{a/2})),
                                                  G^-1(Phi(2 z0 + z_{1-a/2})) ]

with G the replicates' distribution: an RMSE of few terms is biased low (Jensen), and so
are its replicates around it; the correction moves the interval up accordingly, which matters most for a row
mean, where the bias of seven cells adds up while their spread averages down.

An interval holds its estimate.  The estimate's own rank among the replicates is Phi(z0), and
the bounds' ranks are Phi(2 z0 -+ z_{1-a/2}): the estimate stays inside while ``|z0|`` <=
z_{1-a/2}.  Beyond that, more than 97.5 % of the replicates fall on one side of the estimate:
a statistic at or near a bound of its range (the R^2 of a constant prediction c is
-n (ybar - c)^2 / SST <= 0 with ybar - c close to 0: resampling moves ybar* - c and SST*
together and the replicates pile up on one side), where the bootstrap distribution is no
shifted copy of the estimate's and the correction would carry both bounds past it.  There z0
is limited to +-z_{1-a/2} (the bound on the estimate's side falls on the estimate's rank),
and a bound that no replicate reaches (the estimate beyond every replicate; the
interpolation between the two replicates around it) is the estimate itself.

Paired comparisons: two rows scored on the same start-ups are resampled with the same draws
(common random numbers), so the replicates of the difference of their row means carry the
pairing.  A row trained several times (a tuner run with several seeds, the row showing one
of them) has its variants: in each replicate of a comparison it is represented by one of
its variants drawn at random, so that the difference between two methods carries the spread
of their trainings as well as that of the test start-ups (two trained models scored on the
same start-ups can differ consistently while their tuners cannot be told apart).  Its p-value inverts the bias-corrected interval: the largest level at which the
interval still excludes zero, p = 2 Phi(-|Phi^-1(F0) - 2 z0|), F0 = #{d* < 0} / B, with F0
kept inside [1/(B+1), B/(B+1)] and p no smaller than 2/(B+1).  Several comparisons are adjusted with Holm's step-down
method (Holm 1979, Scand. J. Statist. 6, 65-70), which controls the family-wise error rate.
Every draw comes from ``numpy.random.default_rng(random_state)``: same seed, same intervals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.stats import norm

from ..docfields import document_fields

__all__ = ["ClusterBootstrap", "PairedComparison", "cluster_bootstrap", "bc_interval", "bc_pvalue",
           "holm", "compare_rows", "DEFAULT_N_BOOT", "LEVEL", "positive_interval"]

#: Replicates of the bootstrap (p-values resolve down to about 2/B: 5e-4).
DEFAULT_N_BOOT = 4000
#: Confidence level of every interval.
LEVEL = 0.95


#: Fewest finite bootstrap replicates the drift and parameter tables draw an interval from.
MIN_REPLICATES = 10


def bc_interval(replicates: np.ndarray, estimate: float, level: float = LEVEL, *,
                min_replicates: int = 1) -> tuple[float, float]:
    """Bias-corrected percentile interval of ``estimate`` from its bootstrap replicates.

    Parameters
    ----------
    replicates : ndarray (B,)
        Bootstrap replicates theta* (non-finite ones are ignored).
    estimate : float
        The statistic on the original data, theta_hat.
    level : float
        Confidence level (0.95: the 2.5 % and 97.5 % bounds).
    min_replicates : int
        Fewest finite replicates an interval is drawn from.

    Returns
    -------
    (low, high) : tuple of float
        low <= estimate <= high (module docstring: the correction limited to
        ``|z0| <= z_{(1+level)/2}``); NaN when there are fewer finite replicates than
        ``min_replicates`` (or none) or the estimate is not finite.
    """
    b = np.asarray(replicates, dtype=float)
    b = b[np.isfinite(b)]
    if b.size < max(1, min_replicates) or not math.isfinite(estimate):
        return math.nan, math.nan
    z = float(norm.ppf((1.0 + level) / 2.0))
    z0 = min(max(_z0(b, estimate), -z), z)
    lo, hi = np.quantile(b, norm.cdf(2.0 * z0 + np.array([-z, z])))
    return float(min(lo, estimate)), float(max(hi, estimate))


def bc_pvalue(replicates: np.ndarray, estimate: float, null: float = 0.0) -> float:
    """Two-sided p-value of ``estimate`` against ``null`` that inverts :func:`bc_interval`.

    The largest 1 - level at which the bias-corrected interval excludes ``null``:
    p = 2 Phi(-|Phi^-1(F0) - 2 z0|), F0 the fraction of replicates below ``null``; never
    below 2 / (B + 1), the smallest p-value B replicates can resolve.
    """
    b = np.asarray(replicates, dtype=float)
    b = b[np.isfinite(b)]
    if b.size == 0 or not math.isfinite(estimate):
        return math.nan
    p = 2.0 * norm.cdf(-abs(norm.ppf(_below(b, null)) - 2.0 * _z0(b, estimate)))
    return float(min(1.0, max(p, 2.0 / (b.size + 1))))


def _below(b: np.ndarray, value: float) -> float:
    """Fraction of replicates below ``value``, ties counted half, kept inside
    [1/(B+1), B/(B+1)].  A replicate within 1e-9 (relative) of ``value`` is a tie: a
    resample that draws the original data again reproduces the estimate up to rounding,
    which must not decide the side (the same table on another number of BLAS threads)."""
    n = b.size
    tol = 1e-9 * max(abs(value), float(np.max(np.abs(b))), np.finfo(float).tiny)
    f = (np.count_nonzero(b < value - tol) + 0.5 * np.count_nonzero(np.abs(b - value) <= tol)) / n
    return min(max(f, 1.0 / (n + 1)), n / (n + 1))


def _z0(b: np.ndarray, estimate: float) -> float:
    return float(norm.ppf(_below(b, estimate)))


def holm(pvalues: Sequence[float]) -> np.ndarray:
    """Holm's step-down adjusted p-values (Holm 1979, Scand. J. Statist. 6(2) 65, sec. 3;
    NaN stays NaN).

    p_adj(i) = max_{k <= i} min(1, (m - k + 1) p_(k)) over the m finite p-values sorted
    ascending; rejecting every hypothesis with p_adj <= alpha keeps the family-wise error
    rate at most alpha for any dependence between the tests.  Written here (a few lines)
    rather than adding statsmodels for its ``multipletests``.
    """
    p = np.asarray(pvalues, dtype=float)
    out = np.full(p.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(p))
    m = ok.size
    if m == 0:
        return out
    order = ok[np.argsort(p[ok], kind="stable")]
    adj = np.minimum(1.0, (m - np.arange(m)) * p[order])
    out[order] = np.maximum.accumulate(adj)
    return out


@dataclass(frozen=True)
class ClusterBootstrap:
    """Point estimates and bootstrap replicates of an RMSE table (rows x columns)."""

    cells: np.ndarray
    """Pooled RMSE of every cell, shape (n_rows, n_columns) [unit of the errors]."""
    cell_replicates: np.ndarray
    """Replicates of every cell, shape (n_rows, n_columns, n_boot)."""
    level: float = LEVEL
    """Confidence level of the intervals."""
    compare_replicates: np.ndarray | None = None
    """Replicates of each row mean for comparisons, shape (n_rows, n_boot): a row with
    variants takes a variant drawn at random in each replicate (None: the row itself)."""

    @property
    def row_means(self) -> np.ndarray:
        """Mean of each row's finite cells, shape (n_rows,)."""
        return finite_mean(self.cells, axis=1)

    @property
    def row_replicates(self) -> np.ndarray:
        """Replicates of each row mean, shape (n_rows, n_boot)."""
        return finite_mean(self.cell_replicates, axis=1)

    def cell_intervals(self) -> np.ndarray:
        """Bias-corrected intervals of the cells, shape (n_rows, n_columns, 2)."""
        r, c, _ = self.cell_replicates.shape
        out = np.empty((r, c, 2))
        for i in range(r):
            for j in range(c):
                out[i, j] = bc_interval(self.cell_replicates[i, j], self.cells[i, j],
                                        self.level)
        return out

    def row_intervals(self) -> np.ndarray:
        """Bias-corrected intervals of the row means, shape (n_rows, 2)."""
        reps, means = self.row_replicates, self.row_means
        return np.array([bc_interval(reps[i], means[i], self.level)
                         for i in range(len(means))]).reshape(-1, 2)

    def difference(self, i: int, j: int) -> tuple[float, float, float, float]:
        """Row mean i minus row mean j, its interval and its two-sided p-value (paired:
        both rows were resampled with the same draws)."""
        d = float(self.row_means[i] - self.row_means[j])
        r = self.row_replicates if self.compare_replicates is None else \
            self.compare_replicates
        reps = r[i] - r[j]
        lo, hi = bc_interval(reps, d, self.level)
        return d, lo, hi, bc_pvalue(reps, d)


def finite_mean(a: np.ndarray, axis: int) -> np.ndarray:
    """Mean of the finite entries of ``a`` along ``axis``, in the unit of ``a`` (an RMSE
    [deg]); NaN where a slice has none (a cell or replicate that did not run), without
    NumPy's warning for an all-NaN slice."""
    a = np.asarray(a, dtype=float)
    ok = np.isfinite(a)
    n = ok.sum(axis=axis)
    s = np.where(ok, a, 0.0).sum(axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, s / np.maximum(n, 1), np.nan)


def cluster_bootstrap(errors, *, variants=None, n_boot: int = DEFAULT_N_BOOT,
                      random_state: int = 0, level: float = LEVEL) -> ClusterBootstrap:
    """Two-level bootstrap of a table of pooled RMSEs (see the module docstring).

    Parameters
    ----------
    errors : nested sequence
        ``errors[row][column][cluster]``: a 1-D array of the errors of one cluster (e.g. the
        start-up heading errors of one test run [deg]).  Every row must have the same
        clusters in every column, in the same order (rows scored on the same runs): they
        are resampled with the same draws, so differences between rows are paired.  A
        cluster's arrays may differ in length between rows (shorter ones are padded with
        NaN); non-finite errors are left out of every RMSE.
    variants : sequence, optional
        ``variants[row]``: None, or a list of tables like ``errors[row]`` (e.g. the same
        method trained with each tuner seed, ``errors[row]`` among them), on the same
        clusters.  Comparisons draw one of them per replicate (uniformly, from a stream of
        its own, so the cluster draws do not depend on it).
    n_boot : int
        Replicates.
    random_state : int
        Seed of the draws.
    level : float
        Confidence level of the intervals.

    Returns
    -------
    ClusterBootstrap
    """
    if n_boot < 1:
        raise ValueError(f"n_boot must be >= 1, got {n_boot}")
    shown = [list(r) for r in errors]
    n_rows = len(shown)
    variants = list(variants) if variants is not None else [None] * n_rows
    if len(variants) != n_rows:
        raise ValueError("variants needs one entry per row")
    # every table resampled: the rows, then each row's variants
    tables, owner = list(shown), []
    for i, v in enumerate(variants):
        for t in v or ():
            tables.append(list(t))
            owner.append(i)
    cells, reps = _bootstrap_tables(tables, n_boot, np.random.default_rng(random_state))
    compare = None
    if owner:
        compare = finite_mean(reps[:n_rows], axis=1)
        pick = np.random.default_rng([random_state, 1])
        means = finite_mean(reps, axis=1)
        for i in range(n_rows):
            idx = np.array([n_rows + k for k, o in enumerate(owner) if o == i])
            if idx.size:
                compare[i] = means[idx[pick.integers(0, idx.size, n_boot)],
                                   np.arange(n_boot)]
    return ClusterBootstrap(cells=cells[:n_rows], cell_replicates=reps[:n_rows], level=level,
                            compare_replicates=compare)


def _bootstrap_tables(tables, n_boot: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Cells and replicates of every table, all resampled with the same draws."""
    n_rows = len(tables)
    n_cols = len(tables[0]) if tables else 0
    if any(len(r) != n_cols for r in tables):
        raise ValueError("every row needs the same number of columns")
    cells = np.full((n_rows, n_cols), np.nan)
    reps = np.full((n_rows, n_cols, n_boot), np.nan)
    for j in range(n_cols):
        clusters = [[np.asarray(c, dtype=float).ravel() for c in r[j]] for r in tables]
        n_cl = len(clusters[0])
        if any(len(c) != n_cl for c in clusters):
            raise ValueError(f"column {j}: every row needs the same clusters")
        if n_cl == 0:
            continue
        slots = np.array([max(c[k].size for c in clusters) for k in range(n_cl)])
        width = int(slots.max())
        if width == 0:
            continue
        sq = np.full((n_rows, n_cl, width), np.nan)
        for i, row in enumerate(clusters):
            for k, c in enumerate(row):
                sq[i, k, :c.size] = c * c
        fin = np.isfinite(sq)
        tot = np.where(fin, sq, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            cells[:, j] = np.sqrt(tot.sum(axis=(1, 2)) / fin.sum(axis=(1, 2)))
        pick = rng.integers(0, n_cl, size=(n_boot, n_cl))              # first stage
        n_pick = slots[pick]
        u = rng.random(size=(n_boot, n_cl, width))                     # second stage
        slot = np.minimum((u * n_pick[..., None]).astype(int), width - 1)
        valid = np.arange(width) < n_pick[..., None]
        s = tot[:, pick[..., None], slot]                 # (rows, B, clusters, width)
        n = fin[:, pick[..., None], slot] & valid
        with np.errstate(invalid="ignore", divide="ignore"):
            reps[:, j, :] = np.sqrt(np.where(n, s, 0.0).sum(axis=(2, 3)) / n.sum(axis=(2, 3)))
    return cells, reps


@document_fields
@dataclass(frozen=True)
class PairedComparison:
    """A paired comparison of two rows' means (row a minus row b)."""

    method_a: str
    method_b: str
    difference_deg: float
    """Mean of a minus mean of b [deg] (negative: a has the lower error)."""
    ci_low_deg: float
    ci_high_deg: float
    """Bias-corrected 95 % interval of the difference (paired bootstrap) [deg]."""
    p_value: float
    """Two-sided p-value of a zero difference (unadjusted)."""
    p_adjusted: float
    """Holm-adjusted over every comparison reported with it."""
    alpha: float = 0.05
    """Family-wise error rate of the verdict."""

    @property
    def distinguishable(self) -> bool:
        """True when the Holm-adjusted p-value is below ``alpha``."""
        return bool(math.isfinite(self.p_adjusted) and self.p_adjusted < self.alpha)

    def sentence(self, digits: int = 4) -> str:
        """E.g. ``SSA-SVR vs PSO-SVR: -0.0003 deg, 95 % CI [-0.0011, 0.0005], Holm p 0.61,
        not distinguishable``."""
        f = f"{{:+.{digits}f}}"
        verdict = "distinguishable" if self.distinguishable else "not distinguishable"
        return (f"{self.method_a} vs {self.method_b}: {f.format(self.difference_deg)} deg, "
                f"95 % CI [{f.format(self.ci_low_deg)}, {f.format(self.ci_high_deg)}], "
                f"Holm p {_p(self.p_adjusted)}, {verdict}")

    def to_dict(self) -> dict:
        """JSON form (NaN as null)."""
        return {"method_a": self.method_a, "method_b": self.method_b,
                "difference_deg": json_number(self.difference_deg, 8),
                "ci_low_deg": json_number(self.ci_low_deg, 8),
                "ci_high_deg": json_number(self.ci_high_deg, 8),
                "p_value": json_number(self.p_value, 8),
                "p_adjusted": json_number(self.p_adjusted, 8),
                "distinguishable": self.distinguishable}


def _p(p: float) -> str:
    if not math.isfinite(p):
        return "-"
    return f"{p:.2g}" if p >= 1e-3 else "< 0.001"


def block_counts(n_blocks: int, n_boot: int, rng: np.random.Generator) -> np.ndarray:
    """How often each of ``n_blocks`` blocks is drawn in each of ``n_boot`` bootstrap
    replicates (each draws ``n_blocks`` blocks with replacement), shape (n_boot, n_blocks):
    a statistic summed per block is resampled by ``counts @ sums``."""
    return np.stack([np.bincount(rng.integers(0, n_blocks, n_blocks), minlength=n_blocks)
                     for _ in range(n_boot)]).astype(float)


def json_number(v: float | None, digits: int | None = None):
    """``v`` for JSON: None when missing or not finite, else a float (rounded to ``digits``
    decimals when given)."""
    if v is None or not math.isfinite(v):
        return None
    return float(v) if digits is None else round(float(v), digits)


def compare_rows(boot: ClusterBootstrap, names: Sequence[str],
                 pairs: Sequence[tuple[str, str]], alpha: float = 0.05) -> list[PairedComparison]:
    """Paired comparisons of row means, Holm-adjusted over ``pairs``.

    Parameters
    ----------
    boot : ClusterBootstrap
        The table's bootstrap (rows resampled with common draws).
    names : sequence of str
        Row names, in the order of ``boot``'s rows.
    pairs : sequence of (str, str)
        (a, b) pairs: each comparison is a minus b.  Duplicates (in either order) are
        dropped.
    alpha : float
        Family-wise error rate of the verdicts.

    Returns
    -------
    list of PairedComparison
    """
    index = {n: i for i, n in enumerate(names)}
    seen, todo = set(), []
    for a, b in pairs:
        if a == b or frozenset((a, b)) in seen:
            continue
        seen.add(frozenset((a, b)))
        todo.append((a, b, *boot.difference(index[a], index[b])))
    adj = holm([t[5] for t in todo])
    return [PairedComparison(a, b, d, lo, hi, p, float(pa), alpha)
            for (a, b, d, lo, hi, p), pa in zip(todo, adj)]


def positive_interval(value: float, half_width: float) -> tuple[float, float]:
    """The interval of a positive quantity (a time constant, a power, a capacity) made on its
    log: the half-width h of a symmetric interval around ``value`` is, to first order, the
    half-width h / value of log(value)'s (the delta method), so the interval is
    (value e^(-h/value), value e^(h/value)): it never holds a negative value and reads as a
    factor either way, as the quantity's own uncertainty does.  A ``value`` <= 0 (a
    positive quantity estimated unphysical) keeps the symmetric interval, so that what the
    runs said stays visible."""
    v, h = float(value), float(half_width)
    if not (v > 0.0 and math.isfinite(h)):
        return (v - h, v + h)
    f = math.exp(min(h / v, 700.0))
    return (v / f, v * f)
