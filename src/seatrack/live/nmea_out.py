"""``--nmea-out udp://HOST:PORT``: radar tracks as NMEA 0183 TTM and TLL sentences, the
ARPA target output that chart plotters (OpenCPN) and ECDIS display.

After every scan each reported radar track is sent as

* ``$RATTM,nn,dist,brg,T,spd,crs,T,dcpa,tcpa,N,name,status,,hhmmss.ss,A*hh``: target
  number ``nn`` (01-99, :class:`TargetNumbers`), distance (NM) and true bearing (deg) from the
  radar, speed (kn) and true course (deg), distance (NM) and time (min) of the closest
  point of approach to the radar (the time negative when it is past), the name
  ``T<track id>``, status ``T`` (tracking, a confirmed track) or ``Q`` (acquiring, coasting
  on no plot this scan), the scan time (UTC) and acquisition ``A`` (automatic);
* ``$RATLL,nn,ddmm.mmmm,N,dddmm.mmmm,E,name,hhmmss.ss,status,*hh``: its WGS84 position.

Target numbers. TTM has two digits for the target number, and a chart plotter keys its
targets by it, so each track keeps one number while it is sent: a track is given the
lowest free number (01-99) the first time it is sent and keeps it until the track is
deleted, when the number is freed for another. With more than 99 reported tracks the 99
nearest the radar are sent (those that hold a number first among equals, so numbers do
not hop between tracks at the same distance); a track pushed out of the nearest 99
gives its number up (it is sent no more, as a deleted one), and every track not sent
in a scan is counted in ``nmea_out_not_sent``.

Sentences go out in UDP datagrams of at most 1400 bytes, each line ending in CR LF, with
the checksum of :func:`seatrack.io.ais.nmea.nmea_checksum`. A send that fails (no route,
full buffer) is counted in ``nmea_out_errors``, never raised.
"""

from __future__ import annotations

import heapq
import math
import socket
from datetime import UTC
from datetime import datetime
from typing import Any

from seatrack.geometry import KNOT_MPS
from seatrack.geometry import bearing
from seatrack.geometry import bearing_rad_to_deg
from seatrack.io.ais.nmea import nmea_checksum
from seatrack.io.asterix import NM_M

__all__ = ["NmeaOut", "TargetNumbers", "sentence", "tll", "ttm"]

#: TTM target numbers handed out (00 is not used)
MAX_TARGETS = 99


def sentence(body: str) -> str:
    """``$BODY*hh`` with the NMEA checksum."""
    return f"${body}*{nmea_checksum(body.encode('ascii')):02X}"


def _hms(t: float) -> str:
    d = datetime.fromtimestamp(t, UTC)
    return d.strftime("%H%M%S.") + f"{d.microsecond // 10_000:02d}"


def ttm(
    number: int, x: float, y: float, vx: float, vy: float, t: float, name: str, confirmed: bool
) -> str:
    """The TTM sentence of target ``number`` (0-99) at East/North ``x, y`` (m) of the
    radar, moving at ``vx, vy`` (m/s; courses on the radar's North), at Unix time ``t``."""
    _check_number(number)
    dist = math.hypot(x, y)
    v2 = vx * vx + vy * vy
    t_cpa = -(x * vx + y * vy) / v2 if v2 > 0 else 0.0
    d_cpa = math.hypot(x + vx * t_cpa, y + vy * t_cpa)
    spd = math.sqrt(v2) / KNOT_MPS
    body = (
        f"RATTM,{number:02d},{dist / NM_M:.3f},{bearing_rad_to_deg(bearing(x, y)):.1f},T,"
        f"{spd:.1f},{bearing_rad_to_deg(bearing(vx, vy)):.1f},T,{d_cpa / NM_M:.3f},"
        f"{t_cpa / 60.0:.1f},N,{name},{'T' if confirmed else 'Q'},,{_hms(t)},A"
    )
    return sentence(body)


