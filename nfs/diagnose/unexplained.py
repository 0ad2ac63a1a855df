"""What the model leaves unexplained: is the drift residual the gyro's noise, and its
cross-correlation with every recorded channel (:func:`nfs.diagnose.diagnose`).

Whiteness is tested against the model's noise (:func:`nfs.noise.whiteness_test`): the
residual window means of each run are whitened with the covariance that its angle random
walk, bias instability and rate random walk imply for those windows (samples at rest only,
:func:`nfs.noise.window_mean_covariance`), the model's fitted drift columns are projected
out (the generalised-least-squares residual), and the Ljung-Box Q of what is left and a
chi-square test of its scale are computed.  On runs the model explains, both are uniform
under the null; a plain Ljung-Box test of the window means would reject every clean run,
since bias instability correlates them.  A model without gyro noise (N = B = K = 0) gets the
plain test, reported as not whitened.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..effects.thermometer import THERMOMETERS
from ..instrument import Instrument
from ..noise import rest_window_segments, whiteness_test, window_mean_covariance
from .columns import PreparedRun
from ..fit.drift_residual import window_means

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


def noise_covariances(inst: Instrument, preps: list[PreparedRun]) -> list[np.ndarray] | None:
    """Covariance [(deg/h)^2] of each run's drift window means under ``inst``'s gyro noise
    (None when the model has none)."""
    g = inst.gyro
    if g.arw_deg_per_rth_h <= 0 and g.bias_instability_dph <= 0:
        return None
    out = []
    for p in preps:
        rd = p.rd
        idx = np.flatnonzero(rd.trusted)
        keep = rd.keep[rd.windows]
        starts, lengths, window = rest_window_segments(idx[keep], rd.windows[keep])
        out.append(window_mean_covariance(
            starts, lengths, rd.cond.sample_rate_hz, window=window,
            arw_deg_per_rth_h=g.arw_deg_per_rth_h, bias_instability_dph=g.bias_instability_dph,
            rrw_deg_per_h_per_rth_h=g.rrw_deg_per_h_per_rth_h))
    return out


def whiteness(inst: Instrument, preps: list[PreparedRun], e_parts: list[np.ndarray],
              alpha: float = 0.01) -> dict[str, Any]:
    """The residual ``e_parts`` (window means per run, after the model's drift columns
    ``p.X`` were fitted) tested against ``inst``'s gyro noise (module docstring)."""
    res = whiteness_test(e_parts, noise_covariances(inst, preps), alpha=alpha,
                         design=[p.X for p in preps])
    return {"Q": res.q, "lags": res.dof, "p_value": res.p_value, "white": res.white,
            "variance_ratio": res.variance_ratio, "variance_p_value": res.variance_p_value,
            "unit_variance": res.unit_variance, "consistent": res.consistent,
            "whitened": res.whitened, "n": res.n, "acf": [float(a) for a in res.acf[:5]],
            "noise_model": {"arw_deg_per_rth_h": inst.gyro.arw_deg_per_rth_h,
                            "bias_instability_dph": inst.gyro.bias_instability_dph,
                            "rrw_deg_per_h_per_rth_h": inst.gyro.rrw_deg_per_h_per_rth_h}}


def unexplained(inst: Instrument, preps: list[PreparedRun], e_parts: list[np.ndarray],
                decimate_s: float) -> dict[str, Any]:
    """Whiteness of the residual window means ``e_parts`` (per run) against ``inst``'s gyro
    noise (:func:`whiteness`, key ``ljung_box``) and their largest cross-correlation (over
    lags up to 30 windows) with the thermometers and their rates, the accelerometers, the
    turntable position's first two harmonics and every ``aux_*``."""
    chans: dict[str, list[np.ndarray]] = {}
    for p in preps:
        run, rd = p.run, p.rd
        t = window_means(rd, np.asarray(run["time_s"], dtype=float))
        series = {}
        for col in THERMOMETERS.values():
            if col in run.columns:
                v = window_means(rd, np.asarray(run[col], dtype=float))
                series[col] = v
                series[f"d{col}/dt"] = np.gradient(v, t) if v.size > 1 else v * 0
        for col in ("acc_x_g", "acc_y_g"):
            if col in run.columns:
                series[col] = window_means(rd, np.asarray(run[col], dtype=float))
        pos = np.radians(np.asarray(run["position_deg"], dtype=float))
        for k in (1, 2):  # first and second harmonics of the turntable position
            suffix = "" if k == 1 else "_2"
            for f, fn in (("cos", np.cos), ("sin", np.sin)):
                v = fn(k * pos)
                v[np.abs(v) < 1e-9] = 0.0  # sin(pi) = 1e-16 is not a signal
                series[f"{f}{suffix}_position"] = window_means(rd, v)
        for col in run.columns:
            if col.startswith("aux_"):
                series[col] = window_means(rd, np.asarray(run[col], dtype=float))
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
    return {"ljung_box": whiteness(inst, preps, e_parts), "cross_correlation": rows,
            "residual_rms_dph": float(np.sqrt(np.mean(np.concatenate(e_parts) ** 2)))}


