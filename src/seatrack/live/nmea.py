"""NMEA 0183 sentences of a live AIS stream: checks, NMEA 4.10 tag blocks, multi-part
reassembly across datagrams and TCP reads, duplicates from several receivers.

A live line is one sentence, optionally preceded by a tag block ``\\c:1509502436,s:rx1*hh\\``
(``c`` = Unix time in seconds, milliseconds above 1e11 as some receivers write them).
:class:`Assembler` takes lines one at a time, from any number of sources, and returns for
each line either nothing (a fragment waiting for the rest of its message) or one
:class:`Message` (the complete message, or a rejection with its reason). Fragments are
grouped by ``(source, talker, channel, sequence id, fragment count)``, so parts of one
message that arrive in different datagrams or TCP reads are joined, and two receivers'
fragments never mix; a fragment waiting longer than ``fragment_timeout_s`` (receipt time)
is rejected as ``"incomplete multi-sentence message"``.

:class:`Duplicates` recognises the same message received by several receivers (or
repeated by one): the key is its armoured payload (all fragments), remembered for
``window_s`` seconds of receipt time.
"""

from __future__ import annotations

import binascii
import math
import re
from collections import OrderedDict
from dataclasses import dataclass
from dataclasses import field
from typing import Any

from seatrack.io.ais.nmea import POSITION_TYPES
from seatrack.io.ais.nmea import checksum_ok
from seatrack.io.ais.nmea import nmea_checksum
from seatrack.io.ais.nmea import parse_tag_time
from seatrack.io.ais.reports import COG_NOT_AVAILABLE_DEG
from seatrack.io.ais.reports import MMSI_MAX
from seatrack.io.ais.reports import SOG_NOT_AVAILABLE_KN

__all__ = [
    "Assembler", "Decoded", "Duplicates", "Message", "checksum_ok", "decode_message",
    "encode_report", "parse_tag_time", "payload_int", "tag_block",
]  # fmt: skip

_TAG = re.compile(rb"^\\([^\\]*)\\")


@dataclass
class Message:
    """A complete AIS message (``sentences``: its fragments in order) or a rejected line.

    ``time_s`` is the tag block's ``c:`` time when present (any fragment's, the first one
    that has it), else the receipt time of the first fragment; ``received_s`` is that
    receipt time (Unix s) and ``perf_s`` its ``time.perf_counter()`` (latency)."""

    source: str
    time_s: float
    received_s: float
    perf_s: float
    sentences: list[bytes] = field(default_factory=list)
    reject: str = ""

    @property
    def payload_key(self) -> bytes:
        """The armoured payload of all fragments (the duplicate key)."""
        return b"|".join(s.split(b",")[5] for s in self.sentences)


@dataclass
class _Pending:
    msg: Message
    parts: dict[int, bytes]
    tag_time: bool


class Assembler:
    """Incremental NMEA checks and multi-part reassembly (see the module docstring).

    Parameters
    ----------
    fragment_timeout_s : float
        A message whose fragments have not all arrived this long (receipt time, s) after
        its first one is rejected.
    """

    def __init__(self, fragment_timeout_s: float = 10.0) -> None:
        self.fragment_timeout_s = fragment_timeout_s
        self._pending: OrderedDict[tuple, _Pending] = OrderedDict()

    @property
    def pending(self) -> int:
        """Messages waiting for fragments."""
        return len(self._pending)

    def expire(self, now_s: float) -> list[Message]:
        """Reject the messages whose first fragment arrived more than the timeout ago."""
        out = []
        while self._pending:
            key, pend = next(iter(self._pending.items()))
            if now_s - pend.msg.received_s <= self.fragment_timeout_s:
                break
            del self._pending[key]
            pend.msg.reject = "incomplete multi-sentence message"
            out.append(pend.msg)
        return out

    def push(self, line: bytes, source: str, received_s: float, perf_s: float) -> list[Message]:
        """Feed one line (stripped of line ends); returns the messages it completes or
        rejects (several when it also ends an incomplete message)."""
        line = line.strip()

        def rejected(reason: str, t: float = received_s) -> list[Message]:
            return [Message(source, t, received_s, perf_s, [line], reason)]

        if not line:
            return rejected("blank line")
        tag_t: float | None = None
        rest = line
        m = _TAG.match(line)
        if m:
            tag = m.group(1)
            if not checksum_ok(tag):
                return rejected("bad checksum")
            tag_t = parse_tag_time(tag)
            rest = line[m.end() :]
        t = received_s if tag_t is None else tag_t
        if not rest.startswith(b"!"):
            return rejected("not an AIS line", t)
        fields = rest.split(b",")
        if fields[0][3:6] not in (b"VDM", b"VDO"):
            return rejected("not an AIS line", t)
        if len(fields) < 7 or b"*" not in fields[-1]:
            return rejected("truncated sentence", t)
        if not checksum_ok(rest[1:]):
            return rejected("bad checksum", t)
        try:
            cnt, num = int(fields[1]), int(fields[2])
        except ValueError:
            return rejected("undecodable message", t)
        if not 1 <= num <= cnt <= 9:
            return rejected("undecodable message", t)
        if cnt == 1:
            return [Message(source, t, received_s, perf_s, [rest])]
        key = (source, fields[0], fields[4], fields[3], cnt)
        pend = self._pending.get(key)
        out: list[Message] = []
        if num == 1:
            if pend is not None:  # a new message started before the old one completed
                pend.msg.reject = "incomplete multi-sentence message"
                out.append(pend.msg)
            msg = Message(source, t, received_s, perf_s)
            pend = _Pending(msg, {}, tag_t is not None)
            self._pending[key] = pend
        elif pend is None or num in pend.parts or num != max(pend.parts) + 1:
            return rejected("incomplete multi-sentence message", t)
        elif not pend.tag_time and tag_t is not None:
            pend.msg.time_s, pend.tag_time = tag_t, True
        pend.parts[num] = rest
        if num == cnt:
            del self._pending[key]
            pend.msg.sentences = [pend.parts[k] for k in sorted(pend.parts)]
            out.append(pend.msg)
        return out


