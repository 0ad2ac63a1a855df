"""What every learner checks and computes before it learns: hyperparameters, inputs, scaling.

One piece of code for every estimator of :mod:`nfs.learners`:

- :class:`HyperparameterError` and the hyperparameter checks :func:`check_positive`,
  :func:`check_count`, :func:`check_int` and :func:`check_real`, called in ``fit``, never in
  ``__init__`` (scikit-learn's estimator contract);
- :func:`validate`: scikit-learn's ``validate_data`` (dense float arrays, finite values,
  ``n_features_in_`` and ``feature_names_in_``) on every scikit-learn version we support;
- :func:`fit_scaling`: the offsets and scales of the standardisation
  ``z = (x - mean) / scale`` that every model applies to its training inputs.
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np
from sklearn.base import BaseEstimator

from nfs.errors import InputError

try:  # scikit-learn >= 1.6
    from sklearn.utils.validation import validate_data as _sk_validate_data
except ImportError:  # pragma: no cover - scikit-learn 1.3 to 1.5
    _sk_validate_data = None

__all__ = [
    "HyperparameterError",
    "check_positive",
    "check_count",
    "check_int",
    "check_real",
    "validate",
    "fit_scaling",
]


class HyperparameterError(InputError, ValueError):
    """A learner's hyperparameter out of its domain (raised by ``fit``, never ``__init__``).

    An :class:`~nfs.errors.InputError` (located by the parameter's name as its ``key`` where
    the check knows it) and a ValueError, as scikit-learn's own estimators raise for bad
    parameters.
    """


def check_positive(name: str, value, *, allow_inf: bool = False) -> float:
    """``value`` as a float > 0 (finite unless ``allow_inf``); HyperparameterError naming
    ``name`` otherwise."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise HyperparameterError(f"{name} must be a positive number, got {value!r}") from None
    if not (v > 0.0 and (allow_inf or np.isfinite(v))):
        raise HyperparameterError(f"{name} must be a positive number, got {value!r}")
    return v


def check_count(name: str, value) -> int:
    """``value`` as an int >= 1 (a bool is refused); HyperparameterError naming ``name``
    otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise HyperparameterError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def check_int(value, name: str, low: int, *, allow_none: bool = False) -> None:
    """HyperparameterError (key ``name``) unless ``value`` is an integer >= ``low`` (or None
    when ``allow_none``); a bool is refused."""
    if allow_none and value is None:
        return
    if isinstance(value, bool) or not isinstance(value, Integral) or value < low:
        raise HyperparameterError(f"must be an integer >= {low}, got {value!r}", key=name)


def check_real(value, name: str, low: float, high: float = math.inf, *,
               low_open: bool = False, high_open: bool = False) -> None:
    """HyperparameterError (key ``name``) unless ``value`` is a finite real number in the
    interval from ``low`` to ``high`` (each end closed unless ``low_open`` / ``high_open``);
    a bool is refused."""
    ok = isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value)
    if ok:
        ok = (value > low if low_open else value >= low) and \
             (value < high if high_open else value <= high)
    if not ok:
        lo = "(" if low_open else "["
        hi = ")" if high_open else "]"
        raise HyperparameterError(
            f"must be a real number in {lo}{low}, {high}{hi}, got {value!r}", key=name)


def validate(estimator: BaseEstimator, X, y="no_validation", *, reset: bool):
    """``sklearn.utils.validation.validate_data`` (or the estimator method before 1.6):
    dense float arrays, finite values, ``n_features_in_`` / ``feature_names_in_``.

    Without ``y`` only X is validated and returned; with it, ``(X, y)`` with y numeric.
    ``y=None`` passed by a caller of ``fit`` is an error (a regressor requires y).
    ``reset=True`` in ``fit`` (records the number and names of the features),
    ``reset=False`` in ``predict`` (checks them).
    """
    kwargs = dict(reset=reset, dtype=np.float64)
    if not (isinstance(y, str) and y == "no_validation"):
        kwargs["y_numeric"] = True
    if _sk_validate_data is not None:
        return _sk_validate_data(estimator, X, y, **kwargs)
    return estimator._validate_data(X, y, **kwargs)  # pragma: no cover


def fit_scaling(X: np.ndarray, center: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Offsets and scales of X (n_samples, n_features) for ``z = (x - mean) / scale``.

    ``center=True``: column means and standard deviations (ddof 0).  ``center=False``: zero
    offsets and the root mean squares about zero, so that z is x rescaled, nothing more.  A
    (numerically) constant or all-zero column keeps scale 1, so that it maps to a finite z.

    Returns
    -------
    mean, scale : arrays (n_features,)
        In the unit of each column.
    """
    if center:
        mean = X.mean(axis=0)
        scale = X.std(axis=0)
    else:
        mean = np.zeros(X.shape[1])
        scale = np.sqrt(np.mean(X ** 2, axis=0))
    tiny = 10.0 * np.finfo(float).eps * np.maximum(np.abs(X.mean(axis=0)), 1.0)
    scale = np.where(scale > tiny, scale, 1.0)
    return mean, scale
