"""nfs.design.space: experiments as chamber programs, their cost, and the grid searched.

Oracles: the chamber program of an experiment read back by nfs.chamber.parse_program (power-off
spans every_s apart, ramp corners at event_s and event_s + |X - T0| / rate), the cost
soak_h + duration / 3600 by hand, the grid counted from its definition.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nfs.chamber import parse_program
from nfs.errors import NfsError
from nfs.conditions import RunConditions
from nfs.ranges import TEMPERATURE_RANGE_C
from nfs.run import Run, RunMeta
from nfs.sensors import Schedule
from nfs.design.space import SOAK_H, Experiment, Space, base_conditions, default_space

POS = (0.0, 90.0, 180.0, 270.0)
DWELL, MOVE = 150.0, 10.0
CYCLE_S = len(POS) * (DWELL + MOVE)          # 640 s


def _prog(e: Experiment):
    return parse_program(e.program(), file=None, key="test.program")


def _run(t0: float, name: str = "r", n: int = 50, fs: float | None = 1.0) -> Run:
    meta = RunMeta(latitude_deg=30.0, start_temperature_c=t0, true_heading_deg=40.0,
                   sample_rate_hz=fs, positions_deg=POS, dwell_s=DWELL, move_s=MOVE)
    return Run(name, {"time_s": np.arange(n) * 0.5, "moving": np.zeros(n)}, meta)


def _base() -> RunConditions:
    return base_conditions([_run(20.0)])


# ---- one experiment ---------------------------------------------------------------------

def test_no_event_is_one_hold():
    e = Experiment(20.0, 5400.0)
    assert e.program() == [{"hold_s": 5400.0}]
    p = _prog(e)
    assert p.power_off_spans_s(20.0, 1.0) == ()
    t, temp = p.corners(20.0, 1.0)
    np.testing.assert_allclose(t, [0.0, 5400.0])
    np.testing.assert_allclose(temp, [20.0, 20.0])
    assert e.event_end_s == 0.0
    assert e.hours == pytest.approx(SOAK_H + 1.5, rel=1e-12)


def test_one_power_cycle():
    e = Experiment(-10.0, 7200.0, "power_off", event_s=1800.0, power_off_s=300.0)
    p = _prog(e)
    assert p.power_off_spans_s(-10.0, 1.0) == ((1800.0, 2100.0),)
    t, temp = p.corners(-10.0, 1.0)
    assert t[-1] == pytest.approx(7200.0)          # the program lasts the run
    np.testing.assert_allclose(temp, -10.0)        # the chamber holds throughout
    assert e.event_end_s == 2100.0
    assert e.hours == pytest.approx(SOAK_H + 2.0, rel=1e-12)


def test_four_power_cycles_every_s_apart():
    e = Experiment(40.0, 14400.0, "power_off", event_s=3600.0, power_off_s=60.0, cycles=4,
                   every_s=1200.0, soak_h=2.5)
    spans = _prog(e).power_off_spans_s(40.0, 1.0)
    want = tuple((3600.0 + k * 1200.0, 3600.0 + k * 1200.0 + 60.0) for k in range(4))
    assert len(spans) == 4
    np.testing.assert_allclose(spans, want)
    assert _prog(e).corners(40.0, 1.0)[0][-1] == pytest.approx(14400.0)
    assert e.event_end_s == 3600.0 + 3 * 1200.0 + 60.0
    assert e.hours == pytest.approx(2.5 + 4.0, rel=1e-12)
    # written out, no top-level repeat (which would make the program's cycles)
    assert _prog(e).cycles == ()
    assert "4 power cycles" in e.describe()


@pytest.mark.parametrize("t0,to,rate", [(20.0, 40.0, 1.0), (20.0, -5.0, 2.5)])
def test_ramp_corners(t0, to, rate):
    e = Experiment(t0, 10800.0, "ramp", event_s=3600.0, ramp_to_c=to, rate_c_per_min=rate)
    ramp_s = abs(to - t0) / rate * 60.0
    assert e.event_end_s == pytest.approx(3600.0 + ramp_s)
    t, temp = _prog(e).corners(t0, 1.0)
    np.testing.assert_allclose(t, [0.0, 3600.0, 3600.0 + ramp_s, 10800.0])
    np.testing.assert_allclose(temp, [t0, t0, to, to])
    assert _prog(e).power_off_spans_s(t0, 1.0) == ()


def test_conditions_follow_the_program():
    base = _base()
    e = Experiment(0.0, 9000.0, "power_off", event_s=1200.0, power_off_s=120.0, cycles=2,
                   every_s=900.0)
    c = e.conditions(base, name="x")
    assert len(c.power_off_s) == 2
    np.testing.assert_allclose(c.power_off_s, [(1200.0, 1320.0), (2100.0, 2220.0)])
    assert c.name == "x" and c.duration_s == 9000.0 and c.start_temperature_c == 0.0
    assert c.schedule == base.schedule and c.sample_rate_hz == base.sample_rate_hz
    np.testing.assert_allclose(c.chamber_c(np.array([0.0, 1250.0, 8000.0])), 0.0)
    # a ramp: the chamber follows it, no power cycle
    r = Experiment(10.0, 9000.0, "ramp", event_s=1800.0, ramp_to_c=30.0, rate_c_per_min=0.5)
    c = r.conditions(base)
    assert c.power_off_s == ()
    ramp_end = 1800.0 + 20.0 / 0.5 * 60.0            # 4200 s
    np.testing.assert_allclose(
        c.chamber_c(np.array([0.0, 1800.0, 3000.0, ramp_end, 8000.0])),
        [10.0, 10.0, 20.0, 30.0, 30.0], atol=1e-9)
    assert c.latitude_deg == base.latitude_deg
    assert c.true_heading_deg == base.true_heading_deg


def test_to_dict_and_with_duration():
    e = Experiment(5.0, 7200.0, "power_off", event_s=600.0, power_off_s=60.0)
    d = e.to_dict()
    assert d["hours"] == e.hours and d["power_off_s"] == 60.0 and d["event_s"] == 600.0
    assert d["program"] == e.program()
    f = e.with_duration(3000.0)
    assert f.duration_s == 3000.0 and f.power_off_s == 60.0
    assert _prog(f).corners(5.0, 1.0)[0][-1] == pytest.approx(3000.0)


@pytest.mark.parametrize("kw", [
    dict(event="power_off", power_off_s=0.0),
    dict(event="power_off", power_off_s=-5.0),
    dict(event="power_cycle", power_off_s=60.0),
    dict(event="ramp"),
    dict(event="ramp", ramp_to_c=30.0, rate_c_per_min=0.0),
    dict(event="power_off", power_off_s=300.0, cycles=3, every_s=300.0),
    dict(event="power_off", power_off_s=300.0, cycles=2, every_s=200.0),
])
def test_invalid_experiments(kw):
    with pytest.raises(NfsError):
        Experiment(20.0, 7200.0, **kw)


@pytest.mark.parametrize("t0", [TEMPERATURE_RANGE_C[0] - 0.1, TEMPERATURE_RANGE_C[1] + 1.0,
                                300.0])
def test_start_temperature_outside_the_range(t0):
    with pytest.raises(NfsError, match="start temperature"):
        Experiment(t0, 7200.0)


def test_valid_edges():
    # Oracle: the range's ends are inside it (the check is lo <= T0 <= hi), and the
    # experiment built there is the one asked for: its program holds T0 for the whole run.
    lo, hi = TEMPERATURE_RANGE_C
    for t0 in (lo, hi):
        e = Experiment(t0, 7200.0)
        assert e.start_temperature_c == t0 and e.event_end_s == 0.0
        t, temp = _prog(e).corners(t0, 1.0)
        np.testing.assert_allclose(t, [0.0, 7200.0])
        np.testing.assert_allclose(temp, [t0, t0])
    # one cycle may be longer than every_s (every_s only spaces repeated cycles): one span,
    # from event_s for power_off_s
    e = Experiment(20.0, 7200.0, "power_off", power_off_s=1800.0, cycles=1, every_s=1200.0)
    assert _prog(e).power_off_spans_s(20.0, 1.0) == ((3600.0, 5400.0),)
    assert e.event_end_s == 3600.0 + 1800.0


# ---- the grid ---------------------------------------------------------------------------

@pytest.mark.parametrize("exp", [
    Experiment(20.0, 14400.0),
    Experiment(20.0, 14400.0, "power_off", 3600.0, 60.0),
    Experiment(20.0, 14400.0, "power_off", 3600.0, 300.0, cycles=4),
    Experiment(20.0, 14400.0, "power_off", 3000.0, 600.0),        # ends on a step
    Experiment(20.0, 14400.0, "ramp", 3600.0, ramp_to_c=0.0),
])
@pytest.mark.parametrize("min_s", [0.0, 1280.0, 5000.0])
def test_durations(exp, min_s):
    sp = Space(start_temperatures_c=(20.0,), min_duration_s=min_s)
    d = sp.durations_s(exp)
    assert d.size > 0
    assert np.all(d > exp.event_end_s)                  # the unit seen after the event
    assert np.all(d >= min_s)
    assert d[-1] <= sp.max_duration_s + 1e-9 and d[-1] > sp.max_duration_s - sp.duration_step_s
    np.testing.assert_allclose(np.diff(d), sp.duration_step_s)
    np.testing.assert_allclose(d % sp.duration_step_s, 0.0)
    # the first is the first step after both the event and the minimum
    first = sp.duration_step_s * max(math.floor(exp.event_end_s / 600.0) + 1,
                                     math.ceil(min_s / 600.0))
    assert d[0] == pytest.approx(first)


def test_durations_other_step():
    sp = Space(start_temperatures_c=(20.0,), max_duration_s=3000.0, duration_step_s=250.0,
               min_duration_s=1280.0)
    d = sp.durations_s(Experiment(20.0, 3000.0, "power_off", 600.0, 60.0))
    np.testing.assert_allclose(d, np.arange(1500.0, 3000.1, 250.0))


def test_default_grid_count():
    """Per T0: the hold, power cycles of 60, 300, 1800 s times 1 or 4 cycles (1800 s x 4
    skipped: the off time is not shorter than every_s = 1200 s), two cycles of 20 s and
    2 min off, ramps of -20 and +20 K."""
    sp = Space(start_temperatures_c=(-20.0, 20.0, 60.0))
    ex = sp.experiments()
    n_power = sum(1 for off in sp.power_off_s for n in sp.cycles
                  if not (n > 1 and off >= sp.every_s))
    assert n_power == 5 and sp.off_pairs_s == ((20.0, 120.0),)
    assert len(ex) == 3 * (1 + n_power + 1 + len(sp.ramps_k)) == 27
    assert all(e.duration_s == sp.max_duration_s for e in ex)
    assert all(e.event_end_s < sp.max_duration_s for e in ex)
    assert sorted({e.start_temperature_c for e in ex}) == [-20.0, 20.0, 60.0]
    kinds = [e.event for e in ex]
    assert kinds.count("none") == 3 and kinds.count("power_off") == 18
    assert kinds.count("ramp") == 6
    pairs = [e for e in ex if e.power_off_2_s is not None]
    assert len(pairs) == 3 and all(e.off_times_s() == (20.0, 120.0) for e in pairs)
    assert all(e.soak_h == sp.soak_h for e in ex)
    for e in ex:
        _prog(e)                                        # every one is a valid program
    ramps = sorted((e.start_temperature_c, e.ramp_to_c) for e in ex if e.event == "ramp")
    assert ramps == [(-20.0, -40.0), (-20.0, 0.0), (20.0, 0.0), (20.0, 40.0), (60.0, 40.0),
                     (60.0, 80.0)]


def test_grid_clips_ramps_to_the_chamber_range():
    lo, hi = TEMPERATURE_RANGE_C
    sp = Space(start_temperatures_c=(hi - 5.0, hi), power_off_s=(), cycles=(1,))
    ex = sp.experiments()
    ramps = sorted((e.start_temperature_c, e.ramp_to_c) for e in ex if e.event == "ramp")
    # hi - 5: -20 K and +5 K (clipped); hi: only -20 K (+20 K would not move)
    assert ramps == [(hi - 5.0, hi - 25.0), (hi - 5.0, hi), (hi, hi - 20.0)]


def test_grid_drops_power_cycles_ending_after_the_longest_run():
    sp = Space(start_temperatures_c=(20.0,), max_duration_s=6000.0, ramps_k=())
    ex = sp.experiments()
    # one cycle of S s ends at 3600 + S (at most 5400: kept); 4 cycles end at
    # 3600 + 3 x 1200 + S > 7200 and two (20 s, 120 s) at 3600 + 1200 + 120 = 4920: kept
    offs = sorted((e.power_off_s, e.cycles) for e in ex if e.event == "power_off")
    assert offs == [(20.0, 2), (60.0, 1), (300.0, 1), (1800.0, 1)]
    assert all(e.event_end_s < 6000.0 for e in ex)


def test_grid_drops_ramps_ending_after_the_longest_run():
    sp = Space(start_temperatures_c=(20.0,), max_duration_s=3600.0, power_off_s=())
    ex = sp.experiments()
    assert all(e.event_end_s < sp.max_duration_s for e in ex)
    assert all(sp.durations_s(e).size for e in ex)


def test_every_neighbour_the_search_tries_is_runnable():
    # Oracle: the neighbours of a ramp that ends at the range's hot end stay inside the range
    # (T0 within the space's temperatures, the chamber within TEMPERATURE_RANGE_C), last the
    # space's longest run, and each gives run conditions.  A chamber above 85 C is unusual (nfs.ranges) but allowed: each program
    # ramping there says so, once, with a RangeWarning.
    from nfs.design.search import _neighbours
    from nfs.ranges import RangeWarning
    lo, hi = TEMPERATURE_RANGE_C
    t_range = (hi - 40.0, hi - 10.0)
    sp = Space(start_temperatures_c=t_range)
    best = Experiment(hi - 10.0, sp.max_duration_s, "ramp", 3600.0, ramp_to_c=hi)
    near = _neighbours(best, sp, t_range, 150.0)
    assert len(near) >= 8          # T0, event_s, dwell, rate and ramp end, each way
    for e in near:
        with pytest.warns(RangeWarning, match=r"key 'design\.program\[1\]\.ramp_to_c'.* is "
                                              r"unusual \(a chamber program runs within"):
            c = e.conditions(_base())
        assert t_range[0] <= c.start_temperature_c <= t_range[1]
        assert c.duration_s == sp.max_duration_s
        chamber = c.chamber_c(np.linspace(0.0, c.duration_s, 401))
        assert lo <= chamber.min() and chamber.max() <= hi
        assert chamber.max() == pytest.approx(e.ramp_to_c)       # the ramp reaches its end


# ---- default space ----------------------------------------------------------------------

def test_default_space_picks_coldest_middle_hottest():
    runs = [_run(t, f"r{i}") for i, t in enumerate([25.0, -10.0, 60.0, 5.0, 40.0, 25.0])]
    sp = default_space(runs)
    # distinct T0s sorted: -10, 5, 25, 40, 60 -> the middle is 25
    assert sp.start_temperatures_c == (-10.0, 25.0, 60.0)
    assert sp.min_duration_s == pytest.approx(2.0 * CYCLE_S)
    assert sp.soak_h == SOAK_H
    assert default_space(runs, soak_h=1.5).soak_h == 1.5
    assert len(sp.experiments()) == 27


def test_default_space_with_one_or_two_temperatures():
    assert default_space([_run(7.0), _run(7.0, "b")]).start_temperatures_c == (7.0,)
    assert default_space([_run(30.0), _run(-5.0, "b")]).start_temperatures_c == (-5.0, 30.0)
    with pytest.raises(NfsError):
        default_space([])
    with pytest.raises(NfsError):
        base_conditions([])


def test_base_conditions_from_the_first_run():
    c = base_conditions([_run(12.0, fs=None), _run(30.0, "b", fs=4.0)])
    assert c.sample_rate_hz == pytest.approx(2.0)          # from the time axis (0.5 s)
    assert c.schedule == Schedule(POS, DWELL, MOVE)
    assert c.start_temperature_c == 12.0 and c.latitude_deg == 30.0
    assert c.true_heading_deg == 40.0
    assert base_conditions([_run(12.0, fs=4.0)]).sample_rate_hz == 4.0


def test_two_power_cycles_of_different_off_times():
    # Oracle: the program and the off spans written out by hand
    e = Experiment(0.0, 7200.0, "power_off", 900.0, 20.0, cycles=2, every_s=1200.0,
                   power_off_2_s=120.0)
    assert e.off_times_s() == (20.0, 120.0)
    assert e.program() == [{"hold_s": 900.0}, {"power_off_s": 20.0}, {"hold_s": 1180.0},
                           {"power_off_s": 120.0}, {"hold_s": 7200.0 - 2220.0}]
    assert e.off_spans_s() == ((900.0, 920.0), (2100.0, 2220.0))
    assert e.event_end_s == 2220.0
    assert "off for 20 s, then on again; 20 min later off for 2 min" in e.describe()
    for bad in ({"cycles": 1}, {"cycles": 3}, {"power_off_2_s": 1500.0},
                {"power_off_2_s": 0.0}):
        kw = {"cycles": 2, "every_s": 1200.0, "power_off_2_s": 120.0, **bad}
        with pytest.raises(NfsError, match="power_off_2_s"):
            Experiment(0.0, 7200.0, "power_off", 900.0, 20.0, **kw)


def test_neighbours_never_propose_a_power_cycle_shorter_than_a_warm_restart():
    # Oracle: the table of ranges' shortest typical power cycle (10 s): the refinement halves
    # and stretches off times, and stops there (a 5 s drop of the supply is a glitch)
    import warnings
    from nfs.design.search import SHORTEST_OFF_S, _neighbours
    assert SHORTEST_OFF_S == 10.0
    sp = Space(start_temperatures_c=(-20.0, 20.0))
    for e in (Experiment(20.0, sp.max_duration_s, "power_off", 3600.0, 10.0),
              Experiment(20.0, sp.max_duration_s, "power_off", 3600.0, 20.0, cycles=2,
                         every_s=1200.0, power_off_2_s=120.0)):
        near = [x for x in _neighbours(e, sp, (-20.0, 20.0), 150.0)
                if x.event == "power_off"]
        assert near and all(min(x.off_times_s()) >= SHORTEST_OFF_S for x in near)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            for x in near:
                x.conditions(_base())
