"""The live process's radar-AIS fusion: time per scan in its worker thread, and the event
loop's stalls while it runs.

``--vessels`` AIS vessels (default 1,000) moving straight at 8 kn within 20 km of the
radar each report once per scan (every 3 s) to a :class:`seatrack.live.ais.LiveAis`;
the radar tracks are the vessels' true positions (one per vessel, 20 m sigma).

1. Time per scan: each scan hands the states the AIS filter emitted
   (:meth:`~seatrack.live.fusion.LiveFusion.add_estimates`, on the ingest path) and the
   scan (:meth:`~seatrack.live.fusion.LiveFusion.scan`) to the started worker and waits
   for it; printed: the median and maximum fusion step (in the worker) over ``--scans``
   scans (the first two left out: compilation), the event loop's share per AIS report and
   per scan, and the share of radar tracks classed ``ais``.
2. Event-loop lag: ``--lag-vessels`` vessels (default 10,000); an asyncio task sleeping
   1 ms records how late it wakes (the loop's lag) while another hands a scan to the
   worker every ``--lag-period`` s (the AIS states of each scan computed beforehand: only
   the fusion's own work runs), against the same loop with the fusion run in the loop
   (as the live process did before the worker) and with no fusion at all. The benchmark's
   precomputed scans (80,000 estimate objects) are frozen out of the garbage collector
   (``gc.freeze``) except in the last line: a full collection walks every tracked
   object while holding the GIL, whichever thread triggers it, and that pause is the
   largest lag the worker leaves.

    python benchmarks/live_fusion.py

Anchor (issue 29): at most 20 ms per radar scan for the fusion step with 1,000 vessels;
ingestion never blocked by the fusion.
"""

from __future__ import annotations

import argparse
import asyncio
import gc
import os
import time

import numpy as np

from seatrack.fusion.picture import parse_fusion_config
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import enu_to_geodetic
from seatrack.live.ais import LiveAis
from seatrack.live.fusion import LiveFusion

PERIOD = 3.0
T0 = 1.7e9


def scene(n: int, scans: int) -> tuple[LiveFusion, list[tuple[list, float, dict]]]:
    """A fusion and per scan: the emitted AIS estimates, the time and the radar columns."""
    setup, cfg = parse_fusion_config(
        {"lat_deg": 56.0, "lon_deg": 7.0, "max_range_m": 30000.0, "fusion": {"land_mask": False}}
    )
    fusion = LiveFusion(setup, cfg)
    ais = LiveAis()
    ais.emitted = []
    rng = np.random.default_rng(0)
    start = rng.uniform(-20000.0, 20000.0, (n, 2))
    course = rng.uniform(0.0, 2 * np.pi, n)
    vel = 8.0 * KNOT_MPS * np.stack([np.sin(course), np.cos(course)], -1)
    mmsi = np.arange(n, dtype=np.int64) + 200_000_000
    out = []
    for s in range(scans):
        t = T0 + PERIOD * s
        xy = start + vel * (t - 0.5 - T0)  # the reports half a second before the scan
        lat, lon, _ = enu_to_geodetic(np.c_[xy, np.zeros(n)], 56.0, 7.0)
        ais.add(mmsi, np.full(n, t - 0.5), lat, lon, np.full(n, 8.0), np.degrees(course))
        pos = start + vel * (t - T0)
        cols = {"x_m": pos[:, 0], "y_m": pos[:, 1], "std_x_m": np.full(n, 20.0),
                "std_y_m": np.full(n, 20.0)}  # fmt: skip
        out.append((list(ais.emitted), t, cols))
        ais.emitted.clear()
    return fusion, out


def per_scan(n: int, scans: int) -> None:
    fusion, data = scene(n, scans)
    fusion.start()
    add_s, hand_s, step_s = [], [], []
    for emitted, t, cols in data:
        tic = time.perf_counter()
        fusion.add_estimates(emitted)
        add_s.append((time.perf_counter() - tic) / max(len(emitted), 1))
        tic = time.perf_counter()
        fusion.scan(t, np.arange(n, dtype=np.int64), None, cols)
        hand_s.append(time.perf_counter() - tic)
        fusion.wait_idle()
        step_s.append(fusion.last_step_s)
    fusion.close()
    ms = 1e3 * np.array(step_s[2:])
    ais_share = sum(f.klass == "ais" for f in fusion.tracks.values()) / n
    print(f"{n} vessels, {n} radar tracks, {scans} scans: fusion step (worker) "
          f"{np.median(ms):.1f} ms median, {ms.max():.1f} ms max per scan (target <= 20 ms); "
          f"errors {fusion.errors or 0}")  # fmt: skip
    print(f"  event loop: add_estimates {1e6 * np.median(add_s[2:]):.2f} us per AIS report, "
          f"scan hand-over {1e3 * np.median(hand_s[2:]):.2f} ms per scan")  # fmt: skip
    print(f"  radar tracks classed ais at the last scan: {ais_share:.3f}")


async def lag(fusion: LiveFusion | None, data: list, period: float, inline: bool) -> tuple:
    """Max and p99 loop lag (ms) while scans are handed over every ``period`` s."""
    lags: list[float] = []
    done = asyncio.Event()

    async def ticker() -> None:
        while not done.is_set():
            t = time.perf_counter()
            await asyncio.sleep(0.001)
            lags.append(time.perf_counter() - t - 0.001)

    async def driver() -> None:
        for emitted, t, cols in data:
            if fusion is not None:
                fusion.add_estimates(emitted)
                fusion.scan(t, np.arange(len(cols["x_m"]), dtype=np.int64), None, cols)
            await asyncio.sleep(period)
        if fusion is not None and not inline:
            await asyncio.to_thread(fusion.wait_idle)
        done.set()

    await asyncio.gather(ticker(), driver())
    ms = 1e3 * np.array(lags)
    return float(ms.max()), float(np.percentile(ms, 99))


def loop_lag(n: int, scans: int, period: float) -> None:
    for mode, frozen in (("none", True), ("worker", True), ("in loop", True), ("worker", False)):
        fusion, data = scene(n, scans)
        if mode == "worker":
            fusion.start()
        use = None if mode == "none" else fusion
        gc.collect()
        if frozen:  # the precomputed scans out of the collector's full passes
            gc.freeze()
        worst, p99 = asyncio.run(lag(use, data, period, mode == "in loop"))
        gc.unfreeze()
        steps = 1e3 * np.array(fusion.step_times()[1:]) if use is not None else np.zeros(1)
        fusion.close()
        drop = fusion.dropped if use is not None else 0
        heap = "frozen" if frozen else "not frozen"
        print(f"{n} vessels, fusion {mode:7s} (heap {heap:10s}): loop lag max {worst:6.1f} ms, "
              f"p99 {p99:5.1f} ms (step median {np.median(steps):.0f} ms, {drop} scans "
              f"dropped)")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vessels", type=int, default=1000)
    ap.add_argument("--scans", type=int, default=30)
    ap.add_argument("--lag-vessels", type=int, default=10_000)
    ap.add_argument("--lag-scans", type=int, default=8)
    ap.add_argument("--lag-period", type=float, default=0.5)
    args = ap.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    per_scan(args.vessels, args.scans)
    if args.lag_vessels > 0:  # 0: the time per scan only
        loop_lag(args.lag_vessels, args.lag_scans, args.lag_period)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
