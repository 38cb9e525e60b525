"""The common AIS line of a live feed checked and decoded for many lines in one compiled
call: a one-sentence class A position report (types 1-3), optionally after a tag block.

:func:`scan_lines` takes the lines of a burst (joined into one byte buffer, with their
start and end offsets) and marks each line that is, with no doubt, such a report: the
tag block (when present) closed and its checksum valid, its ``c:`` field (when present)
plain digits; ``!xxVDM`` or ``!xxVDO``, at least seven fields, fragment count and number
``1``, a valid checksum; a 28-character payload of type 1, 2 or 3 with no fill bits and
only payload characters; an MMSI in 1 .. 999,999,999; latitude and longitude available
and in range. For those it gives the message time from the tag block (NaN when there is
none), the MMSI, latitude and longitude (deg), SOG (kn) and COG (deg) with "not
available" as NaN -- the values and the scalings of
:func:`seatrack.live.nmea.decode_message` -- and the payload's offsets (the duplicate
key). Every other line (multi-sentence messages, other types, anything malformed or
doubtful) is left to :class:`~seatrack.live.nmea.Assembler` and
:func:`~seatrack.live.nmea.decode_message`, which decide on it as before; a marked line
would have been accepted by them with the same values (tested line by line).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from seatrack.io.ais.reports import COG_NOT_AVAILABLE_DEG
from seatrack.io.ais.reports import MMSI_MAX
from seatrack.io.ais.reports import SOG_NOT_AVAILABLE_KN

__all__ = ["FastLines", "scan_lines"]

_BACKSLASH, _STAR, _COMMA, _BANG = 92, 42, 44, 33


@njit(cache=True, nogil=True)
def _hex(c):  # pragma: no cover - compiled
    """The value of a hexadecimal digit, -1 if ``c`` is not one."""
    if 48 <= c <= 57:
        return c - 48
    if 65 <= c <= 70:
        return c - 55
    if 97 <= c <= 102:
        return c - 87
    return -1


@njit(cache=True, nogil=True)
def _checksum_ok(buf, s, e):  # pragma: no cover - compiled
    """:func:`seatrack.io.ais.nmea.checksum_ok` of ``buf[s:e]`` when its two checksum
    characters are hexadecimal digits: 1 valid, 0 invalid, -1 undecided (left to it)."""
    star = -1
    for i in range(e - 1, s - 1, -1):
        if buf[i] == _STAR:
            star = i
            break
    if star < 0 or e < star + 3:
        return -1
    hi, lo = _hex(buf[star + 1]), _hex(buf[star + 2])
    if hi < 0 or lo < 0:
        return -1
    x = 0
    for i in range(s, star):
        x ^= buf[i]
    return 1 if x == 16 * hi + lo else 0


@njit(cache=True, nogil=True)
def _tag_time(buf, s, e):  # pragma: no cover - compiled
    """The ``c:`` time (Unix s, milliseconds above 1e11) of the tag block ``buf[s:e]``:
    NaN if absent, -1.0 if present but not plain digits (left to the Python parser)."""
    end = e
    for i in range(s, e):  # the body ends at the first '*'
        if buf[i] == _STAR:
            end = i
            break
    i = s
    while i < end:
        j = i
        while j < end and buf[j] != _COMMA:
            j += 1
        if j - i >= 2 and buf[i] == 99 and buf[i + 1] == 58:  # "c:"
            if j - i < 3 or j - i > 17:
                return -1.0
            v = 0
            for k in range(i + 2, j):
                d = buf[k] - 48
                if d < 0 or d > 9:
                    return -1.0
                v = 10 * v + d
            c = float(v)
            return c / 1000.0 if c > 1e11 else c
        i = j + 1
    return np.nan


@njit(cache=True, nogil=True)
def _bits(six, start, width):  # pragma: no cover - compiled
    """Bits ``start .. start + width - 1`` (first bit most significant) of 6-bit values."""
    v = 0
    for b in range(start, start + width):
        v = (v << 1) | ((six[b // 6] >> (5 - b % 6)) & 1)
    return v


@njit(cache=True, nogil=True)
def _line(buf, s, e, six, commas, out_f, out_i):  # pragma: no cover - compiled
    """One stripped line ``buf[s:e]``: True and its values in ``out_f`` (time, lat, lon,
    sog, cog) and ``out_i`` (mmsi, payload start, payload end) if it is a marked line
    (``six``, ``commas``: work arrays of 28 and 7 integers)."""
    if e <= s:
        return False
    t = np.nan
    if buf[s] == _BACKSLASH:
        k = s + 1
        while k < e and buf[k] != _BACKSLASH:
            k += 1
        if k >= e or _checksum_ok(buf, s + 1, k) != 1:
            return False
        t = _tag_time(buf, s + 1, k)
        if t == -1.0:
            return False
        s = k + 1
    if e - s < 7 or buf[s] != _BANG:
        return False
    n = 0  # commas, at most seven remembered
    for i in range(s, e):
        if buf[i] == _COMMA:
            if n < 7:
                commas[n] = i
            n += 1
    if n != 6:  # exactly seven fields, the last one "F*hh"
        return False
    if commas[0] - s != 6 or buf[s + 3] != 86 or buf[s + 4] != 68:  # "!xxVD?"
        return False
    if buf[s + 5] != 77 and buf[s + 5] != 79:  # VDM | VDO
        return False
    if commas[1] != commas[0] + 2 or buf[commas[0] + 1] != 49:  # count "1"
        return False
    if commas[2] != commas[1] + 2 or buf[commas[1] + 1] != 49:  # number "1"
        return False
    if _checksum_ok(buf, s + 1, e) != 1:
        return False
    ps, pe = commas[4] + 1, commas[5]
    if pe - ps != 28 or commas[5] + 1 >= e or buf[commas[5] + 1] != 48:  # no fill bits
        return False
    star = False
    for i in range(commas[5] + 1, e):
        star = star or buf[i] == _STAR
    if not star:
        return False
    for i in range(28):
        c = buf[ps + i]
        if c < 48 or c >= 120:
            return False
        six[i] = c - 48 if c < 88 else c - 56
    mtype = six[0]
    if mtype < 1 or mtype > 3:
        return False
    mmsi = _bits(six, 8, 30)
    if mmsi <= 0 or mmsi > MMSI_MAX:
        return False
    lon = _bits(six, 61, 28)
    lon = lon - 0x10000000 if lon & 0x8000000 else lon
    lat = _bits(six, 89, 27)
    lat = lat - 0x8000000 if lat & 0x4000000 else lat
    lat_deg, lon_deg = ((10 * lat + 3) // 6) / 1e6, ((10 * lon + 3) // 6) / 1e6
    if lat_deg == 91.0 or lon_deg == 181.0 or not abs(lat_deg) <= 90.0:
        return False
    if not abs(lon_deg) <= 180.0:
        return False
    sog, cog = _bits(six, 50, 10) / 10.0, _bits(six, 116, 12) / 10.0
    if not 0 <= sog < SOG_NOT_AVAILABLE_KN - 1e-9:
        sog = np.nan
    if not 0 <= cog < COG_NOT_AVAILABLE_DEG:
        cog = np.nan
    out_f[0], out_f[1], out_f[2], out_f[3], out_f[4] = t, lat_deg, lon_deg, sog, cog
    out_i[0], out_i[1], out_i[2] = mmsi, ps, pe
    return True


@njit(cache=True, nogil=True)
def _is_space(c):  # pragma: no cover - compiled
    return c == 32 or 9 <= c <= 13  # bytes.strip(): space, \t \n \v \f \r


@njit(cache=True, nogil=True)
def _scan(buf, starts, ends, ok, f, i64):  # pragma: no cover - compiled
    six, commas = np.empty(28, np.int64), np.empty(7, np.int64)
    for k in range(starts.size):
        s, e = starts[k], ends[k]
        while s < e and _is_space(buf[s]):
            s += 1
        while e > s and _is_space(buf[e - 1]):
            e -= 1
        ok[k] = _line(buf, s, e, six, commas, f[k], i64[k])


class FastLines:
    """The result of :func:`scan_lines`: ``ok`` (N,) marks the decoded lines; for those,
    ``t`` (Unix s, NaN = no tag time), ``mmsi``, ``lat``, ``lon`` (deg), ``sog_kn``,
    ``cog_deg`` (NaN = not available) and the payload's offsets ``payload`` (N, 2) in the
    buffer."""

    __slots__ = ("cog_deg", "floats", "ints", "lat", "lon", "mmsi", "ok", "payload", "sog_kn", "t")

    def __init__(self, n: int) -> None:
        self.ok = np.zeros(n, np.bool_)
        f = np.empty((n, 5))
        i64 = np.zeros((n, 3), np.int64)
        self.t, self.lat, self.lon, self.sog_kn, self.cog_deg = f.T
        self.mmsi, self.payload = i64[:, 0], i64[:, 1:]
        self.floats, self.ints = f, i64  # the compiled call's outputs


def scan_lines(buf: bytes, starts: NDArray[np.int64], ends: NDArray[np.int64]) -> FastLines:
    """Check and decode the lines ``buf[starts[k]:ends[k]]`` (see the module docstring)."""
    out = FastLines(starts.size)
    if starts.size:
        _scan(np.frombuffer(buf, np.uint8), starts, ends, out.ok, out.floats, out.ints)
    return out
