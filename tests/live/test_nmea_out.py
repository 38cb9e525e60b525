"""NMEA TTM/TLL output of the radar tracks, parsed with pynmea2, over loopback UDP."""

from __future__ import annotations

import asyncio
import math
import socket

import numpy as np
import pynmea2
import pytest

from live.streams import plot_csv
from live.streams import radar_scans
from live.streams import started
from live.streams import udp_send
from live.streams import wait_for
from seatrack.io.radar import parse_radar_config
from seatrack.live.counters import Counters
from seatrack.live.nmea_out import NmeaOut
from seatrack.live.nmea_out import TargetNumbers
from seatrack.live.nmea_out import tll
from seatrack.live.nmea_out import ttm
from seatrack.live.picture import RadarTrackView
from seatrack.live.process import LiveOptions
from seatrack.live.sources import Source


def test_ttm_and_tll_fields():
    # 1 NM north-east of the radar, heading west at 10 kn: CPA ahead
    x = y = 1852.0 / math.sqrt(2)
    v = 10 * 1852 / 3600
    m = pynmea2.parse(ttm(23, x, y, -v, 0.0, 1.7e9, "T123", True))
    assert m.sentence_type == "TTM" and m.target_number == 23
    assert float(m.distance) == 1.0 and float(m.bearing) == 45.0 and m.brg_ref == "T"
    assert float(m.speed) == 10.0 and float(m.cog) == 270.0
    assert float(m.dist_cpa) == round(1 / math.sqrt(2), 3)
    assert float(m.time_cpa) == round(x / v / 60, 1) and m.dist_unit == "N"
    assert (m.name, m.status, m.acquisition) == ("T123", "T", "A")
    assert m.timestamp.strftime("%H%M%S") == "221320"
    m = pynmea2.parse(tll(7, -33.5, -70.25, 1.7e9, "T7", False))
    assert (m.lat, m.lat_dir, m.lon, m.lon_dir) == ("3330.0000", "S", "07015.0000", "W")
    assert m.target_status == "Q" and m.target_number == 7
    for bad in (-1, 100):
        with pytest.raises(ValueError, match="not 00-99"):
            ttm(bad, x, y, 0.0, 0.0, 1.7e9, "T", True)


def test_target_numbers_are_kept_freed_and_reused_lowest_first():
    nums = TargetNumbers()
    assert nums.assign([10, 11, 12], [300.0, 100.0, 200.0]) == {11: 1, 12: 2, 10: 3}
    # kept while the track lives, whatever its distance does
    assert nums.assign([10, 11, 12, 13], [50.0, 100.0, 200.0, 10.0]) == {13: 4, 10: 3,
                                                                     11: 1, 12: 2}  # fmt: skip
    # 11 and 12 deleted: their numbers are free, the lowest goes to the next new track
    assert nums.assign([10, 13, 14], [50.0, 10.0, 70.0]) == {13: 4, 10: 3, 14: 1}
    assert nums.assign([10, 13, 14, 15, 16], [5.0] * 5) == {10: 3, 13: 4, 14: 1, 15: 2,
                                                            16: 5}  # fmt: skip


def test_more_than_99_tracks_send_the_99_nearest():
    nums = TargetNumbers()
    ids = list(range(1000, 1120))
    rng = [float(1000 + 10 * k) for k in range(120)]  # 1000 nearest, 1119 farthest
    first = nums.assign(ids, rng)
    assert sorted(first) == ids[:99] and sorted(first.values()) == list(range(1, 100))
    # two new tracks nearer than all: the two farthest sent lose their numbers to them
    second = nums.assign(ids + [5, 6], rng + [1.0, 2.0])
    assert len(second) == 99 and 1097 not in second and 1098 not in second
    assert {second[5], second[6]} == {first[1097], first[1098]}
    assert all(second[t] == first[t] for t in ids[:97])
    with pytest.raises(ValueError):
        TargetNumbers(100)


def test_nmea_out_sends_99_of_120_tracks_with_distinct_numbers():
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", 0))
    sink.settimeout(3)
    counters = Counters()
    out = NmeaOut("127.0.0.1", sink.getsockname()[1], counters)

    class Radar:  # what NmeaOut.scan reads of a LiveRadar
        current = [RadarTrackView(500 + k, 1.7e9, 57.0, 11.0, 5.0, 0.0, 20.0, True)
                   for k in range(120)]  # fmt: skip
        scan_rows = [(0.0, 1000.0 + 10 * k, 5.0, 0.0, "confirmed") for k in range(120)]

    out.scan(Radar())
    out.close()
    lines = []
    while len(lines) < 2 * 99:
        lines += sink.recv(65536).decode("ascii").split("\r\n")[:-1]
    sink.close()
    ttms = [m for m in map(pynmea2.parse, lines) if m.sentence_type == "TTM"]
    assert sorted(int(m.target_number) for m in ttms) == list(range(1, 100))
    assert {m.name for m in ttms} == {f"T{500 + k}" for k in range(99)}  # the nearest
    assert counters.nmea_out_not_sent == 21 and counters.nmea_out_errors == 0


def test_radar_tracks_go_out_as_ttm_and_tll():
    setup = parse_radar_config(
        {"lat_deg": 57.7, "lon_deg": 11.85, "sigma_range_m": 15.0, "sigma_azimuth_deg": 0.3,
         "scan_period_s": 1.0}
    )  # fmt: skip
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", 0))
    sink.settimeout(3)
    scans = radar_scans(seed=5, scans=12)

    async def go():
        opts = LiveOptions(plots=[Source("udp", "127.0.0.1", 0)], radar=setup,
                           nmea_out=("127.0.0.1", sink.getsockname()[1]))  # fmt: skip
        proc = await started(opts)
        for sc in scans:
            udp_send(proc.udp_ports[0], ["\n".join(plot_csv([sc])).encode()])
            await asyncio.sleep(0.003)
        await wait_for(lambda: proc.counters.scans == len(scans) - 1)
        await proc.drain()
        await proc.stop()
        return proc

    proc = asyncio.run(asyncio.wait_for(go(), 20))
    lines = []
    while True:
        try:
            lines += sink.recv(65536).decode("ascii").split("\r\n")[:-1]
        except TimeoutError:
            break
        sink.settimeout(0.3)
    sink.close()
    msgs = [pynmea2.parse(s, check=True) for s in lines]  # checksums checked
    ttms = [m for m in msgs if m.sentence_type == "TTM"]
    tlls = [m for m in msgs if m.sentence_type == "TLL"]
    assert len(ttms) == len(tlls) > 0
    numbers = {(m.name, int(m.target_number)) for m in ttms}  # one number per track
    assert len(numbers) == len({m.name for m in ttms}) and all(0 < n < 100 for _, n in numbers)
    last = {f"T{v.track_id}": v for v in proc.radar.current}
    final = {m.name: m for m in ttms[-len(last) :]}
    assert final.keys() == last.keys()
    for name, v in last.items():
        assert abs(float(final[name].speed) - v.speed / 0.514444) < 0.06
    for m in tlls[-len(last) :]:
        lat = int(m.lat[:2]) + float(m.lat[2:]) / 60
        lon = int(m.lon[:3]) + float(m.lon[3:]) / 60
        v = last[m.target_name]
        assert np.hypot(lat - v.lat, (lon - v.lon) * np.cos(np.radians(lat))) < 1e-6
