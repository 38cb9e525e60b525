"""AIS CSV readers on the real data bundled in seatrack/data/ais (every row accounted for)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from ais_samples import FILES
from ais_samples import data_file
from seatrack.geometry import local_frames
from seatrack.geometry import local_to_geodetic
from seatrack.io.ais import REJECT_REASONS
from seatrack.io.ais import detect_schema
from seatrack.io.ais import output_order
from seatrack.io.ais import parse_times
from seatrack.io.ais import read_ais
from seatrack.io.ais import read_ais_csv
from seatrack.io.ais import rejection_counts
from seatrack.io.ais import write_tracks_csv
from seatrack.io.table import InputError


def _raw_rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.mark.parametrize("name", FILES)
def test_every_real_row_accounted_for(name: str) -> None:
    path = data_file(name)
    raw = _raw_rows(path)
    r = read_ais_csv(path)
    assert len(r) == len(raw)  # one entry per data row
    assert np.array_equal(r.line, np.arange(2, len(raw) + 2))
    assert set(np.unique(r.reject)) <= {""} | set(REJECT_REASONS)
    ok = r.valid
    # usable rows carry exactly the values of the file
    lat = np.array([float(x["lat"]) for x in raw])
    assert np.array_equal(r.lat[ok], lat[ok])
    assert np.array_equal(r.mmsi, np.array([int(x["mmsi"]) for x in raw]))
    assert np.isfinite(r.t).all()
    assert sum(rejection_counts(r).values()) == int((~ok).sum())


def test_duplicates_in_the_north_sea_file_match_the_readme() -> None:
    # README: 638 same-second pairs in _all, 120 of them with different positions, so 518
    # exact repeats (same mmsi, time, lat, lon); only those are rejected
    r = read_ais_csv(data_file("dk_northsea_20221101_1h_all.csv"))
    assert rejection_counts(r) == {"duplicate report": 518}
    dup = np.flatnonzero(r.reject == "duplicate report")
    # every duplicate repeats the row just before it (files are sorted by mmsi, time)
    for i in dup:
        assert (r.mmsi[i], r.t[i], r.lat[i], r.lon[i]) == (
            r.mmsi[i - 1],
            r.t[i - 1],
            r.lat[i - 1],
            r.lon[i - 1],
        )
    sel = read_ais_csv(data_file("dk_northsea_20221101_1h_selected.csv"))
    assert rejection_counts(sel) == {"duplicate report": 494 - 87}


def test_selected_is_subset_duplicates_across_files() -> None:
    sel = data_file("dk_northsea_20221101_1h_selected.csv")
    both = read_ais([data_file("dk_northsea_20221101_1h_all.csv"), sel])
    n_all = len(_raw_rows(data_file("dk_northsea_20221101_1h_all.csv")))
    assert len(both) == n_all + len(_raw_rows(sel))
    # every row of _selected is a row of _all: all of them are duplicates across files
    assert (both.reject[both.source == 1] == "duplicate report").all()
    assert both.sources[1] == str(sel)


def _write(path: Path, header: list[str], rows: list[list[str]]) -> Path:
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
    return path


def test_dma_and_noaa_headers_read_the_same_values(tmp_path: Path) -> None:
    src = data_file("dk_gothenburg_20170705_cpa.csv")
    raw = _raw_rows(src)
    common = read_ais_csv(src)
    dma_rows = []
    noaa_rows = []
    for x in raw:
        d, t = x["time_utc"][:10], x["time_utc"][11:19]
        dmy = f"{d[8:10]}/{d[5:7]}/{d[0:4]} {t}"
        dma_rows.append(
            [
                dmy,
                "Class A",
                x["mmsi"],
                x["lat"],
                x["lon"],
                "Under way",
                "",
                x["sog_kn"],
                x["cog_deg"],
                x["heading_deg"],
            ]
        )
        noaa_rows.append(
            [
                x["mmsi"],
                x["time_utc"][:19],
                x["lat"],
                x["lon"],
                x["sog_kn"],
                x["cog_deg"],
                x["heading_deg"],
                "NAME",
            ]
        )
    dma = _write(
        tmp_path / "dma.csv",
        [
            "# Timestamp",
            "Type of mobile",
            "MMSI",
            "Latitude",
            "Longitude",
            "Navigational status",
            "ROT",
            "SOG",
            "COG",
            "Heading",
        ],
        dma_rows,
    )
    noaa = _write(
        tmp_path / "noaa.csv",
        ["MMSI", "BaseDateTime", "LAT", "LON", "SOG", "COG", "Heading", "VesselName"],
        noaa_rows,
    )
    for path, schema in ((dma, "dma"), (noaa, "noaa")):
        with path.open() as fh:
            assert detect_schema(next(csv.reader(fh))) == schema
        r = read_ais_csv(path)
        assert r.valid.all()
        for f in ("mmsi", "t", "lat", "lon", "sog_kn", "cog_deg"):
            assert np.array_equal(getattr(r, f), getattr(common, f), equal_nan=True), f


def test_bad_rows_are_rejected_with_reasons(tmp_path: Path) -> None:
    rows = [
        ["1", "2022-11-01T09:00:00Z", "56.0", "7.0", "10", "90", "90"],  # ok
        ["1", "2022-11-01T09:00:10Z", "91", "7.0", "", "", ""],  # lat n/a
        ["1", "2022-11-01T09:00:20Z", "56.0", "181", "", "", ""],  # lon n/a
        ["1", "2022-11-01T09:00:30Z", "nan", "7.0", "", "", ""],  # NaN
        ["1", "yesterday", "56.0", "7.0", "", "", ""],  # time
        ["", "2022-11-01T09:00:40Z", "56.0", "7.0", "", "", ""],  # mmsi
        ["x7", "2022-11-01T09:00:40Z", "56.0", "7.0", "", "", ""],  # mmsi
        ["1", "2022-11-01T09:00:50Z", "north", "7.0", "", "", ""],  # text
        ["1", "2022-11-01T09:01:00Z", "-95", "7.0", "", "", ""],  # range
        ["1", "2022-11-01T09:01:10Z", "56.0", "", "", "", ""],  # missing
        ["1", "2022-11-01T09:00:00Z", "56.0", "7.0", "10", "90", "90"],  # duplicate of 1st
        ["2", "2022-11-01T09:00:00Z", "56.0", "7.0", "102.3", "360", "511"],  # n/a optionals
    ]
    p = _write(
        tmp_path / "bad.csv",
        ["mmsi", "time_utc", "lat", "lon", "sog_kn", "cog_deg", "heading_deg"],
        rows,
    )
    r = read_ais_csv(p)
    assert r.reject.tolist() == [
        "",
        "lat not available (91)",
        "lon not available (181)",
        "position NaN",
        "unparsable time",
        "missing mmsi",
        "invalid mmsi",
        "position not a number",
        "lat out of range",
        "missing position",
        "duplicate report",
        "",
    ]
    assert np.isnan([r.sog_kn[-1], r.cog_deg[-1], r.heading_deg[-1]]).all()
    assert r.sog_kn[0] == 10.0


def test_unknown_header_names_the_file(tmp_path: Path) -> None:
    p = _write(tmp_path / "x.csv", ["a", "b"], [["1", "2"]])
    with pytest.raises(InputError, match=r"x\.csv.*not a recognised AIS CSV header"):
        read_ais_csv(p)
    with pytest.raises(InputError, match="file not found"):
        read_ais_csv(tmp_path / "missing.csv")


def test_time_formats() -> None:
    good = [
        "2022-11-01T09:35:36Z",
        "2022-11-01 09:35:36",
        "01/11/2022 09:35:36",
        "1667295336",
        "2022-11-01T10:35:36+01:00",
        "2022-11-01T08:35:36-01:00",
    ]
    t = parse_times(np.array([*good, "soon", ""]))
    assert np.array_equal(t[: len(good)], np.full(len(good), 1667295336.0))
    assert np.isnan(t[len(good) :]).all()
    # the vectorised ISO path alone
    assert np.array_equal(parse_times(np.array(good[:1] * 3)), np.full(3, 1667295336.0))


def test_local_frame_round_trip_per_vessel() -> None:
    r = read_ais_csv(data_file("no_vestland_20220901.csv"))
    fr = local_frames(r.mmsi, r.lat, r.lon, r.valid)
    # one origin per vessel: the vessel's first report maps to (0, 0)
    for m in np.unique(r.mmsi):
        i = np.flatnonzero(r.mmsi == m)[0]
        assert np.allclose(fr.enu[i], 0.0, atol=1e-6)
    lat, lon = local_to_geodetic(fr.enu[:, 0], fr.enu[:, 1], fr.lat0, fr.lon0)
    assert np.abs(lat - r.lat).max() < 1e-9 and np.abs(lon - r.lon).max() < 1e-9
    # the longest track (350 km) spans > 100 km from its origin: the round trip is exact
    assert np.hypot(fr.enu[:, 0], fr.enu[:, 1]).max() > 1e5


def test_from_local_with_a_vessel_without_estimates() -> None:
    """A vessel none of whose rows has an estimate (all NaN) must not break the others."""
    r = read_ais_csv(data_file("no_vestland_20220901.csv"))
    fr = local_frames(r.mmsi, r.lat, r.lon, r.valid)
    east, north = fr.enu[:, 0].copy(), fr.enu[:, 1].copy()
    first = r.mmsi == np.unique(r.mmsi)[0]
    east[first] = np.nan
    lat, lon = local_to_geodetic(east, north, fr.lat0, fr.lon0)
    assert np.isnan(lat[first]).all()
    assert np.abs(lat[~first] - r.lat[~first]).max() < 1e-9


def test_tracks_csv_order_and_accounting(tmp_path: Path) -> None:
    rows = [
        ["5", "2022-11-01T09:00:10Z", "56.0", "7.0", "", "", ""],
        ["3", "2022-11-01T09:00:00Z", "55.0", "7.0", "", "", ""],
        ["", "2022-11-01T09:00:00Z", "55.0", "7.0", "", "", ""],
        ["5", "2022-11-01T09:00:00Z", "56.0", "7.001", "", "", ""],  # earlier, later line
        ["3", "2022-11-01T09:00:10Z", "91", "7.0", "", "", ""],
    ]
    p = _write(
        tmp_path / "o.csv",
        ["mmsi", "time_utc", "lat", "lon", "sog_kn", "cog_deg", "heading_deg"],
        rows,
    )
    r = read_ais_csv(p)
    assert r.line[output_order(r)].tolist() == [2, 5, 3, 6, 4]
    out = tmp_path / "T.csv"
    lat = np.where(r.valid, r.lat + 0.5, np.nan)  # a stand-in "smoothed" column
    n = write_tracks_csv(out, r, {"lat": lat, "lon": r.lon, "outlier": np.zeros(5, bool)})
    got = _raw_rows(out)
    assert n == 5 and len(got) == 5
    assert [g["line"] for g in got] == ["2", "5", "3", "6", "4"]
    assert [g["reject_reason"] for g in got] == [
        "",
        "",
        "",
        "lat not available (91)",
        "missing mmsi",
    ]
    assert got[0]["time_utc"] == "2022-11-01T09:00:10Z"
    assert got[3]["lat"] == "" and got[3]["raw_lat"] == "91.000000"
    assert got[0]["lat"] == "56.5000000"
