"""Per-vessel tangent planes of the AIS tracker, compiled: the numbers of
:func:`seatrack.geometry.local_frames`, :func:`~seatrack.geometry.north_convergence` and
:func:`~seatrack.geometry.local_to_geodetic`, bit for bit, vessel by vessel on all threads.

WGS84 geodetic -> ECEF is written out as PROJ's ``cart`` conversion computes it (the
operation :mod:`seatrack.geometry` calls through pyproj): ``N = a / sqrt(1 - e^2 sin^2
phi)``, ``X = N cos phi cos lam``, ``Y = N cos phi sin lam``, ``Z = N (1 - e^2) sin phi``
at sea level, with PROJ's degree factor and ``e^2 = 2 f - f^2`` (tested equal to pyproj on
random points of the whole globe). The way back (ECEF -> geodetic) stays with pyproj, the
rows split over threads (pyproj releases the GIL); the arctangents stay with NumPy (its
vectorised ``arctan2`` rounds differently from the C library's in the last bit).
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache
from typing import Any

import numba
import numpy as np
from numba import njit
from numba import prange
from numpy.typing import NDArray

from seatrack.filters.ais.kernel import vessel_chunks
from seatrack.geometry import wrap_2pi

FloatArray = NDArray[np.float64]

__all__ = ["north_convergence_rows", "plane_to_wgs84", "vessel_planes"]

#: WGS84 semi-major axis (m) and squared eccentricity as PROJ derives it from 1/f
A_WGS84 = 6378137.0
_F = 1.0 / 298.257223563
ES_WGS84 = 2.0 * _F - _F * _F
#: PROJ's degree -> radian factor (the same double as pi / 180)
DEG_TO_RAD = 0.017453292519943296
#: sphere radius of the first guess of the height iteration (as local_to_geodetic)
_R_START = 2.0 * 6_371_000.0


@njit(cache=True, inline="always")
def _ecef(lat_deg, lon_deg):  # pragma: no cover - compiled
    """ECEF (m) of a point at sea level, as PROJ's ``cart`` (see the module docstring)."""
    phi = lat_deg * DEG_TO_RAD
    lam = lon_deg * DEG_TO_RAD
    s = math.sin(phi)
    n = A_WGS84 / math.sqrt(1.0 - ES_WGS84 * s * s)
    cphi = math.cos(phi)
    return n * cphi * math.cos(lam), n * cphi * math.sin(lam), n * (1.0 - ES_WGS84) * s


@njit(cache=True, inline="always")
def _rotation(lat0_deg, lon0_deg):  # pragma: no cover - compiled
    """``(sin lat0, cos lat0, sin lon0, cos lon0)`` of the ENU rotation at an origin."""
    p = np.radians(lat0_deg)
    lam = np.radians(lon0_deg)
    return math.sin(p), math.cos(p), math.sin(lam), math.cos(lam)


@njit(cache=True, inline="always")
def _north_dots(lat_deg, lon_deg, sl0, cl0, so0, co0):  # pragma: no cover - compiled
    """True North at a point projected on the East and North axes of an origin's plane
    (the arguments of the arctangent of ``seatrack.geometry.north_convergence``)."""
    p = np.radians(lat_deg)
    lam = np.radians(lon_deg)
    sp, cp = math.sin(p), math.cos(p)
    n0, n1, n2 = -sp * math.cos(lam), -sp * math.sin(lam), cp
    east = n0 * -so0 + n1 * co0 + n2 * 0.0
    north = n0 * (-sl0 * co0) + n1 * (-sl0 * so0) + n2 * cl0
    return east, north


@njit(cache=True, nogil=True, parallel=True)
def _planes(lat, lon, rows, starts, chunks, en, dots, lat0, lon0):  # pragma: no cover
    """Per vessel (sorted rows ``rows[starts[v]:starts[v + 1]]`` of the report table):
    origin = its first row in table order; East, North of every row in the origin's plane
    and the North dots of :func:`_north_dots`."""
    for c in prange(chunks.size - 1):
        for v in range(chunks[c], chunks[c + 1]):
            a, b = starts[v], starts[v + 1]
            o = rows[a]
            for k in range(a + 1, b):
                o = min(o, rows[k])
            la0, lo0 = lat[o], lon[o]
            x0, y0, z0 = _ecef(la0, lo0)
            sl, cl, so, co = _rotation(la0, lo0)
            for k in range(a, b):
                i = rows[k]
                x, y, z = _ecef(lat[i], lon[i])
                dx, dy, dz = x - x0, y - y0, z - z0
                en[k, 0] = -so * dx + co * dy
                en[k, 1] = -sl * co * dx - sl * so * dy + cl * dz
                dots[k, 0], dots[k, 1] = _north_dots(lat[i], lon[i], sl, cl, so, co)
                lat0[k] = la0
                lon0[k] = lo0


def _bearing_or_zero(dots: FloatArray) -> FloatArray:
    """``north_convergence``'s last step: the bearing of the dots, 0 where not finite."""
    gam = wrap_2pi(np.arctan2(dots[:, 0], dots[:, 1]))
    return np.where(np.isfinite(gam), gam, 0.0)


