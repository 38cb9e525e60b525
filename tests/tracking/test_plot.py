"""The picture of a multi-target run."""

import numpy as np

from seatrack.tracking.plot import tracks_figure


def test_figure_has_the_plan_view_and_the_gospa_panel():
    rng = np.random.default_rng(0)
    pos = rng.uniform(-5000, 5000, (50, 2))
    lab = np.where(rng.random(50) < 0.5, -1, rng.integers(1, 4, 50))
    t = np.repeat(np.arange(5.0), 3)
    trk = np.tile([1, 2, 3], 5)
    st = np.tile([0, 1, 2], 5)
    xy = rng.uniform(-5000, 5000, (15, 2))
    g = {"t": np.arange(5.0), "gospa": np.ones(5), "localisation": np.ones(5),
         "missed": np.zeros(5), "false": np.zeros(5)}  # fmt: skip
    fig = tracks_figure(pos, lab, t, trk, st, xy, {7: xy[:4]}, g, "test")
    assert len(fig.axes) == 2
    assert fig.axes[1].get_title() == "GOSPA over time"
    fig = tracks_figure(pos, lab, t, trk, st, xy)
    assert len(fig.axes) == 1
