"""A unit's chain: its measured runs and a model, fit -> compare -> diagnose -> apply -> design.

The measurement side's counterpart of :class:`nfs.ModelChain`.  A :class:`UnitChain` holds
one unit's runs and the model being worked on; each step returns a frozen result that the
next step takes as it is, and that writes and reads itself as JSON (``to_dict`` /
``from_dict``, :mod:`nfs.io.records`)::

    import nfs
    chain = nfs.UnitChain("default", "runs/")        # a model (name, file) and the runs
    fit = chain.fit()                                # nfs.fit.FitResult
    comparison = chain.compare()                     # nfs.comparison.Comparison
    finding = chain.diagnose(decide=True)            # nfs.rivals.Finding: one answer
    print(finding.verdict)
    if finding.answer.kind == "add":
        chain.apply(finding.answer.labels[0])        # nfs.unit.Applied; the chain moves on
    elif finding.answer.kind == "tie":
        design = chain.design()                      # nfs.design.Design: the run to make

The work a step needs from an earlier one is not done twice: the start states of the runs
(each run's node temperatures at power-on) and the fit are estimated once, by :meth:`fit`,
and reused by :meth:`compare`, :meth:`diagnose` and :meth:`apply`.  :meth:`apply` moves the
chain to the new model (the working loop is: diagnose, apply what it names, diagnose again);
:attr:`history` keeps every result in order.  The ``nfs fit``, ``nfs compare``,
``nfs diagnose`` and ``nfs design`` commands are this chain on files.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from ..comparison import Comparison, compare
from ..design import Design, default_space, design_experiment
from ..design.search import N_DRAWS
from ..design.space import SOAK_H, Space
from ..diagnose import Diagnosis, apply_candidate, diagnose
from ..effects import get_effect
from ..errors import NfsError
from ..fit import FitResult, fit_unit, write_fitted_model
from ..fit.calibration import DEFAULT_DECIMATE_S
from ..fit.free_set import FIT_STAGES
from ..fit.refine import MAX_STEPS, REFINE_FACTOR
from ..fit.start_state import StartModel
from ..fit.thermal_residual import DEFAULT_START, start_states
from ..instrument import Instrument, load_instrument
from ..io.atomic import atomic_write_text
from ..io.measurement import read_runs
from ..rivals import Finding, rival_models, settle_tie
from ..rivals.models import check_label
from ..rivals.separation import MARGIN_SIGMA
from ..run import Run
from .applied import Applied

__all__ = ["UnitChain"]


def _model(model: Instrument | str | os.PathLike) -> Instrument:
    return model if isinstance(model, Instrument) else load_instrument(model)


def _runs(runs: Sequence[Run] | str | os.PathLike | Iterable[str | os.PathLike]) -> list[Run]:
    if isinstance(runs, (str, os.PathLike)):
        return read_runs(runs)
    runs = list(runs)
    if runs and all(isinstance(r, Run) for r in runs):
        return runs
    if any(isinstance(r, Run) for r in runs):
        raise NfsError("runs: give Run objects or paths, not both")
    return read_runs(runs)


class UnitChain:
    """One unit's measured runs and the model being worked on (module docstring).

    Parameters
    ----------
    model : Instrument, or a preset name or TOML file
        The model to start from (``"default"``: the default instrument).
    runs : sequence of Run, or paths (files, stems, folders)
        The unit's measured runs (:func:`nfs.read_runs`).
    start_state : StartModel or None
        How each run's node temperatures at power-on are estimated from its thermometers
        (:mod:`nfs.fit.start_state`: an unfinished soak); None: every run soaked at T0.
    decimate_s : float
        Window of the residual grid of the fit and the diagnosis [s].
    """

    def __init__(self, model: Instrument | str | os.PathLike,
                 runs: Sequence[Run] | str | os.PathLike | Iterable[str | os.PathLike], *,
                 start_state: StartModel | None = DEFAULT_START,
                 decimate_s: float = DEFAULT_DECIMATE_S) -> None:
        self.model: Instrument = _model(model)
        self.runs: list[Run] = _runs(runs)
        if not self.runs:
            raise NfsError("a unit's chain needs runs: none given")
        self.start_state = start_state
        self.decimate_s = float(decimate_s)
        self.fitted: FitResult | None = None
        self.finding: Finding | None = None
        self.history: list[Any] = []
        self._start_c: dict[str, np.ndarray] | None = None

    def __repr__(self) -> str:
        state = "fitted" if self.fitted is not None else "not fitted"
        return f"UnitChain({self.model.name!r}, {len(self.runs)} runs, {state})"

    # -----------------------------------------------------------------------------------------
    # the steps

    def fit(self, *, refine: bool = True, free: Iterable[str] | None = None,
            stages: Sequence[str] = FIT_STAGES, prior: Mapping[str, float | str] | str | None
            = "default", prior_scale: float = 1.0, n_starts: int = 1, fit_noise: bool = True,
            factor: float = REFINE_FACTOR, max_steps: int = MAX_STEPS) -> FitResult:
        """Fit the model to the runs (:func:`nfs.fit.fit_unit`: both stages, then the thermal
        structure's alternatives that pay); the chain's model becomes the fitted one."""
        res = fit_unit(self.model, self.runs, refine=refine, factor=factor,
                       max_steps=max_steps, free=free, stages=tuple(stages),
                       decimate_s=self.decimate_s, prior=prior, prior_scale=prior_scale,
                       n_starts=n_starts, fit_noise=fit_noise, start_state=self.start_state)
        self.model, self.fitted, self.finding = res.instrument, res, None
        self._start_c = dict(res.start_c) if res.start_c else None
        self.history.append(res)
        return res

    def compare(self, *, seed: int = 0, startup_end_s: float = 3600.0,
                stable_start_s: float = 5400.0, window_s: float = 600.0) -> Comparison:
        """The model beside the runs, channel by channel (:func:`nfs.compare`)."""
        res = compare(self.model, self.runs, seed=seed, startup_end_s=startup_end_s,
                      stable_start_s=stable_start_s, window_s=window_s,
                      start_state=self.start_state, start_c=self._starts())
        self.history.append(res)
        return res

    def diagnose(self, *, decide: bool = False, rivals: Sequence[str] | None = None,
                 alpha: float = 0.05, n_boot: int = 20, seed: int = 0,
                 node_temperatures: str = "smoothed", check_structure: bool = True
                 ) -> Finding:
        """Which registered effect the model lacks, with one answer
        (:func:`nfs.diagnose.diagnose`).

        ``decide``: a tie is put to the runs (:func:`nfs.rivals.settle_tie`), and the answer
        is the settlement's; ``rivals``: these explanations are put to the runs instead of
        the tie's (at least two labels, e.g. the rivals a designed run was made for).
        """
        if rivals is not None:
            self.check_rivals(rivals)
        d = diagnose(self.model, self.runs, n_boot=n_boot, alpha=alpha, random_state=seed,
                     decimate_s=self.decimate_s, node_temperatures=node_temperatures,
                     check_structure=check_structure, start_state=self.start_state,
                     start_c=self._starts(), baseline=self.fitted)
        settled = None
        if (decide and d.answer.kind == "tie") or rivals is not None:
            settled = settle_tie(d, self.model, self.runs, labels=rivals,
                                 start_state=self.start_state)
        self.finding = Finding(d, settled)
        self.history.append(self.finding)
        return self.finding

    def apply(self, effect: str, target: str | None = None, *,
              finding: Finding | Diagnosis | None = None) -> Applied:
        """Add ``effect`` (``name``, ``name:target`` or ``name`` with ``target``) to the model
        and refit it (:func:`nfs.diagnose.apply_candidate`); the chain moves to the new
        model.  ``finding``: the diagnosis the effect comes from (default: the chain's last),
        whose support for it is reported, and warned about when it does not support it."""
        name, _, tgt = effect.partition(":")
        target = target if target is not None else (tgt or None)
        get_effect(name)                       # an unknown name fails before any work
        label = name + (f":{target}" if target else "")
        found = finding if finding is not None else self.finding
        supported, support = (None, "") if found is None else found.support_for(name, target)
        warn = ()
        if found is not None and not supported:
            warn = (f"the diagnosis does not support {label}: {support}; added as asked",)
        new, fit, report = apply_candidate(self.model, self.runs, name, target,
                                           decimate_s=self.decimate_s,
                                           start_state=self.start_state,
                                           start_c=self._starts())
        res = Applied(label, new, fit, dict(report["rms_before"]), dict(report["rms_after"]),
                      float(report["heading_rmse_before_deg"]),
                      float(report["heading_rmse_after_deg"]), support, supported,
                      warn + tuple(fit.warnings))
        self.model, self.fitted, self.finding = new, fit, None
        self._start_c = dict(fit.start_c) if fit.start_c else None
        self.history.append(res)
        return res

    def design(self, rivals: Sequence[str] | None = None, *, space: Space | None = None,
               soak_h: float = SOAK_H, start_temperatures_c: Sequence[float] | None = None,
               max_hours: float | None = None, margin_sigma: float = MARGIN_SIGMA,
               n_draws: int = N_DRAWS, seed: int = 0,
               progress: Callable[[str], None] | None = None) -> Design:
        """The cheapest chamber run that would tell ``rivals`` apart
        (:func:`nfs.design.design_experiment`); default rivals: those the chain's last
        finding could not tell apart (:meth:`nfs.rivals.Finding.rivals`).

        ``space``: the experiments searched (default :func:`nfs.design.default_space` of the
        runs with ``soak_h``, ``start_temperatures_c`` and a longest run of ``max_hours``
        chamber hours, soak included).
        """
        if rivals is None:
            if self.finding is None:
                raise NfsError("a design needs rivals: diagnose first, or name them "
                               "(rivals=['model', 'turn_on_transient'])")
            rivals = self.finding.rivals()
        if space is None:
            space = self.design_space(soak_h=soak_h, start_temperatures_c=start_temperatures_c,
                                      max_hours=max_hours)
        # rival_models refuses bad labels before its first fit
        fitted = rival_models(self.model, self.runs, list(rivals), start_state=self.start_state)
        res = design_experiment(fitted, self.runs, None, space,
                                margin_sigma=margin_sigma, n_draws=n_draws, seed=seed,
                                progress=progress)
        self.history.append(res)
        return res

    # -----------------------------------------------------------------------------------------

    def _starts(self) -> dict[str, np.ndarray] | None:
        """The start states of the chain's model, estimated once."""
        if self.start_state is None:
            return None
        if self._start_c is None:
            self._start_c = start_states(self.model, self.runs, self.decimate_s,
                                         self.start_state)
        return self._start_c

    def check_rivals(self, rivals: Sequence[str]) -> None:
        """Refuse, before any work, rivals that are fewer than two or that the model cannot
        take (an unknown effect or target, an effect the model has already)."""
        labels = list(rivals)
        if len(labels) < 2:
            raise NfsError(f"rivals: a decision needs at least two explanations, got "
                           f"{len(labels)}")
        for label in labels:
            check_label(self.model, self.runs, label)

    def design_space(self, *, soak_h: float = SOAK_H,
                     start_temperatures_c: Sequence[float] | None = None,
                     max_hours: float | None = None, option: str = "max_hours") -> Space:
        """The experiments :meth:`design` searches: :func:`nfs.design.default_space` of the
        runs with a soak of ``soak_h`` [h], the start temperatures given, and a longest run
        that fits ``max_hours`` chamber hours with its soak (``option`` names it in the
        error when none fits)."""
        space = default_space(self.runs, soak_h=soak_h)
        if start_temperatures_c is not None:
            space = replace(space, start_temperatures_c=tuple(float(t)
                                                              for t in start_temperatures_c))
        if max_hours is not None:
            step = space.duration_step_s
            longest = step * np.floor((max_hours - soak_h) * 3600.0 / step + 1e-9)
            if longest < step:
                raise NfsError(f"{option} {max_hours:g}: no run of {step / 60.0:g} min fits "
                               f"after the {soak_h:g} h soak")
            space = replace(space, max_duration_s=float(longest))
        return space

    def write_model(self, path: str | Path) -> Path:
        """Write the chain's model as the TOML file ``nfs fit`` writes (with the fit's
        account in its header when the model is a fit's)."""
        if self.fitted is not None and self.fitted.instrument is self.model:
            return write_fitted_model(self.fitted, path)
        atomic_write_text(Path(path), self.model.to_toml())
        return Path(path)
