"""The heat input of a run's thermal effects: the state-free powers as arrays, and the
state-dependent ones (a TEC's draw) as a per-sample law P(t_k, T_k) for :func:`thermal.simulate`
and :func:`thermal.simulate_many` (docs/physics.md section 2).

While the unit is off (:mod:`nfs.power`) the network's constant node powers are cancelled
(an extra -P_j [W]) and every thermal effect releases nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .effects import EffectInstance
from .instrument import Instrument

__all__ = ["thermal_effects", "fixed_thermal_power", "thermal_power", "HeatLaw"]

#: Stacked runs up to this many get the state-dependent heat law row by row.
_ROW_BY_ROW = 4


def thermal_effects(inst: Instrument) -> list[tuple[EffectInstance, int, dict[str, Any]]]:
    """Each thermal effect of ``inst`` with the index of the node it heats and its call
    parameters (``node`` resolved: the gyro's source when the effect does not name one)."""
    names = inst.network.node_names
    out = []
    for e in inst.effects:
        if e.spec.kind != "thermal":
            continue
        node = e.params.get("node") or inst.gyro.source
        params = dict(e.params)
        if "node" in params:
            params["node"] = node
        out.append((e, names.index(node), params))
    return out


def fixed_thermal_power(inst: Instrument, time_s: np.ndarray, moving: np.ndarray,
                        powered: np.ndarray | None = None):
    """The state-free part of the heat input: (fixed, terms, stateful).

    ``fixed`` (n_samples, n_nodes) [W]: the state-free thermal effects' power, and, while
    the unit is off (``powered`` False, :mod:`nfs.power`), nothing of them and an extra
    -P_j cancelling the network's constant node powers; ``terms`` each state-free effect's
    power by label; ``stateful`` the state-dependent effects (effect, node index, params).
    """
    n = len(inst.network.node_names)
    fixed = np.zeros((len(time_s), n))
    stateful: list[tuple[EffectInstance, int, dict[str, Any]]] = []
    terms: dict[str, np.ndarray] = {}
    off = None if powered is None else ~np.asarray(powered, dtype=bool)
    for e, j, params in thermal_effects(inst):
        if e.spec.state_dependent:
            stateful.append((e, j, params))
        else:
            p = np.array(np.broadcast_to(np.asarray(
                e.spec.function(time_s, None, moving, **params), dtype=float), time_s.shape))
            if off is not None:
                p[off] = 0.0
            fixed[:, j] += p
            terms[e.label] = p
    if off is not None:
        fixed[off] -= inst.network.node_power_w
    return fixed, terms, stateful


class HeatLaw:
    """The per-sample heat law P(t_k, T_k) [W] of a run's thermal effects, for
    :func:`thermal.simulate` (one run: temperatures (n_nodes,) -> powers (n_nodes,)) and
    :func:`thermal.simulate_many` (R stacked runs: (R, n_nodes) -> (R, n_nodes)).

    At sample k it is the state-free part ``fixed[k]`` plus each state-dependent effect
    evaluated on its node's temperature; while the unit is off, ``fixed[k]`` alone (which
    then cancels the constant node powers, :func:`fixed_thermal_power`).  An effect gives
    the same value for a float and an array element (the registry's contract for
    state-dependent effects), so a run's bits do not depend on how many runs are stacked.
    """

    def __init__(self, fixed: np.ndarray, time_s: np.ndarray, moving: np.ndarray,
                 on: np.ndarray | None, stateful) -> None:
        self._fixed = fixed
        self._index = {float(t): k for k, t in enumerate(time_s)}
        self._moving = moving.tolist()
        self._on = [True] * len(time_s) if on is None else on.tolist()
        self._calls = [(e.spec.function, j, params) for e, j, params in stateful]
        self.heated_nodes: tuple[int, ...] = tuple(sorted(
            {j for _, j, _ in self._calls}
            | set(np.flatnonzero(np.any(fixed != 0.0, axis=0)).tolist())))
        """Indices of the nodes whose power the law can make non-zero (the others' is 0 at
        every sample): what :func:`thermal.simulate`'s ``heated_nodes`` takes."""

    def __call__(self, t_s: float, temperature_c: np.ndarray) -> np.ndarray:
        """The extra node powers [W] at sample time ``t_s`` [s] (one of the run's samples)
        from the node temperatures ``temperature_c`` [degC], (n,) or (R, n)."""
        k = self._index[t_s]
        fixed = self._fixed[k]
        if not self._on[k]:
            return (fixed.copy() if temperature_c.ndim == 1 else
                    np.repeat(fixed[None, :], temperature_c.shape[0], axis=0))
        if temperature_c.ndim == 1:
            p = fixed.copy()
            for f, j, params in self._calls:
                p[j] += f(t_s, float(temperature_c[j]), self._moving[k], **params)
            return p
        # runs stacked: a few row by row (float arithmetic, cheaper than ufuncs on tiny
        # arrays; each element's sum as the column's would be), more at once
        p = self._fixed[k:k + 1].repeat(temperature_c.shape[0], axis=0)
        m = self._moving[k]
        if temperature_c.shape[0] <= _ROW_BY_ROW:
            for f, j, params in self._calls:
                col = p[:, j]
                for i, v in enumerate(temperature_c[:, j].tolist()):
                    col[i] += f(t_s, v, m, **params)
            return p
        for f, j, params in self._calls:
            p[:, j] += f(t_s, temperature_c[:, j], m, **params)
        return p


def thermal_power(inst: Instrument, time_s: np.ndarray, moving: np.ndarray,
                  powered: np.ndarray | None = None):
    """The heat input of the thermal effects: (power, terms, stateful).

    ``powered``: the power state s(t_k) of a run with power cycles (:mod:`nfs.power`), or
    None (on throughout).  Off, the network's constant node powers are cancelled (an extra
    -P_j) and every thermal effect releases nothing.

    ``power`` is an array (n_samples, n_nodes) when no effect depends on the state, else a
    :class:`HeatLaw` ``power(t_s, temperature_c)`` for :func:`thermal.simulate` (or, with
    temperatures (R, n_nodes) of R stacked runs, for :func:`thermal.simulate_many`: a
    state-dependent effect then gets an array of the runs' node temperatures); ``terms``
    holds each state-free effect's power by label; ``stateful`` lists the state-dependent
    effects (effect, node index, params) to evaluate on the solution afterwards.
    """
    fixed, terms, stateful = fixed_thermal_power(inst, time_s, moving, powered)
    if not stateful:
        return fixed, terms, stateful
    on = None if powered is None else np.asarray(powered, dtype=bool)
    return HeatLaw(fixed, time_s, moving, on, stateful), terms, stateful
