"""Radar-AIS fusion inside the live process, over loopback UDP: the scene of
``tests/fusion_samples.py`` (two AIS-carrying vessels, one dark) replayed into a live
process classes the radar tracks (read from ``/api/tracks`` and ``/api/health``), and the
classes at the last scan equal ``seatrack fuse``
on the same AIS and plot files."""

from __future__ import annotations

import asyncio

import aiohttp
import numpy as np
import pytest

from fusion_samples import write_scene
from live.streams import started
from live.streams import udp_send
from live.streams import wait_for
from seatrack.fusion.picture import CLASSES
from seatrack.fusion.picture import fuse_picture
from seatrack.fusion.picture import load_fusion_config
from seatrack.fusion.picture import parse_fusion_config
from seatrack.io.ais import read_ais
from seatrack.io.multitarget import read_unlabelled_plots
from seatrack.live.ais import LiveAis
from seatrack.live.fusion import LiveFusion
from seatrack.live.nmea import encode_report
from seatrack.live.process import LiveOptions
from seatrack.live.sources import Source
from seatrack.live.web import start_web

UDP = Source("udp", "127.0.0.1", 0)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """The scene's files, its AIS reports as NMEA (``ais.nmea``) and the live run."""
    d = tmp_path_factory.mktemp("scene")
    ais_csv, plots_csv, toml = write_scene(d)
    rep = read_ais([ais_csv])
    lines = []
    for m, t, la, lo, sog, cog in zip(rep.mmsi, rep.t, rep.lat, rep.lon, rep.sog_kn,
                                      rep.cog_deg, strict=True):  # fmt: skip
        lines += encode_report(int(m), float(t), float(la), float(lo), float(sog), float(cog))
    nmea = d / "ais.nmea"
    nmea.write_bytes(b"\n".join(lines) + b"\n")
    setup, cfg = load_fusion_config(toml)
    text = plots_csv.read_text().splitlines()
    header, rows = text[0], text[1:]
    times = [r.split(",", 1)[0] for r in rows]
    scans: dict[str, list[str]] = {}
    for t, r in zip(times, rows, strict=True):
        scans.setdefault(t, []).append(r)
    datagrams = [("\n".join([header, *rs]) + "\n").encode() for rs in scans.values()]

    async def go():
        opts = LiveOptions(
            ais=[UDP], plots=[UDP], radar=setup, fusion=cfg, fusion_queue=len(datagrams)
        )  # every scan fused: none dropped
        proc = await started(opts)
        runner = await start_web(proc, "127.0.0.1", 0)
        url = f"http://127.0.0.1:{proc.http_port}"
        ais_port, plot_port = proc.udp_ports
        for k in range(0, len(lines), 20):  # all AIS first: every state is there at each scan
            udp_send(ais_port, [b"\n".join(lines[k : k + 20])])
            await asyncio.sleep(0.001)
        await wait_for(lambda: proc.counters.received == len(lines))
        for k in range(0, len(datagrams), 10):
            udp_send(plot_port, datagrams[k : k + 10])
            await asyncio.sleep(0.001)
        await wait_for(lambda: proc.counters.scans >= len(datagrams) - 1)
        await proc.drain()
        async with aiohttp.ClientSession() as s:
            feats = (await (await s.get(url + "/api/tracks")).json())["features"]
            health = await (await s.get(url + "/api/health")).json()
        await runner.cleanup()
        await proc.stop()
        return proc, feats, health

    proc, feats, health = asyncio.run(asyncio.wait_for(go(), 20.0))
    return {"proc": proc, "feats": feats, "health": health, "nmea": nmea, "plots": plots_csv,
            "setup": setup, "cfg": cfg, "rep": rep, "scans": len(datagrams)}  # fmt: skip


