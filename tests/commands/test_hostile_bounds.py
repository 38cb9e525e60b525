"""Issue 26 (bounded work, all-or-nothing commands): the internal errors, size bombs, output
paths and suspicious inputs it lists, each run through the CLI (see hostile_inputs.py).

Every case must end in exit status 0 or 2 with one ``error:`` line naming the file or the
option, and without touching an earlier output.
"""

from __future__ import annotations

import csv
import errno
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hostile_inputs import assert_clean
from hostile_inputs import run_cli
from hostile_inputs import snapshot
from test_hostile_ais import CSV_TEXT
from test_hostile_ais import NMEA_TEXT
from test_hostile_navigate import nav_inputs
from test_hostile_simulate import SCENARIO
from test_hostile_tma import BEARINGS
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
    """PLOTS.csv without the track column: ``seatrack track`` runs the multi-target tracker."""
    p = d / "plots.csv"
    p.write_text("".join(ln.split(",", 1)[1] + "\n" for ln in PLOTS.splitlines()))
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
