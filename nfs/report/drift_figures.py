"""Figures of the papers' chamber experiments: the drift against temperature and the residual
against time, before and after compensation, each with the paper's published figure beside
ours.

- A drift table of a chamber program's cycles or of whole runs
  (:class:`~nfs.studies.cycle_study.CycleStudy`, Tao et al. 2019 and Cheng et al. 2015):
  :func:`plot_drift_vs_temperature` (the separated drift less the constant calibration, and
  the drift less each row's prediction, against the FOG thermometer: a loop is thermal
  hysteresis, a rate term the model lacks) and :func:`plot_residual_vs_time` (the 100 s
  means of the compensated bias, whose standard deviation is Tao et al.'s bias stability,
  with +-1 bias stability here and in the paper; the chamber's ramps shaded).
- A parameter-level study (:class:`~nfs.studies.parameter_study.ParameterStudy`, Liang et al.
  2021): :func:`plot_parameters_vs_temperature` (each cycle's calibrated parameter against
  its sensor's thermometer, with every model's curve) and :func:`plot_parameter_residuals`
  (calibrated minus predicted on the test cycles: the constant, before compensation, and
  the models, after).

Signed quantities get limits symmetric about 0; every line and band is labelled in words
and units; legends stand beside the panels, off the data.  Figures are made without pyplot.
"""

from __future__ import annotations

import io
import math
import textwrap

import numpy as np
from matplotlib.figure import Figure

from ..studies.cycle_study import BIAS_WINDOW_S, UNCOMPENSATED
from .reference import CHENG2015_TABLE2_MSD, LIANG2021_RVR_OVER_LS_PCT, TAO2019_BIAS_STABILITY

__all__ = ["plot_drift_vs_temperature", "plot_residual_vs_time",
           "plot_parameters_vs_temperature", "plot_parameter_residuals", "png_bytes"]

#: Colour of the uncompensated row (the methods take C0, C1, ...).
_BEFORE = "0.35"
#: Width of a title line [characters].
_WRAP = 140


def png_bytes(fig: Figure) -> bytes:
    """The figure as PNG bytes (metadata pinned: the same figure, the same bytes)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    return buf.getvalue()


def _symmetric(ax, values, pad: float = 1.08) -> None:
    """y limits symmetric about 0 that hold every finite value of ``values``."""
    v = np.concatenate([np.abs(np.asarray(x, dtype=float)).ravel() for x in values])
    v = v[np.isfinite(v)]
    r = float(v.max()) if v.size else 1.0
    ax.set_ylim(-pad * (r or 1e-9), pad * (r or 1e-9))
    ax.axhline(0.0, color="k", lw=0.5)


def _plus_minus(ax, value: float, **kw) -> None:
    """Horizontal lines at +value and -value across the axes, one labelled artist."""
    ax.plot([0.0, 1.0, np.nan, 0.0, 1.0], [value, value, np.nan, -value, -value],
            transform=ax.get_yaxis_transform(), **kw)


def _beside(ax) -> None:
    """The axes' legend beside it, right, off the data."""
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)


def _below(ax, ncol: int = 2) -> None:
    """The axes' legend below it, off the data (panels side by side keep their width)."""
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=ncol,
              frameon=False)


def _title(fig: Figure, lines: list[str]) -> None:
    fig.suptitle("\n".join(w for line in lines for w in textwrap.wrap(line, _WRAP)),
                 fontsize=9)


def _colours(study) -> dict[str, str]:
    return {r.method: (_BEFORE if r.method == UNCOMPENSATED else f"C{i - 1}")
            for i, r in enumerate(study.rows)}


def _runs(study) -> bool:
    return not study.spans_s


