"""AIS tracking throughput: reports per second, end to end (read, track, write) and for the
tracking stage alone, on the real files bundled in seatrack/data/ais and on a synthetic
1,000,000-report file generated in a temporary directory.

    python benchmarks/ais.py            # full run (a few minutes)
    python benchmarks/ais.py --quick    # smoke run (100,000 synthetic reports)

One core: numba runs the tracker single-threaded and BLAS threads are pinned to 1.
The anchor is the same coordinated-turn EKF written as one Python loop per report over
``seatrack.kalman`` (single-track predict/update), timed on the first 20,000 reports of the
all-vessels North Sea file; the ``x anchor`` column is the tracking-stage speed-up over it.
The target for the tracking stage is >= 100,000 reports/s.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from seatrack.commands.ais import track_columns  # noqa: E402
from seatrack.data import AIS_SAMPLES, ais_sample  # noqa: E402
from seatrack.filters.ais import AisTrackerConfig, track_reports, track_vessels  # noqa: E402
from seatrack.geometry import local_frames  # noqa: E402
from seatrack.io.ais import read_ais, write_tracks_csv  # noqa: E402

DATA = ais_sample(AIS_SAMPLES[0]).parent  # the real files bundled in seatrack/data/ais
REAL = list(AIS_SAMPLES)
TARGET = 100_000.0


def synthetic_csv(path: Path, n_reports: int, n_vessels: int = 1000, seed: int = 0) -> None:
    """Write ``n_reports`` AIS reports of ``n_vessels`` manoeuvring vessels (common schema).

    Each vessel: 2-15 s report intervals, speed 2-20 kn, turn rate piecewise constant
    (new value, mostly 0, every ~2 min, up to 1 deg/s), 4 m position noise, 0.2 % gross
    jumps of 500 m. Positions are placed around 56 N 7 E with a local flat-earth map
    (synthetic data: only the tracker's speed is measured here).
    """
    rng = np.random.default_rng(seed)
    per = np.full(n_vessels, n_reports // n_vessels)
    per[: n_reports - per.sum()] += 1
    vid = np.repeat(np.arange(n_vessels), per)
    dt = rng.uniform(2.0, 15.0, n_reports)
    first = np.r_[0, np.cumsum(per)[:-1]]
    dt[first] = 0.0
    t = np.cumsum(dt)
    t -= np.repeat(t[first], per)
    t += 1667293200.0 + np.repeat(rng.uniform(0, 600, n_vessels), per)
    speed = np.repeat(rng.uniform(2, 20, n_vessels), per) * 1852 / 3600
    seg = np.floor((t - t.min()) / 120.0).astype(np.int64)
    w = np.where(rng.random(n_reports) < 0.3, rng.uniform(-1, 1, n_reports), 0.0)
    w = np.radians(w)
    # piecewise constant per (vessel, 2-min block): take the value at the block's first row
    key = vid * (seg.max() + 1) + seg
    _, blk_first, blk_inv = np.unique(key, return_index=True, return_inverse=True)
    w = w[blk_first][blk_inv.ravel()]
    heading = np.cumsum(w * dt)
    heading -= np.repeat(heading[first], per)
    heading += np.repeat(rng.uniform(0, 2 * np.pi, n_vessels), per)
    e = np.cumsum(speed * np.sin(heading) * dt)
    n = np.cumsum(speed * np.cos(heading) * dt)
    e -= np.repeat(e[first], per)
    n -= np.repeat(n[first], per)
    e += rng.normal(0, 4.0, n_reports) + np.repeat(rng.uniform(-1e5, 1e5, n_vessels), per)
    n += rng.normal(0, 4.0, n_reports) + np.repeat(rng.uniform(-1e5, 1e5, n_vessels), per)
    jump = rng.random(n_reports) < 0.002
    e[jump] += 500.0
    lat = 56.0 + n / 111_320.0
    lon = 7.0 + e / (111_320.0 * math.cos(math.radians(56.0)))
    sog = speed / (1852 / 3600)
    cog = np.degrees(np.mod(heading, 2 * np.pi))
    times = (t * 1000).astype(np.int64).astype("datetime64[ms]")
    iso = np.datetime_as_string(times, unit="s")
    mmsi = 211000000 + vid
    with path.open("w") as fh:
        fh.write("mmsi,time_utc,lat,lon,sog_kn,cog_deg,heading_deg\n")
        fh.writelines(
            f"{a},{b}Z,{c:.6f},{d:.6f},{s:.1f},{g:.1f},{int(g)}\n"
            for a, b, c, d, s, g in zip(
                mmsi.tolist(),
                iso.tolist(),
                lat.tolist(),
                lon.tolist(),
                sog.tolist(),
                cog.tolist(),
                strict=True,
            )
        )


def python_loop_anchor(path: Path, n: int, cfg: AisTrackerConfig) -> float:
    """Reports/s of a per-report Python loop (CT EKF via seatrack.kalman, no smoothing)."""
    from seatrack import kalman
    from seatrack.models import CoordinatedTurn

    r = read_ais([path])
    fr = local_frames(r.mmsi, r.lat, r.lon, r.valid)
    ok = np.flatnonzero(r.valid)[:n]
    order = ok[np.lexsort((r.t[ok], r.mmsi[ok]))]
    model = CoordinatedTurn(q=cfg.q_accel, q_omega=cfg.q_turn)
    H = np.zeros((2, 5))
    H[0, 0] = H[1, 1] = 1.0
    R = np.eye(2) * cfg.sigma_pos_m**2
    gate = cfg.gate
    t0 = time.perf_counter()
    last_m, x, P, tl = -1, np.zeros(5), np.eye(5), 0.0
    for i in order:
        z = fr.enu[i, :2]
        if r.mmsi[i] != last_m:
            last_m, tl = int(r.mmsi[i]), float(r.t[i])
            x = np.array([z[0], z[1], 0.0, 0.0, 0.0])
            P = np.diag([cfg.sigma_pos_m**2] * 2 + [cfg.init_speed_std_mps**2] * 2 + [1e-4])
            continue
        dt = float(r.t[i]) - tl
        tl = float(r.t[i])
        fx, F = model.transition(x, dt)
        x, P = kalman.extended_predict(fx, P, F, model.noise(dt))
        res = kalman.update(x, P, z, H, R)
        if res.nis <= gate:
            x, P = res.x, res.P
    return order.size / (time.perf_counter() - t0)


def run_file(path: Path, cfg: AisTrackerConfig, out_dir: Path) -> dict[str, float]:
    t0 = time.perf_counter()
    r = read_ais([path])
    t1 = time.perf_counter()
    tr = track_reports(r, cfg)
    t2 = time.perf_counter()
    write_tracks_csv(out_dir / "TRACKS.csv", r, track_columns(tr))
    t3 = time.perf_counter()
    # the tracking stage again, best of 3 (the machine's timing noise is +-30 %)
    track_best = t2 - t1
    for _ in range(2):
        s = time.perf_counter()
        track_reports(r, cfg)
        track_best = min(track_best, time.perf_counter() - s)
    # the tracking kernel alone (local frame precomputed), best of 3
    fr = local_frames(r.mmsi, r.lat, r.lon, r.valid)
    ok = r.valid
    best = math.inf
    for _ in range(3):
        s = time.perf_counter()
        track_vessels(r.mmsi[ok], r.t[ok], fr.enu[ok, :2], cfg)
        best = min(best, time.perf_counter() - s)
    n = len(r)
    return {
        "n": n,
        "vessels": float(np.unique(r.mmsi[ok]).size),
        "read": t1 - t0,
        "track": track_best,
        "kernel": best,
        "write": t3 - t2,
        "e2e": t3 - t0,
        "rate_e2e": n / (t3 - t0),
        "rate_track": n / track_best,
        "rate_kernel": int(ok.sum()) / best,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: 100,000 synthetic reports")
    args = ap.parse_args(argv)
    cfg = AisTrackerConfig()
    for name in REAL:
        if not (DATA / name).is_file():
            print(f"error: real AIS data missing: {(DATA / name).resolve()}", file=sys.stderr)
            return 2
    # compile (numba caches to disk; the first call of a fresh checkout compiles)
    track_reports(read_ais([DATA / REAL[3]]), cfg)
    n_syn = 100_000 if args.quick else 1_000_000
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmpd = Path(tmp)
        real = REAL[2:4] if args.quick else REAL
        for name in real:
            rows.append((name, run_file(DATA / name, cfg, tmpd)))
        syn = tmpd / "synthetic.csv"
        s = time.perf_counter()
        synthetic_csv(syn, n_syn)
        gen = time.perf_counter() - s
        rows.append((f"synthetic_{n_syn // 1000}k.csv", run_file(syn, cfg, tmpd)))
        # the same file without the refinement pass (timestamp offsets, steady/manoeuvring
        # choice): what the refinement costs
        fast = run_file(syn, replace(cfg, refine=False), tmpd)
        anchor = python_loop_anchor(DATA / REAL[2], 5_000 if args.quick else 20_000, cfg)
    hdr = (
        f"{'file':38s} {'reports':>9s} {'vessels':>7s} {'read s':>7s} {'track s':>7s} "
        f"{'write s':>7s} {'e2e s':>7s} {'e2e rep/s':>10s} {'track rep/s':>11s} "
        f"{'kernel rep/s':>12s} {'x anchor':>8s} {'>=100k':>6s}"
    )
    print(hdr)
    print("-" * len(hdr))
    for name, m in rows:
        print(
            f"{name:38s} {m['n']:9d} {int(m['vessels']):7d} {m['read']:7.2f} "
            f"{m['track']:7.2f} {m['write']:7.2f} {m['e2e']:7.2f} {m['rate_e2e']:10,.0f} "
            f"{m['rate_track']:11,.0f} {m['rate_kernel']:12,.0f} "
            f"{m['rate_track'] / anchor:8.1f} {'yes' if m['rate_track'] >= TARGET else 'NO':>6s}"
        )
    print(
        f"{'anchor: Python loop per report (CT EKF)':38s} {'':9s} {'':7s} {'':7s} {'':7s} "
        f"{'':7s} {'':7s} {'':10s} {anchor:11,.0f} {'':12s} {1.0:8.1f} "
        f"{'yes' if anchor >= TARGET else 'NO':>6s}"
    )
    print(
        f"(track = whole tracking stage, best of 3: local frame, tracker with revisit passes, "
        f"refinement pass and RTS, back to lat/lon and true course; kernel = compiled tracker "
        f"alone, best of 3; e2e = one run; synthetic file generated in {gen:.1f} s)"
    )
    print(
        f"synthetic without the refinement pass (refine=False): track {fast['rate_track']:,.0f} "
        f"rep/s, kernel {fast['rate_kernel']:,.0f} rep/s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
