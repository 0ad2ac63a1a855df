"""Each run's node temperatures at power-on: the soak as it really ended.

A start-up is meant to begin with the unpowered unit soaked at T0 until uniform.  Real soaks
end early (the thermometers look steady long before the housing's global time constant has
run out several times), and the unit sits a few tenths of a kelvin off the chamber's air
(the door opened to cable it, unevenly stirred air).  A model started at T0 everywhere then
misses the first hour of every thermometer by those tenths, and a fit pays for it by moving
capacities and powers far from the unit's.  So the start of every run is estimated with the
model's other parameters:

    T(0) = T0 1 + V a,       V = [v_1, ..., v_k, u]                                    [degC]

v_1 ... v_k are the k slowest free modes of the network (:meth:`thermal.Network.modes`,
each scaled to max |v| = 1): after hours of soak every other mode has decayed, so an
unfinished soak leaves a_1 v_1 (v_1 is nearly uniform: the housing and what it holds,
lagging the air together).  u is the part of a uniform offset 1 that the slow modes do not
hold (1 minus its projection on v_1 ... v_k in the capacity-weighted inner product, scaled
to max |u| = 1): a unit set a little off its air relaxes in minutes by this pattern.  By
default only the slow mode is free (:attr:`StartModel.fast`: a free u takes up what the
model misses of the first minutes in every run alike).  The amplitudes a [K] are a run's
own; a Gaussian prior keeps them where the record cannot see:

- no soak history: centre 0, widths :data:`SLOW_WIDTH_C` (slow modes) and
  :data:`FAST_WIDTH_C` (u);
- a sidecar that gives the soak (``soak_from_c`` [degC], the temperature the unit was
  brought from, and ``soak_h`` [h], how long it soaked at T0): the unpowered network from
  ``soak_from_c`` for ``soak_h`` in air at T0, T(0) - T0 = expm(A t_soak) (T_from - T0) 1,
  projected on V, is the centre; the slow widths become half of that centre's amplitude
  (at least :data:`HISTORY_WIDTH_C`), since the housing's time constant of the unit is
  known only as well as the model's.

For given network parameters the readings are linear in a (up to the kink of a TEC law, a
second-order effect of tenths of a kelvin on a slope of hundredths of a watt per kelvin), so
a is solved per run by weighted linear least squares with its prior: variable projection
(Golub and Pereyra, SIAM J. Numer. Anal. 10(2), 413 (1973)), in
:func:`nfs.fit.thermal_residual.thermal_residual`.  The fit's cost then carries the
prior rows of a, and its parameters' errors include what the start could explain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import thermal

from ..errors import InputError
from ..run import Run

__all__ = ["SLOW_WIDTH_C", "FAST_WIDTH_C", "HISTORY_WIDTH_C", "DEFAULT_SLOW_MODES",
           "SOAK_KEYS", "StartModel", "start_basis", "soak_history", "start_prior",
           "solve_amplitudes"]

#: Prior width of a slow mode's amplitude without a soak history [K]: soaks that end when
#: the thermometers look steady (about 0.01 K/min) leave about 0.5 K behind a 48 min time
#: constant, up to 1 K after a short soak from a laboratory 50 K away.
SLOW_WIDTH_C = 1.0
#: Prior width of the fast remainder u [K]: a chamber holds its air to +-0.3-0.5 K (IEC
#: 60068-3-5) and the unit is cabled with the door open, which puts a few tenths on every
#: node; nearly all of a uniform offset lies on the slow mode, a tenth of it on u.
FAST_WIDTH_C = 0.1
#: Least width of a slow amplitude whose centre comes from a soak history [K].
HISTORY_WIDTH_C = 0.2
#: Slow modes estimated per run by default (the rest of the network's modes have decayed
#: after any soak of an hour or more).
DEFAULT_SLOW_MODES = 1
#: Sidecar keys of the soak history: the temperature the unit came from [degC], and how long
#: it soaked at T0 before power-on [h].
SOAK_KEYS = ("soak_from_c", "soak_h")


@dataclass(frozen=True)
class StartModel:
    """How the start of every run is estimated (None in its place: every node at T0)."""

    n_slow: int = DEFAULT_SLOW_MODES
    """Slow modes with a free amplitude per run."""
    fast: bool = False
    """Also free the fast remainder u per run.  Off by default: on the package's default
    world (0.2 K common offsets, whose fast part is a few hundredths of a kelvin) a free u
    came out near -0.1 K in every run alike, a model error of the first minutes taken up as
    a start, while the slow mode alone brings the thermometers to their floor."""
    slow_width_c: float = SLOW_WIDTH_C
    """Prior width of each slow amplitude without a soak history [K]."""
    fast_width_c: float = FAST_WIDTH_C
    """Prior width of the fast remainder's amplitude [K]."""

    @property
    def n_amplitudes(self) -> int:
        """Amplitudes per run."""
        return self.n_slow + (1 if self.fast else 0)


