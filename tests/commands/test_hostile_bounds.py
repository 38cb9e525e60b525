"""Issue 26 (bounded work, all-or-nothing commands): the internal errors, size bombs, output
paths and suspicious inputs it lists, each run through the CLI (see hostile_inputs.py).

Every case must end in exit status 0 or 2 with one ``error:`` line naming the file or the
option, and without touching an earlier output.
"""

from __future__ import annotations

import csv
import errno
import gzip
import math
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hostile_inputs import assert_clean
from hostile_inputs import hostile_output
from hostile_inputs import run_cli
from hostile_inputs import snapshot
from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
from test_hostile_ais import CSV_TEXT
from test_hostile_ais import NMEA_TEXT
from test_hostile_navigate import nav_inputs
from test_hostile_simulate import SCENARIO
from test_hostile_tma import BEARINGS
from test_hostile_tma import bearings_text
from test_hostile_track import PLOTS

from seatrack.io.ais.nmea import nmea_checksum

FAST = ["--methods", "ekf", "--runs", "1", "--no-progress"]


def _sentence(payload: str, fill: int = 0) -> str:
    body = f"AIVDM,1,1,,A,{payload},{fill}"
    return f"!{body}*{nmea_checksum(body.encode()):02X}"


# ---------------------------------------------------------------------------
# section 3: internal errors
# ---------------------------------------------------------------------------
#: payloads too short for their message type (1, 1, 18, 3, 27, 19): decoded with None fields
SHORT_PAYLOADS = ["1", "13mi84", "B", "3", "K", "C0000"]


def test_short_ais_payloads_are_rejected_lines_and_the_log_kept(tmp_path):
    good = NMEA_TEXT.splitlines()
    bad = [f"2017-07-05T10:00:00Z {_sentence(p)}" for p in SHORT_PAYLOADS]
    log = tmp_path / "log.nmea"
    log.write_text("\n".join([good[0], *bad, *good[1:]]) + "\n")
    out = tmp_path / "tracks.csv"
    args = ["ais", log, "--out", out]
    r = run_cli(*args)
    assert_clean(r, {}, args)
    assert r.code == 0, r.err
    rows = list(csv.DictReader(out.open(newline="")))
    reasons = {int(row["line"]): row["reject_reason"] for row in rows}
    for k in range(len(bad)):  # lines 2..7, each rejected with its own line number
        assert reasons[2 + k] == "undecodable message"
    assert sum(1 for row in rows if not row["reject_reason"]) == len(good)


@pytest.mark.parametrize("key", ["range_m = 20.0", "azimuth_deg = 0.3"])
def test_a_tiny_sensor_sigma_is_refused_by_name(tmp_path, key):
    sc = tmp_path / "s.toml"
    sc.write_text(SCENARIO.replace(key, key.split("=")[0] + "= 1e-300"))
    assert SCENARIO != sc.read_text()
    for cmd in (["evaluate", sc, *FAST], ["simulate", sc, "--out", tmp_path / "sim"]):
        r = run_cli(*cmd)
        assert r.code == 2, r.err
        assert r.err.startswith(f"error: {sc}: sensors[0].sigma.{key.split()[0]}: must be >= 1e-06")


@pytest.mark.parametrize("runs", ["0", "-5"])
def test_evaluate_runs_is_checked_for_multitarget_scenarios(runs):
    r = run_cli("evaluate", "coastal_multitarget", "--runs", runs)
    assert r.code == 2 and r.err == f"error: --runs = {runs} must be in [1, 100000]\n"


def test_evaluate_processes_zero_is_refused():
    r = run_cli("evaluate", "coastal_multitarget", "--processes", "0", "--runs", "1")
    assert r.code == 2 and r.err.startswith("error: --processes = 0 must be in [1, ")


# ---------------------------------------------------------------------------
# section 2: outputs checked before the inputs are read, and replaced together
# ---------------------------------------------------------------------------
PREVIOUS = b"previous output\n"


def _unlabelled(d: Path) -> Path:
    """PLOTS.csv without the track column, in time order: ``seatrack track`` runs the
    multi-target tracker."""
    p = d / "unlabelled.csv"
    head, *body = [ln.split(",", 1)[1] for ln in PLOTS.splitlines()]
    body.sort(key=lambda ln: float(ln.split(",")[0]))
    p.write_text("".join(ln + "\n" for ln in [head, *body]))
    return p


