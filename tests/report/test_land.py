"""Natural Earth land: TopoJSON decoding, box clipping, the bundled data and its budget."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from seatrack.report.land import Rings
from seatrack.report.land import clip_rings
from seatrack.report.land import land_rings
from seatrack.report.land import natural_earth_land
from seatrack.report.land import rings_from_topojson
from seatrack.report.land import topojson_transform


def _area(r: Rings) -> float:
    """Even-odd area (shoelace; holes are rings of the opposite orientation here)."""
    total = 0.0
    for a, b in zip(r.offsets[:-1], r.offsets[1:], strict=True):
        x, y = r.lon[a:b], r.lat[a:b]
        total += 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    return total


def _inside(r: Rings, lon: float, lat: float) -> bool:
    """Even-odd point in polygon over all rings."""
    inside = False
    for a, b in zip(r.offsets[:-1], r.offsets[1:], strict=True):
        x, y = r.lon[a:b], r.lat[a:b]
        x2, y2 = np.roll(x, -1), np.roll(y, -1)
        cross = (y > lat) != (y2 > lat)
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = x + (lat - y) * (x2 - x) / (y2 - y)
        inside ^= bool(np.sum(cross & (lon < xi)) % 2)
    return inside


def _square(x0: float, y0: float, s: float) -> Rings:
    return Rings(
        np.array([x0, x0 + s, x0 + s, x0]), np.array([y0, y0, y0 + s, y0 + s]), np.array([0, 4])
    )


def test_topojson_arcs_are_joined_and_reversed(tmp_path: Path) -> None:
    # unit square from two arcs: the second is used reversed (~1); a triangle from arc 2
    topo = {
        "type": "Topology",
        "transform": {"scale": [0.5, 0.25], "translate": [10, 50]},
        "arcs": [
            [[0, 0], [2, 0], [0, 4]],  # (0,0) -> (2,0) -> (2,4)
            [[0, 0], [0, 4], [2, 0]],  # (0,0) -> (0,4) -> (2,4): reversed below
            [[4, 4], [1, 0], [0, 1], [-1, -1]],  # closed triangle
        ],
        "objects": {
            "land": {
                "type": "GeometryCollection",
                "geometries": [
                    {"type": "Polygon", "arcs": [[0, ~1]]},
                    {"type": "MultiPolygon", "arcs": [[[2]]]},
                ],
            }
        },
    }
    p = tmp_path / "t.json"
    p.write_text(json.dumps(topo))
    r = rings_from_topojson(p)
    assert r.offsets.tolist() == [0, 4, 7]
    np.testing.assert_allclose(r.lon[:4], [10, 11, 11, 10])
    np.testing.assert_allclose(r.lat[:4], [50, 50, 51, 51])
    np.testing.assert_allclose(r.lon[4:], [12, 12.5, 12.5])
    assert topojson_transform(p) == ((0.5, 0.25), (10.0, 50.0))


def test_clip_keeps_the_part_inside_the_box() -> None:
    sq = _square(0.0, 0.0, 2.0)
    c = clip_rings(sq, 1.0, -5.0, 5.0, 1.5)  # west, south, east, north
    assert c.n_rings == 1
    assert _area(c) == pytest.approx(1.0 * 1.5)
    assert c.lon.min() == 1.0 and c.lat.max() == 1.5  # intersections exactly on the edges
    assert clip_rings(sq, 3, 3, 4, 4).n_rings == 0  # disjoint: dropped
    inside = clip_rings(sq, -1, -1, 3, 3)
    assert _area(inside) == pytest.approx(4.0)


def test_clip_of_a_concave_ring_preserves_area() -> None:
    # a U shape (area 5) cut through both arms
    x = np.array([0.0, 3, 3, 2, 2, 1, 1, 0])
    y = np.array([0.0, 0, 3, 3, 1, 1, 3, 3])
    c = clip_rings(Rings(x, y, np.array([0, 8])), -1, 2, 4, 4)
    assert _area(c) == pytest.approx(2.0)  # the two arm tops, 1 x 1 each


def test_bundled_natural_earth_land() -> None:
    r = natural_earth_land()
    assert r.n_rings > 4000 and r.offsets[-1] > 400_000
    jutland = clip_rings(r, 7.5, 54.5, 11.0, 58.0)
    assert _inside(jutland, 9.2, 56.2)  # inland Jutland
    assert not _inside(jutland, 7.8, 56.2)  # North Sea
    assert not _inside(jutland, 10.8, 57.8)  # Kattegat


@pytest.mark.parametrize("budget", [300, 3000])
def test_land_rings_budget(budget: int) -> None:
    r, eps = land_rings(7.5, 54.5, 11.0, 58.0, max_vertices=budget)
    assert 0 < r.offsets[-1] <= budget
    assert (eps > 0) == (budget == 300)  # the box holds ~1,600 vertices: 3,000 keeps all
    assert r.lon.min() >= 7.5 and r.lon.max() <= 11.0
    assert _inside(r, 9.2, 56.2) and not _inside(r, 7.8, 56.2)


def test_focus_spends_the_budget_near_the_tracks() -> None:
    box = (0.0, 50.0, 20.0, 62.0)
    focus = (7.5, 55.5, 8.5, 56.5)  # Jutland's west coast
    plain, _ = land_rings(*box, max_vertices=3000)
    focused, _ = land_rings(*box, max_vertices=3000, focus=focus)

    def near(r: Rings) -> int:
        return int(np.sum((r.lon > 7.0) & (r.lon < 9.0) & (r.lat > 55.0) & (r.lat < 57.0)))

    assert focused.offsets[-1] <= 3000
    assert near(focused) > 2 * near(plain)
