"""Benchmark: every track method as a new user runs it, on scenarios no method was tuned on.

Issue 16 ("methods that work out of the box"). For each scenario set (families of
:mod:`seatrack.simulate.families`, HEADLINE seeds only) and each ``seatrack track``
method, the **headline row** runs the method with nothing but the sensor's nominal noise
in its configuration (``sigma_range_m``, ``sigma_azimuth_deg`` and, when the plots have
it, ``sigma_range_rate_mps``); everything else is the method's default. Beside the
headline rows, labelled anchors:

* ``cv narrow`` / ``cv wide`` -- CV EKFs with the target class's steady and hardest-
  manoeuvre PSDs (``q = a^2 T`` with ``a`` = ``accel_steady`` / ``accel_max`` of
  :mod:`seatrack.models.targets`);
* ``cv best q (hindsight)`` -- the CV EKF with the q of a grid that is best ON THESE RUNS
  (an oracle: no filter can pick it in advance);
* contaminated sets also: ``cv mixture R (hindsight q)`` -- the EKF whose measurement
  variance is the mixture variance ``sigma^2 (1 - eps + eps k)``, and ``clairvoyant
  (hindsight q)`` -- the EKF that knows which plot components are outliers (variance
  ``k sigma^2`` for them), each with its own best grid q.

Every filter starts from the first plot; the anchors use the plot converted to Cartesian
with zero velocity and the class's maximum speed as velocity std. Metrics after a
transient of ``SKIP`` scans: position and velocity RMSE pooled over runs and scans (m,
m/s). The targets of the issue are printed as MET / NOT MET (ratios on headline runs):
every method <= best fixed q in hindsight on manoeuvring targets; ``turning`` <= 0.95 x
min(narrow, wide); ``robust-adaptive`` <= 0.7 x mixture-R EKF and <= 1.3 x clairvoyant at
20 % contamination; ``mm-rangerate`` <= 0.97 x best fixed q.

The methods are called in ONE place, :func:`run_method` (the registry's
:func:`~seatrack.filters.registry.run` on the filter contract).

Seeds: headline runs use seeds ``HEADLINE_SEEDS.start + i``; ``--tuning`` runs the same
table on ``TUNING_SEEDS.start + i`` instead (for development of the methods: see
``benchmarks/defaults_experiments.py``).

Run: ``python benchmarks/defaults.py`` (20 runs per set), ``--runs N``, ``--quick``
(4 runs, three sets), ``--sets a,b``, ``--methods a,b``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from seatrack import kalman
from seatrack.evaluate.montecarlo import format_table
from seatrack.filters.base import measurement_model
from seatrack.filters.base import plot_gaussian
from seatrack.filters.registry import METHODS
from seatrack.filters.registry import run
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition
from seatrack.models.targets import TargetClass
from seatrack.models.targets import target_class
from seatrack.simulate.families import ACTIVE_SONAR
from seatrack.simulate.families import COASTAL_RADAR
from seatrack.simulate.families import HEADLINE_SEEDS
from seatrack.simulate.families import TUNING_SEEDS
from seatrack.simulate.families import Scenario
from seatrack.simulate.families import SensorSpec
from seatrack.simulate.families import ais_replay
from seatrack.simulate.families import labelled_runs
from seatrack.simulate.families import random_manoeuvres
from seatrack.simulate.families import weaving

SKIP = 10  # transient scans excluded from every metric
Estimate = np.ndarray  # (B, N, 4): x, y, vx, vy per run and scan


#: a coastal radar with Doppler: the range-rate sets' second family (real AIS tracks)
DOPPLER_RADAR = SensorSpec("doppler-radar", 2.5, 10.0, math.radians(0.3), 0.2)


@dataclass(frozen=True)
class ScenarioSet:
    name: str
    target: str
    make: Callable[[int], Scenario]
    description: str


SETS: dict[str, ScenarioSet] = {
    s.name: s
    for s in (
        ScenarioSet(
            "ais-radar", "ship", lambda k: ais_replay(k, COASTAL_RADAR), "real AIS tracks, radar"
        ),
        ScenarioSet(
            "ais-sonar-c20",
            "ship",
            lambda k: ais_replay(k, ACTIVE_SONAR, 0.2),
            "real AIS tracks, sonar, 20 % contaminated",
        ),
        ScenarioSet("ship", "ship", lambda k: random_manoeuvres("ship", k), "ship, coastal radar"),
        ScenarioSet(
            "submarine-c20",
            "submarine",
            lambda k: random_manoeuvres("submarine", k, 0.2),
            "submarine, sonar, 20 % contaminated",
        ),
        ScenarioSet(
            "aircraft",
            "aircraft",
            lambda k: random_manoeuvres("aircraft", k),
            "air traffic, 1.5-3 deg/s turns, 4 s",
        ),
        ScenarioSet(
            "fighter",
            "fighter",
            lambda k: random_manoeuvres("fighter", k),
            "fighter, 3-6 g, range rate",
        ),
        ScenarioSet(
            "weave-aircraft", "aircraft", lambda k: weaving("aircraft", k), "aircraft weaving"
        ),
        ScenarioSet(
            "ais-doppler",
            "ship",
            lambda k: ais_replay(k, DOPPLER_RADAR),
            "real AIS tracks, Doppler radar (range rate)",
        ),
        ScenarioSet(
            "weave-fighter", "fighter", lambda k: weaving("fighter", k), "fighter weaving, rr"
        ),
    )
}
#: the methods of ``seatrack track`` benchmarked (all of the registry)
TRACK_METHODS = tuple(METHODS)


# ---------------------------------------------------------------------------
# The one adapter to the track methods
# ---------------------------------------------------------------------------
def nominal_config(sc: Scenario) -> dict[str, Any]:
    """What a user gives: the sensor's nominal noise, in the documented keys."""
    return sc.sensor_table()


