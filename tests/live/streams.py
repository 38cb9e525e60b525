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


RADAR_TOML = """lat_deg = 57.70
lon_deg = 11.85
sigma_range_m = 15.0
sigma_azimuth_deg = 0.3
scan_period_s = 1.0
scan_timeout_s = 0.3
"""


def radar_scans(seed: int = 0, scans: int = 30, targets: int = 6, clutter: int = 5,  # noqa: E501
                t0: float = 1.7e9, period: float = 1.0):  # fmt: skip
    """Synthetic 2-D radar scans: straight-moving targets (detected with probability
    0.9, range/azimuth noise 15 m / 0.3 deg) plus uniform clutter; a list of
    ``(t, range_m, azimuth_deg)`` arrays, one per scan."""
    rng = np.random.default_rng(seed)
    pos = rng.uniform(-8000, 8000, (targets, 2))
    vel = rng.uniform(-8, 8, (targets, 2))
    out = []
    for k in range(scans):
        t = t0 + k * period
        p = pos + vel * k * period
        det = rng.uniform(size=targets) < 0.9
        r = np.hypot(p[det, 0], p[det, 1]) + rng.normal(0, 15, det.sum())
        az = np.degrees(np.arctan2(p[det, 0], p[det, 1])) + rng.normal(0, 0.3, det.sum())
        r = np.r_[r, rng.uniform(500, 12000, clutter)]
        az = np.r_[az, rng.uniform(0, 360, clutter)] % 360.0
        out.append((np.full(r.size, t), r, az))
    return out


def plot_csv(scans, header: bool = True) -> list[str]:
    """PLOTS.csv lines of scans (6 decimals, as seatrack writes them)."""
    lines = ["time_s,range_m,azimuth_deg"] if header else []
    for t, r, az in scans:
        lines += [f"{a:.6f},{b:.6f},{c:.6f}" for a, b, c in zip(t, r, az, strict=True)]
    return lines
