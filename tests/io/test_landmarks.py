"""Landmark map: CSV and binary record round trips, geodetic input, row-naming errors."""

from __future__ import annotations

import numpy as np
import pytest

from seatrack.geometry import enu_to_geodetic
from seatrack.io.landmarks import decode_records
from seatrack.io.landmarks import encode_records
from seatrack.io.landmarks import read_map_csv
from seatrack.io.landmarks import write_map_csv
from seatrack.io.table import InputError
from seatrack.navigation.landmarks import LandmarkMap


def _map() -> LandmarkMap:
    rng = np.random.default_rng(3)
    xy = rng.uniform(-9000, 9000, (7, 2))
    c = np.array([0, 1, 0, 0, 1, 1, 0], bool)
    ori = np.radians([0, 12.5, 0, 0, 179.0, 90.0, 0])
    return LandmarkMap.from_arrays(xy, c, ori, [f"R{k}" for k in range(7)])


def test_csv_round_trip(tmp_path):
    m = _map()
    p = tmp_path / "map.csv"
    write_map_csv(m, p)
    back = read_map_csv(p)
    assert back.ids.tolist() == m.ids.tolist()
    assert np.array_equal(back.is_contour, m.is_contour)
    np.testing.assert_allclose(back.xy, m.xy, atol=5e-4)
    np.testing.assert_allclose(back.orientation, m.orientation, atol=1e-5)
    assert np.allclose(m.normal[m.is_contour], m.orientation[m.is_contour] + np.pi / 2)


def test_binary_records_layout_and_round_trip():
    m = _map()
    data = encode_records(m, resolution_m=1.0, origin_m=(100.0, -50.0))
    n_p, n_c = int((~m.is_contour).sum()), int(m.is_contour.sum())
    assert len(data) == 19 + len(m) + 4 * n_p + 5 * n_c  # 4 bytes / point, 5 / contour
    # first point record: big-endian int16 X, Y about the origin
    off = 19 + len(m)
    x = int.from_bytes(data[off : off + 2], "big", signed=True)
    assert x == int(np.rint(m.xy[0, 0] - 100.0))
    back = decode_records(data)
    assert np.array_equal(back.is_contour, m.is_contour)  # channel order kept
    assert np.max(np.abs(back.xy - m.xy)) <= 0.5 + 1e-9  # quantised to 1 m
    d_or = np.abs(back.orientation - m.orientation)[m.is_contour]
    assert np.max(np.minimum(d_or, np.pi - d_or)) <= np.pi / 512 + 1e-12  # 0.35 deg
    # decoding then encoding again is exact
    assert encode_records(back, 1.0, (100.0, -50.0)) == data


def test_binary_records_errors():
    m = _map()
    with pytest.raises(ValueError, match="32767"):
        encode_records(m, resolution_m=0.1)
    data = encode_records(m)
    with pytest.raises(InputError, match="expected"):
        decode_records(data[:-1])
    with pytest.raises(InputError, match="magic"):
        decode_records(b"XXXX" + data[4:])


def test_geodetic_rows(tmp_path):
    lat0, lon0 = 48.85, 2.35
    lat, lon, _ = enu_to_geodetic(np.array([[1200.0, -300.0]]), lat0, lon0)
    p = tmp_path / "map.csv"
    p.write_text(
        "id,kind,x_m,y_m,orientation_deg,lat_deg,lon_deg\n"
        f"A,point,,,,{lat[0]:.10f},{lon[0]:.10f}\n"
        "B,contour,10,20,45,,\n"
    )
    m = read_map_csv(p, origin=(lat0, lon0))
    np.testing.assert_allclose(m.xy[0], [1200.0, -300.0], atol=1e-3)
    np.testing.assert_allclose(m.xy[1], [10.0, 20.0])
    with pytest.raises(InputError, match="line 2: lat_deg/lon_deg given but no origin"):
        read_map_csv(p)


@pytest.mark.parametrize(
    ("row", "message"),
    [
        ("C,tower,1,2,", "line 3: kind = 'tower'"),
        ("C,contour,1,2,", "line 3: contour element needs orientation_deg"),
        ("A,point,1,2,", "line 3: duplicate id 'A'"),
        ("C,point,,,", "line 3: give x_m and y_m"),
        ("C,contour,1,2,400", "line 3: orientation_deg = 400 outside"),
        ("C,point,abc,2,", "line 3: column x_m = 'abc' is not a number"),
    ],
)
def test_bad_rows_name_the_line(tmp_path, row, message):
    p = tmp_path / "bad.csv"
    p.write_text("id,kind,x_m,y_m,orientation_deg\nA,point,0,0,\n" + row + "\n")
    with pytest.raises(InputError, match=message):
        read_map_csv(p)
