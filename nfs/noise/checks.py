"""Argument checks of the noise functions: one place, one message format.

Each returns the value converted (float, int or the generator itself) or raises
:class:`~nfs.errors.InputError` naming the argument, the condition and the value received.
The generators (:mod:`nfs.noise.generators`) and the covariance of window means
(:mod:`nfs.noise.covariance`) validate their arguments through these, so a wrong sample rate
reads the same whichever function received it.
"""

from __future__ import annotations

import math

import numpy as np

from nfs.errors import InputError

__all__ = ["check_n_samples", "check_non_negative", "check_positive", "check_rng"]


def check_rng(rng: object) -> np.random.Generator:
    """``rng`` itself when it is a :class:`numpy.random.Generator` (the only source of random
    draws a noise function accepts), else an InputError that says how to make one."""
    if not isinstance(rng, np.random.Generator):
        raise InputError(
            f"rng must be a numpy.random.Generator (e.g. numpy.random.default_rng(seed)), "
            f"got {type(rng).__name__}")
    return rng


def check_n_samples(n_samples: object) -> int:
    """A number of samples [-] as an int >= 0 (a bool is refused), else an InputError."""
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) \
            or n_samples < 0:
        raise InputError(f"n_samples must be an integer >= 0, got {n_samples!r}")
    return int(n_samples)


def check_positive(name: str, value: float) -> float:
    """``value`` as a float, finite and > 0, in the unit of the argument ``name`` (a sample
    rate [Hz], a correlation time [s]), else an InputError naming ``name``."""
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(f"{name} must be finite and > 0, got {value!r}")
    return value


def check_non_negative(name: str, value: float) -> float:
    """``value`` as a float, finite and >= 0, in the unit of the argument ``name`` (a noise
    coefficient: N [deg/sqrt(h)], B [deg/h], K [deg/h/sqrt(h)]; 0 switches the term off),
    else an InputError naming ``name``."""
    value = float(value)
    if not math.isfinite(value) or value < 0.0:
        raise InputError(f"{name} must be finite and >= 0, got {value!r}")
    return value
