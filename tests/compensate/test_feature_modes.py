"""Feature modes: what a feature at t may use (cycle, causal, offline) and the rate filters.

Oracles: invariants of causality (a feature at t cannot change when readings after its
horizon change: after t in causal mode, after the end of t's north-finding cycle in cycle
mode), the closed form of a linear ramp (its rate is its slope, exactly), the north
finder's own cycles, and SciPy's ``savgol_filter`` for the rule that picks the windows.
"""

import dataclasses

import joblib
import numpy as np
import pytest
from sklearn.linear_model import LinearRegression

from nfs.compensate import DriftCompensator, compute_features, load_compensator
from nfs.compensate.features import RATE_WINDOW, THERMOMETER_COLUMNS
from nfs.compensate.kalman_rate import (
    CAUSAL_RATE,
    kalman_rate_filter,
    kalman_rate_k_per_min,
)
from nfs.compensate.modes import (
    FEATURE_MODES,
    FeatureModeError,
    check_features_mode,
    cycle_spans,
    horizon_index,
    in_cycle_mask,
)
from nfs.compensate.rates import savgol_rate_k_per_min, windowed_rate_k_per_min
from nfs.errors import NfsError
from nfs.learners import CubicLeastSquares
from nfs.northfind import north_find, synthetic_run

FEATURES = ["T_fog", "dT_fog", "dT_acc_x", "dT_acc_y", "TdT_fog", "G_fog_acc_x"]


def warming_run(duration_s=3000.0, seed=7):
    """A 4-position run (dwell 150 s, move 10 s; a partial cycle at the end) whose three
    thermometers warm up like a powered-on unit, read with noise and a 0.0625 K quantum."""
    run = synthetic_run(heading_deg=40.0, duration_s=duration_s, name="warm")
    t = run.columns["time_s"]
    rng = np.random.default_rng(seed)
    cols = dict(run.columns)
    for k, (col, tau) in enumerate(zip(THERMOMETER_COLUMNS.values(), (200.0, 350.0, 500.0))):
        true = -10.0 + (6.0 + k) * (1.0 - np.exp(-t / tau)) + 0.001 * t
        cols[col] = 0.0625 * np.round((true + 0.01 * rng.standard_normal(t.size)) / 0.0625)
    return dataclasses.replace(run, columns=cols)


def perturbed_after(run, k, seed=11):
    """The run with every thermometer reading after sample k changed (noise, a step, a gap)."""
    rng = np.random.default_rng(seed)
    cols = dict(run.columns)
    for col in THERMOMETER_COLUMNS.values():
        x = np.array(cols[col], dtype=float)
        x[k + 1:] += 0.5 + rng.standard_normal(x.size - k - 1)
        x[k + 1:k + 4] = np.nan
        cols[col] = x
    return dataclasses.replace(run, columns=cols)


def test_cycle_spans_end_where_the_north_finder_ends_its_cycles():
    # Oracle: north_find's own cycles (cycle mode must not outlast the heading it serves).
    run = warming_run()
    spans = cycle_spans(run)
    nf = north_find(run, tilt_correction=False)
    t = run.columns["time_s"]
    assert len(spans) == nf.n_cycles == 4            # 3000 s: four whole cycles of 640 s
    np.testing.assert_array_equal([t[b - 1] for _, b in spans], nf.t_end_s)
    np.testing.assert_array_equal([t[a] for a, _ in spans], nf.t_start_s)


def test_horizon_of_each_mode():
    run = warming_run()
    n = run.columns["time_s"].size
    i = np.arange(n)
    np.testing.assert_array_equal(horizon_index(run, "causal"), i)
    np.testing.assert_array_equal(horizon_index(run, "offline"), np.full(n, n - 1))
    h = horizon_index(run, "cycle")
    (a0, b0), (a1, _) = cycle_spans(run)[:2]
    np.testing.assert_array_equal(h[a0:b0], b0 - 1)   # inside a cycle: its last sample
    np.testing.assert_array_equal(h[b0:a1], i[b0:a1])  # the move between cycles: causal
    last_stop = cycle_spans(run)[-1][1]
    np.testing.assert_array_equal(h[last_stop:], i[last_stop:])   # partial cycle: causal