def test_live_fusion_classes_ais_and_dark_vessels(scene):
    proc, feats = scene["proc"], scene["feats"]
    assert proc.counters.scans == scene["scans"] and proc.counters.check()
    radar = [f["properties"] for f in feats if f["properties"]["source"] == "radar"]
    ais = [f["properties"] for f in feats if f["properties"]["source"] == "ais"]
    mmsis = sorted({int(m) for m in scene["rep"].mmsi})
    assert len(mmsis) == 2 and len(ais) == 2
    # the three vessels' radar tracks (the scene has clutter-free tracks but coasting ones)
    by_class = {}
    for p in radar:
        by_class.setdefault(p["class"], []).append(p)
    assert sorted(p["mmsi"] for p in by_class["ais"]) == mmsis
    assert all(p["identity_prob"] > 0.9 for p in by_class["ais"])
    assert len(by_class["dark"]) == 1 and by_class["dark"][0]["mmsi"] is None
    assert by_class["dark"][0]["identity_prob"] is None
    assert all(p["not_seen"] is False for p in ais)
    assert all(p["sub"] == 0 and not (p["gap"] or p["jump"] or p["identity_conflict"])
               for p in ais)  # fmt: skip
    h = scene["health"]
    assert h["dark"] == 1 and h["not_seen"] == 0 and h["radar_tracks"] == len(radar)
    assert h["fusion_ms"]["p99"] is not None
    assert h["fusion_scans"] == scene["scans"] and h["fusion_scans_dropped"] == 0
    assert h["fusion_waiting"] == 0 and "fusion_errors" not in h


def test_live_fusion_equals_batch_fuse_at_the_last_scan(scene):
    """Per radar track at the last scan: the same class, MMSI and (to 1e-9) identity
    probability as ``fuse_picture`` on the files of the same messages and plots."""
    pic = fuse_picture(read_ais([scene["nmea"]]), read_unlabelled_plots(scene["plots"]),
                       scene["setup"], scene["cfg"])  # fmt: skip
    last = pic.radar.t == pic.radar.t.max()
    names = pic.ais.vessel_mmsi
    want = {
        int(tid): (CLASSES[int(k)], int(names[v]) if v >= 0 else None)
        for tid, k, v in zip(
            pic.radar.track[last], pic.klass[last], pic.radar_vessel[last], strict=True
        )  # fmt: skip
    }
    got = {tid: (f.klass, f.mmsi) for tid, f in scene["proc"].fusion.tracks.items()}
    assert got == want
    assert {c for c, _ in want.values()} == {"ais", "dark"}
    prob = dict(zip(pic.radar.track[last].tolist(), pic.identity_prob[last], strict=True))
    for tid, f in scene["proc"].fusion.tracks.items():
        if f.identity_prob is None:
            assert np.isnan(prob[tid])
        else:
            np.testing.assert_allclose(f.identity_prob, prob[tid], rtol=0, atol=1e-9)


def test_a_vessel_rerun_replaces_its_later_states():
    """An out-of-order report re-runs its vessel: the fusion keeps one state per report
    time, the re-run ones replacing those it had; a scan drops the states it no longer
    needs."""
    setup, cfg = parse_fusion_config(
        {"lat_deg": 56.0, "lon_deg": 7.0, "fusion": {"land_mask": False}}
    )
    fusion = LiveFusion(setup, cfg)
    ais = LiveAis(window_s=30.0)
    ais.emitted = []
    t0, lat, lon = 1.7e9, 56.0, 7.0
    step = 10 * 5.0 * 0.514444 / (111_320.0 * np.cos(np.radians(lat)))  # 5 kn East, 10 s
    for k in (0, 1, 2, 4):
        ais.add(np.array([219000001]), np.array([t0 + 10 * k]), np.array([lat]),
                np.array([lon + k * step]), np.array([5.0]), np.array([90.0]))  # fmt: skip
    none = np.zeros(0, np.int64)
    fusion.add_estimates(ais.emitted)
    fusion.scan(t0 - 1, none, None, {})  # folds the states in, keeps them all
    key = 219000001
    before = fusion.states_of(key)
    ais.emitted.clear()
    ais.add(np.array([219000001]), np.array([t0 + 30]), np.array([lat]),
            np.array([lon + 3 * step]), np.array([5.0]), np.array([90.0]))  # fmt: skip
    assert [e.t for _, e in ais.emitted] == [t0 + 30, t0 + 40]  # the re-run
    fusion.add_estimates(ais.emitted)
    fusion.scan(t0 - 1, none, None, {})
    assert sorted(fusion.states_of(key)) == [t0 + 10 * k for k in range(5)]
    assert fusion.report_times(key) == [t0 + 10 * k for k in range(5)]
    after = fusion.states_of(key)
    assert all(after[t] == before[t] for t in (t0, t0 + 10, t0 + 20))
    assert after[t0 + 40] != before[t0 + 40]  # re-run with the report at 30 s
    fusion.scan(t0 + 35, none, None, {})
    assert sorted(fusion.states_of(key)) == [t0 + 30, t0 + 40]  # older states are not needed


