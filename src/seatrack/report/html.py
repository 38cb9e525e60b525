"""Offline HTML map of AIS tracks, and GeoJSON export.

The HTML page is one self-contained file: the data are embedded as JSON and drawn by a
small inline canvas renderer (Web Mercator, pan with the mouse, zoom with the wheel); no
script or style is loaded from the network. Background map tiles are optional
(``tile_url``, e.g. ``https://tile.openstreetmap.org/{z}/{x}/{y}.png``) and off by default,
so the page works fully offline.

What is drawn, per vessel: raw reports (small grey dots), the smoothed track (one coloured
polyline per track segment) and outliers (red crosses). For each vessel it has drawn, the
script appends ``<li class="vessel" data-mmsi=.. data-raw=.. data-track=.. data-outliers=..>``
to the legend, and finally sets ``data-drawn-vessels`` on ``<body>`` -- so a headless
browser's DOM dump shows what was drawn.
"""

from __future__ import annotations

import html
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

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
    """Group per-report arrays into :class:`VesselTrack` (valid rows only, time-sorted)."""
    idx = np.flatnonzero(valid)
    if idx.size == 0:
        return []
    order = idx[np.lexsort((t[idx], mmsi[idx]))]
    m = mmsi[order]
    cuts = np.flatnonzero(np.r_[True, m[1:] != m[:-1], True])
    out = []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        rows = order[a:b]
        out.append(
            VesselTrack(
                int(m[a]),
                t[rows],
                raw_lat[rows],
                raw_lon[rows],
                lat[rows],
                lon[rows],
                segment[rows],
                outlier[rows],
            )
        )
    return out


def _r(a: FloatArray, nd: int = 6) -> list[Any]:
    return [None if not np.isfinite(v) else round(float(v), nd) for v in a]


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
    """Write :func:`geojson` to ``path``."""
    Path(path).write_text(json.dumps(geojson(tracks, include_reports)), encoding="utf-8")


_SCRIPT = r"""
(function () {
  "use strict";
  var D = JSON.parse(document.getElementById("seatrack-data").textContent);
  var cv = document.getElementById("map"), ctx = cv.getContext("2d");
  var legend = document.getElementById("legend");
  function merc(lat, lon) {            // Web Mercator, unit square (x east, y south)
    var s = Math.sin(lat * Math.PI / 180);
    return [lon / 360 + 0.5, 0.5 - Math.log((1 + s) / (1 - s)) / (4 * Math.PI)];
  }
  var minx = 1, maxx = 0, miny = 1, maxy = 0;
  D.vessels.forEach(function (v) {
    v.P = v.rlat.map(function (la, i) { return merc(la, v.rlon[i]); });
    v.S = v.segs.map(function (sg) {
      return sg.lat.map(function (la, i) { return merc(la, sg.lon[i]); });
    });
    v.P.forEach(function (p) {
      minx = Math.min(minx, p[0]); maxx = Math.max(maxx, p[0]);
      miny = Math.min(miny, p[1]); maxy = Math.max(maxy, p[1]);
    });
  });
  var W, H, scale, ox, oy;
  function resize() {
    W = cv.width = cv.clientWidth || 900; H = cv.height = cv.clientHeight || 600;
  }
  function fit(x0, x1, y0, y1) {
    var dx = Math.max(x1 - x0, 1e-9), dy = Math.max(y1 - y0, 1e-9);
    scale = 0.9 * Math.min(W / dx, H / dy);
    ox = (x0 + x1) / 2; oy = (y0 + y1) / 2;
  }
  function px(p) { return [(p[0] - ox) * scale + W / 2, (p[1] - oy) * scale + H / 2]; }
  var tiles = {};
  function drawTiles() {
    if (!D.tile_url) return;
    var z = Math.max(0, Math.min(18, Math.floor(Math.log2(scale / 256))));
    var n = Math.pow(2, z), ts = scale / n;
    var x0 = Math.floor((ox - W / 2 / scale) * n), x1 = Math.floor((ox + W / 2 / scale) * n);
    var y0 = Math.floor((oy - H / 2 / scale) * n), y1 = Math.floor((oy + H / 2 / scale) * n);
    for (var tx = x0; tx <= x1; tx++) for (var ty = y0; ty <= y1; ty++) {
      if (ty < 0 || ty >= n) continue;
      var key = z + "/" + tx + "/" + ty, img = tiles[key];
      if (!img) {
        img = tiles[key] = new Image();
        img.onload = draw;
        img.src = D.tile_url.replace("{z}", z)
          .replace("{x}", ((tx % n) + n) % n).replace("{y}", ty);
      }
      if (img.complete && img.naturalWidth) {
        var q = px([tx / n, ty / n]);
        ctx.drawImage(img, q[0], q[1], ts + 0.5, ts + 0.5);
      }
    }
  }
  var drawnOnce = false;
  function draw() {
    ctx.fillStyle = "#eef3f7"; ctx.fillRect(0, 0, W, H);
    drawTiles();
    D.vessels.forEach(function (v, k) {
      var col = "hsl(" + ((k * 137.5) % 360) + ",70%,38%)", nr = 0, nt = 0, no = 0;
      ctx.fillStyle = "rgba(90,90,90,0.55)";
      v.P.forEach(function (p) { var q = px(p); ctx.fillRect(q[0] - 1, q[1] - 1, 2, 2); nr++; });
      ctx.strokeStyle = col; ctx.lineWidth = 1.6;
      v.S.forEach(function (seg) {
        ctx.beginPath();
        seg.forEach(function (p, i) {
          var q = px(p);
          if (i) ctx.lineTo(q[0], q[1]); else ctx.moveTo(q[0], q[1]);
          nt++;
        });
        ctx.stroke();
      });
      ctx.strokeStyle = "#d00"; ctx.lineWidth = 1.5;
      v.out.forEach(function (i) {
        var q = px(v.P[i]); ctx.beginPath();
        ctx.moveTo(q[0] - 4, q[1] - 4); ctx.lineTo(q[0] + 4, q[1] + 4);
        ctx.moveTo(q[0] + 4, q[1] - 4); ctx.lineTo(q[0] - 4, q[1] + 4); ctx.stroke(); no++;
      });
      if (!drawnOnce) {
        var li = document.createElement("li");
        li.className = "vessel"; li.dataset.mmsi = v.mmsi;
        li.dataset.raw = nr; li.dataset.track = nt; li.dataset.outliers = no;
        li.style.color = col;
        li.textContent = v.mmsi + " (" + nr + " reports, " + no + " outliers)";
        li.onclick = function () {
          var xs = v.P.map(function (p) { return p[0]; });
          var ys = v.P.map(function (p) { return p[1]; });
          fit(Math.min.apply(null, xs), Math.max.apply(null, xs),
              Math.min.apply(null, ys), Math.max.apply(null, ys));
          draw();
        };
        legend.appendChild(li);
      }
    });
    if (!drawnOnce) {
      document.body.dataset.drawnVessels = D.vessels.length;
      drawnOnce = true;
    }
  }
  resize(); fit(minx, maxx, miny, maxy); draw();
  var drag = null;
  cv.addEventListener("mousedown", function (e) { drag = [e.clientX, e.clientY]; });
  window.addEventListener("mouseup", function () { drag = null; });
  window.addEventListener("mousemove", function (e) {
    if (!drag) return;
    ox -= (e.clientX - drag[0]) / scale; oy -= (e.clientY - drag[1]) / scale;
    drag = [e.clientX, e.clientY]; draw();
  });
  cv.addEventListener("wheel", function (e) {
    e.preventDefault();
    var f = e.deltaY < 0 ? 1.25 : 0.8, r = cv.getBoundingClientRect();
    var mx = (e.clientX - r.left - W / 2) / scale + ox;
    var my = (e.clientY - r.top - H / 2) / scale + oy;
    scale *= f; ox = mx - (mx - ox) / f; oy = my - (my - oy) / f; draw();
  }, {passive: false});
  window.addEventListener("resize", function () { resize(); draw(); });
})();
"""