def _previous(*paths: Path) -> dict[Path, bytes | None]:
    for p in paths:
        p.write_bytes(PREVIOUS)
    return snapshot(list(paths))


def _refused(args: list[object], before: dict[Path, bytes | None], *words: str) -> str:
    r = run_cli(*args)
    assert_clean(r, before, args)
    assert r.code == 2 and r.out == "", (r.out, r.err)  # refused before any work
    for w in words:
        assert w in r.err, r.err
    return r.err


@pytest.mark.parametrize("name", ["pic.xyz", "pic"])
def test_track_plot_without_a_picture_suffix_is_refused_first(tmp_path, name):
    plots, out = _unlabelled(tmp_path), tmp_path / "track.csv"
    before = _previous(out)
    pic = tmp_path / name
    _refused(["track", plots, "--out", out, "--plot", pic], before, f"--plot {pic}", ".png")
    assert not pic.exists()


def test_tma_plot_without_a_picture_suffix_is_refused_first(tmp_path):
    b = tmp_path / "b.csv"
    b.write_text(BEARINGS)
    out = tmp_path / "r.json"
    before = _previous(out)
    _refused(["tma", b, "--out", out, "--plot", tmp_path / "p.xyz"], before, "--plot")


def test_an_output_that_is_an_input_is_refused(tmp_path):
    plots = tmp_path / "plots.csv"
    plots.write_text(PLOTS)
    (tmp_path / "u").mkdir()
    unl = _unlabelled(tmp_path / "u")
    b = tmp_path / "b.csv"
    b.write_text(BEARINGS)
    ais = tmp_path / "ais.nmea"
    ais.write_text(NMEA_TEXT)
    sc = tmp_path / "s.toml"
    sc.write_text(SCENARIO)
    alias = tmp_path / "hard-link.csv"
    os.link(plots, alias)
    out = tmp_path / "out.csv"
    cases = [
        (["track", plots, "--out", plots], "--out", plots),
        (["track", plots, "--out", alias], "--out", plots),  # the same inode
        (["track", unl, "--out", out, "--plots-out", unl], "--plots-out", unl),
        (["track", unl, "--out", out, "--plots-out", out], "--plots-out", out),
        (["track", unl, "--out", out, "--plot", unl.with_suffix(".png"), "--plots-out", out],
         "--plots-out", out),
        (["tma", b, "--out", b], "--out", b),
        (["tma", b, "--out", out, "--plot", b], "--plot", b),
        (["ais", ais, "--out", ais], "--out", ais),
        (["ais", ais, "--out", out, "--html", ais], "--html", ais),
        (["evaluate", sc, *FAST, "--csv", sc], "--csv", sc),
    ]  # fmt: skip
    for args, opt, path in cases:
        inputs = [a for a in args if isinstance(a, Path) and a.exists()]
        before = snapshot(inputs)
        err = _refused(args, before, opt)
        assert "is the input file" in err or "the same file as" in err, err
        assert str(path) in err or str(alias) in err


def test_navigate_out_equal_to_the_echoes_is_refused(tmp_path):
    start = nav_inputs(tmp_path)
    ech = tmp_path / "echoes.csv"
    nav = ["--map", tmp_path / "map.csv", "--echoes", ech, "--start", start]
    before = snapshot([ech])
    _refused(["navigate", *nav, "--out", ech], before, "--out", "is the input file")


def test_a_device_node_or_pipe_is_not_replaced(tmp_path):
    plots = tmp_path / "plots.csv"
    plots.write_text(PLOTS)
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    _refused(["track", plots, "--out", fifo], {}, "--out", "not a regular file")
    assert stat.S_ISFIFO(fifo.lstat().st_mode)
    r = run_cli("track", plots, "--out", "/dev/null")
    assert r.code == 2 and "not a regular file" in r.err
    assert stat.S_ISCHR(os.lstat("/dev/null").st_mode)


def test_an_output_symlink_is_resolved_and_kept(tmp_path):
    plots = tmp_path / "plots.csv"
    plots.write_text(PLOTS)
    target, link = tmp_path / "real.csv", tmp_path / "link.csv"
    target.write_bytes(PREVIOUS)
    link.symlink_to(target)
    r = run_cli("track", plots, "--out", link)
    assert r.code == 0, r.err
    assert link.is_symlink() and target.read_bytes().startswith(b"track,time_s")


