"""Cost of tuning an SVR's (C, sigma, epsilon) by sparrow search (seed 004's SSA-SVR).

Problem: 7 start-up runs (one per start temperature of seed 004), features = the 9 seed-004
thermometer features (3 temperatures, 3 rates, 3 gradients), target = the wavelet-separated
gyro drift, validation = leave one run out (7 folds).  By default the runs come from the
simulator (``--data simulated``: nfs.experiment on the default scenario, then
nfs.compensate.dataset.drift_dataset -- the hook that turns simulated runs into a grouped
regression problem); ``--data synthetic`` uses a stand-alone smooth nonlinear function of
synthetic thermometer features plus time-correlated noise (used as well when the simulator
chain cannot be imported).

Sampling: the brief's representative size is 7 runs x ~900 samples at 0.1 Hz
(``--decimate-s 10``).  An RBF SVR fit at large C and small epsilon costs 20-170 s at that
size (LIBSVM, O(n^2)-O(n^3)), so one SSA run at budget 60 takes tens of minutes on 2 cores
and the grid side hours; the default keeps one sample every 30 s (7 x ~280 samples), which
keeps the whole benchmark near half an hour on 2 cores.  ``--quick`` (60 s) is a smoke run.

Parts:

1. SSA (``MetaheuristicSearchCV(method="ssa")``, default budget 60) against scikit-learn's
   ``GridSearchCV`` on the same LeaveOneGroupOut folds and the same ranges (log-spaced
   grids of k points per axis, k = 3, 4, 5, ...): the grid grows until its best CV error
   reaches SSA's; a grid whose predicted time exceeds 10x SSA's is not started, and the error
   of the largest grid run is reported instead.  Target: SSA 10x faster.
2. Our SSA against mealpy's ``OriginalSSA`` (optional, the 'bench' extra) at the same budget
   on the same objective: mealpy is plugged into the tuner registry (``TUNERS``) as a user's
   function, so both run through the same MetaheuristicSearchCV objective (mean
   leave-one-run-out error).  Evaluations past the budget are not made (mealpy's last epoch
   is cut like ours).

Run: ``python benchmarks/bench_tuning.py [--quick] [--decimate-s S] [--budget B]
[--n-jobs N] [--data simulated|synthetic]``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.model_selection import GridSearchCV, LeaveOneGroupOut
from sklearn.svm import SVR

from nfs.compensate.search import MetaheuristicSearchCV, Real
from nfs.compensate.tuners import TUNERS, TuneResult

START_TEMPERATURES_C = (-32, -16, -5, 17, 28, 43, 54)  # seed 004 Table 3
# Search ranges and validation score: those of the SSA-SVR row of `nfs table`
# (nfs.compensate.methods: the bounded box, and the residual's STD within the held-out run).
from nfs.compensate.methods import svr_space, get_method, neg_residual_std  # noqa: E402

RANGES = {name: (r.low, r.high) for name, r in svr_space().items()}
SCORING = neg_residual_std
TIME_FACTOR = 10.0  # grid allowed 10x SSA's time


# -- estimator --------------------------------------------------------------------------

try:
    from nfs.compensate.kernels import SVRRegressor
except ImportError:  # stand-in until nfs.compensate.kernels exists
    from sklearn.preprocessing import StandardScaler

    class SVRRegressor(RegressorMixin, BaseEstimator):
        """SVR in the sigma convention (gamma = 1 / (2 sigma^2)) on standardised x and y."""

        def __init__(self, C=1.0, sigma=1.0, epsilon=0.01):
            self.C, self.sigma, self.epsilon = C, sigma, epsilon

        def fit(self, X, y):
            self.sx_ = StandardScaler().fit(X)
            self.my_, self.sy_ = float(np.mean(y)), float(np.std(y)) or 1.0
            self.svr_ = SVR(C=self.C, gamma=1.0 / (2.0 * self.sigma ** 2),
                            epsilon=self.epsilon).fit(self.sx_.transform(X),
                                                      (y - self.my_) / self.sy_)
            return self

        def predict(self, X):
            return self.my_ + self.sy_ * self.svr_.predict(self.sx_.transform(X))


# -- data -------------------------------------------------------------------------------

def simulated_problem(decimate_s: float):
    """HOOK: simulated runs -> grouped regression problem (X, y, groups, description)."""
    from nfs.compensate.dataset import drift_dataset
    from nfs.experiment import simulate_run
    from nfs.io.scenario import load_scenario

    import dataclasses
    sc = load_scenario()
    # the training start-ups of `nfs table` (train_seed), capped as the SSA-SVR row is
    sc = dataclasses.replace(sc, seed=sc.compensation.train_seed, repeats=1)
    runs = [simulate_run(sc.instrument, c).run for c in sc.conditions()]
    ds = drift_dataset(runs, "seed004", decimate_s=decimate_s)
    cap = get_method("ssa-svr").max_samples
    if cap is not None and ds.X.shape[0] > cap:
        ds = ds.thinned(cap)
    return ds.X, ds.y, ds.groups, (f"the training start-ups of nfs table, {len(runs)} runs, "
                                   f"features {', '.join(ds.feature_names)}")


def synthetic_problem(decimate_s: float, seed: int = 0):
    """7 start-up runs of 9000 s: thermometer-like features and a smooth drift plus AR(1) noise.

    Temperatures approach T0 + 18 K (self-heating) with time constants 900, 1400, 2000 s;
    rates in K/min; gradients are differences.  y [deg/h] = a smooth nonlinear function of
    the features + AR(1) noise (correlation time 300 s, 0.002 deg/h).
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 9000.0, decimate_s)
    X, y, g = [], [], []
    for k, t0 in enumerate(START_TEMPERATURES_C):
        temps = np.stack([t0 + 18.0 * (1 - np.exp(-t / tau)) + 0.3 * k
                          for tau in (900.0, 1400.0, 2000.0)], axis=1)
        rates = np.gradient(temps, t, axis=0) * 60.0
        grads = np.stack([temps[:, 0] - temps[:, 1], temps[:, 0] - temps[:, 2],
                          temps[:, 1] - temps[:, 2]], axis=1)
        feats = np.hstack([temps, rates, grads])
        drift = (0.02 * np.tanh(rates[:, 0] / 0.5) + 0.004 * grads[:, 0]
                 + 1e-5 * (temps[:, 0] - 25.0) ** 2 + 0.01 * rates[:, 1] * grads[:, 2] / 5.0)
        phi = math.exp(-decimate_s / 300.0)
        e = np.zeros(t.size)
        w = rng.standard_normal(t.size) * 0.002 * math.sqrt(1 - phi ** 2)
        for i in range(1, t.size):
            e[i] = phi * e[i - 1] + w[i]
        X.append(feats)
        y.append(drift + e)
        g.append(np.full(t.size, k))
    return (np.vstack(X), np.concatenate(y), np.concatenate(g),
            "synthetic thermometer features, smooth drift + AR(1) noise")


