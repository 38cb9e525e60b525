"""ASTERIX category 048 (monoradar target reports): the items a plot tracker needs.

A file or UDP datagram holds data blocks: ``CAT`` (1 byte, 48), ``LEN`` (2 bytes, big
endian, the block's length with this header), then records. A record is its FSPEC (one
bit per item of the User Application Profile, 7 per byte, the lowest bit of each byte
= "another FSPEC byte follows") and the items present, in UAP order. Decoded here
(EUROCONTROL ASTERIX Part 4, Category 048):

* I048/010 data source: SAC, SIC (1 byte each);
* I048/140 time of day: 3 bytes, 1/128 s since midnight UTC;
* I048/040 measured position: RHO (2 bytes, 1/256 NM) and THETA (2 bytes, 360/2^16 deg,
  clockwise from North);
* I048/070 Mode 3/A code: 12 bits (four octal digits) with the V, G and L flags;
* I048/090 flight level: 14 bits two's complement, 1/4 FL, with V and G.

Every other item of the UAP is skipped by its length (fixed, extended with FX, compound,
repetitive or explicit), so records holding them decode too. :func:`encode_cat048` is the
project's encoder (the same items; plots for replay and the tests), round-trip tested and
checked against the ``asterix-decoder`` package in the tests.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.io.table import InputError

FloatArray = NDArray[np.float64]

__all__ = [
    "Cat048", "AsterixError", "cat048_plots", "decode_cat048", "encode_cat048", "read_cat048",
    "NM_M",
]  # fmt: skip

NM_M = 1852.0
CAT = 48
_RHO = NM_M / 256.0  # m per LSB
_THETA = 360.0 / 65536.0  # deg per LSB
_TOD = 1.0 / 128.0  # s per LSB
DAY_S = 86400.0

# item lengths by FRN (1-based) of the CAT048 UAP: an int = fixed length, or a kind
_FX, _C130, _C120, _R250, _EXPL = "fx", "c130", "c120", "r250", "expl"
_UAP: dict[int, int | str] = {
    1: 2, 2: 3, 3: _FX, 4: 4, 5: 2, 6: 2, 7: _C130,  # 010 140 020 040 070 090 130
    8: 3, 9: 6, 10: _R250, 11: 2, 12: 4, 13: 4, 14: _FX,  # 220 240 250 161 042 200 170
    15: 4, 16: _FX, 17: 2, 18: 4, 19: 2, 20: _C120, 21: 2,  # 210 030 080 100 110 120 230
    22: 7, 23: 1, 24: 2, 25: 1, 26: 2, 27: _EXPL, 28: _EXPL,  # 260 055 050 065 060 SP RE
}  # fmt: skip


class AsterixError(ValueError):
    """A malformed data block or record (the message says where)."""


@dataclass(frozen=True)
class Cat048:
    """Target reports of CAT048 records (one entry per record with I040).

    Attributes
    ----------
    sac, sic : (N,) int -- data source (-1 absent)
    time_of_day_s : (N,) s since midnight UTC (NaN absent)
    range_m : (N,) slant range RHO, m
    azimuth : (N,) rad, clockwise from North, [0, 2 pi)
    mode3a : (N,) int -- the 12-bit code (print with ``oct``), -1 absent
    flight_level : (N,) FL (hundreds of feet), NaN absent
    """

    sac: NDArray[np.int64]
    sic: NDArray[np.int64]
    time_of_day_s: FloatArray
    range_m: FloatArray
    azimuth: FloatArray
    mode3a: NDArray[np.int64]
    flight_level: FloatArray

    def __len__(self) -> int:
        return int(self.range_m.size)


def _fx_len(buf: bytes, p: int) -> int:
    """Length of an item extended by FX bits starting at ``p``."""
    n = 1
    while buf[p + n - 1] & 1:
        n += 1
    return n


def _item_len(buf: bytes, p: int, kind: int | str) -> int:
    if isinstance(kind, int):
        return kind
    if kind == _FX:
        return _fx_len(buf, p)
    if kind == _EXPL:
        return buf[p]
    if kind == _R250:
        return 1 + 8 * buf[p]
    if kind == _C130:  # primary subfield (7 flags + FX), each subfield 1 byte
        n = _fx_len(buf, p)
        bits = sum(bin(buf[p + k] >> 1).count("1") for k in range(n))
        return n + bits
    # _C120: subfield 1 (CAL) 2 bytes, subfield 2 (RDS) 1 + 6 * REP
    n = _fx_len(buf, p)
    size = n
    if buf[p] & 0x80:
        size += 2
    if buf[p] & 0x40:
        size += 1 + 6 * buf[p + size]
    return size


def _records(block: bytes, rows: list[tuple], where: str) -> None:
    p = 3
    while p < len(block):
        start = p
        fspec = []
        while True:
            if p >= len(block):
                raise AsterixError(f"{where}: record at byte {start}: FSPEC cut short")
            fspec.append(block[p])
            p += 1
            if not fspec[-1] & 1:
                break
        sac = sic = mode = -1
        tod = rho = theta = fl = math.nan
        for k, byte in enumerate(fspec):
            for bit in range(7):
                if not byte & (0x80 >> bit):
                    continue
                frn = 7 * k + bit + 1
                kind = _UAP.get(frn)
                if kind is None:
                    raise AsterixError(f"{where}: record at byte {start}: no item FRN {frn}")
                try:
                    n = _item_len(block, p, kind)
                except IndexError:
                    n = len(block)
                if n <= 0 or p + n > len(block):
                    raise AsterixError(f"{where}: record at byte {start}: item FRN {frn} cut")
                it = block[p : p + n]
                if frn == 1:
                    sac, sic = it[0], it[1]
                elif frn == 2:
                    tod = int.from_bytes(it, "big") * _TOD
                elif frn == 4:
                    r, th = struct.unpack(">HH", it)
                    rho, theta = r * _RHO, math.radians(th * _THETA)
                elif frn == 5:
                    mode = int.from_bytes(it, "big") & 0x0FFF
                elif frn == 6:
                    v = int.from_bytes(it, "big") & 0x3FFF
                    fl = (v - 0x4000 if v & 0x2000 else v) / 4.0
                p += n
        if rho == rho:
            rows.append((sac, sic, tod, rho, theta, mode, fl))


def decode_cat048(data: bytes, where: str = "data") -> Cat048:
    """Decode CAT048 data blocks (records without a measured position are skipped).

    Raises
    ------
    AsterixError
        A block of another category, a length that does not fit, a record cut short.
    """
    rows: list[tuple] = []
    p = 0
    while p < len(data):
        if len(data) - p < 3:
            raise AsterixError(f"{where}: byte {p}: data block header cut short")
        cat, length = data[p], int.from_bytes(data[p + 1 : p + 3], "big")
        if cat != CAT:
            raise AsterixError(f"{where}: byte {p}: category {cat}, expected 48")
        if length < 3 or p + length > len(data):
            raise AsterixError(f"{where}: byte {p}: data block length {length} does not fit")
        _records(data[p : p + length], rows, f"{where}: block at byte {p}")
        p += length
    a = np.array(rows, dtype=float).reshape(-1, 7)
    return Cat048(
        a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), a[:, 2], a[:, 3], a[:, 4],
        a[:, 5].astype(np.int64), a[:, 6],
    )  # fmt: skip


def encode_cat048(
    time_of_day_s: ArrayLike,
    range_m: ArrayLike,
    azimuth: ArrayLike,
    sac: int = 0,
    sic: int = 1,
    mode3a: ArrayLike | None = None,
    flight_level: ArrayLike | None = None,
    max_block: int = 1400,
) -> list[bytes]:
    """CAT048 data blocks of plots (each at most ``max_block`` bytes: one UDP datagram).

    Parameters
    ----------
    time_of_day_s : (N,) s since midnight UTC, [0, 86400)
    range_m : (N,) m, [0, 256 NM)
    azimuth : (N,) rad clockwise from North
    sac, sic : data source
    mode3a : (N,) 12-bit codes, -1 = absent (optional)
    flight_level : (N,) FL, NaN = absent (optional)

    Values are rounded to the items' resolutions (1/128 s, 1/256 NM, 360/2^16 deg,
    1/4 FL). Records carry I010, I140, I020 (a primary-radar plot), I040 and, where given,
    I070 and I090.
    """
    t = np.asarray(time_of_day_s, dtype=float)
    r = np.asarray(range_m, dtype=float)
    az = np.asarray(azimuth, dtype=float)
    n = t.size
    m3 = np.full(n, -1) if mode3a is None else np.asarray(mode3a, dtype=np.int64)
    fls = np.full(n, np.nan) if flight_level is None else np.asarray(flight_level, dtype=float)
    if not (np.all((t >= 0) & (t < DAY_S)) and np.all((r >= 0) & (r < 256 * NM_M))):
        raise ValueError("time of day must be in [0, 86400) s and range in [0, 256 NM)")
    blocks, body = [], b""
    for k in range(n):
        tod = int(round(t[k] / _TOD)) % (1 << 24)
        rho = min(int(round(r[k] / _RHO)), 0xFFFF)
        th = int(round((math.degrees(az[k]) % 360.0) / _THETA)) % 65536
        f0 = 0b11110000  # 010, 140, 020, 040
        items = (
            bytes([sac, sic]) + tod.to_bytes(3, "big") + bytes([0x20]) + struct.pack(">HH", rho, th)
        )  # 020: TYP = 001, single PSR detection
        if m3[k] >= 0:
            f0 |= 0b00001000
            items += (int(m3[k]) & 0x0FFF).to_bytes(2, "big")
        if fls[k] == fls[k]:
            f0 |= 0b00000100
            items += (int(round(fls[k] * 4)) & 0x3FFF).to_bytes(2, "big")
        rec = bytes([f0]) + items
        if body and 3 + len(body) + len(rec) > max_block:
            blocks.append(bytes([CAT]) + (3 + len(body)).to_bytes(2, "big") + body)
            body = b""
        body += rec
    if body:
        blocks.append(bytes([CAT]) + (3 + len(body)).to_bytes(2, "big") + body)
    return blocks


def read_cat048(path: str | Path) -> Cat048:
    """Decode a file of concatenated CAT048 data blocks (``.ast``).

    Raises
    ------
    InputError
        Naming the file and the byte of the first malformed block or record.
    """
    try:
        return decode_cat048(Path(path).read_bytes(), str(path))
    except AsterixError as exc:
        raise InputError(str(exc)) from None


def cat048_plots(c: Cat048, where: str = "data") -> Any:
    """:class:`~seatrack.filters.base.Plots` of target reports (2-D: range, azimuth; the
    sensor at the origin): ``t`` = time of day (s), unwrapped across midnight (a step back
    of more than 12 h is the next day); ``line`` = the record's number (1, 2, ...).

    Raises
    ------
    InputError
        A record without time of day, or times going back.
    """
    from seatrack.filters.base import Plots

    t = c.time_of_day_s.copy()
    if np.isnan(t).any():
        k = int(np.flatnonzero(np.isnan(t))[0]) + 1
        raise InputError(f"{where}, record {k}: no time of day (I048/140)")
    day = np.cumsum(np.r_[0.0, np.diff(t) < -DAY_S / 2]) * DAY_S
    t = t + day
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        raise InputError(f"{where}, record {back[0] + 2}: time of day goes back")
    return Plots(t, c.range_m, c.azimuth, line=np.arange(1, t.size + 1, dtype=np.int64))
