"""Incremental TMA: bearings one by one, warm-started."""

import numpy as np
import pytest

from seatrack.simulate.tma import classic_scenario
from seatrack.tma import SupportValue
from seatrack.tma import TMATracker
from seatrack.tma import solve

SC = classic_scenario()


def test_incremental_matches_batch_at_every_step():
    b = SC.bearings(np.random.default_rng(31))
    tr = TMATracker(sigma=SC.sigma)
    out = [tr.add(t, z, o) for t, z, o in zip(b.t, b.bearing, b.observer, strict=True)]
    assert out[:3] == [None, None, None]
    assert len(tr) == len(b) and len(tr.history) == len(b) - 3
    final = tr.solution
    assert final is not None and final.converged and final.observable
    batch = solve(b, sigma=SC.sigma)
    assert np.allclose(final.state, batch.state, rtol=1e-5, atol=1e-2)
    # before the own-ship turn (samples 1-13) the geometry is not observable
    assert not out[10].observable
    assert out[-1].observable


def test_tracker_support_and_manoeuvre_and_errors():
    b = SC.bearings(np.random.default_rng(32))
    tr = TMATracker(sigma=SC.sigma, manoeuvres=[900.0])
    o = SC.observer.pos[5, :2]
    tr.add_support(SupportValue("range", float(SC.times[5]), 4000.0, 100.0, (o[0], o[1])))
    for i in range(8):
        s = tr.add(b.t[i], b.bearing[i], b.observer[i])
    assert s is not None and s.state.size == 4  # the leg starting at 900 s is not reached yet
    assert s.observable  # the range support value fixes the scale before the own-ship turn
    for i in range(8, 20):
        s = tr.add(b.t[i], b.bearing[i], b.observer[i])
    assert s.state.size == 6 and np.allclose(s.manoeuvres, [900.0])
    with pytest.raises(ValueError, match="not after"):
        tr.add(b.t[5], 1.0, (0.0, 0.0))
    with pytest.raises(ValueError, match="finite"):
        tr.add(b.t[-1] + 1000, np.nan, (0.0, 0.0))
