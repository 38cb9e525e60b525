"""The DuckDB store: every report and track point committed, restart from the store
(in-process and after SIGKILL of a real ``seatrack live`` process), clean SIGTERM."""

from __future__ import annotations

import asyncio
import json
import os
import select
import signal
import subprocess
import sys
import threading
import time
import urllib.request

import duckdb
import numpy as np

from cli_inprocess import seatrack
from live.streams import plot_csv
from live.streams import radar_scans
from live.streams import started
from live.streams import synthetic
from live.streams import udp_send
from live.streams import wait_for
from seatrack.io.radar import parse_radar_config
from seatrack.live.nmea import encode_report
from seatrack.live.process import LiveOptions
from seatrack.live.sources import Source

SETUP = parse_radar_config(
    {"lat_deg": 57.7, "lon_deg": 11.85, "sigma_range_m": 15.0, "sigma_azimuth_deg": 0.3,
     "scan_period_s": 1.0, "scan_timeout_s": 5.0}
)  # fmt: skip


def ais_lines(seed: int = 7):
    r = synthetic(seed=seed, vessels=5, reports=30)
    lines = []
    for k in range(len(r)):
        lines += encode_report(r.mmsi[k], r.t[k], r.lat[k], r.lon[k], r.sog_kn[k], r.cog_deg[k])
    return lines


async def feed(proc, lines, scans):
    ais_port, plot_port = proc.udp_ports
    for k in range(0, len(lines), 10):
        udp_send(ais_port, [b"\n".join(lines[k : k + 10])])
        await asyncio.sleep(0.001)
    for sc in scans:
        udp_send(plot_port, ["\n".join(plot_csv([sc])).encode()])
        await asyncio.sleep(0.002)
    n_plots = sum(s[0].size for s in scans)
    await wait_for(lambda: proc.counters.received >= len(lines)
                   and proc.counters.plots_received >= n_plots)  # fmt: skip
    await proc.drain()


def options(store):
    udp = Source("udp", "127.0.0.1", 0)
    return LiveOptions(ais=[udp], plots=[udp], radar=SETUP, store=store, commit_s=0.1)


def picture(proc):
    ids, tr, _ = proc.ais.tracks()
    ais = {m: (tr.lat[k], tr.lon[k], tr.speed[k], tr.course[k]) for k, m in enumerate(ids)}
    views = proc.radar.current if proc.radar is not None else []
    radar = {v.track_id: (v.lat, v.lon, v.speed) for v in views}
    return ais, radar


def test_restart_from_the_store_carries_on_as_without_a_stop(tmp_path):
    lines = ais_lines()
    scans = radar_scans(seed=8, scans=16)
    half, sh = len(lines) // 2, 8

    async def whole():
        proc = await started(options(None))
        await feed(proc, lines, scans)
        await proc.stop()
        return picture(proc), proc.counters

    async def in_two(path):
        proc = await started(options(path))
        await feed(proc, lines[:half], scans[:sh])
        await proc.stop()  # the last commit
        rows = duckdb.connect(str(path), read_only=True).execute(
            "SELECT (SELECT count(*) FROM ais_reports), (SELECT count(*) FROM ais_track_points),"
            " (SELECT count(*) FROM radar_plots), (SELECT count(*) FROM radar_track_points),"
            " (SELECT count(*) FROM ais_vessel_state)").fetchone()  # fmt: skip
        proc2 = await started(options(path))
        restored = proc2.restored
        first = picture(proc2)
        await feed(proc2, lines[half:], scans[sh:])
        await proc2.stop()
        return rows, restored, first, picture(proc2), proc2.counters, picture(proc)

    want, cnt_whole = asyncio.run(asyncio.wait_for(whole(), 20))
    rows, restored, first, got, cnt, before = asyncio.run(
        asyncio.wait_for(in_two(tmp_path / "live.duckdb"), 30)
    )
    assert rows[0] == half and rows[1] >= half  # every report, every estimate
    assert rows[2] == sum(s[0].size for s in scans[:sh]) and rows[3] > 0 and rows[4] == 5
    assert restored == 5 + len(before[1])
    for m, v in before[0].items():  # the restarted picture is the committed one
        np.testing.assert_allclose(first[0][m], v, rtol=0, atol=1e-9)
    assert first[1] == before[1]
    assert got[0].keys() == want[0].keys() and got[1].keys() == want[1].keys()
    for m in want[0]:
        np.testing.assert_allclose(got[0][m], want[0][m], rtol=0, atol=1e-9)
    for i in want[1]:
        np.testing.assert_allclose(got[1][i], want[1][i], rtol=0, atol=1e-9)
    assert (cnt.received, cnt.decoded, cnt.scans) == (
        cnt_whole.received,
        cnt_whole.decoded,
        cnt_whole.scans,
    )
    assert cnt.check()


# ---- a real process --------------------------------------------------------------------
def launch(store, *extra):
    cmd = [
        sys.executable,
        "-c",
        "from seatrack.cli import main; main()",
        "live",
        "--ais",
        "udp://127.0.0.1:0",
        "--http",
        "127.0.0.1:0",
        "--store",
        str(store),
        *extra,
    ]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    info = {}
    deadline = time.monotonic() + 60
    while "map" not in info:
        assert time.monotonic() < deadline, "seatrack live did not start"
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        if not ready:
            assert proc.poll() is None, proc.stderr.read()
            continue
        line = proc.stdout.readline()
        if line.startswith("store "):
            info["restored"] = int(line.split(": ")[1].split()[0])
        elif line.startswith("ais: reading udp://"):
            info["port"] = int(line.rsplit(":", 1)[1])
        elif line.startswith("map at "):
            info["map"] = line.split()[-1].rstrip("/")
    return proc, info


