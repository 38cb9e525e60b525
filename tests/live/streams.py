"""Helpers of the live tests: a LiveProcess on loopback sockets, senders, waits."""

from __future__ import annotations

import asyncio
import socket
import time
from collections.abc import Callable

import numpy as np

from seatrack.live.process import LiveOptions
from seatrack.live.process import LiveProcess


def udp_send(port: int, datagrams: list[bytes]) -> None:
    """Send datagrams to 127.0.0.1:port."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        for d in datagrams:
            s.sendto(d, ("127.0.0.1", port))


async def wait_for(cond: Callable[[], bool], timeout: float = 5.0) -> None:
    """Poll ``cond`` until true; fail after ``timeout`` seconds."""
    t0 = time.monotonic()
    while not cond():
        if time.monotonic() - t0 > timeout:
            raise AssertionError("condition not met in time")
        await asyncio.sleep(0.01)


async def started(opts: LiveOptions) -> LiveProcess:
    """A started LiveProcess (UDP sources bound; their ports in ``proc.udp_ports``)."""
    proc = LiveProcess(opts)
    await proc.start()
    return proc


class Reports:
    """The minimal report table :func:`track_reports` reads."""

    def __init__(self, mmsi, t, lat, lon, sog, cog):
        self.mmsi, self.t, self.lat, self.lon = mmsi, t, lat, lon
        self.sog_kn, self.cog_deg = sog, cog
        self.valid = np.ones(len(t), dtype=bool)

    def __len__(self):
        return len(self.t)


def synthetic(seed: int = 1, vessels: int = 6, reports: int = 60) -> Reports:
    """Vessels turning and accelerating near 57 N 11 E, reports every 2-12 s, with noise,
    SOG/COG (some missing), a few jumps, repeated positions and a long gap; rows in time
    order."""
    rng = np.random.default_rng(seed)
    rows = []
    for v in range(vessels):
        t, e, n = 1.7e9 + rng.uniform(0, 20), rng.uniform(-5e3, 5e3), rng.uniform(-5e3, 5e3)
        spd, crs, turn = rng.uniform(0, 10), rng.uniform(0, 2 * np.pi), rng.uniform(-0.01, 0.01)
        for k in range(reports):
            dt = rng.uniform(2, 12) + (900 if k == reports // 2 and v % 2 else 0)
            t += dt
            crs += turn * dt
            e += spd * np.sin(crs) * dt
            n += spd * np.cos(crs) * dt
            pe, pn = e + rng.normal(0, 3), n + rng.normal(0, 3)
            if rng.uniform() < 0.04:
                pe += 3000.0  # an implausible jump
            if k and rng.uniform() < 0.05:
                pe, pn = rows[-1][2], rows[-1][3]  # a repeated (stale) position
            sog = spd / 0.514444 + rng.normal(0, 0.1) if rng.uniform() > 0.1 else np.nan
            cog = np.degrees(crs) % 360 + rng.normal(0, 0.5) if rng.uniform() > 0.1 else np.nan
            rows.append((200000000 + v, t, pe, pn, sog, cog % 360 if cog == cog else cog))
    rows.sort(key=lambda r: r[1])
    a = np.array(rows)
    lat = 57.0 + a[:, 3] / 111_320.0
    lon = 11.0 + a[:, 2] / (111_320.0 * np.cos(np.radians(57.0)))
    return Reports(a[:, 0].astype(np.int64), a[:, 1], lat, lon, a[:, 4], a[:, 5])
