"""Speed of north finding: 7 start-up runs (one per start temperature of the FOG start-up paper).

Each run: 9000 s at 1 Hz, 4 positions, dwell 150 s, move 10 s (14 complete cycles), the
section 5 rate model with tilt, bias, a linear drift and white noise (synthetic_run). Times
north_find + heading_rmse over all 7 runs in one process, best of several repeats (runs built
once, outside the timing). Target: < 0.1 s.

Run: ``python benchmarks/bench_northfind.py``.
"""

from __future__ import annotations

import time

from nfs.northfind import heading_rmse, north_find, synthetic_run

TARGET_S = 0.1
START_TEMPERATURES_C = (-32, -16, -5, 17, 28, 43, 54)


def build_runs():
    """The 7 synthetic runs."""
    return [synthetic_run(heading_deg=212.7, latitude_deg=30.26, duration_s=9000.0,
                          dwell_s=150.0, move_s=10.0, tilt_north_deg=0.02, tilt_east_deg=-0.01,
                          bias_dph=0.5, drift_dph=lambda t: 1e-6 * t,
                          arw_deg_per_rth_h=0.0005, name=f"synthetic_{t0:+d}C",
                          random_state=i)
            for i, t0 in enumerate(START_TEMPERATURES_C)]


def north_find_all(runs):
    """north_find + heading_rmse of every run."""
    return [heading_rmse(north_find(run)) for run in runs]


def main(repeats: int = 7) -> float:
    runs = build_runs()
    north_find_all(runs)  # warm up
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        stages = north_find_all(runs)
        best = min(best, time.perf_counter() - t0)
    n_cycles = sum(north_find(r).n_cycles for r in runs)
    print(f"north-find 7 runs ({runs[0].n_samples} samples, {n_cycles} cycles in all): "
          f"{best:.4f} s (target < {TARGET_S} s), ratio {TARGET_S / best:.1f}x under target")
    print("start-up / stable heading RMSE [deg]: " + ", ".join(
        f"{s.startup_deg:.4f}/{s.stable_deg:.4f}" for s in stages))
    return best


if __name__ == "__main__":
    main()
