"""Natural Earth land polygons for the offline map: load, clip to a box, simplify.

The bundled file ``assets/ne_10m_land.npz`` holds the Natural Earth 1:10m land polygons
(public domain; via the ``world-atlas`` TopoJSON redistribution, see ``assets/README.md``)
as rings of quantised integer coordinates. :func:`rings_from_topojson` rebuilds that file
from the TopoJSON; :func:`land_rings` cuts out the land around a box and simplifies it to a
vertex budget, so a page carries only the coast it shows.

Rings are returned as concatenated arrays with offsets: ring ``k`` is
``lon[offsets[k]:offsets[k+1]]``; rings are implicitly closed (no repeated first vertex);
outer rings and holes are mixed and meant to be filled with the even-odd rule.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.report.decimate import budget_tolerance
from seatrack.report.decimate import dp_ranks
from seatrack.report.decimate import mercator

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "Rings",
    "clip_rings",
    "land_rings",
    "natural_earth_land",
    "rings_from_topojson",
    "topojson_transform",
]

LAND_ASSET = "ne_10m_land.npz"


@dataclass(frozen=True)
class Rings:
    """Closed rings (degrees), concatenated: ring ``k`` is ``[offsets[k], offsets[k+1])``."""

    lon: FloatArray
    lat: FloatArray
    offsets: IntArray

    @property
    def n_rings(self) -> int:
        """Number of rings."""
        return int(self.offsets.size - 1)


def rings_from_topojson(path: str | Path, obj: str = "land") -> Rings:
    """Every ring of the (Multi)Polygons of TopoJSON object ``obj`` (quantised topology).

    Arcs are delta-decoded and joined as the TopoJSON specification says (a negative
    index ``~i`` is arc ``i`` reversed; consecutive arcs share their joining point).
    Returned rings drop the closing vertex.
    """
    topo = json.loads(Path(path).read_text(encoding="utf-8"))
    (sx, sy), (tx, ty) = _transform(topo)
    arcs = [np.cumsum(np.asarray(a, dtype=np.int64), axis=0) for a in topo["arcs"]]
    rings: list[NDArray[np.int64]] = []
    for geom in topo["objects"][obj]["geometries"]:
        polys = geom["arcs"] if geom["type"] == "MultiPolygon" else [geom["arcs"]]
        for poly in polys:
            for ring in poly:
                parts = [arcs[i] if i >= 0 else arcs[~i][::-1] for i in ring]
                pts = np.concatenate([parts[0]] + [p[1:] for p in parts[1:]])
                rings.append(pts[:-1] if np.array_equal(pts[0], pts[-1]) else pts)
    q = np.concatenate(rings)
    offsets = np.r_[0, np.cumsum([r.shape[0] for r in rings])].astype(np.int64)
    return Rings(
        (q[:, 0] * sx + tx).astype(np.float64), (q[:, 1] * sy + ty).astype(np.float64), offsets
    )


def _transform(topo: dict[str, Any]) -> tuple[tuple[float, float], tuple[float, float]]:
    t = topo["transform"]
    return (float(t["scale"][0]), float(t["scale"][1])), (
        float(t["translate"][0]),
        float(t["translate"][1]),
    )


def topojson_transform(path: str | Path) -> tuple[tuple[float, float], tuple[float, float]]:
    """``(scale, translate)`` of a quantised TopoJSON: degrees = q * scale + translate."""
    return _transform(json.loads(Path(path).read_text(encoding="utf-8")))


@lru_cache(maxsize=1)
def natural_earth_land() -> Rings:
    """The bundled Natural Earth 1:10m land rings (degrees; cached after the first call)."""
    with resources.as_file(resources.files("seatrack.report") / "assets" / LAND_ASSET) as p:
        z = np.load(p)
        (sx, sy), (tx, ty) = z["scale"], z["origin"]
        offsets = z["offsets"].astype(np.int64)
        lon = _undelta(z["dlon"].astype(np.int64), offsets) * sx + tx
        lat = _undelta(z["dlat"].astype(np.int64), offsets) * sy + ty
    return Rings(lon, lat, offsets)


def _undelta(d: IntArray, offsets: IntArray) -> FloatArray:
    """Inverse of per-ring delta coding (each ring's first value is absolute)."""
    c = np.cumsum(d)
    base = np.r_[0, c[offsets[1:-1] - 1]]  # running sum before each ring
    return (c - np.repeat(base, np.diff(offsets))).astype(np.float64)


def _next_index(offsets: IntArray) -> IntArray:
    """Index of the next vertex of the same ring (wrapping at the ring's end)."""
    n = int(offsets[-1])
    nxt = np.arange(1, n + 1, dtype=np.int64)
    nxt[offsets[1:] - 1] = offsets[:-1]
    return nxt


def _clip_half(r: Rings, coord: int, value: float, keep_below: bool) -> Rings:
    """Sutherland-Hodgman clip of every ring against one axis-aligned half-plane.

    ``coord`` 0 = lon, 1 = lat; keeps ``coord <= value`` (``keep_below``) or ``>= value``.
    Intersection points get ``coord`` exactly equal to ``value``.
    """
    if r.offsets[-1] == 0:
        return r
    u, w = (r.lon, r.lat) if coord == 0 else (r.lat, r.lon)
    nxt = _next_index(r.offsets)
    inside = u <= value if keep_below else u >= value
    ins_e = inside[nxt]
    cross = inside != ins_e
    du = u[nxt] - u
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(cross, (value - u) / np.where(du == 0, 1.0, du), 0.0)
    wi = w + f * (w[nxt] - w)
    # per edge S->E: (I) if crossing, then (E) if E inside
    first_u = np.where(cross, value, u[nxt])
    first_w = np.where(cross, wi, w[nxt])
    take = np.stack([cross | ins_e, cross & ins_e], axis=1)
    cu = np.stack([first_u, u[nxt]], axis=1)[take]
    cw = np.stack([first_w, w[nxt]], axis=1)[take]
    counts = np.add.reduceat(take.sum(axis=1), r.offsets[:-1]) if r.n_rings else np.zeros(0)
    counts = np.where(np.diff(r.offsets) > 0, counts, 0)
    offsets = np.r_[0, np.cumsum(counts)].astype(np.int64)
    lon, lat = (cu, cw) if coord == 0 else (cw, cu)
    return _drop_small(Rings(lon, lat, offsets), 3)


def _drop_small(r: Rings, min_vertices: int) -> Rings:
    """Remove rings with fewer than ``min_vertices`` vertices."""
    sizes = np.diff(r.offsets)
    keep = sizes >= min_vertices
    if keep.all():
        return r
    rows = np.repeat(keep, sizes)
    return Rings(r.lon[rows], r.lat[rows], np.r_[0, np.cumsum(sizes[keep])].astype(np.int64))


def clip_rings(r: Rings, west: float, south: float, east: float, north: float) -> Rings:
    """The rings clipped to the box (degrees; Sutherland-Hodgman, one half-plane at a time).

    Rings whose bounding box misses the box are dropped first. Concave rings may keep
    zero-area edges along the box border (harmless for even-odd filling).
    """
    sizes = np.diff(r.offsets)
    nonempty = sizes > 0
    starts = r.offsets[:-1][nonempty]
    keep = np.zeros(sizes.size, bool)
    keep[nonempty] = (
        (np.minimum.reduceat(r.lon, starts) <= east)
        & (np.maximum.reduceat(r.lon, starts) >= west)
        & (np.minimum.reduceat(r.lat, starts) <= north)
        & (np.maximum.reduceat(r.lat, starts) >= south)
    )
    rows = np.repeat(keep, sizes)
    out = Rings(r.lon[rows], r.lat[rows], np.r_[0, np.cumsum(sizes[keep])].astype(np.int64))
    for coord, value, below in ((0, east, True), (0, west, False), (1, north, True)):
        out = _clip_half(out, coord, value, below)
    return _clip_half(out, 1, south, False)


def land_rings(
    west: float,
    south: float,
    east: float,
    north: float,
    max_vertices: int = 40_000,
    focus: tuple[float, float, float, float] | None = None,
) -> tuple[Rings, float]:
    """Natural Earth land within the box, Douglas-Peucker-simplified to ``max_vertices``.

    With a ``focus`` box (west, south, east, north), a vertex at distance ``d`` outside it
    counts its DP rank divided by ``1 + d / size`` (``size`` the focus's larger side, in Web
    Mercator): the budget buys detail near the focus and coarser coast further away.

    Returns the rings and the tolerance used (Web Mercator, units of the world width;
    0 when nothing had to go). Rings that simplify to fewer than three vertices are dropped.
    """
    r = clip_rings(natural_earth_land(), west, south, east, north)
    if r.offsets[-1] == 0:
        return r, 0.0
    x, y = mercator(r.lat, r.lon)
    # each ring is ranked as a polyline from its first vertex to its last (closing edge kept)
    rank = dp_ranks(x, y, r.offsets[:-1], r.offsets[1:])
    if focus is not None:
        (fx0, fx1), (fy0, fy1) = (
            v.tolist() for v in mercator(np.array(focus[1::2]), np.array(focus[0::2]))
        )
        size = max(fx1 - fx0, fy1 - fy0, 1e-9)
        d = np.hypot(
            np.maximum(0, np.maximum(fx0 - x, x - fx1)), np.maximum(0, np.maximum(fy0 - y, y - fy1))
        )
        rank = rank / (1.0 + d / size)
    eps = budget_tolerance(rank, max_vertices)
    keep = rank > eps
    sizes = np.add.reduceat(keep, r.offsets[:-1])
    out = Rings(r.lon[keep], r.lat[keep], np.r_[0, np.cumsum(sizes)].astype(np.int64))
    return _drop_small(out, 3), eps