def run_method(name: str, scs: Sequence[Scenario], config: dict[str, Any]) -> Estimate:
    """Run track method ``name`` over the runs of a set: ``(B, N, 4)`` x, y, vx, vy.

    THE adapter: the registry runs the method on the filter contract
    (:func:`seatrack.filters.registry.run`, i.e. ``run_tracks`` over a file whose tracks
    are the runs -- all runs as one batch per scan, as ``seatrack track`` does).
    """
    cols = run(name, labelled_runs(scs), config)
    est = np.stack([cols["x_m"], cols["y_m"], cols["vx_mps"], cols["vy_mps"]], -1)
    return est.reshape(len(scs), -1, 4)


# ---------------------------------------------------------------------------
# Anchors: batched CV EKFs (all runs x all q at once)
# ---------------------------------------------------------------------------
def stack_plots(scs: Sequence[Scenario]) -> dict[str, np.ndarray]:
    """Plots of runs that share their scan times, stacked ``(B, N, ...)``."""
    t = scs[0].plots.t
    if any(s.plots.t.shape != t.shape or not np.allclose(s.plots.t, t) for s in scs):
        raise ValueError("the runs of a set must share their scan times")
    rr = scs[0].plots.has_range_rate
    return {
        "t": t,
        "z": np.stack([s.plots.polar(rr) for s in scs]),
        "sensor": np.stack([np.concatenate([s.plots.sensor[:, :2], s.plots.sensor_vel[:, :2]], -1)
                            for s in scs]),
        "outlier": np.stack([s.outlier for s in scs]),
        "truth": np.stack([s.truth for s in scs]),
    }  # fmt: skip


def polar_setup(
    scs: Sequence[Scenario],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any, np.ndarray]:
    """The stacked plots ``z (B, N, m)``, sensor states ``(B, N, 4)`` and scan times of the
    runs of a set, their polar measurement model on ``[x, y, vx, vy]`` and its angular
    flags (the set-up of every batched EKF of the benchmark)."""
    st = stack_plots(scs)
    model = measurement_model(2, 4, st["z"].shape[-1] == 3)
    return st["z"], st["sensor"], st["t"], model, model.angular.astype(float)


