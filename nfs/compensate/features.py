"""Named features from the three thermometers (and any aux channel) for drift compensation.

The compensators learn the FOG drift from what the instrument measures: its three built-in
thermometers (physics.md section 6; seed 004 uses their temperatures, temperature rates and
gradients), the T x dT/dt product of seed 001, and auxiliary electrical channels such as seed
000's oscillator voltage.  Features are picked by name, so a user composes inputs::

    compute_features(run, ["T_fog", "dT_fog", "G_fog_acc_x", "aux_tec_power_w"])
    compute_features(run, "seed004")          # a named set
    compute_features(run, ["T_*", "dT_*"])    # patterns

Names
-----
``T_<th>``            thermometer reading [degC], th in fog, acc_x, acc_y
``dT_<th>``           its rate [K/min] (Savitzky-Golay derivative, see :func:`rate_k_per_min`)
``G_<a>_<b>``         gradient T_a - T_b [K] between two thermometers
``TdT_<th>``          (T_th - T_ref) dT_th/dt [K K/min] (seed 001's product term)
``aux_*``             any auxiliary column of the run, as recorded
``time_min``          time since power-on [min] (not a thermometer: not in the seed sets)
"""

from __future__ import annotations

import fnmatch
from typing import Iterable, Sequence

import numpy as np
from scipy.signal import savgol_filter

from ..constants import T_REF_C
from ..errors import NfsError

__all__ = ["THERMOMETER_COLUMNS", "FEATURE_SETS", "available_features", "resolve_features",
           "compute_features", "rate_k_per_min", "FeatureError", "feature_columns"]

#: Thermometer short names -> measurement columns (measurement-format.md).
THERMOMETER_COLUMNS = {"fog": "temp_fog_c", "acc_x": "temp_acc_x_c", "acc_y": "temp_acc_y_c"}
_TH = tuple(THERMOMETER_COLUMNS)
_PAIRS = (("fog", "acc_x"), ("fog", "acc_y"), ("acc_x", "acc_y"))

#: Named feature sets, after the papers.
FEATURE_SETS: dict[str, tuple[str, ...]] = {
    # seed 004: temperature, temperature rate and gradient of the three thermometers
    "seed004": tuple([f"T_{t}" for t in _TH] + [f"dT_{t}" for t in _TH]
                     + [f"G_{a}_{b}" for a, b in _PAIRS]),
    # seed 001: T, dT and T x dT of the coil (here: the FOG thermometer)
    "seed001": ("T_fog", "dT_fog", "TdT_fog"),
    # seed 000: T, dT/dt and the auxiliary electrical signal(s)
    "seed000": ("T_fog", "dT_fog", "aux_*"),
    # every thermometer feature
    "thermometers": tuple([f"T_{t}" for t in _TH] + [f"dT_{t}" for t in _TH]
                          + [f"G_{a}_{b}" for a, b in _PAIRS] + [f"TdT_{t}" for t in _TH]),
}


class FeatureError(NfsError):
    """An unknown feature name or a run that lacks a feature's input channel."""


def _builtin_names() -> list[str]:
    return (
        [f"T_{t}" for t in _TH] + [f"dT_{t}" for t in _TH]
        + [f"G_{a}_{b}" for a in _TH for b in _TH if a != b]
        + [f"TdT_{t}" for t in _TH] + ["time_min"])


def available_features(columns: Iterable[str] = ()) -> list[str]:
    """Every feature name (the aux_* ones of ``columns`` included)."""
    return _builtin_names() + sorted(c for c in columns if c.startswith("aux_"))


def resolve_features(spec: str | Sequence[str], columns: Iterable[str] = ()) -> list[str]:
    """Expand set names (``seed004``) and patterns (``dT_*``, ``aux_*``) into feature names.

    Raises FeatureError naming an unknown feature and listing the valid names and sets.
    """
    columns = list(columns)
    items = [spec] if isinstance(spec, str) else list(spec)
    valid = available_features(columns)
    out: list[str] = []
    for item in items:
        expanded = FEATURE_SETS.get(item, (item,))
        for name in expanded:
            if any(ch in name for ch in "*?["):
                matches = [v for v in valid if fnmatch.fnmatchcase(v, name)]
                if not matches and not name.startswith("aux_"):
                    raise FeatureError(f"feature pattern '{name}' matches nothing")
            elif name in valid or name.startswith("aux_"):
                matches = [name]
            else:
                raise FeatureError(
                    f"unknown feature '{name}'; features: {', '.join(valid)}; sets: "
                    + ", ".join(FEATURE_SETS))
            out.extend(m for m in matches if m not in out)
    if not out:
        raise FeatureError(f"no features selected by {spec!r}")
    return out


