"""The pool a study's trainings run in (nfs.studies.startup_study.training_pool).

Invariants: with several workers the trainings run in other processes, each on one BLAS
thread (the study's table does not depend on the number of workers:
tests/compensate/test_study_seeds.py); with one, in this process; a study stopped by an
error leaves no joblib warning about the jobs it cancelled.
"""

import os
import subprocess
import sys

import pytest
from joblib import delayed
from threadpoolctl import threadpool_info

from nfs.studies.startup_study import training_pool


def _blas_threads(info):
    return {d["num_threads"] for d in info if d.get("user_api") == "blas"}


def test_several_workers_are_other_processes_on_one_blas_thread():
    with training_pool(2) as pool:
        list(pool.start())
        out = list(pool(delayed(lambda: (os.getpid(), threadpool_info()))()
                        for _ in range(4)))
    pids = {pid for pid, _ in out}
    assert os.getpid() not in pids
    for _, info in out:
        assert _blas_threads(info) == {1}


@pytest.mark.parametrize("n_jobs, trainings", [(1, None), (-1, 1)])
def test_one_worker_is_this_process(n_jobs, trainings):
    # one worker asked for, or one training on every core: no worker process is started
    with training_pool(n_jobs, trainings) as pool:
        list(pool.start())
        out = list(pool(delayed(os.getpid)() for _ in range(2)))
    assert set(out) == {os.getpid()}


_STOPPED = """
from nfs.studies.startup_study import training_pool
try:
    with training_pool(2) as pool:
        pool.start()                   # left unread, as an error in a study leaves it
        raise ValueError("stopped")
except ValueError:
    print("stopped")
"""


def test_an_error_in_the_study_cancels_the_jobs_quietly():
    # joblib warns about cancelled jobs when their unread results are collected, which can
    # be at the interpreter's exit: the whole process's stderr is read
    done = subprocess.run([sys.executable, "-c", _STOPPED], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "stopped"
    assert "cancelled" not in done.stderr, done.stderr