def get(url):
    with urllib.request.urlopen(url, timeout=5) as r:
        return json.loads(r.read())


def poll(cond, timeout=10.0):
    t0 = time.monotonic()
    while not cond():
        assert time.monotonic() - t0 < timeout, "condition not met in time"
        time.sleep(0.05)


def test_sigkill_loses_nothing_committed(tmp_path):
    """A real ``seatrack live`` killed with SIGKILL: every committed report is in the
    store, and a process started on it has the same picture and carries on as one that
    was never stopped."""
    store = tmp_path / "live.duckdb"
    lines = ais_lines(seed=9)
    half = len(lines) // 2
    p, info = launch(store)
    try:
        udp_send(info["port"], lines[:half])
        poll(lambda: get(info["map"] + "/api/health")["decoded"] == half)
        poll(lambda: get(info["map"] + "/api/health")["store"]["committed_rows"] >= 2 * half + 5)
        before = get(info["map"] + "/api/tracks")
        os.kill(p.pid, signal.SIGKILL)
        p.wait(10)
    finally:
        if p.poll() is None:
            p.kill()
    con = duckdb.connect(str(store), read_only=True)
    assert con.execute("SELECT count(*) FROM ais_reports").fetchone()[0] == half
    con.close()

    async def restart():
        proc = await started(LiveOptions(ais=[Source("udp", "127.0.0.1", 0)], store=store))
        proc.refresh()
        first = proc.picture.collection()
        for k in range(half, len(lines), 10):
            udp_send(proc.udp_ports[0], [b"\n".join(lines[k : k + 10])])
            await asyncio.sleep(0.001)
        await wait_for(lambda: proc.counters.received == len(lines))
        await proc.stop()
        return proc, first

    async def whole():
        proc = await started(LiveOptions(ais=[Source("udp", "127.0.0.1", 0)]))
        udp_send(proc.udp_ports[0], lines)
        await wait_for(lambda: proc.counters.received == len(lines))
        await proc.stop()
        return proc

    proc, first = asyncio.run(asyncio.wait_for(restart(), 20))
    ref = asyncio.run(asyncio.wait_for(whole(), 20))
    pos = lambda fc: {f["id"]: f["geometry"]["coordinates"] for f in fc["features"]}  # noqa: E731
    assert proc.restored == 5 and pos(first) == pos(before)
    import gc

    assert gc.isenabled()  # the collector, paused for the restore, runs again
    assert proc.counters.decoded == len(lines) and proc.counters.check()
    got, want = picture(proc)[0], picture(ref)[0]
    assert got.keys() == want.keys()
    for m in want:
        np.testing.assert_allclose(got[m], want[m], rtol=0, atol=1e-9)
    con = duckdb.connect(str(store), read_only=True)
    assert con.execute("SELECT count(*) FROM ais_reports").fetchone()[0] == len(lines)


def test_sigterm_shuts_down_cleanly_with_the_store_committed(tmp_path):
    """``seatrack live`` (in this process) stopped by SIGTERM: ``error: interrupted``,
    exit 130, and every report it decoded is in the store."""
    store = tmp_path / "live.duckdb"
    src = tmp_path / "ais.nmea"
    src.write_bytes(b"\n".join(ais_lines(seed=10)) + b"\n")

    def stop_later():
        t0 = time.monotonic()
        while not store.exists() and time.monotonic() - t0 < 20:
            time.sleep(0.02)
        if not store.exists():  # the command failed before its signal handlers
            return
        time.sleep(0.5)
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=stop_later, daemon=True).start()
    run = seatrack("live", "--ais", src, "--http", "127.0.0.1:0", "--store", store)
    assert run.returncode == 130 and run.stderr.strip() == "error: interrupted"
    health = json.loads(run.stdout.strip().splitlines()[-1])
    assert health["decoded"] == 150 and health["received"] == 150
    con = duckdb.connect(str(store), read_only=True)
    assert con.execute("SELECT count(*) FROM ais_reports").fetchone()[0] == 150
    # the 5 MMSIs' vessels, one MMSI split in two by a lasting jump (docs/live.md)
    assert con.execute("SELECT count(*) FROM ais_vessel_state").fetchone()[0] == 6


def test_vessel_columns_restore_as_the_rows_do(tmp_path):
    from seatrack.live.ais import LiveAis
    from seatrack.live.store import Store

    r = synthetic(seed=5, vessels=4, reports=12)
    live = LiveAis()
    live.add(r.mmsi, r.t, r.lat, r.lon, r.sog_kn, r.cog_deg)
    rows = [live.state_row(m) for m in sorted(live.vessels)]
    rows[1] = (*rows[1][:3], "NAME", *rows[1][4:6], None)  # a name, no estimate
    store = Store(tmp_path / "s.duckdb")
    for row in rows:
        store.con.execute("INSERT INTO ais_vessel_state VALUES (?, ?, ?, ?, ?, ?, ?)", list(row))
    by_rows, by_cols = LiveAis(), LiveAis()
    for row in store.vessel_states():
        by_rows.restore_vessel(row)
    by_cols.restore_vessels(**store.vessel_columns())
    store.close()
    assert list(by_rows.vessels) == list(by_cols.vessels) and by_rows.changed == by_cols.changed
    for m, a in by_rows.vessels.items():
        b = by_cols.vessels[m]
        assert (a.lat0, a.lon0, a.name, a.t_restored) == (b.lat0, b.lon0, b.name, b.t_restored)
        np.testing.assert_array_equal(a.filter.s.a, b.filter.s.a)
        assert (a.estimate is None) == (b.estimate is None)
        if a.estimate is not None:
            assert a.estimate.numbers() == b.estimate.numbers()
    assert by_cols.vessels[rows[1][0]].estimate is None
    assert by_cols.vessels[rows[1][0]].name == "NAME"
