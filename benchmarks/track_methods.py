"""``seatrack track`` end to end, every method, against a FilterPy EKF loop on the same plots.

A radar file of 40 targets (2 s scans for 290 s: 5,800 plots of range, azimuth and range
rate, sensor at rest at the origin; straight legs and 1-3 g turns) is written once with
:func:`seatrack.simulate.files.write_plots`. For every registered method the timed
work is what ``seatrack track`` does after start-up: read PLOTS.csv, run the method over
all tracks, write TRACK.csv (best of ``--repeat`` runs, after one warm-up run that compiles
the kernels). The anchor is a plain Python loop over FilterPy's ``ExtendedKalmanFilter``
(CV, range/azimuth/range-rate with a wrapped azimuth residual) on the same plots, also end to
end: the ``csv`` module reads the file and writes one row per plot.

Target (issue 14): every method at least 3x faster per plot than the FilterPy loop.

Run: ``python benchmarks/track_methods.py [--quick] [--repeat N]``.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from seatrack.filters.registry import METHODS
from seatrack.filters.registry import run
from seatrack.io.plots import read_plots
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory
from seatrack.simulate.files import write_plots

SIGMA = (20.0, math.radians(0.5), 1.0)  # range m, azimuth rad, range rate m/s
CONFIG = {"sigma_range_m": SIGMA[0], "sigma_azimuth_deg": 0.5, "sigma_range_rate_mps": SIGMA[2]}


def make_plots(path: Path, n_targets: int, duration: float, seed: int = 1) -> int:
    """Write the benchmark PLOTS.csv; returns the number of plots."""
    rng = np.random.default_rng(seed)
    tracks = []
    for j in range(n_targets):
        r0 = rng.uniform(5e3, 40e3)
        b0 = rng.uniform(0, 2 * math.pi)
        start = [r0 * math.sin(b0), r0 * math.cos(b0)]
        speed = rng.uniform(5.0, 250.0)
        third = duration / 3
        g = rng.uniform(1.0, 3.0) if speed > 50 else 0.02
        legs = [Leg.straight(third), Leg.turn_g(math.pi / 2, g, speed), Leg.straight(duration)]
        times = np.arange(0.0, duration, 2.0)
        tr = trajectory(start, rng.uniform(0, 2 * math.pi), speed, legs, times=times)
        m = observe(tr, None, ("range", "azimuth", "range_rate"), NoiseModel(list(SIGMA)), rng)
        tracks.append((f"T{j + 1}", m))
    return write_plots(path, tracks)


def seatrack_track(plots_csv: Path, out: Path, method: str) -> None:
    """What ``seatrack track`` does after start-up."""
    from seatrack.api.track import write_track_csv

    plots = read_plots(plots_csv)
    cols = run(method, plots, CONFIG)
    assert plots.track is not None
    write_track_csv(out, plots.track, plots.t, cols)


def filterpy_track(plots_csv: Path, out: Path) -> None:
    """A plain Python loop over FilterPy's ExtendedKalmanFilter, end to end."""
    from filterpy.kalman import ExtendedKalmanFilter

    with open(plots_csv, newline="") as fh:
        rows = list(csv.DictReader(fh))
    by_track: dict[str, list[dict[str, str]]] = {}
    for r in rows:
        by_track.setdefault(r["track"], []).append(r)
    R = np.diag(np.square(SIGMA))
    q = 1.0

    def hx(x: np.ndarray) -> np.ndarray:
        r = math.hypot(x[0], x[1])
        return np.array(
            [r, math.atan2(x[0], x[1]) % (2 * math.pi), (x[0] * x[2] + x[1] * x[3]) / r]
        )

    def jac(x: np.ndarray) -> np.ndarray:
        px, py, vx, vy = x
        r2 = px * px + py * py
        r = math.sqrt(r2)
        rd = (px * vx + py * vy) / r
        return np.array(
            [
                [px / r, py / r, 0.0, 0.0],
                [py / r2, -px / r2, 0.0, 0.0],
                [(vx - rd * px / r) / r, (vy - rd * py / r) / r, px / r, py / r],
            ]
        )

    def residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        y = a - b
        y[1] = (y[1] + math.pi) % (2 * math.pi) - math.pi
        return y

    with open(out, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["track", "time_s", "x_m", "y_m", "vx_mps", "vy_mps", "std_x_m", "std_y_m"])
        for tid, rs in by_track.items():
            f = ExtendedKalmanFilter(dim_x=4, dim_z=3)
            t_prev = None
            for r in rs:
                t = float(r["time_s"])
                z = np.array(
                    [float(r["range_m"]), math.radians(float(r["azimuth_deg"])),
                     float(r["range_rate_mps"])]
                )  # fmt: skip
                if t_prev is None:
                    az = z[1]
                    f.x = np.array([z[0] * math.sin(az), z[0] * math.cos(az), 0.0, 0.0])
                    f.P = np.diag([SIGMA[0] ** 2 * 50, SIGMA[0] ** 2 * 50, 50.0**2, 50.0**2])
                else:
                    dt = t - t_prev
                    f.F = np.array(
                        [[1, 0, dt, 0], [0, 1, 0, dt], [0, 0, 1, 0], [0, 0, 0, 1]], float
                    )
                    b = np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]]) * q
                    f.Q = np.kron(b, np.eye(2))
                    f.predict()
                    f.update(z, jac, hx, R=R, residual=residual)
                t_prev = t
                s = np.sqrt(np.diag(f.P))
                w.writerow([tid, f"{t:.6f}", *(f"{v:.6f}" for v in (*f.x, s[0], s[1]))])


def best_times(jobs: dict[str, object], repeat: int) -> dict[str, float]:
    """Best of ``repeat`` rounds per job; each round runs every job once, so a change of
    machine load hits the anchor and the methods alike."""
    best = dict.fromkeys(jobs, math.inf)
    for _ in range(repeat):
        for name, fn in jobs.items():
            t0 = time.perf_counter()
            fn()  # type: ignore[operator]
            best[name] = min(best[name], time.perf_counter() - t0)
    return best


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="8 targets, 2 repeats")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    n_targets, repeat = (8, 2) if args.quick else (40, args.repeat)
    with tempfile.TemporaryDirectory() as tmp:
        plots_csv = Path(tmp) / "PLOTS.csv"
        n = make_plots(plots_csv, n_targets, 290.0)
        out = Path(tmp) / "TRACK.csv"
        jobs: dict[str, object] = {"FilterPy": lambda: filterpy_track(plots_csv, out)}
        for name in METHODS:
            jobs[name] = lambda name=name: seatrack_track(plots_csv, out, name)
        for fn in jobs.values():
            fn()  # type: ignore[operator]  # warm-up: imports, compiled kernels
        best = best_times(jobs, repeat)
        anchor = best.pop("FilterPy") / n * 1e6
        print(
            f"{n_targets} tracks, {n} plots; end to end (read CSV, run, write CSV), "
            f"best of {repeat}"
        )
        print(
            f"{'method':<17}{'us/plot':>9}{'FilterPy EKF loop':>19}{'speed-up':>10}  target >= 3x"
        )
        worst = math.inf
        for name, sec in best.items():
            us = sec / n * 1e6
            worst = min(worst, anchor / us)
            ok = "ok" if anchor / us >= 3 else "MISSED"
            print(f"{name:<17}{us:9.2f}{anchor:19.2f}{anchor / us:9.1f}x  {ok}")
        print(f"slowest method: {worst:.1f}x faster than the FilterPy EKF loop per plot")
    return 0


if __name__ == "__main__":
    sys.exit(main())