def cv_ekf_batch(
    scs: Sequence[Scenario],
    q: np.ndarray,
    R: np.ndarray,
    speed_sigma: float,
) -> Estimate:
    """CV EKFs on polar plots for every run and every ``q`` at once.

    Parameters
    ----------
    q : (G,) PSDs, m^2/s^3.
    R : (B, N, m, m) or (m, m) measurement covariance (per run and scan, or fixed).

    Returns
    -------
    (G, B, N, 4) filtered states.
    """
    z, sen, t, model, ang = polar_setup(scs)
    B, N, m = z.shape
    G = len(q)
    x0, P0 = plot_gaussian(scs[0].plots.take(np.zeros(1, int)), scs[0].sensor, speed_sigma)
    x0 = np.stack([plot_gaussian(s.plots.take(np.zeros(1, int)), s.sensor, speed_sigma)[0][0]
                   for s in scs])  # fmt: skip
    x = np.broadcast_to(x0, (G, B, 4)).copy()
    P = np.broadcast_to(P0[0], (G, B, 4, 4)).copy()
    RR = np.broadcast_to(R, (B, N, m, m)) if R.ndim == 2 else R
    out = np.empty((G, B, N, 4))
    out[:, :, 0] = x
    for k in range(1, N):
        dt = t[k] - t[k - 1]
        F = cv_transition(dt, 2)
        Q = cv_noise(dt, q, 2)[:, None]  # (G, 1, 4, 4)
        x, P = kalman.predict(x, P, F, Q)
        s = sen[:, k]
        res = kalman.extended_update(
            x, P, z[:, k], model.h(x, s), model.jacobian(x, s), RR[:, k], ang, check=False
        )
        x, P = res.x, res.P
        out[:, :, k] = x
    return out


def rmse(est: Estimate, scs: Sequence[Scenario], skip: int = SKIP) -> tuple[float, float]:
    """Pooled position and velocity RMSE (m, m/s) of ``est (..., B, N, 4)``."""
    truth = np.stack([s.truth for s in scs])
    e = est[..., skip:, :] - truth[:, skip:]
    pos = np.sqrt(np.mean(np.sum(e[..., :2] ** 2, -1), axis=(-1, -2)))
    vel = np.sqrt(np.mean(np.sum(e[..., 2:] ** 2, -1), axis=(-1, -2)))
    return pos, vel  # type: ignore[return-value]


def q_grid(tc: TargetClass, dt: float) -> np.ndarray:
    """Log grid of CV PSDs from a tenth of the steady q to ten times the hardest one."""
    lo, hi = math.log10(tc.q_steady(dt) / 10), math.log10(tc.q_max(dt) * 10)
    return np.logspace(lo, hi, int(round((hi - lo) * 3)) + 1)


