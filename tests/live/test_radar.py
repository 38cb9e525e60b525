"""Live radar plots: datagram parsing, scan assembly, and equivalence with
``seatrack track`` (the unlabelled path) on the same plots, over UDP."""

from __future__ import annotations

import asyncio
import csv
import math

import numpy as np

from cli_inprocess import seatrack
from live.streams import RADAR_TOML
from live.streams import plot_csv
from live.streams import radar_scans
from live.streams import started
from live.streams import udp_send
from live.streams import wait_for
from seatrack.io.asterix import encode_cat048
from seatrack.io.radar import parse_radar_config
from seatrack.live.counters import Counters
from seatrack.live.process import LiveOptions
from seatrack.live.radar import LiveRadar
from seatrack.live.radar import parse_plot_datagram
from seatrack.live.radar import unix_time_of_day
from seatrack.live.sources import Source

SETUP = parse_radar_config(
    {"lat_deg": 57.7, "lon_deg": 11.85, "sigma_range_m": 15.0, "sigma_azimuth_deg": 0.3,
     "scan_period_s": 1.0, "scan_timeout_s": 0.3}
)  # fmt: skip


def test_csv_datagram_rows_and_rejections():
    data = b"time_s,range_m,azimuth_deg,snr_db\n1.7e9,1000,10,3\n1.7e9,-5,10,3\n1.7e9,x,1,1\n"
    t, r, az, bad = parse_plot_datagram(data, 1.7e9)
    assert t.tolist() == [1.7e9] and r.tolist() == [1000.0] and az[0] == math.radians(10)
    assert bad == {"bad plot value": 1, "bad plot row": 1}
    assert parse_plot_datagram(b"a,b\n1,2\n", 0)[3] == {"no PLOTS.csv header": 1}
    assert parse_plot_datagram(b"\x30\x00\x09junk", 0)[3] == {"bad CAT048 datagram": 1}
    assert parse_plot_datagram(b"\xff\xfe", 0)[3] == {"not CAT048 or CSV": 1}


def test_cat048_datagram_time_on_the_nearest_day():
    day = 1_700_006_400.0  # a midnight UTC
    (block,) = encode_cat048([86399.0, 1.0], [5000.0, 6000.0], [0.1, 0.2])
    t, r, az, bad = parse_plot_datagram(block, day + 30.0)
    assert not bad and t.tolist() == [day - 1.0, day + 1.0]
    assert np.allclose(r, [5000, 6000], atol=4) and np.allclose(az, [0.1, 0.2], atol=1e-4)
    assert unix_time_of_day(np.array([43200.0]), day + 1.0)[0] == day + 43200.0


def test_scans_close_on_a_later_time_and_late_plots_are_rejected():
    cnt = Counters()
    radar = LiveRadar(SETUP, cnt)
    times = []
    radar.listeners.append(lambda t, *a: times.append(t))
    scans = radar_scans(scans=3)
    for t, r, az in scans:
        half = t.size // 2  # one scan in two datagrams
        radar.add(t[:half], r[:half], np.radians(az[:half]), 0.0)
        radar.add(t[half:], r[half:], np.radians(az[half:]), 0.0)
    assert times == [scans[0][0][0], scans[1][0][0]]  # the third is still open
    radar.add(scans[0][0][:2], scans[0][1][:2], np.radians(scans[0][2][:2]), 0.0)
    assert cnt.plots_rejected == {"late plot": 2}
    radar.timeout(0.2)
    assert len(times) == 2
    radar.timeout(0.5)  # scan_timeout_s = 0.3 after its first plot
    assert times[-1] == scans[2][0][0] and radar.open_t is None


def batch_rows(tmp_path, lines):
    """``seatrack track`` (unlabelled) on the plot lines with the radar's tracker keys."""
    plots = tmp_path / "plots.csv"
    plots.write_text("\n".join(lines) + "\n")
    cfg = tmp_path / "track.toml"
    cfg.write_text("sigma_range_m = 15.0\nsigma_azimuth_deg = 0.3\n")
    out = tmp_path / "tracks.csv"
    res = seatrack("track", plots, "--method", "ekf", "--config", cfg, "--out", out)
    assert res.returncode == 0, res.stderr
    with open(out) as fh:
        return [(float(r["time_s"]), int(r["track"]), r["status"], float(r["x_m"]),
                 float(r["y_m"]), float(r["vx_mps"]), float(r["vy_mps"]))
                for r in csv.DictReader(fh)]  # fmt: skip


def test_live_radar_equals_seatrack_track_over_udp(tmp_path):
    scans = radar_scans(seed=3, scans=25)
    want = batch_rows(tmp_path, plot_csv(scans))
    cfg = tmp_path / "radar.toml"
    cfg.write_text(RADAR_TOML)
    from seatrack.io.radar import load_radar_config

    setup = load_radar_config(cfg)
    got = []

    async def go():
        proc = await started(LiveOptions(plots=[Source("udp", "127.0.0.1", 0)], radar=setup))
        names = {0: "tentative", 1: "confirmed", 2: "coasting"}
        proc.radar.listeners.append(
            lambda t, ids, st, cols: got.extend(
                (t, int(ids[k]), names[int(st[k])], cols["x_m"][k], cols["y_m"][k],
                 cols["vx_mps"][k], cols["vy_mps"][k]) for k in range(ids.size)
            )
        )  # fmt: skip
        for sc in scans:
            udp_send(proc.udp_ports[0], ["\n".join(plot_csv([sc])).encode()])
            await asyncio.sleep(0.003)
        await wait_for(lambda: proc.counters.plots_received == sum(s[0].size for s in scans))
        await proc.drain()  # closes the last scan
        h = proc.health()
        await proc.stop()
        return proc, h

    proc, h = asyncio.run(asyncio.wait_for(go(), 20))
    assert proc.counters.scans == len(scans) and not proc.counters.plots_rejected
    assert len(want) > 50 and len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        assert g[:3] == w[:3]
        np.testing.assert_allclose(g[3:], w[3:], rtol=0, atol=2e-6)
    last = [w for w in want if w[0] == want[-1][0]]
    assert h["radar_tracks"] == len(last) >= 4
    feats = [
        f for f in proc.picture.collection()["features"] if f["properties"]["source"] == "radar"
    ]
    assert len(feats) == len(last)
    lat0, lon0 = 57.7, 11.85
    for f in feats:
        lon, lat = f["geometry"]["coordinates"]
        assert abs(lat - lat0) < 0.2 and abs(lon - lon0) < 0.3
        assert f["properties"]["mmsi"] is None and f["properties"]["status"] in (
            "confirmed",
            "tentative",
        )


def test_cat048_plots_over_udp_make_tracks():
    scans = radar_scans(seed=4, scans=12, clutter=2)

    async def go():
        proc = await started(LiveOptions(plots=[Source("udp", "127.0.0.1", 0)], radar=SETUP))
        for t, r, az in scans:
            tod = np.full(t.size, 3600.0 + (t[0] - scans[0][0][0]))
            for block in encode_cat048(tod, r, np.radians(az)):
                udp_send(proc.udp_ports[0], [block])
            await asyncio.sleep(0.003)
        udp_send(proc.udp_ports[0], [b"\x30\x00\x05\xf0\x01"])  # a broken record
        await wait_for(lambda: proc.counters.scans == len(scans))  # the last by timeout
        await proc.drain()
        await proc.stop()
        return proc

    proc = asyncio.run(asyncio.wait_for(go(), 20))
    assert proc.counters.plots_rejected == {"bad CAT048 datagram": 1}
    assert proc.radar.n_tracks >= 4