_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>{title}</title>
<style>
body {{ margin: 0; font: 13px sans-serif; display: flex; height: 100vh; }}
#side {{ width: 260px; overflow-y: auto; padding: 8px; border-right: 1px solid #ccc; }}
#map {{ flex: 1 1 auto; min-width: 0; height: 100vh; display: block; cursor: grab; }}
li.vessel {{ cursor: pointer; }}
</style></head>
<body data-drawn-vessels="0">
<div id="side"><h3>{title}</h3>
<p>{summary}</p>
<p>grey dots: AIS reports; lines: smoothed tracks; red crosses: outliers.
Drag to pan, wheel to zoom, click a vessel to zoom to it.</p>
<ul id="legend"></ul></div>
<canvas id="map"></canvas>
<script type="application/json" id="seatrack-data">{data}</script>
<script>{script}</script>
</body></html>
"""


def html_page(
    tracks: Sequence[VesselTrack],
    title: str = "seatrack AIS tracks",
    summary: str = "",
    tile_url: str | None = None,
) -> str:
    """The self-contained HTML page (see the module docstring)."""
    vessels = []
    for v in tracks:
        segs = [{"lat": _r(v.lat[rows], 6), "lon": _r(v.lon[rows], 6)} for _, rows in _segments(v)]
        vessels.append(
            {
                "mmsi": v.mmsi,
                "rlat": _r(v.raw_lat, 6),
                "rlon": _r(v.raw_lon, 6),
                "segs": segs,
                "out": np.flatnonzero(v.outlier).tolist(),
            }
        )
    data = json.dumps({"vessels": vessels, "tile_url": tile_url}, separators=(",", ":"))
    data = data.replace("</", "<\\/")  # never close the script element from inside the data
    return _PAGE.format(
        title=html.escape(title),
        summary=html.escape(summary),
        data=data,
        script=_SCRIPT,
    )


def write_html(path: str | Path, tracks: Sequence[VesselTrack], **kwargs: Any) -> None:
    """Write :func:`html_page` to ``path``."""
    Path(path).write_text(html_page(tracks, **kwargs), encoding="utf-8")
