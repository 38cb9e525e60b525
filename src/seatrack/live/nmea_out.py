"""``--nmea-out udp://HOST:PORT``: radar tracks as NMEA 0183 TTM and TLL sentences, the
ARPA target output that chart plotters (OpenCPN) and ECDIS display.

After every scan each reported radar track is sent as

* ``$RATTM,nn,dist,brg,T,spd,crs,T,dcpa,tcpa,N,name,status,,hhmmss.ss,A*hh``: target
  number ``nn`` (the track id modulo 100), distance (NM) and true bearing (deg) from the
  radar, speed (kn) and true course (deg), distance (NM) and time (min) of the closest
  point of approach to the radar (the time negative when it is past), the name
  ``T<track id>``, status ``T`` (tracking, a confirmed track) or ``Q`` (acquiring, coasting
  on no plot this scan), the scan time (UTC) and acquisition ``A`` (automatic);
* ``$RATLL,nn,ddmm.mmmm,N,dddmm.mmmm,E,name,hhmmss.ss,status,*hh``: its WGS84 position.

Sentences go out in UDP datagrams of at most 1400 bytes, each line ending in CR LF, with
the checksum of :func:`seatrack.io.ais.nmea.nmea_checksum`. A send that fails (no route,
full buffer) is counted in ``nmea_out_errors``, never raised.
"""

from __future__ import annotations

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

__all__ = ["NmeaOut", "sentence", "tll", "ttm"]


def sentence(body: str) -> str:
    """``$BODY*hh`` with the NMEA checksum."""
    return f"${body}*{nmea_checksum(body.encode('ascii')):02X}"


def _hms(t: float) -> str:
    d = datetime.fromtimestamp(t, UTC)
    return d.strftime("%H%M%S.") + f"{d.microsecond // 10_000:02d}"


def ttm(
    number: int, x: float, y: float, vx: float, vy: float, t: float, name: str, confirmed: bool
) -> str:
    """The TTM sentence of a track at East/North ``x, y`` (m) of the radar, moving at
    ``vx, vy`` (m/s; courses on the radar's North), at Unix time ``t``."""
    dist = math.hypot(x, y)
    v2 = vx * vx + vy * vy
    t_cpa = -(x * vx + y * vy) / v2 if v2 > 0 else 0.0
    d_cpa = math.hypot(x + vx * t_cpa, y + vy * t_cpa)
    spd = math.sqrt(v2) / KNOT_MPS
    body = (
        f"RATTM,{number % 100:02d},{dist / NM_M:.3f},{bearing_rad_to_deg(bearing(x, y)):.1f},T,"
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
    """The TLL sentence of a track at WGS84 ``lat``, ``lon`` (deg)."""
    la, ns = _dm(lat, 2, "N", "S")
    lo, ew = _dm(lon, 3, "E", "W")
    status = "T" if confirmed else "Q"
    return sentence(f"RATLL,{number % 100:02d},{la},{ns},{lo},{ew},{name},{_hms(t)},{status},")


class NmeaOut:
    """Sends each scan's tracks to ``host:port`` (hook it on ``LiveRadar.on_scan``)."""

    def __init__(self, host: str, port: int, counters: Any) -> None:
        self.addr = (host, port)
        self.counters = counters
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self.sock = socket.socket(family, socket.SOCK_DGRAM)
        self.sock.setblocking(False)
        self.sent = 0

    def scan(self, radar: Any) -> None:
        """The sentences of the radar's current tracks, sent."""
        lines = []
        for v, (x, y, vx, vy, _) in zip(radar.current, radar.scan_rows, strict=True):
            name = f"T{v.track_id}"
            lines.append(ttm(v.track_id, x, y, vx, vy, v.t, name, v.confirmed))
            lines.append(tll(v.track_id, v.lat, v.lon, v.t, name, v.confirmed))
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
