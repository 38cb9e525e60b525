"""``seatrack demo --live``: the replayed AIS sample and simulated radar, and the command
(in this process, stopped by SIGTERM once its map answers)."""

from __future__ import annotations

import json
import os
import re
import signal
import threading
import time
import urllib.request

import numpy as np

from cli_inprocess import seatrack
from seatrack.live.demo import demo_items
from seatrack.live.demo import radar_setup
from seatrack.live.radar import parse_plot_datagram


def test_demo_items_hold_the_sample_and_radar_scans():
    items = demo_items()
    ais = [it for it in items if it.kind == "ais"]
    plots = [it for it in items if it.kind == "plots"]
    assert len(ais) == 255 and all(it.data.startswith(b"\\c:") for it in ais)
    assert [it.t for it in items] == sorted(it.t for it in items)
    periods = np.diff([it.t for it in plots])
    assert np.allclose(periods, radar_setup().site.scan_period)
    t, r, az, bad = parse_plot_datagram(plots[10].data, 0.0)
    assert not bad and (t == plots[10].t).all() and (r > 0).all()


def test_demo_live_serves_the_map_until_sigterm():
    out: dict = {}

    url: list[str] = []

    def stop_when_up():
        t0 = time.monotonic()
        while time.monotonic() - t0 < 30 and not url:
            time.sleep(0.1)
        if not url:  # the command failed before its signal handlers: it returns by itself
            return
        t1 = time.monotonic()
        while time.monotonic() - t1 < 20:
            with urllib.request.urlopen(url[0] + "api/health", timeout=5) as r:
                h = json.loads(r.read())
            if h["vessels"] == 2 and h["radar_tracks"] >= 1:
                out["health"] = h
                break
            time.sleep(0.2)
        os.kill(os.getpid(), signal.SIGTERM)

    import seatrack.commands.live as live_cmd

    real = live_cmd.run_live

    async def spy(opts, echo, on_start=None):
        def started(proc):
            url.append(f"http://127.0.0.1:{proc.http_port}/")
            on_start(proc)

        return await real(opts, echo, on_start=started)

    live_cmd.run_live = spy
    try:
        threading.Thread(target=stop_when_up, daemon=True).start()
        run = seatrack("demo", "--live", "--http", "127.0.0.1:0", "--speed", "60")
    finally:
        live_cmd.run_live = real
    assert run.returncode == 130 and run.stderr.strip() == "error: interrupted"
    assert re.search(r"map at http://127\.0\.0\.1:\d+/", run.stdout)
    assert out["health"]["vessels"] == 2 and out["health"]["rejected"] == {}
