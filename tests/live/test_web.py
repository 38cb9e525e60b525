"""The live web server over loopback with aiohttp's client: the map page and its assets,
/api/tracks, /api/health, /api/land, the WebSocket and its bounded per-client queue."""

from __future__ import annotations

import asyncio
import json

import aiohttp

from live.streams import started
from live.streams import udp_send
from live.streams import wait_for
from seatrack.live.nmea import encode_report
from seatrack.live.process import LiveOptions
from seatrack.live.sources import Source
from seatrack.live.web import CLIENT_QUEUE
from seatrack.live.web import start_web

T0 = 1.7e9


def run(coro, timeout: float = 15.0):
    return asyncio.run(asyncio.wait_for(coro, timeout))


async def serving():
    proc = await started(LiveOptions(ais=[Source("udp", "127.0.0.1", 0)], tick_s=0.05))
    runner = await start_web(proc, "127.0.0.1", 0)
    return proc, runner, f"http://127.0.0.1:{proc.http_port}"


def report(mmsi: int, dt: float, lon: float = 11.0) -> bytes:
    return encode_report(mmsi, T0 + dt, 57.0, lon, 8.0, 90.0)[0]


def test_api_tracks_health_page_and_assets():
    async def go():
        proc, runner, url = await serving()
        udp_send(proc.udp_ports[0], [report(219000001, 0), report(219000002, 1), b"junk"])
        await wait_for(lambda: proc.counters.received == 3)
        await proc.drain()
        async with aiohttp.ClientSession() as s:
            tracks = await (await s.get(url + "/api/tracks")).json()
            health = await (await s.get(url + "/api/health")).json()
            page = await (await s.get(url + "/")).text()
            assets = [(await s.get(url + p)).status for p in (
                "/static/leaflet/leaflet.js", "/static/leaflet/leaflet.css", "/static/live.js",
                "/static/live.css", "/static/nothing.js")]  # fmt: skip
            land = await s.get(url + "/api/land?box=10,56,12,58")
            land_json = await land.json()
            bad = (await s.get(url + "/api/land?box=1,2")).status
        await runner.cleanup()
        await proc.stop()
        return tracks, health, page, assets, land_json, bad

    tracks, health, page, assets, land, bad = run(go())
    assert tracks["type"] == "FeatureCollection"
    feats = {f["properties"]["id"]: f for f in tracks["features"]}
    assert set(feats) == {"ais:219000001", "ais:219000002"}
    p = feats["ais:219000002"]["properties"]
    for key in ("id", "source", "mmsi", "time_utc", "sog_kn", "cog_deg", "status", "std_m"):
        assert key in p
    assert p["source"] == "ais" and p["mmsi"] == 219000002 and p["status"] == "tracking"
    assert abs(p["sog_kn"] - 8.0) < 1e-6 and abs(p["cog_deg"] - 90.0) < 0.2
    assert feats["ais:219000002"]["geometry"]["type"] == "Point"
    lon, lat = feats["ais:219000002"]["geometry"]["coordinates"]
    assert abs(lat - 57.0) < 1e-5 and abs(lon - 11.0) < 1e-5
    assert health["received"] == 3 and health["decoded"] == 2
    assert health["rejected"] == {"not an AIS line": 1} and health["late"] == 0
    assert health["vessels"] == 2 and health["radar_tracks"] == 0
    assert set(health["latency_ms"]) == {"p50", "p99", "since_start"}
    assert health["latency_ms"]["p99"] > 0 and health["latency_ms"]["since_start"]["n"] > 0
    assert "/static/leaflet/leaflet.js" in page and "/static/live.js" in page
    assert "http" not in page.replace("http-equiv", "")  # every asset served locally
    assert assets == [200, 200, 200, 200, 404]
    assert land["geometry"]["type"] == "MultiPolygon" and len(land["geometry"]["coordinates"]) > 0
    assert bad == 400


def test_websocket_pushes_changes_and_health():
    async def go():
        proc, runner, url = await serving()
        udp_send(proc.udp_ports[0], [report(219000001, 0)])
        await wait_for(lambda: proc.counters.decoded == 1)
        await proc.drain()
        got = []
        async with aiohttp.ClientSession() as s, s.ws_connect(url + "/ws") as ws:
            got.append(json.loads((await ws.receive(timeout=3)).data))
            udp_send(proc.udp_ports[0], [report(219000001, 10, 11.001)])
            while len(got) < 3 or not any(m.get("type") == "health" for m in got):
                got.append(json.loads((await ws.receive(timeout=3)).data))
        await runner.cleanup()
        await proc.stop()
        return got

    got = run(go())
    assert got[0]["full"] and [f["id"] for f in got[0]["features"]] == ["ais:219000001"]
    moved = [m for m in got[1:] if m.get("type") == "FeatureCollection"]
    assert moved and moved[0]["features"][0]["geometry"]["coordinates"][0] > 11.0005
    assert len(moved[0]["features"][0]["properties"]["trail"]) == 2
    health = [m for m in got if m.get("type") == "health"][0]["health"]
    assert health["decoded"] == 2


def test_slow_websocket_client_drops_display_updates_only():
    """A client that cannot keep up loses display updates (counted), never messages: the
    picture and the counters go on, and the client then gets the whole picture again."""

    async def go():
        proc, runner, url = await serving()
        async with aiohttp.ClientSession() as s, s.ws_connect(url + "/ws") as ws:
            first = json.loads((await ws.receive(timeout=3)).data)
            # updates faster than the client's writer can run: no await in between
            for k in range(3 * CLIENT_QUEUE):
                proc.handle_messages(proc.assembler.push(report(219000000 + k, k), "test", T0, 0.0))
                proc.refresh()
            drops = proc.counters.display_drops
            msgs = []
            while not (msgs and msgs[-1].get("full")):
                msgs.append(json.loads((await ws.receive(timeout=3)).data))
        await runner.cleanup()
        await proc.stop()
        return first, drops, msgs, proc

    first, drops, msgs, proc = run(go())
    assert first["full"] and first["features"] == []
    assert drops == 3 * CLIENT_QUEUE - CLIENT_QUEUE
    assert proc.counters.decoded == 3 * CLIENT_QUEUE and proc.counters.check()
    assert len(msgs[-1]["features"]) == 3 * CLIENT_QUEUE