def vessel_planes(
    lat: FloatArray, lon: FloatArray, rows: NDArray[np.int64], starts: NDArray[np.int64]
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Tangent planes of the vessels of a report table.

    Parameters
    ----------
    lat, lon : (N,) WGS84 degrees of the table's rows.
    rows : (M,) the usable rows, sorted by vessel (and time); vessel ``v`` owns
        ``rows[starts[v]:starts[v + 1]]``.
    starts : (V + 1,) vessel boundaries.

    Returns
    -------
    en : (M, 2) East, North (m) of each row in its vessel's plane, whose origin is the
        vessel's first row in table order (``local_frames`` of the table).
    lat0, lon0 : (M,) the origin of each row's plane (deg).
    gamma : (M,) bearing (rad) of true North at the row in the plane
        (``north_convergence``).
    """
    m = rows.size
    en, dots = np.empty((m, 2)), np.empty((m, 2))
    lat0, lon0 = np.empty(m), np.empty(m)
    if m:
        chunks = vessel_chunks(starts, 8 * numba.get_num_threads())
        c = np.ascontiguousarray
        _planes(c(lat, dtype=np.float64), c(lon, dtype=np.float64), c(rows, dtype=np.int64),
                starts, chunks, en, dots, lat0, lon0)  # fmt: skip
    return en, lat0, lon0, _bearing_or_zero(dots)


@njit(cache=True, nogil=True, parallel=True)
def _dots_rows(lat, lon, lat0, lon0, dots):  # pragma: no cover - compiled
    for i in prange(lat.size):
        sl, cl, so, co = _rotation(lat0[i], lon0[i])
        dots[i, 0], dots[i, 1] = _north_dots(lat[i], lon[i], sl, cl, so, co)


def north_convergence_rows(
    lat: FloatArray, lon: FloatArray, lat0: FloatArray, lon0: FloatArray
) -> FloatArray:
    """:func:`seatrack.geometry.north_convergence` of rows (same numbers, compiled)."""
    dots = np.empty((lat.size, 2))
    if lat.size:
        c = np.ascontiguousarray
        _dots_rows(c(lat, dtype=np.float64), c(lon, dtype=np.float64),
                   c(lat0, dtype=np.float64), c(lon0, dtype=np.float64), dots)  # fmt: skip
    return _bearing_or_zero(dots)


@njit(cache=True, nogil=True, parallel=True)
def _to_ecef(e, n, u, lat0, lon0, xyz):  # pragma: no cover - compiled
    """Plane (East, North, Up) about per-row origins -> ECEF (``_enu_to_geodetic_at``)."""
    for i in prange(e.size):
        x0, y0, z0 = _ecef(lat0[i], lon0[i])
        sl, cl, so, co = _rotation(lat0[i], lon0[i])
        xyz[i, 0] = -so * e[i] - sl * co * n[i] + cl * co * u[i] + x0
        xyz[i, 1] = co * e[i] - sl * so * n[i] + cl * so * u[i] + y0
        xyz[i, 2] = cl * n[i] + sl * u[i] + z0


@lru_cache(maxsize=1)
def _inverse() -> Any:
    from pyproj import Transformer

    return Transformer.from_crs("EPSG:4978", "EPSG:4979", always_xy=True)


def _geodetic(xyz: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """ECEF -> (lat, lon, h) by pyproj, the rows split over two threads."""
    n = xyz.shape[0]
    out = np.empty((3, n))

    def part(sl: slice) -> None:
        lon, lat, h = _inverse().transform(xyz[sl, 0], xyz[sl, 1], xyz[sl, 2])
        out[0, sl], out[1, sl], out[2, sl] = lat, lon, h

    k = max(1, min(numba.get_num_threads(), n // 50_000))
    cuts = np.linspace(0, n, k + 1).astype(np.int64)
    parts = [slice(int(a), int(b)) for a, b in zip(cuts[:-1], cuts[1:], strict=True)]
    if k == 1:
        part(parts[0])
    else:
        with ThreadPoolExecutor(k) as pool:
            list(pool.map(part, parts))
    return out[0], out[1], out[2]


def plane_to_wgs84(
    east: FloatArray, north: FloatArray, lat0: FloatArray, lon0: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """:func:`seatrack.geometry.local_to_geodetic` (two height iterations; same numbers):
    plane East, North (m) about per-row origins (deg) -> WGS84 lat, lon (deg) at sea level;
    NaN where an input is not finite."""
    lat, lon = np.full(east.shape, np.nan), np.full(east.shape, np.nan)
    ok = np.isfinite(east) & np.isfinite(north) & np.isfinite(lat0) & np.isfinite(lon0)
    if not ok.any():
        return lat, lon
    e, n = east[ok], north[ok]
    la0, lo0 = lat0[ok], lon0[ok]
    u = -(e**2 + n**2) / _R_START
    xyz = np.empty((e.size, 3))
    for _ in range(2):
        _to_ecef(e, n, u, la0, lo0, xyz)
        u = u - _geodetic(xyz)[2]
    _to_ecef(e, n, u, la0, lo0, xyz)
    lat[ok], lon[ok], _ = _geodetic(xyz)
    return lat, lon