def _published(study) -> str:
    """The paper's figure for the study, in one sentence (empty when none applies)."""
    if _runs(study):
        ratios = [b / a for b, a in CHENG2015_TABLE2_MSD]
        unc = study.rows[0].msd_by_part
        ours = []
        for r in study.rows[1:]:
            rs = [b / a for a, b in zip(r.msd_by_part, unc) if a > 0]
            if rs:
                ours.append(f"{r.method} {min(rs):.1f}-{max(rs):.1f}x")
        return (f"Cheng et al. 2015 (Table 2): the RBF network makes the mean square deviation "
                f"{min(ratios):.0f}-{max(ratios):.0f}x smaller on five test runs; here "
                + (", ".join(ours) or "no row") + " (at 1 Hz, floored by the gyro's white "
                "noise).")
    pub = {m: v for m, v in TAO2019_BIAS_STABILITY.items() if m != UNCOMPENSATED}
    top = min(pub, key=lambda m: pub[m][0])
    before = TAO2019_BIAS_STABILITY[UNCOMPENSATED][0]
    best = min(study.rows[1:], key=lambda r: r.values["bias_stability_dph"], default=None)
    here = study.rows[0].values["bias_stability_dph"]
    ours = (f"here {here:.4f} -> {best.values['bias_stability_dph']:.4f} deg/h ({best.method}, "
            f"{best.values['improvement_pct']:.1f} %)") if best else f"here {here:.4f} deg/h"
    return (f"Tao et al. 2019 (Tables 2-5): bias stability {before:.5f} -> {pub[top][0]:.5f} "
            f"deg/h ({top}, {pub[top][1]:.2f} %); {ours}.")


def plot_drift_vs_temperature(study) -> Figure:
    """The drift of every test part against its FOG thermometer, before compensation (the
    separated drift less the constant calibration) and after (the separated drift less each
    row's prediction) [deg/h]."""
    colours = _colours(study)
    fig = Figure(figsize=(12.0, 4.8), dpi=110, layout="constrained")
    before, after = fig.subplots(1, 2)
    many = len(study.traces) > 1
    shade = np.linspace(0.25, 0.75, max(1, len(study.traces)))
    left, right = [], []
    for k, tr in enumerate(study.traces):
        y = tr.drift_dph - tr.predicted_dph[UNCOMPENSATED]
        left.append(y)
        before.plot(tr.temp_fog_c, y, lw=0.8, color=str(shade[k]) if many else _BEFORE,
                    label=f"{tr.name}" if many else "separated drift - constant calibration")
        for r in study.rows[1:]:
            e = tr.drift_dph - tr.predicted_dph[r.method]
            right.append(e)
            after.plot(tr.temp_fog_c, e, lw=0.8, color=colours[r.method],
                       label=f"{r.method}: drift - prediction" if k == 0 else None)
    part = "run" if _runs(study) else "cycle"
    before.set_title(f"before compensation (test {part}s)", fontsize=9)
    after.set_title("after compensation", fontsize=9)
    for ax, vals in ((before, left), (after, right)):
        if vals:
            _symmetric(ax, vals)
        ax.set_xlabel("FOG thermometer temp_fog_c [degC]")
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            _below(ax, 3 if many and ax is before else 2)
    before.set_ylabel(f"drift - constant calibration [deg/h]\n(the training {part}s' "
                      "mean bias)", fontsize=9)
    after.set_ylabel("drift - prediction [deg/h]")
    _title(fig, [f"{study.scenario.name}: drift against temperature (a loop: thermal "
                 "hysteresis, a rate term the model lacks)", _published(study)])
    return fig


