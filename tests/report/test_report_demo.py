"""The situations of `seatrack demo` (seatrack.report.demo): the comparison's rows and anchor."""

from __future__ import annotations

import math

import numpy as np

from seatrack.filters.registry import METHODS
from seatrack.filters.registry import run
from seatrack.report.demo import SECTIONS
from seatrack.report.demo import WHEN
from seatrack.report.demo import rmse_rows
from seatrack.simulate.families import HEADLINE_SEEDS
from seatrack.simulate.families import labelled_runs
from seatrack.simulate.families import random_manoeuvres


def test_rows_and_the_hindsight_anchor():
    scs = [random_manoeuvres("ship", HEADLINE_SEEDS.start + i) for i in range(2)]
    grid = (0.01, 0.1, 1.0)
    rows, est = rmse_rows(scs, [("turning", {}), ("ekf", {"target": "ship"})], grid)
    assert [r.config for r in rows[:2]] == ["defaults", "target=ship"]
    anchor = rows[-1]
    assert anchor.method == "ekf" and anchor.ratio == 1.0 and "hindsight" in anchor.config
    # the anchor is the best EKF of the grid on these runs, computed independently here
    plots = labelled_runs(scs)
    cfg = {"sigma_range_m": 10.0, "sigma_azimuth_deg": math.degrees(scs[0].sensor.sigma_azimuth)}
    truth = np.stack([s.truth[:, :2] for s in scs])
    errs = []
    for q in grid:
        c = run("ekf", plots, {**cfg, "q": q})
        e = np.stack([c["x_m"], c["y_m"]], -1).reshape(2, -1, 2) - truth
        errs.append(np.sqrt(np.mean(np.sum(e[:, 10:] ** 2, -1))))
    assert math.isclose(anchor.value, min(errs), rel_tol=1e-12)
    for r in rows[:2]:
        assert math.isclose(r.ratio, r.value / anchor.value)
    assert est["turning"].shape == (2, len(scs[0].plots), 2)


def test_sections_and_sentences():
    assert list(SECTIONS) == [
        "turns", "range_rate", "outliers", "tma", "navigation", "ais", "multitarget",
    ]  # fmt: skip
    assert set(METHODS) <= set(WHEN)
    # one sentence each, no more
    assert all(s and ". " not in s and not s.endswith(".") for s in WHEN.values())
