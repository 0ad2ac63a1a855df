"""Which tuner reaches the best validation error for a given budget?  (the SVR rows of ``nfs table``)

The question a user of the tuned rows asks is not "is the sparrow search faster than a grid"
(every tuner pays the same fit per candidate, so time follows the budget) but "at a budget of
B evaluations, which tuner finds the lowest validation error, and can the seeds tell them
apart?".  This benchmark answers it on the problem the SVR rows of ``nfs table`` solve.

Problem: the training start-ups of the default scenario (its ``[compensation]`` settings:
training seed, features, features mode; 7 start temperatures x 2.5 h), the drift target
separated by the wavelet, decimated to one sample every ``--decimate-s`` seconds (default
180 s: 350 samples, one evaluation about 30 ms, the whole benchmark about 9 min on 2 cores;
``--decimate-s 30``, the table's own density, costs hours: a fit grows as n^2 to n^3).  Estimator, search box and validation score are those of the
SSA-SVR row (:func:`nfs.compensate.methods.get_method`): the SVR (C, sigma, epsilon) box,
the residual's standard deviation on the held-out start temperature (leave one start
temperature out).

Tuners: SSA, PSO, GWO, HHO (the papers' metaheuristics), random search (uniform in the box),
a factorial grid (k^3 <= budget points; deterministic), and Optuna's TPE (optional: the
'tune' extra; skipped when Optuna is missing).  ``--mealpy`` adds mealpy's OriginalSSA (the
'bench' extra) behind the same interface.

Printed:

1. the validation error reached against budget (default 10, 25, 50, 100, 200 evaluations; a
   separate tuner run per budget, since SSA, PSO and GWO schedule their generations on the
   budget): median and quartiles over ``--seeds`` tuner seeds (default 10);
2. at the largest budget, each tuner against the best median: the difference of medians
   with a bootstrap 95 % interval over seeds, "not distinguishable" when it holds 0;
3. each tuner's own overhead per evaluation (its time on a free objective, 3-D, at the
   largest budget) against the mean cost of one evaluation of the real objective (7 fold fits
   and scores), and the ratio (goal < 1 %).

Run: ``python benchmarks/bench_tuning.py [--seeds 10] [--budgets 10,25,50,100,200]
[--tuners ssa,pso,gwo,hho,random,grid,tpe] [--decimate-s 180] [--n-jobs 2] [--mealpy]
[--quick]``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from sklearn.base import clone

from nfs.compensate.dataset import drift_dataset
from nfs.compensate import get_method
from nfs.learners.tuners import TUNERS, TuneResult, minimize
from nfs.experiment import simulate_run
from nfs.config.scenario import load_scenario

DEFAULT_TUNERS = ("ssa", "pso", "gwo", "hho", "random", "grid", "tpe")
OVERHEAD_GOAL = 0.01


# -- the problem ------------------------------------------------------------------------------

def training_problem(decimate_s: float):
    """The training set of the SVR rows of ``nfs table`` on the default scenario.

    Returns (X, y, groups, description): features, separated drift [deg/h] and the
    validation groups (start temperatures) of the default scenario's training start-ups.
    """
    sc = load_scenario()
    comp = sc.compensation
    units, _ = sc.unit_split(comp.train_units, comp.test_units)
    train = sc.made_by(units, comp.train_repeats, seed=comp.train_seed)
    runs = [simulate_run(train.instrument, c).run for c in train.conditions()]
    ds = drift_dataset(runs, list(comp.features), decimate_s=decimate_s,
                       cutoff_period_s=comp.cutoff_period_s,
                       features_mode=comp.features_mode)
    spec = get_method("ssa-svr")
    if spec.max_samples is not None and ds.X.shape[0] > spec.max_samples:
        ds = ds.thinned(spec.max_samples)
    desc = (f"{len(runs)} training start-ups of the default scenario, {ds.X.shape[0]} samples "
            f"(one every {decimate_s:g} s), {ds.X.shape[1]} features "
            f"({comp.features_mode} mode), {len(np.unique(ds.validation_groups))} "
            "validation groups (start temperatures)")
    return ds.X, ds.y, ds.validation_groups, desc


def search_for(method: str, budget: int, seed: int, n_jobs: int | None):
    """The SSA-SVR row's search with another tuner (same estimator, box and score)."""
    search = get_method("ssa-svr").build(budget=budget, random_state=seed, n_jobs=n_jobs)
    options = {"kind": "factorial"} if method == "grid" else None
    return clone(search).set_params(method=method, budget=budget, random_state=seed,
                                    tuner_options=options)


