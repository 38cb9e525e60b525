"""Live AIS tracking against the batch AIS tracker's causal output."""

from __future__ import annotations

import numpy as np
import pytest

from live.streams import synthetic
from seatrack.filters.ais import track_reports
from seatrack.live.ais import SNAP_EVERY
from seatrack.live.ais import LiveAis
from seatrack.live.ais import causal_config


def batch_last(r):
    """Per vessel, the batch causal estimate of its last report that has one."""
    tr = track_reports(r, causal_config())
    out = {}
    for k in range(len(r)):
        if np.isfinite(tr.lat[k]):
            out[int(r.mmsi[k])] = (tr.lat[k], tr.lon[k], tr.speed[k], tr.course[k])
    return out


def live_picture(live: LiveAis):
    ids, tr, _ = live.tracks()
    return {m: (tr.lat[k], tr.lon[k], tr.speed[k], tr.course[k]) for k, m in enumerate(ids)}


def assert_same(a, b):
    assert a.keys() == b.keys()
    for m in a:
        np.testing.assert_allclose(a[m][:2], b[m][:2], rtol=0, atol=1e-8)  # deg
        np.testing.assert_allclose(a[m][2], b[m][2], rtol=0, atol=1e-7)  # m/s
        np.testing.assert_allclose(a[m][3], b[m][3], rtol=0, atol=1e-7)  # rad


def test_in_order_equals_batch_causal_every_report():
    r = synthetic()
    tr = track_reports(r, causal_config())
    live = LiveAis()
    flagged = 0
    for k in range(len(r)):
        live.add(r.mmsi[k : k + 1], r.t[k : k + 1], r.lat[k : k + 1], r.lon[k : k + 1],
                 r.sog_kn[k : k + 1], r.cog_deg[k : k + 1])  # fmt: skip
        v = live.vessels[int(r.mmsi[k])]
        est = v.estimate if v.report is not None and v.report.t == r.t[k] else None
        if not np.isfinite(tr.x_m[k]):
            assert est is None or v.report.t != r.t[k]
            continue
        assert est is not None
        np.testing.assert_allclose(est.state[:2], [tr.x_m[k], tr.y_m[k]], rtol=0, atol=1e-6)
        assert est.kind == tr.outlier_kind[k]
        assert est.segment == tr.segment[k]
        flagged += est.kind > 0
    assert flagged > 0  # the outlier logic was exercised
    assert tr.segment.max() >= 2  # and the gap split
    assert_same(live_picture(live), batch_last(r))


def test_out_of_order_within_window_equals_time_order():
    r = synthetic(seed=2)
    rng = np.random.default_rng(0)
    # arrival order: each report delayed by up to 8 s (message time unchanged)
    order = np.argsort(r.t + rng.uniform(0, 8, len(r)), kind="stable")
    live = LiveAis(window_s=10.0)
    used = live.add(r.mmsi[order], r.t[order], r.lat[order], r.lon[order],
                    r.sog_kn[order], r.cog_deg[order])  # fmt: skip
    assert used.all()
    assert (np.diff(r.t[order]) < 0).any()
    assert_same(live_picture(live), batch_last(r))


def test_older_than_window_is_late():
    r = synthetic(seed=3, vessels=1, reports=20)
    live = LiveAis(window_s=5.0)
    used = live.add(r.mmsi, r.t, r.lat, r.lon, r.sog_kn, r.cog_deg)
    assert used.all()
    before = live_picture(live)
    late = live.add(r.mmsi[:1], r.t[-1:] - 30.0, r.lat[:1], r.lon[:1], r.sog_kn[:1],
                    r.cog_deg[:1])  # fmt: skip
    assert not late.any()
    assert_same(live_picture(live), before)


@pytest.mark.parametrize("window", [0.0, 10.0])
def test_history_is_bounded_by_the_window(window):
    r = synthetic(seed=4, vessels=1, reports=50)
    live = LiveAis(window_s=window)
    live.add(r.mmsi, r.t, r.lat, r.lon, r.sog_kn, r.cog_deg)
    v = live.vessels[int(r.mmsi[0])]
    older = sum(t < v.times[-1] - window for t in v.times)  # kept back to a state
    assert older < SNAP_EVERY and v.with_state(0) == 0  # the first entry holds a state
    assert len(v.history) == len(v.times) < 10 + SNAP_EVERY - 1
