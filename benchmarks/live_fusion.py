"""The live process's radar-AIS fusion step: time per scan and per AIS report, in process.

``--vessels`` AIS vessels (default 1,000) moving straight at 8 kn within 20 km of the
radar each report once per scan (every 3 s) to a :class:`seatrack.live.ais.LiveAis`;
the radar tracks are the vessels' true positions (one per vessel, 20 m sigma). Each scan
calls :meth:`seatrack.live.fusion.LiveFusion.add_estimates` with the states the AIS filter
emitted (the part on the ingest path) and :meth:`~seatrack.live.fusion.LiveFusion.scan`
(the step after the scan's tracker step: the new states to WGS84, prediction,
association, classes). Printed: the median and maximum per scan over ``--scans`` scans
(the first two left out: compilation), the time per AIS report of ``add_estimates``, the
share of radar tracks classed ``ais``, and the load average (the machine is shared).

    python benchmarks/live_fusion.py
    NUMBA_NUM_THREADS=1 python benchmarks/live_fusion.py   # one thread for the kernels

Anchor (issue 29): at most 20 ms per radar scan for the fusion step with 1,000 vessels.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from seatrack.fusion.picture import parse_fusion_config
from seatrack.geometry import KNOT_MPS
from seatrack.live.ais import LiveAis
from seatrack.live.fusion import LiveFusion


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vessels", type=int, default=1000)
    ap.add_argument("--scans", type=int, default=30)
    args = ap.parse_args()
    n = args.vessels
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
    t0, period = 1.7e9, 3.0
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    scan_s, add_s = [], []
    for s in range(args.scans):
        t = t0 + period * s
        xy = start + vel * (t - 0.5 - t0)  # the reports half a second before the scan
        lat, lon = _geodetic(fusion, xy)
        ais.add(mmsi, np.full(n, t - 0.5), lat, lon, np.full(n, 8.0), np.degrees(course))
        tic = time.perf_counter()
        fusion.add_estimates(ais.emitted)
        add_s.append((time.perf_counter() - tic) / max(len(ais.emitted), 1))
        ais.emitted.clear()
        pos = start + vel * (t - t0)
        cols = {"x_m": pos[:, 0], "y_m": pos[:, 1], "std_x_m": np.full(n, 20.0),
                "std_y_m": np.full(n, 20.0)}  # fmt: skip
        tic = time.perf_counter()
        fusion.scan(t, np.arange(n, dtype=np.int64), None, cols)
        scan_s.append(time.perf_counter() - tic)
    ms = 1e3 * np.array(scan_s[2:])
    ais_share = sum(f.klass == "ais" for f in fusion.tracks.values()) / n
    print(f"{n} vessels, {n} radar tracks: fusion step {np.median(ms):.1f} ms median, "
          f"{ms.max():.1f} ms max per scan (target <= 20 ms)")  # fmt: skip
    print(f"add_estimates: {1e6 * np.median(add_s[2:]):.1f} us per AIS report (ingest path)")
    print(f"radar tracks classed ais at the last scan: {ais_share:.3f}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


def _geodetic(fusion: LiveFusion, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """WGS84 (deg) of positions in the radar's plane."""
    from seatrack.geometry import enu_to_geodetic

    site = fusion.coverage.site
    enu = np.c_[xy, np.zeros(len(xy))]
    lat, lon, _ = enu_to_geodetic(enu, np.degrees(site.lat), np.degrees(site.lon))
    return lat, lon


if __name__ == "__main__":
    main()
