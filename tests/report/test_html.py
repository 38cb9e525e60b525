"""HTML map and GeoJSON export; the page is loaded in headless Chromium.

The browser test runs wherever Chromium is on PATH. Without it the test is skipped with the
install command, except under CI (``CI=true``), where a missing browser is a failure.
"""

from __future__ import annotations

import json
import re
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ais_samples import data_file
from browser import browse
from browser import chromium
from seatrack.report.html import VesselTrack
from seatrack.report.html import geojson
from seatrack.report.html import html_page
from seatrack.report.html import map_tracks
from seatrack.report.html import vessel_tracks
from seatrack.report.html import write_geojson
from seatrack.report.html import write_html

# tiles from a closed local port: they fail at once, whatever network the machine has
DEAD_TILES = "http://127.0.0.1:9/{z}/{x}/{y}.png"
SEA = (0xCF, 0xE1, 0xEC)
LAND = (0xF1, 0xED, 0xE3)
SIDEBAR_PX = 290
FIELDS = ("t", "raw_lat", "raw_lon", "lat", "lon", "segment", "outlier")


def _two_vessels() -> list[VesselTrack]:
    t = np.arange(5.0)
    lat = 56.0 + 1e-4 * t
    lon = 7.0 + 2e-4 * t
    a = VesselTrack(
        1,
        t,
        lat,
        lon,
        lat,
        lon,
        np.array([1, 1, 1, 2, 2]),
        np.array([False, False, True, False, False]),
    )
    b = VesselTrack(2, t[:1], lat[:1], lon[:1], lat[:1], lon[:1], np.array([3]), np.array([False]))
    return [a, b]


def test_geojson_structure(tmp_path: Path) -> None:
    g = geojson(_two_vessels(), include_reports=True)
    assert g["type"] == "FeatureCollection"
    kinds = [
        (f["properties"]["mmsi"], f["properties"]["kind"], f["geometry"]["type"])
        for f in g["features"]
    ]
    assert kinds == [
        (1, "track", "LineString"),
        (1, "track", "LineString"),
        (1, "outlier", "Point"),
        (1, "reports", "MultiPoint"),
        (2, "track", "Point"),
        (2, "reports", "MultiPoint"),
    ]
    line = g["features"][0]["geometry"]["coordinates"]
    assert line[0] == [7.0, 56.0]  # RFC 7946: longitude first
    assert g["features"][0]["properties"]["n_reports"] == 3
    out = tmp_path / "sub" / "t.geojson"
    write_geojson(out, _two_vessels(), include_reports=True)
    assert json.loads(out.read_text()) == json.loads(json.dumps(g))
    assert [p.name for p in out.parent.iterdir()] == ["t.geojson"]  # no temporary left


def test_vessel_tracks_groups_sorted_and_unsorted_input_alike() -> None:
    rng = np.random.default_rng(0)
    n = 200
    mmsi = rng.integers(1, 6, n)
    t = np.sort(rng.uniform(0, 1000, n))
    cols = [rng.normal(size=n) for _ in range(4)]
    seg = rng.integers(0, 3, n)
    out = rng.random(n) < 0.1
    valid = rng.random(n) < 0.9
    a = vessel_tracks(mmsi, t, *cols, seg, out, valid)
    perm = rng.permutation(n)  # time order broken within vessels: the full sort path
    b = vessel_tracks(
        mmsi[perm], t[perm], *(c[perm] for c in cols), seg[perm], out[perm], valid[perm]
    )
    assert [v.mmsi for v in a] == [v.mmsi for v in b] == sorted(set(mmsi[valid]))
    for u, v in zip(a, b, strict=True):
        assert np.all(np.diff(u.t) >= 0) and u.t.size == int(np.sum(valid & (mmsi == u.mmsi)))
        for name in FIELDS:
            np.testing.assert_array_equal(getattr(u, name), getattr(v, name))