def test_a_failing_scan_consumer_is_counted_and_the_radar_goes_on() -> None:
    """An exception in a scan listener (the fusion step) is counted by type; the radar's
    own scan bookkeeping is done before and the next scans run."""
    import numpy as np

    from seatrack.io.radar import parse_radar_config
    from seatrack.live.counters import Counters
    from seatrack.live.radar import LiveRadar

    setup = parse_radar_config({"lat_deg": 57.0, "lon_deg": 11.0, "scan_period_s": 2.0})
    radar = LiveRadar(setup, Counters())
    calls = []

    def broken(*args: object) -> None:
        calls.append(args[0])
        raise RuntimeError("boom")

    radar.listeners.append(broken)
    for k in range(3):
        radar.add(np.array([1000.0 + 2.0 * k]), np.array([5000.0]), np.array([0.5]), 0.0)
        radar.flush()
    assert radar.listener_errors == {"RuntimeError": 3}
    assert len(calls) == 3 and radar.counters.scans == 3


def test_a_full_queue_drops_the_oldest_scan_and_keeps_its_ais_states() -> None:
    """The worker busy with one scan, three more arrive with a queue of one: the two
    older are dropped (counted), the newest is fused with every AIS state recorded."""
    import threading

    setup, cfg = parse_fusion_config(
        {"lat_deg": 56.0, "lon_deg": 7.0, "fusion": {"land_mask": False}}
    )
    fusion = LiveFusion(setup, cfg, queue_size=1)
    ais = LiveAis()
    ais.emitted = []
    release, entered = threading.Event(), threading.Event()
    step = fusion._step
    seen: list[float] = []

    def held(item):  # the first scan waits until released
        seen.append(item.t)
        if len(seen) == 1:
            entered.set()
            release.wait(10.0)
        step(item)

    fusion._step = held
    fusion.start()
    t0, none = 1.7e9, np.zeros(0, np.int64)
    mmsi = np.array([219000001])
    for k in range(4):
        ais.add(mmsi, np.array([t0 + 10 * k]), np.array([56.0]), np.array([7.0 + 1e-3 * k]),
                np.array([5.0]), np.array([90.0]))  # fmt: skip
        fusion.add_estimates(ais.emitted)
        ais.emitted.clear()
        fusion.scan(t0 + 10 * k + 1, none, None, {})
        if k == 0:
            assert entered.wait(10.0)
    assert fusion.dropped == 2 and fusion.waiting == 1
    release.set()
    assert fusion.wait_idle(10.0)
    fusion.close()
    assert seen == [t0 + 1, t0 + 31] and fusion.version == 2 and not fusion.errors
    assert fusion.report_times(219000001) == [t0 + 10 * k for k in range(4)]  # dropped scans'


def test_a_failing_fusion_step_is_counted_and_the_worker_goes_on() -> None:
    setup, cfg = parse_fusion_config(
        {"lat_deg": 56.0, "lon_deg": 7.0, "fusion": {"land_mask": False}}
    )
    fusion = LiveFusion(setup, cfg, queue_size=4)
    step, calls = fusion._step, []

    def flaky(item):
        calls.append(item.t)
        if len(calls) == 1:
            raise RuntimeError("boom")
        step(item)

    fusion._step = flaky
    fusion.start()
    for k in range(3):
        fusion.scan(1.7e9 + k, np.zeros(0, np.int64), None, {})
    assert fusion.wait_idle(10.0)
    fusion.close()
    assert fusion.errors == {"RuntimeError": 1} and fusion.version == 2 and len(calls) == 3


