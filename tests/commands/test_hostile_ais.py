"""Hostile inputs for `seatrack ais` (see hostile_inputs.py).

The command and its readers belong to another work package; these tests state the contract
every command meets (exit status 0 or 2, one error line, previous outputs intact, no
temporary left) and the AIS accounting of issue 13: every input line is a TRACKS.csv row or
is counted in the summary.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import pytest
from hostile_inputs import assert_clean
from hostile_inputs import mutated_csv
from hostile_inputs import mutated_text
from hostile_inputs import plain
from hostile_inputs import run_cli
from hostile_inputs import snapshot
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
from pyais.encode import encode_dict

from ais_samples import data_file
from seatrack.io.ais import format_times
from seatrack.io.ais import read_ais_csv
from seatrack.io.ais.columnar import detect_schema
from seatrack.io.table import InputError
from seatrack.io.table import decode_text

SAMPLE = data_file("dk_gothenburg_20170705_cpa.csv")
CSV_TEXT = "".join(SAMPLE.read_text().splitlines(keepends=True)[:41])


def nmea_text(n: int = 30) -> str:
    """The first ``n`` rows of the sample as timestamped !AIVDM lines."""
    p = SAMPLE
    r = read_ais_csv(p)
    lines = []
    for i, ts in enumerate(format_times(r.t[:n])):
        data = {"type": 1, "mmsi": int(r.mmsi[i]), "lat": float(r.lat[i]),
                "lon": float(r.lon[i]), "speed": float(r.sog_kn[i]),
                "course": float(r.cog_deg[i])}  # fmt: skip
        (s,) = encode_dict(data, talker_id="AI", sentence_type="VDM", radio_channel="A")
        lines.append(f"{ts} {s}")
    return "\n".join(lines) + "\n"


NMEA_TEXT = nmea_text()


def _records(data: bytes, nmea: bool) -> int:
    """Input records as the reader accounts for them: every physical line (universal line
    ends: LF, CRLF, CR, as the reader and Python's text files), less a CSV file's first
    line when it is a header of a known schema. A quote never joins two lines: a CSV file
    that is not one row per line is read line by line (docs/ais.md), so a stray ``"``
    cell leaves every later line a row of its own."""
    text, _ = decode_text(plain(data))
    lines = io.StringIO(text, newline=None).readlines()
    if nmea or not lines:
        return len(lines)
    first = next(csv.reader([lines[0].rstrip("\r\n")]), [])
    try:
        detect_schema([f.strip() for f in first])
    except InputError:
        return len(lines)  # no header: the first line is a row (rejected) too
    return len(lines) - 1


def _run(d: Path, data: bytes, name: str, *extra: object) -> tuple[int, int, int]:
    """Run on one input; returns (exit status, TRACKS.csv rows, lines counted as skipped)."""
    p = d / name
    p.write_bytes(data)
    outs = [d / "tracks.csv", d / "t.geojson", d / "t.html"]
    for o in outs:
        o.write_bytes(b"previous\n")
    args: list[object] = ["ais", p, "--out", outs[0], "--geojson", outs[1], "--html", outs[2],
                          *extra]  # fmt: skip
    before = snapshot(outs)
    res = run_cli(*args)
    assert_clean(res, before, args)
    if res.code != 0:
        return res.code, 0, 0
    with outs[0].open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    m = re.search(r"lines that are not position reports: (\d+)", res.out)
    return 0, len(rows), int(m.group(1)) if m else 0


@settings(max_examples=70, deadline=None)
@given(data=st.data())
def test_mutated_csv(tmp_path_factory, data):
    _run(tmp_path_factory.mktemp("ais"), data.draw(mutated_csv(CSV_TEXT)), "a.csv")


@settings(max_examples=50, deadline=None)
@given(data=st.data())
def test_mutated_nmea(tmp_path_factory, data):
    _run(tmp_path_factory.mktemp("nmea"), data.draw(mutated_text(NMEA_TEXT)), "a.nmea")


@settings(max_examples=40, deadline=None)
@given(
    option=st.sampled_from(["--sigma-pos", "--max-gap", "--max-speed", "--max-accel"]),
    value=st.sampled_from(["nan", "inf", "-1", "0", "1e308", "abc", "", "5"]),
)
def test_options(tmp_path_factory, option, value):
    _run(tmp_path_factory.mktemp("aisopt"), CSV_TEXT.encode(), "a.csv", option, value)


@settings(max_examples=60, deadline=None)
@given(data=st.data(), nmea=st.booleans())
def test_every_input_line_is_accounted_for(tmp_path_factory, data, nmea):
    raw = data.draw(mutated_text(NMEA_TEXT) if nmea else mutated_csv(CSV_TEXT))
    code, rows, skipped = _run(tmp_path_factory.mktemp("acc"), raw, "a.nmea" if nmea else "a.csv")
    if code == 0:
        assert rows + skipped == _records(raw, nmea)


@pytest.mark.parametrize("padded", ["mmsi ", " lon"])
def test_padded_column_names_read_as_the_plain_ones(tmp_path, padded):
    """A header name with white space around it (``mmsi ,``): the same rows as without (it
    was an internal error: pyarrow selects columns by their exact names)."""
    text = CSV_TEXT.encode()
    bad = CSV_TEXT.replace(padded.strip() + ",", padded + ",", 1).encode()
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    assert _run(tmp_path / "a", text, "a.csv") == _run(tmp_path / "b", bad, "a.csv")
    assert _run(tmp_path / "a", text, "a.csv")[1] == _records(text, False)


@pytest.mark.parametrize("nmea", [False, True])
@pytest.mark.parametrize("end", [b"\r\n", b"\r"])
def test_old_line_ends_read_as_lines(tmp_path, nmea, end):
    """CRLF and the old Mac CR alone: every line a report, as with LF (a CR-only NMEA log
    was read as one line holding every sentence, and only its first report kept)."""
    text = (NMEA_TEXT if nmea else CSV_TEXT).encode()
    name = "a.nmea" if nmea else "a.csv"
    (tmp_path / "lf").mkdir()
    (tmp_path / "end").mkdir()
    base = _run(tmp_path / "lf", text, name)
    other = _run(tmp_path / "end", text.replace(b"\n", end), name)
    assert base == other == (0, _records(text, nmea), 0)


@pytest.mark.parametrize(
    ("case", "nmea"),
    [
        ("blank", False),
        ("empty_cells", False),
        ("garbage", False),
        ("blank", True),
        ("cut", True),
        ("csv_line", True),
    ],  # fmt: skip
)
def test_item_3_lines_are_accounted_for(tmp_path, case, nmea):
    """The lines issue 13 item 3 found unaccounted: blank lines, rows of empty cells,
    foreign lines, sentences cut mid-payload, CSV lines inside an NMEA file."""
    lines = (NMEA_TEXT if nmea else CSV_TEXT).splitlines()
    extra = {"blank": "", "empty_cells": ",,,,,,", "garbage": "garbage line",
             "cut": lines[2][:30], "csv_line": CSV_TEXT.splitlines()[1]}[case]  # fmt: skip
    lines.insert(4, extra)
    raw = ("\n".join(lines) + "\n").encode()
    code, rows, skipped = _run(tmp_path, raw, "a.nmea" if nmea else "a.csv")
    assert code == 0 and rows + skipped == _records(raw, nmea), (rows, skipped)


@pytest.mark.parametrize(
    ("column", "value"),
    [("mmsi", "1e30"), ("mmsi", "99999999999999999999"), ("time_utc", "1e308")],  # fmt: skip
)
def test_invalid_values_are_rejected_with_a_reason(tmp_path, column, value):
    lines = CSV_TEXT.splitlines()
    head = lines[0].split(",")
    cells = lines[3].split(",")
    cells[head.index(column)] = value
    lines[3] = ",".join(cells)
    (tmp_path / "a.csv").write_text("\n".join(lines) + "\n")
    out = tmp_path / "t.csv"
    r = run_cli("ais", tmp_path / "a.csv", "--out", out)
    assert r.code == 0, r.err
    rows = list(csv.DictReader(out.open()))
    bad = [row for row in rows if row["line"] == "4"]
    assert len(bad) == 1 and bad[0]["reject_reason"], bad


@pytest.mark.parametrize("option", ["--out", "--geojson", "--html"])
def test_bad_output_path_fails_before_any_work(tmp_path, option):
    f = tmp_path / "f"
    f.write_text("x")
    a = tmp_path / "a.csv"
    a.write_text(CSV_TEXT)
    args = {"--out": tmp_path / "t.csv", "--geojson": None, "--html": None}
    args[option] = f / "x"
    flat = [x for k, v in args.items() if v is not None for x in (k, v)]
    r = run_cli("ais", a, *flat)
    assert r.code == 2 and r.err.startswith("error: ") and "Traceback" not in r.err
    assert not (tmp_path / "t.csv").exists()  # TRACKS.csv not written before the failure