def test_a_run_without_turntable_columns_is_causal_in_cycle_mode():
    run = warming_run()
    cols = {k: v for k, v in run.columns.items() if k not in ("position_deg", "moving")}
    bare = dataclasses.replace(run, columns=cols)
    np.testing.assert_array_equal(horizon_index(bare, "cycle"), np.arange(cols["time_s"].size))


@pytest.mark.parametrize("mode", ["causal", "cycle"])
def test_no_feature_reads_past_its_horizon(mode):
    # Invariant: change every reading after sample k; no feature up to the horizon-bounded
    # sample may change by a single bit.  Cut points: the first samples, inside a dwell,
    # the last sample of a cycle, inside the move that follows it, the partial last cycle.
    run = warming_run()
    spans = cycle_spans(run)
    X, _ = compute_features(run, FEATURES, mode=mode)
    cuts = [0, 1, 2, 30, 200, spans[0][1] - 1, spans[0][1] + 3, spans[1][0] + 70,
            spans[2][1] - 1, spans[-1][1] + 100]
    for k in cuts:
        Xp, _ = compute_features(perturbed_after(run, k), FEATURES, mode=mode)
        if mode == "causal":
            safe = k
        else:   # the last sample whose horizon is <= k (-1: none, inside the first cycle)
            safe = int(np.flatnonzero(horizon_index(run, "cycle") <= k).max(initial=-1))
        np.testing.assert_array_equal(Xp[:safe + 1], X[:safe + 1], err_msg=f"cut at {k}")
        assert not np.array_equal(Xp[safe + 1:], X[safe + 1:])   # the perturbation is seen


def test_cycle_mode_uses_its_cycle_and_offline_looks_ahead():
    # The look-ahead each mode is allowed does reach the features: cycle mode sees a change
    # later in the same cycle, offline one after the cycle's end.
    run = warming_run()
    (a0, b0) = cycle_spans(run)[0]
    k = a0 + 300
    Xc, _ = compute_features(run, FEATURES, mode="cycle")
    Xcp, _ = compute_features(perturbed_after(run, k), FEATURES, mode="cycle")
    assert not np.array_equal(Xcp[k - 60:k + 1], Xc[k - 60:k + 1])
    Xo, _ = compute_features(run, FEATURES, mode="offline")
    Xop, _ = compute_features(perturbed_after(run, b0 - 1), FEATURES, mode="offline")
    assert not np.array_equal(Xop[:b0], Xo[:b0])
    Xs, _ = compute_features(perturbed_after(run, 100), FEATURES, mode="offline")
    assert not np.array_equal(Xs[:60], Xo[:60])      # the first minute reads the second


@pytest.mark.parametrize("mode", ["causal", "cycle"])
def test_predicted_drift_reads_no_further_than_its_features(mode):
    # Invariant: the compensated output (the model evaluated on a stride and interpolated)
    # obeys the same horizon as the features.
    run = warming_run()
    X, names = compute_features(run, FEATURES, mode="offline")
    rng = np.random.default_rng(5)
    est = LinearRegression().fit(X[::10], rng.standard_normal(X[::10].shape[0]))
    comp = DriftCompensator(method="linear", estimator=est, feature_names=tuple(names),
                            features_mode=mode, settings={"decimate_s": 30.0})
    d = comp.predict_drift(run)
    h = horizon_index(run, mode)
    for k in (5, 400, cycle_spans(run)[1][1] - 1, cycle_spans(run)[1][1] + 2):
        safe = int(np.flatnonzero(h <= k).max(initial=-1))
        dp = comp.predict_drift(perturbed_after(run, k))
        np.testing.assert_array_equal(dp[:safe + 1], d[:safe + 1], err_msg=f"cut at {k}")


