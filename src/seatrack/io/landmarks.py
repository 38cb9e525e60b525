"""Landmark map files: CSV and the patent's binary records (:class:`LandmarkMap`).

Files
-----
CSV (``read_map_csv`` / ``write_map_csv``): columns ``id``, ``kind`` (``point`` or
``contour``), ``x_m``, ``y_m`` (East, North of the local origin), ``orientation_deg``
(required for contours, ignored for points). Instead of ``x_m``/``y_m`` a row may give
``lat_deg``/``lon_deg`` (WGS84); they are converted with :func:`seatrack.geometry.geodetic_to_enu`
about an origin the caller supplies. Rows are kept in file order (= channel order).

Binary records (``encode_records`` / ``decode_records``), the patent's format plus a small
header (all big-endian, "network order", as the patent's 16-bit words):

======  ======  ===========================================================
offset  bytes   content
======  ======  ===========================================================
0       4       magic ``b"SLMB"``
4       1       format version (1)
5       4       float32 ``resolution_m``: metres per coordinate unit
9       8       float32 ``x0_m``, ``y0_m``: origin of the coordinates (m)
17      2       uint16 ``n``: number of landmarks
19      n       kind of landmark n in channel order, ``b"P"`` or ``b"C"``
19+n    4 each  point list: int16 X, int16 Y in units of ``resolution_m`` about (x0, y0)
...     5 each  contour list: int16 X, int16 Y, uint8 orientation in units of 180/256 deg
======  ======  ===========================================================

Point n of the point list starts at byte ``4 n`` of that list and contour n at ``5 n``
of its list, as in the patent. The kind string keeps the single channel numbering over
both lists. Quantisation: coordinates to ``resolution_m`` (range +-32767 units, so +-32.7 km
at the default 1 m), orientation to 0.703 deg. Identifiers are not stored: decoded
landmarks are named by their order number.
"""

from __future__ import annotations

import csv
import struct
from pathlib import Path

import numpy as np

from seatrack.geometry import geodetic_to_enu
from seatrack.io.atomic import atomic_write
from seatrack.io.table import InputError
from seatrack.io.table import coordinate
from seatrack.io.table import latitude
from seatrack.io.table import longitude
from seatrack.io.table import read_csv_table
from seatrack.navigation.landmarks import LandmarkMap

__all__ = ["read_map_csv", "write_map_csv", "encode_records", "decode_records"]

_MAGIC = b"SLMB"
_HEADER = struct.Struct(">4sBfffH")
_ORIENT_UNIT = np.pi / 256.0  # rad per orientation unit (180 deg / 256)


def read_map_csv(path: str | Path, origin: tuple[float, float] | None = None) -> LandmarkMap:
    """Read a landmark map CSV (see module docstring).

    Parameters
    ----------
    path : file name.
    origin : (lat0_deg, lon0_deg), optional
        Origin of the local East-North frame, needed when rows give ``lat_deg``/``lon_deg``
        instead of ``x_m``/``y_m``.

    Raises
    ------
    InputError
        Naming the file and line: unknown kind, contour without orientation, a row with
        neither x/y nor lat/lon, duplicate id, orientation outside [0, 360).
    """
    t = read_csv_table(
        path,
        required=["id", "kind"],
        optional=["x_m", "y_m", "orientation_deg", "lat_deg", "lon_deg"],
        text=["id", "kind"],
        checks=(coordinate("x_m"), coordinate("y_m"), latitude("lat_deg"), longitude("lon_deg")),
    )
    n = len(t)
    nan = np.full(n, np.nan)
    x = t.columns.get("x_m", nan)
    y = t.columns.get("y_m", nan)
    lat = t.columns.get("lat_deg", nan)
    lon = t.columns.get("lon_deg", nan)
    ori = t.columns.get("orientation_deg", nan)
    kinds = np.char.lower(t["kind"])
    seen: dict[str, int] = {}
    for i in range(n):
        ln = int(t.lines[i])
        ident = str(t["id"][i])
        if ident in seen:
            raise InputError(
                f"{t.path}, line {ln}: duplicate id {ident!r} (also on line {seen[ident]})"
            )
        seen[ident] = ln
        if kinds[i] not in ("point", "contour"):
            raise InputError(
                f"{t.path}, line {ln}: kind = {str(t['kind'][i])!r}; use 'point' or 'contour'"
            )
        has_xy = np.isfinite(x[i]) and np.isfinite(y[i])
        has_ll = np.isfinite(lat[i]) and np.isfinite(lon[i])
        if not has_xy and not has_ll:
            raise InputError(f"{t.path}, line {ln}: give x_m and y_m (or lat_deg and lon_deg)")
        if not has_xy and origin is None:
            raise InputError(
                f"{t.path}, line {ln}: lat_deg/lon_deg given but no origin for the local frame"
            )
        if kinds[i] == "contour":
            if not np.isfinite(ori[i]):
                raise InputError(f"{t.path}, line {ln}: contour element needs orientation_deg")
            if not 0.0 <= ori[i] < 360.0:
                raise InputError(
                    f"{t.path}, line {ln}: orientation_deg = {ori[i]:g} outside [0, 360)"
                )
    xy = np.stack([x, y], axis=1)
    need = ~np.isfinite(xy).all(axis=1)
    if need.any():
        assert origin is not None
        enu = geodetic_to_enu(lat[need], lon[need], 0.0, origin[0], origin[1])
        xy[need] = enu[:, :2]
    c = kinds == "contour"
    return LandmarkMap.from_arrays(
        xy, c, np.where(c, np.radians(np.nan_to_num(ori)), 0.0), t["id"].tolist()
    )