def start_basis(network: thermal.Network, n_slow: int = DEFAULT_SLOW_MODES,
                fast: bool = False, modes: tuple[np.ndarray, np.ndarray] | None = None
                ) -> np.ndarray:
    """V = [v_1, ..., v_k, u] (n_nodes, k + 1) of the module docstring (without u when not
    ``fast``); ``modes``: the network's :meth:`~thermal.Network.modes`, when known."""
    _, v = network.modes() if modes is None else modes
    k = min(max(int(n_slow), 0), v.shape[1] - 1)
    slow = v[:, :k]
    if not fast:
        return slow
    c = network.capacity_j_per_k
    ones = np.ones(v.shape[0])
    if k:
        gram = slow.T @ (c[:, None] * slow)
        u = ones - slow @ np.linalg.solve(gram, slow.T @ (c * ones))
    else:
        u = ones
    big = float(np.max(np.abs(u)))
    u = u / (big if big > 0 else 1.0)
    return np.column_stack([slow, u])


def soak_history(run: Run) -> tuple[float, float] | None:
    """(soak_from_c [degC], soak_h [h]) from the run's sidecar, or None when it gives neither.

    Raises
    ------
    InputError
        Only one of the two keys, or a value that is not a finite number (soak_h < 0).
    """
    extra = run.meta.extra
    given = [k for k in SOAK_KEYS if k in extra]
    if not given:
        return None
    if len(given) == 1:
        missing = SOAK_KEYS[1 - SOAK_KEYS.index(given[0])]
        raise InputError(f"run '{run.name}' gives '{given[0]}' but not '{missing}': the soak "
                         "history needs both", file=run.path, key=missing)
    out = []
    for key in SOAK_KEYS:
        value = extra[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise InputError(f"run '{run.name}': '{key}' must be a finite number, got "
                             f"{value!r}", file=run.path, key=key)
        out.append(float(value))
    if out[1] < 0:
        raise InputError(f"run '{run.name}': 'soak_h' must be >= 0 h, got {out[1]:g}",
                         file=run.path, key="soak_h")
    return out[0], out[1]


def start_prior(network: thermal.Network, basis: np.ndarray, t0_c: float,
                history: tuple[float, float] | None, model: StartModel,
                modes: tuple[np.ndarray, np.ndarray] | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
    """(centre, width) of the amplitudes a [K] of one run (module docstring); ``modes``:
    the network's :meth:`~thermal.Network.modes`, when the caller has them."""
    k = basis.shape[1]
    n_slow = basis.shape[1] - (1 if model.fast else 0)
    centre = np.zeros(k)
    width = np.full(k, model.slow_width_c)
    width[n_slow:] = model.fast_width_c
    if history is not None:
        t_from, hours = history
        # expm(A t) 1 from the free modes: 1 = V b, T(t) - T0 = V diag(exp(-t / tau)) b
        taus, v = network.modes() if modes is None else modes
        b = np.linalg.solve(v, np.full(v.shape[0], t_from - t0_c))
        decay = np.exp(-3600.0 * hours / taus)      # tau = inf (floating) keeps its part
        dev = v @ (decay * b)
        c = network.capacity_j_per_k
        gram = basis.T @ (c[:, None] * basis)
        centre = np.linalg.solve(gram, basis.T @ (c * dev))
        width[:n_slow] = np.maximum(0.5 * np.abs(centre[:n_slow]), HISTORY_WIDTH_C)
    return centre, width


def solve_amplitudes(r0: np.ndarray, g: np.ndarray, centre: np.ndarray, width: np.ndarray
                     ) -> np.ndarray:
    """a minimising |r0 + G a|^2 + |(a - centre) / width|^2 (rows already weighted)."""
    w2 = 1.0 / np.square(width)
    lhs = g.T @ g + np.diag(w2)
    rhs = -(g.T @ r0) + w2 * centre
    return np.linalg.solve(lhs, rhs)
