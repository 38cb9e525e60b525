"""Where a radar can see a vessel: range limits, blind sectors, radar horizon, land shadow.

A point (East ``x``, North ``y`` in metres about the antenna) is *covered* when all of

* ``min_range <= r <= max_range`` with ``r = hypot(x, y)``;
* its true bearing lies in no blind sector (:func:`in_sectors`);
* ``r`` is within the radar horizon of the antenna and the target heights
  (:func:`radar_horizon_m`);
* no land lies between the antenna and the point, and the point itself is not on land
  (:class:`LandShadow`, from the bundled Natural Earth coast).

The fusion calls nothing outside coverage dark or not seen. Every test is vectorised over
the points; the land shadow is computed once per site on a polar grid and looked up.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import bearing
from seatrack.geometry import geodetic_to_enu
from seatrack.geometry import polar_to_cart
from seatrack.io.radar import RadarSite
from seatrack.report.land import Rings
from seatrack.report.land import clip_rings
from seatrack.report.land import natural_earth_land

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

__all__ = [
    "EARTH_RADIUS_M",
    "EFFECTIVE_EARTH_FACTOR",
    "Coverage",
    "LandShadow",
    "in_sectors",
    "land_shadow",
    "radar_horizon_m",
    "rasterize_rings",
]

#: mean Earth radius (m)
EARTH_RADIUS_M = 6_371_000.0
#: effective Earth radius factor of the standard atmosphere (refraction bends the beam)
EFFECTIVE_EARTH_FACTOR = 4.0 / 3.0
#: metres per degree of latitude (box sizes only)
_M_PER_DEG = 111_320.0


def radar_horizon_m(
    antenna_height_m: ArrayLike, target_height_m: ArrayLike, k: float = EFFECTIVE_EARTH_FACTOR
) -> FloatArray:
    """Range (m) at which a target of height ``h_t`` rises above the radar horizon.

    ``d = sqrt(2 k R h_a) + sqrt(2 k R h_t)`` with the effective Earth radius ``k R``
    (``k = 4/3`` for the standard refracting atmosphere; M. I. Skolnik, *Introduction to
    Radar Systems*, 3rd ed., 2001, sec. 8.2). With heights in metres it is the familiar
    ``4.12 km (sqrt(h_a) + sqrt(h_t))``.
    """
    kr2 = 2.0 * k * EARTH_RADIUS_M
    ha = np.maximum(np.asarray(antenna_height_m, float), 0.0)
    ht = np.maximum(np.asarray(target_height_m, float), 0.0)
    return np.asarray(np.sqrt(kr2 * ha) + np.sqrt(kr2 * ht), float)


def in_sectors(bearing_rad: ArrayLike, sectors: Sequence[tuple[float, float]]) -> BoolArray:
    """Whether each true bearing (rad) lies in any sector ``(from, to)`` (rad, clockwise).

    The vectorised form of :func:`seatrack.io.radar.in_sector`: a sector runs clockwise
    from its first bearing to its second and may cross North.
    """
    b = np.asarray(bearing_rad, float)
    out = np.zeros(b.shape, bool)
    turn = 2.0 * math.pi
    for a, z in sectors:
        out |= np.mod(b - a, turn) <= (z - a) % turn
    return out


def rasterize_rings(
    x: FloatArray,
    y: FloatArray,
    offsets: NDArray[np.int64],
    x0: float,
    y0: float,
    cell: float,
    nx: int,
    ny: int,
) -> BoolArray:
    """Even-odd fill of closed rings on a grid: ``(ny, nx)`` bool, True inside.

    Cell ``(i, j)`` has its centre at ``(x0 + (j + 0.5) cell, y0 + (i + 0.5) cell)``.
    Scan-line fill, vectorised: every edge crossing a row's centre line toggles the parity
    of all cells whose centre lies east of the crossing (a cumulative sum along the row).
    """
    grid = np.zeros((ny, nx + 1), np.int32)
    n = int(offsets[-1]) if offsets.size else 0
    if n == 0:
        return np.zeros((ny, nx), bool)
    nxt = np.arange(1, n + 1)
    nxt[offsets[1:] - 1] = offsets[:-1]
    ya, yb = (y - y0) / cell - 0.5, (y[nxt] - y0) / cell - 0.5  # in row units
    xa, xb = (x - x0) / cell - 0.5, (x[nxt] - x0) / cell - 0.5
    lo = np.ceil(np.minimum(ya, yb)).astype(np.int64)
    hi = np.ceil(np.maximum(ya, yb)).astype(np.int64)  # rows lo..hi-1 (half-open)
    lo, hi = np.clip(lo, 0, ny), np.clip(hi, 0, ny)
    counts = np.maximum(hi - lo, 0)
    edge = np.repeat(np.arange(n), counts)
    row = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) + lo[edge]
    f = (row - ya[edge]) / (yb[edge] - ya[edge])
    xc = xa[edge] + f * (xb[edge] - xa[edge])
    col = np.clip(np.ceil(xc).astype(np.int64), 0, nx)  # first cell centre east of it
    np.add.at(grid, (row, col), 1)
    return (np.cumsum(grid, axis=1)[:, :nx] % 2).astype(bool)


@dataclass(frozen=True)
class LandShadow:
    """Land on a polar grid about the antenna: ``blocked[a, k]`` is True when cell ``k``
    (range ``[k, k+1) * range_cell``) of azimuth bin ``a`` lies on land or behind land.

    Land that holds the antenna itself (the cells from the antenna out to the first sea
    cell of each ray) blocks nothing: a coastal radar stands on land.
    """

    blocked: BoolArray
    range_cell: float

    def shadowed(self, x: ArrayLike, y: ArrayLike) -> BoolArray:
        """Whether each point (East, North, m) is on land or behind land."""
        xa, ya = np.asarray(x, float), np.asarray(y, float)
        n_az, n_r = self.blocked.shape
        a = np.floor(bearing(xa, ya) * (n_az / (2.0 * math.pi))).astype(np.int64) % n_az
        k = np.floor(np.hypot(xa, ya) / self.range_cell).astype(np.int64)
        inside = (k >= 0) & (k < n_r)
        out = np.zeros(xa.shape, bool)
        out[inside] = self.blocked[a[inside], k[inside]]
        return out


def land_shadow(
    site: RadarSite,
    range_cell_m: float = 100.0,
    azimuth_bins: int = 2048,
    rings: Rings | None = None,
) -> LandShadow:
    """The land shadow of ``site`` out to its ``max_range`` (:class:`LandShadow`).

    The coast (``rings``, degrees; default the bundled Natural Earth 1:10m land) is clipped
    to a box around the site, brought to the site's East-North plane
    (:func:`seatrack.geometry.geodetic_to_enu`), filled on a square grid of
    ``range_cell_m`` cells (:func:`rasterize_rings`), sampled at the centres of the polar
    cells, and every cell at or beyond the first land cell of its ray (after the
    antenna's own land) is blocked.
    """
    rmax = site.max_range + range_cell_m
    lat0, lon0 = math.degrees(site.lat), math.degrees(site.lon)
    dlat = rmax / _M_PER_DEG
    dlon = dlat / max(math.cos(site.lat), 1e-3)
    src = natural_earth_land() if rings is None else rings
    r = clip_rings(src, lon0 - dlon, lat0 - dlat, lon0 + dlon, lat0 + dlat)
    n_r = int(math.ceil(site.max_range / range_cell_m)) + 1
    half = n_r + 1
    if r.offsets[-1] > 0:
        enu = geodetic_to_enu(r.lat, r.lon, 0.0, lat0, lon0)
        land_xy = rasterize_rings(
            enu[:, 0], enu[:, 1], r.offsets, -half * range_cell_m, -half * range_cell_m,
            range_cell_m, 2 * half, 2 * half,
        )  # fmt: skip
    else:
        land_xy = np.zeros((2 * half, 2 * half), bool)
    az = (np.arange(azimuth_bins) + 0.5) * (2.0 * math.pi / azimuth_bins)
    rng = (np.arange(n_r) + 0.5) * range_cell_m
    p = polar_to_cart(rng[None, :], az[:, None])
    col = np.clip(np.floor(p[..., 0] / range_cell_m).astype(np.int64) + half, 0, 2 * half - 1)
    row = np.clip(np.floor(p[..., 1] / range_cell_m).astype(np.int64) + half, 0, 2 * half - 1)
    land = land_xy[row, col]
    own = np.logical_and.accumulate(land, axis=1)  # the antenna's own land
    blocked = np.logical_or.accumulate(land & ~own, axis=1)
    return LandShadow(blocked, range_cell_m)


@dataclass(frozen=True)
class Coverage:
    """The coverage of one radar (see the module docstring); points in the radar's
    East-North plane (m), or WGS84 through :meth:`covered_geodetic`."""

    site: RadarSite
    shadow: LandShadow | None = None

    @classmethod
    def of(cls, site: RadarSite, land: bool = True, range_cell_m: float = 100.0) -> Coverage:
        """The coverage of ``site``, with the bundled coast's land shadow when ``land``."""
        return cls(site, land_shadow(site, range_cell_m) if land else None)

    @property
    def horizon_m(self) -> float:
        """Radar horizon (m) of the site's antenna and target heights."""
        return float(radar_horizon_m(self.site.antenna_height, self.site.target_height))

    def covered(self, x: ArrayLike, y: ArrayLike, margin_m: float = 0.0) -> BoolArray:
        """Whether the radar can see a target at each point (East ``x``, North ``y``, m);
        with ``margin_m``, also at the four points ``margin_m`` East, West, North and South
        of it (well inside coverage, not on its edge)."""
        xa, ya = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        if margin_m > 0:
            ok = self.covered(xa, ya)
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                ok &= self.covered(xa + dx * margin_m, ya + dy * margin_m)
            return ok
        r = np.hypot(xa, ya)
        s = self.site
        ok = (r >= s.min_range) & (r <= min(s.max_range, self.horizon_m)) & np.isfinite(r)
        if s.blind_sectors:
            ok &= ~in_sectors(bearing(xa, ya), s.blind_sectors)
        if self.shadow is not None:
            ok &= ~self.shadow.shadowed(xa, ya)
        return np.asarray(ok)

    def to_local(self, lat_deg: ArrayLike, lon_deg: ArrayLike) -> FloatArray:
        """WGS84 (deg) to the radar's East-North plane: ``(..., 2)`` metres."""
        s = self.site
        enu = geodetic_to_enu(lat_deg, lon_deg, 0.0, math.degrees(s.lat), math.degrees(s.lon))
        return np.asarray(enu[..., :2])

    def covered_geodetic(self, lat_deg: ArrayLike, lon_deg: ArrayLike) -> BoolArray:
        """:meth:`covered` for WGS84 points (deg)."""
        xy = self.to_local(lat_deg, lon_deg)
        return self.covered(xy[..., 0], xy[..., 1])
