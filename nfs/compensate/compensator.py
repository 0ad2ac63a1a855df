"""A trained drift compensator: features + estimator, applied to runs, saved to a file.

Apply = predict the drift from the run's own thermometers (and aux channels) and subtract it
from the gyro output, then north-find (docs/physics.md section 6; the FOG start-up paper).  A
compensator is saved as a model file (:mod:`~nfs.compensate.model_file`, ``nfs-model/1``:
arrays and JSON, read without running code) with its feature list, settings, the runs it was
trained on (hashed) and the versions of the libraries that trained it, and refuses runs that
lack one of its input channels.  The joblib pickles of earlier versions are read only when
the caller trusts them (``trust_pickle=True``).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import NfsError
from ..run import Run
from ..io.provenance import library_versions, runs_provenance
from .dataset import DriftDataset, drift_dataset
from .features import compute_features
from .model_file import (FORMAT, ModelFileError, former_modules, model_file_kind,
                         read_model_file, write_model_file)
from .modes import (
    DEFAULT_FEATURE_MODE,
    FeatureModeError,
    check_features_mode,
    horizon_index,
)
from .catalog import MethodSpec
from . import get_method  # the package registers the seed papers' methods first

__all__ = ["DriftCompensator", "PredictionPlan", "prediction_plan", "train_compensator",
           "load_compensator", "FORMAT", "PICKLE_FORMAT"]

#: Format tag of the dict in the joblib pickles of earlier versions.
PICKLE_FORMAT = "nfs-compensator/1"

#: DriftCompensator fields stored in a model file's header (the estimator is stored apart).
_HEADER_FIELDS = ("method", "feature_names", "rate_window_s", "features_mode", "settings",
                  "trained_on", "provenance", "fit_time_s", "versions")


@dataclass(frozen=True)
class PredictionPlan:
    """The samples of one run where a drift model is evaluated, and its features there.

    Computed once per run and feature set, it serves every compensator trained on those
    features (the comparison behind ``nfs table`` applies a dozen to each test run).
    """

    n_samples: int
    """Samples of the run."""
    time_s: np.ndarray
    """Time of every sample [s]."""
    finite_idx: np.ndarray
    """Samples where every feature is finite (the prediction is NaN elsewhere)."""
    eval_idx: np.ndarray
    """Samples where the model is evaluated (a subset of ``finite_idx``)."""
    X_eval: np.ndarray
    """Features at ``eval_idx`` (n_eval, n_features)."""
    feature_names: tuple[str, ...]
    """Names of the feature columns."""
    features_mode: str
    """The features mode they were computed in."""

    def interpolate(self, pred_eval: np.ndarray) -> np.ndarray:
        """The drift at every sample from its values at ``eval_idx`` [deg/h] (linear in time
        between evaluations; NaN where a feature is missing)."""
        out = np.full(self.n_samples, np.nan)
        idx, ev = self.finite_idx, self.eval_idx
        if idx.size == 0:
            return out
        t = self.time_s
        out[idx] = np.interp(t[idx], t[ev], pred_eval) if ev.size < idx.size else pred_eval
        return out


def prediction_plan(run: Run, feature_names: Sequence[str], *, features_mode: str,
                    rate_window_s: float | None = None, stride_s: float = 10.0
                    ) -> PredictionPlan:
    """The evaluation samples of ``run`` and its features there.

    One sample every ``stride_s`` seconds (``0``: every sample), plus the first and last
    sample of every stretch that shares a horizon in ``features_mode``
    (:func:`~nfs.compensate.modes.horizon_index`), so that no interpolation between two
    evaluations reaches past what the mode allows.

    Parameters
    ----------
    run : Run
        The run, with the input channels.
    feature_names : sequence of str
        The features, in the model's column order.
    features_mode : str
        ``cycle``, ``causal`` or ``offline``.
    rate_window_s : float, optional
        Window of the rate features [s] (None: the mode's).
    stride_s : float
        Time between evaluations [s].

    Returns
    -------
    PredictionPlan
    """
    X, names = compute_features(run, list(feature_names), mode=features_mode,
                                rate_window_s=rate_window_s)
    if tuple(names) != tuple(feature_names):
        raise NfsError(f"run '{run.name}': features {names} differ from the model's "
                       f"{list(feature_names)}")
    t = np.asarray(run.columns["time_s"], dtype=float)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    k = max(1, int(round(stride_s / dt))) if stride_s > 0 else 1
    idx = np.flatnonzero(np.all(np.isfinite(X), axis=1))
    if idx.size:
        # stretches of equal horizon: ends are evaluated, so no interpolation crosses one
        h = horizon_index(run, features_mode)[idx]
        change = h[1:] != h[:-1]
        ends = idx[np.concatenate(([True], change)) | np.concatenate((change, [True]))]
        eval_idx = np.union1d(idx[::k], ends)
    else:
        eval_idx = idx
    return PredictionPlan(n_samples=X.shape[0], time_s=t, finite_idx=idx, eval_idx=eval_idx,
                          X_eval=X[eval_idx], feature_names=tuple(feature_names),
                          features_mode=features_mode)


@dataclass(frozen=True)
class DriftCompensator:
    """A fitted drift model and how to feed it."""

    method: str
    """Method name (e.g. ``SSA-SVR``)."""
    estimator: Any
    """The fitted scikit-learn estimator (features -> drift [deg/h])."""
    feature_names: tuple[str, ...]
    """The input features, in column order."""
    rate_window_s: float | None = None
    """Window of the temperature-rate features [s] (None: the mode's)."""
    features_mode: str = DEFAULT_FEATURE_MODE
    """What a feature at t may use (:mod:`nfs.compensate.modes`), as in training: ``cycle``,
    ``causal`` or ``offline`` (a model saved before the modes existed was trained
    offline, and is read so by :func:`load_compensator`)."""
    settings: dict = field(default_factory=dict)
    """How it was trained (decimation, wavelet cutoff, budget, ...)."""
    trained_on: tuple[str, ...] = ()
    """Names of the training runs."""
    fit_time_s: float = float("nan")
    """Wall time of the training [s]."""
    versions: dict = field(default_factory=dict)
    """Library versions at training time."""
    provenance: dict = field(default_factory=dict)
    """What it was trained on: ``{"runs": [{name, file, sha256}, ...]}``
    (:func:`~nfs.io.provenance.runs_provenance`; the names only when trained on a prepared
    :class:`~nfs.compensate.dataset.DriftDataset`)."""

    def plan(self, run: Run, *, stride_s: float | None = None) -> "PredictionPlan":
        """Where and on what this compensator is evaluated on ``run``
        (:func:`prediction_plan` with its features, mode and rate window; ``stride_s``
        default: the training decimation, at most 10 s)."""
        if stride_s is None:
            stride_s = min(10.0, float(self.settings.get("decimate_s", 10.0)))
        return prediction_plan(run, self.feature_names, features_mode=self.features_mode,
                               rate_window_s=self.rate_window_s, stride_s=stride_s)

    def predict_drift(self, run: Run | None = None, *, stride_s: float | None = None,
                      plan: "PredictionPlan | None" = None) -> np.ndarray:
        """Predicted drift at every sample of ``run`` [deg/h].

        The model is evaluated every ``stride_s`` seconds (default: the training decimation,
        at most 10 s) and linearly interpolated in between: its inputs vary on the scale of
        minutes (rate windows of minutes, thermometer lags) and its target was low-passed at
        the wavelet cutoff (8.5 min), so a kernel model need not be evaluated at every 1 Hz
        sample (a 10x saving for SVR, whose cost is one kernel row per support vector).
        The interpolation never reaches past what the features mode allows: the model is
        also evaluated at the first and last sample of every stretch of samples that share
        a horizon (:func:`~nfs.compensate.modes.horizon_index`: each north-finding cycle in
        ``cycle`` mode; every sample, so no interpolation at all, in ``causal`` mode).
        ``stride_s=0`` evaluates every sample.

        Parameters
        ----------
        run : Run
            The run, with the model's input channels (not needed with ``plan``).
        stride_s : float, optional
            Time between evaluations of the model [s].
        plan : PredictionPlan, optional
            The run's features already computed (:meth:`plan`; several compensators trained
            on the same features share one).

        Returns
        -------
        ndarray
            Drift [deg/h]; NaN where a feature is missing.
        """
        if plan is None:
            plan = self.plan(run, stride_s=stride_s)
        elif (plan.feature_names, plan.features_mode) != (self.feature_names,
                                                          self.features_mode):
            raise NfsError(f"prediction plan of features {list(plan.feature_names)} "
                           f"({plan.features_mode} mode) differs from the model's "
                           f"{list(self.feature_names)} ({self.features_mode} mode)")
        return plan.interpolate(self.estimator.predict(plan.X_eval)
                                if plan.eval_idx.size else np.zeros(0))

    def compensate(self, run: Run, *, drift_dph: np.ndarray | None = None) -> Run:
        """The run with the predicted drift subtracted from ``gyro_dph``.

        The original output is kept as ``gyro_uncompensated_dph`` and the prediction as
        ``drift_model_dph`` (unknown columns pass through the measurement format).
        ``drift_dph``: a prediction already made by :meth:`predict_drift`.
        """
        drift = self.predict_drift(run) if drift_dph is None else np.asarray(drift_dph)
        cols = dict(run.columns)
        gyro = np.asarray(cols["gyro_dph"], dtype=float)
        cols["gyro_uncompensated_dph"] = gyro
        cols["drift_model_dph"] = drift
        cols["gyro_dph"] = gyro - drift
        return replace(run, columns=cols, path=None)

    def save(self, path: str | Path) -> Path:
        """Write the compensator as a model file (:data:`FORMAT`, e.g. ``model.npz``),
        atomically; loading it runs no code (:mod:`~nfs.compensate.model_file`).
        ModelFileError, in one line naming the method and the class, when the estimator
        holds a class a model file may not hold (a registered method's own classes it may,
        when the method lists them in ``model_classes``)."""
        header = {name: getattr(self, name) for name in _HEADER_FIELDS}
        header["feature_names"] = list(self.feature_names)
        header["trained_on"] = list(self.trained_on)
        try:
            return write_model_file(path, header, self.estimator)
        except ModelFileError as exc:    # one line that names the method it cannot save
            raise ModelFileError(f"method '{self.method}': {exc.message}",
                                 file=exc.file) from None


def load_compensator(path: str | Path, *, trust_pickle: bool = False) -> DriftCompensator:
    """Read a compensator written by :meth:`DriftCompensator.save`.

    A joblib pickle (what earlier versions wrote) is refused by its leading bytes before
    anything is unpickled, unless ``trust_pickle``: unpickling runs whatever code the file
    holds.  ``load_compensator(old, trust_pickle=True).save(new)`` converts a trusted one.

    Parameters
    ----------
    path : str or Path
        The model file.
    trust_pickle : bool
        Also read a joblib pickle of an earlier version (only from a source you trust).

    Returns
    -------
    DriftCompensator
        With ``features_mode="offline"`` when a pickle predates the features modes (its
        rates were the centred Savitzky-Golay ones).

    Raises
    ------
    ModelFileError
        A missing, foreign or corrupt file, or an untrusted pickle, in one line.
    """
    path = Path(path)
    if trust_pickle and model_file_kind(path) not in ("nfs-model", "missing"):
        return _load_pickle(path)
    header, estimator = read_model_file(path)
    try:
        kwargs = {name: header[name] for name in _HEADER_FIELDS}
    except KeyError as exc:
        raise NfsError(f"{path}: model file without {exc.args[0]!r} in its header") from None
    kwargs["feature_names"] = tuple(kwargs["feature_names"])
    kwargs["trained_on"] = tuple(kwargs["trained_on"])
    return DriftCompensator(estimator=estimator, **kwargs)


def _load_pickle(path: Path) -> DriftCompensator:
    """A compensator pickled by joblib (earlier versions' ``save``): runs the file's code."""
    import joblib
    try:
        with former_modules():              # its classes by their paths of that time
            obj = joblib.load(path)
    except Exception as exc:  # a corrupt or foreign file
        raise NfsError(f"{path}: not a compensator model file ({type(exc).__name__}: {exc})") \
            from None
    if not isinstance(obj, dict) or obj.get("format") != PICKLE_FORMAT or \
            not isinstance(obj.get("compensator"), DriftCompensator):
        raise NfsError(f"{path}: not a compensator model file (a pickle without a "
                       f"{PICKLE_FORMAT} compensator)")
    state = vars(obj["compensator"])
    # fields added since: a pickle without the features modes was trained offline
    defaults = {"features_mode": "offline", "provenance": {}}
    return DriftCompensator(**{f.name: state[f.name] if f.name in state else defaults[f.name]
                               for f in fields(DriftCompensator)})


def train_compensator(method: str | MethodSpec, runs: Sequence[Run] | DriftDataset, *,
                      features="seed004", budget: int = 40, random_state: int = 0,
                      n_jobs: int | None = None, decimate_s: float = 30.0,
                      cutoff_period_s: float = 512.0, rate_window_s: float | None = None,
                      features_mode: str | None = None) -> DriftCompensator:
    """Train a compensator of ``method`` (a key or name of a registered method,
    :data:`~nfs.compensate.registry.METHODS`).

    Tuned methods search their hyperparameters with ``budget`` evaluations of a validation
    error that leaves one start temperature out (one run out when all share one T0;
    :attr:`DriftDataset.validation_groups`).

    Parameters
    ----------
    method : str or MethodSpec
        Method key or name, or the method itself (as the studies hand it to their workers,
        which may not have it registered).
    runs : sequence of Run or DriftDataset
        Measurement runs with a known heading, or a prepared training set (whose features,
        mode and rate window are then used).
    features : str or list of str
        Feature names, sets or patterns (with runs).
    budget : int
        Evaluations of a tuned method's validation error.
    random_state : int
        Seed of every stochastic model and tuner.
    n_jobs : int, optional
        Parallel evaluations of a tuner's population.
    decimate_s, cutoff_period_s : float
        Training samples every ``decimate_s`` [s]; wavelet cutoff of the drift [s].
    rate_window_s : float, optional
        Window of the rate features [s] (default: the mode's).
    features_mode : str, optional
        ``cycle`` (default), ``causal`` or ``offline``; with a DriftDataset, its own mode
        (a different one given here is an error).

    Returns
    -------
    DriftCompensator
    """
    spec = method if isinstance(method, MethodSpec) else get_method(method)
    if isinstance(runs, DriftDataset):
        data = runs
        provenance = {"runs": [{"name": name} for name in data.run_names]}
        if features_mode is not None and check_features_mode(features_mode) != \
                data.features_mode:
            raise FeatureModeError(f"features mode {features_mode!r} differs from the training "
                                   f"set's {data.features_mode!r}: train and apply in one mode")
    else:
        data = drift_dataset(runs, features, decimate_s=decimate_s,
                             cutoff_period_s=cutoff_period_s, rate_window_s=rate_window_s,
                             features_mode=features_mode or DEFAULT_FEATURE_MODE)
        provenance = {"runs": runs_provenance(runs)}
    if spec.tuned and len(set(data.groups.tolist())) < 2:
        raise NfsError(f"{spec.name} tunes by leaving whole runs out: it needs at least "
                       "2 training runs")
    if spec.max_samples is not None and data.X.shape[0] > spec.max_samples:
        data = data.thinned(spec.max_samples)
    est = spec.build(budget=budget, random_state=random_state, n_jobs=n_jobs)
    t0 = time.perf_counter()
    if spec.tuned:
        est.fit(data.X, data.y, groups=data.validation_groups)
    else:
        est.fit(data.X, data.y)
    dt = time.perf_counter() - t0
    return DriftCompensator(
        method=spec.name, estimator=est, feature_names=data.feature_names,
        rate_window_s=data.rate_window_s, features_mode=data.features_mode,
        settings={"decimate_s": decimate_s, "cutoff_period_s": cutoff_period_s,
                  "budget": budget if spec.tuned else None, "random_state": random_state,
                  "n_samples": int(data.X.shape[0]), "features_mode": data.features_mode},
        trained_on=data.run_names, fit_time_s=dt, versions=library_versions(),
        provenance=provenance)
