"""Simulated scenes: interpolation, plots with detection and clutter, corrupted AIS."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seatrack.filters.base import SensorNoise
from seatrack.fusion import scenario as sc
from seatrack.fusion.coverage import Coverage
from seatrack.geometry import geodetic_to_enu
from seatrack.io.radar import RadarSite

T0 = 1.7e9


def _truth() -> sc.Truth:
    start = np.array([[-5000.0, 0.0], [0.0, 5000.0], [3000.0, -3000.0]])
    return sc.straight_truth(start, np.array([90.0, 180.0, 0.0]), np.array([10.0, 10.0, 5.0]),
                             T0, 600.0)  # fmt: skip


def test_interpolate_is_linear_between_samples() -> None:
    tr = _truth()
    v, pos, vel = sc.interpolate(tr, T0 + 95.0)
    assert v.tolist() == [0, 1, 2]
    speed = 10.0 * 1852.0 / 3600.0
    assert np.allclose(pos[0], [-5000.0 + speed * 95.0, 0.0])
    assert np.allclose(vel[1], [0.0, -speed], atol=1e-9)
    assert sc.interpolate(tr, T0 + 601.0)[0].size == 0


def test_plots_follow_detection_probability_and_clutter() -> None:
    site = RadarSite(lat=math.radians(56.0), lon=math.radians(7.0), max_range=20000.0,
                     detection_probability=0.8)  # fmt: skip
    cov = Coverage.of(site, land=False)
    rng = np.random.default_rng(4)
    scans = np.arange(T0, T0 + 600.0, 3.0)
    plots, lab = sc.simulate_plots(_truth(), scans, cov, SensorNoise(), 3.0, rng)
    n = scans.size
    hits = np.bincount(lab[lab >= 0], minlength=3) / n
    assert np.all(np.abs(hits - 0.8) < 4 * math.sqrt(0.8 * 0.2 / n))
    clutter = (lab < 0).sum() / n
    assert abs(clutter - 3.0) < 4 * math.sqrt(3.0 / n)
    assert np.all((plots.azimuth >= 0) & (plots.azimuth < 2 * math.pi))


def test_ais_reports_carry_the_corruption() -> None:
    tr = _truth()
    rng = np.random.default_rng(5)
    corr = sc.Corruption(
        dark=(0,), spoof=(2,), spoof_offset=((2000.0, 0.0),), spoof_start=(T0 + 300.0,),
        spoof_end=(T0 + 700.0,), shared=((2, 1),),
    )  # fmt: skip
    rep, who = sc.ais_reports(tr, np.full(3, 10.0), (56.0, 7.0), corr, 0.0, rng)
    assert 0 not in who  # dark: no report
    assert set(rep.mmsi[who == 1]) == {tr.mmsi[2]}  # vessel 1 sends vessel 2's MMSI
    xy = geodetic_to_enu(rep.lat, rep.lon, 0.0, 56.0, 7.0)[:, :2]
    mine = who == 2
    for k in np.flatnonzero(mine):
        v, pos, _ = sc.interpolate(tr, float(rep.t[k]))
        moved = np.hypot(*(xy[k] - pos[list(v).index(2)]))
        want = 2000.0 if rep.t[k] >= T0 + 300.0 else 0.0
        assert moved == pytest.approx(want, abs=0.05)
    assert np.all(np.diff(rep.t) >= 0)