def _dm(value: float, width: int, pos: str, neg: str) -> tuple[str, str]:
    a = abs(value)
    deg = int(a)
    minutes = (a - deg) * 60.0
    if round(minutes, 4) >= 60.0:
        deg, minutes = deg + 1, 0.0
    return f"{deg:0{width}d}{minutes:07.4f}", pos if value >= 0 else neg


def tll(number: int, lat: float, lon: float, t: float, name: str, confirmed: bool) -> str:
    """The TLL sentence of target ``number`` (0-99) at WGS84 ``lat``, ``lon`` (deg)."""
    _check_number(number)
    la, ns = _dm(lat, 2, "N", "S")
    lo, ew = _dm(lon, 3, "E", "W")
    status = "T" if confirmed else "Q"
    return sentence(f"RATLL,{number:02d},{la},{ns},{lo},{ew},{name},{_hms(t)},{status},")


def _check_number(number: int) -> None:
    if not 0 <= number <= 99:
        raise ValueError(f"TTM/TLL target number {number} is not 00-99")


class TargetNumbers:
    """TTM target numbers of radar tracks (module docstring, "Target numbers").

    Parameters
    ----------
    size : int
        Numbers handed out: 1..size (at most 99).
    """

    def __init__(self, size: int = MAX_TARGETS) -> None:
        if not 1 <= size <= MAX_TARGETS:
            raise ValueError(f"TargetNumbers: size must be 1-{MAX_TARGETS}")
        self.number: dict[int, int] = {}  # track id -> its number
        self._free = list(range(1, size + 1))  # a heap: the lowest free number first
        self.size = size

    def assign(self, track_ids: list[int], range_m: list[float]) -> dict[int, int]:
        """Numbers of the tracks to send this scan (track id -> number) among the
        reported ``track_ids`` at ``range_m`` from the radar: every number of a track
        not reported (deleted) or not among the ``size`` nearest is freed, then the
        tracks sent without a number get the lowest free ones, nearest first."""
        held = self.number
        rank = [(r, tid not in held, tid) for tid, r in zip(track_ids, range_m, strict=True)]
        order = sorted(range(len(track_ids)), key=rank.__getitem__)
        send = [track_ids[k] for k in order[: self.size]]
        keep = set(send)
        for tid in [t for t in held if t not in keep]:
            heapq.heappush(self._free, held.pop(tid))
        for tid in send:
            if tid not in held:
                held[tid] = heapq.heappop(self._free)
        return {tid: held[tid] for tid in send}


class NmeaOut:
    """Sends each scan's tracks to ``host:port`` (hook it on ``LiveRadar.on_scan``)."""

    def __init__(self, host: str, port: int, counters: Any) -> None:
        self.addr = (host, port)
        self.counters = counters
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self.sock = socket.socket(family, socket.SOCK_DGRAM)
        self.sock.setblocking(False)
        self.sent = 0
        self.numbers = TargetNumbers()

    def scan(self, radar: Any) -> None:
        """The sentences of the radar's current tracks (at most 99, the nearest), sent."""
        rows = radar.scan_rows
        ids = [v.track_id for v in radar.current]
        number = self.numbers.assign(ids, [math.hypot(r[0], r[1]) for r in rows])
        self.counters.nmea_out_not_sent += len(ids) - len(number)
        lines = []
        for v, (x, y, vx, vy, _) in zip(radar.current, rows, strict=True):
            nn = number.get(v.track_id)
            if nn is None:
                continue
            name = f"T{v.track_id}"
            lines.append(ttm(nn, x, y, vx, vy, v.t, name, v.confirmed))
            lines.append(tll(nn, v.lat, v.lon, v.t, name, v.confirmed))
        datagram = ""
        for line in lines:
            if datagram and len(datagram) + len(line) + 2 > 1400:
                self._send(datagram)
                datagram = ""
            datagram += line + "\r\n"
        if datagram:
            self._send(datagram)

    def _send(self, text: str) -> None:
        try:
            self.sock.sendto(text.encode("ascii"), self.addr)
            self.sent += 1
        except OSError:
            self.counters.nmea_out_errors += 1

    def close(self) -> None:
        self.sock.close()
