"""Douglas-Peucker ranks against a textbook recursive Douglas-Peucker, and the budget."""

from __future__ import annotations

import numpy as np
import pytest

from seatrack.report.decimate import budget_tolerance
from seatrack.report.decimate import dp_ranks
from seatrack.report.decimate import mercator
from seatrack.report.decimate import mercator_rows
from seatrack.report.decimate import pixel_size


def _seg_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    d = b - a
    L2 = float(d @ d)
    u = 0.0 if L2 == 0 else min(1.0, max(0.0, float((p - a) @ d) / L2))
    return float(np.hypot(*(p - a - u * d)))


def _dp_reference(pts: np.ndarray, eps: float) -> list[int]:
    """Recursive Douglas-Peucker: indices kept at tolerance ``eps`` (distance > eps kept)."""

    def rec(i: int, j: int) -> list[int]:
        if j - i < 2:
            return []
        d = [_seg_dist(pts[k], pts[i], pts[j]) for k in range(i + 1, j)]
        k = i + 1 + int(np.argmax(d))
        if d[k - i - 1] <= eps:
            return []
        return rec(i, k) + [k] + rec(k, j)

    n = len(pts)
    return sorted({0, n - 1, *rec(0, n - 1)}) if n else []


@pytest.mark.parametrize("seed", range(6))
def test_ranks_reproduce_recursive_douglas_peucker(seed: int) -> None:
    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 60, size=5)
    xy = [np.cumsum(rng.normal(size=(s, 2)), axis=0) for s in sizes]
    x = np.concatenate([p[:, 0] for p in xy])
    y = np.concatenate([p[:, 1] for p in xy])
    stops = np.cumsum(sizes)
    starts = stops - sizes
    rank = dp_ranks(x, y, starts, stops)
    for eps in (0.0, 0.3, 1.0, 2.5, 10.0):
        for p, a, b in zip(xy, starts, stops, strict=True):
            got = np.flatnonzero(rank[a:b] > eps).tolist()
            assert got == _dp_reference(p, eps), (seed, eps)


def test_ranks_of_a_closed_ring_and_repeated_points() -> None:
    # square ring that returns to its start, then a polyline of one repeated point
    x = np.array([0.0, 1, 1, 0, 0, 5, 5, 5])
    y = np.array([0.0, 0, 1, 1, 0, 5, 5, 5])
    r = dp_ranks(x, y, np.array([0, 5]), np.array([5, 8]))
    assert np.isinf(r[[0, 4, 5, 7]]).all()
    assert r[6] == 0.0  # a repeated point adds nothing
    assert np.all(np.isfinite(r[1:4])) and np.all(r[1:4] > 0)


def test_gaps_between_polylines_are_nan_and_bad_ranges_refused() -> None:
    r = dp_ranks(np.arange(5.0), np.zeros(5), np.array([0]), np.array([2]))
    assert np.isnan(r[2:]).all()
    with pytest.raises(ValueError):
        dp_ranks(np.arange(5.0), np.zeros(5), np.array([3]), np.array([2]))
    with pytest.raises(ValueError):
        dp_ranks(np.arange(5.0), np.zeros(5), np.array([0]), np.array([6]))


def test_budget_tolerance_meets_the_budget() -> None:
    rng = np.random.default_rng(1)
    x, y = np.cumsum(rng.normal(size=(2, 10_000)), axis=1)
    starts = np.arange(0, 10_000, 1000)
    rank = dp_ranks(x, y, starts, starts + 1000)
    for budget in (20, 100, 1234, 5000, 10_000):
        eps = budget_tolerance(rank, budget)
        kept = int(np.sum(rank > eps))
        assert kept <= budget
        if budget < 10_000:
            assert kept >= 0.95 * budget  # not far below it either (ties only)
    # end points alone exceed the budget: only they stay
    eps = budget_tolerance(rank, 5)
    assert np.sum(rank > eps) == 20
    # a floor is respected even when the budget is generous
    assert budget_tolerance(rank, 10_000, floor=0.5) == 0.5
    with pytest.raises(ValueError):
        budget_tolerance(rank, -1)
    # only end points (two-point lines), more than the budget: nothing else to drop
    ends = dp_ranks(np.arange(6.0), np.zeros(6), np.array([0, 2, 4]), np.array([2, 4, 6]))
    assert budget_tolerance(ends, 2, floor=0.1) == 0.1


def test_mercator_and_pixel_size() -> None:
    x, y = mercator(np.array([0.0, 85.0511, -85.0511, 45.0]), np.array([0.0, 180.0, -180.0, 90]))
    np.testing.assert_allclose(x, [0.0, 0.5, -0.5, 0.25])
    np.testing.assert_allclose(y[:3], [0.0, 0.5, -0.5], atol=1e-6)  # square world
    np.testing.assert_allclose(y[3], np.log(np.tan(np.pi * 3 / 8)) / (2 * np.pi))
    assert pixel_size(0) == 1 / 256 and pixel_size(1) == 1 / 512


def test_mercator_rows_is_mercator_of_the_rows() -> None:
    rng = np.random.default_rng(2)
    lat, lon = rng.uniform(-89, 89, 50), rng.uniform(-180, 180, 50)
    rows = rng.integers(0, 50, 30)
    lat0, lon0 = lat.copy(), lon.copy()
    x, y = mercator_rows(lat, lon, rows)
    xr, yr = mercator(lat[rows], lon[rows])
    np.testing.assert_allclose(x, xr, rtol=0, atol=1e-15)
    np.testing.assert_allclose(y, yr, rtol=1e-13, atol=1e-15)
    np.testing.assert_array_equal(lat, lat0)  # computed in place, but not in the inputs
    np.testing.assert_array_equal(lon, lon0)