def anchor_rows(scs: Sequence[Scenario], tc: TargetClass) -> list[dict[str, Any]]:
    """The labelled anchor rows of one set (see the module docstring)."""
    sc0 = scs[0]
    dt = sc0.dt
    sig = np.array([sc0.sensor.sigma_range, sc0.sensor.sigma_azimuth, sc0.sensor.sigma_range_rate])
    m = 3 if sc0.plots.has_range_rate else 2
    R0 = np.diag(sig[:m] ** 2)
    grid = q_grid(tc, dt)
    speed_sigma = tc.speed_max
    rows = []
    narrow_wide = np.array([tc.q_steady(dt), tc.q_max(dt)])
    pos, vel = rmse(cv_ekf_batch(scs, narrow_wide, R0, speed_sigma), scs)
    rows.append(_row("cv narrow", pos[0], vel[0], f"q={narrow_wide[0]:.3g}", "anchor"))
    rows.append(_row("cv wide", pos[1], vel[1], f"q={narrow_wide[1]:.3g}", "anchor"))
    pos, vel = rmse(cv_ekf_batch(scs, grid, R0, speed_sigma), scs)
    i = int(np.argmin(pos))
    rows.append(_row("cv best q (hindsight)", pos[i], vel[i], f"q={grid[i]:.3g}", "oracle"))
    if sc0.epsilon > 0:
        k = np.array(sc0.outlier_scale)
        mix = np.diag(sig[:m] ** 2 * (1 - sc0.epsilon + sc0.epsilon * k))
        pos, vel = rmse(cv_ekf_batch(scs, grid, mix, speed_sigma), scs)
        i = int(np.argmin(pos))
        rows.append(_row("cv mixture R (hindsight q)", pos[i], vel[i], f"q={grid[i]:.3g}",
                         "anchor"))  # fmt: skip
        out = np.stack([s.outlier for s in scs])  # (B, N, m)
        var = sig[:m] ** 2 * np.where(out, k, 1.0)
        Rc = np.einsum("bni,ij->bnij", var, np.eye(m))
        pos, vel = rmse(cv_ekf_batch(scs, grid, Rc, speed_sigma), scs)
        i = int(np.argmin(pos))
        rows.append(_row("clairvoyant (hindsight q)", pos[i], vel[i], f"q={grid[i]:.3g}",
                         "oracle"))  # fmt: skip
    return rows


def _row(name: str, pos: float, vel: float, note: str, kind: str) -> dict[str, Any]:
    return {"filter": name, "pos": float(pos), "vel": float(vel), "note": note, "kind": kind}


# ---------------------------------------------------------------------------
# Headline rows and targets
# ---------------------------------------------------------------------------
def method_rows(
    scs: Sequence[Scenario],
    methods: Sequence[str],
    target: str,
    extra: dict[str, dict[str, Any]] | None = None,
) -> list[dict[str, Any]]:
    """Per method: the ``headline`` row (the sensor's nominal noise, every other key at its
    default) and the ``+target`` row (plus ``target = <the set's class>``); ``extra`` rows
    (labelled ``tuned``): ``label=method`` -> keys added to the nominal noise."""
    rows = []
    jobs = []
    for m in methods:
        jobs += [(m, m, {}, "headline"), (f"{m} +target", m, {"target": target}, "+target")]
    for label, cfg in (extra or {}).items():
        jobs.append((label, label.split("=")[-1], cfg, "tuned"))
    for label, method, cfg, kind in jobs:
        t0 = time.perf_counter()
        try:
            est = run_method(method, scs, {**nominal_config(scs[0]), **cfg})
        except ValueError as exc:
            rows.append({"filter": label, "note": f"n/a: {str(exc)[:40]}", "kind": kind})
            continue
        pos, vel = rmse(est, scs)
        us = (time.perf_counter() - t0) / (len(scs) * len(scs[0].plots)) * 1e6
        rows.append(_row(label, pos, vel, f"{us:.0f} us/plot", kind))
    return rows


def _method(row: dict[str, Any]) -> str:
    return str(row["filter"]).removesuffix(" +target")


def targets(set_name: str, rows: list[dict[str, Any]]) -> list[str]:
    """The issue's targets that apply to this set, with the measured ratios (every
    ``headline`` and ``+target`` row)."""
    by = {r["filter"]: r.get("pos", math.nan) for r in rows}
    best = by["cv best q (hindsight)"]
    narrow_wide = min(by["cv narrow"], by["cv wide"])
    out = []

    def check(label: str, ratio: float, limit: float) -> None:
        if math.isfinite(ratio):
            verdict = "MET" if ratio <= limit else "NOT MET"
            out.append(f"  {label:<48s} {ratio:6.3f}  (<= {limit})  {verdict}")

    for r in rows:
        if r["kind"] not in ("headline", "+target") or not math.isfinite(r.get("pos", math.nan)):
            continue
        name, pos = r["filter"], r["pos"]
        check(f"{name} / best fixed q", pos / best, 1.0)
        if _method(r) == "turning":
            check(f"{name} / min(narrow, wide)", pos / narrow_wide, 0.95)
        if _method(r) == "robust-adaptive" and "clairvoyant (hindsight q)" in by:
            check(f"{name} / mixture-R EKF", pos / by["cv mixture R (hindsight q)"], 0.7)
            check(f"{name} / clairvoyant", pos / by["clairvoyant (hindsight q)"], 1.3)
        if _method(r) == "mm-rangerate":
            check(f"{name} / best fixed q (issue: <= 0.97)", pos / best, 0.97)
    return out


