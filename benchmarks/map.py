"""HTML map writing: time and page size for the bundled real file and synthetic days.

    python benchmarks/map.py            # full run: 1 M and 15 M synthetic reports (~2 min)
    python benchmarks/map.py --quick    # smoke run: 200,000 synthetic reports

For each input: ``vessel_tracks`` (grouping the per-report arrays by vessel), ``write_html``
(decimation, Natural Earth coast, JSON, the file), the page size and what it carries.
The anchor is the page the map had before decimation -- every smoothed position and raw
report as JSON -- timed as ``json.dumps`` alone (its size is the page it would write);
``x anchor`` is how much smaller our page is. Best of ``--repeat`` runs; the first
``write_html`` call (numba compile or cache load, land data) is done before timing.
The synthetic vessels are smooth random-heading walks around 54-58 N, 3-13 E.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from seatrack.commands.ais import track_files  # noqa: E402
from seatrack.data import ais_sample  # noqa: E402
from seatrack.report.html import VesselTrack  # noqa: E402
from seatrack.report.html import map_tracks  # noqa: E402
from seatrack.report.html import vessel_tracks  # noqa: E402
from seatrack.report.html import write_html  # noqa: E402


def synthetic(n_reports: int, n_vessels: int, seed: int = 0) -> tuple[Any, ...]:
    """Per-report arrays (``vessel_tracks`` arguments) of ``n_vessels`` smooth walks.

    2-10 s report intervals, 0-20 kn, heading a random walk (0.1 deg/report), 3-5 m
    report noise, 0.2 % gross jumps (~5 km) flagged as outliers, a new segment every
    ~5.5 h; rows in time order within each vessel.
    """
    rng = np.random.default_rng(seed)
    per = np.full(n_vessels, n_reports // n_vessels)
    per[: n_reports - per.sum()] += 1
    first = np.r_[0, np.cumsum(per)[:-1]]
    dt = rng.uniform(2, 10, n_reports)
    dt[first] = 0.0
    t = np.cumsum(dt)
    t -= np.repeat(t[first], per)
    seg = (t // 20000).astype(np.int64)
    t += 1.667e9
    speed = np.repeat(rng.uniform(0, 10, n_vessels), per)
    turn = rng.normal(0, 0.002, n_reports)
    turn[first] = rng.uniform(0, 2 * np.pi, n_vessels)
    hdg = np.cumsum(turn)
    hdg -= np.repeat(hdg[first] - turn[first], per)
    de, dn = np.cumsum(speed * dt * np.sin(hdg)), np.cumsum(speed * dt * np.cos(hdg))
    de -= np.repeat(de[first], per)
    dn -= np.repeat(dn[first], per)
    lat0 = np.repeat(rng.uniform(54, 58, n_vessels), per)
    lon0 = np.repeat(rng.uniform(3, 13, n_vessels), per)
    lat = lat0 + dn / 111_195.0
    lon = lon0 + de / (111_195.0 * np.cos(np.radians(lat0)))
    raw_lat = lat + rng.normal(0, 3e-5, n_reports)
    raw_lon = lon + rng.normal(0, 5e-5, n_reports)
    out = rng.random(n_reports) < 0.002
    raw_lat[out] += rng.normal(0, 0.05, out.sum())
    mmsi = 219_000_000 + np.repeat(np.arange(n_vessels), per)
    return mmsi, t, raw_lat, raw_lon, lat, lon, seg, out, np.ones(n_reports, bool)


def anchor(vt: list[VesselTrack]) -> tuple[float, int]:
    """Time and size of the JSON of every smoothed position and raw report (6 decimals)."""
    t0 = time.perf_counter()
    s = json.dumps(
        [
            {
                "mmsi": v.mmsi,
                "lat": np.round(v.lat, 6).tolist(),
                "lon": np.round(v.lon, 6).tolist(),
                "rlat": np.round(v.raw_lat, 6).tolist(),
                "rlon": np.round(v.raw_lon, 6).tolist(),
            }
            for v in vt
        ],
        separators=(",", ":"),
    )
    return time.perf_counter() - t0, len(s)


def measure(
    name: str, args: tuple[Any, ...] | None, vt: list[VesselTrack] | None, repeat: int
) -> None:
    best_g = float("nan")
    if args is not None:
        best_g = 1e9
        for _ in range(repeat):
            t0 = time.perf_counter()
            vt = vessel_tracks(*args)
            best_g = min(best_g, time.perf_counter() - t0)
    assert vt is not None
    n = sum(v.t.size for v in vt)
    with tempfile.TemporaryDirectory() as tmp:
        page = Path(tmp) / "map.html"
        best_w = 1e9
        for _ in range(repeat):
            t0 = time.perf_counter()
            write_html(page, vt, title=name)
            best_w = min(best_w, time.perf_counter() - t0)
        text = page.read_text(encoding="utf-8")
    data = json.loads(text.split('id="seatrack-data">', 1)[1].split("</script>", 1)[0])
    a_time, a_size = anchor(vt)
    group = "-" if args is None else f"{best_g:.2f}"
    print(
        f"{name:<34} {n:>11,} {len(vt):>7,} {group:>8} {best_w:>8.2f} "
        f"{len(text) / 1e6:>8.2f} {len(data['la']):>9,} {a_time:>8.2f} {a_size / 1e6:>9.1f} "
        f"{a_size / len(text):>8.1f}"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke run (200,000 reports)")
    ap.add_argument("--repeat", type=int, default=3, help="best of N timings")
    a = ap.parse_args(argv)
    sizes = [(200_000, 200)] if a.quick else [(1_000_000, 1000), (15_000_000, 5000)]
    write_html(Path(tempfile.gettempdir()) / "seatrack_map_warmup.html", [])  # compile, load
    print(
        f"{'input':<34} {'reports':>11} {'vessels':>7} {'group s':>8} {'write s':>8} "
        f"{'page MB':>8} {'vertices':>9} {'anchor s':>8} {'anchor MB':>9} {'x anchor':>8}"
    )
    name = "dk_northsea_20221101_1h_all.csv"
    reports, tracks = track_files([ais_sample(name)])
    measure(name, None, map_tracks(reports, tracks), a.repeat)
    for n, nv in sizes:
        args = synthetic(n, nv)
        measure(f"synthetic {n:,} / {nv:,} vessels", args, None, 1 if n > 5e6 else a.repeat)
        del args
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
