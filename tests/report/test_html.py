"""Offline HTML map and GeoJSON export; the page is loaded in headless Chromium."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from ais_samples import data_file
from seatrack.report.html import (
    VesselTrack,
    geojson,
    html_page,
    map_tracks,
    vessel_tracks,
    write_html,
)

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


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


def test_geojson_structure() -> None:
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
    json.dumps(g)  # serialisable


def test_page_is_self_contained() -> None:
    page = html_page(_two_vessels(), title="t </script> & <b>")
    assert not re.search(r"<script[^>]*\bsrc=", page)
    assert "<link" not in page and "http://" not in page and "https://" not in page
    assert "&lt;/script&gt;" in page  # title escaped
    data = re.search(r'id="seatrack-data">(.*?)</script>', page, re.S)
    assert data is not None
    assert len(json.loads(data.group(1))["vessels"]) == 2


def _chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.fail(
            "headless Chromium is needed for this test and was not found on PATH; install it "
            "with: apt-get update && apt-get install -y chromium"
        )
    return exe


def test_page_draws_every_vessel_in_headless_chromium(tmp_path: Path) -> None:
    from seatrack.commands.ais import track_files

    src = data_file("dk_northsea_20221101_1h_selected.csv")
    reports, tracks = track_files([src])
    vt = map_tracks(reports, tracks)
    page = tmp_path / "map.html"
    write_html(page, vt, title="selected")
    exe = _chromium()
    profile = tmp_path / "profile"
    run = subprocess.run(
        [exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--dump-dom", page.as_uri()],
        capture_output=True,
        text=True,
        timeout=180,
    )
    dom = run.stdout
    assert run.returncode == 0, run.stderr[-2000:]
    m = re.search(r'<body[^>]*data-drawn-vessels="(\d+)"', dom)
    assert m is not None, "the page script did not run"
    assert int(m.group(1)) == len(vt) == 30
    items = re.findall(
        r'<li class="vessel" data-mmsi="(\d+)" data-raw="(\d+)" data-track="(\d+)" '
        r'data-outliers="(\d+)"',
        dom,
    )
    assert len(items) == len(vt)
    for (mmsi, raw, track, outl), v in zip(items, vt, strict=True):
        assert int(mmsi) == v.mmsi
        assert int(raw) == v.t.size  # every usable report drawn
        assert int(track) == int(np.sum(np.isfinite(v.lat) & (v.segment >= 0)))
        assert int(outl) == int(v.outlier.sum())
    # and pixels were drawn: a screenshot has track colours and the red outlier crosses
    shot = tmp_path / "shot.png"
    run = subprocess.run(
        [
            exe,
            *CHROMIUM_FLAGS,
            f"--user-data-dir={profile}",
            f"--screenshot={shot}",
            "--window-size=1000,700",
            page.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert run.returncode == 0 and shot.is_file(), run.stderr[-2000:]
    import matplotlib.image as mpimg

    img = (mpimg.imread(shot)[..., :3] * 255).round().astype(int)
    red = (img[..., 0] > 200) & (img[..., 1] < 40) & (img[..., 2] < 40)
    assert red.sum() > 20
    background = np.all(np.abs(img - np.array([0xEE, 0xF3, 0xF7])) <= 1, axis=-1)
    assert background.mean() < 0.99 and background.mean() > 0.3


def test_no_usable_rows_gives_an_empty_map() -> None:
    z = np.zeros(2)
    vt = vessel_tracks(
        np.array([1, 2]), z, z, z, z, z, np.array([-1, -1]), np.zeros(2, bool), np.zeros(2, bool)
    )
    assert vt == []
    assert geojson(vt) == {"type": "FeatureCollection", "features": []}
    assert '"vessels":[]' in html_page(vt)