def ramp_run(slope_k_per_s=0.01):
    """The warming run's schedule with every thermometer on the ramp -31.7 C + slope t."""
    run = warming_run()
    t = run.columns["time_s"]
    cols = dict(run.columns)
    for col in THERMOMETER_COLUMNS.values():
        cols[col] = -31.7 + slope_k_per_s * t
    return dataclasses.replace(run, columns=cols)


@pytest.mark.parametrize("mode", ["cycle", "offline"])
def test_windowed_rate_of_a_ramp_is_its_slope(mode):
    # Oracle: a local polynomial reproduces a line exactly, so every window returns the
    # slope (0.6 K/min) to rounding once it holds two samples; in cycle mode the samples
    # outside the cycles are causal (next test), so the comparison is on the cycles.
    run = ramp_run()
    X, _ = compute_features(run, ["dT_fog"], mode=mode)
    inside = in_cycle_mask(run) if mode == "cycle" else np.ones(X.shape[0], dtype=bool)
    np.testing.assert_allclose(X[inside, 0], 0.6, rtol=0, atol=1e-9)
    w = int(RATE_WINDOW.window_s)
    r = windowed_rate_k_per_min(-31.7 + 0.01 * np.arange(3000.0), np.arange(3000.0),
                                np.arange(3000), w, RATE_WINDOW.polyorder)
    np.testing.assert_allclose(r[w:], 0.6, rtol=0, atol=1e-9)   # one-sided, window filled
    np.testing.assert_allclose(r[1:], 0.6, rtol=0, atol=1e-9)   # ... and before


def test_causal_rate_of_a_ramp_is_its_slope_after_the_filter_memory():
    # Oracle: the constant-velocity Kalman filter tracks a ramp with no steady-state error
    # (its double pole 0.964 per sample forgets the soak start, rate 0, within ~560 s).
    X, _ = compute_features(ramp_run(), ["dT_fog", "dT_acc_y"], mode="causal")
    np.testing.assert_allclose(X[600:], 0.6, rtol=0, atol=1e-9)
    assert X[0, 0] == 0.0 and 0.0 < X[60, 0] < 0.6       # from the soak towards the slope
    _, a = kalman_rate_filter(1.0, CAUSAL_RATE.accel_psd_k2_per_s3,
                              CAUSAL_RATE.reading_variance_k2)
    np.testing.assert_allclose(np.abs(np.roots(a)), 0.9642, atol=1e-4)


def test_causal_rate_survives_quantisation():
    # A 0.1 K/min ramp read by a 0.0625 K thermometer with 0.01 K noise (the finite
    # difference is spikes of +-3.75 K/min): after the filter's memory the Kalman rate stays
    # within 0.05 K/min, 5.8 sigma of its 0.0086 K/min for this reading noise.
    rng = np.random.default_rng(3)
    t = np.arange(3600.0)
    true = 10.0 + t * (0.1 / 60.0)
    read = 0.0625 * np.round((true + 0.01 * rng.standard_normal(t.size)) / 0.0625)
    r = kalman_rate_k_per_min(read, t)
    assert np.max(np.abs(np.diff(read))) * 60 > 3.0
    assert np.max(np.abs(r[600:] - 0.1)) < 0.05


def test_one_sided_window_uses_only_the_samples_there_are():
    # At sample i < W the one-sided window (horizon h_i = i) is the i + 1 samples 0..i: the
    # first sample alone has the rate 0 of a constant, the second the finite difference.
    t = np.arange(10.0)
    x = np.array([0.0, 0.0625, 0.0625, 0.125, 0.125, 0.125, 0.1875, 0.25, 0.25, 0.3125])
    r = windowed_rate_k_per_min(x, t, np.arange(10), 121.0, 1)
    assert r[0] == 0.0
    assert r[1] == pytest.approx(0.0625 * 60)
    slope = np.polyfit(t[:6], x[:6], 1)[0] * 60
    assert r[5] == pytest.approx(slope, abs=1e-12)