def seeds(n: int, tuning: bool) -> list[int]:
    base = TUNING_SEEDS.start if tuning else HEADLINE_SEEDS.start
    return [base + i for i in range(n)]


def evaluate_set(
    ss: ScenarioSet,
    n: int,
    methods: Sequence[str],
    tuning: bool = False,
    extra_rows: Callable[[list[Scenario], TargetClass], list[dict[str, Any]]] | None = None,
    extra_configs: dict[str, dict[str, Any]] | None = None,
) -> tuple[list[dict[str, Any]], list[str]]:
    """Rows (methods, anchors, extras) and target lines of one set."""
    scs = [ss.make(k) for k in seeds(n, tuning)]
    tc = target_class(ss.target)
    rows = method_rows(scs, methods, ss.target, extra_configs) + anchor_rows(scs, tc)
    if extra_rows is not None:
        rows += extra_rows(scs, tc)
    return rows, targets(ss.name, rows)


def print_set(ss: ScenarioSet, rows: list[dict[str, Any]], lines: list[str], n: int) -> None:
    best = next(r["pos"] for r in rows if r["filter"] == "cv best q (hindsight)")
    for r in rows:
        r["ratio"] = r.get("pos", math.nan) / best
    print(f"\n== {ss.name}: {ss.description} ({n} runs, class {ss.target}) ==")
    cols = [
        ("filter", "filter"),
        ("kind", "row"),
        ("pos", "pos RMSE m", ".4g"),
        ("vel", "vel RMSE m/s", ".3g"),
        ("ratio", "/best q", ".3f"),
        ("note", "note"),
    ]
    print(format_table(rows, cols))
    print("targets:")
    print("\n".join(lines) if lines else "  (none)")


def summary(results: dict[str, list[dict[str, Any]]], kind: str) -> str:
    """Markdown table: ``/best q`` of every ``kind`` row, one column per set."""
    sets = list(results)
    names: list[str] = []
    for rows in results.values():
        names += [r["filter"] for r in rows if r["kind"] == kind and r["filter"] not in names]
    lines = ["| method | " + " | ".join(sets) + " |", "|---" * (len(sets) + 1) + "|"]
    for name in names:
        cells = []
        for rows in results.values():
            r = next((r for r in rows if r["filter"] == name), {})
            pos = r.get("pos", math.nan)
            cells.append(f"{pos:.4g} ({r['ratio']:.2f})" if math.isfinite(pos) else "n/a")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--quick", action="store_true", help="4 runs, three sets")
    ap.add_argument("--sets", default=",".join(SETS))
    ap.add_argument("--methods", default=",".join(TRACK_METHODS))
    ap.add_argument("--tuning", action="store_true", help="TUNING seeds instead of headline")
    a = ap.parse_args(argv)
    n = 4 if a.quick else a.runs
    names = ["ais-radar", "submarine-c20", "fighter"] if a.quick else a.sets.split(",")
    methods = a.methods.split(",")
    print(f"seeds: {'TUNING' if a.tuning else 'HEADLINE'}; transient {SKIP} scans skipped")
    results = {}
    for name in names:
        ss = SETS[name]
        rows, lines = evaluate_set(ss, n, methods, a.tuning)
        print_set(ss, rows, lines, n)
        results[name] = rows
        sys.stdout.flush()
    for kind in ("headline", "+target", "anchor", "oracle"):
        print(f"\n{kind} rows, position RMSE m (/best q):")
        print(summary(results, kind))


if __name__ == "__main__":
    main()
