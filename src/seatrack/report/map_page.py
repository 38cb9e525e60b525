"""The data and the page of the HTML track map (Leaflet, one self-contained file).

:func:`page_data` turns vessel-grouped per-report arrays into the compact JSON the page's
script draws; :func:`render_page` wraps it with the bundled Leaflet, the page script and
style (``assets/``) into one HTML document. The public entry points are in
:mod:`seatrack.report.html`.

What goes into a page, and what is left out so that a national day of AIS (15 million
reports, thousands of vessels) stays a page a browser can draw:

* **tracks**: the smoothed positions of every vessel, one polyline part per track segment,
  simplified by Douglas-Peucker in Web Mercator with *one* tolerance for all vessels, the
  smallest that keeps at most ``max_vertices`` vertices (never finer than a tenth of a
  pixel at zoom 18, which is lossless on screen);
* **reports**: the usable raw reports, 1 in ``k`` when there are more than ``max_reports``
  (``k`` the smallest stride that fits; rows are grouped by vessel, so every vessel keeps
  1 in ``k`` of its own);
* **outliers**: every outlier, 1 in ``k`` beyond ``max_outliers``;
* **land**: the Natural Earth 1:10m land in a box three times the tracks' extent
  (:mod:`seatrack.report.land`), simplified to ``max_land_vertices`` with the detail spent
  near the tracks, drawn under the tiles: it is what the page shows when the browser is
  offline;
* **first view**: the box of the 1st-99th percentiles of the smoothed latitudes and
  longitudes (a few wild positions do not zoom the map out to specks).

Coordinates are integers of 1e-5 degree and times integer seconds after ``t0``, delta-coded
along each array (the script undoes it with one running sum).
"""

from __future__ import annotations

import html
import json
import math
import re
from base64 import b64encode
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.config import require
from seatrack.report.decimate import budget_tolerance
from seatrack.report.decimate import dp_ranks
from seatrack.report.decimate import mercator_rows
from seatrack.report.decimate import pixel_size
from seatrack.report.land import land_rings

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "OPENSEAMAP_URL",
    "OSM_URL",
    "MapOptions",
    "page_data",
    "render_page",
    "robust_bounds",
]

OSM_URL = "https://tile.openstreetmap.org/{z}/{x}/{y}.png"
OPENSEAMAP_URL = "https://tiles.openseamap.org/seamark/{z}/{x}/{y}.png"
OSM_ATTRIBUTION = '&copy; <a href="https://www.openstreetmap.org/copyright">OpenStreetMap</a>'
SEAMARK_ATTRIBUTION = '&copy; <a href="https://www.openseamap.org">OpenSeaMap</a>'
DEG = 1e5  # stored units per degree
EARTH_CIRCUMFERENCE_M = 40_075_016.686


@dataclass(frozen=True)
class MapOptions:
    """What the page carries (budgets) and which online layers it asks for.

    Attributes
    ----------
    tile_url : base map tile URL template (``{z}/{x}/{y}``); ``None`` = OpenStreetMap.
    seamark_url : overlay tile URL template; ``None`` = no overlay (default OpenSeaMap).
    online : ``False`` = no tile layer at all (the page never touches the network).
    max_vertices : track vertices drawn, all vessels together (Douglas-Peucker budget).
    max_reports : raw reports carried (shown for the selected vessel), all vessels.
    max_outliers : outliers drawn, all vessels.
    max_land_vertices : Natural Earth coast vertices carried.
    percentile : the first view spans the ``percentile``-th to ``100 - percentile``-th
        percentile of the smoothed latitudes and longitudes.
    """

    tile_url: str | None = None
    seamark_url: str | None = OPENSEAMAP_URL
    online: bool = True
    max_vertices: int = 250_000
    max_reports: int = 100_000
    max_outliers: int = 20_000
    max_land_vertices: int = 40_000
    percentile: float = 1.0

    def __post_init__(self) -> None:
        own = "MapOptions."
        budgets = ("max_vertices", "max_reports", "max_outliers", "max_land_vertices")
        require(self, budgets, lambda n: n >= 0, ">= 0", prefix=own)
        require(self, ("percentile",), lambda p: 0.0 <= p < 50.0, "in [0, 50)", prefix=own)


