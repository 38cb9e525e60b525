"""Landmark navigation (JP H03-66630) on a simulated 10 km river passage.

Cases (same route and landmark layout, seeded Monte-Carlo runs, each run a fresh echo
log, map errors and start error):

* nominal: 18 landmarks (points and contour elements), 2.5 s antenna, 1.2 deg beam,
  2 kHz PRF, 6 m bins, 3 km range, clutter 1e-5 /m^2/rev (~280 false samples per
  revolution), 20 % missed landmark passes, landmark coordinate errors sigma 3 m per axis,
  gyro 0.05 deg/s per sample at 10 Hz; start error 10 m / 1 deg;
* no gyro;
* hidden: all landmarks invisible for 120 s (t = 1200..1320 s), recovery afterwards;
The navigator is told the map accuracy (``map_sigma`` = 3 m).

* survey: every landmark displaced 30 m in a random direction; repeated passages
  (GNSS 5 m at 1 Hz fused during the survey passages, and radar + gyro only), the map
  corrected after each pass; landmark position error reported per pass (2-D for points,
  along the normal for contour elements). During a survey pass ``map_sigma`` is the prior
  30 m, then the RMS correction of the previous pass.

Run: ``python benchmarks/navigation.py [--quick] [--runs N]``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from seatrack.evaluate.montecarlo import format_table
from seatrack.evaluate.montecarlo import monte_carlo
from seatrack.geometry import wrap_pi
from seatrack.navigation.navigator import AuxData
from seatrack.navigation.navigator import Echoes
from seatrack.navigation.navigator import NavigatorConfig
from seatrack.navigation.navigator import navigate
from seatrack.navigation.survey import survey
from seatrack.simulate.radar_echoes import EchoEnvironment
from seatrack.simulate.radar_echoes import channel_landmarks
from seatrack.simulate.radar_echoes import river_route
from seatrack.simulate.radar_echoes import simulate_radar

ROUTE = river_route(10_000.0, 4.0)
LANDMARKS = channel_landmarks(ROUTE, 18, np.random.default_rng(20260308))
HIDE = (1200.0, 1320.0)
DIVERGED_M = 100.0


def _truth_at(run, t):
    return np.column_stack([np.interp(t, run.truth_t, run.truth[:, i]) for i in range(6)])


def _start(run, rng):
    x0 = run.truth[0].copy()
    x0[:2] += rng.normal(0.0, 10.0 / np.sqrt(2), 2)
    x0[2] += np.radians(rng.normal(0.0, 1.0))
    return x0


def nav_case(env: EchoEnvironment, use_gyro: bool):
    def fn(rng: np.random.Generator, run: int) -> dict:
        sim = simulate_radar(ROUTE, LANDMARKS, rng, env=env)
        x0 = _start(sim, rng)
        e = sim.echoes
        t = time.perf_counter()
        res = navigate(
            sim.nav_map,
            Echoes(e.t, e.antenna, e.range),
            x0,
            NavigatorConfig(map_sigma=env.map_error_std),  # q_turn raised without gyro
            gyro=(sim.gyro_t, sim.gyro_rate) if use_gyro else None,
            t0=0.0,
        )
        wall = time.perf_counter() - t
        tr = _truth_at(sim, res.t)
        pe = np.hypot(res.x[:, 0] - tr[:, 0], res.x[:, 1] - tr[:, 1])
        he = np.degrees(wrap_pi(res.x[:, 2] - tr[:, 2]))
        d = res.x[:, :2] - tr[:, :2]
        # marginal NEES per axis (East, North), averaged: 1 for a consistent filter
        nees_x = (d[:, 0] / res.std[:, 0]) ** 2
        nees_y = (d[:, 1] / res.std[:, 1]) ** 2
        return {
            "t": res.t,
            "pe": pe,
            "he": he,
            "nees1": 0.5 * (nees_x + nees_y),
            "wall": wall,
            "sim_s": res.t[-1] - res.t[0],
        }

    return fn


def summarise(name: str, arr: dict, skip_s: float = 60.0) -> dict:
    t = arr["t"][0]
    use = t >= t[0] + skip_s
    pe, he = arr["pe"][:, use], arr["he"][:, use]
    per_run_max = arr["pe"].max(axis=1)
    div = int(np.sum((per_run_max > DIVERGED_M) | (arr["pe"][:, -1] > 20.0)))
    row = {
        "case": name,
        "runs": pe.shape[0],
        "pos_rmse_m": float(np.sqrt(np.mean(pe**2))),
        "pos_p95_m": float(np.percentile(pe, 95)),
        "worst_m": float(arr["pe"].max()),
        "within_10m": float(np.mean(pe <= 10.0)),
        "head_rmse_deg": float(np.sqrt(np.mean(he**2))),
        "nees_1d": float(np.mean(arr["nees1"][:, use])),
        "diverged": div,
        "rtf": float(np.sum(arr["sim_s"]) / np.sum(arr["wall"])),
    }
    return row


def over_time(arr: dict, edges) -> list[str]:
    t = arr["t"][0]
    out = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        m = (t >= lo) & (t < hi)
        p = np.sqrt(np.mean(arr["pe"][:, m] ** 2))
        h = np.sqrt(np.mean(arr["he"][:, m] ** 2))
        out.append(f"{p:5.1f} m / {h:4.2f} deg")
    return out


def recovery(arr: dict) -> dict:
    t = arr["t"][0]
    pe = arr["pe"]
    during = (t >= HIDE[0]) & (t <= HIDE[1])
    after = t > HIDE[1]
    rec = []
    for r in range(pe.shape[0]):
        ok = np.flatnonzero(after & (pe[r] <= 10.0))
        # time after the landmarks reappear until the error is back within 10 m
        rec.append(t[ok[0]] - HIDE[1] if ok.size else np.inf)
    m5 = after & (t <= HIDE[1] + 300.0)
    return {
        "max_err_hidden_m": float(pe[:, during].max()),
        "rmse_hidden_m": float(np.sqrt(np.mean(pe[:, during] ** 2))),
        "rmse_5min_after_m": float(np.sqrt(np.mean(pe[:, m5] ** 2))),
        "recovery_s_median": float(np.median(rec)),
        "recovery_s_max": float(np.max(rec)),
        "worst_after_1620s_m": float(pe[:, t > HIDE[1] + 300.0].max()),
    }


def survey_case(n_runs: int, passes: int, use_gnss: bool, seed: int) -> np.ndarray:
    """Mean landmark position error (m) before pass 1 and after each pass, per run."""
    ss = np.random.SeedSequence(seed).spawn(n_runs)
    errs = np.zeros((n_runs, passes + 1))
    for r in range(n_runs):
        rng = np.random.default_rng(ss[r])
        ang = rng.uniform(0, 2 * np.pi, len(LANDMARKS))
        cur = LANDMARKS.with_xy(LANDMARKS.xy + 30.0 * np.column_stack([np.sin(ang), np.cos(ang)]))
        errs[r, 0] = _map_error(cur)
        sigma = 30.0  # prior landmark uncertainty, then the RMS correction of the last pass
        for k in range(passes):
            sim = simulate_radar(ROUTE, LANDMARKS, rng, nav_map=cur)
            aux = None
            if use_gnss:
                gt = np.arange(0.0, ROUTE.t[-1], 1.0)
                tr = _truth_at(sim, gt)
                aux = AuxData(gnss=(gt, tr[:, :2] + rng.normal(0, 5.0, (gt.size, 2))))
            e = sim.echoes
            res = navigate(
                cur,
                Echoes(e.t, e.antenna, e.range),
                _start(sim, rng),
                NavigatorConfig(map_sigma=sigma),
                gyro=(sim.gyro_t, sim.gyro_rate),
                aux=aux,
                t0=0.0,
            )
            sv = survey(cur, [res])
            cur = sv.corrected
            sigma = max(float(np.sqrt(np.mean(np.sum(sv.correction**2, axis=1)))), 3.0)
            errs[r, k + 1] = _map_error(cur)
    return errs


def _map_error(m) -> float:
    """Mean landmark error (m): full 2-D for points, along the normal for contour elements
    (the position along a contour line is not observable and not used)."""
    d = m.xy - LANDMARKS.xy
    n = np.column_stack([np.sin(LANDMARKS.normal), np.cos(LANDMARKS.normal)])
    e = np.where(LANDMARKS.is_contour, np.abs(np.sum(d * n, axis=1)), np.hypot(d[:, 0], d[:, 1]))
    return float(np.mean(e))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="smoke run: 3 runs, 1 survey run")
    ap.add_argument("--runs", type=int, default=50)
    ap.add_argument("--survey-runs", type=int, default=50)
    ap.add_argument("--passes", type=int, default=3)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    n = 3 if a.quick else a.runs
    n_sv = 1 if a.quick else a.survey_runs
    nominal = EchoEnvironment()
    cases = [
        ("nominal", nominal, True),
        ("no gyro", nominal, False),
        ("hidden 2 min", replace(nominal, hidden=(HIDE,)), True),
    ]
    print(
        f"route {ROUTE.t[-1]:.0f} s, {len(LANDMARKS)} landmarks "
        f"({int(LANDMARKS.is_contour.sum())} contour elements), {n} runs per case"
    )
    rows, results = [], {}
    for name, env, gyro in cases:
        t = time.perf_counter()
        mc = monte_carlo(nav_case(env, gyro), n, a.seed)
        results[name] = mc.arrays
        rows.append(summarise(name, mc.arrays))
        print(f"  {name}: {time.perf_counter() - t:.0f} s", flush=True)
    anchor = rows[0]["pos_rmse_m"]
    for r in rows:
        r["ratio"] = r["pos_rmse_m"] / anchor
    print()
    print(
        format_table(
            rows,
            [
                ("case", "case"),
                ("runs", "runs", "d"),
                ("pos_rmse_m", "pos RMSE m", ".2f"),
                ("ratio", "x nominal", ".2f"),
                ("pos_p95_m", "p95 m", ".1f"),
                ("worst_m", "worst m", ".1f"),
                ("within_10m", "<=10 m", ".3f"),
                ("head_rmse_deg", "head RMSE deg", ".3f"),
                ("nees_1d", "NEES/axis", ".2f"),
                ("diverged", "diverged", "d"),
                ("rtf", "RTF", ".0f"),
            ],
        )
    )
    edges = [0, 60, 500, 1000, 1200, 1320, 1600, 2000, 2500]
    print("\nposition / heading RMSE over time (s):")
    hdr = "  ".join(f"{lo}-{hi}" for lo, hi in zip(edges[:-1], edges[1:], strict=True))
    print(f"{'':14s}{hdr}")
    for name in results:
        print(f"{name:14s}" + " | ".join(over_time(results[name], edges)))
    rc = recovery(results["hidden 2 min"])
    print("\nhidden 2 min (1200-1320 s): " + ", ".join(f"{k} {v:.1f}" for k, v in rc.items()))
    print(f"\nsurvey: 30 m landmark errors, {n_sv} runs, mean landmark error (m) per pass")
    srows = []
    for gnss in (True, False):
        e = survey_case(n_sv, a.passes, gnss, a.seed + 1)
        row = {"survey": "radar+gyro+GNSS" if gnss else "radar+gyro"}
        for k in range(a.passes + 1):
            row[f"p{k}"] = float(e[:, k].mean())
        srows.append(row)
    cols = [("survey", "survey")] + [
        (f"p{k}", "before" if k == 0 else f"after pass {k}", ".1f") for k in range(a.passes + 1)
    ]
    print(format_table(srows, cols))
    print(
        "\ntargets: nominal pos RMSE <= 10 m: "
        f"{'MET' if rows[0]['pos_rmse_m'] <= 10 else 'NOT MET'}; heading RMSE <= 1 deg: "
        f"{'MET' if rows[0]['head_rmse_deg'] <= 1 else 'NOT MET'}; no divergence: "
        f"{'MET' if all(r['diverged'] == 0 for r in rows) else 'NOT MET'}; RTF >= 50: "
        f"{'MET' if min(r['rtf'] for r in rows) >= 50 else 'NOT MET'}"
    )


if __name__ == "__main__":
    main()
