"""Raw NMEA ``!AIVDM`` / ``!AIVDO`` sentences with timestamps -> AIS report rows.

Each line holds one NMEA 0183 sentence with its time, given either as

* an NMEA 4.10 tag block ``\\c:1509502436*hh\\!AIVDM,...`` (``c`` = UNIX time in seconds;
  values above 1e11 are taken as milliseconds, as some receivers write them), or
* a leading timestamp, separated by blanks, ``,`` or ``;``: ISO 8601
  (``2022-11-01T09:35:36Z``), DMA style (``01/11/2022 09:35:36``) or epoch seconds.

Sentence checksums (and tag-block checksums) are verified here; a line with a wrong one is
rejected as ``"bad checksum"``, a sentence without its ``*hh`` checksum or with fewer than
seven fields (cut mid-payload) as ``"truncated sentence"``. Multi-sentence messages are
assembled per (talker, channel, sequence id, fragment count) and decoded with ``pyais``; the
message time is the first fragment's (a later fragment's if only that one carries it) and
its line is the first fragment's line. Position reports (types 1, 2, 3, 18, 19, 27) become
rows; other message types and other NMEA sentences are counted in
:attr:`~seatrack.io.ais.reports.AisReports.skipped` by kind. Files are read line by line by
:mod:`seatrack.io.ais.lines`, which gives blank and foreign lines (CSV rows without a
header, text) a rejected row of their own and reads CSV rows that follow a CSV header in the
same file."""

from __future__ import annotations

import re
from dataclasses import dataclass
from dataclasses import field
from functools import reduce
from operator import xor
from typing import Any

import numpy as np

from seatrack.io.ais.reports import parse_times

__all__ = [
    "POSITION_TYPES",
    "NmeaRow",
    "checksum_ok",
    "is_nmea_line",
    "nmea_checksum",
    "nmea_rows",
    "parse_tag_time",
]

#: AIS message types that carry a position report
POSITION_TYPES = frozenset({1, 2, 3, 18, 19, 27})

_TAG = re.compile(rb"^\\([^\\]*)\\")
_SENTENCE_START = re.compile(rb"[!$\\]")


def nmea_checksum(body: bytes) -> int:
    """XOR of all bytes of ``body`` (the text between ``!``/``$``/``\\`` and ``*``)."""
    return reduce(xor, body, 0)


def checksum_ok(text: bytes) -> bool:
    """True if ``text`` = ``BODY*HH`` (without the leading delimiter) has a valid checksum."""
    star = text.rfind(b"*")
    if star < 0 or len(text) < star + 3:
        return False
    try:
        want = int(text[star + 1 : star + 3], 16)
    except ValueError:
        return False
    return nmea_checksum(text[:star]) == want


def is_nmea_line(line: bytes) -> bool:
    """True if ``line`` (stripped) is an NMEA sentence, maybe after a short time prefix."""
    m = _SENTENCE_START.search(line)
    if m is None or m.start() > 40:
        return False
    return m.start() == 0 or b"VDM" in line or b"VDO" in line


@dataclass
class _Pending:
    line: int
    time: float
    parts: dict[int, bytes] = field(default_factory=dict)
    lines: list[int] = field(default_factory=list)


def parse_tag_time(tag: bytes) -> float | None:
    """Unix time (s) of a tag block's ``c:`` field (ms above 1e11), None if absent or bad."""
    body = tag.split(b"*", 1)[0]
    for item in body.split(b","):
        if item.startswith(b"c:"):
            try:
                c = float(item[2:])
            except ValueError:
                return None
            return c / 1000.0 if c > 1e11 else c
    return None


def _time_of(prefix: bytes, tag: bytes | None) -> tuple[float, bool]:
    """(epoch seconds or NaN, tag-block checksum ok)."""
    t = float("nan")
    ok = True
    if tag is not None:
        ok = checksum_ok(tag)
        c = parse_tag_time(tag)
        if c is not None:
            t = c
    if np.isnan(t) and prefix:
        txt = prefix.decode("ascii", "replace").strip().rstrip(",;").strip()
        if txt:
            t = float(parse_times(np.array([txt]))[0])
    return t, ok


#: one row: (line, mmsi, time, lat, lon, sog, cog, heading, reject reason)
NmeaRow = tuple[int, int, float, float, float, float, float, float, str]


