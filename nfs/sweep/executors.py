"""Where the cells run: local joblib workers, or a Dask cluster (optional ``dask`` extra).

Each executor maps the cell function over a lazy stream of tasks and yields results as they
finish, in any order, holding only a bounded number of tasks in flight (memory does not grow
with the number of cells).  The results do not depend on the executor: a cell is computed
from its inputs alone and the table is assembled in cell order afterwards.

- :class:`LocalExecutor`: joblib (loky processes), ``jobs`` workers (-1: every core; 1: in
  this process).
- :class:`DaskExecutor`: a ``dask.distributed`` client, either on a ``LocalCluster`` it
  starts (``workers``) or on an existing scheduler (``address``).
"""

from __future__ import annotations

import sys
import time
from typing import Any, Callable, Iterable, Iterator

import joblib
from joblib import Parallel, delayed
from tqdm import tqdm

from ..errors import NfsError
from ..workers import close_unread

__all__ = ["LocalExecutor", "DaskExecutor", "SweepProgress"]


class LocalExecutor:
    """Local processes through joblib."""

    def __init__(self, jobs: int = -1) -> None:
        if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs == 0 or jobs < -1:
            raise NfsError(f"--jobs must be a positive number of workers or -1 (every core), "
                           f"got {jobs!r}")
        self.jobs = jobs

    def describe(self) -> str:
        """One line for the log."""
        n = joblib.cpu_count() if self.jobs == -1 else self.jobs
        return f"local, {n} worker(s)"

    def map_unordered(self, fn: Callable, tasks: Iterable) -> Iterator[Any]:
        """fn(task) for every task, yielded as they finish."""
        with Parallel(n_jobs=self.jobs, return_as="generator_unordered",
                      pre_dispatch="2*n_jobs") as parallel:
            results = parallel(delayed(fn)(t) for t in tasks)
            try:
                # not ``yield from``: closing it would close ``results`` before the finally
                for result in results:
                    yield result
            finally:               # a stopped sweep: its batches in flight are cancelled
                close_unread(results)

    def close(self) -> None:
        """Nothing to release."""


class DaskExecutor:
    """A Dask cluster: a new ``LocalCluster`` of ``workers`` processes, or ``address``."""

    def __init__(self, *, workers: int | None = None, address: str | None = None) -> None:
        if (workers is None) == (address is None):
            raise NfsError("give either --dask-local N or --scheduler ADDRESS")
        try:  # the optional 'dask' extra: imported only when asked for
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise NfsError("Dask is not installed: pip install 'dask[distributed]' (the "
                           "package's 'dask' extra)") from None
        self.cluster = None
        if workers is not None:
            if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
                raise NfsError(f"--dask-local must be a positive number of workers, got "
                               f"{workers!r}")
            self.cluster = LocalCluster(n_workers=workers, threads_per_worker=1,
                                        processes=True, dashboard_address=None)
            self.client = Client(self.cluster)
        else:
            try:
                self.client = Client(address, timeout="10s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise NfsError(f"--scheduler {address}: cannot connect to a Dask scheduler "
                               f"({exc})") from None
        self.where = f"Dask LocalCluster, {workers} worker(s)" if workers else \
            f"Dask scheduler {address}"

    def describe(self) -> str:
        """One line for the log."""
        return self.where

    def _slots(self) -> int:
        info = self.client.scheduler_info()
        threads = sum(w.get("nthreads", 1) for w in info.get("workers", {}).values())
        return max(2, 2 * threads)

    def map_unordered(self, fn: Callable, tasks: Iterable) -> Iterator[Any]:
        """fn(task) for every task, yielded as they finish (twice the cluster's threads in
        flight)."""
        from dask.distributed import as_completed
        it = iter(tasks)
        window = self._slots()
        first = [self.client.submit(fn, t, pure=False) for _, t in zip(range(window), it)]
        if not first:
            return
        pending = as_completed(first)
        try:
            for fut in pending:
                result = fut.result()
                fut.release()
                nxt = next(it, None)
                if nxt is not None:
                    pending.add(self.client.submit(fn, nxt, pure=False))
                yield result
        finally:
            pending.clear()

    def close(self) -> None:
        """Close the client (and the cluster it started)."""
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


class SweepProgress:
    """Progress of the cells: a tqdm bar with ETA on a terminal, else a sparse log line
    (every tenth of the cells or every ``every_s`` seconds, whichever comes later)."""

    def __init__(self, total: int, *, quiet: bool = False, stream=None,
                 every_s: float = 30.0) -> None:
        self.total, self.done, self.quiet = total, 0, quiet
        self.stream = sys.stderr if stream is None else stream
        self.every_s = every_s
        self.t0 = self.last = time.perf_counter()
        self.step = max(1, total // 10)
        self.bar = None
        if not quiet and total and getattr(self.stream, "isatty", lambda: False)():
            self.bar = tqdm(total=total, unit="cell", file=self.stream, desc="sweep",
                            dynamic_ncols=True)

    def update(self) -> None:
        """One more cell done."""
        self.done += 1
        if self.quiet:
            return
        if self.bar is not None:
            self.bar.update(1)
            return
        now = time.perf_counter()
        if self.done == self.total or (self.done % self.step == 0
                                       and now - self.last >= self.every_s):
            self.last = now
            rate = self.done / max(now - self.t0, 1e-9)
            eta = (self.total - self.done) / rate if rate > 0 else float("inf")
            self.stream.write(f"sweep: {self.done}/{self.total} cells, {rate:.3g} cells/s, "
                              f"ETA {eta:.0f} s\n")
            self.stream.flush()

    def close(self) -> None:
        """Close the bar."""
        if self.bar is not None:
            self.bar.close()