class Duplicates:
    """The same message seen again within ``window_s`` seconds of receipt time.

    Keys are remembered with their first receipt time in dictionaries of bytes -> float,
    one per quarter of the window (the newest takes new keys; one whose keys are all older
    than the window is dropped whole). Such a dictionary holds no object the garbage
    collector follows, so the 200,000 keys of 10 s at 20,000 msg/s cost a full collection
    nothing (a set and two deques of them cost it about a million references to visit).
    """

    def __init__(self, window_s: float = 10.0) -> None:
        self.window_s = window_s
        self._span = window_s / 4.0 if window_s > 0 else 1.0  # receipt time per bucket (s)
        self._buckets: list[dict[bytes, float]] = [{}]  # oldest first
        self._last: list[float] = [-math.inf]  # latest receipt time in each bucket
        self._start = -math.inf  # receipt time of the newest bucket's first key

    def __len__(self) -> int:
        """Keys remembered (some may be older than the window until their bucket goes)."""
        return sum(map(len, self._buckets))

    def seen(self, key: bytes, now_s: float) -> bool:
        """True if ``key`` was seen within the window (else it is remembered now)."""
        if now_s - self._start >= self._span:
            self._rotate(now_s)
        buckets = self._buckets
        for k in range(len(buckets) - 1, -1, -1):
            t = buckets[k].get(key)
            if t is not None:
                if now_s - t <= self.window_s:
                    return True
                break  # remembered, but before the window: seen anew now
        buckets[-1][key] = now_s
        self._last[-1] = max(self._last[-1], now_s)
        return False

    def _rotate(self, now_s: float) -> None:
        """A new bucket from ``now_s``; the buckets whose keys all left the window go."""
        keep = [k for k, last in enumerate(self._last) if now_s - last <= self.window_s]
        self._buckets = [self._buckets[k] for k in keep] + [{}]
        self._last = [self._last[k] for k in keep] + [-math.inf]
        self._start = now_s


@dataclass
class Decoded:
    """A decoded AIS message: its type and MMSI, and for a position report (types 1, 2,
    3, 18, 19, 27) lat/lon (deg), SOG (kn) and COG (deg) with the "not available" codes
    as NaN; for a static report (types 5, 24) the vessel name."""

    msg_type: int
    mmsi: int
    lat: float = float("nan")
    lon: float = float("nan")
    sog_kn: float = float("nan")
    cog_deg: float = float("nan")
    name: str = ""

    @property
    def is_position(self) -> bool:
        return self.msg_type in POSITION_TYPES


#: the armoured payload characters (ITU-R M.1371 / IEC 61162-1: ``c - 48`` below 88, else
#: ``c - 56``) translated to the base64 characters of the same 6-bit values; every other
#: byte to ``!``, which the base64 decoder rejects
_B64 = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/"
_TO_B64 = bytes(_B64[c - 48 if c < 88 else c - 56] if 48 <= c < 120 else 33 for c in range(256))


def payload_int(payload: bytes) -> int | None:
    """The bits of an armoured payload whose length is a multiple of 4 characters (24
    bits) as one integer (first bit most significant); None if a character is not a
    payload character. Decoded in C (``bytes.translate`` and base64), not per character."""
    try:
        return int.from_bytes(
            binascii.a2b_base64(payload.translate(_TO_B64), strict_mode=True), "big"
        )
    except binascii.Error:
        return None


