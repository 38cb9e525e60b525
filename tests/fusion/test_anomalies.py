"""AIS anomalies: shared MMSIs split, jumps, reporting gaps."""

from __future__ import annotations

import numpy as np

from seatrack.fusion.anomalies import gap_limits
from seatrack.fusion.anomalies import reporting_gaps
from seatrack.fusion.anomalies import split_identities


def _line(t: np.ndarray, x0: float, y0: float, vx: float) -> np.ndarray:
    return np.stack([x0 + vx * (t - t[0]), np.full(t.size, y0)], -1)


def test_two_vessels_on_one_mmsi_are_split_and_flagged() -> None:
    rng = np.random.default_rng(3)
    ta = np.arange(0.0, 600.0, 10.0)
    tb = np.arange(5.0, 600.0, 10.0)
    t = np.r_[ta, tb]
    xy = np.r_[_line(ta, 0.0, 0.0, 6.0), _line(tb, 0.0, 4000.0, -5.0)]
    xy += 10.0 * rng.standard_normal(xy.shape)
    sog = np.r_[np.full(ta.size, 6.0), np.full(tb.size, 5.0)] / 0.514444
    cog = np.r_[np.full(ta.size, 90.0), np.full(tb.size, 270.0)]
    s = split_identities(np.full(t.size, 7), t, xy, sog, cog)
    assert s.vessel_mmsi.tolist() == [7, 7]
    truth = np.r_[np.zeros(ta.size), np.ones(tb.size)]
    right = np.mean(s.vessel == truth)
    assert right >= 0.99
    assert s.conflict.all() and not s.jump.any()


def test_one_wild_report_is_a_jump_not_a_vessel() -> None:
    t = np.arange(0.0, 300.0, 10.0)
    xy = _line(t, 0.0, 0.0, 5.0)
    xy[12] += [30000.0, 0.0]
    s = split_identities(np.full(t.size, 9), t, xy, np.full(t.size, 9.72), np.full(t.size, 90.0))
    assert np.flatnonzero(s.jump).tolist() == [12]
    assert s.vessel_mmsi.size == 1 and not s.conflict.any()
    assert (s.vessel[np.arange(t.size) != 12] == 0).all() and s.vessel[12] == -1


def test_a_lasting_move_flags_its_first_report_and_starts_a_new_segment() -> None:
    t = np.arange(0.0, 600.0, 10.0)
    xy = _line(t, 0.0, 0.0, 5.0)
    xy[30:] += [0.0, 3000.0]  # a spoofed position from t = 300 s on
    s = split_identities(np.full(t.size, 9), t, xy, np.full(t.size, 9.72), np.full(t.size, 90.0))
    assert np.flatnonzero(s.jump).tolist() == [30]
    assert s.vessel_sub[s.vessel[29]] == 0 and s.vessel_sub[s.vessel[31]] == 1
    assert not s.conflict.any()


def test_gap_limit_follows_the_own_reporting_rate() -> None:
    t = np.r_[np.arange(0.0, 100.0, 2.0), 400.0, np.arange(0.0, 3000.0, 180.0)]
    vessel = np.r_[np.zeros(51, np.int64), np.ones(17, np.int64)]
    limit = gap_limits(vessel, t, 2, gap_factor=3.0, min_gap_s=30.0)
    assert limit.tolist() == [30.0, 540.0]
    gaps = reporting_gaps(vessel, t, limit)
    assert np.flatnonzero(gaps).tolist() == [50]  # 98 s -> 400 s; the 180 s vessel is fine


def test_a_long_silence_continues_the_vessel_only_within_reach() -> None:
    t = np.r_[np.arange(0.0, 100.0, 10.0), np.arange(2000.0, 2100.0, 10.0)]
    xy = _line(t, 0.0, 0.0, 5.0)  # 2 km/400 s: resumes where the vessel can be
    s = split_identities(np.full(t.size, 4), t, xy, np.full(t.size, 9.72), np.full(t.size, 90.0))
    assert s.vessel_mmsi.size == 1 and not s.jump.any()
    xy[10:, 1] += 1e6  # 1000 km away after 1900 s: not reachable at 50 kn
    s = split_identities(np.full(t.size, 4), t, xy, np.full(t.size, 9.72), np.full(t.size, 90.0))
    assert s.vessel_mmsi.size == 2 and np.flatnonzero(s.jump).tolist() == [10]


def test_recent_intervals_give_the_gap_limits_of_their_times() -> None:
    """Pushed and bounded: the limit equals ``gap_limits`` of the times kept."""
    from seatrack.fusion.anomalies import RecentIntervals

    rng = np.random.default_rng(3)
    rec = RecentIntervals(8)
    times = np.cumsum(rng.uniform(1.0, 40.0, 30)).tolist()
    assert rec.limit(2.5, 30.0) == 30.0
    for t in times:
        rec.push(t)
        kept = np.array(rec.times)
        assert kept.size <= 8
        want = gap_limits(np.zeros(kept.size, np.int64), kept, 1, 2.5, 30.0)[0]
        assert rec.limit(2.5, 30.0) == want
