"""``seatrack demo --live``: a bundled real AIS sample and a simulated radar replayed into
a live process, with its map.

The AIS sample is ``dk_gothenburg_20170705_cpa.csv`` (two vessels meeting off Gothenburg,
14 minutes, Danish Maritime Authority data; see ``seatrack/data/ais/README.md``), encoded
as NMEA by the replay. The radar stands at :data:`RADAR_LAT_DEG`, :data:`RADAR_LON_DEG`
and sees the same vessels: every ``PERIOD_S`` seconds each vessel's position
interpolated from its reports, detected with probability 0.9, with 15 m / 0.3 deg noise,
plus clutter plots; the plots are sent as CSV datagrams. The replay runs in a thread at
``speed`` times real time, over and over with the times moved on, until the process is
stopped.
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np

from seatrack.geometry import cart_to_polar
from seatrack.geometry import geodetic_to_enu

__all__ = ["RADAR_LAT_DEG", "RADAR_LON_DEG", "demo_items", "radar_setup", "start_replay"]

RADAR_LAT_DEG = 57.70
RADAR_LON_DEG = 11.85
PERIOD_S = 2.5
SAMPLE = "dk_gothenburg_20170705_cpa.csv"


def radar_setup() -> Any:
    """The demo radar's :class:`~seatrack.io.radar.RadarSetup`."""
    from seatrack.io.radar import parse_radar_config

    return parse_radar_config({
        "lat_deg": RADAR_LAT_DEG, "lon_deg": RADAR_LON_DEG, "sigma_range_m": 15.0,
        "sigma_azimuth_deg": 0.3, "scan_period_s": PERIOD_S, "scan_timeout_s": 1.0,
    })  # fmt: skip


def demo_items(seed: int = 0, clutter: int = 4) -> list[Any]:
    """The replay items: the AIS sample's reports and the simulated radar's scans."""
    from seatrack.data import ais_sample
    from seatrack.io.ais import read_ais
    from seatrack.live.replay import Item
    from seatrack.live.replay import file_items

    path = ais_sample(SAMPLE)
    items = file_items(path)
    r = read_ais([path])
    rng = np.random.default_rng(seed)
    vessels = [np.flatnonzero(r.valid & (r.mmsi == m)) for m in np.unique(r.mmsi[r.valid])]
    t0, t1 = float(r.t[r.valid].min()), float(r.t[r.valid].max())
    for t in np.arange(t0, t1, PERIOD_S):
        rows = []
        for idx in vessels:
            k = idx[np.argsort(r.t[idx])]
            if not r.t[k[0]] <= t <= r.t[k[-1]] or rng.uniform() > 0.9:
                continue
            lat, lon = np.interp(t, r.t[k], r.lat[k]), np.interp(t, r.t[k], r.lon[k])
            en = geodetic_to_enu(lat, lon, 0.0, RADAR_LAT_DEG, RADAR_LON_DEG)
            rng_m, az = cart_to_polar(en[:2])
            rows.append((float(rng_m) + rng.normal(0, 15), np.degrees(az) + rng.normal(0, 0.3)))
        rows += [(rng.uniform(300, 8000), rng.uniform(0, 360)) for _ in range(clutter)]
        text = "time_s,range_m,azimuth_deg\n" + "\n".join(
            f"{t:.3f},{a:.2f},{b % 360.0:.4f}" for a, b in rows
        )
        items.append(Item(float(t), text.encode(), "plots"))
    return sorted(items, key=lambda it: it.t)


def _shifted(items: list[Any], dt: float) -> list[Any]:
    """The items ``dt`` seconds later (AIS tag blocks and plot times rewritten)."""
    from seatrack.live.nmea import parse_tag_time
    from seatrack.live.nmea import tag_block
    from seatrack.live.replay import Item

    out = []
    for it in items:
        if it.kind == "ais":
            end = it.data.index(b"\\", 1) + 1
            t = parse_tag_time(it.data[1 : end - 1])
            assert t is not None
            data = tag_block(t + dt) + it.data[end:]
        else:
            head, *rows = it.data.decode().split("\n")
            data = "\n".join([head, *(f"{float(r.split(',', 1)[0]) + dt:.3f},"
                                      f"{r.split(',', 1)[1]}" for r in rows)]).encode()  # fmt: skip
        out.append(Item(it.t + dt, data, it.kind))
    return out


def start_replay(targets: dict[str, tuple[str, int]], speed: float, stop: threading.Event,
                 rounds: int = 1000) -> threading.Thread:  # fmt: skip
    """Replay the demo items in a thread, ``rounds`` times (each later by the span and a
    pause), until ``stop`` is set."""
    from seatrack.live.replay import send_items

    items = demo_items()
    span = items[-1].t - items[0].t + 30.0

    def run() -> None:
        for k in range(rounds):
            if stop.is_set():
                return
            send_items(_shifted(items, k * span) if k else items, targets, speed, stop)

    th = threading.Thread(target=run, daemon=True, name="seatrack-demo-replay")
    th.start()
    return th