def test_window_rule_with_the_whole_run_is_savgol_interp():
    # Oracle: SciPy's savgol_filter(mode="interp") fits the first and last windows at the
    # ends, which is the window rule with the horizon at the run's last sample.
    rng = np.random.default_rng(2)
    t = np.arange(1500.0)
    x = 5.0 * (1.0 - np.exp(-t / 300.0)) + 0.02 * rng.standard_normal(t.size)
    np.testing.assert_allclose(
        windowed_rate_k_per_min(x, t, np.full(t.size, t.size - 1), 121.0, 2),
        savgol_rate_k_per_min(x, t, 121.0, 2), rtol=0, atol=1e-9)


@pytest.mark.parametrize("rate", [
    lambda x, t: windowed_rate_k_per_min(x, t, np.arange(t.size), 61.0, 1),
    kalman_rate_k_per_min], ids=["one-sided window", "kalman"])
def test_causal_gap_is_held_not_interpolated(rate):
    t = np.arange(300.0)
    x = 0.01 * t
    x[100:110] = np.nan
    r = rate(x, t)
    assert np.all(np.isfinite(r))
    later = x.copy()
    later[110:] += 3.0            # what comes after the gap cannot reach into it
    np.testing.assert_array_equal(rate(later, t)[:110], r[:110])
    lead = x.copy()
    lead[:5] = np.nan             # before the first reading there is no rate
    assert np.all(np.isnan(rate(lead, t)[:5])) and np.isfinite(rate(lead, t)[5:]).all()


def test_same_seed_same_features_bytes():
    for mode in FEATURE_MODES:
        a, _ = compute_features(warming_run(seed=3), FEATURES, mode=mode)
        b, _ = compute_features(warming_run(seed=3), FEATURES, mode=mode)
        assert a.tobytes() == b.tobytes()


def test_unknown_mode_is_one_clear_error():
    with pytest.raises(FeatureModeError, match=r"^--features-mode: unknown mode 'live'; "
                                               r"choose one of cycle, causal, offline$"):
        check_features_mode("live", "--features-mode")
    with pytest.raises(NfsError, match="unknown mode 'centred'"):
        compute_features(warming_run(), FEATURES, mode="centred")


def test_a_model_saved_before_the_modes_is_read_as_offline(tmp_path):
    est = LinearRegression().fit(np.eye(2), [0.0, 1.0])
    comp = DriftCompensator(method="linear", estimator=est, feature_names=("T_fog", "dT_fog"))
    object.__delattr__(comp, "features_mode")      # as pickled by an older version
    joblib.dump({"format": "nfs-compensator/1", "compensator": comp}, tmp_path / "old.joblib")
    assert load_compensator(tmp_path / "old.joblib",
                            trust_pickle=True).features_mode == "offline"
    est = CubicLeastSquares(degree=1).fit(np.eye(2)[:, :1], [0.0, 1.0])
    comp = DriftCompensator(method="LS", estimator=est, feature_names=("T_fog",),
                            features_mode="causal")
    assert load_compensator(comp.save(tmp_path / "new.npz")).features_mode == "causal"


def test_cycle_mode_is_the_window_inside_cycles_and_causal_outside():
    run = warming_run()
    X, _ = compute_features(run, ["dT_fog"], mode="cycle")
    x, t = run.columns["temp_fog_c"], run.columns["time_s"]
    inside = in_cycle_mask(run)
    window = windowed_rate_k_per_min(x, t, horizon_index(run, "cycle"), RATE_WINDOW.window_s,
                                     RATE_WINDOW.polyorder)
    np.testing.assert_array_equal(X[inside, 0], window[inside])
    np.testing.assert_array_equal(X[~inside, 0], kalman_rate_k_per_min(x, t)[~inside])
    assert (~inside).sum() > 100                     # the moves and the partial cycle


def test_the_causal_rate_has_no_window_to_set():
    with pytest.raises(NfsError, match="causal rate is a Kalman filter without a window"):
        compute_features(warming_run(), ["dT_fog"], mode="causal", rate_window_s=61.0)