# -- mealpy as a user-supplied tuner ----------------------------------------------------------

def mealpy_ssa(objective_batch, n_dims, *, budget, random_state=None, population=None,
               ST=0.8, PD=0.2, SD=0.2) -> TuneResult:
    """mealpy's OriginalSSA behind the tuners' interface (one evaluation per call).

    Epochs are chosen to reach the budget; evaluations past it are not made (mealpy gets
    +inf for them), so the budget is cut as our tuners cut their last generation.
    """
    from mealpy import SSA, FloatVar  # optional ('bench' extra): imported only when asked

    pop = population or max(6, min(30, budget // 10))
    epochs = max(1, math.ceil((budget - pop) / (2 * pop - int(SD * pop))))
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


# -- statistics -------------------------------------------------------------------------------

def quartiles(v) -> tuple[float, float, float]:
    q = np.percentile(np.asarray(v, dtype=float), [25, 50, 75])
    return float(q[1]), float(q[0]), float(q[2])


def median_difference_ci(a, b, *, n_boot: int = 4000, seed: int = 0):
    """Median(a) - median(b) and its percentile-bootstrap 95 % interval (seeds resampled
    independently in each group: the tuner seeds of two tuners are unrelated draws)."""
    rng = np.random.default_rng(seed)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    d = np.median(a) - np.median(b)
    ia = rng.integers(0, a.size, size=(n_boot, a.size))
    ib = rng.integers(0, b.size, size=(n_boot, b.size))
    boot = np.median(a[ia], axis=1) - np.median(b[ib], axis=1)
    lo, hi = np.percentile(boot, [2.5, 97.5])
    return float(d), float(lo), float(hi)


# -- parts ------------------------------------------------------------------------------------

def error_vs_budget(X, y, groups, tuners, budgets, seeds, n_jobs):
    """errors[tuner][budget] = list over seeds of the best validation error [deg/h];
    fit_s = mean seconds of one evaluation (every fold's fit and score)."""
    errors: dict[str, dict[int, list[float]]] = {t: {b: [] for b in budgets} for t in tuners}
    used: dict[str, dict[int, int]] = {t: {} for t in tuners}
    eval_s: list[float] = []
    for t in tuners:
        t_start = time.perf_counter()
        for b in budgets:
            for s in (seeds[:1] if t == "grid" else seeds):  # the factorial grid is fixed
                search = search_for(t, b, s, n_jobs).fit(X, y, groups=groups)
                errors[t][b].append(-float(search.best_score_))
                used[t][b] = int(search.n_evaluations_)
                eval_s.append(float(np.sum(search.cv_results_["mean_fit_time"]))
                              * search.n_splits_ / search.n_evaluations_)
        print(f"  {t}: {time.perf_counter() - t_start:.0f} s", flush=True)
    return errors, used, float(np.mean(eval_s))


def tuner_overhead(tuners, budget, repeats: int = 5) -> dict[str, float]:
    """Seconds per evaluation a tuner spends in its own code (free objective, 3-D box)."""
    def free(X):
        return np.sum((X - 0.3) ** 2, axis=1)
    out = {}
    for t in tuners:
        best = float("inf")
        for r in range(repeats):
            t0 = time.perf_counter()
            res = minimize(free, 3, method=t, budget=budget, random_state=r)
            best = min(best, (time.perf_counter() - t0) / res.n_evaluations)
        out[t] = best
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10, help="tuner seeds per (tuner, budget)")
    ap.add_argument("--budgets", default="10,25,50,100,200")
    ap.add_argument("--tuners", default=",".join(DEFAULT_TUNERS))
    ap.add_argument("--decimate-s", type=float, default=180.0,
                    help="one training sample every S seconds (nfs table: 30)")
    ap.add_argument("--n-jobs", type=int, default=-1, help="parallel fold fits (joblib)")
    ap.add_argument("--mealpy", action="store_true", help="add mealpy's OriginalSSA")
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: 3 seeds, budgets 10 and 25, one sample every 180 s")
    args = ap.parse_args(argv)
    budgets = [int(b) for b in args.budgets.split(",")]
    seeds = list(range(args.seeds))
    decimate = args.decimate_s
    if args.quick:
        budgets, seeds, decimate = [10, 25], [0, 1, 2], 180.0
    tuners = [t.strip() for t in args.tuners.split(",") if t.strip()]
    if "tpe" in tuners:
        try:
            import optuna  # noqa: F401  (optional: the 'tune' extra)
        except ImportError:
            print("tpe skipped: Optuna is not installed (pip install -e '.[tune]')")
            tuners.remove("tpe")
    if args.mealpy:
        TUNERS["mealpy-ssa"] = mealpy_ssa
        tuners.append("mealpy-ssa")

    t_all = time.perf_counter()
    X, y, groups, desc = training_problem(decimate)
    print(f"problem: {desc}")
    print(f"tuners: {', '.join(tuners)}; budgets {budgets}; {len(seeds)} tuner seeds each "
          f"(grid: factorial, one run)", flush=True)
    errors, used, eval_s = error_vs_budget(X, y, groups, tuners, budgets, seeds, args.n_jobs)

    print("\n(1) validation error reached [deg/h]: median [25 %, 75 %] over seeds")
    head = f"{'budget':>7s} " + " ".join(f"{t:>26s}" for t in tuners)
    print(head)
    for b in budgets:
        cells = []
        for t in tuners:
            med, q1, q3 = quartiles(errors[t][b])
            tag = f"{med:.5f} [{q1:.5f}, {q3:.5f}]"
            if used[t][b] != b:
                tag = f"({used[t][b]}) " + tag
            cells.append(f"{tag:>26s}")
        print(f"{b:7d} " + " ".join(cells))
    print("(n) before a grid cell: the factorial grid's evaluations (k^3 <= budget)")

    b = budgets[-1]
    best = min(tuners, key=lambda t: np.median(errors[t][b]))
    print(f"\n(2) at budget {b}, each tuner against the best median ({best}): "
          "difference of medians, bootstrap 95 % interval over seeds")
    for t in tuners:
        if t == best:
            continue
        if t == "grid":
            d = float(np.median(errors[t][b]) - np.median(errors[best][b]))
            print(f"  {t:12s} {d:+.5f} deg/h (deterministic: no interval)")
            continue
        d, lo, hi = median_difference_ci(errors[t][b], errors[best][b])
        verdict = "not distinguishable" if lo <= 0.0 <= hi else "worse"
        print(f"  {t:12s} {d:+.5f} deg/h, 95 % CI [{lo:+.5f}, {hi:+.5f}]: {verdict}")

    over = tuner_overhead(tuners, b)
    print(f"\n(3) tuner overhead per evaluation (free 3-D objective, budget {b}) against one "
          f"evaluation of the real objective ({eval_s * 1e3:.1f} ms: every fold's fit and "
          "score, CPU time)")
    for t in tuners:
        ratio = over[t] / eval_s
        print(f"  {t:12s} {over[t] * 1e3:8.3f} ms / {eval_s * 1e3:.1f} ms = {100 * ratio:6.3f} % "
              f"({'under' if ratio < OVERHEAD_GOAL else 'OVER'} the {100 * OVERHEAD_GOAL:g} % "
              "goal)")
    print(f"\nbenchmark wall time {time.perf_counter() - t_all:.0f} s")


if __name__ == "__main__":
    main()
