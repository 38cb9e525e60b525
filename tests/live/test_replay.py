"""``seatrack replay``: files to UDP with their own timing, into a live process; and
``seatrack track PLOTS.ast``."""

from __future__ import annotations

import asyncio
import csv
import time

import numpy as np

from cli_inprocess import seatrack
from live.streams import plot_csv
from live.streams import radar_scans
from live.streams import started
from live.streams import wait_for
from seatrack.io.asterix import encode_cat048
from seatrack.io.radar import parse_radar_config
from seatrack.live.nmea import encode_report
from seatrack.live.process import LiveOptions
from seatrack.live.replay import file_items
from seatrack.live.replay import merge_files
from seatrack.live.replay import send_items
from seatrack.live.sources import Source

SETUP = parse_radar_config(
    {"lat_deg": 57.7, "lon_deg": 11.85, "sigma_range_m": 15.0, "sigma_azimuth_deg": 0.3,
     "scan_period_s": 1.0, "scan_timeout_s": 0.3}
)  # fmt: skip


def nmea_file(tmp_path):
    """A log mixing tag blocks and leading ISO timestamps, with a 2-part message."""
    lines = [encode_report(219000001, 1.7e9, 57.7, 11.9, 8.0, 90.0)[0]]
    body = encode_report(219000002, 1.7e9 + 2, 57.71, 11.91, 5.0, 10.0)[0].split(b"\\")[-1]
    lines.append(b"2023-11-14T22:13:22Z " + body)
    lines += [
        b"2023-11-14T22:13:23Z !AIVDM,2,1,4,A,55O0W7`00001L@gCWGA2uItLth@DqtL5@F22220j1h742t0Ht"
        b"0000000,0*08",
        b"!AIVDM,2,2,4,A,000000000000000,2*20",
    ]  # fmt: skip
    p = tmp_path / "log.nmea"
    p.write_bytes(b"\n".join(lines) + b"\n")
    return p


def test_items_keep_the_files_timing(tmp_path):
    items = file_items(nmea_file(tmp_path))
    assert [it.t - items[0].t for it in items] == [0.0, 2.0, 3.0, 3.0]
    assert items[1].data.startswith(b"\\c:1700000002*") and b"!AIVDM" in items[1].data
    csv_path = tmp_path / "ais.csv"
    csv_path.write_text("mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg\n"
                        "219000003,2023-11-14T22:13:25Z,57.7,11.8,3.0,45.0,\n")  # fmt: skip
    (it,) = file_items(csv_path)
    assert it.t == 1.7e9 + 5 and it.data.startswith(b"\\c:1700000005*")
    ast = tmp_path / "plots.ast"
    ast.write_bytes(b"".join(encode_cat048([10.0, 10.0, 11.0], [1e3, 2e3, 3e3], [0.1, 0.2, 0.3])))
    merged = merge_files([csv_path, ast])
    assert [m.kind for m in merged] == ["plots", "plots", "ais"]  # 00:00:10 UTC < 22:13:25
    assert merged[0].t == 1699920000.0 + 10


def test_replay_into_live_at_speed(tmp_path):
    scans = radar_scans(seed=6, scans=8)
    plots = tmp_path / "plots.csv"
    plots.write_text("\n".join(plot_csv(scans)) + "\n")
    items = merge_files([nmea_file(tmp_path), plots])

    async def go():
        udp = Source("udp", "127.0.0.1", 0)
        proc = await started(LiveOptions(ais=[udp], plots=[udp], radar=SETUP))
        targets = {"ais": ("127.0.0.1", proc.udp_ports[0]),
                   "plots": ("127.0.0.1", proc.udp_ports[1])}  # fmt: skip
        t0 = time.monotonic()
        n = await asyncio.to_thread(send_items, items, targets, 20.0)
        took = time.monotonic() - t0
        await wait_for(lambda: proc.counters.scans == len(scans))  # the last by timeout
        await proc.stop()
        return proc, n, took

    proc, n, took = asyncio.run(asyncio.wait_for(go(), 20))
    assert 7 / 20 * 0.9 <= took < 2.0  # 7 s of data at 20x
    assert proc.counters.received == 3 and proc.counters.decoded == 3
    assert proc.counters.plots_received == sum(s[0].size for s in scans)
    assert proc.names == {368060190: "P/V_GOLDEN_GATE"} and len(proc.ais.vessels) == 2


def test_replay_command_and_track_ast(tmp_path):
    run = seatrack("replay", nmea_file(tmp_path), "--to", "udp://127.0.0.1:9", "--speed", "1e6")
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[-1] == "sent 3 datagrams"
    bad = seatrack("replay", nmea_file(tmp_path), "--to", "tcp://127.0.0.1:9")
    assert bad.returncode == 2 and "--to: expected udp://HOST:PORT" in bad.stderr
    # seatrack track on CAT048 = on the same plots as CSV (at CAT048 resolution)
    scans = radar_scans(seed=2, scans=15, t0=0.0)
    ast = tmp_path / "plots.ast"
    ast.write_bytes(b"".join(b for t, r, az in scans
                             for b in encode_cat048(t, r, np.radians(az))))  # fmt: skip
    from seatrack.io.asterix import read_cat048

    c = read_cat048(ast)
    csv_path = tmp_path / "plots.csv"
    csv_path.write_text("time_s,range_m,azimuth_deg\n" + "".join(
        f"{float(t)!r},{float(r)!r},{float(a)!r}\n" for t, r, a in
        zip(c.time_of_day_s, c.range_m, np.degrees(c.azimuth), strict=True)))  # fmt: skip
    outs = []
    for src in (ast, csv_path):
        out = tmp_path / f"{src.suffix[1:]}_tracks.csv"
        run = seatrack("track", src, "--out", out)
        assert run.returncode == 0, run.stderr
        with open(out) as fh:  # plot_line: the record number, or the CSV line (one more)
            outs.append([{k: v for k, v in r.items() if k != "plot_line"}
                         for r in csv.DictReader(fh)])  # fmt: skip
    assert outs[0] == outs[1] and len(outs[0]) > 20
