"""What a fit tells its user in words: a stage that did not converge, a parameter at a bound
or moved far from its start, a parameter the runs cannot determine, a single run."""

from __future__ import annotations

import math
from typing import Mapping, Sequence

from ..conditions import chamber_assumption
from ..run import Run, run_caveats
from .soak import SoakAnchor
from .stage import StageReport

__all__ = ["FAR_FACTOR", "far_from_start", "fit_warnings"]

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
