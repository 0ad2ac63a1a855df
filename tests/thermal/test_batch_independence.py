"""A run's bits do not depend on the batch it is marched in (thermal/march.py, equation (9)).

Oracle: invariance.  Every run of a batch goes through the same correctly rounded
elementwise operations on its own numbers, so each run's temperatures, powers, rates and
heat bookkeeping are equal (np.array_equal, every bit) whether it is marched alone
(thermal.simulate), in batches of 1, 2, 7 or all R runs, in any order, beside any
neighbours, the march's blocks of samples included (a record of many blocks and one that
ends inside a block); and the step's sum, NumPy's ``einsum`` without path optimisation, is
the running sum of rounded products written out, whatever the shape.
"""

import numpy as np
import pytest

from thermal import ThermalError, iter_simulate_many, simulate, simulate_many
from thermal.batch import runs_per_batch
from thermal.march import _BLOCK
from thermal_networks import seven_nodes

R = 40
FIELDS = ("temperature_c", "power_w", "rate_c_per_s", "heat_in_j", "heat_lost_j")


def _tec(j):
    """A TEC-like law on node j for one run (n,) or many (R, n) [W]."""
    def law(t_s, temperature_c):
        p = np.zeros(np.shape(temperature_c))
        d = np.asarray(temperature_c)[..., j] - 25.0
        p[..., j] = np.where(d < 0, -0.03 * d, 0.08 * d) + 0.2 * np.sin(t_s / 90.0)
        return p
    return law


@pytest.fixture(scope="module")
def case():
    net = seven_nodes()
    rng = np.random.default_rng(25)
    t = np.arange(0.0, 1500.0, 1.0)
    starts = rng.uniform(-40.0, 60.0, R)
    ambient = (starts[:, None] + rng.uniform(-2.0, 2.0, (R, 1)) * np.sin(t / 300.0)
               + rng.uniform(-1.0, 1.0, (R, 1)) * t / 1500.0)
    initial = starts[:, None] + rng.uniform(-3.0, 3.0, (R, len(net.node_names)))
    law = _tec(net.node_names.index("electronics"))
    return net, t, ambient, initial, law


def _same(a, b):
    for f in FIELDS:
        assert np.array_equal(getattr(a, f), getattr(b, f)), f


@pytest.mark.parametrize("hold", ["zero-order", "first-order"])
def test_every_run_has_its_bits_in_any_batch(case, hold):
    net, t, ambient, initial, law = case
    assert t.size > 10 * _BLOCK and t.size % _BLOCK     # many blocks, the last one partial
    all_runs = simulate_many(net, t, ambient_c=ambient, initial_c=initial, power_w=law,
                             ambient_hold=hold)
    for size in (1, 2, 7):
        for b0 in range(0, R, size):
            idx = list(range(b0, min(R, b0 + size)))
            part = simulate_many(net, t, ambient_c=ambient[idx], initial_c=initial[idx],
                                 power_w=law, ambient_hold=hold)
            for i, res in zip(idx, part):
                _same(res, all_runs[i])


def test_order_and_neighbours_do_not_matter(case):
    net, t, ambient, initial, law = case
    all_runs = simulate_many(net, t, ambient_c=ambient, initial_c=initial, power_w=law,
                             ambient_hold="first-order")
    order = np.random.default_rng(7).permutation(R)
    shuffled = simulate_many(net, t, ambient_c=ambient[order], initial_c=initial[order],
                             power_w=law, ambient_hold="first-order")
    for i, res in zip(order, shuffled):
        _same(res, all_runs[i])
    # run 0 beside copies of run 5 and beside its own copies
    for mix in ([0, 5, 5, 5], [5] * 20 + [0], [0] * (R + 3)):
        res = simulate_many(net, t, ambient_c=ambient[mix], initial_c=initial[mix],
                            power_w=law, ambient_hold="first-order")
        _same(res[mix.index(0)], all_runs[0])


@pytest.mark.parametrize("hold", ["zero-order", "first-order"])
def test_a_single_run_is_a_batch_of_one(case, hold):
    net, t, ambient, initial, law = case
    all_runs = simulate_many(net, t, ambient_c=ambient, initial_c=initial, power_w=law,
                             ambient_hold=hold)
    for i in (0, 13, R - 1):
        one = simulate(net, t, ambient_c=ambient[i], initial_c=initial[i], power_w=law,
                       ambient_hold=hold)
        _same(one, all_runs[i])


