"""Coverage: range limits, blind sectors, radar horizon, land shadow from the coast."""

from __future__ import annotations

import math

import numpy as np

from seatrack.fusion.coverage import Coverage
from seatrack.fusion.coverage import in_sectors
from seatrack.fusion.coverage import land_shadow
from seatrack.fusion.coverage import radar_horizon_m
from seatrack.fusion.coverage import rasterize_rings
from seatrack.geometry import polar_to_cart
from seatrack.io.radar import RadarSite
from seatrack.io.radar import in_sector
from seatrack.report.land import Rings


def _site(**kw: float) -> RadarSite:
    return RadarSite(lat=math.radians(56.0), lon=math.radians(7.0), **kw)  # open North Sea


def test_horizon_matches_the_4_12_km_rule() -> None:
    # 4/3 Earth: d = 4.12 km (sqrt(ha) + sqrt(ht)) with heights in metres (Skolnik 8.2)
    d = radar_horizon_m(25.0, 9.0)
    assert abs(d - 4122.0 * (5.0 + 3.0)) < 0.002 * d
    assert radar_horizon_m(0.0, 0.0) == 0.0


def test_in_sectors_agrees_with_the_scalar_rule() -> None:
    rng = np.random.default_rng(0)
    b = rng.uniform(0, 2 * math.pi, 500)
    sectors = [
        (math.radians(350.0), math.radians(10.0)),
        (math.radians(120.0), math.radians(150.0)),
    ]
    want = [any(in_sector(x, s) for s in sectors) for x in b]
    assert np.array_equal(in_sectors(b, sectors), want)
    assert in_sectors(np.radians([0.0, 5.0, 355.0, 180.0]), sectors[:1]).tolist() == [
        True, True, True, False,
    ]  # fmt: skip


def test_range_sectors_and_horizon_bound_coverage() -> None:
    site = _site(
        antenna_height=20.0, target_height=4.0, min_range=100.0, max_range=60000.0,
        blind_sectors=((math.radians(80.0), math.radians(100.0)),),
    )  # fmt: skip
    cov = Coverage.of(site, land=False)
    horizon = cov.horizon_m
    assert 25000.0 < horizon < 27000.0  # 4.12 (sqrt 20 + sqrt 4) km = 26.7 km
    r = np.array([50.0, 1000.0, horizon - 100.0, horizon + 100.0, 5000.0])
    az = np.radians([0.0, 0.0, 200.0, 200.0, 90.0])
    xy = polar_to_cart(r, az)
    assert cov.covered(xy[:, 0], xy[:, 1]).tolist() == [False, True, True, False, False]


def test_rasterize_fills_a_square_and_its_hole_even_odd() -> None:
    outer = np.array([[0, 0], [10, 0], [10, 10], [0, 10.0]])
    hole = np.array([[3, 3], [7, 3], [7, 7], [3, 7.0]])
    xy = np.r_[outer, hole]
    grid = rasterize_rings(xy[:, 0], xy[:, 1], np.array([0, 4, 8]), -5.0, -5.0, 1.0, 20, 20)
    cx = np.arange(20) - 5 + 0.5
    inside_outer = (cx[None, :] > 0) & (cx[None, :] < 10) & (cx[:, None] > 0) & (cx[:, None] < 10)
    inside_hole = (cx[None, :] > 3) & (cx[None, :] < 7) & (cx[:, None] > 3) & (cx[:, None] < 7)
    assert np.array_equal(grid, inside_outer & ~inside_hole)


def _island(lat0: float, lon0: float, north_m: float, half_m: float) -> Rings:
    """A square island ``half_m`` wide each side, centred ``north_m`` North of the origin."""
    dlat = 1.0 / 111_320.0
    dlon = dlat / math.cos(math.radians(lat0))
    ys = np.array([north_m - half_m, north_m - half_m, north_m + half_m, north_m + half_m])
    xs = np.array([-half_m, half_m, half_m, -half_m])
    return Rings(lon0 + xs * dlon, lat0 + ys * dlat, np.array([0, 4]))


def test_land_shadows_what_lies_behind_it_only() -> None:
    site = _site(max_range=20000.0)
    island = _island(56.0, 7.0, 8000.0, 1000.0)
    cov = Coverage(site, land_shadow(site, 100.0, 2048, island))
    x = np.array([0.0, 0.0, 0.0, 0.0, 3000.0, 0.0])
    y = np.array([5000.0, 8000.0, 12000.0, 19000.0, 12000.0, -12000.0])
    # before the island, on it, behind it (twice), beside it, opposite side
    assert cov.covered(x, y).tolist() == [True, False, False, False, True, True]


def test_a_radar_on_land_sees_the_sea_beyond_its_own_coast() -> None:
    site = _site(max_range=20000.0)
    own = _island(56.0, 7.0, 0.0, 1500.0)  # the radar stands in the middle of it
    cov = Coverage(site, land_shadow(site, 100.0, 2048, own))
    assert cov.covered(np.array([0.0, 5000.0]), np.array([5000.0, 0.0])).all()


def test_bundled_coast_shadows_inland_points() -> None:
    # a radar near Gothenburg: points far inland Sweden (east) are behind land
    site = RadarSite(lat=math.radians(57.60), lon=math.radians(11.60), max_range=40000.0)
    cov = Coverage.of(site)
    inland = cov.covered_geodetic(np.array([57.70]), np.array([12.20]))
    open_sea = cov.covered_geodetic(np.array([57.55]), np.array([11.30]))
    assert not inland[0] and open_sea[0]


def test_margin_keeps_points_off_the_edges() -> None:
    site = _site(max_range=20000.0, blind_sectors=((math.radians(80.0), math.radians(100.0)),))
    cov = Coverage.of(site, land=False)
    x = np.array([0.0, 0.0, 2000.0, 5000.0])
    y = np.array([19800.0, 19000.0, 5000.0, 1000.0])  # near max range; inside; 22 deg; ~79 deg
    assert cov.covered(x, y).tolist() == [True, True, True, True]
    assert cov.covered(x, y, margin_m=500.0).tolist() == [False, True, True, False]