# -- mealpy as a user-supplied tuner ------------------------------------------------------

def mealpy_ssa(objective_batch, n_dims, *, budget, random_state=None, population=None,
               ST=0.8, PD=0.2, SD=0.2) -> TuneResult:
    """mealpy's OriginalSSA behind the tuners' interface (one evaluation per call).

    Epochs are chosen to reach the budget; evaluations past it are not made (mealpy gets
    +inf for them), so the budget is cut like our tuners cut their last generation.
    """
    from mealpy import SSA, FloatVar

    pop = population or max(6, min(30, budget // 10))
    n2 = int(SD * pop)
    epochs = max(1, math.ceil((budget - pop) / (2 * pop - n2)))
    xs, fs = [], []

    def obj(u):
        if len(fs) >= budget:
            return float("inf")
        u = np.clip(np.asarray(u, dtype=float), -1.0, 1.0)
        f = float(objective_batch(u[None, :])[0])
        xs.append(u)
        fs.append(f)
        return f

    seed = None if random_state is None else int(np.random.default_rng(random_state)
                                                 .integers(0, 2**31 - 1))
    model = SSA.OriginalSSA(epoch=epochs, pop_size=pop, ST=ST, PD=PD, SD=SD)
    model.solve({"obj_func": obj, "bounds": FloatVar(lb=[-1.0] * n_dims, ub=[1.0] * n_dims),
                 "minmax": "min", "log_to": None}, seed=seed)
    all_x, all_f = np.array(xs), np.array(fs)
    i = int(np.argmin(all_f))
    return TuneResult(x_best=all_x[i], f_best=float(all_f[i]), n_evaluations=len(fs),
                      history=np.minimum.accumulate(all_f), all_x=all_x, all_f=all_f,
                      method="mealpy-ssa")


# -- parts ---------------------------------------------------------------------------------

def space():
    return {name: Real(lo, hi, log=True) for name, (lo, hi) in RANGES.items()}


def run_search(method, X, y, groups, budget, n_jobs, seed, verbose=1):
    t0 = time.perf_counter()
    s = MetaheuristicSearchCV(SVRRegressor(), space(), method=method, budget=budget,
                              n_jobs=n_jobs, random_state=seed, verbose=verbose,
                              scoring=SCORING)
    s.fit(X, y, groups=groups)
    return s, time.perf_counter() - t0


def run_grid(k, X, y, groups, n_jobs):
    grid = {name: np.logspace(math.log10(lo), math.log10(hi), k)
            for name, (lo, hi) in RANGES.items()}
    t0 = time.perf_counter()
    gs = GridSearchCV(SVRRegressor(), grid, cv=LeaveOneGroupOut(),
                      scoring=SCORING, n_jobs=n_jobs, refit=True)
    gs.fit(X, y, groups=groups)
    return gs, time.perf_counter() - t0


def fit_seconds(cv_results, n_splits):
    """Fit time summed over candidates and folds [CPU-s]."""
    return float(np.sum(cv_results["mean_fit_time"]) * n_splits)


def fmt_params(p):
    return ", ".join(f"{k}={v:.4g}" for k, v in p.items())


def part1(X, y, groups, budget, n_jobs, seed):
    print(f"\n(1) SSA vs GridSearchCV, SVR (C, sigma, epsilon), leave one run out "
          f"({len(np.unique(groups))} folds)", flush=True)
    ssa, t_ssa = run_search("ssa", X, y, groups, budget, n_jobs, seed)
    rmse_ssa = -ssa.best_score_
    fit_ssa = fit_seconds(ssa.cv_results_, ssa.n_splits_)
    print(f"SSA   budget {budget}: {ssa.n_evaluations_} candidates, best CV error "
          f"{rmse_ssa:.6g} [{fmt_params(ssa.best_params_)}], {t_ssa:.1f} s "
          f"(fits {fit_ssa:.0f} CPU-s, {fit_ssa / ssa.n_evaluations_:.2f} per candidate)",
          flush=True)
    cap = TIME_FACTOR * t_ssa
    reached, last, per_cand = None, None, None
    for k in range(3, 12):
        n_cand = k ** 3
        if per_cand is not None and per_cand * n_cand > cap:
            print(f"grid  k={k} ({n_cand} candidates) not started: predicted "
                  f"{per_cand * n_cand:.0f} s > {TIME_FACTOR:g}x SSA = {cap:.0f} s", flush=True)
            break
        print(f"grid  k={k}: {n_cand} candidates x 7 folds ...", flush=True)
        gs, t_gs = run_grid(k, X, y, groups, n_jobs)
        per_cand = t_gs / n_cand
        rmse = -gs.best_score_
        last = (k, n_cand, rmse, t_gs, gs.best_params_)
        fit_gs = fit_seconds(gs.cv_results_, gs.n_splits_)
        print(f"grid  k={k}: best CV error {rmse:.6g} [{fmt_params(gs.best_params_)}], "
              f"{t_gs:.1f} s (fits {fit_gs:.0f} CPU-s, {fit_gs / n_cand:.2f} per candidate)",
              flush=True)
        if rmse <= rmse_ssa:
            reached = last
            break
        if t_gs > cap:
            break
    print("-- part 1 summary")
    print(f"SSA  : CV error {rmse_ssa:.6g} in {t_ssa:.1f} s ({ssa.n_evaluations_} candidates)")
    if reached:
        k, n_cand, rmse, t_gs, _ = reached
        print(f"grid : reaches it at k={k} ({n_cand} candidates): CV error {rmse:.6g} in "
              f"{t_gs:.1f} s")
        print(f"ratio: grid time / SSA time = {t_gs / t_ssa:.1f}x (target >= 10x); "
              f"candidates {n_cand / ssa.n_evaluations_:.1f}x")
    elif last:
        k, n_cand, rmse, t_gs, _ = last
        print(f"grid : does not reach it within {TIME_FACTOR:g}x SSA's time; largest grid run "
              f"k={k} ({n_cand} candidates): CV error {rmse:.6g} in {t_gs:.1f} s "
              f"({t_gs / t_ssa:.1f}x SSA's time), error ratio grid/SSA "
              f"{rmse / rmse_ssa:.3f}")
    return ssa, t_ssa


def part2(X, y, groups, budget, n_jobs, seed, ssa, t_ssa):
    print(f"\n(2) our SSA vs mealpy OriginalSSA, same objective, budget {budget}", flush=True)
    try:
        import mealpy
    except ImportError:
        print("mealpy is not installed (pip install 'nfs-startup[bench]'): part 2 skipped")
        return
    TUNERS["mealpy-ssa"] = mealpy_ssa  # a user's tuner plugs into the registry
    try:
        mp, t_mp = run_search("mealpy-ssa", X, y, groups, budget, n_jobs, seed, verbose=0)
    finally:
        del TUNERS["mealpy-ssa"]
    r_ours, r_mp = -ssa.best_score_, -mp.best_score_
    print(f"ours   SSA: CV error {r_ours:.6g} [{fmt_params(ssa.best_params_)}], "
          f"{ssa.n_evaluations_} evaluations, {t_ssa:.1f} s")
    print(f"mealpy SSA {mealpy.__version__}: CV error {r_mp:.6g} [{fmt_params(mp.best_params_)}], "
          f"{mp.n_evaluations_} evaluations, {t_mp:.1f} s")
    print(f"ratio: mealpy/ours CV error {r_mp / r_ours:.3f}, time {t_mp / t_ssa:.2f}x")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", choices=("simulated", "synthetic"), default="simulated")
    ap.add_argument("--decimate-s", type=float, default=None,
                    help="seconds between samples (10 = the 0.1 Hz of the brief; default 30)")
    ap.add_argument("--budget", type=int, default=30, help="the nfs table default")
    ap.add_argument("--n-jobs", type=int, default=-1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true", help="smoke run: 60 s sampling")
    args = ap.parse_args(argv)
    decimate_s = args.decimate_s or (60.0 if args.quick else 30.0)

    t0 = time.perf_counter()
    if args.data == "simulated":
        try:
            X, y, groups, desc = simulated_problem(decimate_s)
        except Exception as exc:  # the simulator chain is work in progress elsewhere
            print(f"simulated runs unavailable ({type(exc).__name__}: {exc}); "
                  f"using the synthetic problem")
            X, y, groups, desc = synthetic_problem(decimate_s, args.seed)
    else:
        X, y, groups, desc = synthetic_problem(decimate_s, args.seed)
    counts = np.bincount(groups)
    print(f"problem: {desc}")
    print(f"{len(counts)} groups x {counts.min()}-{counts.max()} samples (one every "
          f"{decimate_s:g} s), {X.shape[1]} features, std(y) {np.std(y):.4g}; "
          f"built in {time.perf_counter() - t0:.1f} s; n_jobs={args.n_jobs}")
    print("ranges: " + ", ".join(f"{k} [{lo:g}, {hi:g}] (log)" for k, (lo, hi) in
                                  RANGES.items()))
    ssa, t_ssa = part1(X, y, groups, args.budget, args.n_jobs, args.seed)
    part2(X, y, groups, args.budget, args.n_jobs, args.seed, ssa, t_ssa)


if __name__ == "__main__":
    main()
