"""A fit's answer does not depend on the machine's core count.

Oracle: work under ``one_blas_thread`` sees one BLAS thread whatever the caller allowed (the
pin itself, which the fit and the diagnosis carry); and the same fit (two 30-min start-ups of
the default instrument, both stages) run under one and under two BLAS threads gives
bit-identical parameters (on this small problem it may do so without the pin too: the first
check is the one that fails when the pin goes).  Without the fit's own pin to
one BLAS thread, the rounding of a multi-threaded BLAS moved the thermal stage to another
minimum on a unit of the independent family as it was drawn then (seed 12, heat source: cost 8981 on one thread,
9483 on two, and another answer of the diagnosis).
"""

from __future__ import annotations

import dataclasses

from threadpoolctl import threadpool_info, threadpool_limits

import nfs
from nfs.fit import fit_model
from nfs.fit.calibration import one_blas_thread


def _blas_threads() -> int:
    return min(m["num_threads"] for m in threadpool_info() if m["user_api"] == "blas")


def test_the_pin_holds_whatever_the_caller_allows():
    with threadpool_limits(limits=2, user_api="blas"):
        assert one_blas_thread(_blas_threads)() == 1
    # the fit carries it (a worker started with one BLAS thread cannot tell the first check
    # from no pin; this one it can)
    assert getattr(fit_model, "__wrapped__", None) is not None


def test_the_fit_is_the_same_on_one_and_two_blas_threads():
    inst = nfs.load_instrument("default")
    sc = nfs.load_scenario().nominal()
    runs = [nfs.simulate_run(inst, dataclasses.replace(sc.conditions()[i], duration_s=1800.0,
                                                       seed=(3, i))).run for i in (1, 5)]
    fits = {}
    for n in (1, 2):
        with threadpool_limits(limits=n, user_api="blas"):
            fits[n] = fit_model(inst, runs, start_state=None)
    assert fits[1].params == fits[2].params
    assert fits[1].cost == fits[2].cost
