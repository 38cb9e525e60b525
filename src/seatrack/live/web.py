"""The web side of ``seatrack live --http HOST:PORT`` (aiohttp).

* ``GET /``: the live Leaflet map (``assets/live.html``, ``live.js``, ``live.css``; Leaflet
  served from the bundled copy of :mod:`seatrack.report`, nothing from the network but the
  optional OSM / OpenSeaMap tiles, over the Natural Earth coast from ``/api/land``);
* ``GET /api/tracks``: the picture as a GeoJSON FeatureCollection
  (:mod:`seatrack.live.picture`);
* ``GET /api/health``: counters, vessels, radar tracks, latency
  (:meth:`~seatrack.live.process.LiveProcess.health`);
* ``GET /api/land?box=W,S,E,N``: the Natural Earth land in a box (deg), GeoJSON;
* ``/ws``: a WebSocket that first sends the whole picture (``"full": true``), then the
  changed features and removed ids (``FeatureCollection`` with ``removed``) as the ticker
  produces them, and the health once a second.

A client never slows ingestion: each has a bounded queue of messages; when it is full the
update is dropped (``display_drops``) and the client gets the whole picture again once it
has caught up.
"""

from __future__ import annotations

import asyncio
import json
from importlib import resources
from typing import Any

from aiohttp import WSMsgType
from aiohttp import web

__all__ = ["make_app", "start_web"]

CLIENT_QUEUE = 16
_TYPES = {".js": "text/javascript", ".css": "text/css", ".html": "text/html", ".png": "image/png"}


def _asset(package: str, *parts: str) -> bytes:
    path = resources.files(package)
    for part in parts:
        path = path.joinpath(part)
    return path.read_bytes()


class _Client:
    def __init__(self, ws: web.WebSocketResponse) -> None:
        self.ws = ws
        self.queue: asyncio.Queue[str] = asyncio.Queue(CLIENT_QUEUE)
        self.resync = False


def _land(request: web.Request) -> web.Response:
    from seatrack.report.land import land_rings

    try:
        w, s, e, n = (float(v) for v in request.query.get("box", "").split(","))
    except ValueError:
        raise web.HTTPBadRequest(text="box=W,S,E,N (degrees) needed") from None
    if not (-180 <= w < e <= 180 and -90 <= s < n <= 90):
        raise web.HTTPBadRequest(text="box outside the globe or empty")
    rings, _ = land_rings(w, s, e, n, max_vertices=20_000)
    polys = [
        [[[float(rings.lon[i]), float(rings.lat[i])] for i in range(a, b)]]
        for a, b in zip(rings.offsets[:-1], rings.offsets[1:], strict=True)
    ]
    return web.json_response(
        {
            "type": "Feature",
            "properties": {},
            "geometry": {"type": "MultiPolygon", "coordinates": polys},
        }
    )


def make_app(proc: Any) -> web.Application:
    """The aiohttp application of a :class:`~seatrack.live.process.LiveProcess`."""
    app = web.Application()
    clients: set[_Client] = set()

    def listener(kind: str, payload: Any) -> None:
        if kind != "picture" or not clients:
            return
        text = json.dumps(payload)
        for c in clients:
            try:
                c.queue.put_nowait(text)
            except asyncio.QueueFull:
                proc.counters.display_drops += 1
                c.resync = True

    proc.listeners.append(listener)
    proc.viewers.append(lambda: bool(clients))

    async def index(_: web.Request) -> web.Response:
        return web.Response(body=_asset("seatrack.live", "assets", "live.html"),
                            content_type="text/html")  # fmt: skip

    async def static(request: web.Request) -> web.Response:
        name = request.match_info["name"]
        if name.startswith("leaflet/"):
            body = _asset("seatrack.report", "assets", "vendor", *name.split("/"))
        elif name in ("live.js", "live.css"):
            body = _asset("seatrack.live", "assets", name)
        else:
            raise web.HTTPNotFound()
        ext = name[name.rfind(".") :]
        return web.Response(body=body, content_type=_TYPES.get(ext, "application/octet-stream"))

    async def tracks(_: web.Request) -> web.Response:
        proc.refresh()
        return web.json_response(proc.picture.collection())

    async def health(_: web.Request) -> web.Response:
        return web.json_response(proc.health())

    async def land(request: web.Request) -> web.Response:
        return await asyncio.get_running_loop().run_in_executor(None, _land, request)

    async def ws_handler(request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(heartbeat=10.0)
        await ws.prepare(request)
        client = _Client(ws)
        proc.refresh()
        full = {**proc.picture.collection(), "full": True}
        client.queue.put_nowait(json.dumps(full))
        clients.add(client)

        async def writer() -> None:
            while True:
                try:
                    text = await asyncio.wait_for(client.queue.get(), 1.0)
                except TimeoutError:
                    text = json.dumps({"type": "health", "health": proc.health()})
                await ws.send_str(text)
                if client.resync and client.queue.empty():
                    client.resync = False
                    await ws.send_str(json.dumps({**proc.picture.collection(), "full": True}))

        task = asyncio.create_task(writer())
        try:
            async for msg in ws:
                if msg.type in (WSMsgType.ERROR, WSMsgType.CLOSE):
                    break
        finally:
            clients.discard(client)
            task.cancel()
        return ws

    app.router.add_get("/", index)
    app.router.add_get("/static/{name:.+}", static)
    app.router.add_get("/api/tracks", tracks)
    app.router.add_get("/api/health", health)
    app.router.add_get("/api/land", land)
    app.router.add_get("/ws", ws_handler)
    return app


async def start_web(proc: Any, host: str, port: int) -> web.AppRunner:
    """Serve the app on ``host:port`` (0 = an ephemeral port, stored in
    ``proc.http_port``); returns the runner (``await runner.cleanup()`` to stop)."""
    runner = web.AppRunner(make_app(proc), access_log=None, handle_signals=False)
    await runner.setup()
    site = web.TCPSite(runner, host, port)
    await site.start()
    proc.http_port = int(runner.addresses[0][1])
    return runner
