"""Fitted values at a bound or beyond what real units have, and the structure each points to.

A fitted parameter that ends on its box (:func:`nfs.fit.params.fit_bounds`) is rarely a
measurement of that parameter: the data pull it there because the model cannot reproduce
them with physical values, and the parameter is the nearest knob.  :func:`bound_advice`
turns the kind of parameter and the side of the box into what to try.

A fit identifies a unit: its numbers are the unit's capacities, conductances, powers, lags
and coefficients, and the one table of ranges (:mod:`nfs.ranges`) says what real units have.
Where the runs push a fitted number beyond its typical range (inside the hard range: the
fit's box never leaves it, :func:`nfs.fit.params.fit_bounds`), the number is rarely a
measurement of an unusual unit: the model lacks a structure and the nearest parameter
stands in for it.  :func:`departures` gives one line per such parameter, with its value,
its standard error, the typical range and what the side it left by points to (a layered
coil, a heat path, a thermometer mounted elsewhere, an effect the model lacks).

The significance is stated, not decided: a departure whose +-2 standard errors reach the
typical range is marked "within 2 sigma of typical".

:func:`fit_warnings` gathers what a fit tells its user in words beside these: a stage that
did not converge, a parameter at a bound or moved far from its start, a parameter the runs
cannot determine, a single run.
"""

from __future__ import annotations

import math
import re
from typing import Mapping, Sequence

from .. import ranges
from ..conditions import chamber_assumption
from ..run import Run, run_caveats
from .soak import SoakAnchor
from .stage import StageReport

__all__ = ["departures", "departure_line", "points_to", "canonical_key", "bound_advice",
           "FAR_FACTOR", "far_from_start", "fit_warnings"]

_COIL_NODE = re.compile(r"^(coil|spool|coil_[a-z0-9_]+|layer[_0-9]*)$")


def canonical_key(path: str) -> str:
    """The key of a fit parameter path as the table of ranges and the file checks name it:
    an effect ``effects.name:target.p`` as ``effects.name.p``."""
    m = re.fullmatch(r"effects\.([^.:]+):[^.]*\.(.+)", path)
    return f"effects.{m.group(1)}.{m.group(2)}" if m else path


def _is_coil_node(node: str) -> bool:
    return bool(_COIL_NODE.match(node)) or node.startswith("coil")