def test_push_times_and_ring_limits_equal_recent_intervals() -> None:
    """The vessels' report-time rows give the gap limits of
    :class:`~seatrack.fusion.anomalies.RecentIntervals` fed the same times."""
    from seatrack.fusion.anomalies import RecentIntervals
    from seatrack.live.fusion import HISTORY
    from seatrack.live.fusion import push_times
    from seatrack.live.fusion import ring_limits

    rng = np.random.default_rng(2)
    rows, refs = np.full((6, HISTORY), np.nan), [RecentIntervals(HISTORY) for _ in range(6)]
    last = np.full(6, 1.7e9)
    for _ in range(40):
        count = rng.integers(0, 5, 6)
        new = np.full((6, int(count.max())), np.nan)
        for r in range(6):
            for q in range(count[r]):
                last[r] += float(rng.choice([0.0, rng.exponential(10.0)]))
                new[r, q] = last[r]
                refs[r].push(last[r])
        rows = push_times(rows, new, count)
        for r in range(6):
            assert [x for x in rows[r] if x == x] == list(refs[r].times)
        lim = ring_limits(rows, 2.5, 30.0)
        assert lim.tolist() == [ref.limit(2.5, 30.0) for ref in refs]


def test_fused_store_equals_a_report_by_report_reference() -> None:
    """Random streams with re-runs (a vessel emitting again from an earlier time) and
    outliers, folded in at scans: every vessel's report times and state times equal a
    report-by-report reference (a re-run drops what came after it; a state replaces the
    one at its time; a scan keeps the last state at or before it and the later ones)."""
    from types import SimpleNamespace

    from seatrack.live.fusion import HISTORY

    setup, cfg = parse_fusion_config(
        {"lat_deg": 56.0, "lon_deg": 7.0, "fusion": {"land_mask": False}}
    )
    fusion = LiveFusion(setup, cfg)
    rng = np.random.default_rng(9)
    keys = [219000001 + k for k in range(8)]
    vessels = {k: SimpleNamespace(mmsi=k, lat0=56.0 + 0.01 * i, lon0=7.0)
               for i, k in enumerate(keys)}  # fmt: skip
    clock = dict.fromkeys(keys, 1.7e9)
    ref_times: dict[int, list[float]] = {k: [] for k in keys}
    ref_states: dict[int, set[float]] = {k: set() for k in keys}
    none = np.zeros(0, np.int64)
    scan_t = 1.7e9
    for _ in range(30):
        emitted = []
        for _ in range(int(rng.integers(0, 25))):
            k = keys[int(rng.integers(0, len(keys)))]
            back = rng.random() < 0.15
            step = -float(rng.uniform(0, 30)) if back else float(rng.uniform(0, 5))
            t = round(clock[k] + step, 1)
            clock[k] = max(clock[k], t)
            kind = 0 if rng.random() > 0.2 else 2
            state = np.array([rng.normal(0, 100), rng.normal(0, 100), 3.0, 1.0, 0.0])
            e = SimpleNamespace(t=t, kind=kind, state=state, std=np.full(5, 2.0), segment=1)
            emitted.append((vessels[k], e))
            times, states = ref_times[k], ref_states[k]
            if times and times[-1] > t:
                ref_times[k] = times = [x for x in times if x <= t]
                ref_states[k] = states = {s for s in states if s <= t}
            times.append(t)
            del times[:-HISTORY]
            if kind == 0:
                states.add(t)
        fusion.add_estimates(emitted)
        scan_t += float(rng.uniform(0, 6))
        fusion.scan(scan_t, none, None, {})
        for k in keys:
            before = sorted(s for s in ref_states[k] if s <= scan_t)
            ref_states[k] = set(before[-1:]) | {s for s in ref_states[k] if s > scan_t}
            assert fusion.report_times(k) == ref_times[k]
            assert sorted(fusion.states_of(k)) == sorted(ref_states[k])
    assert not fusion.errors
