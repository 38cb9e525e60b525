"""A burst of lines through the fast path and the assembler: positions in arrival order,
every message counted once, as the assembler and decoder alone would."""

from __future__ import annotations

import numpy as np
from pyais.encode import encode_dict

from seatrack.live.counters import Counters
from seatrack.live.ingest import Positions
from seatrack.live.ingest import read_lines
from seatrack.live.ingest import read_messages
from seatrack.live.nmea import Assembler
from seatrack.live.nmea import Duplicates
from seatrack.live.nmea import encode_report
from seatrack.live.nmea import tag_block

NAME = [
    b"!AIVDM,2,1,4,A,55O0W7`00001L@gCWGA2uItLth@DqtL5@F22220j1h742t0Ht0000000,0*08",
    b"!AIVDM,2,2,4,A,000000000000000,2*20",
]


def burst() -> list[bytes]:
    t0 = 1.7e9
    a = encode_report(219000001, t0, 57.0, 11.0, 10.0, 90.0, source="rx1")[0]
    (b18,) = encode_dict({"type": 18, "mmsi": 211234567, "lat": 54.0, "lon": 10.5,
                          "speed": 4.2, "course": 88.0}, "AI", "VDM", "B")  # fmt: skip
    b = encode_report(219000002, t0 + 1, 57.1, 11.1, 5.0, 180.0)[0]
    far = encode_report(219000003, 5e9, 57.1, 11.1, 5.0, 180.0)[0]  # time out of range
    c = encode_report(219000001, t0 + 2, 57.0, 11.001, 10.0, 90.0)[0]
    return [a, NAME[0], tag_block(t0 + 1.5) + b18.encode(), a, b, b"junk", NAME[1], far, c, b""]


def test_fast_and_slow_lines_give_the_assembler_result_in_order():
    lines = burst()
    fast_pos, fast_cnt, names = Positions(), Counters(), {}
    read_lines(lines, "rx", 1.7e9 + 3, 0.5, Assembler(), Duplicates(), fast_cnt, fast_pos,
               names.__setitem__)  # fmt: skip
    ref_pos, ref_cnt, asm, ref_names = Positions(), Counters(), Assembler(), {}
    dup = Duplicates()
    for line in lines:  # every line through the assembler and the decoder
        read_messages(asm.push(line, "rx", 1.7e9 + 3, 0.5), dup, ref_cnt, ref_pos,
                      ref_names.__setitem__)  # fmt: skip
    got, ref = fast_pos.columns(), ref_pos.columns()
    assert list(got["mmsi"]) == [219000001, 211234567, 219000002, 219000001]
    for name in got:
        np.testing.assert_array_equal(got[name], ref[name])
    assert fast_pos.sources == ["rx"] * 4
    assert fast_cnt.health() == ref_cnt.health()
    assert fast_cnt.duplicate == 1 and fast_cnt.rejected["time out of range"] == 1
    assert names == ref_names == {368060190: "P/V_GOLDEN_GATE"}
    assert fast_cnt.received + len(fast_pos) == 9  # 10 lines, one message in two; the
    # positions are counted when the tracker takes them
