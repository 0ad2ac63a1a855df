"""Training data for drift compensators: features X, separated drift y, run groups.

For each run with a known heading: the drift target is the wavelet-separated gyro drift
(gyro output minus the Earth-rate projection at the known heading, denoised; the FOG start-up paper,
docs/physics.md section 6), the inputs are named thermometer features
(:mod:`nfs.compensate.features`).  Samples while the turntable moves are left out, and the
rest is decimated (the separated drift is smooth: the wavelet cutoff is 8.5 min, so 0.1 Hz
or less loses nothing, and kernel methods cost O(n^2)-O(n^3)).  ``groups`` numbers the runs,
so validation leaves whole runs out: drift noise is correlated in time, and random samples
of one run in both the training and the validation folds would leak.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..denoise import separate_drift
from ..errors import NfsError
from .features import compute_features
from .modes import DEFAULT_FEATURE_MODE, check_features_mode

__all__ = ["DriftDataset", "drift_dataset"]


@dataclass(frozen=True)
class DriftDataset:
    """Stacked, decimated training samples of several runs."""

    X: np.ndarray
    """Features (n_samples, n_features)."""
    y: np.ndarray
    """Separated drift [deg/h]."""
    groups: np.ndarray
    """Run number of each sample (folds of whole runs; see :attr:`validation_groups`)."""
    time_s: np.ndarray
    """Time since power-on of each sample [s]."""
    feature_names: tuple[str, ...]
    """Names of the feature columns."""
    run_names: tuple[str, ...]
    """Name of each run (index = group number)."""
    start_temperatures_c: tuple[float, ...]
    """T0 of each run."""
    features_mode: str = DEFAULT_FEATURE_MODE
    """What each feature may use (:mod:`nfs.compensate.modes`): a compensator trained on
    this set must be applied in the same mode."""
    rate_window_s: float | None = None
    """Window of the rate features [s] (None: the mode's)."""

    @property
    def validation_groups(self) -> np.ndarray:
        """Fold id of every sample for tuning: its run's start temperature.

        Validation leaves one start temperature out: with several
        start-ups per temperature, leaving one run out would keep its twins (same T0, same
        thermal history) in the training folds and reward hyperparameters that interpolate
        between them instead of generalising across temperatures.  When every run has the
        same start temperature, the runs themselves are the folds.
        """
        temps = np.asarray(self.start_temperatures_c, dtype=float)
        uniq, per_run = np.unique(temps, return_inverse=True)
        if uniq.size < 2:
            return self.groups
        return per_run[self.groups]

    def thinned(self, max_samples: int) -> "DriftDataset":
        """Every k-th sample, k = ceil(n / max_samples): at most ``max_samples`` samples."""
        k = -(-self.X.shape[0] // max_samples)
        sl = slice(None, None, k)
        return dataclasses.replace(self, X=self.X[sl], y=self.y[sl], groups=self.groups[sl],
                                   time_s=self.time_s[sl])


def drift_dataset(runs: Sequence, features, *, decimate_s: float = 30.0,
                  cutoff_period_s: float = 512.0, wavelet: str = "db4", rule: str = "visu",
                  features_mode: str = DEFAULT_FEATURE_MODE,
                  rate_window_s: float | None = None) -> DriftDataset:
    """Build the training set of ``runs`` (each needs ``true_heading_deg``).

    Parameters
    ----------
    runs : sequence of Run
    features : str or list of str
        Feature names or sets (:func:`~nfs.compensate.features.resolve_features`).
    decimate_s : float
        Keep one sample every ``decimate_s`` seconds [s].
    cutoff_period_s : float
        Wavelet cutoff period of the drift separation [s] (512 s: level 8 at 1 Hz).
    wavelet, rule : str
        Wavelet family and threshold rule of the separation.
    features_mode : str
        ``cycle``, ``causal`` or ``offline`` (:mod:`nfs.compensate.modes`).
    rate_window_s : float, optional
        Window of the temperature-rate features [s] (default: the mode's).

    Returns
    -------
    DriftDataset
    """
    features_mode = check_features_mode(features_mode)
    if not runs:
        raise NfsError("no runs to train on")
    Xs, ys, gs, ts = [], [], [], []
    names = None
    for g, run in enumerate(runs):
        X, names_g = compute_features(run, features, mode=features_mode,
                                      rate_window_s=rate_window_s)
        if names is None:
            names = names_g
        elif names_g != names:
            raise NfsError(f"run '{run.name}' gives features {names_g}, the others {names}")
        sep = separate_drift(run, cutoff_period_s=cutoff_period_s, wavelet=wavelet, rule=rule)
        t = np.asarray(run.columns["time_s"], dtype=float)
        dt = float(np.median(np.diff(t)))
        step = max(1, int(round(decimate_s / dt)))
        keep = np.zeros(t.size, dtype=bool)
        keep[::step] = True
        keep &= ~np.asarray(sep.moving, dtype=bool)
        keep &= np.all(np.isfinite(X), axis=1) & np.isfinite(sep.drift_dph)
        Xs.append(X[keep])
        ys.append(np.asarray(sep.drift_dph)[keep])
        gs.append(np.full(int(keep.sum()), g))
        ts.append(t[keep])
    return DriftDataset(X=np.vstack(Xs), y=np.concatenate(ys), groups=np.concatenate(gs),
                        time_s=np.concatenate(ts), feature_names=tuple(names),
                        run_names=tuple(r.name for r in runs),
                        start_temperatures_c=tuple(float(r.meta.start_temperature_c)
                                                   for r in runs),
                        features_mode=features_mode, rate_window_s=rate_window_s)
