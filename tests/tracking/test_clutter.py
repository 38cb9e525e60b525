"""Surveillance region, clutter rate and detection probability from the data."""

import numpy as np
import pytest

from seatrack.filters.base import Plots
from seatrack.tracking.clutter import ClutterRate
from seatrack.tracking.clutter import DetectionRate
from seatrack.tracking.clutter import SurveillanceRegion


def _plots(rng, n, az_lo=0.0, az_hi=2 * np.pi):
    return Plots(np.zeros(n), rng.uniform(1000, 9000, n), rng.uniform(az_lo, az_hi, n))


def test_region_volume_full_circle_and_sector():
    rng = np.random.default_rng(0)
    full = SurveillanceRegion()
    sector = SurveillanceRegion()
    for _ in range(10):
        full.update(_plots(rng, 50))
        sector.update(_plots(rng, 50, np.radians(300), np.radians(420)))  # 120 deg across North
    assert full.volume(False, False) == pytest.approx(8000 * 2 * np.pi, rel=0.01)
    assert sector.azimuth_span() == pytest.approx(np.radians(120), abs=np.radians(2))


def test_region_needs_enough_plots_before_trusting_a_gap():
    r = SurveillanceRegion(min_plots=200)
    r.update(_plots(np.random.default_rng(1), 50, 0.0, 1.0))
    assert r.azimuth_span() == pytest.approx(2 * np.pi)


def test_clutter_rate_converges_to_the_mean_count():
    rng = np.random.default_rng(2)
    c = ClutterRate(memory=20)
    for n in rng.poisson(30, 400):
        c.update(n)
    assert c.per_scan == pytest.approx(30, rel=0.2)
    assert ClutterRate(given=7.0).per_scan == 7.0


def test_detection_rate():
    d = DetectionRate(prior=0.9, weight=20)
    for _ in range(100):
        d.update(hits=8, misses=2)  # 80 %
    assert d.pd == pytest.approx(0.8, abs=0.01)
    assert DetectionRate(given=0.95).pd == 0.95


def test_plots_that_start_tracks_leave_the_clutter_count_of_their_scan():
    c = ClutterRate(None, memory=10.0)
    c.update(20.0)  # first scan: every plot unexplained
    c.update(11.0)
    c.explain_earlier(9.0, scans_ago=1)  # the first scan's target plots started tracks
    forget = 1 - 1 / 10
    assert c.per_scan == pytest.approx((forget * 11.0 + 11.0) / (forget + 1.0))
    c.explain_earlier(1e6, 1)
    assert c.per_scan == pytest.approx(0.1)  # never below the floor
