"""A trained drift compensator: features + estimator, applied to runs, saved to a file.

Apply = predict the drift from the run's own thermometers (and aux channels) and subtract it
from the gyro output, then north-find (physics.md section 6; seed 004).  A compensator is
saved with its feature list, settings and the versions of the libraries that trained it, and
refuses runs that lack one of its input channels.
"""

from __future__ import annotations

import io
import platform
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..errors import NfsError
from ..io.atomic import atomic_write_bytes
from ..io.measurement import Run
from .dataset import DriftDataset, drift_dataset
from .features import compute_features

__all__ = ["DriftCompensator", "train_compensator", "load_compensator", "FORMAT"]

#: Format tag of a saved compensator.
FORMAT = "nfs-compensator/1"


def _versions() -> dict[str, str]:
    import joblib
    import pywt
    import scipy
    import sklearn

    from .. import __version__
    return {"nfs": __version__, "numpy": np.__version__, "scipy": scipy.__version__,
            "scikit-learn": sklearn.__version__, "pywavelets": pywt.__version__,
            "joblib": joblib.__version__, "python": platform.python_version()}


@dataclass(frozen=True)
class DriftCompensator:
    """A fitted drift model and how to feed it."""

    method: str
    """Method name (e.g. ``SSA-SVR``)."""
    estimator: Any
    """The fitted scikit-learn estimator (features -> drift [deg/h])."""
    feature_names: tuple[str, ...]
    """The input features, in column order."""
    rate_window_s: float = 121.0
    """Window of the temperature-rate features [s]."""
    settings: dict = field(default_factory=dict)
    """How it was trained (decimation, wavelet cutoff, budget, ...)."""
    trained_on: tuple[str, ...] = ()
    """Names of the training runs."""
    fit_time_s: float = float("nan")
    """Wall time of the training [s]."""
    versions: dict = field(default_factory=dict)
    """Library versions at training time."""

    def predict_drift(self, run: Run, *, stride_s: float | None = None) -> np.ndarray:
        """Predicted drift at every sample of ``run`` [deg/h].

        The model is evaluated every ``stride_s`` seconds (default: the training decimation,
        at most 10 s) and linearly interpolated in between: its inputs vary on the scale of
        minutes (121 s rate window, thermometer lags) and its target was low-passed at the
        wavelet cutoff (8.5 min), so a kernel model need not be evaluated at every 1 Hz
        sample (a 10x saving for SVR, whose cost is one kernel row per support vector).
        ``stride_s=0`` evaluates every sample.
        """
        X, names = compute_features(run, list(self.feature_names),
                                    rate_window_s=self.rate_window_s)
        if tuple(names) != self.feature_names:
            raise NfsError(f"run '{run.name}': features {names} differ from the model's "
                           f"{list(self.feature_names)}")
        t = np.asarray(run.columns["time_s"], dtype=float)
        if stride_s is None:
            stride_s = min(10.0, float(self.settings.get("decimate_s", 10.0)))
        dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
        k = max(1, int(round(stride_s / dt))) if stride_s > 0 else 1
        ok = np.all(np.isfinite(X), axis=1)
        idx = np.flatnonzero(ok)
        out = np.full(X.shape[0], np.nan)
        if idx.size == 0:
            return out
        eval_idx = idx[::k]
        if eval_idx[-1] != idx[-1]:
            eval_idx = np.append(eval_idx, idx[-1])
        pred = self.estimator.predict(X[eval_idx])
        out[idx] = np.interp(t[idx], t[eval_idx], pred) if k > 1 else pred
        return out

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
        """Write the compensator with joblib, atomically."""
        import joblib
        buf = io.BytesIO()
        joblib.dump({"format": FORMAT, "compensator": self}, buf)
        atomic_write_bytes(path, buf.getvalue())
        return Path(path)


def load_compensator(path: str | Path) -> DriftCompensator:
    """Read a compensator written by :meth:`DriftCompensator.save`."""
    import joblib
    path = Path(path)
    if not path.is_file():
        raise NfsError(f"{path}: model file not found")
    try:
        obj = joblib.load(path)
    except Exception as exc:  # a corrupt or foreign file
        raise NfsError(f"{path}: not a compensator model file ({type(exc).__name__}: {exc})") \
            from None
    if not isinstance(obj, dict) or obj.get("format") != FORMAT:
        raise NfsError(f"{path}: not a compensator model file (expected format {FORMAT})")
    return obj["compensator"]


def train_compensator(method: str, runs: Sequence[Run] | DriftDataset, *,
                      features="seed004", budget: int = 40, random_state: int = 0,
                      n_jobs: int | None = None, decimate_s: float = 30.0,
                      cutoff_period_s: float = 512.0, rate_window_s: float = 121.0
                      ) -> DriftCompensator:
    """Train a compensator of ``method`` (a key or name of :data:`~nfs.compensate.methods.METHODS`).

    ``runs`` are measurement runs with a known heading (or a prepared :class:`DriftDataset`).
    Tuned methods search their hyperparameters with ``budget`` evaluations of a validation
    error that leaves one start temperature out (one run out when all share one T0;
    :attr:`DriftDataset.validation_groups`).
    """
    from .methods import get_method
    spec = get_method(method)
    data = runs if isinstance(runs, DriftDataset) else drift_dataset(
        runs, features, decimate_s=decimate_s, cutoff_period_s=cutoff_period_s,
        rate_window_s=rate_window_s)
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
        rate_window_s=rate_window_s,
        settings={"decimate_s": decimate_s, "cutoff_period_s": cutoff_period_s,
                  "budget": budget if spec.tuned else None, "random_state": random_state,
                  "n_samples": int(data.X.shape[0])},
        trained_on=data.run_names, fit_time_s=dt, versions=_versions())