def test_a_name_without_room_for_the_temporary_is_refused_first(tmp_path):
    plots = tmp_path / "plots.csv"
    plots.write_text(PLOTS)
    out = tmp_path / ("x" * 250 + ".csv")  # a legal name of 254 characters
    _refused(["track", plots, "--out", out], {}, "--out", "file name too long")


def test_a_failure_on_the_last_output_keeps_every_previous_one(tmp_path, monkeypatch):
    """ais --out --html: the HTML does not fit on its disk -> TRACKS.csv not replaced."""
    import seatrack.report.html as html

    def full_disk(path, *args, **kwargs):
        Path(path).write_bytes(b"<html>")  # part of it, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(html, "write_html", full_disk)
    ais = tmp_path / "ais.nmea"
    ais.write_text(NMEA_TEXT)
    outs = [tmp_path / "tracks.csv", tmp_path / "map.geojson", tmp_path / "map.html"]
    before = _previous(*outs)
    args = ["ais", ais, "--out", outs[0], "--geojson", outs[1], "--html", outs[2]]
    r = run_cli(*args)
    assert_clean(r, before, args)
    assert r.code == 2 and "No space left on device" in r.err and str(outs[2]) in r.err


def _wait_for(pred, timeout_s: float) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.05)
    return False


def _big_ais_csv(path: Path, rows: int) -> None:
    head, *body = CSV_TEXT.splitlines()
    reps = rows // len(body) + 1
    with path.open("w") as fh:
        fh.write(head + "\n")
        for k in range(reps):  # the same reports under new MMSIs: many vessels
            for ln in body:
                cells = ln.split(",")
                cells[0] = str(200000000 + k)
                fh.write(",".join(cells) + "\n")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_ends_the_run_cleanly(tmp_path, sig):
    """A real process, signalled while it writes: one ``error: interrupted`` line, the
    previous output intact, no temporary beside it nor in the temporary folder."""
    src = tmp_path / "in"
    src.mkdir()
    ais = src / "ais.csv"
    _big_ais_csv(ais, 200_000)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    out = out_dir / "tracks.csv"
    out.write_bytes(PREVIOUS)
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    env = {**os.environ, "TMPDIR": str(tmpdir)}
    proc = subprocess.Popen(
        [sys.executable, "-c", "from seatrack.cli import main; main()", "ais", str(ais),
         "--out", str(out), "--memory-limit", "64M"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )  # fmt: skip
    try:
        started = _wait_for(lambda: any(tmpdir.iterdir()) and len(os.listdir(out_dir)) > 1, 60)
        assert started, "the run never started writing"
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert [ln for ln in err.splitlines() if ln.strip()] == ["error: interrupted"]
    assert out.read_bytes() == PREVIOUS
    assert os.listdir(out_dir) == ["tracks.csv"]
    assert os.listdir(tmpdir) == []


# ---------------------------------------------------------------------------
# section 4: bad input accepted or reported without its file
# ---------------------------------------------------------------------------
def _plots_with(d: Path, column: str, value: str, row: int = 5, labelled: bool = True) -> Path:
    lines = PLOTS.splitlines()
    header = lines[0].split(",")
    cells = lines[row].split(",")
    cells[header.index(column)] = value
    lines[row] = ",".join(cells)
    if not labelled:
        lines = [ln.split(",", 1)[1] for ln in lines]
        lines[1:] = sorted(lines[1:], key=lambda ln: float(ln.split(",")[0]))
    p = d / ("plots.csv" if labelled else "unlabelled.csv")
    p.write_text("\n".join(lines) + "\n")
    return p


@pytest.mark.parametrize("labelled", [True, False])
@pytest.mark.parametrize(
    ("column", "value", "words"),
    [
        ("range_m", "1e300", "range_m = 1e+300 is implausible"),
        ("range_m", "1e-320", "range_m = 9.99989e-321 is implausible"),
        ("time_s", "1e300", "time_s = 1e+300"),
    ],
)
def test_plot_values_beyond_the_limits_are_refused_with_file_and_line(
    tmp_path, labelled, column, value, words
):
    p = _plots_with(tmp_path, column, value, labelled=labelled)
    out = tmp_path / "t.csv"
    before = _previous(out)
    r = run_cli("track", p, "--out", out)
    assert_clean(r, before, ["track", p, "--out", out])
    assert r.code == 2 and r.err.startswith(f"error: {p}, line ") and words in r.err, r.err


def test_a_1e9_s_gap_in_unlabelled_plots_is_refused(tmp_path):
    lines = [ln.split(",", 1)[1] for ln in PLOTS.splitlines()]
    body = sorted(lines[1:], key=lambda ln: float(ln.split(",")[0]))
    last = body[-1].split(",")
    last[0] = str(float(last[0]) + 1e9)
    p = tmp_path / "unlabelled.csv"
    p.write_text("\n".join([lines[0], *body, ",".join(last)]) + "\n")
    r = run_cli("track", p, "--out", tmp_path / "t.csv")
    assert r.code == 2 and f"line {len(body) + 2}: time gap" in r.err, r.err


def test_a_duplicated_column_name_is_refused(tmp_path):
    lines = PLOTS.splitlines()
    for labelled in (True, False):
        rows = [ln + ",5" for ln in lines]
        rows[0] = lines[0] + ",range_m"
        if not labelled:
            rows = [ln.split(",", 1)[1] for ln in rows]
        p = tmp_path / f"dup{labelled}.csv"
        p.write_text("\n".join(rows) + "\n")
        r = run_cli("track", p, "--out", tmp_path / "t.csv")
        assert r.code == 2, r.err
        assert r.err == f"error: {p}, line 1: column range_m appears more than once in the header\n"


def test_a_csv_that_is_really_gzip_is_read_as_gzip(tmp_path):
    plain, packed = tmp_path / "plain.csv", tmp_path / "packed.csv"
    plain.write_text(PLOTS)
    packed.write_bytes(gzip.compress(PLOTS.encode()))
    r1 = run_cli("track", plain, "--out", tmp_path / "a.csv")
    r2 = run_cli("track", packed, "--out", tmp_path / "b.csv")
    assert r1.code == r2.code == 0, r2.err
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


@pytest.mark.parametrize("kind", ["truncated", "corrupt"])
def test_a_bad_compressed_input_is_named_not_the_output(tmp_path, kind):
    data = gzip.compress(CSV_TEXT.encode() * 50)
    if kind == "truncated":
        data = data[: len(data) // 2]
    else:
        data = data[:40] + bytes(200) + data[240:]
    src = tmp_path / "ais.csv.gz"
    src.write_bytes(data)
    out = tmp_path / "tracks.csv"
    before = _previous(out)
    args = ["ais", src, "--out", out]
    r = run_cli(*args)
    assert_clean(r, before, args)
    assert r.code == 2 and r.err.startswith(f"error: {src}: not valid gzip data"), r.err


@pytest.mark.parametrize("value", ["1e-300", "4e-320"])
def test_a_tiny_bearing_sigma_is_refused_by_name(tmp_path, value):
    b = tmp_path / "b.csv"
    b.write_text(BEARINGS)
    r = run_cli("tma", b, "--sigma-deg", value)
    assert r.code == 2 and r.err.startswith("error: --sigma-deg must be a number of degrees in")
    lines = BEARINGS.splitlines()
    cells = lines[3].split(",")
    cells[-1] = value
    lines[3] = ",".join(cells)
    b.write_text("\n".join(lines) + "\n")
    r = run_cli("tma", b)
    assert r.code == 2 and r.err.startswith(f"error: {b}, line 4: sigma_deg = "), r.err


@pytest.mark.parametrize("text", ["", ",,,", " , "])
def test_manoeuvres_without_a_time_are_refused(tmp_path, text):
    b = tmp_path / "b.csv"
    b.write_text(BEARINGS)
    r = run_cli("tma", b, "--manoeuvres", text)
    assert r.code == 2 and r.err.startswith("error: --manoeuvres: no time in"), r.err


# ---------------------------------------------------------------------------
# section 5: plausible but suspicious units are warned about, by column
# ---------------------------------------------------------------------------
def _convert(text: str, column: str, f) -> str:
    lines = text.splitlines()
    j = lines[0].split(",").index(column)
    out = [lines[0]]
    for ln in lines[1:]:
        cells = ln.split(",")
        cells[j] = repr(f(float(cells[j])))
        out.append(",".join(cells))
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("labelled", [True, False])
@pytest.mark.parametrize(
    ("column", "f", "words"),
    [
        ("azimuth_deg", math.radians, "azimuth_deg is between"),
        ("range_m", lambda r: r / 1000, "range_m is below 100: it looks like kilometres"),
        ("time_s", lambda t: t * 1000, "time_s values are a median 2000 s apart"),
    ],
)
def test_suspicious_plot_units_are_warned_about(tmp_path, labelled, column, f, words):
    text = PLOTS if labelled else _unlabelled(tmp_path).read_text()
    p = tmp_path / "plots.csv"
    p.write_text(_convert(text, column, f))
    r = run_cli("track", p, "--out", tmp_path / "t.csv")
    assert r.code == 0, r.err
    lines = r.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"warning: {p}: ") and words in lines[0]
    p.write_text(text)
    r = run_cli("track", p, "--out", tmp_path / "t.csv")
    assert r.code == 0 and r.err == ""


def test_tma_times_in_milliseconds_are_warned_about(tmp_path):
    b = tmp_path / "b.csv"
    b.write_text(_convert(bearings_text(1), "time_s", lambda t: t * 1000))  # 60 s -> 60000
    r = run_cli("tma", b, "--no-detect")
    assert r.code == 0, r.err
    assert r.err.startswith(f"warning: {b}: consecutive time_s values are a median ")


# ---------------------------------------------------------------------------
# property tests: hostile output paths for every command with an --out file
# ---------------------------------------------------------------------------
#: kinds that must be refused before any work
REFUSED = {"input", "hard_link", "folder", "under_file", "fifo", "device", "long_name"}


@settings(max_examples=40, deadline=None)
@given(data=st.data(), cmd=st.sampled_from(["track", "tma", "ais"]))
def test_hostile_output_paths(tmp_path_factory, data, cmd):
    d = tmp_path_factory.mktemp("outpath")
    text = {"track": PLOTS, "tma": BEARINGS, "ais": NMEA_TEXT}[cmd]
    inp = d / "input.csv"
    inp.write_text(text)
    kind, out = data.draw(hostile_output(d, [inp]))
    extra = ["--no-detect"] if cmd == "tma" else []
    args: list[object] = [cmd, inp, "--out", out, *extra]
    watched = [inp] + ([out] if out.is_file() and out.parent != Path("/dev") else [])
    before = snapshot(watched)
    r = run_cli(*args)
    assert_clean(r, before, args)
    assert inp.read_text() == text, f"{kind}: the input was changed"
    if kind in REFUSED:
        assert r.code == 2 and "--out" in r.err, (kind, r.err)
    if kind == "symlink":
        assert out.is_symlink()
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)


