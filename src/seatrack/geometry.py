"""Conventions: angles, bearings, polar <-> Cartesian, local ENU <-> geodetic, units.

This is the *only* module in seatrack that turns vectors into bearings. Every other
module calls :func:`bearing` / :func:`wrap_pi` rather than writing ``atan2`` itself.

Conventions (shared by all five methods, see ``docs/conventions.md``)
-----------------------------------------------------------------
* Horizontal frame: ``x`` = East, ``y`` = North, ``z`` = Up. Metres, seconds, radians.
* Bearing, course, heading and azimuth: clockwise from North, ``atan2(dx, dy)``.
  Wrapped to ``[0, 2*pi)`` for display (:func:`wrap_2pi`) and to ``(-pi, pi]`` for
  differences and innovations (:func:`wrap_pi`).
* Elevation: positive up from the horizontal plane.
* Degrees and knots appear only at the edges (I/O, CLI, plots) through the helpers
  at the end of this module.

All functions are pure and broadcast over leading array dimensions.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

TWO_PI = 2.0 * np.pi
KNOT_MPS = 1852.0 / 3600.0  #: one knot in metres per second (exact)
G0 = 9.80665  #: standard gravity, m/s^2


# ---------------------------------------------------------------------------
# Angles
# ---------------------------------------------------------------------------
def wrap_pi(angle: ArrayLike) -> Any:
    """Wrap an angle (rad) to the half-open interval ``(-pi, pi]``.

    Use for every angle *difference* (innovations, residuals, heading changes).
    """
    a = np.asarray(angle, dtype=float)
    w = np.mod(a + np.pi, TWO_PI) - np.pi  # [-pi, pi)
    w = np.where(w <= -np.pi, w + TWO_PI, w)
    return w if w.ndim else float(w)


def wrap_2pi(angle: ArrayLike) -> Any:
    """Wrap an angle (rad) to ``[0, 2*pi)`` (display form of bearings and courses)."""
    a = np.asarray(angle, dtype=float)
    w = np.mod(a, TWO_PI)
    w = np.where(w >= TWO_PI, 0.0, w)  # guard against mod returning 2*pi by rounding
    return w if w.ndim else float(w)


def angle_diff(a: ArrayLike, b: ArrayLike) -> Any:
    """Signed smallest difference ``a - b`` (rad), wrapped to ``(-pi, pi]``."""
    return wrap_pi(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def bearing(dx: ArrayLike, dy: ArrayLike) -> Any:
    """Bearing (rad, clockwise from North, ``[0, 2*pi)``) of the vector (dx East, dy North)."""
    return wrap_2pi(np.arctan2(dx, dy))


def bearing_between(p_from: ArrayLike, p_to: ArrayLike) -> Any:
    """Bearing (rad) from point ``p_from`` to ``p_to``; points are ``(..., 2+)`` East, North."""
    a = np.asarray(p_from, dtype=float)
    b = np.asarray(p_to, dtype=float)
    return bearing(b[..., 0] - a[..., 0], b[..., 1] - a[..., 1])


def course_speed(vx: ArrayLike, vy: ArrayLike) -> tuple[Any, Any]:
    """Course (rad, clockwise from North, ``[0, 2*pi)``) and speed (m/s) of a velocity."""
    vx_a = np.asarray(vx, dtype=float)
    vy_a = np.asarray(vy, dtype=float)
    spd = np.hypot(vx_a, vy_a)
    return bearing(vx_a, vy_a), (spd if spd.ndim else float(spd))


def velocity_from_course(course: ArrayLike, speed: ArrayLike) -> FloatArray:
    """Velocity ``(..., 2)`` (East, North; m/s) from course (rad) and speed (m/s)."""
    c = np.asarray(course, dtype=float)
    s = np.asarray(speed, dtype=float)
    return np.stack([s * np.sin(c), s * np.cos(c)], axis=-1)


# ---------------------------------------------------------------------------
# Polar <-> Cartesian
# ---------------------------------------------------------------------------
def polar_to_cart(rng: ArrayLike, az: ArrayLike) -> FloatArray:
    """2-D: range (m) and azimuth (rad, clockwise from North) to ``(..., 2)`` East, North."""
    r = np.asarray(rng, dtype=float)
    a = np.asarray(az, dtype=float)
    return np.stack([r * np.sin(a), r * np.cos(a)], axis=-1)


def cart_to_polar(xy: ArrayLike) -> tuple[Any, Any]:
    """2-D: ``(..., 2)`` East, North to range (m) and azimuth (rad, ``[0, 2*pi)``)."""
    p = np.asarray(xy, dtype=float)
    r = np.hypot(p[..., 0], p[..., 1])
    return (r if r.ndim else float(r)), bearing(p[..., 0], p[..., 1])


def spherical_to_cart(rng: ArrayLike, az: ArrayLike, el: ArrayLike) -> FloatArray:
    """3-D: range (m), azimuth (rad, cw from North), elevation (rad, up) to ``(..., 3)`` ENU."""
    r = np.asarray(rng, dtype=float)
    a = np.asarray(az, dtype=float)
    e = np.asarray(el, dtype=float)
    ce = np.cos(e)
    return np.stack([r * ce * np.sin(a), r * ce * np.cos(a), r * np.sin(e)], axis=-1)


def cart_to_spherical(xyz: ArrayLike) -> tuple[Any, Any, Any]:
    """3-D: ``(..., 3)`` ENU to range (m), azimuth (rad, ``[0, 2*pi)``), elevation (rad)."""
    p = np.asarray(xyz, dtype=float)
    rh = np.hypot(p[..., 0], p[..., 1])
    r = np.hypot(rh, p[..., 2])
    el = np.arctan2(p[..., 2], rh)
    return (
        (r if r.ndim else float(r)),
        bearing(p[..., 0], p[..., 1]),
        (el if el.ndim else float(el)),
    )


def rotation_to_beam(psi: ArrayLike) -> FloatArray:
    """Rotation matrix ``(..., 2, 2)`` from (East, North) to the beam frame of bearing ``psi``.

    The beam frame has its first axis (xi) along the beam (bearing ``psi``) and its
    second axis (eta) across it, to the right (clockwise) of the beam:
    ``[xi, eta] = R @ [E, N]``. ``R`` is orthogonal, so ``R.T`` rotates back.
    """
    p = np.asarray(psi, dtype=float)
    s, c = np.sin(p), np.cos(p)
    return np.stack([np.stack([s, c], -1), np.stack([c, -s], -1)], -2)


# ---------------------------------------------------------------------------
# Geodesy: local East-North-Up <-> geodetic (WGS84) through pyproj
# ---------------------------------------------------------------------------
@lru_cache(maxsize=8)
def _transformers() -> tuple[Any, Any]:
    from pyproj import Transformer

    # geodetic (lon, lat, h) <-> ECEF, exact ellipsoidal maths from PROJ
    fwd = Transformer.from_crs("EPSG:4979", "EPSG:4978", always_xy=True)
    inv = Transformer.from_crs("EPSG:4978", "EPSG:4979", always_xy=True)
    return fwd, inv


def _origin(
    lat0_deg: ArrayLike, lon0_deg: ArrayLike, h0_m: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray, tuple[FloatArray, ...]]:
    """ECEF (X0, Y0, Z0) of the origin(s) and the sines/cosines ``(sin lat0, cos lat0,
    sin lon0, cos lon0)`` of the ENU rotation, whose rows (East, North, Up unit vectors in
    ECEF) are ``(-so, co, 0)``, ``(-sl co, -sl so, cl)``, ``(cl co, cl so, sl)``. One origin
    or one per point: the arrays broadcast with the points."""
    fwd, _ = _transformers()
    la0, lo0, h0 = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (lat0_deg, lon0_deg, h0_m))
    )
    X0, Y0, Z0 = (np.asarray(c, float) for c in fwd.transform(lo0, la0, h0))
    p, lam = np.radians(la0), np.radians(lo0)
    return X0, Y0, Z0, (np.sin(p), np.cos(p), np.sin(lam), np.cos(lam))


def geodetic_to_enu(
    lat_deg: ArrayLike,
    lon_deg: ArrayLike,
    h_m: ArrayLike,
    lat0_deg: ArrayLike,
    lon0_deg: ArrayLike,
    h0_m: ArrayLike = 0.0,
) -> FloatArray:
    """WGS84 geodetic (deg, deg, m) to local East-North-Up (m) about an origin.

    Exact (no flat-earth approximation): geodetic -> ECEF via PROJ, then the rotation to
    the local tangent plane at ``(lat0, lon0, h0)``. The origin may be one point or one
    per point (arrays broadcasting with the points). Returns ``(..., 3)``.
    """
    fwd, _ = _transformers()
    lat, lon, h = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (lat_deg, lon_deg, h_m))
    )
    X, Y, Z = fwd.transform(lon, lat, h)
    X0, Y0, Z0, (sl, cl, so, co) = _origin(lat0_deg, lon0_deg, h0_m)
    dx, dy, dz = np.asarray(X) - X0, np.asarray(Y) - Y0, np.asarray(Z) - Z0
    east = -so * dx + co * dy
    north = -sl * co * dx - sl * so * dy + cl * dz
    up = cl * co * dx + cl * so * dy + sl * dz
    return np.stack([east, north, up], axis=-1)


def enu_to_geodetic(
    enu: ArrayLike, lat0_deg: ArrayLike, lon0_deg: ArrayLike, h0_m: ArrayLike = 0.0
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Local East-North-Up ``(..., 3)`` (or ``(..., 2)``, Up = 0) to WGS84 (lat, lon, h).

    Inverse of :func:`geodetic_to_enu` (one origin, or one per point); returns degrees,
    degrees, metres.
    """
    e = np.asarray(enu, dtype=float)
    if e.shape[-1] == 2:
        e = np.concatenate([e, np.zeros(e.shape[:-1] + (1,))], axis=-1)
    return _enu_to_geodetic_at(e[..., 0], e[..., 1], e[..., 2], _origin(lat0_deg, lon0_deg, h0_m))


