"""``seatrack ais`` end to end on the real data (one TRACKS.csv row per input row)."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

from typer.testing import CliRunner

from ais_samples import data_file
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
    res = subprocess.run(
        [sys.executable, "-m", "seatrack.cli", "ais", str(bad), "--out", str(tmp_path / "o.csv")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 2
    assert res.stderr.startswith("error: ") and "x.csv" in res.stderr
    assert "Traceback" not in res.stderr


def test_dask_path_equals_per_file_in_process() -> None:
    try:
        import dask  # noqa: F401
    except ImportError:
        raise AssertionError(
            "the optional Dask path needs dask: pip install 'seatrack[dask]' (CI installs it)"
        ) from None
    import numpy as np

    from seatrack.commands.ais import track_files

    files = [
        data_file("dk_gothenburg_20170705_cpa.csv"),
        data_file("us_boston_201401_trajectools.csv"),
    ]
    rep, tr = track_files(files, use_dask=True)
    start = 0
    segs = []
    for f in files:
        r1, t1 = track_files([f])
        n = len(r1)
        assert np.array_equal(rep.t[start : start + n], r1.t)
        assert np.array_equal(tr.lat[start : start + n], t1.lat, equal_nan=True)
        assert np.array_equal(tr.outlier[start : start + n], t1.outlier)
        segs.append(set(tr.segment[start : start + n][tr.segment[start : start + n] >= 0]))
        start += n
    assert start == len(rep)
    assert not segs[0] & segs[1]  # segment ids stay unique across files