def write_map_csv(lm: LandmarkMap, path: str | Path) -> None:
    """Write ``id, kind, x_m, y_m, orientation_deg`` (3 decimals for metres and degrees).

    Written atomically (:func:`seatrack.io.atomic.atomic_write`); ids are CSV-quoted when
    they need it.
    """
    with atomic_write(path, newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["id", "kind", "x_m", "y_m", "orientation_deg"])
        for i in range(len(lm)):
            kind = "contour" if lm.is_contour[i] else "point"
            ori = f"{np.degrees(lm.orientation[i]):.3f}" if lm.is_contour[i] else ""
            w.writerow([lm.ids[i], kind, f"{lm.xy[i, 0]:.3f}", f"{lm.xy[i, 1]:.3f}", ori])


def encode_records(
    lm: LandmarkMap, resolution_m: float = 1.0, origin_m: tuple[float, float] = (0.0, 0.0)
) -> bytes:
    """Encode the map in the patent's binary records (layout in the module docstring).

    Raises
    ------
    ValueError
        If a coordinate does not fit in int16 units of ``resolution_m`` about ``origin_m``,
        or the map has more than 65535 landmarks.
    """
    if not resolution_m > 0:
        raise ValueError(f"resolution_m must be positive, got {resolution_m}")
    n = len(lm)
    if n > 0xFFFF:
        raise ValueError(f"at most 65535 landmarks fit in the record format, got {n}")
    q = np.rint((lm.xy - np.asarray(origin_m, float)) / resolution_m)
    bad = np.flatnonzero(np.any(np.abs(q) > 32767, axis=1))
    if bad.size:
        raise ValueError(
            f"landmark {lm.ids[bad[0]]!r} lies more than 32767 x {resolution_m} m from the origin; "
            "use a coarser resolution_m or another origin"
        )
    q = q.astype(">i2")
    o = np.mod(np.rint(lm.orientation / _ORIENT_UNIT), 256).astype(np.uint8)
    kinds = b"".join(b"C" if c else b"P" for c in lm.is_contour)
    head = _HEADER.pack(_MAGIC, 1, resolution_m, origin_m[0], origin_m[1], n)
    pts = q[~lm.is_contour].tobytes()
    con = b"".join(q[i].tobytes() + bytes([int(o[i])]) for i in np.flatnonzero(lm.is_contour))
    return head + kinds + pts + con


def decode_records(data: bytes) -> LandmarkMap:
    """Decode :func:`encode_records` output; ids are the order numbers ``"0"``, ``"1"``, ...

    Raises
    ------
    InputError
        Wrong magic, unknown version, unknown kind byte or truncated data.
    """
    if len(data) < _HEADER.size:
        raise InputError(f"landmark records: {len(data)} bytes is shorter than the header")
    magic, version, res, x0, y0, n = _HEADER.unpack_from(data)
    if magic != _MAGIC or version != 1:
        raise InputError(f"landmark records: not a version-1 SLMB record file (magic {magic!r})")
    off = _HEADER.size
    kinds = data[off : off + n]
    if len(kinds) != n or set(kinds) - {ord("P"), ord("C")}:
        raise InputError("landmark records: kind string truncated or not made of 'P'/'C'")
    is_c = np.frombuffer(kinds, np.uint8) == ord("C")
    n_c = int(is_c.sum())
    n_p = n - n_c
    off += n
    need = off + 4 * n_p + 5 * n_c
    if len(data) != need:
        raise InputError(
            f"landmark records: expected {need} bytes for {n} landmarks, got {len(data)}"
        )
    pts = np.frombuffer(data, ">i2", 2 * n_p, off).reshape(n_p, 2).astype(float)
    off += 4 * n_p
    con = np.frombuffer(data, np.uint8, 5 * n_c, off).reshape(n_c, 5)
    cxy = con[:, :4].copy().view(">i2").reshape(n_c, 2).astype(float)
    xy = np.empty((n, 2))
    xy[~is_c] = pts
    xy[is_c] = cxy
    xy = xy * res + np.array([x0, y0])
    ori = np.zeros(n)
    ori[is_c] = con[:, 4] * _ORIENT_UNIT
    return LandmarkMap.from_arrays(xy, is_c, ori)
