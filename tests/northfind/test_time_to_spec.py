"""Time to spec on synthetic heading-error sequences whose answer is known in closed form."""

import math

import numpy as np
import pytest

from nfs.errors import NfsError
from nfs.northfind import rolling_rmse_deg, run_time_to_spec_s, time_to_spec_s

DT = 640.0                       # one 4-position cycle of 150 s dwells and 10 s moves [s]
T = DT * np.arange(1, 15)        # output time of each cycle over 2.5 h [s]


def test_exponential_settling_is_first_cycle_past_tau_log_ratio():
    # e(t) = A exp(-t / tau) falls within s at t* = tau ln(A / s): the answer is the first
    # cycle output at or after t*.
    a, tau, s = 0.05, 1800.0, 0.01
    err = a * np.exp(-T / tau)
    t_star = tau * math.log(a / s)
    expected = T[T >= t_star][0]
    assert time_to_spec_s(T, err, s) == expected
    assert time_to_spec_s(T, -err, s) == expected        # the sign of the error is no matter


def test_rolling_rmse_of_exponential_closed_form():
    # r_k^2 = (A^2 / W) exp(-2 t_k / tau) sum_{m<W} exp(2 m dt / tau)
    a, tau, s, w = 0.05, 1800.0, 0.01, 3
    err = a * np.exp(-T / tau)
    g = sum(math.exp(2 * m * DT / tau) for m in range(w)) / w
    r = a * np.exp(-T / tau) * math.sqrt(g)
    np.testing.assert_allclose(rolling_rmse_deg(err, w)[w - 1:], r[w - 1:], rtol=1e-12)
    assert np.all(np.isnan(rolling_rmse_deg(err, w)[:w - 1]))
    t_star = tau * math.log(a * math.sqrt(g) / s)   # r(t) = s
    ok = (T >= t_star) & (np.arange(T.size) >= w - 1)
    t_e = tau * math.log(a / s)                     # |e(t)| = s
    assert run_time_to_spec_s(T, err, s, window=w) == (T[T > t_e][0], T[ok][0])


def test_a_late_excursion_resets_the_time_and_a_last_one_means_never():
    err = np.full(T.size, 0.001)
    err[[2, 6]] = 0.05
    assert time_to_spec_s(T, err, 0.01) == T[7]
    err[-1] = 0.05
    assert time_to_spec_s(T, err, 0.01) == math.inf


def test_within_spec_from_the_first_cycle_and_no_data():
    assert time_to_spec_s(T, np.full(T.size, 0.001), 0.01) == T[0]
    assert math.isnan(time_to_spec_s(T, np.full(T.size, np.nan), 0.01))
    assert math.isnan(run_time_to_spec_s(T[:2], [0.0, 0.0], 0.01, window=5)[1])
    # a cycle without data is left out, not counted as in or out of spec
    err = np.full(T.size, 0.001)
    err[0], err[1] = 0.05, np.nan
    assert time_to_spec_s(T, err, 0.01) == T[2]
    # the boundary |e| = s is within spec
    assert time_to_spec_s(T, np.full(T.size, 0.01), 0.01) == T[0]


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf])
def test_bad_spec_is_an_error(bad):
    with pytest.raises(NfsError, match="specification"):
        time_to_spec_s(T, np.zeros(T.size), bad)