def test_batches_by_memory_and_streaming_give_the_same_bits(case):
    net, t, ambient, initial, law = case
    all_runs = simulate_many(net, t, ambient_c=ambient, initial_c=initial, power_w=law)
    per_run = 8 * 2 * len(net.node_names) * t.size
    for max_bytes in (1, 3 * per_run, 17 * per_run):
        streamed = iter_simulate_many(net, t, ambient_c=ambient, initial_c=initial,
                                      power_w=law, max_bytes=max_bytes)
        for a, b in zip(streamed, all_runs, strict=True):
            _same(a, b)


def test_uneven_steps_keep_batch_independence(case):
    """Two step classes (a grid with a gap): each interval takes its own class's maps."""
    net, _, _, _, law = case
    t = np.concatenate([np.arange(0.0, 300.0, 1.0), 310.0 + np.arange(0.0, 300.0, 2.0)])
    rng = np.random.default_rng(3)
    starts = rng.uniform(-30.0, 50.0, 20)
    ambient = starts[:, None] + np.sin(t / 60.0)[None, :]
    many = simulate_many(net, t, ambient_c=ambient, initial_c=starts, power_w=law,
                         ambient_hold="first-order")
    for i in (0, 19):
        one = simulate(net, t, ambient_c=ambient[i], initial_c=starts[i], power_w=law,
                       ambient_hold="first-order")
        _same(one, many[i])


@pytest.mark.parametrize("hold", ["zero-order", "first-order"])
def test_carrying_only_the_heated_nodes_changes_no_bit(case, hold):
    """The law heats one node: marched with ``heated_nodes`` naming it (the other powers'
    exact-zero terms left out of the sum (9)), every run has the bits of the march over every
    node, alone and in batches."""
    net, t, ambient, initial, law = case
    j = net.node_names.index("electronics")
    every = simulate_many(net, t, ambient_c=ambient, initial_c=initial, power_w=law,
                          ambient_hold=hold)
    heated = simulate_many(net, t, ambient_c=ambient, initial_c=initial, power_w=law,
                           ambient_hold=hold, heated_nodes=[j])
    for a, b in zip(heated, every, strict=True):
        _same(a, b)
    for size in (1, 5):
        part = simulate_many(net, t, ambient_c=ambient[:size], initial_c=initial[:size],
                             power_w=law, ambient_hold=hold, heated_nodes=(j,))
        for a, b in zip(part, every[:size], strict=True):
            _same(a, b)
    one = simulate(net, t, ambient_c=ambient[3], initial_c=initial[3], power_w=law,
                   ambient_hold=hold, heated_nodes=[j])
    _same(one, every[3])
    # a node outside the network is refused
    with pytest.raises(ThermalError, match="heated_nodes"):
        simulate(net, t, ambient_c=ambient[3], initial_c=initial[3], power_w=law,
                 heated_nodes=[len(net.node_names)])


def test_a_batch_by_memory_counts_only_the_heated_nodes(case):
    """runs_per_batch: a run's states are (n + m) rows of n_t samples, 8 bytes each."""
    net, t, _, _, _ = case
    n = len(net.node_names)
    assert runs_per_batch(n, t.size, 8 * (n + 1) * t.size * 5, 1) == 5
    assert runs_per_batch(n, t.size, 8 * 2 * n * t.size * 5) == 5
    assert runs_per_batch(n, t.size, None) is None


def test_the_step_sum_is_the_running_sum_of_rounded_products():
    """thermal/march.py's sum of (9) by ``np.einsum("ji,jr->ir", M^T, s)``: for every run
    r, ((0 + M_0 s_0r) + M_1 s_1r) + ..., each product and sum rounded, whatever the number
    of runs beside it (NumPy's einsum loops; no BLAS, no pairwise sum, no fused
    multiply-add): the arithmetic the march's batch independence rests on."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        n, m, r = int(rng.integers(2, 40)), int(rng.integers(0, 4)), int(rng.integers(1, 300))
        mt = rng.standard_normal((n + m, n)) * 10.0 ** rng.uniform(-8, 2, (n + m, n))
        s = rng.standard_normal((n + m, r)) * 10.0 ** rng.uniform(-3, 3, (n + m, 1))
        running = np.zeros((n, r))
        for j in range(n + m):
            running = running + mt[j][:, None] * s[j][None, :]
        got = np.einsum("ji,jr->ir", mt, s, out=np.empty((n, r)))
        assert np.array_equal(got, running), (n, m, r)
        k = int(rng.integers(0, r))
        alone = np.einsum("ji,jr->ir", mt, s[:, k:k + 1].copy(), out=np.empty((n, 1)))
        assert np.array_equal(alone[:, 0], running[:, k]), (n, m, r)