def test_pages_of_views_and_of_copies_are_identical() -> None:
    rng = np.random.default_rng(4)
    n = 300
    mmsi = np.repeat([7, 3, 9], 100)
    t = np.tile(np.arange(100.0), 3)
    lat, lon = 56 + rng.normal(0, 0.01, n), 7 + rng.normal(0, 0.01, n)
    seg, out = np.repeat([0, 1, 2], 100), rng.random(n) < 0.1
    views = vessel_tracks(mmsi, t, lat, lon, lat, lon, seg, out, np.ones(n, bool))
    assert views[0].t.base is views[1].t.base  # slices of one gathered copy
    copies = [VesselTrack(v.mmsi, *(np.array(getattr(v, f)) for f in FIELDS)) for v in views]
    assert html_page(views) == html_page(copies)
    assert html_page(views[::-1]) != html_page(views)  # order matters: not a stale view


def test_page_options_reach_the_page(tmp_path: Path) -> None:
    page = html_page(_two_vessels(), title="t </script> & <b>")
    assert "&lt;/script&gt;" in page  # title escaped
    assert "tile.openstreetmap.org" in page and "tiles.openseamap.org/seamark" in page
    data = json.loads(re.search(r'id="seatrack-data">(.*?)</script>', page, re.S).group(1))
    assert data["mmsi"] == [1, 2] and data["tiles"]["base"].startswith("https://tile.")
    offline = html_page(_two_vessels(), online=False, max_vertices=3)
    assert "tile.openstreetmap.org/{z}" not in offline
    data = json.loads(re.search(r'id="seatrack-data">(.*?)</script>', offline, re.S).group(1))
    assert data["tiles"] is None
    # parts of 3, 2 and 1 positions: a budget below their 5 end points keeps just those
    assert len(data["la"]) == 5 and data["stats"]["track_points"] == 6
    out = tmp_path / "m.html"
    write_html(out, _two_vessels(), title="x", tile_url=DEAD_TILES, seamark_url=None)
    assert DEAD_TILES in out.read_text() and [p.name for p in tmp_path.iterdir()] == ["m.html"]


def test_no_usable_rows_gives_an_empty_map() -> None:
    z = np.zeros(2)
    vt = vessel_tracks(
        np.array([1, 2]), z, z, z, z, z, np.array([-1, -1]), np.zeros(2, bool), np.zeros(2, bool)
    )
    assert vt == []
    assert geojson(vt) == {"type": "FeatureCollection", "features": []}
    page = html_page(vt)
    assert '"mmsi":[]' in page and '"view":null' in page


