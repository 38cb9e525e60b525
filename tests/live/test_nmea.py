"""Live NMEA: tag blocks, reassembly, duplicates, and the class A decoder against pyais."""

from __future__ import annotations

import numpy as np
from pyais import decode
from pyais.encode import encode_dict

from seatrack.io.ais.nmea import checksum_ok
from seatrack.live.nmea import Assembler
from seatrack.live.nmea import Duplicates
from seatrack.live.nmea import decode_message
from seatrack.live.nmea import parse_tag_time
from seatrack.live.nmea import payload_int
from seatrack.live.nmea import tag_block


def test_class_a_reports_decode_as_pyais_does():
    rng = np.random.default_rng(0)
    for k in range(400):
        data = {
            "type": int(rng.integers(1, 4)), "mmsi": int(rng.integers(1, 999_999_999)),
            "lat": float(rng.uniform(-90, 90)), "lon": float(rng.uniform(-180, 180)),
            "speed": float(rng.integers(0, 1023)) / 10, "course": float(rng.integers(0, 3600)) / 10,
        }  # fmt: skip
        if k % 50 == 0:
            data.update(lat=91.0, lon=181.0)
        (line,) = encode_dict(data, "AI", "VDM", "A")
        ref = decode(line)
        got = decode_message([line.encode()])
        if isinstance(got, str):
            assert got == "lat not available (91)" and ref.lat == 91.0
            continue
        assert (got.msg_type, got.mmsi) == (ref.msg_type, ref.mmsi)
        assert (got.lat, got.lon) == (ref.lat, ref.lon)  # bit for bit
        assert got.sog_kn == ref.speed or (np.isnan(got.sog_kn) and ref.speed >= 102.3)
        assert got.cog_deg == ref.course or (np.isnan(got.cog_deg) and ref.course >= 360)


def test_other_messages_go_to_pyais():
    (b18,) = encode_dict({"type": 18, "mmsi": 211234567, "lat": 54.0, "lon": 10.5,
                          "speed": 4.2, "course": 88.0}, "AI", "VDM", "B")  # fmt: skip
    d = decode_message([b18.encode()])
    assert d.msg_type == 18 and (d.lat, d.lon, d.sog_kn, d.cog_deg) == (54.0, 10.5, 4.2, 88.0)
    assert decode_message([b"!AIVDM,1,1,,A,1,0*00"]) == "undecodable message"


def test_tag_blocks_and_fragments_per_source():
    assert parse_tag_time(b"c:1700000000123,s:rx*00") == 1700000000.123
    assert parse_tag_time(b"s:rx*00") is None
    tag = tag_block(1.7e9, "rx1")
    assert tag.startswith(b"\\c:1700000000,s:rx1*") and checksum_ok(tag[1:-1])
    a = Assembler()
    p1 = b"!AIVDM,2,1,4,A,55O0W7`00001L@gCWGA2uItLth@DqtL5@F22220j1h742t0Ht0000000,0*08"
    p2 = b"!AIVDM,2,2,4,A,000000000000000,2*20"
    assert a.push(p1, "rx1", 1.0, 0.0) == [] and a.push(p1, "rx2", 1.0, 0.0) == []
    (m,) = a.push(tag_block(5.0) + p2, "rx2", 2.0, 0.0)  # rx2's message, time from part 2
    assert m.source == "rx2" and m.time_s == 5.0 and m.sentences == [p1, p2] and not m.reject
    assert a.pending == 1
    (late,) = a.expire(20.0)
    assert late.source == "rx1" and late.reject == "incomplete multi-sentence message"


def test_duplicates_within_the_window():
    d = Duplicates(10.0)
    assert not d.seen(b"x", 0.0) and d.seen(b"x", 5.0) and not d.seen(b"x", 16.0)


def test_payload_int_equals_the_per_character_decoding():
    rng = np.random.default_rng(1)
    chars = list(range(48, 120))
    for n in (4, 28, 56):
        for _ in range(300):
            payload = bytes(rng.choice(chars, n).tolist())
            ref = 0
            for c in payload:
                ref = (ref << 6) | (c - 48 if c < 88 else c - 56)
            assert payload_int(payload) == ref
    for bad in (b"13u?etPv2;0n:dDPwUM1U1Cb06 9D", b"13u?\x7f", b"1*2,", b"1/2+"):
        assert payload_int(bad) is None


def test_duplicates_equal_a_plain_window_on_random_streams():
    """The bucketed filter answers as a reference that keeps every key's first receipt
    time and forgets it once older than the window."""
    rng = np.random.default_rng(5)
    for window in (0.0, 0.7, 10.0):
        d = Duplicates(window)
        first: dict[bytes, float] = {}
        now = 0.0
        for _ in range(20_000):
            now += float(rng.exponential(0.01))
            key = b"%d" % rng.integers(0, 400)
            t = first.get(key)
            expect = t is not None and now - t <= window
            if not expect:
                first[key] = now
            assert d.seen(key, now) == expect
        assert len(d) >= sum(1 for t in first.values() if now - t <= window)


def test_duplicates_hold_nothing_the_garbage_collector_follows():
    import gc

    d = Duplicates(10.0)
    for k in range(1_000):
        d.seen(b"key %d" % k, k * 0.001)
    reach, level = [], [d]
    for _ in range(3):  # the object, its attributes, the containers they hold
        level = gc.get_referents(*level)
        reach += level
    keys = [o for o in reach if isinstance(o, dict) and len(o) >= 100]
    assert sum(map(len, keys)) == 1_000 and not any(gc.is_tracked(o) for o in keys)
