"""The live process over loopback sockets: UDP, TCP (split reads, reconnects), FILE;
counters, duplicates, multi-part messages, and equivalence with the batch AIS tracker."""

from __future__ import annotations

import asyncio

import numpy as np

from live.streams import started
from live.streams import synthetic
from live.streams import udp_send
from live.streams import wait_for
from seatrack.filters.ais import track_reports
from seatrack.io.ais import read_ais
from seatrack.live.ais import causal_config
from seatrack.live.nmea import encode_report
from seatrack.live.process import LiveOptions
from seatrack.live.sources import Source

UDP = Source("udp", "127.0.0.1", 0)
NAME = [
    b"!AIVDM,2,1,4,A,55O0W7`00001L@gCWGA2uItLth@DqtL5@F22220j1h742t0Ht0000000,0*08",
    b"!AIVDM,2,2,4,A,000000000000000,2*20",
]


def run(coro, timeout: float = 10.0):
    return asyncio.run(asyncio.wait_for(coro, timeout))


def test_udp_counts_every_message_and_keeps_the_invariant():
    t0 = 1.7e9
    a = encode_report(219000001, t0, 57.0, 11.0, 10.0, 90.0, source="rx1")
    a_rx2 = encode_report(219000001, t0, 57.0, 11.0, 10.0, 90.0, channel="B", source="rx2")
    b = encode_report(219000002, t0 + 1, 57.1, 11.1, 5.0, 180.0)
    c = encode_report(219000001, t0 + 10, 57.0, 11.0 + 10 * 10 * 0.514444 / 60_600, 10.0, 90.0)
    bad_sum = b[0][:-2] + b"00"
    cut = b[0][: len(b[0]) // 2]
    lines = [
        a[0],
        a_rx2[0],
        b[0],
        bad_sum,
        cut,
        b"hello",
        b"$GPGGA,1,2*00",
        b"",
        NAME[0],  # the second fragment comes in the next datagram
    ]

    async def go():
        proc = await started(LiveOptions(ais=[UDP, UDP]))
        p1, p2 = proc.udp_ports
        udp_send(p1, [b"\n".join(lines[:3]), b"\r\n".join(lines[3:])])
        udp_send(p2, [a_rx2[0]])  # the same message via the second receiver
        udp_send(p1, [NAME[1], b"\n".join(c)])
        await wait_for(lambda: proc.counters.received == 11)
        await proc.drain()
        cnt, h = proc.counters, proc.health()
        await proc.stop()
        return cnt, h, proc

    cnt, h, proc = run(go())
    assert cnt.check()
    assert (cnt.decoded, cnt.duplicate, cnt.late) == (4, 2, 0)
    assert dict(cnt.rejected) == {
        "bad checksum": 1, "truncated sentence": 1, "not an AIS line": 2, "blank line": 1,
    }  # fmt: skip
    assert h["vessels"] == 2 and h["positions"] == 3
    assert proc.names == {368060190: "P/V_GOLDEN_GATE"}
    assert h["latency_ms"]["p99"] is not None
    feats = {f["id"]: f for f in proc.picture.collection()["features"]}
    assert set(feats) == {"ais:219000001", "ais:219000002"}
    p = feats["ais:219000001"]["properties"]
    assert p["source"] == "ais" and p["mmsi"] == 219000001
    assert p["time_utc"].startswith("2023-11-14T22:13:30")  # t0 + 10 s
    assert abs(p["sog_kn"] - 10.0) < 0.5 and abs(p["cog_deg"] - 90.0) < 2.0


def test_tcp_reassembles_split_reads_and_reconnects():
    t0 = 1.7e9
    msgs = [encode_report(219000000 + k, t0 + k, 57.0, 11.0, 1.0, 10.0)[0] for k in range(6)]
    stream1 = b"\r\n".join([*msgs[:3], *NAME]) + b"\r\n" + msgs[3][:40]  # cut by the close
    stream2 = b"\r\n".join(msgs[4:]) + b"\r\n"
    connections = []

    async def serve(reader, writer):
        connections.append(1)
        data = stream1 if len(connections) == 1 else stream2
        for k in range(0, len(data), 7):  # 7-byte writes: sentences split across reads
            writer.write(data[k : k + 7])
            await writer.drain()
            await asyncio.sleep(0)
        writer.close()

    async def go():
        server = await asyncio.start_server(serve, "127.0.0.1", 0)
        port = server.sockets[0].getsockname()[1]
        proc = await started(LiveOptions(ais=[Source("tcp", "127.0.0.1", port)]))
        await wait_for(lambda: proc.counters.received >= 7 and len(connections) >= 2)
        await proc.drain()
        cnt = proc.counters
        await proc.stop()
        server.close()
        return cnt

    cnt = run(go())
    assert cnt.check()
    assert cnt.decoded == 6  # 5 positions + the 2-part static report
    assert cnt.rejected == {"truncated sentence": 1}
    assert cnt.reconnects >= 1


def test_fragment_timeout_rejects_incomplete_message():
    async def go():
        proc = await started(LiveOptions(ais=[UDP]))
        proc.assembler.fragment_timeout_s = 0.2
        udp_send(proc.udp_ports[0], [NAME[0]])
        await wait_for(lambda: proc.counters.received == 1)
        cnt = proc.counters
        await proc.stop()
        return cnt

    cnt = run(go())
    assert cnt.rejected == {"incomplete multi-sentence message": 1} and cnt.check()


def test_late_report_is_counted_late():
    t0 = 1.7e9
    msgs = [encode_report(219000001, t0 + dt, 57.0, 11.0, 0.0, np.nan)[0] for dt in (0, 30, 5)]

    async def go():
        proc = await started(LiveOptions(ais=[UDP], window_s=10.0))
        udp_send(proc.udp_ports[0], msgs)
        await wait_for(lambda: proc.counters.received == 3)
        cnt = proc.counters
        await proc.stop()
        return cnt

    cnt = run(go())
    assert (cnt.decoded, cnt.late) == (2, 1) and cnt.check()


def test_udp_picture_equals_batch_causal_tracker(tmp_path):
    """The same messages in the same order: the live picture equals the batch tracker's
    causal output (``track_reports`` with ``causal_config``) on the file of those lines,
    each report tracked under the vessel the live MMSI split gave it (the stream has
    3 km jumps: a jump that lasts is a second vessel on the MMSI)."""
    r = synthetic(seed=5, vessels=8, reports=40)
    lines = []
    for k in range(len(r)):
        lines += encode_report(r.mmsi[k], r.t[k], r.lat[k], r.lon[k], r.sog_kn[k], r.cog_deg[k])
    path = tmp_path / "ais.nmea"
    path.write_bytes(b"\n".join(lines) + b"\n")
    rep = read_ais([path])

    async def go():
        proc = await started(LiveOptions(ais=[UDP]))
        proc.identities.record()  # the vessel key of every report
        for k in range(0, len(lines), 20):
            udp_send(proc.udp_ports[0], [b"\n".join(lines[k : k + 20])])
            await asyncio.sleep(0.002)
        await wait_for(lambda: proc.counters.received == len(lines))
        await proc.drain()
        await proc.stop()
        return proc

    proc = run(go())
    assert proc.counters.decoded == len(lines) and proc.counters.check()
    key = {(m, t): k for m, t, k in proc.identities.routed}
    rep.mmsi = np.array([key[m, t] for m, t in zip(rep.mmsi.tolist(), rep.t.tolist(),
                                                   strict=True)], np.int64)  # fmt: skip
    assert (rep.mmsi > 1e9).any()  # a split MMSI
    tr = track_reports(rep, causal_config())
    want = {}
    for k in range(len(rep)):
        if np.isfinite(tr.lat[k]):
            want[int(rep.mmsi[k])] = (tr.lat[k], tr.lon[k], tr.speed[k], tr.course[k])
    ids, got, _ = proc.ais.tracks()
    assert sorted(ids) == sorted(want)
    for k, m in enumerate(ids):
        np.testing.assert_allclose([got.lat[k], got.lon[k]], want[m][:2], rtol=0, atol=1e-8)
        np.testing.assert_allclose(got.speed[k], want[m][2], rtol=0, atol=1e-7)
        np.testing.assert_allclose(got.course[k], want[m][3], rtol=0, atol=1e-7)


def test_tune_garbage_collector_freezes_the_live_objects_and_sets_thresholds() -> None:
    import gc

    from seatrack.live.process import GC_THRESHOLDS
    from seatrack.live.process import tune_garbage_collector

    thresholds = gc.get_threshold()
    try:
        marker = [object()]  # a container alive now
        frozen = tune_garbage_collector()
        assert frozen == gc.get_freeze_count() > 0
        assert not any(o is marker for o in gc.get_objects())  # frozen: not scanned
        assert gc.get_threshold() == GC_THRESHOLDS
    finally:
        gc.unfreeze()
        gc.set_threshold(*thresholds)
    assert any(o is marker for o in gc.get_objects())
