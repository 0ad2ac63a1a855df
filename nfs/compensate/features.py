"""Named features from the three thermometers (and any aux channel) for drift compensation.

The compensators learn the FOG drift from what the instrument measures: its three built-in
thermometers (docs/physics.md section 6; the FOG start-up paper uses their temperatures,
temperature rates and
gradients), the T x dT/dt product of Cheng et al. (2015), and auxiliary electrical channels such as
Tao et al.'s (2019)
oscillator voltage.  Features are picked by name, so a user composes inputs::

    compute_features(run, ["T_fog", "dT_fog", "G_fog_acc_x", "aux_tec_power_w"])
    compute_features(run, "seed004")          # a named set
    compute_features(run, ["T_*", "dT_*"])    # patterns

Names
-----
``T_<th>``            thermometer reading [degC], th in fog, acc_x, acc_y
``dT_<th>``           its rate [K/min]: a Savitzky-Golay derivative within what the features
                      mode allows (cycle, offline; :mod:`nfs.compensate.rates`) or a
                      Kalman filter of the readings so far (causal;
                      :mod:`nfs.compensate.kalman_rate`)
``G_<a>_<b>``         gradient T_a - T_b [K] between two thermometers
``TdT_<th>``          (T_th - T_ref) dT_th/dt [K K/min] (Cheng et al.'s (2015) product term)
``aux_*``             any auxiliary column of the run, as recorded
``time_min``          time since power-on [min] (not a thermometer: not in the seed sets)

Modes
-----
A feature at sample t uses only what the features mode allows (:mod:`nfs.compensate.modes`):
``cycle`` (the default) the readings up to the end of t's north-finding cycle, ``causal``
the readings up to t, ``offline`` the whole run.  Only the rates (``dT_``, ``TdT_``) look
beyond t; the other features are the readings at t.  A compensator is trained and applied
in one mode.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from ..constants import T_REF_C
from ..errors import NfsError
from .kalman_rate import CAUSAL_RATE, kalman_rate_k_per_min
from .modes import (
    DEFAULT_FEATURE_MODE,
    FEATURE_MODES,
    check_features_mode,
    horizon_index,
    in_cycle_mask,
)
from .rates import rate_k_per_min

__all__ = [
    "FEATURE_MODES",
    "FEATURE_SETS",
    "RATE_WINDOW",
    "THERMOMETER_COLUMNS",
    "FeatureError",
    "RateFilter",
    "available_features",
    "compute_features",
    "feature_columns",
    "rate_k_per_min",
    "resolve_features",
]

#: Thermometer short names -> measurement columns (docs/measurement-format.md).
THERMOMETER_COLUMNS = {"fog": "temp_fog_c", "acc_x": "temp_acc_x_c", "acc_y": "temp_acc_y_c"}
_TH = tuple(THERMOMETER_COLUMNS)
_PAIRS = (("fog", "acc_x"), ("fog", "acc_y"), ("acc_x", "acc_y"))

#: Named feature sets, after the papers.
FEATURE_SETS: dict[str, tuple[str, ...]] = {
    # the FOG start-up paper: temperature, temperature rate and gradient of the three thermometers
    "seed004": tuple([f"T_{t}" for t in _TH] + [f"dT_{t}" for t in _TH]
                     + [f"G_{a}_{b}" for a, b in _PAIRS]),
    # Cheng et al. (2015): T, dT and T x dT of the coil (here: the FOG thermometer)
    "seed001": ("T_fog", "dT_fog", "TdT_fog"),
    # Tao et al. (2019): T, dT/dt and the auxiliary electrical signal(s)
    "seed000": ("T_fog", "dT_fog", "aux_*"),
    # every thermometer feature
    "thermometers": tuple([f"T_{t}" for t in _TH] + [f"dT_{t}" for t in _TH]
                          + [f"G_{a}_{b}" for a, b in _PAIRS] + [f"TdT_{t}" for t in _TH]),
}


@dataclass(frozen=True)
class RateFilter:
    """The local-polynomial derivative of the offline and cycle rate features."""

    window_s: float
    """Window length [s]."""
    polyorder: int
    """Order of the polynomial fitted over the window."""


#: The rate filter of the offline and cycle modes: the FOG start-up paper's 121 s quadratic, centred
#: wherever the horizon allows (:mod:`nfs.compensate.rates`).  The causal mode's rate is
#: :data:`nfs.compensate.kalman_rate.CAUSAL_RATE`.
RATE_WINDOW = RateFilter(121.0, 2)


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
                     mode: str = DEFAULT_FEATURE_MODE, rate_window_s: float | None = None,
                     rate_polyorder: int | None = None, t_ref_c: float = T_REF_C
                     ) -> tuple[np.ndarray, list[str]]:
    """The feature matrix X (n_samples, n_features) of a run and the feature names.

    Parameters
    ----------
    run : Run
        A :class:`~nfs.run.Run` (or any object with ``columns``, ``name`` and,
        for ``cycle`` mode, ``meta``).
    spec : str or sequence of str
        Feature names, sets or patterns (:func:`resolve_features`).
    mode : str
        What a feature at t may use (:mod:`nfs.compensate.modes`): ``cycle`` (data up to
        the end of t's north-finding cycle), ``causal`` (up to t) or ``offline`` (the whole
        run).  Train and apply a compensator in the same mode.
    rate_window_s : float, optional
        Window of the cycle and offline rate features [s] (default:
        :data:`RATE_WINDOW`, 121 s); the causal rate has none.
    rate_polyorder : int, optional
        Order of their local polynomial (default 2).
    t_ref_c : float
        T_ref of the ``TdT_`` features [degC].

    Returns
    -------
    (ndarray, list of str)
        X and the feature names of its columns.
    """
    mode = check_features_mode(mode)
    if mode == "causal" and rate_window_s is not None:
        raise FeatureError("the causal rate is a Kalman filter without a window: "
                           "rate_window_s applies to the cycle and offline modes")
    cols = run.columns
    names = resolve_features(spec, cols.keys())
    t = _column(cols, "time_s", run.name)
    window = RATE_WINDOW.window_s if rate_window_s is None else float(rate_window_s)
    order = RATE_WINDOW.polyorder if rate_polyorder is None else int(rate_polyorder)
    horizon = None
    if mode == "cycle" and any(n.partition("_")[0] in ("dT", "TdT") for n in names):
        horizon = horizon_index(run, mode)
        outside = ~in_cycle_mask(run)          # the moves, a partial cycle: causal
    cache: dict[str, np.ndarray] = {}

    def temp(th: str) -> np.ndarray:
        key = f"T_{th}"
        if key not in cache:
            cache[key] = _column(cols, THERMOMETER_COLUMNS[th], run.name)
        return cache[key]

    def rate(th: str) -> np.ndarray:
        key = f"dT_{th}"
        if key not in cache:
            if mode == "causal":
                cache[key] = kalman_rate_k_per_min(temp(th), t, CAUSAL_RATE)
            elif mode == "offline":
                cache[key] = rate_k_per_min(temp(th), t, window, order)
            else:
                r = rate_k_per_min(temp(th), t, window, order, horizon=horizon)
                if outside.any():
                    r[outside] = kalman_rate_k_per_min(temp(th), t, CAUSAL_RATE)[outside]
                cache[key] = r
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
