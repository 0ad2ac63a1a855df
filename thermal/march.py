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
serves every run at once; the sum is one ``np.add.accumulate`` over j for a few runs
(documented as the running sum r_j = r_{j-1} + a_j, the same order) and one
``np.add.reduce`` over j for many (over the first axis of a C-ordered (n + m, n, R) array
NumPy adds whole (n, R) blocks one after the other, j = 0, 1, ...: the same running sum; its
pairwise summation applies only along a contiguous reduced axis, which this is not;
tests/thermal/test_batch_independence.py checks the bits against runs marched alone).

The drive d_k depends on no state; it is computed elementwise, in the order written in
(9), into the slot of T_{k+1}: for every sample at once for a few runs, for blocks of
:data:`_DRIVE_BLOCK` samples for many (no array of the record's size beside the states; the
slope's products in one scratch block kept over the march).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from thermal.errors import ThermalError

__all__ = ["StepMaps", "step_maps", "march", "heated_rows", "state_buffer", "release_buffers"]

#: Up to this many runs the sum (9) is one ``np.add.accumulate`` (fewer calls); above it
#: one ``np.add.reduce`` of whole blocks (less memory traffic).  The two give the same bits.
_ACCUMULATE_UP_TO = 16
#: Above _ACCUMULATE_UP_TO runs the drive d_k is computed for this many samples at once
#: (elementwise, the order of (9)) into the slots of T_{k+1}: few calls, small temporaries.
_DRIVE_BLOCK = 256


#: Each thread's kept march buffer (``array``) and whether a march holds it (``busy``).
_KEPT = threading.local()


@contextmanager
def state_buffer(shape: tuple[int, ...]) -> Iterator[np.ndarray]:
    """An array of ``shape`` (float64, uninitialised) for a march's states, made from the
    buffer this thread kept from its last march when that is large enough and free.

    A fresh array of a chunk's states (a sweep's 256 start-ups: about 150 MB) costs its page
    faults on first touch, as much time as the march itself on a virtual machine (0.17 s
    for 138 MB here); the kept buffer is touched once per thread.  One march holds it at a
    time (a march begun while another thread's or generator's holds it gets a fresh array);
    :func:`release_buffers` gives it back to the system.
    """
    size = int(np.prod(shape))
    kept = getattr(_KEPT, "array", None)
    if getattr(_KEPT, "busy", False):
        yield np.empty(shape)
        return
    if kept is None or kept.size < size:
        kept = None
        _KEPT.array = None
        kept = _KEPT.array = np.empty(size)
    _KEPT.busy = True
    try:
        yield kept[:size].reshape(shape)
    finally:
        _KEPT.busy = False


def release_buffers() -> None:
    """Free this thread's kept march buffer (:func:`state_buffer`)."""
    _KEPT.array = None


@dataclass(frozen=True)
class StepMaps:
    """The matrices of (9) for each step class (distinct step h)."""

    columns: tuple[np.ndarray, ...]
    """Per class, M^T as (2n, n, 1): row j is the column M_j of [Phi - I | Gamma_P]."""

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
        np.column_stack([m.phi_minus_i, m.gamma[:, 1:]]).T[:, :, None]) for m in steps)
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
          stacked: bool, heated=None, out: np.ndarray | None = None) -> np.ndarray:
    """The states [T_k, p_k] of R runs at every sample by (9), shape (n_t, n + m, R): the n
    node temperatures [degC], then the extra powers [W] of the m ``heated`` nodes.

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
        read-only view of T_k, which is never changed after.
    heated : sequence of int, optional
        The nodes whose extra power can be non-zero (the others' entries of ``extra_w`` or
        of the law's value are zero at every sample, which the caller guarantees); None:
        every node (m = n).  A node left out contributes M_j 0 = 0 to the sum (9), so
        carrying only the heated ones drops exact zeros from it and keeps every other term
        in its order: the same bits, fewer operations and a smaller state.
    out : array (n_t, n + m, R), optional
        Where to write the states (:func:`state_buffer`); None: a new array.
    """
    n, r = initial_c.shape
    n_t = time_s.size
    nodes = heated_rows(n, heated)
    m = nodes.size
    rows_used = np.concatenate([np.arange(n), n + nodes])
    every = m == n
    state = np.empty((n_t, n + m, r)) if out is None else out
    temp, power = state[:, :n], state[:, n:]
    temp[0] = initial_c
    if law is None:
        power[...] = 0.0 if extra_w is None else extra_w[:, nodes, None]
    frozen = state.view()
    frozen.flags.writeable = False
    seen = list(frozen[:, :n].transpose(0, 2, 1)) if stacked else list(frozen[:, :n, 0])
    want = (r, n) if stacked else (n,)
    # the law's heated columns: a slice when they are contiguous (a view, where an index
    # array copies them at every sample)
    pick = (slice(int(nodes[0]), int(nodes[-1]) + 1)
            if m and nodes[-1] - nodes[0] == m - 1 else nodes)
    columns = [np.ascontiguousarray(col[rows_used]) for col in maps.columns]
    classes = cls.tolist()
    few = r <= _ACCUMULATE_UP_TO
    prod = np.empty((n + m, n, r))
    acc = np.empty((n + m, n, r)) if few else np.empty((n, r))
    scratch = None if few else np.empty((_DRIVE_BLOCK, n, r))
    times = time_s.tolist()
    if few:
        _drive(maps, cls, ambient_c, slope_c_per_s, temp[1:])
    # per sample: the state as (n + m, 1, R) for the products, T_k and the slot of T_{k+1}
    rows, temps, new_temps = list(state[:, :, None, :]), list(temp[:-1]), list(temp[1:])
    last = acc[-1]                                  # the running sum's end (few runs)
    powers = list(power.transpose(0, 2, 1)) if stacked else list(power[:, :, 0])
    for k, t_s in enumerate(times):
        if law is not None:
            p = np.asarray(law(t_s, seen[k]), dtype=float)
            if p.shape != want:
                raise ThermalError(f"power_w(t_s, temperature_c) must return shape {want}"
                                   f"{f' for {r} runs' if stacked else ''}, got shape "
                                   f"{p.shape}")
            powers[k][...] = p if every else p[..., pick]
        if k == n_t - 1:
            break
        if not few and k % _DRIVE_BLOCK == 0:   # d_k of the next block, in the order of (9)
            stop = min(k + _DRIVE_BLOCK, n_t - 1)
            _drive(maps, cls[k:stop], ambient_c[k:stop + 1],
                   None if slope_c_per_s is None else slope_c_per_s[k:stop + 1],
                   temp[k + 1:stop + 1], scratch)
        new = new_temps[k]
        np.multiply(columns[classes[k]], rows[k], out=prod)
        if few:
            np.add.accumulate(prod, axis=0, out=acc)
            new += last
        else:
            np.add.reduce(prod, axis=0, out=acc)
            new += acc
        new += temps[k]
    return state