def _class_a(sentence: bytes) -> tuple[int, int, float, float, float, float] | None:
    """``(type, mmsi, lat, lon, sog, cog)`` of a one-sentence type 1-3 report of 168 bits
    (the usual case), with pyais's scalings bit for bit (``lat = round(v * 5 / 3) / 1e6``
    in integers, SOG and COG ``v / 10``); None for anything else (pyais decodes it)."""
    fields = sentence.split(b",")
    payload = fields[5]
    if len(payload) != 28 or payload[:1] not in (b"1", b"2", b"3") or fields[6][:1] != b"0":
        return None
    v = payload_int(payload)
    if v is None:
        return None
    lon = (v >> 79) & 0xFFFFFFF
    lon = lon - 0x10000000 if lon & 0x8000000 else lon
    lat = (v >> 52) & 0x7FFFFFF
    lat = lat - 0x8000000 if lat & 0x4000000 else lat
    lat_deg, lon_deg = ((10 * lat + 3) // 6) / 1e6, ((10 * lon + 3) // 6) / 1e6
    sog, cog = ((v >> 108) & 1023) / 10.0, ((v >> 40) & 4095) / 10.0
    return v >> 162, (v >> 130) & 0x3FFFFFFF, lat_deg, lon_deg, sog, cog


def decode_message(sentences: list[bytes]) -> Decoded | str:
    """Decode a complete message (class A position reports directly, everything else with
    pyais); the reject reason (a label of :data:`seatrack.io.ais.REJECT_REASONS`) when it
    cannot be used."""
    fast = _class_a(sentences[0]) if len(sentences) == 1 else None
    if fast is not None:
        mtype, mmsi, lat, lon, sog, cog = fast
    else:
        from pyais.exceptions import AISBaseException
        from pyais.messages import AISSentence
        from pyais.messages import NMEASentenceFactory

        try:
            parts = [NMEASentenceFactory.produce(b) for b in sentences]
            msg: Any = AISSentence.assemble_from_iterable(parts).decode()  # type: ignore[arg-type]
            mtype, mmsi = int(msg.msg_type), int(msg.mmsi)
        except (AISBaseException, ValueError, IndexError, TypeError, AttributeError):
            return "undecodable message"
        if mtype in POSITION_TYPES:
            lat, lon = float(msg.lat), float(msg.lon)
            sog, cog = float(msg.speed), float(msg.course)
    if not 0 < mmsi <= MMSI_MAX:
        return "invalid mmsi"
    if mtype not in POSITION_TYPES:
        name = str(getattr(msg, "shipname", "") or "").strip(" @")
        return Decoded(mtype, mmsi, name=name)
    if lat == 91.0:
        return "lat not available (91)"
    if lon == 181.0:
        return "lon not available (181)"
    if not abs(lat) <= 90.0:
        return "lat out of range"
    if not abs(lon) <= 180.0:
        return "lon out of range"
    if mtype == 27 and sog >= 63:  # 6-bit knots (63 = n/a)
        sog = float("nan")
    if not 0 <= sog < SOG_NOT_AVAILABLE_KN - 1e-9:
        sog = float("nan")
    if not 0 <= cog < COG_NOT_AVAILABLE_DEG:
        cog = float("nan")
    return Decoded(mtype, mmsi, lat, lon, sog, cog)


def tag_block(t: float, source: str = "") -> bytes:
    """An NMEA 4.10 tag block with ``c:`` = ``t`` (Unix s, whole seconds, or ms when
    ``t`` has a fraction) and ``s:`` = ``source`` when given."""
    c = f"c:{int(round(t * 1000))}" if t != int(t) else f"c:{int(t)}"
    body = c + (f",s:{source}" if source else "")
    return f"\\{body}*{nmea_checksum(body.encode()):02X}\\".encode()


def encode_report(
    mmsi: int, t: float, lat: float, lon: float, sog_kn: float, cog_deg: float,
    channel: str = "A", seq_id: int | None = None, source: str = "",
) -> list[bytes]:  # fmt: skip
    """A class A position report (type 1) as ``!AIVDM`` sentences (pyais's encoder) with
    a tag block giving its time ``t`` (Unix s); NaN SOG/COG are sent as "not available"."""
    from pyais.encode import encode_dict

    data: dict[str, Any] = {
        "type": 1, "mmsi": int(mmsi), "lat": float(lat), "lon": float(lon),
        "speed": SOG_NOT_AVAILABLE_KN if sog_kn != sog_kn else float(sog_kn),
        "course": COG_NOT_AVAILABLE_DEG if cog_deg != cog_deg else float(cog_deg),
        "second": int(t) % 60,
    }  # fmt: skip
    lines = encode_dict(data, "AI", "VDM", channel, seq_id)
    tag = tag_block(t, source)
    return [tag + s.encode() for s in lines]
