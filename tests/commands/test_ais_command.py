"""``seatrack ais`` end to end on the real data (one TRACKS.csv row per input row)."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ais_samples import data_file
from cli_inprocess import seatrack
from seatrack.cli import app


def test_ais_command_writes_every_row(tmp_path: Path) -> None:
    files = [
        data_file("dk_gothenburg_20170705_cpa.csv"),
        data_file("dk_northsea_20221101_1h_selected.csv"),
    ]
    out, gj, page = tmp_path / "TRACKS.csv", tmp_path / "t.geojson", tmp_path / "t.html"
    res = CliRunner().invoke(
        app, ["ais", *map(str, files), "--out", str(out), "--geojson", str(gj), "--html", str(page)]
    )
    assert res.exit_code == 0, res.output
    n_in = sum(len(list(csv.DictReader(f.open()))) for f in files)
    with out.open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == n_in
    for col in (
        "mmsi",
        "time_utc",
        "lat",
        "lon",
        "course_deg",
        "speed_kn",
        "turn_rate_dps",
        "std_pos_m",
        "outlier",
        "reject_reason",
        "time_offset_s",
    ):
        assert col in rows[0]
    # whole-second timestamp offsets estimated on the Danish file (about one report in
    # eight there), whole numbers in -2..2 on the used rows
    offs = [float(r["time_offset_s"]) for r in rows if r["time_offset_s"]]
    assert set(offs) <= {-2.0, -1.0, 0.0, 1.0, 2.0}
    assert 0.05 < sum(o != 0 for o in offs) / len(offs) < 0.3
    n_off = sum(o != 0 for o in offs)
    assert f"reports with a whole-second timestamp offset: {n_off} (" in res.output
    assert f"rows read: {n_in}" in res.output
    assert "duplicate report: 407" in res.output
    # vessels contiguous in order of first appearance; input order (file, line) within each
    seen: dict[str, int] = {}
    for r in rows:
        seen.setdefault(r["mmsi"], len(seen))
    src = {str(f): k for k, f in enumerate(files)}
    keys = [(seen[r["mmsi"]], src[r["source"]], int(r["line"])) for r in rows]
    assert keys == sorted(keys)
    used = [r for r in rows if not r["reject_reason"]]
    assert all(r["lat"] and r["course_deg"] for r in used if r["outlier"] == "0")
    assert all(r["lat"] == "" for r in rows if r["reject_reason"])
    g = json.loads(gj.read_text())
    assert {f["properties"]["mmsi"] for f in g["features"]} == {int(m) for m in seen}
    assert page.read_text().startswith("<!DOCTYPE html>")


def test_ais_command_user_error_is_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "x.csv"
    bad.write_text("a,b\n1,2\n")
    res = seatrack("ais", bad, "--out", tmp_path / "o.csv")
    assert res.returncode == 2
    assert res.stderr.startswith("error: ") and "x.csv" in res.stderr
    assert "Traceback" not in res.stderr


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return seatrack("ais", *args)


def _one_line_error(res: subprocess.CompletedProcess[str], *words: str) -> None:
    assert res.returncode == 2, res.stdout + res.stderr
    assert res.stderr.startswith("error: ") and res.stderr.count("\n") == 1, res.stderr
    assert "Traceback" not in res.stderr
    for w in words:
        assert w in res.stderr, res.stderr


HEAD = "mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg\n"


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--max-gap", "-1"),
        ("--max-gap", "nan"),
        ("--sigma-pos", "0"),
        ("--max-speed", "inf"),
        ("--max-accel", "-2"),
        ("--memory-limit", "lots"),
        ("--memory-limit", "1K"),
    ],
)
def test_options_are_checked_by_name(tmp_path: Path, option: str, value: str) -> None:
    f = tmp_path / "a.csv"
    f.write_text(HEAD + "1,2022-11-01T09:00:00Z,56.0,7.0,,,\n")
    out = tmp_path / "o.csv"
    _one_line_error(_run(str(f), "--out", str(out), option, value), option)
    assert not out.exists()


def test_bad_output_paths_fail_before_any_work(tmp_path: Path) -> None:
    f = tmp_path / "a.csv"
    f.write_text(HEAD + "1,2022-11-01T09:00:00Z,56.0,7.0,,,\n")
    out = tmp_path / "o.csv"
    blocker = tmp_path / "file"
    blocker.write_text("x")
    # the GeoJSON path is under a file: refused before TRACKS.csv is written
    _one_line_error(_run(str(f), "--out", str(out), "--geojson", str(blocker / "g.json")), "g.json")
    assert not out.exists()
    _one_line_error(_run(str(f), "--out", str(tmp_path)), "directory")
    _one_line_error(_run(str(f), "--out", str(out), "--html", str(out)), "different")


def test_failed_write_keeps_the_previous_output(tmp_path: Path) -> None:
    f = tmp_path / "a.csv"
    f.write_text(HEAD + "".join(f"1,2022-11-01T09:00:{s:02d}Z,56.0,7.0,,,\n" for s in range(50)))
    out = tmp_path / "o.csv"
    out.write_text("previous\n")
    code = (
        "import resource, sys; resource.setrlimit(resource.RLIMIT_FSIZE, (200, 200));"
        "from seatrack.cli import main; sys.argv = ['seatrack', 'ais', sys.argv[1], '--out',"
        " sys.argv[2]]; main()"
    )
    res = subprocess.run(
        [sys.executable, "-c", code, str(f), str(out)], capture_output=True, text=True, timeout=300
    )
    assert res.returncode != 0
    assert out.read_text() == "previous\n"
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".o.csv")] == []


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


def test_invalid_values_are_rejected_with_reasons(tmp_path: Path) -> None:
    """Issue 13 item 3: invalid MMSI and times are rejected, small anonymised MMSIs kept."""
    body = [
        "1,2022-11-01T09:00:00Z,56.0,7.0,,,",  # 2 anonymised MMSI: kept
        "202,2022-11-01T09:00:00Z,56.0,7.1,,,",  # 3 kept
        "1e30,2022-11-01T09:00:01Z,56.0,7.0,,,",  # 4
        "99999999999999999999,2022-11-01T09:00:02Z,56.0,7.0,,,",  # 5
        "12.5,2022-11-01T09:00:03Z,56.0,7.0,,,",  # 6
        "1000000000,2022-11-01T09:00:03Z,56.0,7.0,,,",  # 7 ten digits
        "1,1e308,56.0,7.0,,,",  # 8
        "1,1900-01-01T00:00:00Z,56.0,7.0,,,",  # 9
        "1,2101-01-01T00:00:00Z,56.0,7.0,,,",  # 10
        ",,,,,,",  # 11 empty cells
        "",  # 12 blank line
        "1,2022-11-01T09:00:04Z,56.0",  # 13 cut row
        "211000000,2022-11-01T09:00:05Z,56.0,7.2,,,",  # 14 ok
    ]
    f = tmp_path / "bad.csv"
    f.write_text(HEAD + "\n".join(body) + "\n")
    out = tmp_path / "o.csv"
    res = _run(str(f), "--out", str(out))
    assert res.returncode == 0, res.stderr
    got = {int(r["line"]): r["reject_reason"] for r in _rows(out)}
    assert got == {
        2: "",
        3: "",
        4: "invalid mmsi",
        5: "invalid mmsi",
        6: "invalid mmsi",
        7: "invalid mmsi",
        8: "time out of range",
        9: "time out of range",
        10: "time out of range",
        11: "empty row",
        12: "blank line",
        13: "wrong number of fields",
        14: "",
    }
    assert "NaT" not in out.read_text()
    assert "rows read: 13" in res.stdout


def _nmea(mmsi: int, lat: float, t: int) -> str:
    from pyais.encode import encode_dict

    s = encode_dict({"type": 1, "mmsi": mmsi, "lat": lat, "lon": 5.3}, sentence_type="VDM")[0]
    return f"{t} {s}"


def test_nmea_then_csv_and_foreign_lines_each_get_a_row(tmp_path: Path) -> None:
    nmea = [_nmea(257725000, 60.4 + 1e-4 * k, 1661990400 + k) for k in range(5)]
    cut = nmea[0][: len(nmea[0]) // 2]
    csv_rows = [f"211000001,2022-11-01T09:00:{s:02d}Z,56.0,7.{s:02d},,," for s in range(20)]
    lines = [*nmea, cut, "211000001,2022-11-01T09:00:00Z,56.0,7.0,,,", "", HEAD.strip(), *csv_rows]
    f = tmp_path / "mixed.log"
    f.write_bytes(("\n".join(lines) + "\n").encode())
    out = tmp_path / "o.csv"
    res = _run(str(f), "--out", str(out))
    assert res.returncode == 0, res.stderr
    rows = _rows(out)
    got = {int(r["line"]): r["reject_reason"] for r in rows}
    assert [got[k] for k in range(1, 6)] == [""] * 5
    assert got[6] == "truncated sentence"
    assert got[7] == "not an AIS line"  # a CSV row before any CSV header
    assert got[8] == "blank line"
    assert 9 not in got  # the CSV header (counted as skipped)
    assert [got[k] for k in range(10, 30)] == [""] * 20  # no valid report vanishes
    assert len(rows) + 1 == len(lines)
    assert "CSV header: 1" in res.stdout


def test_latin1_bytes_never_refuse_a_file(tmp_path: Path) -> None:
    head = b"mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg,shipname\n"
    body = b"".join(
        f"1,2022-11-01T09:00:{s:02d}Z,56.0,7.{s:02d},,,,".encode() + b"F\xf8rde\n"
        for s in range(10)
    )
    f = tmp_path / "latin1.csv"
    f.write_bytes(head + body + b"1,2022-11-01T09:00:\xf810Z,56.0,7.1,,,,x\n")
    out = tmp_path / "o.csv"
    res = _run(str(f), "--out", str(out))
    assert res.returncode == 0, res.stderr
    got = {int(r["line"]): r["reject_reason"] for r in _rows(out)}
    assert [got[k] for k in range(2, 12)] == [""] * 10
    assert got[12] == "unparsable time"


def test_dask_output_equals_one_process(tmp_path: Path) -> None:
    """--dask: every report of all files shuffled by MMSI; same TRACKS as one process."""
    from seatrack.io.ais import track_files
    from seatrack.io.ais.cluster import dask_client
    from seatrack.io.ais.cluster import track_files_dask

    files = split_file(data_file("dk_northsea_20221101_1h_selected.csv"), tmp_path, 3)
    one = track_files(files, tmp_path / "one.csv")
    track_files(files, tmp_path / "one.parquet")
    with dask_client(processes=False) as client:
        many = track_files_dask(files, tmp_path / "dask.csv", partitions=4, client=client)
        track_files_dask(files, tmp_path / "dask.parquet", partitions=4, client=client)
    assert (tmp_path / "dask.csv").read_bytes() == (tmp_path / "one.csv").read_bytes()
    assert one.lines() == many.lines()
    # partitioned Parquet: one file per partition, the same rows as one process
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    parts = sorted((tmp_path / "dask.parquet").iterdir())
    assert len(parts) == 5  # 4 MMSI partitions + the rows without an MMSI

    def by_line(t):  # noqa: ANN001, ANN202
        return t.take(pc.sort_indices(t, [("source", "ascending"), ("line", "ascending")]))

    a = by_line(pq.read_table(tmp_path / "one.parquet"))
    b = by_line(pq.read_table(tmp_path / "dask.parquet"))
    assert a.equals(b)
    # vessels cross the file boundaries
    rows = _rows(tmp_path / "one.csv")
    per_vessel: dict[str, set[str]] = {}
    for r in rows:
        per_vessel.setdefault(r["mmsi"], set()).add(r["source"])
    assert sum(len(v) == 3 for v in per_vessel.values()) >= 10


def split_file(src: Path, folder: Path, k: int) -> list[Path]:
    """``src`` cut into ``k`` CSV files of consecutive times, each with the header."""
    lines = src.read_text().splitlines(keepends=True)
    head = lines[0]
    col = head.strip().split(",").index("time_utc")
    body = sorted(lines[1:], key=lambda ln: ln.split(",")[col])
    size = -(-len(body) // k)
    out = []
    for j in range(k):
        p = folder / f"part{j}.csv"
        p.write_text(head + "".join(body[j * size : (j + 1) * size]))
        out.append(p)
    return out