def nmea_rows(items: list[tuple[int, bytes]]) -> tuple[list[NmeaRow], dict[str, int]]:
    """Rows of NMEA lines ``(line number, stripped bytes)`` in line order (see the module
    docstring) and the counts of the lines that hold no report, by kind."""
    from pyais.exceptions import AISBaseException
    from pyais.messages import AISSentence
    from pyais.messages import NMEASentenceFactory

    rows: list[NmeaRow] = []
    skipped: dict[str, int] = {}
    pending: dict[tuple, _Pending] = {}

    def skip(kind: str, n: int = 1) -> None:
        skipped[kind] = skipped.get(kind, 0) + n

    def reject(line: int, t: float, reason: str) -> None:
        nan = float("nan")
        rows.append((line, -1, t, nan, nan, nan, nan, nan, reason))

    def emit(line: int, t: float, parts: list[bytes]) -> None:
        try:
            sentences = [NMEASentenceFactory.produce(b) for b in parts]
            sent = AISSentence.assemble_from_iterable(sentences)  # type: ignore[arg-type]
            msg: Any = sent.decode()
        except (AISBaseException, ValueError, IndexError, TypeError):
            reject(line, t, "undecodable message")
            return
        mtype = int(msg.msg_type)
        if mtype not in POSITION_TYPES:
            skip(f"not a position report (type {mtype})")
            return
        try:  # a payload too short for its type decodes with None fields
            lat, lon = float(msg.lat), float(msg.lon)
            sog, cog = float(msg.speed), float(msg.course)
            hdg = float(getattr(msg, "heading", float("nan")))
        except (TypeError, ValueError, AttributeError):
            reject(line, t, "undecodable message")
            return
        if mtype == 27:  # 6-bit knots (63 = n/a), 9-bit degrees (511 = n/a)
            sog = float("nan") if sog >= 63 else sog
        rows.append((line, int(msg.mmsi), t, lat, lon, sog, cog, hdg, ""))

    for i, line in items:
        start = _SENTENCE_START.search(line)
        if start is None:
            reject(i, float("nan"), "not an AIS line")
            continue
        prefix, rest = line[: start.start()], line[start.start() :]
        tag = None
        m = _TAG.match(rest)
        if m:
            tag = m.group(1)
            rest = rest[m.end() :]
        t, tag_ok = _time_of(prefix, tag)
        if not rest.startswith((b"!", b"$")):
            reject(i, t, "not an AIS line")
            continue
        fields = rest.split(b",")
        if not rest.startswith(b"!") or fields[0][3:6] not in (b"VDM", b"VDO"):
            skip("not an AIS sentence")
            continue
        if len(fields) < 7 or b"*" not in fields[-1]:
            reject(i, t, "truncated sentence")
            continue
        if not tag_ok or not checksum_ok(rest[1:]):
            reject(i, t, "bad checksum")
            continue
        try:
            cnt, num = int(fields[1]), int(fields[2])
        except ValueError:
            reject(i, t, "undecodable message")
            continue
        if cnt == 1:
            if np.isnan(t):
                reject(i, t, "unparsable time")
                continue
            emit(i, t, [rest])
            continue
        key = (fields[0], fields[4], fields[3], cnt)
        pend = pending.get(key)
        if num == 1:
            if pend is not None:  # a new message started before the old one completed
                for ln in pend.lines:
                    reject(ln, pend.time, "incomplete multi-sentence message")
            pend = pending[key] = _Pending(i, t)
        elif pend is None or num in pend.parts or num != max(pend.parts) + 1:
            reject(i, t, "incomplete multi-sentence message")
            continue
        pend.parts[num] = rest
        pend.lines.append(i)
        if np.isnan(pend.time) and not np.isnan(t):
            pend.time = t
        if num == cnt:
            del pending[key]
            skip("continuation fragment", len(pend.lines) - 1)
            if np.isnan(pend.time):
                reject(pend.line, pend.time, "unparsable time")
                continue
            emit(pend.line, pend.time, [pend.parts[k] for k in sorted(pend.parts)])
    for pend in pending.values():
        for ln in pend.lines:
            reject(ln, pend.time, "incomplete multi-sentence message")

    rows.sort(key=lambda r: r[0])
    return rows, skipped
