"""The drift's structural alternative: each drift candidate is also tested beyond a rate
term on every node; one that does not stand beyond it is tied with it.

Synthetic runs with a known answer (no simulator): 7 runs of 10 s window means over 2.5 h;
two "node rates" per run, a fast and a slow exponential whose amplitudes differ from run to
run (as the heating after power-on differs with the start temperature); the candidate is a
turn-on transient exp(-t / 300 s) with the same amplitude in every run.

- Structural misfit: the drift is a misweighted sum of the rates.  Against the model alone
  (a constant) the transient is hugely significant; beyond the alternative it explains
  nothing: its p-value is not small.
- A genuine transient on top of the rates: significant beyond the alternative.
- Calibration: with no transient and the rates in the alternative, the p-value of the
  transient is uniform: over 200 seeded data sets its rejection rate at 5 % stays within
  the binomial band.
"""

from __future__ import annotations

import numpy as np

from nfs.diagnose.drift_structure import DriftStructure, beyond_alternative
from nfs.scoring.run_stats import clustered_fit, run_grams

T = np.arange(0.0, 9000.0, 10.0)
GROUPS = np.arange(7)


def _runs(rng, weights, transient, noise=0.004):
    ys, Xs, Rs, Cs = [], [], [], []
    for r in range(7):
        fast = (1.0 + 0.25 * r) * np.exp(-T / 400.0)
        slow = (1.0 - 0.12 * r) * np.exp(-T / 2500.0)
        R = np.column_stack([fast, slow])
        C = np.exp(-T / 300.0)[:, None]
        y = R @ weights + transient * C[:, 0] + noise * rng.standard_normal(T.size)
        ys.append(y)
        Xs.append(np.ones((T.size, 1)))
        Rs.append(R)
        Cs.append(C)
    return ys, Xs, Rs, Cs


def _tests(ys, Xs, Rs, Cs):
    plain = clustered_fit(run_grams(ys, [np.hstack([X, C]) for X, C in zip(Xs, Cs)]))
    p_plain = plain.test([1])[1]
    alt = [np.hstack([X, R]) for X, R in zip(Xs, Rs)]
    p_beyond, cv = beyond_alternative(run_grams(ys, alt), ys, alt, [({}, Cs)], GROUPS)
    return p_plain, p_beyond, cv


def test_misweighted_rates_are_not_a_transient():
    ys, Xs, Rs, Cs = _runs(np.random.default_rng(1), np.array([0.02, -0.01]), 0.0)
    p_plain, p_beyond, _ = _tests(ys, Xs, Rs, Cs)
    assert p_plain < 0.01
    assert p_beyond > 0.05


def test_a_genuine_transient_stands_beyond_the_rates():
    ys, Xs, Rs, Cs = _runs(np.random.default_rng(2), np.array([0.02, -0.01]), 0.02)
    p_plain, p_beyond, _ = _tests(ys, Xs, Rs, Cs)
    assert p_plain < 0.01 and p_beyond < 0.01


def test_beyond_test_is_calibrated():
    rng = np.random.default_rng(3)
    p = np.array([_tests(*_runs(rng, np.array([0.02, -0.01]), 0.0))[1] for _ in range(200)])
    rate = float(np.mean(p < 0.05))
    # binomial(200, 0.05): mean 10, sd 3.1; 3.5 sd either side
    assert 0.0 <= rate <= 0.05 + 3.5 * np.sqrt(0.05 * 0.95 / 200), rate


def test_structure_message():
    ok = DriftStructure(nodes=("a", "b"), cv_rms_model=0.010, cv_rms_alternative=0.009)
    assert ok.adequate and "holds" in ok.message and abs(ok.cv_drop - 0.1) < 1e-12
    bad = DriftStructure(nodes=("a", "b"), cv_rms_model=0.010, cv_rms_alternative=0.008,
                         tied=("turn_on_transient",), best_rate="shupe_rate:a")
    assert not bad.adequate
    assert "turn_on_transient" in bad.message and "shupe_rate:a" in bad.message
    assert bad.tie_message(["x"]).startswith("x tied with a rate term")
    # a tied power-on transient also points at heat inside the coil; other ties do not
    assert "heat_source at the coil" in bad.message
    assert "heat_source" not in bad.tie_message(["shupe_rate:b"])
    assert bad.to_dict()["cv_drop"] == bad.cv_drop
