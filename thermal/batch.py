"""Many runs of one thermal network solved together (:func:`simulate_many`).

Start-ups of one instrument differ in where they start and what the chamber does, not in
the network: the step matrices of thermal/solve.py, equations (5) and (8), are computed once,
and a temperature-dependent heat law is marched for every run at once, one array operation
per term of the step (thermal/march.py, equation (9)), in arithmetic that gives each run the
bits it gets alone.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from thermal.errors import ThermalError
from thermal.inputs import as_ambient, as_time, step_classes
from thermal.march import heated_rows, march, step_maps
from thermal.network import Network
from thermal.solve import (AMBIENT_HOLDS, PowerLaw, ThermalResult, fill_inputs, simulate,
                           step_matrices, thermal_result)

__all__ = ["simulate_many", "iter_simulate_many", "runs_per_batch"]

def runs_per_batch(n_nodes: int, n_samples: int, max_bytes: int | None,
                   n_heated: int | None = None) -> int | None:
    """Runs whose marched states [T_k, p_k] (8 bytes x (n_nodes + n_heated) x n_samples
    each; ``n_heated`` the nodes a law heats, default every node) fit in ``max_bytes`` (at
    least one); None without a bound."""
    if max_bytes is None:
        return None
    rows = n_nodes + (n_nodes if n_heated is None else n_heated)
    return max(1, int(max_bytes) // (8 * rows * max(n_samples, 1)))


def simulate_many(network: Network, time_s: np.ndarray, *, ambient_c, initial_c,
                  power_w: PowerLaw | np.ndarray | None = None,
                  ambient_hold: str = "zero-order",
                  max_bytes: int | None = None, heated_nodes=None) -> list[ThermalResult]:
    """:func:`simulate` for R runs of one network on one time grid, solved together.

    Many start-ups of one instrument differ only in where they start and what the chamber
    does: the step matrices (5), (8) are computed once, and a temperature-dependent power law
    is marched for every run at once (thermal/march.py: one array operation per term of the
    step for all runs, the law called once per sample with every run's temperatures).  Every
    run gets the bits :func:`simulate` gives it alone, whatever batch it is in (without a
    law, each run is solved in closed form by it).

    Parameters
    ----------
    ambient_c : array_like (R, n_t)
        Chamber temperature of every run at the samples [degC].
    initial_c : array_like (R,) or (R, n_nodes)
        Node temperatures of every run at time_s[0] [degC].
    power_w : callable(t_s, temperature_c) -> array, array (n_t, n_nodes), optional
        As :func:`simulate`, shared by every run; a callable gets the temperatures of every
        run at t_s, shape (R, n_nodes), and returns the extra powers, shape (R, n_nodes).
    time_s, ambient_hold :
        As :func:`simulate`.
    max_bytes : int, optional
        The marched states of at most this many bytes at once (:func:`runs_per_batch`):
        the runs are taken in as many batches as that needs (a run's bits do not depend on
        its batch).
    heated_nodes : sequence of int, optional
        As :func:`simulate`: the nodes a callable ``power_w`` can heat (None: every node).

    Returns
    -------
    list of ThermalResult
        One per run, in order.
    """
    return list(iter_simulate_many(network, time_s, ambient_c=ambient_c, initial_c=initial_c,
                                   power_w=power_w, ambient_hold=ambient_hold,
                                   max_bytes=max_bytes, heated_nodes=heated_nodes))


def iter_simulate_many(network: Network, time_s: np.ndarray, *, ambient_c, initial_c,
                       power_w: PowerLaw | np.ndarray | None = None,
                       ambient_hold: str = "zero-order",
                       max_bytes: int | None = None,
                       heated_nodes=None) -> Iterator[ThermalResult]:
    """:func:`simulate_many`, its results yielded one at a time, in order: at most one
    batch of marched states (``max_bytes``) and the result being read are held at once."""
    t = as_time(time_s)
    n_t = t.size
    names = network.node_names
    n = len(names)
    amb_all = np.asarray(ambient_c, dtype=float)
    if amb_all.ndim != 2 or amb_all.shape[1] != n_t:
        raise ThermalError(f"ambient_c must have shape (R, {n_t}), got shape {amb_all.shape}")
    r = amb_all.shape[0]
    t0_all = np.asarray(initial_c, dtype=float)
    if t0_all.ndim == 1:
        t0_all = np.repeat(t0_all[:, None], n, axis=1)
    if t0_all.shape != (r, n):
        raise ThermalError(f"initial_c must have shape ({r},) or ({r}, {n}), got shape "
                           f"{np.shape(initial_c)}")
    law = power_w if callable(power_w) else None
    if law is None:
        # closed form: each run alone is exact and costs no loop
        for i in range(r):
            yield simulate(network, t, ambient_c=amb_all[i], initial_c=t0_all[i],
                           power_w=power_w, ambient_hold=ambient_hold)
        return
    if not np.all(np.isfinite(t0_all)):
        i, j = (int(v) for v in np.argwhere(~np.isfinite(t0_all))[0])
        raise ThermalError(f"initial_c is not finite for run {i}, node {names[j]!r}")
    if ambient_hold not in AMBIENT_HOLDS:
        raise ThermalError(f"ambient_hold must be one of {', '.join(AMBIENT_HOLDS)}, got "
                           f"{ambient_hold!r}")
    linear = ambient_hold == "first-order"
    a, b = network.matrices()
    steps, cls = step_classes(t)
    mats = [step_matrices(a, b, h, slope=linear) for h in steps]
    maps = step_maps(mats, network.node_power_w)
    nodes = heated_rows(n, heated_nodes)
    per = runs_per_batch(n, n_t, max_bytes, nodes.size) or r
    for b0 in range(0, r, per):
        batch = range(b0, min(r, b0 + per))
        ambs = np.array([as_ambient(amb_all[i], t) for i in batch])      # (R, n_t)
        slopes = np.zeros(ambs.shape)
        if linear and n_t > 1:
            slopes[:, :-1] = np.diff(ambs, axis=1) / np.diff(t)
        temps, powers = march(maps, cls, t, t0_all[batch.start:batch.stop].T,
                              np.ascontiguousarray(ambs.T),
                              np.ascontiguousarray(slopes.T) if linear else None, None, law,
                              stacked=True, heated=nodes)
        for q in range(len(batch)):
            inputs = np.empty((n_t, 1 + n))
            inputs[:, 0] = ambs[q]
            fill_inputs(inputs, network.node_power_w, nodes, powers[q], t, names)
            yield thermal_result(network, a, b, mats, steps, cls, t, ambs[q], linear,
                                 temps[q], inputs, ambient_hold)
        del temps, powers