def points_to(path: str, side: str) -> str:
    """What a fitted ``path`` beyond its typical range on ``side`` (``"below"`` or
    ``"above"``) points to: the structure the model likely lacks, in a few words."""
    parts = path.split(".")
    leaf = parts[-1]
    if path.startswith("thermal.nodes."):
        node = ".".join(parts[2:-1])
        coil = _is_coil_node(node)
        if leaf == "capacity_j_per_k":
            if side == "below":
                return (f"the thermometer sees a faster response than {node} can give: "
                        + ("the coil's winding in layers (its faces lead its bulk; "
                           "refine_structure tries the wound coil)" if coil else
                           f"a thermometer on a smaller part than {node}, or {node} split "
                           "in two (a layered part)"))
            return (f"{node} lumps a larger mass than such a part has: a heat path to a larger "
                    f"mass (the housing) or a node between {node} and its heat is missing")
        if leaf == "power_w":
            if side == "below":
                return (f"heat leaves {node} by a heat path the model lacks (a link to the "
                        "housing or the chamber), or its thermometer sits elsewhere")
            if coil:
                return ("heat inside a passive coil: a heater, or heat reaching a coil face "
                        "through a hub or outer-face path the model lacks")
            return f"a heat source is missing near {node} (a heater, a neighbour)"
    if path.startswith("thermal.links."):
        link = ".".join(parts[2:-1])
        if side == "below":
            return (f"a thermal resistance in {link} (a gap, a mount), or the heat goes "
                    "another way (a node between)")
        return f"the ends of {link} behave as one node, or a second path between them is missing"
    if path.startswith("coil."):
        return ("the winding's radial time constant or its face contacts differ from the "
                "drawing's: a contact or a potting the model lacks")
    if path.startswith("thermometers."):
        name = parts[1]
        if leaf == "lag_s":
            if side == "below":
                return (f"the {name} thermometer leads its node: mounted on a faster part "
                        "(nearer the heat)")
            return (f"the {name} thermometer sits behind a conductance: mounted on a larger "
                    "mass, or a node between it and its node")
        if leaf == "offset_c":
            return (f"the {name} thermometer is calibrated off, or the runs were not soaked "
                    "at their T0")
        return f"the {name} thermometer's noise or resolution differs from its datasheet"
    if leaf.startswith("tilt_"):
        return "the table is not levelled, or the accelerometer axes are not the model's"
    if path.startswith("accelerometers."):
        return "an accelerometer beyond its datasheet: check its mounting and axes"
    if path.startswith("gyro."):
        return "a gyro beyond its class: check the data's units and the gyro's calibration"
    if path.startswith("effects.tec_power") and leaf in ("c_h", "c_c"):
        return ("the source's extra power does not follow the modelled TEC law (another set "
                "point, or another law)")
    if path.startswith("effects.heat_source:") and leaf == "power" and side == "above":
        node = path[len("effects.heat_source:"):].rsplit(".", 1)[0]
        if _is_coil_node(node):
            return ("more heat than a passive winding can release: a heater in the coil, "
                    f"or heat reaching {node} through a hub or outer-face path the model "
                    "lacks (a link, not a source)")
    if path.startswith("effects."):
        label = path[len("effects."):].rsplit(".", 1)[0]
        if side == "below":
            return f"{label} is weaker here than in typical units (or absent)"
        return (f"{label} is standing in for an effect the model lacks (nfs diagnose names "
                "it)")
    return "the model lacks a structure here"


def departure_line(path: str, value: float, stderr: float = math.nan) -> str | None:
    """One line for a fitted ``value`` of ``path`` beyond its typical range, or None when
    it lies inside (or the table has no row, or the value switches the term off)."""
    row = ranges.find(path)
    if row is None or not row.unusual(value):
        return None
    lo, hi = row.typical
    v = abs(value) if row.magnitude else value
    side = "below" if v < lo else "above"
    unit = f" {row.unit}" if row.unit else ""
    err = f" +- {stderr:.2g}" if math.isfinite(stderr) else ""
    near = ""
    if math.isfinite(stderr) and (v + 2 * stderr >= lo if side == "below"
                                   else v - 2 * stderr <= hi):
        near = " (within 2 sigma of typical)"
    return (f"{path} = {value:.4g}{err}{unit}, {side} the typical {row.typical_text()}"
            f"{near}: {points_to(path, side)}")


def departures(params: Mapping[str, float],
               stderr: Mapping[str, float] | None = None) -> dict[str, str]:
    """{path: one line} for every fitted parameter beyond its typical range
    (:func:`departure_line`), in the order of ``params``."""
    stderr = stderr or {}
    out = {}
    for p, v in params.items():
        line = departure_line(p, float(v), float(stderr.get(p, math.nan)))
        if line is not None:
            out[p] = line
    return out


def _side(value: float, bounds: tuple[float, float]) -> str:
    lo, hi = bounds
    if not math.isfinite(hi) or abs(value - lo) <= abs(hi - value):
        return "below"
    return "above"


def bound_advice(path: str, value: float, bounds: tuple[float, float]) -> str:
    """One sentence: what the parameter ``path`` at ``value`` on its box ``bounds`` suggests
    to try (the side of the box it presses on, and :func:`points_to` of that side)."""
    side = _side(value, bounds)
    lo, hi = bounds
    which = f"its floor {lo:g}" if side == "below" else f"its ceiling {hi:g}"
    return f"{path} presses on {which}: {points_to(path, side)}"


#: A fitted value this many times its start (or its inverse), or this many prior widths
#: away, is reported as moved far: one effect or node explaining what another should.
FAR_FACTOR = 3.0


