"""The named feature library: names, sets, patterns and the quantisation-proof derivative."""

import numpy as np
import pytest

from nfs.compensate.features import (FeatureError, compute_features,
                                     rate_k_per_min, resolve_features)
from nfs.run import Run, RunMeta


def make_run(n=3600, aux=True):
    t = np.arange(n, dtype=float)
    cols = {
        "time_s": t,
        "temp_fog_c": 20.0 + 0.01 * t,               # 0.6 K/min
        "temp_acc_x_c": 18.0 + 0.005 * t,            # 0.3 K/min
        "temp_acc_y_c": np.full(n, 19.0),
    }
    if aux:
        cols["aux_v"] = np.sin(t / 100.0)
    return Run(name="r", columns=cols, meta=RunMeta(latitude_deg=30.0, start_temperature_c=20.0))


def test_sets_and_patterns():
    assert len(resolve_features("seed004")) == 9
    assert resolve_features("seed001") == ["T_fog", "dT_fog", "TdT_fog"]
    assert resolve_features("seed000", ["aux_v"]) == ["T_fog", "dT_fog", "aux_v"]
    assert resolve_features(["dT_*"]) == ["dT_fog", "dT_acc_x", "dT_acc_y"]
    with pytest.raises(FeatureError, match="unknown feature 'Tfog'.*T_fog.*sets: seed004"):
        resolve_features(["Tfog"])


def test_feature_values():
    # Oracle: linear ramps have exact rates; gradient and product by definition.  (Offline:
    # every sample; the cycle and causal modes' rates of a ramp are tested in
    # test_feature_modes.py.)
    X, names = compute_features(make_run(), ["T_fog", "dT_fog", "dT_acc_x", "G_fog_acc_x",
                                             "TdT_fog", "aux_v"], mode="offline")
    col = dict(zip(names, X.T))
    np.testing.assert_allclose(col["dT_fog"], 0.6, rtol=1e-9)
    np.testing.assert_allclose(col["dT_acc_x"], 0.3, rtol=1e-9)
    np.testing.assert_allclose(col["G_fog_acc_x"], 2.0 + 0.005 * np.arange(3600), rtol=1e-12)
    np.testing.assert_allclose(col["TdT_fog"], (col["T_fog"] - 25.0) * 0.6, rtol=1e-9)


def test_rate_survives_quantisation():
    # A 0.1 K/min ramp read by a 0.0625 K thermometer with 0.01 K noise: the finite difference
    # is spikes of +-3.75 K/min; the Savitzky-Golay rate stays within 0.02 K/min (about 5 sigma
    # of sigma_q sqrt(12 / W^3) * 60 with W = 121, sigma_q = 0.0625/sqrt(12) + noise).
    rng = np.random.default_rng(3)
    t = np.arange(3600.0)
    true = 10.0 + t * (0.1 / 60.0)
    read = 0.0625 * np.round((true + 0.01 * rng.standard_normal(t.size)) / 0.0625)
    r = rate_k_per_min(read, t)
    assert np.max(np.abs(np.diff(read))) * 60 > 3.0
    assert np.max(np.abs(r[100:-100] - 0.1)) < 0.02


def test_missing_channel_is_named():
    with pytest.raises(FeatureError, match="run 'r' has no column 'aux_w'"):
        compute_features(make_run(), ["T_fog", "aux_w"])
