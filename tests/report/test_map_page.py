"""The data carried by the map page: parts, budgets, first view, tiles, rendering."""

from __future__ import annotations

import json
import re
from typing import Any

import numpy as np
import pytest

from seatrack.report.map_page import OPENSEAMAP_URL
from seatrack.report.map_page import OSM_URL
from seatrack.report.map_page import MapOptions
from seatrack.report.map_page import page_data
from seatrack.report.map_page import render_page
from seatrack.report.map_page import robust_bounds


def _undelta(a: list[int]) -> np.ndarray:
    return np.cumsum(np.asarray(a, dtype=np.int64))


def _walks(n_vessels: int, n: int, seed: int = 0) -> dict[str, Any]:
    """Random-walk vessels near 56 N 7 E: per-row arrays grouped by vessel."""
    rng = np.random.default_rng(seed)
    lat = 56.0 + np.cumsum(rng.normal(0, 1e-4, (n_vessels, n)), axis=1)
    lon = 7.0 + np.cumsum(rng.normal(0, 2e-4, (n_vessels, n)), axis=1)
    outlier = rng.random((n_vessels, n)) < 0.05
    seg = np.repeat((np.arange(n) >= n // 2)[None, :], n_vessels, axis=0).astype(np.int64)
    t = np.tile(1.6e9 + 10.0 * np.arange(n), n_vessels)
    return dict(
        mmsi=np.arange(n_vessels, dtype=np.int64) + 1,
        counts=np.full(n_vessels, n, dtype=np.int64),
        t=t,
        raw_lat=lat.ravel(),
        raw_lon=lon.ravel(),
        lat=lat.ravel(),
        lon=lon.ravel(),
        segment=seg.ravel(),
        outlier=outlier.ravel(),
    )


def test_parts_vertices_times_and_outliers_are_exact() -> None:
    t = np.arange(5.0) + 100.0
    lat = 56.0 + np.array([0.0, 1e-3, 3e-3, 2e-3, 5e-3])
    lon = 7.0 + np.array([0.0, 2e-3, 1e-3, 4e-3, 3e-3])
    d = page_data(
        np.array([5, 9]),
        np.array([5, 2]),
        np.r_[t, 50.0, 51.0],
        np.r_[lat, 50.0, np.nan],
        np.r_[lon, 1.0, 1.0],
        np.r_[lat[:2], np.nan, lat[3:], 50.0, 50.0],
        np.r_[lon, 1.0, 1.0],
        np.array([1, 1, 1, 2, 2, 3, -1]),
        np.array([False, False, True, False, False, False, False]),
    )
    assert d["t0"] == 50.0 and d["mmsi"] == [5, 9]
    assert d["vpart"] == [0, 2, 3]  # vessel 5: segments 1 and 2; vessel 9: segment 3
    assert d["poff"] == [0, 2, 4, 5]  # the NaN row is skipped; the -1 row is in no part
    np.testing.assert_array_equal(_undelta(d["la"]), np.round(np.r_[lat[[0, 1, 3, 4]], 50.0] * 1e5))
    np.testing.assert_array_equal(_undelta(d["tt"]), [50, 51, 53, 54, 0])
    assert d["nusable"] == [5, 1] and d["noutliers"] == [1, 0]
    assert d["rv"] == [0, 4, 5] and d["ov"] == [0, 1, 1]
    np.testing.assert_array_equal(_undelta(d["ola"]), [round(lat[2] * 1e5)])
    np.testing.assert_array_equal(_undelta(d["ot"]), [52])
    assert d["stats"]["vertices"] == d["stats"]["track_points"] == 5
    json.dumps(d, allow_nan=False)


def test_budgets_bound_what_the_page_carries() -> None:
    w = _walks(40, 500)
    d = page_data(**w, opts=MapOptions(max_vertices=2000, max_reports=1000, max_outliers=100))
    la, lo = _undelta(d["la"]), _undelta(d["lo"])
    assert la.size == d["stats"]["vertices"] <= 2000
    assert la.size > 1500  # the budget is used, not wasted
    assert d["stats"]["tolerance_m"] > 0
    # every part keeps its first and last position exactly
    q_lat = np.round(w["lat"].reshape(40, 2, 250) * 1e5)
    poff = np.asarray(d["poff"])
    assert poff.size == 81
    np.testing.assert_array_equal(la[poff[:-1]], q_lat[:, :, 0].ravel())
    np.testing.assert_array_equal(la[poff[1:] - 1], q_lat[:, :, -1].ravel())
    assert lo.size == la.size
    # reports: every k-th per vessel, k the smallest that fits
    n_rep = int(np.sum(~w["outlier"]))
    k = d["stats"]["report_stride"]
    assert d["rv"][-1] <= 1000 < n_rep and k > 1
    assert d["stats"]["outliers_drawn"] == d["ov"][-1] <= 100
    assert d["stats"]["outliers"] == int(w["outlier"].sum())


def test_no_budget_pressure_keeps_everything() -> None:
    w = _walks(3, 200)
    d = page_data(**w)
    assert d["stats"]["report_stride"] == 1 and d["stats"]["outlier_stride"] == 1
    assert d["rv"][-1] + d["ov"][-1] == 600
    assert len(d["la"]) == 600  # random walks: no vertex is redundant at 1/10 pixel, z18


def test_vessels_without_rows_are_counted_as_empty() -> None:
    lat = np.array([56.0, 56.1, 56.2])
    d = page_data(
        np.array([1, 2, 3]),
        np.array([2, 0, 1]),
        np.arange(3.0),
        lat,
        lat,
        lat,
        lat,
        np.zeros(3, np.int64),
        np.array([False, True, True]),
    )
    assert d["nusable"] == [2, 0, 1] and d["noutliers"] == [1, 0, 1]
    assert d["vpart"] == [0, 1, 1, 2] and d["rv"] == [0, 1, 1, 1] and d["ov"] == [0, 1, 1, 2]
    z = np.zeros(3, np.int64)
    last_empty = page_data(
        np.array([1, 2]), np.array([3, 0]), np.arange(3.0), lat, lat, lat, lat, z, z > 0
    )
    assert last_empty["nusable"] == [3, 0] and last_empty["noutliers"] == [0, 0]


def test_interleaved_segments_are_grouped() -> None:
    lat = np.array([56.0, 56.1, 56.2, 56.3])
    d = page_data(
        np.array([1]),
        np.array([4]),
        np.arange(4.0),
        lat,
        lat,
        lat,
        lat,
        np.array([0, 1, 0, 1]),
        np.zeros(4, bool),
    )
    assert d["poff"] == [0, 2, 4]
    np.testing.assert_array_equal(_undelta(d["tt"]), [0, 2, 1, 3])


def test_first_view_ignores_a_few_wild_positions() -> None:
    rng = np.random.default_rng(3)
    lat = np.r_[56 + rng.uniform(0, 0.2, 2000), 0.0, 80.0, 10.0]
    lon = np.r_[7 + rng.uniform(0, 0.4, 2000), 0.0, -170.0, 100.0]
    s, w, n, e = robust_bounds(lat, lon)  # type: ignore[misc]
    assert 55.99 < s < 56.01 and 56.19 < n < 56.21
    assert 6.99 < w < 7.01 and 7.39 < e < 7.41
    assert robust_bounds(np.array([np.nan]), np.array([1.0])) is None
    s, w, n, e = robust_bounds(np.array([56.0]), np.array([7.0]))  # type: ignore[misc]
    assert n - s == pytest.approx(0.005) and e - w == pytest.approx(0.005)


def test_options_and_tiles() -> None:
    w = _walks(1, 10)
    assert page_data(**w)["tiles"]["base"] == OSM_URL
    assert page_data(**w)["tiles"]["seamarks"] == OPENSEAMAP_URL
    own = page_data(**w, opts=MapOptions(tile_url="http://x/{z}/{x}/{y}.png", seamark_url=None))
    assert own["tiles"]["base"] == "http://x/{z}/{x}/{y}.png"
    assert own["tiles"]["seamarks"] is None and own["tiles"]["base_attribution"] == ""
    assert page_data(**w, opts=MapOptions(online=False))["tiles"] is None
    assert page_data(**w)["land"]["off"][-1] > 0  # the coast near 56 N 7 E
    with pytest.raises(ValueError, match="max_vertices"):
        MapOptions(max_vertices=-1)
    with pytest.raises(ValueError, match="percentile"):
        MapOptions(percentile=50)


def test_render_page_is_one_self_contained_file() -> None:
    d = page_data(**_walks(2, 20))
    d["stats"]["note"] = "</script><script>alert(1)</script>"
    page = render_page("t </script> & <b>", "s <i>", d)
    assert "&lt;/script&gt; &amp; &lt;b&gt;" in page and "s &lt;i&gt;" in page
    assert not re.search(r"<script[^>]*\bsrc=", page)
    assert not re.search(r"<link\b|@import|url\(\s*['\"]?https?:", page)
    assert page.count("</script>") == 3  # Leaflet, the data, the page script
    m = re.search(r'id="seatrack-data">(.*?)</script>', page, re.S)
    assert m is not None and json.loads(m.group(1)) == json.loads(json.dumps(d))
    assert "sourceMappingURL" not in page


def _package_glob_matches(path: str, pattern: str) -> bool:
    """setuptools package-data semantics: ``*`` within one folder, ``**`` across folders."""
    import fnmatch

    parts, pats = path.split("/"), pattern.split("/")
    if "**" in pats:
        k = pats.index("**")
        return (
            len(parts) > k
            and all(fnmatch.fnmatch(a, b) for a, b in zip(parts[:k], pats[:k], strict=True))
            and fnmatch.fnmatch(parts[-1], pats[-1])
        )
    return len(parts) == len(pats) and all(
        fnmatch.fnmatch(a, b) for a, b in zip(parts, pats, strict=True)
    )


def test_every_bundled_asset_is_package_data_and_leaflet_is_vendored_with_its_licence():
    import tomllib
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]  # the source tree, installed or not
    root = repo / "src" / "seatrack"
    pyproject = repo / "pyproject.toml"
    globs = tomllib.loads(pyproject.read_text())["tool"]["setuptools"]["package-data"]["seatrack"]
    assets = root / "report" / "assets"
    files = [p.relative_to(root).as_posix() for p in assets.rglob("*") if p.is_file()]
    files = [f for f in files if "__pycache__" not in f]
    missing = [f for f in files if not any(_package_glob_matches(f, g) for g in globs)]
    assert files and not missing
    leaflet = assets / "vendor" / "leaflet"
    assert {p.name for p in leaflet.iterdir()} >= {
        "leaflet.js", "leaflet.css", "layers.png", "layers-2x.png", "LICENSE-leaflet.txt"
    }  # fmt: skip
    page = render_page("t", "s", page_data(**_walks(1, 5)))
    assert "Leaflet 1.9.4" in page and "url(data:image/png;base64," in page
