"""Columnar AIS readers: DMA (26 columns, dd/mm/yyyy) and NOAA layouts, compressed CSV and
Parquet read the same values and line numbers as the common schema; files that are not one
row per line fall back to the line reader with every line accounted for."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from ais_samples import data_file
from seatrack.io.ais import read_ais_csv
from seatrack.io.ais.columnar import NotColumnar
from seatrack.io.ais.columnar import iter_csv_blocks
from seatrack.io.table import InputError

DMA_HEAD = (
    "# Timestamp,Type of mobile,MMSI,Latitude,Longitude,Navigational status,ROT,SOG,COG,"
    "Heading,IMO,Callsign,Name,Ship type,Cargo type,Width,Length,"
    "Type of position fixing device,Draught,Destination,ETA,Data source type,A,B,C,D"
)


def _common(n: int = 300) -> tuple[Path, list[list[str]]]:
    """The first ``n`` rows of the Vestland file as cells."""
    lines = data_file("no_vestland_20220901.csv").read_text().splitlines()
    return data_file("no_vestland_20220901.csv"), [ln.split(",") for ln in lines[1 : n + 1]]


def _dma_line(c: list[str]) -> str:
    iso = c[1].rstrip("Z")
    date, clock = iso.split("T")
    y, m, d = date.split("-")
    cells = [f"{d}/{m}/{y} {clock}", "Class A", c[0], c[2], c[3], "Under way", "0.0"]
    cells += [c[4], c[5], c[6], "Unknown", "LAXX", "SKIB, DEN", "Cargo", "", "20", "100"]
    cells += ["GPS", "6.1", "BERGEN", "01/09/2022 12:00:00", "AIS", "1", "2", "3", "4"]
    return ",".join(f'"{x}"' if "," in x else x for x in cells)


def _check_same(r, ref, n: int) -> None:
    assert len(r) == n
    assert np.array_equal(r.line, np.arange(2, n + 2))
    for f in ("mmsi", "t", "lat", "lon", "sog_kn", "cog_deg", "heading_deg"):
        assert np.array_equal(getattr(r, f), getattr(ref, f)[:n], equal_nan=True), f
    assert r.reject.tolist() == ref.reject[:n].tolist()


def test_dma_gzip_zstd_and_parquet_read_the_same_values(tmp_path: Path) -> None:
    _, cells = _common()
    n = len(cells)
    ref = read_ais_csv(data_file("no_vestland_20220901.csv"))
    text = DMA_HEAD + "\n" + "\n".join(_dma_line(c) for c in cells) + "\n"
    dma = tmp_path / "aisdk.csv"
    dma.write_text(text)
    _check_same(read_ais_csv(dma), ref, n)
    gz = tmp_path / "aisdk.csv.gz"
    gz.write_bytes(gzip.compress(text.encode()))
    _check_same(read_ais_csv(gz), ref, n)
    zst = tmp_path / "aisdk.csv.zst"
    with pa.output_stream(str(zst), compression="zstd") as fh:
        fh.write(text.encode())
    _check_same(read_ais_csv(zst), ref, n)
    noaa = tmp_path / "noaa.csv"
    noaa.write_text(
        "MMSI,BaseDateTime,LAT,LON,SOG,COG,Heading,VesselName\n"
        + "\n".join(
            f"{c[0]},{c[1].rstrip('Z')},{c[2]},{c[3]},{c[4]},{c[5]},{c[6]},X" for c in cells
        )
        + "\n"
    )
    _check_same(read_ais_csv(noaa), ref, n)
    table = pa.table(
        {
            "mmsi": pa.array([int(c[0]) for c in cells]),
            "time_utc": pa.array([c[1] for c in cells]),
            "lat": pa.array([float(c[2]) for c in cells]),
            "lon": pa.array([float(c[3]) for c in cells]),
            "sog_kn": pa.array([float(c[4]) if c[4] else None for c in cells], pa.float64()),
            "cog_deg": pa.array([float(c[5]) if c[5] else None for c in cells], pa.float64()),
            "heading_deg": pa.array([float(c[6]) if c[6] else None for c in cells], pa.float64()),
        }
    )
    par = tmp_path / "in.parquet"
    pq.write_table(table, par)
    _check_same(read_ais_csv(par), ref, n)


def test_not_one_row_per_line_is_detected(tmp_path: Path) -> None:
    p = tmp_path / "blank.csv"
    p.write_text(
        "mmsi,time_utc,lat,lon\n1,2022-11-01T09:00:00Z,56,7\n\n1,2022-11-01T09:00:01Z,56,7\n"
    )
    with pytest.raises(NotColumnar):
        list(iter_csv_blocks(p))
    r = read_ais_csv(p)  # the line reader: the blank line gets its row
    assert r.line.tolist() == [2, 3, 4]
    assert r.reject.tolist() == ["", "blank line", ""]


def test_a_bad_number_reads_the_file_as_text_with_reasons(tmp_path: Path) -> None:
    p = tmp_path / "text.csv"
    p.write_text(
        "mmsi,time_utc,lat,lon,sog_kn\n"
        "1,2022-11-01T09:00:00Z,56,7,abc\n"
        "1,2022-11-01T09:00:01Z,north,7,1\n"
        "x1,2022-11-01T09:00:02Z,56,7,1\n"
        "2,2022-11-01T09:00:02.5Z,56,7,1\n"
    )
    r = read_ais_csv(p)
    assert r.reject.tolist() == ["", "position not a number", "invalid mmsi", ""]
    assert np.isnan(r.sog_kn[0])
    assert r.t[3] == pytest.approx(1667293202.5)


def test_binary_file_is_refused_with_a_printable_header(tmp_path):
    p = tmp_path / "x.csv"
    p.write_bytes(b"\x7fELF\x02\x01\x01\x00\x00\x1b[31m,\x00\x01\n" + bytes(range(256)))
    with pytest.raises(InputError, match="not a recognised AIS CSV header") as ei:
        read_ais_csv(p)
    assert str(ei.value).isprintable()


@pytest.mark.parametrize("column", [0, 2])  # mmsi, lat
def test_a_very_long_cell_is_one_rejected_row_not_a_wide_copy_of_every_row(tmp_path, column):
    """A 300,000-character text cell: its row is rejected with its line, the others read as
    without it, and the cells are held as objects (it took 24 GB as fixed-width text)."""
    from seatrack.io.ais.columnar import TOO_LONG
    from seatrack.io.ais.columnar import bounded_cell
    from seatrack.io.ais.read import read_file

    src = data_file("no_vestland_20220901.csv").read_text().splitlines()[:201]
    cells = src[50].split(",")
    cells[column] = "x" * 300_000
    bad = tmp_path / "long.csv"
    bad.write_text("\n".join([*src[:50], ",".join(cells), *src[51:]]) + "\n")
    good = tmp_path / "good.csv"
    good.write_text("\n".join(src) + "\n")
    r, ref = read_file(bad), read_file(good)
    assert len(r) == len(ref) == 200
    row = int(np.flatnonzero(r.line == 51)[0])
    assert r.code[row] != 0 and ref.code[row] == 0  # the long cell's row is rejected
    keep = np.arange(len(r)) != row
    np.testing.assert_array_equal(r.mmsi[keep], ref.mmsi[keep])
    np.testing.assert_array_equal(r.lat[keep], ref.lat[keep])
    assert bounded_cell("x" * 101) == TOO_LONG and bounded_cell("x" * 100) == "x" * 100
