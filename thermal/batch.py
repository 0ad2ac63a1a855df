"""Many runs of one thermal network solved together (:func:`simulate_many`).

Start-ups of one instrument differ in where they start and what the chamber does, not in
the network: the step matrices of thermal/solve.py, equations (5) and (8), are computed once,
and a temperature-dependent heat law is marched for every run in one loop over the samples.
"""

from __future__ import annotations

import numpy as np

from thermal.errors import ThermalError
from thermal.network import Network
from thermal.solve import (AMBIENT_HOLDS, PowerLaw, StepMatrices, ThermalResult, _as_ambient,
                           _as_time, _check_power_array, _result, _step_classes, _step_maps,
                           simulate, step_matrices)

__all__ = ["simulate_many"]


def _march_many(steps: list[StepMatrices], cls: list[int], x: np.ndarray, time_s: np.ndarray,
                node_power_w: np.ndarray, power: PowerLaw) -> None:
    """:func:`_march` for R runs at once: ``x`` is (n_t, R, m), the rows of every run at a
    sample side by side, so that one product per step advances every run, and the power law
    is called once per step with the temperatures of every run, shape (R, n), returning
    (R, n).  The step's arithmetic is that of :func:`_march`, bit for bit."""
    n = node_power_w.size
    dots = [m.dot for m in _step_maps(steps, node_power_w)]
    frozen = x.view()
    frozen.flags.writeable = False
    times = time_s.tolist()
    r = x.shape[1]
    first = np.asarray(power(times[0], frozen[0, :, :n]), dtype=float)
    if first.shape != (r, n):
        raise ThermalError(f"power_w(t_s, temperature_c) must return shape ({r}, {n}) for "
                           f"{r} runs, got shape {first.shape}")
    x[0, :, n:2 * n] = first
    step = np.empty((r, n))
    # Each run's product is the matrix-vector product of _march (one BLAS gemv per run): a
    # run's bits are those simulate() gives it, whatever is stacked beside it, while the
    # loop's Python cost and the heat law's call are paid once per step for all runs.
    rows, temps, new_temps = list(x[:-1]), list(x[:-1, :, :n]), list(x[1:, :, :n])
    new_powers, seen = list(x[1:, :, n:2 * n]), list(frozen[1:, :, :n])
    lanes = range(r)
    for c, row, temp, new_temp, new_power, t_s, view in zip(
            cls, rows, temps, new_temps, new_powers, times[1:], seen):
        dot = dots[c]
        for i in lanes:
            dot(row[i], out=step[i])
        np.add(temp, step, out=new_temp)
        new_power[...] = power(t_s, view)


def simulate_many(network: Network, time_s: np.ndarray, *, ambient_c, initial_c,
                  power_w: PowerLaw | np.ndarray | None = None,
                  ambient_hold: str = "zero-order",
                  max_bytes: int | None = None) -> list[ThermalResult]:
    """:func:`simulate` for R runs of one network on one time grid, solved together.

    Many start-ups of one instrument differ only in where they start and what the chamber
    does: the step matrices (5), (8) are computed once, and a temperature-dependent power law
    is marched for every run in one loop over the samples (the loop's Python cost and the
    law's call paid once per step for all runs).  Every run gets the bits :func:`simulate` gives it alone (without a law, each
    run is solved in closed form by it).

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
        The marched state of at most this many bytes at once: the runs are taken in as many
        batches as that needs (a run's bits do not depend on its batch).

    Returns
    -------
    list of ThermalResult
        One per run, in order.
    """
    t = _as_time(time_s)
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
    linear = ambient_hold == "first-order"
    width = 2 * n + 2 + linear
    per = r if max_bytes is None else max(1, int(max_bytes) // (8 * n_t * width))
    if law is None or r == 1 or per == 1:
        # closed form (no law) or one run at a time: simulate's own march, the same bits
        # at less cost, and no step matrices built here for nothing
        return [simulate(network, t, ambient_c=amb_all[i], initial_c=t0_all[i],
                         power_w=power_w, ambient_hold=ambient_hold) for i in range(r)]
    if not np.all(np.isfinite(t0_all)):
        i, j = (int(v) for v in np.argwhere(~np.isfinite(t0_all))[0])
        raise ThermalError(f"initial_c is not finite for run {i}, node {names[j]!r}")
    if ambient_hold not in AMBIENT_HOLDS:
        raise ThermalError(f"ambient_hold must be one of {', '.join(AMBIENT_HOLDS)}, got "
                           f"{ambient_hold!r}")
    ambs = [_as_ambient(amb_all[i], t) for i in range(r)]
    a, b = network.matrices()
    steps, cls = _step_classes(t)
    mats = [step_matrices(a, b, h, slope=linear) for h in steps]
    slopes = []
    for amb in ambs:
        slope = np.zeros(n_t)
        if linear and n_t > 1:
            slope[:-1] = np.diff(amb) / np.diff(t)
        slopes.append(slope)
    out = []
    for b0 in range(0, r, per):
        batch = range(b0, min(r, b0 + per))
        if len(batch) == 1:        # the same bits as the march of many, at less cost
            i = batch[0]
            out.append(simulate(network, t, ambient_c=amb_all[i], initial_c=t0_all[i],
                                power_w=law, ambient_hold=ambient_hold))
            continue
        x = np.zeros((n_t, len(batch), width))
        for k, i in enumerate(batch):
            x[0, k, :n] = t0_all[i]
            x[:, k, 2 * n] = ambs[i]
            x[:, k, 2 * n + 1] = 1.0
            if linear:
                x[:, k, 2 * n + 2] = slopes[i]
        _march_many(mats, cls.tolist(), x, t, network.node_power_w, law)
        for k, i in enumerate(batch):
            _check_power_array(x[:, k, n:2 * n], t, names, "power_w(t_s, temperature_c)")
            inputs = np.empty((n_t, 1 + n))
            inputs[:, 0] = ambs[i]
            inputs[:, 1:] = network.node_power_w + x[:, k, n:2 * n]
            out.append(_result(network, a, b, mats, steps, cls, t, ambs[i], slopes[i],
                               linear, np.ascontiguousarray(x[:, k, :n]), inputs,
                               ambient_hold))
    return out
