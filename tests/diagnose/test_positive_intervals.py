"""Intervals of positive quantities made on their log: no verdict prints a negative time
constant, power or lag.

Oracles: the delta method's closed form (value e^(+-h/value)); the interval holds the
value and is symmetric in log; an unphysical (negative) estimate keeps its symmetric
interval; which parameters are positive, by their physics.
"""

import math

import pytest

from nfs.fit.structure import positive_parameter
from nfs.scoring.intervals import positive_interval


def test_the_interval_of_a_time_constant_stays_positive():
    # the tie of a turn-on transient settled by a short power cycle gave tau = 222 s with a
    # standard error of 193 s: a symmetric interval [-156, 600] held negative time constants
    lo, hi = positive_interval(222.0, 1.959963984540054 * 193.0)
    assert lo > 0.0 and lo < 222.0 < hi
    assert math.log(hi / 222.0) == pytest.approx(math.log(222.0 / lo), rel=1e-12)
    assert (lo, hi) == pytest.approx((222.0 * math.exp(-1.959963984540054 * 193.0 / 222.0),
                                      222.0 * math.exp(1.959963984540054 * 193.0 / 222.0)))
    # a narrow interval is the symmetric one to first order
    lo, hi = positive_interval(118.0, 10.0)
    assert (lo + hi) / 2.0 == pytest.approx(118.0, rel=5e-3) and hi - lo == pytest.approx(
        20.0, rel=5e-3)


def test_an_unphysical_estimate_keeps_its_symmetric_interval():
    assert positive_interval(-0.2, 0.5) == (-0.7, 0.3)
    assert positive_interval(3.0, math.inf) == (-math.inf, math.inf)


@pytest.mark.parametrize("effect, parameter, positive", [
    ("turn_on_transient", "tau", True), ("turn_on_transient", "a", False),
    ("thermometer_lag", "tau", True), ("heat_source", "power", True),
    ("motor_heat", "power", True), ("polarization_ripple", "T_p", True),
    ("magnetic", "m", False), ("magnetic", "D_mag", False)])
def test_which_parameters_are_positive(effect, parameter, positive):
    assert positive_parameter(effect, parameter) is positive
