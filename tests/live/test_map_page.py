"""The live map page in headless Chromium (driven over the DevTools protocol with
aiohttp): while a replay runs, markers appear for the vessels and the radar tracks and
move. Skipped without Chromium except under CI (``tests/browser.py``)."""

from __future__ import annotations

import asyncio
import json
import threading
import time

import aiohttp

from browser import FLAGS
from browser import chromium
from live.streams import started
from seatrack.live.demo import radar_setup
from seatrack.live.demo import start_replay
from seatrack.live.process import LiveOptions
from seatrack.live.sources import Source
from seatrack.live.web import start_web

READ = """JSON.stringify({ais: +document.body.dataset.ais, radar: +document.body.dataset.radar,
 markers: Array.from(document.querySelectorAll('.st-live')).map(
   e => [e.dataset.id, +e.dataset.lat, +e.dataset.lon])})"""


async def devtools(profile, timeout=30.0):
    """The DevTools WebSocket URL of the page once Chromium has written its port."""
    t0 = time.monotonic()
    port_file = profile / "DevToolsActivePort"
    while not port_file.exists() or not port_file.read_text().strip():
        assert time.monotonic() - t0 < timeout, "Chromium did not start"
        await asyncio.sleep(0.1)
    port = int(port_file.read_text().split()[0])
    async with aiohttp.ClientSession() as s:
        while True:
            pages = await (await s.get(f"http://127.0.0.1:{port}/json/list")).json()
            pages = [p for p in pages if p.get("type") == "page"]
            if pages:
                return pages[0]["webSocketDebuggerUrl"]
            await asyncio.sleep(0.1)


def test_markers_appear_and_move_while_a_replay_runs(tmp_path):
    exe = chromium()
    stop = threading.Event()

    async def go():
        udp = Source("udp", "127.0.0.1", 0)
        proc = await started(LiveOptions(ais=[udp], plots=[udp], radar=radar_setup(), tick_s=0.1))
        runner = await start_web(proc, "127.0.0.1", 0)
        url = f"http://127.0.0.1:{proc.http_port}/"
        profile = tmp_path / "profile"
        browser = await asyncio.create_subprocess_exec(
            exe, *FLAGS, f"--user-data-dir={profile}", "--remote-debugging-port=0", url,
            stdout=asyncio.subprocess.DEVNULL, stderr=asyncio.subprocess.DEVNULL,
        )  # fmt: skip
        seen = []
        try:
            ws_url = await devtools(profile)
            a, p = proc.udp_ports
            start_replay({"ais": ("127.0.0.1", a), "plots": ("127.0.0.1", p)}, 40.0, stop)
            async with aiohttp.ClientSession() as s, s.ws_connect(ws_url, max_msg_size=0) as ws:
                for k in range(200):
                    await ws.send_json(
                        {
                            "id": k,
                            "method": "Runtime.evaluate",
                            "params": {"expression": READ, "returnByValue": True},
                        }
                    )
                    while True:
                        msg = json.loads((await ws.receive(timeout=10)).data)
                        if msg.get("id") == k:
                            break
                    value = msg["result"]["result"].get("value")
                    if value:
                        seen.append(json.loads(value))
                    if len(seen) > 2 and moved(seen) and seen[-1]["radar"] >= 1:
                        break
                    await asyncio.sleep(0.1)
        finally:
            stop.set()
            browser.kill()
            await browser.wait()
            await runner.cleanup()
            await proc.stop()
        return seen, proc

    seen, proc = asyncio.run(asyncio.wait_for(go(), 60))
    last = seen[-1]
    assert last["ais"] == 2 and last["radar"] >= 1
    ids = {m[0] for m in last["markers"]}
    assert {"ais:265410000", "ais:265550210"} <= ids
    assert any(i.startswith("radar:") for i in ids)
    assert moved(seen)
    assert proc.counters.decoded > 2


def moved(seen):
    """Some AIS marker is drawn at two different places."""
    first = {}
    for s in seen:
        for fid, lat, lon in s["markers"]:
            if fid.startswith("ais:"):
                if fid in first and first[fid] != (lat, lon):
                    return True
                first.setdefault(fid, (lat, lon))
    return False