def _window_means(tr, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(centre time [h], mean) of ``values`` over each :data:`BIAS_WINDOW_S` window of a
    part (the windows of Tao et al.'s bias stability)."""
    w = np.floor((tr.time_s - tr.time_s[0]) / BIAS_WINDOW_S).astype(int)
    n = np.bincount(w)
    has = n > 0
    mean = np.bincount(w, values)[has] / n[has]
    t = np.bincount(w, tr.time_s)[has] / n[has]
    return t / 3600.0, mean


def _shade_ramps(ax, tr) -> None:
    """Shade where the chamber rises (red) and falls (blue) in a part."""
    t_h = tr.time_s / 3600.0
    for sign, colour, label in ((1, "tab:red", "chamber rising"),
                                (-1, "tab:blue", "chamber falling")):
        on = np.concatenate([[False], tr.ramp == sign, [False]]).astype(int)
        starts, ends = np.flatnonzero(np.diff(on) == 1), np.flatnonzero(np.diff(on) == -1)
        for j, (a, b) in enumerate(zip(starts, ends)):
            ax.axvspan(t_h[a], t_h[b - 1], color=colour, alpha=0.08, lw=0,
                       label=label if j == 0 else None)


def plot_residual_vs_time(study) -> Figure:
    """The 100 s means of the compensated bias (gyro output - Earth rate - prediction) of
    every test part against time since power-on, before compensation (the constant) and
    after (each row), with +-1 bias stability here and, for the temperature cycle, in Tao
    et al. 2019 [deg/h]."""
    colours = _colours(study)
    fig = Figure(figsize=(12.0, 6.8), dpi=110, layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    many = len(study.traces) > 1
    shade = np.linspace(0.25, 0.75, max(1, len(study.traces)))
    drawn = {top: [], bottom: []}
    for k, tr in enumerate(study.traces):
        t, m = _window_means(tr, tr.bias_dph - tr.predicted_dph[UNCOMPENSATED])
        drawn[top].append(m)
        top.plot(t, m, lw=0.9, color=str(shade[k]) if many else _BEFORE,
                 label=tr.name if many else "gyro - Earth rate - constant, 100 s means")
        for r in study.rows[1:]:
            t, m = _window_means(tr, tr.bias_dph - tr.predicted_dph[r.method])
            drawn[bottom].append(m)
            bottom.plot(t, m, lw=0.9, color=colours[r.method],
                        label=f"{r.method}: gyro - Earth rate - prediction, 100 s means"
                        if k == 0 else None)
    best = min(study.rows[1:], key=lambda r: r.values["bias_stability_dph"], default=None)
    for ax, row in ((top, study.rows[0]), (bottom, best)):
        if row is None:
            continue
        s = row.values["bias_stability_dph"]
        if math.isfinite(s):
            _plus_minus(ax, s, color=colours[row.method], ls="--", lw=1.0,
                        label=f"+-1 bias stability here, {row.method}: {s:.4f} deg/h")
            drawn[ax].append(np.array([s]))
    if not _runs(study):
        pub = {m: v for m, v in TAO2019_BIAS_STABILITY.items() if m != UNCOMPENSATED}
        top_m = min(pub, key=lambda m: pub[m][0])
        for ax, (name, value) in ((top, (UNCOMPENSATED, TAO2019_BIAS_STABILITY[UNCOMPENSATED])),
                                  (bottom, (top_m, pub[top_m]))):
            _plus_minus(ax, value[0], color="tab:purple", ls=":", lw=1.4,
                        label=f"+-1 bias stability, Tao et al. 2019, {name}: "
                              f"{value[0]:.5f} deg/h")
            drawn[ax].append(np.array([value[0]]))
    if study.traces:
        for ax in (top, bottom):
            _shade_ramps(ax, study.traces[0])
    part = "run" if _runs(study) else "cycle"
    top.set_title(f"before compensation (test {part}s)", fontsize=9)
    bottom.set_title("after compensation", fontsize=9)
    for ax in (top, bottom):
        if drawn[ax]:
            _symmetric(ax, drawn[ax])
        ax.set_ylabel("compensated bias [deg/h]")
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            _beside(ax)
    bottom.set_xlabel("time since power-on [h]")
    _title(fig, [f"{study.scenario.name}: residual against time; the standard deviation of "
                 "the 100 s means is the bias stability", _published(study)])
    return fig


def _liang(pstudy) -> str:
    """Liang et al.'s average gain of HHO-RVR over LS beside ours, one sentence."""
    by = {(r.parameter, r.method): r.values["rmse"] for r in pstudy.parameters}
    ours = []
    for p, (desc, _, _) in pstudy.described.items():
        ls, rvr = by.get((p, "LS")), by.get((p, "HHO-RVR"))
        if ls and rvr is not None and math.isfinite(ls) and math.isfinite(rvr):
            ours.append(f"{desc} {100.0 * (1.0 - rvr / ls):+.1f} %")
    return (f"Liang et al. 2021: HHO-RVR's RMSE {LIANG2021_RVR_OVER_LS_PCT['rmse']:.2f} % "
            "below the cubic LS on average over their 15 parameters"
            + ("; here (RMSE below LS's): " + ", ".join(ours) if ours else "") + ".")


def _model_colours(pstudy) -> dict[str, str]:
    methods = list(dict.fromkeys(r.method for r in pstudy.parameters))
    return {m: (_BEFORE if i == 0 else f"C{i - 1}") for i, m in enumerate(methods)}


def plot_parameters_vs_temperature(pstudy) -> Figure:
    """Each parameter every cycle calibrates against its sensor's thermometer: training and
    test cycles, and every model's curve over the cycles' temperatures."""
    colours = _model_colours(pstudy)
    params = list(pstudy.described)
    cols = 2
    nrow = math.ceil(len(params) / cols)
    fig = Figure(figsize=(13.0, 3.6 * nrow + 0.8), dpi=110, layout="constrained")
    axes = fig.subplots(nrow, cols, squeeze=False).ravel()
    for ax, p in zip(axes, params):
        desc, unit, col = pstudy.described[p]
        x_tr = np.concatenate([c.temperature_c[col] for c in pstudy.train])
        y_tr = np.concatenate([c.values[p] for c in pstudy.train])
        x_te = np.concatenate([c.temperature_c[col] for c in pstudy.test])
        y_te = np.concatenate([c.values[p] for c in pstudy.test])
        ax.plot(x_tr, y_tr, ".", ms=3, color="0.7", label=f"training cycles ({x_tr.size})")
        ax.plot(x_te, y_te, ".", ms=3, color="k", label=f"test cycles ({x_te.size})")
        x = np.concatenate([x_tr, x_te])
        x = x[np.isfinite(x)]
        grid = np.linspace(x.min(), x.max(), 200)
        rmse = []
        for r in (r for r in pstudy.parameters if r.parameter == p):
            if r.method == "constant":
                ax.axhline(float(np.nanmean(y_tr)), color=colours[r.method], ls="--", lw=1.0,
                           label="constant: training mean (before compensation)")
            else:
                ax.plot(grid, pstudy.models[(r.method, p)].predict(grid[:, None]), lw=1.2,
                        color=colours[r.method], label=f"{r.method} model")
            rmse.append(f"{r.method} {r.values['rmse']:.3g}")
        ax.set_title(f"{desc}: test RMSE " + ", ".join(rmse) + f" {unit}", fontsize=8)
        ax.set_xlabel(f"{col} [degC]")
        ax.set_ylabel(f"{desc} [{unit}]")
        ax.grid(alpha=0.3)
    for ax in axes[len(params):]:
        ax.set_visible(False)
    # every panel draws the same entries: one legend, under the panels
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=5,
               fontsize=8, frameon=False)
    _title(fig, [f"{pstudy.scenario.name}: every north-finding cycle's calibrated parameters "
                 "against temperature", _liang(pstudy)])
    return fig


def plot_parameter_residuals(pstudy) -> Figure:
    """Calibrated minus predicted on the test cycles against time since power-on, for the
    constant (before compensation, left) and the models (after, right), one row per
    parameter; limits symmetric about 0, each panel its own; each panel's RMSEs in its
    title."""
    colours = _model_colours(pstudy)
    params = list(pstudy.described)
    fig = Figure(figsize=(13.0, 2.5 * len(params) + 1.2), dpi=110, layout="constrained")
    axes = fig.subplots(len(params), 2, sharex=True, squeeze=False)
    t_h = np.concatenate([c.t_end_s for c in pstudy.test]) / 3600.0
    handles: dict[str, object] = {}
    for (left, right), p in zip(axes, params):
        desc, unit, _ = pstudy.described[p]
        y = np.concatenate([c.values[p] for c in pstudy.test])
        for ax, before in ((left, True), (right, False)):
            drawn, rmse = [], []
            for r in (r for r in pstudy.parameters if r.parameter == p):
                if (r.method == "constant") != before:
                    continue
                e = y - pstudy.predicted[(r.method, p)]
                drawn.append(e)
                name = ("constant (the training mean)" if r.method == "constant"
                        else r.method) + ": calibrated - predicted"
                handles[name] = ax.plot(t_h, e, "-o", ms=2, lw=0.7, color=colours[r.method],
                                        label=name)[0]
                rmse.append(f"{r.method} {r.values['rmse']:.3g}")
            if drawn:
                _symmetric(ax, drawn)
            ax.set_title(f"{desc}, {'before' if before else 'after'} compensation: "
                         f"test RMSE {', '.join(rmse)} {unit}", fontsize=8)
            ax.set_ylabel(f"residual [{unit}]", fontsize=8)
            ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time since power-on [h] (end of each test cycle)")
    fig.legend(list(handles.values()), list(handles), loc="outside lower center",
               ncol=len(handles), fontsize=8, frameon=False)
    _title(fig, [f"{pstudy.scenario.name}: every calibrated parameter's residual against "
                 "time, before (left) and after compensation (right)", _liang(pstudy)])
    return fig
