"""Robust weights of the iteratively reweighted LS-SVM: the weight functions and their registry.

A weight v(r) [-] of a standardised residual r = e_k / s (s the robust scale
:func:`robust_scale`) scales sample k's squared error in the weighted LS-SVM
(:class:`~nfs.learners.lssvm.IRLSSVMRegressor`; Tao et al. (2019) eq. (14)-(20); Suykens,
De Brabanter, Lukas & Vandewalle 2002, Neurocomputing 48; De Brabanter et al. 2009).  One
plain function per published weight, side by side, and one registry,
:data:`WEIGHT_FUNCTIONS`, with the null weight ``"unweighted"``; an unknown name raises an
error listing the valid ones, and a user's own function v = f(r) plugs in as
``IRLSSVMRegressor(weight=f)``.

Equation numbers "Tao et al. (2019) eq. (n)" count the displayed equations of its stored text
(see :mod:`nfs.learners.kernels`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .validation import HyperparameterError

__all__ = [
    "HAMPEL_FLOOR",
    "robust_scale",
    "unit_weight",
    "huber_weight",
    "hampel_weight",
    "logistic_weight",
    "myriad_weight",
    "WeightFunction",
    "WEIGHT_FUNCTIONS",
    "get_weight_function",
]

#: Floor of the Hampel weight beyond c2 (Suykens et al. 2002, Neurocomputing 48, the
#: weighted LS-SVM weights).  Tao et al. (2019) writes 0 there, which makes 1/(gamma v_k)
#: infinite in the KKT system; LS-SVMlab's weightingscheme.m uses 1e-7.
HAMPEL_FLOOR = 1e-4


def robust_scale(e: np.ndarray) -> float:
    """Robust standard deviation s = 1.483 MAD(e), MAD(e) = median |e_k - median(e)|.

    Tao et al. (2019) eq. (20); Suykens et al. 2002 (Neurocomputing 48).  1.483 ~ 1/Phi^-1(3/4)
    makes s consistent with the standard deviation for Gaussian errors.  [unit of e]
    """
    e = np.asarray(e, dtype=float)
    return float(1.483 * np.median(np.abs(e - np.median(e))))


def unit_weight(r: np.ndarray) -> np.ndarray:
    """The null weight v = 1 for every standardised residual r (plain LS-SVM; Tao et al.'s (2019)
    "Unweighted" row of Table 5)."""
    return np.ones_like(np.asarray(r, dtype=float))


def huber_weight(r: np.ndarray, beta: float = 1.345) -> np.ndarray:
    """Huber weight (Tao et al. (2019) eq. (15); De Brabanter et al. 2009)::

        v(r) = 1           if |r| < beta
               beta / |r|  if |r| >= beta

    r = e_k / s [-] is the standardised residual; beta [-] the corner.  Default 1.345, the
    usual constant for 95 % efficiency at Gaussian errors (Holland & Welsch 1977); Tao et al. (2019)
    tunes it by robust cross-validation and does not give its value.
    """
    a = np.abs(np.asarray(r, dtype=float))
    with np.errstate(divide="ignore"):
        return np.where(a < beta, 1.0, beta / np.where(a < beta, 1.0, a))


def hampel_weight(r: np.ndarray, c1: float = 2.5, c2: float = 3.0) -> np.ndarray:
    """Hampel weight (Tao et al. (2019) eq. (16), with c1 = b1 = 2.5, c2 = b2 = 3 as there)::

        v(r) = 1                       if |r| <= c1
               (c2 - |r|) / (c2 - c1)  if c1 < |r| <= c2
               1e-4                    otherwise

    The floor 1e-4 (:data:`HAMPEL_FLOOR`) is that of Suykens et al. 2002; Tao et al. (2019) writes
    0,
    which would make the weighted KKT system infinite.  The ramp is floored at it too, so v
    is continuous at |r| = c2.  r [-], c1 < c2 [-].
    """
    a = np.abs(np.asarray(r, dtype=float))
    ramp = (c2 - a) / (c2 - c1)
    v = np.where(a <= c1, 1.0, np.where(a <= c2, ramp, HAMPEL_FLOOR))
    return np.maximum(v, HAMPEL_FLOOR)


def logistic_weight(r: np.ndarray) -> np.ndarray:
    """Logistic weight v(r) = tanh(r) / r, with v(0) = 1 (its limit) (Tao et al. (2019) eq. (17);
    De Brabanter et al. 2009).  r [-]."""
    r = np.asarray(r, dtype=float)
    small = np.abs(r) < 1e-8
    with np.errstate(invalid="ignore", divide="ignore"):
        v = np.tanh(r) / np.where(small, 1.0, r)
    return np.where(small, 1.0, v)


def myriad_weight(r: np.ndarray, delta: float = 2.385) -> np.ndarray:
    """Myriad weight v(r) = delta^2 / (delta^2 + r^2) (Tao et al. (2019) eq. (18); De Brabanter et
    al. 2009).  r [-]; delta [-] the linearity parameter (small: robust, large: least
    squares).  Default 2.385, the Cauchy-weight constant for 95 % Gaussian efficiency
    (Holland & Welsch 1977); Tao et al. (2019) tunes delta by robust cross-validation."""
    r = np.asarray(r, dtype=float)
    d2 = float(delta) ** 2
    return d2 / (d2 + r * r)


@dataclass(frozen=True)
class WeightFunction:
    """One entry of :data:`WEIGHT_FUNCTIONS`."""

    func: Callable[..., np.ndarray]
    """v = func(r, **params): weight [-] of a standardised residual r [-]."""
    params: tuple[str, ...]
    """Names of the IRLSSVMRegressor hyperparameters passed to ``func`` as keywords."""


#: Weight-function registry: name -> function and the hyperparameters it takes.
#: "unweighted" is the null weight (plain LS-SVM).  A user's own function v(r) plugs in by
#: passing it as ``IRLSSVMRegressor(weight=my_function)``.
WEIGHT_FUNCTIONS: dict[str, WeightFunction] = {
    "unweighted": WeightFunction(unit_weight, ()),
    "huber": WeightFunction(huber_weight, ("beta",)),
    "hampel": WeightFunction(hampel_weight, ("c1", "c2")),
    "logistic": WeightFunction(logistic_weight, ()),
    "myriad": WeightFunction(myriad_weight, ("delta",)),
}


def get_weight_function(name: str) -> WeightFunction:
    """The registry entry for ``name`` (case-insensitive); HyperparameterError listing the
    valid names otherwise."""
    try:
        return WEIGHT_FUNCTIONS[str(name).lower()]
    except KeyError:
        raise HyperparameterError(
            f"unknown weight function {name!r}; valid: {', '.join(WEIGHT_FUNCTIONS)}, "
            "or a callable v = f(r)") from None

