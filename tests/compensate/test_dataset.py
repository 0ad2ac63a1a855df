"""nfs.compensate.dataset: the training set and its validation folds."""

import numpy as np

from nfs.compensate.dataset import DriftDataset


def _ds(temps, n=4):
    groups = np.repeat(np.arange(len(temps)), n)
    return DriftDataset(X=np.zeros((groups.size, 1)), y=np.zeros(groups.size), groups=groups,
                        time_s=np.tile(np.arange(n, dtype=float), len(temps)),
                        feature_names=("x",), run_names=tuple(f"r{i}" for i in range(len(temps))),
                        start_temperatures_c=tuple(temps))


def test_validation_groups_leave_one_start_temperature_out():
    # Oracle: runs 0 and 2 start at -32 C, runs 1 and 3 at 54 C, run 4 at 28 C: three folds,
    # the twins in one fold.
    ds = _ds([-32.0, 54.0, -32.0, 54.0, 28.0])
    g = ds.validation_groups
    assert len(np.unique(g)) == 3
    for a, b in ((0, 2), (1, 3)):
        assert np.all(g[ds.groups == a] == g[ds.groups == b][0])
    assert len(set(g[ds.groups == 0]) | set(g[ds.groups == 1]) | set(g[ds.groups == 4])) == 3


def test_validation_groups_fall_back_to_runs_at_one_temperature():
    ds = _ds([20.0, 20.0, 20.0])
    np.testing.assert_array_equal(ds.validation_groups, ds.groups)


def test_thinned_keeps_groups_aligned():
    ds = _ds([-32.0, 54.0, -32.0], n=10).thinned(7)
    assert ds.X.shape[0] <= 7 and ds.groups.size == ds.X.shape[0] == ds.time_s.size
