"""What the model leaves unexplained: whiteness of the drift residual and its
cross-correlation with every recorded channel (:func:`nfs.diagnose.diagnose`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..effects.thermometer import THERMOMETERS
from .design import PreparedRun
from .fit import _block
from .stats import _ljung_box

__all__ = ["unexplained"]

_MAX_LAG = 30


def _xcorr(e: list[np.ndarray], x: list[np.ndarray], max_lag: int) -> tuple[float, int]:
    """max |r| over lags (residual lagging the channel by ``lag`` windows) within runs."""
    mx = np.mean(np.concatenate(x))
    me = np.mean(np.concatenate(e))
    xs = [v - mx for v in x]
    es = [v - me for v in e]
    den = math.sqrt(sum(float(v @ v) for v in xs) * sum(float(v @ v) for v in es))
    if den == 0:
        return 0.0, 0
    best, lag = 0.0, 0
    for L in range(-max_lag, max_lag + 1):
        s = 0.0
        for ev, xv in zip(es, xs):
            m = ev.size
            if abs(L) >= m:
                continue
            s += float(ev[L:] @ xv[:m - L]) if L >= 0 else float(ev[:m + L] @ xv[-L:])
        r = s / den
        if abs(r) > abs(best):
            best, lag = r, L
    return best, lag


def unexplained(preps: list[PreparedRun], e_parts: list[np.ndarray], decimate_s: float
                ) -> dict[str, Any]:
    """Ljung-Box test of the residual window means ``e_parts`` (per run) and their largest
    cross-correlation (over lags up to 30 windows) with the thermometers and their rates,
    the accelerometers, the turntable position's first two harmonics and every ``aux_*``."""
    chans: dict[str, list[np.ndarray]] = {}
    for p in preps:
        run, rd = p.run, p.rd
        t = _block(rd, np.asarray(run["time_s"], dtype=float))
        series = {}
        for col in THERMOMETERS.values():
            if col in run.columns:
                v = _block(rd, np.asarray(run[col], dtype=float))
                series[col] = v
                series[f"d{col}/dt"] = np.gradient(v, t) if v.size > 1 else v * 0
        for col in ("acc_x_g", "acc_y_g"):
            if col in run.columns:
                series[col] = _block(rd, np.asarray(run[col], dtype=float))
        pos = np.radians(np.asarray(run["position_deg"], dtype=float))
        for k in (1, 2):  # first and second harmonics of the turntable position
            suffix = "" if k == 1 else "_2"
            for f, fn in (("cos", np.cos), ("sin", np.sin)):
                v = fn(k * pos)
                v[np.abs(v) < 1e-9] = 0.0  # sin(pi) = 1e-16 is not a signal
                series[f"{f}{suffix}_position"] = _block(rd, v)
        for col in run.columns:
            if col.startswith("aux_"):
                series[col] = _block(rd, np.asarray(run[col], dtype=float))
        for k, v in series.items():
            chans.setdefault(k, []).append(v)
    rows = []
    for name, parts in chans.items():
        if len(parts) != len(preps):
            continue
        r, lag = _xcorr(e_parts, parts, _MAX_LAG)
        rows.append({"channel": name, "max_abs_r": abs(r), "r": r,
                     "lag_s": lag * decimate_s})
    rows.sort(key=lambda d: -d["max_abs_r"])
    return {"ljung_box": _ljung_box(e_parts), "cross_correlation": rows,
            "residual_rms_dph": float(np.sqrt(np.mean(np.concatenate(e_parts) ** 2)))}


