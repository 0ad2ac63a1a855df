"""Tests of dwell and cycle segmentation (nfs.northfind.segment).

Oracle: the schedules are built by hand (or by synthetic_run with known dwell and move
lengths), so every dwell's angle, first and last sample are known in closed form.
"""

import numpy as np
import pytest

from nfs.errors import NfsError
from nfs.northfind import find_dwells, segment_cycles, synthetic_run

FWD_REV = (0.0, 90.0, 180.0, 270.0, 270.0, 180.0, 90.0, 0.0)


def _cols(run):
    c = run.columns
    return c["time_s"], c["position_deg"], c["moving"]


def test_sequential_schedule_dwells_and_cycles():
    # 4 positions, dwell 150 samples, move 10 samples at 1 Hz, 9000 s: cycle = 640 s, so
    # 14 complete cycles; dwell j of cycle c starts at 640 c + 160 j.
    run = synthetic_run(heading_deg=10.0, duration_s=9000.0)
    cycles = segment_cycles(*_cols(run), run.meta.positions_deg, dwell_s=run.meta.dwell_s)
    assert len(cycles) == 14
    for c, cyc in enumerate(cycles):
        np.testing.assert_array_equal(cyc.theta_deg, [0, 90, 180, 270])
        for j, d in enumerate(cyc.dwells):
            assert d.start == 640 * c + 160 * j
            assert d.stop - d.start == 150
            assert d.t_start_s == d.start and d.t_end_s == d.stop - 1
            assert not np.any(run.columns["moving"][d.index])
        assert cyc.t_start_s == 640 * c and cyc.t_end_s == 640 * c + 629
    # the schedule recovered from position_deg and moving is the same
    rec = segment_cycles(*_cols(run))
    assert [[d.start for d in c.dwells] for c in rec] == \
        [[d.start for d in c.dwells] for c in cycles]


@pytest.mark.parametrize("schedule_given", [True, False])
@pytest.mark.parametrize("skip_null_moves", [True, False])
def test_forward_reverse_repeated_angles_are_split(schedule_given, skip_null_moves):
    # Without null moves (270, 270) and (0 | 0) across cycles are single 300-sample blocks
    # that must be split in two dwells of 150; with them, separate blocks. Either way each
    # cycle has the 8 dwells of the schedule.
    run = synthetic_run(heading_deg=10.0, positions_deg=FWD_REV, n_cycles=4,
                        skip_null_moves=skip_null_moves)
    sched = run.meta.positions_deg if schedule_given else None
    dwell = run.meta.dwell_s if schedule_given else None
    cycles = segment_cycles(*_cols(run), sched, dwell_s=dwell)
    assert len(cycles) == 4
    for cyc in cycles:
        np.testing.assert_array_equal(cyc.theta_deg, FWD_REV)
        assert all(d.stop - d.start == 150 for d in cyc.dwells)
    if skip_null_moves:
        d3, d4 = cycles[0].dwells[3:5]
        assert d4.start == d3.stop  # the pair touches
        assert cycles[1].dwells[0].start == cycles[0].dwells[-1].stop


def test_settle_drops_the_start_of_every_dwell():
    # Oracle: at 1 Hz, settle_s = 20 drops exactly 20 samples of each 150-sample dwell,
    # including the second dwell of a touching pair.
    run = synthetic_run(heading_deg=10.0, positions_deg=FWD_REV, n_cycles=2)
    full = segment_cycles(*_cols(run), run.meta.positions_deg, dwell_s=150.0)
    settled = segment_cycles(*_cols(run), run.meta.positions_deg, dwell_s=150.0, settle_s=20.0)
    for a, b in zip(full, settled):
        for da, db in zip(a.dwells, b.dwells):
            assert db.start == da.start + 20 and db.stop == da.stop
    with pytest.raises(NfsError, match="settle_s"):
        segment_cycles(*_cols(run), run.meta.positions_deg, dwell_s=150.0, settle_s=150.0)


def test_partial_cycles_and_foreign_dwells_are_left_out():
    # Hand-built: a stray dwell at 45 deg, two full cycles 0-90-180-270, then 0, 90 (partial).
    blocks = [45, 0, 90, 180, 270, 0, 90, 180, 270, 0, 90]
    pos, mov = [], []
    for a in blocks:
        pos += [a] * 5 + [a] * 2
        mov += [0] * 5 + [1] * 2
    t = np.arange(len(pos), dtype=float)
    cycles = segment_cycles(t, np.array(pos, float), np.array(mov), [0, 90, 180, 270])
    assert len(cycles) == 2
    assert cycles[0].dwells[0].start == 7 and cycles[1].dwells[-1].stop == 7 * 8 + 5
    # recovered schedule: the first dwell (45) starts the sequence, period is the whole of it
    rec = segment_cycles(t, np.array(pos, float), np.array(mov))
    assert len(rec) == 1 and len(rec[0].dwells) == len(blocks)


def test_angle_mean_is_circular_and_jitter_is_tolerated():
    # Encoder jitter of +-0.01 deg around 0 (i.e. 359.99 and 0.01) must give theta ~ 0,
    # not 180, and must not split the dwell.
    pos = np.array([359.99, 0.01] * 50 + [90.0] * 100)
    mov = np.zeros(pos.size)
    t = np.arange(pos.size, dtype=float)
    dwells = find_dwells(t, pos, mov)
    assert len(dwells) == 2
    assert min(dwells[0].theta_deg, 360 - dwells[0].theta_deg) < 1e-9
    assert dwells[1].theta_deg == 90.0


def test_no_dwell_and_bad_input():
    t = np.arange(10.0)
    assert segment_cycles(t, np.zeros(10), np.ones(10)) == []
    with pytest.raises(NfsError, match="same length"):
        segment_cycles(t, np.zeros(9), np.zeros(10))