def robust_bounds(
    lat: FloatArray,
    lon: FloatArray,
    percentile: float = 1.0,
    min_span_deg: float = 0.005,
    rows: IntArray | None = None,
) -> tuple[float, float, float, float] | None:
    """``(south, west, north, east)`` of the ``percentile``..``100-percentile`` box, degrees.

    Only ``rows`` (default all) count; non-finite values are ignored; beyond 2 million
    positions a regular subsample of at least 1 million is used. Spans narrower than
    ``min_span_deg`` are widened about their centre. ``None`` without a finite position.
    """
    if rows is None:
        rows = np.arange(lat.size)
    if rows.size > 2_000_000:
        rows = rows[:: rows.size // 1_000_000]
    la, lo = lat[rows], lon[rows]
    ok = np.isfinite(la) & np.isfinite(lo)
    if not ok.any():
        return None
    la, lo = la[ok], lo[ok]
    s, n = np.percentile(la, [percentile, 100.0 - percentile])
    w, e = np.percentile(lo, [percentile, 100.0 - percentile])
    out = []
    for a, b in ((s, n), (w, e)):
        pad = max(0.0, min_span_deg - (b - a)) / 2
        out.append((float(a - pad), float(b + pad)))
    return out[0][0], out[1][0], out[0][1], out[1][1]


def _q(deg: FloatArray) -> IntArray:
    return np.round(np.asarray(deg) * DEG).astype(np.int64)


def _delta(a: IntArray) -> list[int]:
    """Delta coding along the whole array (first value absolute)."""
    return np.diff(a, prepend=0).tolist() if a.size else []


def _offsets(counts: IntArray) -> list[int]:
    return np.r_[0, np.cumsum(counts)].astype(np.int64).tolist()


def _stride(n: int, budget: int) -> int:
    """Smallest ``k`` with ``ceil(n / k) <= budget`` (0 when nothing may be kept)."""
    if n <= budget:
        return 1
    return 0 if budget == 0 else -(-n // budget)


def _track_parts(
    vessel: IntArray, segment: IntArray, lat: FloatArray, lon: FloatArray
) -> tuple[IntArray, IntArray]:
    """Rows of drawable smoothed positions, grouped by (vessel, segment) in time order, and
    the start of each part among them."""
    rows = np.flatnonzero(np.isfinite(lat) & np.isfinite(lon) & (segment >= 0))
    v, s = vessel[rows], segment[rows]
    if rows.size > 1 and not np.all((v[1:] > v[:-1]) | ((v[1:] == v[:-1]) & (s[1:] >= s[:-1]))):
        order = np.lexsort((rows, s, v))  # segments interleaved in time: group them
        rows, v, s = rows[order], v[order], s[order]
    starts = (
        np.flatnonzero(np.r_[True, (v[1:] != v[:-1]) | (s[1:] != s[:-1])]) if rows.size else rows
    )
    return rows, starts


def page_data(
    mmsi: IntArray,
    counts: IntArray,
    t: FloatArray,
    raw_lat: FloatArray,
    raw_lon: FloatArray,
    lat: FloatArray,
    lon: FloatArray,
    segment: IntArray,
    outlier: NDArray[np.bool_],
    opts: MapOptions | None = None,
) -> dict[str, Any]:
    """The JSON-ready data of a map page.

    Parameters
    ----------
    mmsi, counts : one entry per vessel: its MMSI and number of rows.
    t, raw_lat, raw_lon, lat, lon, segment, outlier : per row, grouped by vessel in the
        order of ``mmsi`` (``counts[i]`` rows each) and in time order within a vessel;
        epoch s, degrees (smoothed ``lat/lon`` may be NaN), segment id (< 0 = none).
    opts : budgets and tile layers (:class:`MapOptions`).
    """
    o = opts or MapOptions()
    nv = int(mmsi.size)
    vfirst = np.r_[0, np.cumsum(counts)[:-1]].astype(np.int64)  # first row of each vessel
    vessel = np.repeat(np.arange(nv), counts)
    t0 = float(np.nanmin(t)) if t.size and np.isfinite(t).any() else 0.0

    rows, starts = _track_parts(vessel, segment, lat, lon)
    x, y = mercator_rows(lat, lon, rows)
    stops = np.r_[starts[1:], rows.size][: starts.size].astype(np.int64)
    rank = dp_ranks(x, y, starts, stops)
    del x, y
    eps = budget_tolerance(rank, o.max_vertices, floor=pixel_size(18) / 10)
    keep = rank > eps
    kept = rows[keep]
    part_sizes = np.add.reduceat(keep, starts) if starts.size else np.zeros(0, np.int64)
    part_vessel = vessel[rows[starts]]

    usable = np.isfinite(raw_lat) & np.isfinite(raw_lon)
    bad = usable & outlier
    # beyond a budget, 1 row in k (rows are grouped by vessel: 1 in k of each vessel's)
    rep_rows = np.flatnonzero(usable & ~outlier)
    rep_stride = _stride(rep_rows.size, o.max_reports)
    rep_rows = rep_rows[:: max(rep_stride, 1)] if rep_stride else rep_rows[:0]
    out_rows = np.flatnonzero(bad)
    out_stride = _stride(out_rows.size, o.max_outliers)
    out_rows = out_rows[:: max(out_stride, 1)] if out_stride else out_rows[:0]

    view = robust_bounds(lat, lon, o.percentile, rows=rows) or robust_bounds(
        raw_lat, raw_lon, o.percentile
    )
    tol_m = eps * EARTH_CIRCUMFERENCE_M * math.cos(math.radians(_mid_lat(view)))
    return {
        "t0": t0,
        "mmsi": mmsi.astype(np.int64).tolist(),
        "nrows": counts.astype(np.int64).tolist(),
        "nusable": _per_vessel(usable, vfirst, counts),
        "noutliers": _per_vessel(bad, vfirst, counts),
        "vpart": _offsets(np.bincount(part_vessel, minlength=nv)),
        "poff": _offsets(part_sizes),
        "la": _delta(_q(lat[kept])),
        "lo": _delta(_q(lon[kept])),
        "tt": _delta(_tq(t[kept], t0)),
        "rv": _offsets(np.bincount(vessel[rep_rows], minlength=nv)),
        "rla": _delta(_q(raw_lat[rep_rows])),
        "rlo": _delta(_q(raw_lon[rep_rows])),
        "ov": _offsets(np.bincount(vessel[out_rows], minlength=nv)),
        "ola": _delta(_q(raw_lat[out_rows])),
        "olo": _delta(_q(raw_lon[out_rows])),
        "ot": _delta(_tq(t[out_rows], t0)),
        "view": None if view is None else [[view[0], view[1]], [view[2], view[3]]],
        "land": _land(lat[kept], lon[kept], view, o.max_land_vertices),
        "tiles": _tiles(o),
        "stats": {
            "track_points": int(rows.size),
            "vertices": int(kept.size),
            "tolerance_m": round(tol_m, 2),
            "reports": int(np.count_nonzero(usable)),
            "reports_carried": int(rep_rows.size + out_rows.size),
            "report_stride": rep_stride,
            "outliers": int(np.count_nonzero(bad)),
            "outliers_drawn": int(out_rows.size),
            "outlier_stride": out_stride,
        },
    }


def _tq(t: FloatArray, t0: float) -> IntArray:
    """Integer seconds after ``t0`` (non-finite times as 0)."""
    return np.round(np.nan_to_num(t - t0)).astype(np.int64)


def _per_vessel(flag: NDArray[np.bool_], vfirst: IntArray, counts: IntArray) -> list[int]:
    """Number of true flags of each vessel (rows grouped by vessel)."""
    if counts.size == 0:
        return []
    c = np.add.reduceat(np.r_[flag.astype(np.int64), 0], vfirst)  # the 0 closes the last
    return np.where(counts > 0, c, 0).tolist()


def _mid_lat(view: tuple[float, float, float, float] | None) -> float:
    return 0.0 if view is None else (view[0] + view[2]) / 2


def _land(
    lat: FloatArray,
    lon: FloatArray,
    view: tuple[float, float, float, float] | None,
    max_vertices: int,
) -> dict[str, Any] | None:
    """Natural Earth land around the tracks (or the first view when there are none).

    The box is square on the ground, centred on the tracks' extent, three times its larger
    side and at least 4 degrees of latitude high -- wider than any first view and a few
    zoom levels out -- with its detail spent near the tracks (``land_rings(focus=...)``).
    """
    if lat.size:
        s, w, n, e = float(lat.min()), float(lon.min()), float(lat.max()), float(lon.max())
    elif view is not None:
        s, w, n, e = view
    else:
        return None
    clat = math.cos(math.radians(min(80.0, abs(s + n) / 2)))
    half_lat = max(2.0, 1.5 * max(n - s, (e - w) * clat))
    half_lon = half_lat / clat
    cy, cx = (s + n) / 2, (w + e) / 2
    box = (
        max(-180.0, cx - half_lon),
        max(-85.0, cy - half_lat),
        min(180.0, cx + half_lon),
        min(85.0, cy + half_lat),
    )
    qbox = _q(np.array(box))
    w0, s0, e0, n0 = (float(v) / DEG for v in qbox)  # on the stored grid: exact edges
    rings, _ = land_rings(w0, s0, e0, n0, max_vertices=max_vertices, focus=(w, s, e, n))
    return {
        "box": qbox.tolist(),  # west, south, east, north
        "off": rings.offsets.tolist(),
        "la": _delta(_q(rings.lat)),
        "lo": _delta(_q(rings.lon)),
    }


def _tiles(o: MapOptions) -> dict[str, Any] | None:
    if not o.online:
        return None
    base = o.tile_url or OSM_URL
    return {
        "base": base,
        "base_attribution": OSM_ATTRIBUTION if base == OSM_URL else "",
        # OSM's tile usage policy requires a Referer: the page asks only when served by http(s)
        "needs_referer": base == OSM_URL,
        "seamarks": o.seamark_url,
        "seamark_attribution": SEAMARK_ATTRIBUTION if o.seamark_url == OPENSEAMAP_URL else "",
    }


#: the vendored third-party files (unmodified Leaflet, see ``assets/README.md``)
_LEAFLET = ("vendor", "leaflet")


def _asset_file(*parts: str) -> Any:
    """The bundled file ``assets/<parts...>`` (an importlib resource)."""
    return resources.files("seatrack.report").joinpath("assets", *parts)


@lru_cache(maxsize=8)
def _asset(*parts: str) -> str:
    return str(_asset_file(*parts).read_text(encoding="utf-8"))


@lru_cache(maxsize=1)
def _leaflet() -> tuple[str, str]:
    """Leaflet's script (without its source-map comment) and its style with the layer
    control's icons as data URIs."""
    js = _asset(*_LEAFLET, "leaflet.js").replace("//# sourceMappingURL=leaflet.js.map", "")
    css = _asset(*_LEAFLET, "leaflet.css")
    for name in ("layers.png", "layers-2x.png"):
        png = _asset_file(*_LEAFLET, name).read_bytes()
        css = css.replace(
            f"url(images/{name})", f"url(data:image/png;base64,{b64encode(png).decode()})"
        )
    return js, css


def _inline(text: str) -> str:
    """A bundled script or style, checked to be safe inside its element."""
    if re.search(r"</(script|style)|<!--", text, re.IGNORECASE):
        raise ValueError("a bundled script or style contains an HTML tag end or comment")
    return text


def render_page(title: str, summary: str, data: dict[str, Any]) -> str:
    """One self-contained HTML page drawing :func:`page_data` output."""
    js, css = _leaflet()
    payload = json.dumps(data, separators=(",", ":"), allow_nan=False)
    return _asset("map.html").format(
        title=html.escape(title),
        summary=html.escape(summary),
        leaflet_css=_inline(css),
        page_css=_inline(_asset("map.css")),
        leaflet_js=_inline(js),
        data=payload.replace("<", "\\u003c"),  # "<" occurs only inside JSON strings
        page_js=_inline(_asset("map.js")),
    )
