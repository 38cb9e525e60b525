"""Bookkeeping columns of the tracker: selection and concatenation keep rows aligned."""

import numpy as np

from seatrack.filters.base import Plots
from seatrack.tracking.tracks import PendingPlots
from seatrack.tracking.tracks import TrackTable
from seatrack.tracking.tracks import concat_plots


def _table(ids):
    n = len(ids)
    return TrackTable(np.array(ids), np.linspace(-1, 1, n), np.arange(n) % 2 == 0,
                      np.arange(n), np.arange(n) + 1, np.zeros(n, np.int64))  # fmt: skip


def test_track_table_take_and_concat():
    a, b = _table([1, 2, 3]), _table([7, 8])
    both = TrackTable.concat([a, b])
    assert both.id.tolist() == [1, 2, 3, 7, 8] and len(both) == 5
    sub = both.take(np.array([4, 0]))
    assert sub.id.tolist() == [8, 1] and sub.logit[1] == a.logit[0] and sub.hits[0] == b.hits[1]
    assert len(TrackTable.empty()) == 0


def _pending(t, n, scan):
    p = Plots(np.full(n, t), np.arange(1.0, n + 1) * 1000, np.zeros(n), None,
              np.arange(n, dtype=float))  # fmt: skip
    return PendingPlots(p, p.positions(), np.zeros((n, 2, 2)), np.arange(n) + 10 * scan,
                        np.full(n, scan), np.full(n, -float(scan)))  # fmt: skip


def test_pending_plots_concat_and_take():
    a, b = _pending(0.0, 2, 0), _pending(2.5, 3, 1)
    c = PendingPlots.concat([a, b])
    assert len(c) == 5 and c.seq.tolist() == [0, 1, 10, 11, 12]
    assert c.plots.range_rate is not None and c.plots.t.tolist() == [0, 0, 2.5, 2.5, 2.5]
    d = c.take(np.array([3]))
    assert d.seq.tolist() == [11] and d.log_prior.tolist() == [-1.0] and d.scan.tolist() == [1]


def test_concat_plots_drops_columns_missing_somewhere():
    a = Plots(np.zeros(1), np.ones(1), np.zeros(1), None, np.ones(1))
    b = Plots(np.zeros(2), np.ones(2), np.zeros(2))
    c = concat_plots([a, b])
    assert len(c) == 3 and c.range_rate is None and c.sensor.shape == (3, 3)
