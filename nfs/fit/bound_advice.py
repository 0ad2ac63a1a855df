"""What a parameter at a bound says about the model's structure, and where else to start.

A fitted parameter that ends on its box (:func:`nfs.fit.params.fit_bounds`) is
rarely a measurement of that parameter: the data pull it there because the model cannot
reproduce them with physical values, and the parameter is the nearest knob.
:func:`bound_advice` turns the kind of parameter and the side of the box into what to try.

:func:`perturbed_starts` gives the deterministic extra starts of the thermal stage (the
network's time constants slowed and sped up), so that a stage that would stop in a corner
from the preset gets another chance; the fit keeps the start of lowest cost.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

__all__ = ["bound_advice", "perturbed_starts", "START_FACTOR"]

#: Relative perturbation of capacities and conductances in the extra starts.
START_FACTOR = 0.3


def _side(value: float, bounds: tuple[float, float]) -> str:
    lo, hi = bounds
    if not math.isfinite(hi) or abs(value - lo) <= abs(hi - value):
        return "low"
    return "high"


def bound_advice(path: str, value: float, bounds: tuple[float, float]) -> str:
    """One sentence: what the parameter ``path`` at ``value`` on ``bounds`` suggests to try."""
    side = _side(value, bounds)
    parts = path.split(".")
    leaf = parts[-1]
    if path.startswith("thermal.nodes."):
        node = ".".join(parts[2:-1])
        if leaf == "power_w":
            if side == "low":
                return (f"the {node} power wants to be < 0: the model lacks a heat path (e.g. a "
                        f"link from {node} to the coil or the housing), or the thermometer that "
                        f"sees {node} sits elsewhere (check its node weights)")
            return (f"the {node} power wants more than 10x the preset: a heat source is missing "
                    f"near {node}, or {node}'s link to the chamber is too strong")
        if side == "low":
            return (f"the {node} capacity wants to vanish: the thermometer sees a faster "
                    f"response than {node} can give; it may sit on another node (electronics), "
                    f"its lag may be too long, or {node} lacks a direct link to its heat source")
        return (f"the {node} capacity wants more than its box allows (10x the preset, or a decade "
                f"above what such a node holds): the thermometer sees a "
                f"larger mass (weights toward the housing), or a node is missing between "
                f"{node} and the heat")
    if path.startswith("thermal.links."):
        link = ".".join(parts[2:-1])
        if side == "low":
            return (f"the link {link} wants to vanish: the heat takes another path between "
                    "these nodes (add the node or link it passes through)")
        return (f"the link {link} wants to be stronger than its box allows (10x the preset, or a "
                "decade above what such a link conducts): the two ends behave as one node "
                "(merge them), or a second path between them is missing")
    if path.startswith("thermometers."):
        name = parts[1]
        if leaf == "lag_s":
            if side == "low":
                return (f"the {name} thermometer wants no lag: it leads its node; it sits on "
                        "a faster node (e.g. the electronics) or nearer the heat")
            return (f"the {name} thermometer lags far more than a sensor's 10-60 s: it sees a "
                    "larger mass than its node (weights toward another node, or a missing "
                    "node between)")
        if leaf == "offset_c":
            return (f"the {name} offset exceeds the box: the runs were not soaked at T0, a "
                    "header's T0 is wrong, or the thermometer sits on another node")
    if leaf.startswith("tilt_"):
        return ("the tilt leaves the +-1 deg box: the table is not levelled, or the "
                "accelerometer axes are not those of the model (sign, misalignment)")
    if path.startswith("effects."):
        label = path[len("effects."):].rsplit(".", 1)[0]
        if leaf in ("c_h", "c_c"):
            return (f"the {label} slope {leaf} wants to be "
                    + ("negative" if side == "low" else "10x the preset")
                    + ": the source's extra power does not follow the modelled TEC law "
                      "(another set point, or another law)")
        return (f"{path} wants to leave its box: {label} is mimicking an effect the model "
                "lacks (nfs diagnose ranks the candidates)")
    return (f"{path} wants to leave its box: the data push it further; the model lacks an "
            "effect or has the wrong structure")


def perturbed_starts(paths: Sequence[str], x0: np.ndarray, lb: np.ndarray, ub: np.ndarray,
                     factor: float = START_FACTOR) -> list[np.ndarray]:
    """Extra starts: every capacity x(1 + f) with every conductance x(1 - f), and the reverse.

    The first slows every time constant C/G of the network by (1 + f)/(1 - f) (x1.9 at
    f = 0.3), the second speeds it up as much; powers, lags and offsets keep their start.
    Clipped into the box.  Empty when no capacity or conductance is free.
    """
    cap = np.array([p.endswith(".capacity_j_per_k") for p in paths])
    cond = np.array([p.endswith(".conductance_w_per_k") for p in paths])
    if not (cap.any() or cond.any()):
        return []
    out = []
    for sign in (+1.0, -1.0):
        x = np.array(x0, dtype=float)
        x[cap] *= 1.0 + sign * factor
        x[cond] *= 1.0 - sign * factor
        out.append(np.clip(x, lb, ub))
    return out