def test_evaluate_skip_is_checked_for_multitarget_scenarios():
    r = run_cli("evaluate", "coastal_multitarget", "--runs", "1", "--skip", "100000")
    assert r.code == 2 and r.err.startswith("error: --skip = 100000 must be in [0, 80]"), r.err


SIZES = ["1.5G", "64M", "10", "", "lots", "-1G", "1e400", "nan", "4G", "100M", "1T"]
DURATIONS = ["1h", "90s", "0", "-5", "", "soon", "1e-9", "30min", "2d"]


@settings(max_examples=30, deadline=None)
@given(memory=st.sampled_from(SIZES), time_limit=st.sampled_from(DURATIONS))
def test_budget_options(tmp_path_factory, memory, time_limit):
    """``seatrack --memory-limit M --time-limit T track ...``: a run or one line naming the
    option (or the budget the run is over)."""
    d = tmp_path_factory.mktemp("budget")
    plots, out = d / "plots.csv", d / "t.csv"
    plots.write_text(PLOTS)
    before = _previous(out)
    args = ["--memory-limit", memory, "--time-limit", time_limit, "track", plots, "--out", out]
    r = run_cli(*args)
    assert_clean(r, before, args)
    if r.code == 2:
        assert r.err.startswith(("error: --memory-limit: ", "error: --time-limit: ")) or (
            "over the budget" in r.err
        ), r.err
