"""Timing shared by the benchmark scripts (run as ``python benchmarks/NAME.py``, so this
folder is on ``sys.path``)."""

from __future__ import annotations

import time


def best_of(f, n: int = 3) -> float:
    """The shortest wall time of ``n`` calls of ``f()`` [s]."""
    best = float("inf")
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best
