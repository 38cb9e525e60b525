"""Line decimation for drawing: Douglas-Peucker ranks and one tolerance under a vertex budget.

A map of a national day of AIS (millions of smoothed positions, thousands of vessels) cannot
hand every vertex to a browser. Each polyline is simplified with the Douglas-Peucker (DP)
algorithm, computed once as a *rank* per vertex: the largest tolerance at which DP still
keeps that vertex. Keeping the vertices whose rank exceeds a tolerance ``eps`` gives exactly
the DP simplification at ``eps`` of every polyline at once, so one global tolerance can be
chosen to meet a total vertex budget (:func:`budget_tolerance`) -- detail goes where the
lines bend, not evenly to every vessel.

Ranks are computed in whatever planar coordinates the caller passes; the map uses Web
Mercator in units of the world width, where a tolerance is a fraction of a pixel at a given
zoom level (:func:`mercator`, :func:`pixel_size`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["budget_tolerance", "dp_ranks", "mercator", "mercator_rows", "pixel_size"]


def mercator(lat_deg: FloatArray, lon_deg: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Web Mercator coordinates in units of the world width (x east, y north).

    ``x = lon / 360``, ``y = ln(tan(pi/4 + lat/2)) / (2 pi)``; latitudes are clipped to the
    Web Mercator limit (85.0511 deg).
    """
    lat = np.radians(np.clip(lat_deg, -85.0511, 85.0511))
    return np.asarray(lon_deg, float) / 360.0, np.log(np.tan(np.pi / 4 + lat / 2)) / (2 * np.pi)


def mercator_rows(
    lat: FloatArray, lon: FloatArray, rows: IntArray
) -> tuple[FloatArray, FloatArray]:
    """:func:`mercator` of ``lat[rows], lon[rows]``, computed in place (two arrays in all)."""
    x = np.take(lon, rows).astype(np.float64, copy=False)
    x /= 360.0
    y = np.take(lat, rows).astype(np.float64, copy=False)
    np.clip(y, -85.0511, 85.0511, out=y)
    y *= np.pi / 360.0
    y += np.pi / 4
    np.tan(y, out=y)
    np.log(y, out=y)
    y /= 2 * np.pi
    return x, y


def pixel_size(zoom: float) -> float:
    """Size of one 256-px-tile pixel at ``zoom``, in units of the world width."""
    return 1.0 / (256.0 * 2.0**zoom)


@njit(cache=True)
def _seg_dist(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Distance of point p from segment a-b (to the nearer end beyond the segment)."""
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    if L2 > 0.0:
        u = ((px - ax) * dx + (py - ay) * dy) / L2
        u = min(1.0, max(0.0, u))
    else:
        u = 0.0
    ex, ey = px - ax - u * dx, py - ay - u * dy
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True)
def _dp_ranks(
    x: FloatArray, y: FloatArray, starts: IntArray, stops: IntArray, rank: FloatArray
) -> None:  # pragma: no cover - compiled
    """Fill ``rank`` for every polyline ``[starts[i], stops[i])`` (explicit stack, no recursion)."""
    n = x.size
    sa = np.empty(n + 1, np.int64)
    sb = np.empty(n + 1, np.int64)
    sr = np.empty(n + 1, np.float64)
    for i in range(starts.size):
        a, b = starts[i], stops[i] - 1
        if b < a:
            continue
        rank[a] = np.inf
        rank[b] = np.inf
        top = 0
        if b - a >= 2:
            sa[0], sb[0], sr[0] = a, b, np.inf
            top = 1
        while top > 0:
            top -= 1
            lo, hi, parent = sa[top], sb[top], sr[top]
            best, k = -1.0, lo + 1
            for j in range(lo + 1, hi):
                d = _seg_dist(x[j], y[j], x[lo], y[lo], x[hi], y[hi])
                if d > best:
                    best, k = d, j
            r = min(best, parent)  # a vertex never outlives the split that exposed it
            rank[k] = r
            if k - lo >= 2:
                sa[top], sb[top], sr[top] = lo, k, r
                top += 1
            if hi - k >= 2:
                sa[top], sb[top], sr[top] = k, hi, r
                top += 1


def dp_ranks(x: FloatArray, y: FloatArray, starts: IntArray, stops: IntArray) -> FloatArray:
    """Douglas-Peucker rank of every vertex of the polylines ``[starts[i], stops[i])``.

    Parameters
    ----------
    x, y : planar coordinates of all polylines, concatenated (any length unit).
    starts, stops : first and one-past-last index of each polyline (disjoint ranges).

    Returns
    -------
    rank : the largest tolerance (same unit as ``x, y``) at which DP keeps the vertex;
        ``inf`` for the end points of each polyline; NaN for vertices in no polyline.
        ``rank > eps`` selects the DP simplification at tolerance ``eps`` (distances to
        the chord measured to the segment, not the infinite line).
    """
    xs = np.ascontiguousarray(x, dtype=np.float64)
    ys = np.ascontiguousarray(y, dtype=np.float64)
    if xs.shape != ys.shape or xs.ndim != 1:
        raise ValueError("x and y must be 1-D arrays of one length")
    a = np.ascontiguousarray(starts, dtype=np.int64)
    b = np.ascontiguousarray(stops, dtype=np.int64)
    if a.shape != b.shape or np.any(b < a) or np.any(a < 0) or np.any(b > xs.size):
        raise ValueError("starts/stops must be ranges within the arrays")
    rank = np.full(xs.size, np.nan)
    _dp_ranks(xs, ys, a, b, rank)
    return rank


def budget_tolerance(rank: FloatArray, max_vertices: int, floor: float = 0.0) -> float:
    """Smallest tolerance ``eps >= floor`` with ``count(rank > eps) <= max_vertices``.

    End points (``rank = inf``) are always kept, so when they alone exceed the budget the
    result keeps only them (``eps`` = the largest finite rank). NaN ranks are ignored.
    """
    if max_vertices < 0:
        raise ValueError(f"max_vertices must be >= 0, got {max_vertices}")
    r = rank[np.isfinite(rank)]
    n_ends = int(np.sum(np.isposinf(rank)))
    room = max_vertices - n_ends
    if r.size == 0 or np.sum(r > floor) <= room:
        return float(floor)
    if room <= 0:
        return float(r.max())
    # keep the ``room`` largest finite ranks: eps = the (room+1)-th largest; ties at eps go
    return float(max(floor, np.partition(r, r.size - room - 1)[r.size - room - 1]))
