"""The situations of ``seatrack demo``: each method where it is made to work.

Every tracking section runs the ``seatrack track`` methods as a new user does -- their
defaults plus the sensor's nominal noise (and a row with the ``target`` class) -- on
simulated runs of :mod:`seatrack.simulate.families` drawn with HEADLINE seeds (no method
was tuned on them), all runs of a section as the tracks of one file, and compares them
with the CV EKF whose fixed q is the best on these very runs (an oracle no filter can
pick in advance). The other sections run bearings-only TMA, landmark navigation, AIS
cleaning of a bundled sample and the multi-target tracker on unlabelled plots.

Each section function returns a :class:`Section` (rows of the comparison, text, the PNG
it wrote); :func:`run_sections` runs them, in worker processes when asked (the results do
not depend on it). :data:`WHEN` holds one sentence per capability on when to use it
(the methods' from the registry, :attr:`seatrack.filters.registry.MethodRecord.when`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from dataclasses import field
from pathlib import Path
from typing import Any

import numpy as np

from seatrack.compiled import compile_all
from seatrack.filters.registry import METHODS
from seatrack.filters.registry import run
from seatrack.io.atomic import adopt_outputs
from seatrack.io.atomic import discard_outputs
from seatrack.io.atomic import held_outputs
from seatrack.report.plots import save
from seatrack.report.plots import situation_figure
from seatrack.simulate.families import HEADLINE_SEEDS
from seatrack.simulate.families import Scenario
from seatrack.simulate.families import labelled_runs

__all__ = ["Row", "Section", "WHEN", "SECTIONS", "run_sections", "rmse_rows"]

#: one sentence per capability: when to use it (the methods' from the registry)
WHEN: dict[str, str] = {name: r.when for name, r in METHODS.items()} | {
    "tma": "passive sonar, bearings only: batch target motion analysis (own ship manoeuvres)",
    "navigate": "own-ship position from radar echoes of charted landmarks, without GNSS",
    "ais": "real AIS reports of many vessels: outliers flagged, gaps split, tracks smoothed",
    "multi-target": "unlabelled plots with clutter and misses: tracks started, kept, ended",
}


@dataclass(frozen=True)
class Row:
    """One method in one situation."""

    method: str
    config: str  #: what the user gave beside the sensor noise ("defaults", "target=...")
    value: float  #: position RMSE, m (or the section's figure of merit)
    ratio: float  #: value / the section's anchor (NaN: none)


@dataclass(frozen=True)
class Section:
    """What one situation showed."""

    key: str
    title: str
    situation: str
    rows: tuple[Row, ...] = ()
    lines: tuple[str, ...] = ()
    figure: Path | None = None
    seconds: float = 0.0
    methods: tuple[str, ...] = field(default=())  #: methods the section is made for


def _positions(cols: dict[str, Any], n: int) -> np.ndarray:
    return np.stack([cols["x_m"], cols["y_m"]], -1).reshape(n, -1, 2)


def _rmse(est: np.ndarray, scs: Sequence[Scenario], skip: int = 10) -> float:
    truth = np.stack([s.truth[:, :2] for s in scs])
    return float(np.sqrt(np.mean(np.sum((est - truth)[:, skip:] ** 2, -1))))


def rmse_rows(
    scs: Sequence[Scenario], jobs: Sequence[tuple[str, dict[str, Any]]], q_grid: Sequence[float]
) -> tuple[list[Row], dict[str, np.ndarray]]:
    """Position RMSE of each ``(method, extra keys)`` on the runs (one batch each), the
    hindsight-best fixed-q EKF of ``q_grid`` as the anchor (last row), and the estimates
    ``(B, N, 2)`` by label."""
    plots, base, n = labelled_runs(scs), scs[0].sensor_table(), len(scs)
    best = min((_rmse(_positions(run("ekf", plots, {**base, "q": q}), n), scs), q) for q in q_grid)
    rows, est = [], {}
    for method, extra in jobs:
        label = " ".join([method, *(f"{k}={v}" for k, v in extra.items())])
        est[label] = _positions(run(method, plots, {**base, **extra}), n)
        value = _rmse(est[label], scs)
        rows.append(
            Row(method, label.removeprefix(method).strip() or "defaults", value, value / best[0])
        )
    rows.append(Row("ekf", f"best fixed q in hindsight (q={best[1]:g})", best[0], 1.0))
    return rows, est


def _tracking_section(
    key: str,
    title: str,
    situation: str,
    make: Callable[[int], Scenario],
    jobs: Sequence[tuple[str, dict[str, Any]]],
    q_grid: Sequence[float],
    shown: Sequence[str],
    out: Path,
    runs: int,
) -> Section:
    t0 = time.perf_counter()
    scs = [make(HEADLINE_SEEDS.start + i) for i in range(runs)]
    rows, est = rmse_rows(scs, jobs, q_grid)
    sc = scs[0]
    fig = situation_figure(
        sc.truth[:, :2],
        {k: est[k][0] for k in shown},
        sc.plots.positions(),
        sc.plots.t,
        title=f"{title}: run 1 of {runs}",
    )
    methods = tuple(dict.fromkeys(m for m, _ in jobs))
    return Section(
        key,
        title,
        situation,
        tuple(rows),
        (),
        save(fig, out / f"{key}.png"),
        time.perf_counter() - t0,
        methods,
    )


def turns_section(out: Path, runs: int) -> Section:
    """Air-traffic radar, aircraft turning at 1.5-3 deg/s."""
    from seatrack.simulate.families import random_manoeuvres

    jobs = [
        ("ekf", {}),
        ("turning-spec", {}),
        ("turning", {}),
        ("turning", {"target": "aircraft"}),
        ("imm", {}),
    ]
    return _tracking_section(
        "turns",
        "Turns: aircraft on an air-traffic radar",
        "Aircraft at 90-150 m/s fly straight legs and 1.5-3 deg/s turns; radar every 4 s, "
        "40 m and 0.08 deg, 20-60 km away.",
        lambda k: random_manoeuvres("aircraft", k),
        jobs,
        (4.0, 16.0, 64.0, 256.0, 1024.0),
        ("ekf", "turning-spec", "turning"),
        out,
        runs,
    )


def range_rate_section(out: Path, runs: int) -> Section:
    """Pulse-Doppler radar with range rate, fighter turning at 3-6 g."""
    from seatrack.simulate.families import random_manoeuvres

    jobs: list[tuple[str, dict[str, Any]]] = [
        ("mm-rangerate-spec", {}),
        ("mm-rangerate", {}),
        ("imm", {}),
        ("turning", {}),
    ]
    return _tracking_section(
        "range_rate",
        "Multiple models with range rate: a fighter",
        "A fighter at 200-300 m/s turns at 3-6 g; radar every 2 s, 30 m, 0.3 deg and range "
        "rate 0.5 m/s, 20-50 km away.",
        lambda k: random_manoeuvres("fighter", k),
        jobs,
        (100.0, 400.0, 1600.0, 6400.0),
        ("mm-rangerate-spec", "mm-rangerate"),
        out,
        runs,
    )


def outliers_section(out: Path, runs: int) -> Section:
    """Active sonar with 20 % contaminated plot components, a manoeuvring submarine."""
    from seatrack.simulate.families import random_manoeuvres

    jobs = [
        ("ekf", {}),
        ("robust-spec", {}),
        ("robust-adaptive-spec", {}),
        ("huber", {}),
        ("student-t", {}),
        ("robust", {}),
        ("robust-adaptive", {}),
        ("robust-adaptive", {"target": "submarine"}),
    ]
    return _tracking_section(
        "outliers",
        "Outliers: a submarine on an active sonar",
        "A submarine at 3-7 m/s turns at 0.5-1 deg/s; sonar every 2 s, 1.5 m and 1 deg, "
        "on an own ship at 2 m/s; 20 % of the range and bearing values are outliers "
        "(variance x10 and x25).",
        lambda k: random_manoeuvres("submarine", k, 0.2),
        jobs,
        (0.001, 0.004, 0.016, 0.064, 0.25),
        ("ekf", "robust-adaptive-spec", "robust-adaptive"),
        out,
        runs,
    )


def tma_section(out: Path, runs: int) -> Section:
    """Bearings-only TMA on the bundled ``tma_classic`` scenario."""
    from seatrack.geometry import course_speed
    from seatrack.geometry import mps_to_knots
    from seatrack.geometry import rad2deg
    from seatrack.report.tma import plot_solutions
    from seatrack.simulate.scenarios import bundled_scenario
    from seatrack.simulate.scenarios import load_scenario
    from seatrack.tma.solver import Bearings
    from seatrack.tma.solver import solve

    t0 = time.perf_counter()
    sc = load_scenario(bundled_scenario("tma_classic"))
    sim = sc.simulate(np.random.default_rng(np.random.SeedSequence(sc.seed).spawn(1)[0]))
    sd = sim.sensors[0]
    m, truth = sd.measurements[0], sd.truth[0]
    ok = m.detected
    b = Bearings(m.t[ok], m.z[ok, 0], m.sensor_pos[ok, :2])
    sol = solve(b, sigma=float(sd.sensor.sigma[0]))
    last, true_p = sol.last, truth.pos[-1, :2]
    tc, ts = course_speed(truth.vel[-1, 0], truth.vel[-1, 1])
    err = float(np.hypot(*(sol.position_at(np.array([b.t[-1]]))[0] - true_p)))
    obs = sd.observer.pos[-1, :2] if sd.observer is not None else np.zeros(2)
    rel = float(np.hypot(*(true_p - obs)))
    lines = (
        f"{len(b)} bearings (sigma {np.degrees(sd.sensor.sigma[0]):.1f} deg), "
        f"{'observable' if sol.observable else 'NOT observable'}, {sol.iterations} iterations",
        f"range {last.range / 1e3:.2f} km +- {last.sigma_range / 1e3:.2f} (truth {rel / 1e3:.2f});"
        f" course {rad2deg(last.course):.1f} deg +- {np.degrees(last.sigma_course):.1f} "
        f"(truth {rad2deg(tc) % 360:.1f}); speed {float(mps_to_knots(last.speed)):.1f} kn "
        f"(truth {float(mps_to_knots(ts)):.1f}); position error {err:.0f} m",
    )
    plot_solutions({"target": b}, {"target": sol}, out / "tma.png")
    return Section(
        "tma",
        "Bearings only: target motion analysis",
        "A passive sonar hears a target; the own ship changes course so that range "
        "becomes observable (bundled scenario tma_classic).",
        (Row("tma", "defaults", err, math.nan),),
        lines,
        out / "tma.png",
        time.perf_counter() - t0,
        ("tma",),
    )


def navigation_section(out: Path, runs: int) -> Section:
    """Own-ship navigation from radar echoes of charted landmarks on a river passage."""
    from seatrack.navigation.navigator import Echoes
    from seatrack.navigation.navigator import NavigatorConfig
    from seatrack.navigation.navigator import navigate
    from seatrack.simulate.radar_echoes import channel_landmarks
    from seatrack.simulate.radar_echoes import river_route
    from seatrack.simulate.radar_echoes import simulate_radar

    t0 = time.perf_counter()
    route = river_route(3000.0, 4.0)
    rng = np.random.default_rng(HEADLINE_SEEDS.start)
    sim = simulate_radar(route, channel_landmarks(route, 8, rng), rng)
    e = sim.echoes
    res = navigate(
        sim.nav_map,
        Echoes(e.t, e.antenna, e.range),
        sim.truth[0].copy(),
        NavigatorConfig(),
        gyro=(sim.gyro_t, sim.gyro_rate),
        t0=0.0,
    )
    truth = np.column_stack([np.interp(res.t, sim.truth_t, sim.truth[:, i]) for i in range(2)])
    err = float(np.sqrt(np.mean(np.sum((res.x[:, :2] - truth) ** 2, -1))))
    fig = situation_figure(
        truth,
        {"navigator": res.x[:, :2]},
        sim.nav_map.xy,
        res.t,
        title="River passage: own-ship position from landmark echoes",
        plots_label="landmarks",
    )
    return Section(
        "navigation",
        "Landmark navigation: a river passage",
        "A ship runs 3 km down a river channel; its radar sees echoes of 8 charted "
        "landmarks (with clutter), a gyro gives the turn rate; no GNSS.",
        (Row("navigate", "defaults", err, math.nan),),
        (f"position RMSE {err:.1f} m over {res.t[-1]:.0f} s",),
        save(fig, out / "navigation.png"),
        time.perf_counter() - t0,
        ("navigate",),
    )


def ais_section(out: Path, runs: int) -> Section:
    """AIS cleaning of a bundled real sample."""
    from seatrack.data import ais_sample
    from seatrack.filters.ais import AisTrackerConfig
    from seatrack.io.ais.pipeline import track_files
    from seatrack.report.plots import ais_figure

    t0 = time.perf_counter()
    got: list[tuple[Any, Any]] = []
    name = "us_boston_201401_trajectools.csv"
    summary = track_files(
        [ais_sample(name)],
        out / "data" / "ais_tracks.csv",
        AisTrackerConfig(),
        on_group=lambda r, tr: got.append((r, tr)),
    )
    reports, tracks = got[0]
    fig = ais_figure(reports, tracks, title=f"AIS sample {name}: reports and smoothed tracks")
    return Section(
        "ais",
        "AIS cleaning: real reports of Boston harbour",
        f"The bundled sample {name} (real, uncleaned reports) through the AIS "
        "tracker: glitches flagged, gaps split, tracks smoothed.",
        (),
        tuple(summary.lines()),
        save(fig, out / "ais.png"),
        time.perf_counter() - t0,
        ("ais",),
    )


def multitarget_section(out: Path, runs: int) -> Section:
    """The multi-target tracker on unlabelled plots of the bundled coastal scenario."""
    from seatrack.evaluate.multitarget import simulate_scenario
    from seatrack.io.atomic import pending_output
    from seatrack.io.multitarget import track_unlabelled_file
    from seatrack.io.multitarget import write_outputs
    from seatrack.io.multitarget import write_unlabelled_plots
    from seatrack.simulate.scenarios import bundled_scenario
    from seatrack.simulate.scenarios import load_scenario

    t0 = time.perf_counter()
    sc = load_scenario(bundled_scenario("coastal_multitarget"))
    sim = simulate_scenario(sc, np.random.default_rng(HEADLINE_SEEDS.start), sc.sensors[0])
    plots_csv = out / "data" / "plots_unlabelled.csv"
    write_unlabelled_plots(plots_csv, sim.plots)
    # as ``seatrack track data/plots_unlabelled.csv``: the file as written (still a
    # temporary of the command's transaction), tracked and written by the command's path
    tracks_csv, png = out / "data" / "tracks_unlabelled.csv", out / "multitarget.png"
    res = track_unlabelled_file(pending_output(plots_csv), "ekf", {})
    write_outputs(res, tracks_csv, None, png, f"{plots_csv.name}: ekf")
    text = res.summary("ekf", tracks_csv)
    n_true = int(np.unique(sim.truth_id).size)
    return Section(
        "multitarget",
        "Multi-target tracking from unlabelled plots",
        f"A coastal radar sees {n_true} ships (born, dying, crossing) in 20 clutter "
        "plots per scan with a detection probability of 0.9; no plot says which "
        "ship it came from.",
        (),
        (text,),
        out / "multitarget.png",
        time.perf_counter() - t0,
        ("multi-target",),
    )


#: the sections in the order of the report
SECTIONS: dict[str, Callable[[Path, int], Section]] = {
    "turns": turns_section,
    "range_rate": range_rate_section,
    "outliers": outliers_section,
    "tma": tma_section,
    "navigation": navigation_section,
    "ais": ais_section,
    "multitarget": multitarget_section,
}


def _one(key: str, out: Path, runs: int) -> Section:
    return SECTIONS[key](out, runs)


def run_sections(out: Path, runs: int, processes: int = 1) -> list[Section]:
    """Every section (in worker processes when ``processes > 1``), in report order."""
    keys = list(SECTIONS)
    if processes <= 1:
        return [_one(k, out, runs) for k in keys]
    compile_all()  # the workers must not compile the same kernels at once (numba #10128)
    done: list[tuple[Section, dict[Path, Path]]] = []
    error: BaseException | None = None
    with ProcessPoolExecutor(max_workers=processes) as pool:
        futures = [pool.submit(_held, k, out, runs) for k in keys]
        for fut in futures:  # every worker is waited for: none leaves a temporary behind
            try:
                done.append(fut.result())
            except BaseException as exc:  # noqa: BLE001 - re-raised below, after the cleanup
                error = error or exc
    if error is not None:
        for _, held in done:
            discard_outputs(held)
        raise error
    for _, held in done:  # the workers' outputs join the command's transaction
        adopt_outputs(held)
    return [s for s, _ in done]


def _held(key: str, out: Path, runs: int) -> tuple[Section, dict[Path, Path]]:
    """One section in a worker process, its outputs held for the parent's transaction."""
    with held_outputs() as held:
        section = _one(key, out, runs)
    return section, held
