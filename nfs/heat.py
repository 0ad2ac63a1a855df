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

__all__ = ["thermal_effects", "fixed_thermal_power", "thermal_power"]

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


def thermal_power(inst: Instrument, time_s: np.ndarray, moving: np.ndarray,
                  powered: np.ndarray | None = None):
    """The heat input of the thermal effects: (power, terms, stateful).

    ``powered``: the power state s(t_k) of a run with power cycles (:mod:`nfs.power`), or
    None (on throughout).  Off, the network's constant node powers are cancelled (an extra
    -P_j) and every thermal effect releases nothing.

    ``power`` is an array (n_samples, n_nodes) when no effect depends on the state, else a
    per-sample law ``power(t_s, temperature_c)`` for :func:`thermal.simulate` (or, with
    temperatures (R, n_nodes) of R stacked runs, for :func:`thermal.simulate_many`: a
    state-dependent effect then gets an array of the runs' node temperatures); ``terms``
    holds each state-free effect's power by label; ``stateful`` lists the state-dependent
    effects (effect, node index, params) to evaluate on the solution afterwards.
    """
    fixed, terms, stateful = fixed_thermal_power(inst, time_s, moving, powered)
    if not stateful:
        return fixed, terms, stateful
    off = None if powered is None else ~np.asarray(powered, dtype=bool)
    # The per-sample law: the state-dependent sources from the current node temperature,
    # held over the sample interval by the exact solver.
    index = {float(t): k for k, t in enumerate(time_s)}
    moving_list = moving.tolist()
    on_list = [True] * len(time_s) if off is None else (~off).tolist()
    calls = [(e.spec.function, j, params) for e, j, params in stateful]

    def law(t_s: float, temperature_c: np.ndarray) -> np.ndarray:
        k = index[t_s]
        if not on_list[k]:
            return (fixed[k].copy() if temperature_c.ndim == 1 else
                    np.repeat(fixed[k][None, :], temperature_c.shape[0], axis=0))
        if temperature_c.ndim == 1:
            p = fixed[k].copy()
            for f, j, params in calls:
                p[j] += f(t_s, float(temperature_c[j]), moving_list[k], **params)
            return p
        # runs stacked (thermal.simulate_many): the law gets every run's node temperature;
        # a few runs row by row (float arithmetic, cheaper than ufuncs on tiny arrays), more
        # at once.  An effect gives the same value for a float and an array element (the
        # registry's contract for state-dependent effects), so the bits do not depend on R.
        p = np.repeat(fixed[k][None, :], temperature_c.shape[0], axis=0)
        if temperature_c.shape[0] <= _ROW_BY_ROW:
            m = moving_list[k]
            for f, j, params in calls:
                p[:, j] += [f(t_s, v, m, **params) for v in temperature_c[:, j].tolist()]
            return p
        for f, j, params in calls:
            p[:, j] += f(t_s, temperature_c[:, j], moving_list[k], **params)
        return p

    return law, terms, stateful
