"""The march of R runs of one network through their samples, in arithmetic whose every bit
of a run is independent of the runs beside it.

A run's augmented state at sample k is s_k = [T_k, p_k] (2n rows: the node temperatures
[degC] and the extra node powers held over [t_k, t_k+1) [W]).  One step of the exact
solution, thermal/solve.py equations (3) and (7), is

    T_{k+1} = T_k + (sum_{j=0}^{2n-1} M_j s_k,j + d_k),        M = [Phi - I | Gamma_P],  (9)
    d_k = (Gamma_amb T_amb,k + Gamma_P P_const) + Lambda v_k,

with Phi - I = A Psi free of the cancellation of Phi - I (solve.py), M_j column j of M
[K per K, or K per W], Gamma_amb the chamber column of Gamma, P_const the constant node
powers [W] and v_k the chamber's slope [K/s] (zero under a zero-order hold).

Bits independent of the batch.  The sum over j in (9) is taken in the fixed order j = 0, 1,
..., 2n-1, one product M_j s_k,j and one addition at a time, each an IEEE-754 operation on
that run's own numbers (NumPy's elementwise ``multiply`` and ``add``, which round every
result and never fuse a multiply and an add).  Every run of a batch goes through the same
sequence of correctly rounded operations on its own operands, so its bits are those it gets
alone: no BLAS product, whose summation order may follow the shape of the batch, is
involved.  The powers of nodes that are never heated (given as ``heated``) are left out of
the sum and of the state: their terms M_j 0 are exact zeros, whose addition changes no
non-zero sum, and the other terms keep their order.  The states of R runs lie side by side
in the last axis, ``state[k]`` of shape (n + m, R) (m heated nodes), so each operation
serves every run at once; the sum is one ``np.einsum("ji,jr->ir", M^T, s_k)`` without
path optimisation: NumPy's own loops, which for each (i, r) add the products M_ji s_k,jr
one after the other, j = 0, 1, ..., each product and sum rounded (no BLAS, no pairwise
summation, no fused multiply-add), the running sum r_j = r_(j-1) + M_j s_k,j of (9)
without forming the (n + m, n, R) array of products (tests/thermal/test_batch_independence.py
checks the bits against the running sum written out and against runs marched alone).

The march works through blocks of :data:`_BLOCK` samples in a buffer of every run's states
(small enough to stay in the cache); after each block the states are copied into each run's
own contiguous record, so no array of the runs' states side by side is ever as large as the
records, and a run's record is read without a pass over the others'.  The drive d_k depends
on no state; it is computed for a block at a time, elementwise, in the order written in (9),
into the slots of T_{k+1} (the slope's products in one scratch block).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from thermal.errors import ThermalError

__all__ = ["StepMaps", "step_maps", "march", "heated_rows"]

#: Samples marched between two writes of the states into the runs' records: the march
#: works in a buffer of this many samples of every run (a few MB for hundreds of runs,
#: which stays in the cache), whose block is then copied into each run's own contiguous
#: record (the layout a run's result is read in).
_BLOCK = 32


@dataclass(frozen=True)
class StepMaps:
    """The matrices of (9) for each step class (distinct step h)."""

    columns: tuple[np.ndarray, ...]
    """Per class, M^T as (2n, n): row j is the column M_j of [Phi - I | Gamma_P]."""

    ambient: np.ndarray
    """Gamma_amb per class [K/K], shape (n_classes, n)."""

    constant: np.ndarray
    """Gamma_P P_const per class [K], shape (n_classes, n)."""

    slope: np.ndarray | None
    """Lambda per class [K per K/s], shape (n_classes, n); None under a zero-order hold."""


def step_maps(steps, node_power_w: np.ndarray) -> StepMaps:
    """The :class:`StepMaps` of the step matrices ``steps`` (solve.StepMatrices, one per
    step class) and the constant node powers ``node_power_w`` [W], shape (n,)."""
    n = node_power_w.size
    if not steps:                           # one sample: nothing to step
        return StepMaps((), np.empty((0, n)), np.empty((0, n)), None)
    columns = tuple(np.ascontiguousarray(
        np.column_stack([m.phi_minus_i, m.gamma[:, 1:]]).T) for m in steps)
    ambient = np.array([m.gamma[:, 0] for m in steps])
    constant = np.array([m.gamma[:, 1:] @ node_power_w for m in steps])
    slope = None if steps[0].lam is None else np.array([m.lam for m in steps])
    return StepMaps(columns, ambient, constant, slope)


def _drive(maps: StepMaps, cls: np.ndarray, ambient_c: np.ndarray,
           slope_c_per_s: np.ndarray | None, out: np.ndarray,
           scratch: np.ndarray | None = None) -> None:
    """d_k of (9) for the intervals ``cls`` into ``out`` (n_intervals, n, R), elementwise in
    the order written in (9); ``scratch`` (at least as large as ``out``) holds the slope's
    products (None: a temporary)."""
    np.multiply(maps.ambient[cls][:, :, None], ambient_c[:-1, None, :], out=out)
    out += maps.constant[cls][:, :, None]
    if maps.slope is not None and slope_c_per_s is not None:
        part = (np.empty(out.shape) if scratch is None else scratch[:cls.size])
        np.multiply(maps.slope[cls][:, :, None], slope_c_per_s[:-1, None, :], out=part)
        out += part


def heated_rows(n: int, heated) -> np.ndarray:
    """Rows of M^T (and of the state) the march carries: the n temperatures, then the powers
    of the ``heated`` nodes (every node when None), in increasing node order."""
    nodes = np.arange(n) if heated is None else np.unique(np.asarray(heated, dtype=int))
    if nodes.size and (nodes[0] < 0 or nodes[-1] >= n):
        raise ThermalError(f"heated_nodes must be node indices in 0..{n - 1}, got "
                           f"{list(np.asarray(heated).tolist())}")
    return nodes


def march(maps: StepMaps, cls: np.ndarray, time_s: np.ndarray, initial_c: np.ndarray,
          ambient_c: np.ndarray, slope_c_per_s: np.ndarray | None,
          extra_w: np.ndarray | None, law: Callable | None, *,
          stacked: bool, heated=None) -> tuple[np.ndarray, np.ndarray]:
    """The temperatures T_k [degC] and the extra powers p_k [W] of the m ``heated`` nodes of
    R runs at every sample by (9): arrays (R, n_t, n) and (R, n_t, m), each run's record
    contiguous (``[i]`` is run i's).

    Parameters
    ----------
    maps, cls :
        The step maps (:func:`step_maps`) and, per interval k, its step class.
    time_s : array (n_t,)
        Sample times [s].
    initial_c : array (n, R)
        T_0 of every run [degC].
    ambient_c, slope_c_per_s : array (n_t, R)
        T_amb,k [degC] and its slope v_k [K/s] (None: held) of every run.
    extra_w : array (n_t, n), optional
        The extra powers p_k [W] shared by every run, when there is no law.
    law : callable(t_s, temperature_c) -> array, optional
        p_k = law(t_k, T_k), called once per sample for every run: with ``stacked`` the
        temperatures of the runs (R, n) -> (R, n), else (one run) (n,) -> (n,).  It gets a
        read-only view of T_k, valid during the call.
    heated : sequence of int, optional
        The nodes whose extra power can be non-zero (the others' entries of ``extra_w`` or
        of the law's value are zero at every sample, which the caller guarantees); None:
        every node (m = n).  A node left out contributes M_j 0 = 0 to the sum (9), so
        carrying only the heated ones drops exact zeros from it and keeps every other term
        in its order: the same bits, fewer operations and a smaller state.
    """
    n, r = initial_c.shape
    n_t = time_s.size
    nodes = heated_rows(n, heated)
    m = nodes.size
    rows_used = np.concatenate([np.arange(n), n + nodes])
    every = m == n
    temps, powers = np.empty((r, n_t, n)), np.empty((r, n_t, m))
    block = max(1, min(_BLOCK, n_t))
    # the march's buffer: samples k0 .. k0 + block of every run, [T_k, p_k] as (n + m, R)
    buf = np.empty((block + 1, n + m, r))
    temp_b, power_b = buf[:, :n], buf[:, n:]
    temp_b[0] = initial_c
    frozen = buf.view()
    frozen.flags.writeable = False
    seen = list(frozen[:, :n].transpose(0, 2, 1)) if stacked else list(frozen[:, :n, 0])
    want = (r, n) if stacked else (n,)
    # the law's heated columns: a slice when they are contiguous (a view, where an index
    # array copies them at every sample)
    pick = (slice(int(nodes[0]), int(nodes[-1]) + 1)
            if m and nodes[-1] - nodes[0] == m - 1 else nodes)
    columns = [np.ascontiguousarray(col[rows_used]) for col in maps.columns]
    classes = cls.tolist()
    acc = np.empty((n, r))
    scratch = np.empty((block, n, r))
    times = time_s.tolist()
    # per sample of the buffer: the state (n + m, R), T_k and the law's view of p_k
    rows, temp_rows = list(buf), list(temp_b)
    power_rows = list(power_b.transpose(0, 2, 1)) if stacked else list(power_b[:, :, 0])
    for k0 in range(0, n_t, block):
        size = min(block, n_t - k0)                 # samples k0 .. k0 + size - 1 here
        steps = min(size, n_t - 1 - k0)             # steps k -> k + 1 taken from them
        if steps:                                   # d_k of (9) into the slots of T_{k+1}
            _drive(maps, cls[k0:k0 + steps], ambient_c[k0:k0 + steps + 1],
                   None if slope_c_per_s is None else slope_c_per_s[k0:k0 + steps + 1],
                   temp_b[1:steps + 1], scratch)
        if law is None:
            power_b[:size] = 0.0 if extra_w is None else extra_w[k0:k0 + size, nodes, None]
        for i in range(size):
            k = k0 + i
            if law is not None:
                p = np.asarray(law(times[k], seen[i]), dtype=float)
                if p.shape != want:
                    raise ThermalError(f"power_w(t_s, temperature_c) must return shape {want}"
                                       f"{f' for {r} runs' if stacked else ''}, got shape "
                                       f"{p.shape}")
                power_rows[i][...] = p if every else p[..., pick]
            if i == steps:
                break
            new = temp_rows[i + 1]
            # sum_j M_j s_k,j, j in order (the module docstring)
            np.einsum("ji,jr->ir", columns[classes[k]], rows[i], out=acc)
            new += acc
            new += temp_rows[i]
        temps[:, k0:k0 + size] = temp_b[:size].transpose(2, 0, 1)
        powers[:, k0:k0 + size] = power_b[:size].transpose(2, 0, 1)
        if k0 + size < n_t:
            temp_b[0] = temp_b[size]                # the next block starts where this ends
    return temps, powers
