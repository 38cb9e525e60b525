"""HTML map of AIS tracks (Leaflet, one self-contained file), and GeoJSON export.

The page (:func:`html_page`, :func:`write_html`) is one HTML file carrying Leaflet, its own
script and the data: it needs no server and works offline. Online, it shows OpenStreetMap
tiles with the OpenSeaMap seamark overlay; when tiles fail to load it says so and shows the
Natural Earth 1:10m land carried in the page. OpenStreetMap's tile usage policy requires a
Referer header, which a page opened from disk (``file://``) cannot send, so such a page
does not ask OpenStreetMap for tiles and tells the reader to serve it over http(s) (e.g.
``python -m http.server``); a ``tile_url`` of another provider is used from disk too.

It shows, per vessel: the smoothed track (one coloured polyline, one part per track
segment), its outliers (small red dots), and, for the vessel selected in the list or on the
map, its raw reports. The first view is the 1st-99th percentile box of the smoothed
positions; the list searches by MMSI; a time slider shows every vessel's position at a
chosen time. Large inputs are decimated to budgets, said on the page: see
:mod:`seatrack.report.map_page`.

For headless-browser tests, the script sets on ``<body>`` ``data-vessels``, ``data-paths``
(polylines drawn), ``data-vertices``, ``data-reports``, ``data-outliers``, ``data-land``
(coast rings) and ``data-tiles`` (``off``, ``needs-http``, ``waiting``, ``failed``,
``partial``, ``loaded``), and lists one ``<li class="vessel" data-mmsi data-parts
data-vertices data-reports data-outliers>`` per vessel; small maps use SVG paths with
class ``st-track st-v<MMSI>``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.io.atomic import atomic_write
from seatrack.report.map_page import OPENSEAMAP_URL
from seatrack.report.map_page import MapOptions
from seatrack.report.map_page import page_data
from seatrack.report.map_page import render_page

FloatArray = NDArray[np.float64]

__all__ = [
    "VesselTrack",
    "vessel_tracks",
    "map_tracks",
    "geojson",
    "write_geojson",
    "html_page",
    "write_html",
]


@dataclass(frozen=True)
class VesselTrack:
    """What the map shows of one vessel (degrees; rows in time order).

    ``raw_lat/raw_lon``: usable reports; ``lat/lon``: smoothed positions (NaN allowed);
    ``segment``: track segment id per row; ``outlier``: flags per row; ``t``: epoch s.
    """

    mmsi: int
    t: FloatArray
    raw_lat: FloatArray
    raw_lon: FloatArray
    lat: FloatArray
    lon: FloatArray
    segment: NDArray[np.int64]
    outlier: NDArray[np.bool_]


def map_tracks(reports: Any, tracks: Any) -> list[VesselTrack]:
    """:func:`vessel_tracks` of :class:`~seatrack.io.ais.AisReports` and their
    :class:`~seatrack.filters.ais_tracker.AisTracks` (raw and smoothed positions)."""
    return vessel_tracks(
        reports.mmsi,
        reports.t,
        reports.lat,
        reports.lon,
        tracks.lat,
        tracks.lon,
        tracks.segment,
        tracks.outlier,
        reports.valid,
    )


def vessel_tracks(
    mmsi: NDArray[np.int64],
    t: FloatArray,
    raw_lat: FloatArray,
    raw_lon: FloatArray,
    lat: FloatArray,
    lon: FloatArray,
    segment: NDArray[np.int64],
    outlier: NDArray[np.bool_],
    valid: NDArray[np.bool_],
) -> list[VesselTrack]:
    """Group per-report arrays into :class:`VesselTrack` (valid rows only, time-sorted).

    Rows already in time order within each vessel (the usual case: a log is written as it
    is received) are grouped by one stable sort on the MMSI; otherwise by MMSI and time.
    The arrays of the returned tracks are slices of one gathered copy of the inputs.
    """
    idx = np.flatnonzero(valid)
    if idx.size == 0:
        return []
    m, tv = mmsi[idx], t[idx]
    order = np.argsort(m, kind="stable")
    ms, ts = m[order], tv[order]
    if np.any((ms[1:] == ms[:-1]) & (ts[1:] < ts[:-1])):
        order = np.lexsort((tv, m))
        ms = m[order]
    rows = idx[order]
    tt, rla, rlo, la, lo = (a[rows] for a in (t, raw_lat, raw_lon, lat, lon))
    seg, out = segment[rows], outlier[rows]
    cuts = np.flatnonzero(np.r_[True, ms[1:] != ms[:-1], True]).tolist()
    return [
        VesselTrack(int(ms[a]), tt[a:b], rla[a:b], rlo[a:b], la[a:b], lo[a:b], seg[a:b], out[a:b])
        for a, b in zip(cuts[:-1], cuts[1:], strict=True)
    ]


def _segments(v: VesselTrack) -> list[tuple[int, NDArray[np.int64]]]:
    ok = np.isfinite(v.lat) & np.isfinite(v.lon) & (v.segment >= 0)
    out = []
    for s in np.unique(v.segment[ok]):
        rows = np.flatnonzero(ok & (v.segment == s))
        out.append((int(s), rows))
    return out


def geojson(tracks: Sequence[VesselTrack], include_reports: bool = False) -> dict[str, Any]:
    """GeoJSON FeatureCollection (RFC 7946, lon/lat order).

    One ``LineString`` per vessel track segment (smoothed; properties ``mmsi``,
    ``segment``, ``kind="track"``, ``n_reports``, ``start``/``end`` epoch s), one ``Point``
    per outlier (``kind="outlier"``, ``time``), and with ``include_reports`` one
    ``MultiPoint`` of the raw reports per vessel (``kind="reports"``).
    """
    feats: list[dict[str, Any]] = []
    for v in tracks:
        for s, rows in _segments(v):
            coords = [
                [round(float(a), 7), round(float(b), 7)]
                for a, b in zip(v.lon[rows], v.lat[rows], strict=True)
            ]
            geom: dict[str, Any] = (
                {"type": "LineString", "coordinates": coords}
                if len(coords) > 1
                else {"type": "Point", "coordinates": coords[0]}
            )
            feats.append(
                {
                    "type": "Feature",
                    "geometry": geom,
                    "properties": {
                        "mmsi": v.mmsi,
                        "kind": "track",
                        "segment": s,
                        "n_reports": int(rows.size),
                        "start": float(v.t[rows[0]]),
                        "end": float(v.t[rows[-1]]),
                    },
                }
            )
        for i in np.flatnonzero(v.outlier):
            feats.append(
                {
                    "type": "Feature",
                    "geometry": {
                        "type": "Point",
                        "coordinates": [float(v.raw_lon[i]), float(v.raw_lat[i])],
                    },
                    "properties": {"mmsi": v.mmsi, "kind": "outlier", "time": float(v.t[i])},
                }
            )
        if include_reports:
            feats.append(
                {
                    "type": "Feature",
                    "geometry": {
                        "type": "MultiPoint",
                        "coordinates": [
                            [float(a), float(b)] for a, b in zip(v.raw_lon, v.raw_lat, strict=True)
                        ],
                    },
                    "properties": {"mmsi": v.mmsi, "kind": "reports", "n_reports": int(v.t.size)},
                }
            )
    return {"type": "FeatureCollection", "features": feats}


def write_geojson(
    path: str | Path, tracks: Sequence[VesselTrack], include_reports: bool = False
) -> None:
    """Write :func:`geojson` to ``path`` (atomically)."""
    with atomic_write(path) as fh:
        json.dump(geojson(tracks, include_reports), fh, separators=(",", ":"))


def _joined_view(parts: list[NDArray[Any]]) -> NDArray[Any] | None:
    """The parts as one view when they are consecutive slices of one 1-D array (as
    :func:`vessel_tracks` makes them), else ``None``."""
    base = parts[0].base
    if not isinstance(base, np.ndarray) or base.ndim != 1 or not base.flags.c_contiguous:
        return None
    item = base.itemsize
    ptr = base.__array_interface__["data"][0]
    pos = parts[0].__array_interface__["data"][0]
    start = (pos - ptr) // item
    for p in parts:
        if p.base is not base or p.ndim != 1 or not p.flags.c_contiguous:
            return None
        if p.__array_interface__["data"][0] != pos:
            return None
        pos += p.size * item
    return base[start : start + (pos - ptr) // item - start]


def _concat(tracks: Sequence[VesselTrack], name: str, dtype: Any) -> NDArray[Any]:
    """One field of all tracks, concatenated (a view, not a copy, when it can be)."""
    if not tracks:
        return np.zeros(0, dtype)
    parts = [getattr(v, name) for v in tracks]
    joined = _joined_view(parts)
    if joined is not None and joined.dtype == dtype:
        return joined
    return np.concatenate([np.asarray(p, dtype) for p in parts])


def html_page(
    tracks: Sequence[VesselTrack],
    title: str = "seatrack AIS tracks",
    summary: str = "",
    tile_url: str | None = None,
    *,
    seamark_url: str | None = OPENSEAMAP_URL,
    online: bool = True,
    max_vertices: int = 250_000,
    max_reports: int = 100_000,
    max_outliers: int = 20_000,
    max_land_vertices: int = 40_000,
) -> str:
    """The self-contained HTML map page (see the module docstring).

    Parameters
    ----------
    tracks : vessels to show (:func:`vessel_tracks`).
    title, summary : page heading and summary text (escaped).
    tile_url : base tile URL template ``.../{z}/{x}/{y}.png``; ``None`` = OpenStreetMap.
    seamark_url : seamark overlay tile template (``None``: no overlay).
    online : ``False`` for a page that loads no tiles at all (Natural Earth land only).
    max_vertices, max_reports, max_outliers, max_land_vertices : what the page carries at
        most (:class:`~seatrack.report.map_page.MapOptions`).
    """
    opts = MapOptions(
        tile_url=tile_url,
        seamark_url=seamark_url,
        online=online,
        max_vertices=max_vertices,
        max_reports=max_reports,
        max_outliers=max_outliers,
        max_land_vertices=max_land_vertices,
    )
    data = page_data(
        np.array([v.mmsi for v in tracks], dtype=np.int64),
        np.array([v.t.size for v in tracks], dtype=np.int64),
        _concat(tracks, "t", np.float64),
        _concat(tracks, "raw_lat", np.float64),
        _concat(tracks, "raw_lon", np.float64),
        _concat(tracks, "lat", np.float64),
        _concat(tracks, "lon", np.float64),
        _concat(tracks, "segment", np.int64),
        _concat(tracks, "outlier", np.bool_),
        opts,
    )
    return render_page(title, summary, data)


def write_html(path: str | Path, tracks: Sequence[VesselTrack], **kwargs: Any) -> None:
    """Write :func:`html_page` (same keyword arguments) to ``path`` (atomically)."""
    page = html_page(tracks, **kwargs)
    with atomic_write(path) as fh:
        fh.write(page)