def rate_k_per_min(temp_c: np.ndarray, time_s: np.ndarray, window_s: float = 121.0,
                   polyorder: int = 2) -> np.ndarray:
    """dT/dt [K/min] by a Savitzky-Golay derivative (Savitzky & Golay 1964, Anal. Chem. 36(8)).

    A least-squares polynomial of order ``polyorder`` over a centred window of ``window_s``
    is differentiated at its centre.  A finite difference of a thermometer quantised to
    0.0625 K would be a train of spikes; the local fit averages the quantisation steps
    (a linear fit over W samples of noise sigma has a slope error sigma sqrt(12 / W^3) per
    sample).  The ends use a fit over the first / last window (``mode="interp"``).
    NaN samples are interpolated first.
    """
    t = np.asarray(time_s, dtype=float)
    x = np.asarray(temp_c, dtype=float)
    ok = np.isfinite(x)
    if not ok.all():
        if ok.sum() < 2:
            return np.full_like(x, np.nan)
        x = np.interp(t, t[ok], x[ok])
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    w = int(round(window_s / dt)) | 1          # odd number of samples
    w = min(w, x.size if x.size % 2 else x.size - 1)
    if w <= polyorder:
        return np.gradient(x, t) * 60.0
    return savgol_filter(x, w, polyorder, deriv=1, delta=dt, mode="interp") * 60.0


def feature_columns(name: str) -> list[str]:
    """The measurement columns a feature is computed from."""
    if name.startswith("aux_"):
        return [name]
    if name == "time_min":
        return ["time_s"]
    kind, _, rest = name.partition("_")
    if kind == "G":
        return [THERMOMETER_COLUMNS[t] for t in _split_pair(rest)]
    if rest in THERMOMETER_COLUMNS:
        return [THERMOMETER_COLUMNS[rest]]
    raise FeatureError(f"unknown feature '{name}'")


def _column(columns: dict, name: str, run_name: str) -> np.ndarray:
    try:
        return np.asarray(columns[name], dtype=float)
    except KeyError:
        raise FeatureError(f"run '{run_name}' has no column '{name}' needed by the "
                           "compensator's features") from None


def compute_features(run, spec: str | Sequence[str] = "seed004", *,
                     rate_window_s: float = 121.0, t_ref_c: float = T_REF_C
                     ) -> tuple[np.ndarray, list[str]]:
    """The feature matrix X (n_samples, n_features) of a run and the feature names.

    ``run`` is a :class:`~nfs.io.measurement.Run` (or any object with ``columns`` and
    ``name``).
    """
    cols = run.columns
    names = resolve_features(spec, cols.keys())
    t = _column(cols, "time_s", run.name)
    cache: dict[str, np.ndarray] = {}

    def temp(th: str) -> np.ndarray:
        key = f"T_{th}"
        if key not in cache:
            cache[key] = _column(cols, THERMOMETER_COLUMNS[th], run.name)
        return cache[key]

    def rate(th: str) -> np.ndarray:
        key = f"dT_{th}"
        if key not in cache:
            cache[key] = rate_k_per_min(temp(th), t, rate_window_s)
        return cache[key]

    out = []
    for name in names:
        kind, _, rest = name.partition("_")
        if name.startswith("aux_"):
            out.append(_column(cols, name, run.name))
        elif name == "time_min":
            out.append(t / 60.0)
        elif kind == "T":
            out.append(temp(rest))
        elif kind == "dT":
            out.append(rate(rest))
        elif kind == "TdT":
            out.append((temp(rest) - t_ref_c) * rate(rest))
        elif kind == "G":
            a, b = _split_pair(rest)
            out.append(temp(a) - temp(b))
        else:  # pragma: no cover - resolve_features guards this
            raise FeatureError(f"unknown feature '{name}'")
    return np.column_stack(out), names


def _split_pair(rest: str) -> tuple[str, str]:
    for a in _TH:
        if rest.startswith(a + "_") and rest[len(a) + 1:] in _TH:
            return a, rest[len(a) + 1:]
    raise FeatureError(f"bad gradient feature 'G_{rest}'")