# --------------------------------------------------------------------------- Chromium
@pytest.fixture(scope="module")
def browsed(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The selected North Sea vessels' map, offline tiles, as the browser drew it."""
    exe = chromium()
    from seatrack.commands.ais import track_files

    tmp = tmp_path_factory.mktemp("map")
    reports, tracks = track_files([data_file("dk_northsea_20221101_1h_selected.csv")])
    vt = map_tracks(reports, tracks)
    page = tmp / "map.html"
    write_html(page, vt, title="selected", tile_url=DEAD_TILES, seamark_url=None)
    text = page.read_text(encoding="utf-8")
    data = json.loads(re.search(r'id="seatrack-data">(.*?)</script>', text, re.S).group(1))
    dom = browse(exe, tmp / "p1", page.as_uri(), "--dump-dom").stdout
    shot = tmp / "shot.png"
    browse(exe, tmp / "p2", page.as_uri(), f"--screenshot={shot}", "--window-size=1200,800")
    pick = vt[len(vt) // 2].mmsi
    selected = browse(exe, tmp / "p3", page.as_uri() + f"#mmsi={pick}", "--dump-dom").stdout
    default = tmp / "default.html"  # OpenStreetMap + OpenSeaMap, opened from disk
    write_html(default, vt, title="default")
    from_file = browse(exe, tmp / "p4", default.as_uri(), "--dump-dom").stdout
    return dict(
        vt=vt, data=data, dom=dom, shot=shot, pick=pick, selected=selected, from_file=from_file
    )


def _body(dom: str) -> dict[str, str]:
    m = re.search(r"<body([^>]*)>", dom)
    assert m is not None
    return dict(re.findall(r'data-([a-z-]+)="([^"]*)"', m.group(1)))


def test_page_draws_every_vessel_in_headless_chromium(browsed: dict[str, Any]) -> None:
    vt: list[VesselTrack] = browsed["vt"]
    d, dom = browsed["data"], browsed["dom"]
    body = _body(dom)
    with_track = [v for v in vt if np.any(np.isfinite(v.lat) & (v.segment >= 0))]
    assert int(body["vessels"]) == len(vt) == 30
    assert int(body["paths"]) == len(with_track) > 25
    assert int(body["vertices"]) == len(d["la"]) and int(body["outliers"]) == len(d["ola"])
    assert body["renderer"] == "svg"
    # one SVG path per vessel with a track, tagged with its MMSI
    paths = Counter(int(m) for m in re.findall(r'<path class="st-track st-v(\d+)', dom))
    assert paths == Counter(v.mmsi for v in with_track)
    items = re.findall(
        r'<li class="vessel" data-mmsi="(\d+)" data-parts="(\d+)" data-vertices="(\d+)" '
        r'data-reports="(\d+)" data-outliers="(\d+)"',
        dom,
    )
    assert len(items) == len(vt)
    for (mmsi, parts, verts, reps, outl), v in zip(items, vt, strict=True):
        drawable = np.isfinite(v.lat) & (v.segment >= 0)
        assert int(mmsi) == v.mmsi
        assert int(parts) == np.unique(v.segment[drawable]).size
        assert int(parts) <= int(verts) <= int(drawable.sum())  # decimated, never more
        assert int(reps) == int(np.sum(~v.outlier))  # small input: every report carried
        assert int(outl) == int(v.outlier.sum())
    assert sum(int(i[2]) for i in items) == len(d["la"])


def test_offline_the_page_says_so_and_draws_the_coast(browsed: dict[str, Any]) -> None:
    body = _body(browsed["dom"])
    assert body["tiles"] == "failed"
    assert int(body["land"]) > 0
    note = re.search(r'<div id="tilenote"([^>]*)>([^<]*)</div>', browsed["dom"])
    assert note is not None and "hidden" not in note.group(1)
    assert "could not be loaded" in note.group(2) and "Natural Earth" in note.group(2)


def test_from_disk_openstreetmap_is_not_asked_and_the_page_says_why(
    browsed: dict[str, Any],
) -> None:
    dom = browsed["from_file"]
    body = _body(dom)
    assert body["tiles"] == "needs-http" and int(body["land"]) > 0
    assert int(body["vessels"]) == 30
    note = re.search(r'<div id="tilenote"([^>]*)>([^<]*)</div>', dom)
    assert note is not None and "hidden" not in note.group(1)
    assert "served over http" in note.group(2)
    imgs = [i for i in re.findall(r"<img[^>]*>", dom) if "leaflet-tile" in i]
    tiles = [re.search(r'src="([^"]*)"', i).group(1) for i in imgs]
    assert tiles and all("tiles.openseamap.org/seamark/" in u for u in tiles)  # no OSM tile


def test_a_link_selects_a_vessel(browsed: dict[str, Any]) -> None:
    dom = browsed["selected"]
    assert _body(dom)["selected"] == str(browsed["pick"])
    assert re.findall(r'<li class="vessel selected" data-mmsi="(\d+)"', dom) == [
        str(browsed["pick"])
    ]


def test_screenshot_shows_sea_land_tracks_and_outliers(browsed: dict[str, Any]) -> None:
    import matplotlib.image as mpimg

    img = (mpimg.imread(browsed["shot"])[..., :3] * 255).round().astype(int)
    assert img.shape[:2] == (800, 1200)
    m = img[:, SIDEBAR_PX + 5 :]  # the map
    colours = np.unique((m[..., 0] << 16) | (m[..., 1] << 8) | m[..., 2]).size
    assert colours > 100  # not blank: sea, land, coast, tracks, text, controls
    sea = np.all(np.abs(m - np.array(SEA)) <= 2, axis=-1).mean()
    land = np.all(np.abs(m - np.array(LAND)) <= 2, axis=-1).mean()
    assert 0.2 < sea < 0.97 and land > 0.01  # the offline Natural Earth coast is drawn
    c = m[80:-70, 60:-60]  # the map without its controls (zoom, layers, note, slider, credits)
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    vivid = (c.max(axis=-1) - c.min(axis=-1)) > 90
    red = (r > 190) & (g < 90) & (b < 90)
    assert (vivid & ~red).sum() > 300  # track colours
    assert red.sum() > 5  # outliers