def _enu_to_geodetic_at(
    E: FloatArray, N: FloatArray, U: FloatArray, origin: tuple[Any, ...]
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`enu_to_geodetic` about an origin computed by :func:`_origin`."""
    _, inv = _transformers()
    X0, Y0, Z0, (sl, cl, so, co) = origin
    # the transposed rotation
    X = -so * E - sl * co * N + cl * co * U + X0
    Y = co * E - sl * so * N + cl * so * U + Y0
    Z = cl * N + sl * U + Z0
    lon, lat, h = inv.transform(X, Y, Z)
    return np.asarray(lat, float), np.asarray(lon, float), np.asarray(h, float)


# ---------------------------------------------------------------------------
# Local frames of many objects (one tangent-plane origin per object)
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class LocalFrame:
    """Per-row local East-North-Up coordinates about one origin per object.

    Attributes
    ----------
    enu : ndarray (N, 3)
        East, North, Up (m) of each valid row (NaN for the others).
    lat0, lon0 : ndarray (N,)
        Origin (deg) of the row's object frame (the object's first valid row).
    group : ndarray of int (N,)
        Index of the row's object among the sorted distinct keys (-1 for invalid rows).
    """

    enu: FloatArray
    lat0: FloatArray
    lon0: FloatArray
    group: NDArray[np.int64] | None = None


def local_frames(
    key: ArrayLike, lat_deg: ArrayLike, lon_deg: ArrayLike, valid: ArrayLike
) -> LocalFrame:
    """Valid rows to a local East-North-Up frame, one tangent-plane origin per ``key``
    (e.g. per vessel): the key's first valid row, heights 0 (sea level).

    A per-object origin keeps the tangent plane close to the track (a common origin would
    rotate North by the meridian convergence, degrees over a few hundred km). All rows in
    one vectorised :func:`geodetic_to_enu` call.
    """
    k = np.asarray(key)
    lat = np.asarray(lat_deg, dtype=float)
    lon = np.asarray(lon_deg, dtype=float)
    n = lat.size
    enu = np.full((n, 3), np.nan)
    lat0 = np.full(n, np.nan)
    lon0 = np.full(n, np.nan)
    ok = np.flatnonzero(np.asarray(valid, dtype=bool))
    group = np.full(n, -1, dtype=np.int64)
    if ok.size == 0:
        return LocalFrame(enu, lat0, lon0, group)
    keys, first = np.unique(k[ok], return_index=True)
    group[ok] = np.searchsorted(keys, k[ok])
    lat0[ok] = lat[ok[first]][group[ok]]
    lon0[ok] = lon[ok[first]][group[ok]]
    enu[ok] = geodetic_to_enu(lat[ok], lon[ok], 0.0, lat0[ok], lon0[ok])
    return LocalFrame(enu, lat0, lon0, group)


def local_to_geodetic(
    east: ArrayLike,
    north: ArrayLike,
    lat0: ArrayLike,
    lon0: ArrayLike,
    iterations: int = 2,
) -> tuple[FloatArray, FloatArray]:
    """Tangent-plane (East, North) about per-row origins back to WGS84 (lat, lon) at sea
    level; NaN inputs give NaN outputs.

    The Up coordinate of the sea-level point is found by fixed-point iteration
    ``U <- U - h(E, N, U)`` starting from the spherical ``-(E^2+N^2)/(2 R)``; that start is
    within metres of the ellipsoid at 100 km, which moves lat/lon by centimetres; one
    iteration brings it to the millimetre, two to well below 0.1 mm. All rows in one
    vectorised :func:`enu_to_geodetic` call (per-row origins).
    """
    e = np.asarray(east, float)
    nn = np.asarray(north, float)
    la0_all = np.asarray(lat0, float)
    lo0_all = np.asarray(lon0, float)
    lat = np.full(e.shape, np.nan)
    lon = np.full(e.shape, np.nan)
    ok = np.isfinite(e) & np.isfinite(nn) & np.isfinite(la0_all) & np.isfinite(lo0_all)
    if not ok.any():
        return lat, lon
    E, N = e[ok], nn[ok]
    la0, lo0 = la0_all[ok], lo0_all[ok]
    U = -(E**2 + N**2) / (2.0 * 6_371_000.0)
    origin = _origin(la0, lo0, 0.0)  # once for all iterations
    for _ in range(iterations):
        _, _, h = _enu_to_geodetic_at(E, N, U, origin)
        U = U - h
    lat[ok], lon[ok], _ = _enu_to_geodetic_at(E, N, U, origin)
    return lat, lon


def north_convergence(
    lat_deg: ArrayLike, lon_deg: ArrayLike, lat0_deg: ArrayLike, lon0_deg: ArrayLike
) -> Any:
    """Bearing (rad) of true North at (lat, lon) in the tangent plane of (lat0, lon0).

    The geodetic North unit vector at the point, ``(-sin p cos l, -sin p sin l, cos p)``
    in ECEF, projected on the plane's East and North axes (the rows of the ENU rotation of
    :func:`geodetic_to_enu` at the origin); the angle is the meridian convergence between
    the point and the frame origin (exact on the ellipsoid). 0 where not finite.
    """
    p, lam = np.radians(lat_deg), np.radians(lon_deg)
    p0, l0 = np.radians(lat0_deg), np.radians(lon0_deg)
    n = np.stack([-np.sin(p) * np.cos(lam), -np.sin(p) * np.sin(lam), np.cos(p)], -1)
    e0 = np.stack([-np.sin(l0), np.cos(l0), np.zeros_like(l0)], -1)
    n0 = np.stack([-np.sin(p0) * np.cos(l0), -np.sin(p0) * np.sin(l0), np.cos(p0)], -1)
    gam = bearing(np.sum(n * e0, -1), np.sum(n * n0, -1))
    return np.where(np.isfinite(gam), gam, 0.0)


# ---------------------------------------------------------------------------
# Units at the edges
# ---------------------------------------------------------------------------
def deg2rad(deg: ArrayLike) -> Any:
    """Degrees to radians."""
    return np.radians(deg)


def rad2deg(rad: ArrayLike) -> Any:
    """Radians to degrees."""
    return np.degrees(rad)


def bearing_deg_to_rad(deg: ArrayLike) -> Any:
    """Bearing in degrees (any range) to radians in ``[0, 2*pi)``."""
    return wrap_2pi(np.radians(deg))


def bearing_rad_to_deg(rad: ArrayLike) -> Any:
    """Bearing in radians to degrees in ``[0, 360)``."""
    d = np.mod(np.degrees(rad), 360.0)
    d = np.where(d >= 360.0, 0.0, d)
    return d if np.ndim(d) else float(d)


def knots_to_mps(kn: ArrayLike) -> Any:
    """Knots to metres per second."""
    return np.asarray(kn, dtype=float) * KNOT_MPS


def mps_to_knots(mps: ArrayLike) -> Any:
    """Metres per second to knots."""
    return np.asarray(mps, dtype=float) / KNOT_MPS
