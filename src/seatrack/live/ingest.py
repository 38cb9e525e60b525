"""AIS lines of a burst to position reports: the compiled fast path for the common line,
the NMEA assembler and decoder for every other one, in arrival order.

:func:`read_lines` runs the lines of one chunk through
:func:`~seatrack.live.nmea_fast.scan_lines`; a marked line (a one-sentence class A
report) goes straight to the duplicate filter and the time check, every other line to
:class:`~seatrack.live.nmea.Assembler` and, once its message is complete, to
:func:`read_messages` (duplicates, :func:`~seatrack.live.nmea.decode_message`). Both
append the position reports to one :class:`Positions`, in the order of their lines, and
count what they drop (:class:`~seatrack.live.counters.Counters`); the caller folds the
positions into the tracker and counts them.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from seatrack.io.ais.reports import TIME_MAX
from seatrack.io.ais.reports import TIME_MIN
from seatrack.live.counters import Counters
from seatrack.live.nmea import Assembler
from seatrack.live.nmea import Duplicates
from seatrack.live.nmea import Message
from seatrack.live.nmea import decode_message
from seatrack.live.nmea_fast import scan_lines

__all__ = ["Positions", "read_lines", "read_messages"]

#: the columns of :class:`Positions`: MMSI, message time (Unix s), lat, lon (deg), SOG
#: (kn), COG (deg), receipt time (Unix s) and its ``time.perf_counter()`` (s)
COLUMNS = ("mmsi", "t", "lat", "lon", "sog_kn", "cog_deg", "received_s", "perf_s")


class Positions:
    """Position reports gathered in arrival order: blocks of arrays (from the fast path)
    and single rows (from the assembler), with each report's source name."""

    def __init__(self) -> None:
        self._blocks: list[list[NDArray]] = []
        self._rows: list[tuple] = []
        self.sources: list[str] = []

    def __len__(self) -> int:
        return len(self.sources)

    def _flush_rows(self) -> None:
        if self._rows:
            cols = list(zip(*self._rows, strict=True))
            self._blocks.append([np.array(c, dtype=float) for c in cols])
            self._rows = []

    def add_row(self, row: tuple, source: str) -> None:
        """One report: the values of :data:`COLUMNS`."""
        self._rows.append(row)
        self.sources.append(source)

    def add_block(self, cols: list[NDArray], source: str) -> None:
        """Reports of one source as arrays in the order of :data:`COLUMNS`."""
        self._flush_rows()
        self._blocks.append(cols)
        self.sources.extend([source] * len(cols[0]))

    def columns(self) -> dict[str, NDArray]:
        """All reports as arrays by column name (``mmsi`` as int64)."""
        self._flush_rows()
        if not self._blocks:
            cols = {c: np.zeros(0) for c in COLUMNS}
        else:
            cols = {c: np.concatenate([b[k] for b in self._blocks]) for k, c in enumerate(COLUMNS)}
        cols["mmsi"] = cols["mmsi"].astype(np.int64)
        return cols


def read_messages(
    messages: list[Message], duplicates: Duplicates, counters: Counters, pos: Positions,
    on_name: Callable[[int, str], None],
) -> None:  # fmt: skip
    """Count rejections and duplicates, decode the rest: position reports to ``pos``,
    other decoded messages counted (``on_name(mmsi, name)`` for a vessel name)."""
    cnt = counters
    for m in messages:
        if m.reject:
            cnt.reject(m.reject)
            continue
        if duplicates.seen(m.payload_key, m.received_s):
            cnt.received += 1
            cnt.duplicate += 1
            continue
        d = decode_message(m.sentences)
        if isinstance(d, str):
            cnt.reject(d)
        elif not TIME_MIN <= m.time_s < TIME_MAX:
            cnt.reject("time out of range")
        elif d.is_position:
            row = (d.mmsi, m.time_s, d.lat, d.lon, d.sog_kn, d.cog_deg, m.received_s, m.perf_s)
            pos.add_row(row, m.source)
        else:
            if d.name:
                on_name(d.mmsi, d.name)
            cnt.received += 1
            cnt.decoded += 1


def read_lines(
    lines: list[bytes], source: str, received_s: float, perf_s: float, assembler: Assembler,
    duplicates: Duplicates, counters: Counters, pos: Positions,
    on_name: Callable[[int, str], None],
) -> None:  # fmt: skip
    """The AIS lines of one chunk (see the module docstring)."""
    n = len(lines)
    if n == 0:
        return
    buf = b"\n".join(lines)
    lens = np.fromiter(map(len, lines), np.int64, n)
    ends = np.cumsum(lens + 1) - 1
    fast = scan_lines(buf, ends - lens, ends)
    ok = fast.ok.tolist()
    payload = fast.payload.tolist()
    seen = duplicates.seen
    cnt = counters
    keep: list[int] = []

    def flush() -> None:
        idx = np.array(keep, dtype=np.intp)
        keep.clear()
        t = fast.t[idx]
        t[np.isnan(t)] = received_s
        good = (t >= TIME_MIN) & (t < TIME_MAX)
        if not good.all():
            cnt.reject("time out of range", int((~good).sum()))
            idx, t = idx[good], t[good]
        m = idx.size
        if m:
            block = [fast.mmsi[idx].astype(float), t, fast.lat[idx], fast.lon[idx],
                     fast.sog_kn[idx], fast.cog_deg[idx], np.full(m, received_s),
                     np.full(m, perf_s)]  # fmt: skip
            pos.add_block(block, source)

    for k in range(n):
        if ok[k]:
            p0, p1 = payload[k]
            if seen(buf[p0:p1], received_s):
                cnt.received += 1
                cnt.duplicate += 1
            else:
                keep.append(k)
            continue
        if keep:
            flush()
        messages = assembler.push(lines[k], source, received_s, perf_s)
        if messages:
            read_messages(messages, duplicates, counters, pos, on_name)
    if keep:
        flush()
