"""The compiled fast path marks only lines the assembler and decoder accept, with their
values bit for bit; it marks the usual class A lines and leaves every other one."""

from __future__ import annotations

import numpy as np
from pyais.encode import encode_dict

from seatrack.live.nmea import Assembler
from seatrack.live.nmea import decode_message
from seatrack.live.nmea import tag_block
from seatrack.live.nmea_fast import scan_lines

RECEIVED = 1.8e9


def scan(lines: list[bytes]):
    buf = b"\n".join(lines)
    lens = np.array([len(x) for x in lines], dtype=np.int64)
    ends = np.cumsum(lens + 1) - 1
    return buf, scan_lines(buf, ends - lens, ends)


def class_a(rng, k: int) -> bytes:
    data = {
        "type": int(rng.integers(1, 4)), "mmsi": int(rng.integers(0, 1 << 30)),
        "lat": float(rng.uniform(-91, 91)), "lon": float(rng.uniform(-181, 181)),
        "speed": float(rng.integers(0, 1024)) / 10, "course": float(rng.integers(0, 4096)) / 10,
    }  # fmt: skip
    if k % 40 == 0:
        data.update(lat=91.0, lon=181.0)
    (line,) = encode_dict(data, "AI", "VDM" if k % 2 else "VDO", "AB"[k % 2])
    return line.encode()


def variants(rng, line: bytes, k: int) -> list[bytes]:
    """The line with tag blocks of several kinds, and damaged copies."""
    t = 1.7e9 + k + (0.123 if k % 3 else 0.0)
    out = [line, tag_block(t) + line, tag_block(t, "rx1") + line, b"  " + line + b"\r"]
    out.append(b"\\s:rx2,c:1700000001*" + b"00\\" + line)  # bad tag checksum
    out.append(b"\\c:17e8*" + b"%02X" % (0x63 ^ 0x3A ^ 0x31 ^ 0x37 ^ 0x65 ^ 0x38) + b"\\" + line)
    out.append(line[:-2] + b"ZZ")  # checksum not hexadecimal
    out.append(line.replace(b",0*", b",2*"))  # fill bits (checksum now wrong)
    b = bytearray(line)
    b[int(rng.integers(0, len(b)))] = int(rng.integers(0, 256))  # one byte damaged
    out.append(bytes(b))
    return out


def test_marked_lines_are_accepted_with_the_same_values():
    rng = np.random.default_rng(4)
    lines: list[bytes] = []
    for k in range(300):
        lines += variants(rng, class_a(rng, k), k)
    (b18,) = encode_dict({"type": 18, "mmsi": 211234567, "lat": 54.0, "lon": 10.5},
                         "AI", "VDM", "B")  # fmt: skip
    lines += [
        b18.encode(), b"", b"hello", b"\\c:1700000000*00\\",
        b"!AIVDM,2,1,4,A,55O0W7`00001L@gCWGA2uItLth@DqtL5@F22220j1h742t0Ht0000000,0*08",
    ]  # fmt: skip
    buf, fast = scan(lines)
    assert fast.ok.sum() > 600  # the plain, tagged and padded copies of most reports
    for k, line in enumerate(lines):
        msgs = Assembler().push(line, "rx", RECEIVED, 0.0)
        if not fast.ok[k]:
            continue
        (m,) = msgs
        assert not m.reject, (line, m.reject)
        d = decode_message(m.sentences)
        assert not isinstance(d, str), (line, d)
        t = RECEIVED if np.isnan(fast.t[k]) else fast.t[k]
        assert t == m.time_s
        assert (fast.mmsi[k], fast.lat[k], fast.lon[k]) == (d.mmsi, d.lat, d.lon)
        np.testing.assert_array_equal([fast.sog_kn[k], fast.cog_deg[k]], [d.sog_kn, d.cog_deg])
        p0, p1 = fast.payload[k]
        assert buf[p0:p1] == m.payload_key


def test_every_plain_report_is_marked_and_others_are_not():
    rng = np.random.default_rng(5)
    lines = []
    for k in range(200):
        data = {
            "type": 1, "mmsi": int(rng.integers(1, 999_999_999)),
            "lat": float(rng.uniform(-90, 90)), "lon": float(rng.uniform(-180, 180)),
        }  # fmt: skip
        (line,) = encode_dict(data, "AI", "VDM", "A")
        lines.append(tag_block(1.7e9 + k / 7, "rx") + line.encode())
    other = [
        b"!AIVDM,2,2,4,A,000000000000000,2*20",  # a second fragment
        lines[0][:-1],  # truncated checksum
        lines[1].replace(b"VDM", b"VDX"),
        lines[2].replace(b",1,1,", b",1,01,"),
    ]  # fmt: skip
    _, fast = scan(lines + other)
    assert fast.ok[:200].all() and not fast.ok[200:].any()
    assert scan_lines(b"", np.zeros(0, np.int64), np.zeros(0, np.int64)).ok.size == 0