def _has_scale(path: str, kind: str) -> bool:
    """A parameter whose size, not only its sign, is physics: a capacity, conductance,
    power, lag or an effect coefficient (an offset, a bias or a tilt is a zero-centred
    number, judged by its prior width only)."""
    leaf = path.rsplit(".", 1)[-1]
    if kind in ("thermal", "thermometer"):
        return leaf != "offset_c"
    return path.startswith("effects.")


def far_from_start(start: float, value: float, prior_shift: float | None,
                   by_ratio: bool = True) -> str:
    """'from a to b (k times; s prior widths)' when ``value`` is far from ``start``
    (with ``by_ratio``: :data:`FAR_FACTOR` times or its inverse, or a change of sign; always:
    that many prior widths), else ''."""
    ratio = value / start if start else math.nan
    far = (by_ratio and start != 0 and (ratio > FAR_FACTOR or ratio < 1.0 / FAR_FACTOR)) or (
        prior_shift is not None and math.isfinite(prior_shift)
        and abs(prior_shift) > FAR_FACTOR)
    if not far:
        return ""
    what = [f"{ratio:.2g} times" if math.isfinite(ratio) else ""]
    if prior_shift is not None and math.isfinite(prior_shift):
        what.append(f"{prior_shift:+.1f} prior widths")
    return f"from {start:.4g} to {value:.4g} (" + "; ".join(w for w in what if w) + ")"


def fit_warnings(runs: Sequence[Run], paths: Sequence[str], params: Mapping[str, float],
                 initial_params: Mapping[str, float], kinds: Mapping[str, str],
                 bounds: Mapping[str, tuple[float, float]], reports: Mapping[str, StageReport],
                 at_bound: Sequence[str], advice: Mapping[str, str],
                 shifts: Mapping[str, float], unident: Mapping[str, str],
                 soak: SoakAnchor | None, departed: Sequence[str] = ()) -> list[str]:
    """Everything a user should know of a fit, in words, in this order: a stage that did
    not converge, a parameter at a bound (with its ``advice``) or moved far from its start
    (:func:`far_from_start`; ``shifts``: in prior widths), the soak anchor's warnings, a
    chamber assumed, what the reader accepted in a run (:func:`nfs.run.run_caveats`), a
    parameter not identifiable (``unident``: with the reason), a single
    run.  ``kinds``: the kind of every parameter path (:data:`nfs.parameters.PARAM_KINDS`).
    A parameter in ``departed`` (beyond its typical range: :mod:`nfs.fit.departures` says what
    it points to) gets no "moved" warning besides."""
    warnings = []
    for s, rep in reports.items():
        if not rep.converged:
            warnings.append(f"{s} stage did not converge ({rep.nfev} evaluations): {rep.message}")
    for p in at_bound:
        warnings.append(f"{p} ended at its bound {bounds[p]} (value {params[p]:.6g}): "
                        f"{advice[p]}")
    for p in paths:
        if p not in at_bound and p not in unident and p not in departed:
            far = far_from_start(initial_params[p], params[p], shifts.get(p),
                                 by_ratio=_has_scale(p, kinds[p]))
            if far:
                warnings.append(f"{p} moved {far}: the runs push it far from the model's "
                                "value, where it may stand in for an effect the model lacks "
                                "(nfs diagnose)")
    if soak is not None:
        warnings.extend(soak.warnings)
    if chamber_assumption(runs):
        warnings.append(chamber_assumption(runs))
    warnings.extend(run_caveats(runs))
    for p, why in unident.items():
        warnings.append(f"{p} is not identifiable: {why}")
    if len(runs) == 1:
        t0 = runs[0].meta.start_temperature_c
        warnings.append(f"a single run (T0 = {t0:g} C): parameters whose effect depends on "
                        "the start temperature cannot be separated; "
                        + (", ".join(unident) if unident else "none flagged by the Jacobian")
                        + " reported as not identifiable")
    return warnings
