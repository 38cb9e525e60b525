"""Benchmark: multi-target tracking from unlabelled plots, seatrack against Stone Soup.

The same plots go through both. Coastal radar at the origin (2-D, range 15 m, azimuth
0.3 deg, scan 2.5 s, clutter window 0.5-16 km), ships born and dying during the run
(:mod:`seatrack.simulate.multitarget`: births, exponential lifetimes, exits from the
1-15 km annulus, 0.5-3 deg/s turns, speed changes, crossing pairs), clutter uniform in
range and azimuth, missed detections.

Evaluation scenarios (never used for tuning; seeds from ``EVAL_SEED``), 200 s (81 scans):

* ``S10``: 10 ships at the start, 10 clutter plots/scan, Pd 0.95
* ``S30``: 30 ships, 30 clutter plots/scan, Pd 0.9
* ``S100``: 100 ships, 100 clutter plots/scan, Pd 0.8

Tuning scenarios (seeds from ``TUNE_SEED``, other generator settings: 20 ships / 20
clutter / Pd 0.9 and 40 ships / 50 clutter / Pd 0.85, more births, shorter lives) chose
seatrack's defaults (``TrackerConfig``, the noise levels of :mod:`seatrack.tracking.auto`)
and Stone Soup's settings: ``--tune`` re-runs both searches and prints them.

Trackers:

* ``seatrack gnn`` / ``seatrack jpda`` (the headline rows) --
  the default :class:`seatrack.tracking.Tracker` with the reference EKF given ONLY the
  sensor's nominal noise: process noise (two-level IMM from the ship class), clutter
  density, detection probability, deletion and gates chosen automatically;
* ``seatrack gnn, one q`` -- the same with a single process noise ``SINGLE_Q``, the best
  fixed q on the tuning scenarios (labelled tuned; Stone Soup's family exactly);
* ``stonesoup gnn`` -- Stone Soup 1.9.1 ``MultiTargetTracker``: EKF
  (``ExtendedKalmanPredictor`` on two ``ConstantVelocity`` models, ``ExtendedKalmanUpdater``
  with ``CartesianToBearingRange``), ``DistanceHypothesiser`` (Mahalanobis, the same
  0.999 chi-square gate), ``GNNWith2DAssignment``, ``MultiMeasurementInitiator``,
  ``UpdateTimeStepsDeleter``;
* ``stonesoup jpda`` -- the same with ``PDAHypothesiser`` (the TRUE Pd and clutter
  density, the same gate) and ``JPDAwithEHM`` (exact JPDA), states merged by
  ``gm_reduce_single`` as in Stone Soup's JPDA tutorial; a track counts as updated (for
  the deleter) when its most probable hypothesis is a detection.

Stone Soup's process noise (same CV white-noise-acceleration family), confirmation count,
deletion steps, holding-track deletion and initial speed sigma were tuned on the tuning
scenarios by coordinate descent (``STONESOUP``). Metrics: mean GOSPA (c = 100 m, p = 2,
alpha = 2) over all scans, its RMS decomposition (localisation / missed / false), missed
and false targets per scan, id switches, fragmentations (CLEAR MOT matching), and the
time per scan: processor time of this process (median over scans; seatrack best of
``--repeat`` runs, Stone Soup one run -- its runs take minutes) and wall time. The machine
is shared: the load average is printed; processor time is the figure that the load
affects least. The scaling curve runs 10 to 1,000 ships with as many clutter plots per
scan (range 1-40 km, no births or deaths), 17 scans; Stone Soup's GNN only up to
``--ss-max`` ships.

Run: ``python benchmarks/multitarget.py`` (everything, about an hour on a loaded machine),
``--quick`` (S10 only, 30 scans, scaling to 100), ``--tune`` (re-run the searches first),
``--localisation`` (where the localisation part of seatrack's GOSPA comes from, on the
tuning scenarios: matched position errors by track age and, for tracks older than 100 s on
straight legs, by range beside the error of a least-squares straight-line fit with no
process noise, ``2 sqrt(sigma_range^2 + sigma_cross^2) / sqrt(n)`` after ``n`` scans).
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from dataclasses import replace
from typing import Any

import numpy as np

from seatrack.evaluate.montecarlo import format_table
from seatrack.evaluate.multitarget import RunScores
from seatrack.evaluate.multitarget import score_run
from seatrack.evaluate.multitarget import summary_row
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.simulate.multitarget import MultiTargetRun
from seatrack.simulate.multitarget import TargetPopulation
from seatrack.simulate.multitarget import simulate_multitarget
from seatrack.simulate.scenarios import SensorConfig
from seatrack.tracking import Tracker
from seatrack.tracking import TrackerConfig
from seatrack.tracking.auto import noise_levels
from seatrack.tracking.auto import per_track_filter
from seatrack.tracking.auto import scan_period
from seatrack.tracking.gating import gate_threshold

EVAL_SEED = 15_2026
TUNE_SEED = 15_77
DEG = math.pi / 180
SIGMA_R, SIGMA_AZ, PERIOD = 15.0, 0.3 * DEG, 2.5
C_GOSPA, P_GOSPA = 100.0, 2.0

#: seatrack's single process-noise EKF: the best fixed q on the tuning scenarios (m^2/s^3)
SINGLE_Q = 0.1
#: Stone Soup settings found by ``--tune`` on the tuning scenarios
STONESOUP = {"q": 0.1, "min_points": 3, "deleter_steps": 3, "speed_sigma": 5.0, "hold_steps": 3}


@dataclass(frozen=True)
class Case:
    name: str
    targets: int
    clutter: float
    pd: float
    duration: float = 200.0
    births: float = 0.03
    life: float = 1800.0
    range_max: float = 15000.0


EVAL = [Case("S10", 10, 10, 0.95), Case("S30", 30, 30, 0.9), Case("S100", 100, 100, 0.8)]
TUNE = [
    Case("T20", 20, 20, 0.9, births=0.05, life=600.0),
    Case("T40", 40, 50, 0.85, births=0.05, life=600.0),
]


def radar(case: Case) -> SensorConfig:
    return SensorConfig(
        "radar", "radar2d", ("azimuth", "range"), (SIGMA_AZ, SIGMA_R),
        p_detect=case.pd, clutter_density=case.clutter,
        clutter_range=(500.0, case.range_max + 1000.0), scan_period=PERIOD,
    )  # fmt: skip


def simulate(case: Case, seed: int) -> MultiTargetRun:
    pop = TargetPopulation(
        targets=case.targets,
        births_per_scan=case.births,
        mean_life=case.life,
        range_limits=(1000.0, case.range_max),
    )
    return simulate_multitarget(pop, radar(case), case.duration, np.random.default_rng(seed))


@dataclass
class Result:
    """Estimated positions per scan (rows) and the wall and processor time per scan."""

    t: np.ndarray
    track: np.ndarray
    pos: np.ndarray
    seconds: np.ndarray
    cpu: np.ndarray


def score(run: MultiTargetRun, res: Result) -> RunScores:
    return score_run(
        run.scan_times, run.truth_t, run.truth_id, run.truth_pos[:, :2],
        res.t, res.track, res.pos, C_GOSPA, P_GOSPA,
    )  # fmt: skip


# ---------------------------------------------------------------------------
# seatrack
# ---------------------------------------------------------------------------
SENSOR = SensorNoise(sigma_range=SIGMA_R, sigma_azimuth=SIGMA_AZ)


#: the configuration ``seatrack track`` is given: the sensor's nominal noise only
SENSOR_TABLE = {"sigma_range_m": SIGMA_R, "sigma_azimuth_deg": SIGMA_AZ / DEG}


def run_seatrack(
    run: MultiTargetRun, config: TrackerConfig, q: float | None = None, method: str = "ekf",
    rule: str | None = None, table: dict[str, Any] | None = None,
) -> Result:  # fmt: skip
    """The tracker with per-track filter ``method`` (default the reference EKF); ``q``
    None: process noise chosen automatically (as ``seatrack track`` does), else this fixed
    PSD; ``rule`` overrides the automatic noise rule; ``table`` adds method keys."""
    tab = {**SENSOR_TABLE, **(table or {})}
    if q is not None:
        tab["q"] = q
    m, _ = per_track_filter(method, tab, 2, False, scan_period(run.plots.t), rule=rule)
    trk = Tracker(m.filter, sensor=SENSOR, config=config)
    out = trk.run(m.prepare(run.plots))
    pos = np.stack([out.columns["x_m"], out.columns["y_m"]], -1) if out.t.size else np.zeros((0, 2))
    return Result(out.t, out.track, pos, out.seconds_per_scan, out.cpu_seconds_per_scan)


# ---------------------------------------------------------------------------
# Stone Soup
# ---------------------------------------------------------------------------
def _ss_scans(plots: Plots, model: Any) -> list[tuple[datetime.datetime, set[Any]]]:
    from stonesoup.types.array import StateVector
    from stonesoup.types.detection import Detection

    t0 = datetime.datetime(2024, 1, 1)
    out = []
    for tk in np.unique(plots.t):
        m = plots.t == tk
        ts = t0 + datetime.timedelta(seconds=float(tk))
        bearing = (np.pi / 2 - plots.azimuth[m] + np.pi) % (2 * np.pi) - np.pi  # CCW from East
        dets = {
            Detection(StateVector([b, r]), timestamp=ts, measurement_model=model)
            for b, r in zip(bearing, plots.range[m], strict=True)
        }
        out.append((ts, dets))
    return out


def _ss_components(s: dict[str, float], gate_p: float) -> dict[str, Any]:
    from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
    from stonesoup.deleter.time import UpdateTimeStepsDeleter
    from stonesoup.hypothesiser.distance import DistanceHypothesiser
    from stonesoup.initiator.simple import MultiMeasurementInitiator
    from stonesoup.measures import Mahalanobis
    from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
    from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel
    from stonesoup.models.transition.linear import ConstantVelocity
    from stonesoup.predictor.kalman import ExtendedKalmanPredictor
    from stonesoup.types.array import StateVector
    from stonesoup.types.state import GaussianState
    from stonesoup.updater.kalman import ExtendedKalmanUpdater

    trans = CombinedLinearGaussianTransitionModel(
        [ConstantVelocity(s["q"]), ConstantVelocity(s["q"])]
    )
    model = CartesianToBearingRange(
        ndim_state=4, mapping=(0, 2), noise_covar=np.diag([SIGMA_AZ**2, SIGMA_R**2])
    )
    predictor = ExtendedKalmanPredictor(trans)
    updater = ExtendedKalmanUpdater(model)
    hyp = DistanceHypothesiser(
        predictor,
        updater,
        measure=Mahalanobis(),
        missed_distance=math.sqrt(gate_threshold(gate_p, 2)),
    )
    sv = s["speed_sigma"] ** 2
    initiator = MultiMeasurementInitiator(
        prior_state=GaussianState(StateVector([0.0, 0.0, 0.0, 0.0]), np.diag([0.0, sv, 0.0, sv])),
        measurement_model=model,
        deleter=UpdateTimeStepsDeleter(int(s["hold_steps"])),
        data_associator=GNNWith2DAssignment(hyp),
        updater=updater,
        min_points=int(s["min_points"]),
    )
    return {
        "model": model, "predictor": predictor, "updater": updater, "hyp": hyp,
        "initiator": initiator, "deleter": UpdateTimeStepsDeleter(int(s["deleter_steps"])),
    }  # fmt: skip


def _ss_rows(tracks: Any, ts: datetime.datetime, t: float, rows: list[Any]) -> None:
    for trk in tracks:
        st = trk.state
        if st.timestamp == ts:
            rows.append((t, id(trk), float(st.state_vector[0, 0]), float(st.state_vector[2, 0])))


def run_stonesoup(
    run: MultiTargetRun, s: dict[str, float], kind: str, pd: float, clutter: float,
    max_scans: int | None = None,
) -> Result:  # fmt: skip
    """Stone Soup GNN or JPDA over the plots (``clutter``: true false plots per scan)."""
    c = _ss_components(s, 0.999)
    scans = _ss_scans(run.plots, c["model"])[:max_scans]
    t0 = scans[0][0]
    rows: list[tuple[float, int, float, float]] = []
    secs, cpu = [], []
    if kind == "gnn":
        from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
        from stonesoup.tracker.simple import MultiTargetTracker as SSTracker

        tracker = SSTracker(
            initiator=c["initiator"], deleter=c["deleter"], detector=iter(scans),
            data_associator=GNNWith2DAssignment(c["hyp"]), updater=c["updater"],
        )  # fmt: skip
        it = iter(tracker)
        for ts, _ in scans:
            a, b = time.perf_counter(), time.process_time()
            _, tracks = next(it)
            secs.append(time.perf_counter() - a)
            cpu.append(time.process_time() - b)
            _ss_rows(tracks, ts, (ts - t0).total_seconds() + float(run.scan_times[0]), rows)
    else:
        volume = (run.plots.range.max() - run.plots.range.min()) * 2 * math.pi
        step = _ss_jpda_step(c, pd, clutter / volume)
        tracks: set[Any] = set()
        for ts, dets in scans:
            a, b = time.perf_counter(), time.process_time()
            tracks = step(tracks, dets, ts)
            secs.append(time.perf_counter() - a)
            cpu.append(time.process_time() - b)
            _ss_rows(tracks, ts, (ts - t0).total_seconds() + float(run.scan_times[0]), rows)
    arr = np.array(rows, dtype=float).reshape(-1, 4)
    return Result(arr[:, 0], arr[:, 1].astype(np.int64), arr[:, 2:4], np.array(secs), np.array(cpu))


def _ss_jpda_step(c: dict[str, Any], pd: float, density: float) -> Callable[..., set[Any]]:
    from stonesoup.dataassociator.probability import JPDAwithEHM
    from stonesoup.functions import gm_reduce_single
    from stonesoup.hypothesiser.probability import PDAHypothesiser
    from stonesoup.types.array import StateVectors
    from stonesoup.types.update import GaussianStateUpdate

    hyp = PDAHypothesiser(
        predictor=c["predictor"], updater=c["updater"], clutter_spatial_density=density,
        prob_detect=pd, prob_gate=0.999,
    )  # fmt: skip
    assoc = JPDAwithEHM(hypothesiser=hyp)

    def step(tracks: set[Any], dets: set[Any], ts: datetime.datetime) -> set[Any]:
        hyps = assoc.associate(tracks, dets, ts)
        used = set()
        for trk in tracks:
            states, weights = [], []
            for h in hyps[trk]:
                if h:
                    states.append(c["updater"].update(h))
                    used.add(h.measurement)
                else:
                    states.append(h.prediction)
                weights.append(float(h.probability))
            means = StateVectors([st.state_vector for st in states])
            covars = np.stack([st.covar for st in states], axis=2)
            mean, cov = gm_reduce_single(means, covars, np.asarray(weights))
            # the dominant hypothesis decides whether this counts as an update (deleter)
            top = max(hyps[trk], key=lambda h: float(h.probability))
            trk.append(GaussianStateUpdate(mean, cov, hypothesis=top, timestamp=ts))
        tracks = tracks - c["deleter"].delete_tracks(tracks)
        return tracks | c["initiator"].initiate(dets - used, ts)

    return step


# ---------------------------------------------------------------------------
# Tables
# ---------------------------------------------------------------------------
COLUMNS = [
    ("tracker", "tracker", ""),
    ("gospa", "GOSPA m", ".1f"),
    ("rms", "RMS GOSPA", ".1f"),
    ("localisation", "loc", ".1f"),
    ("missed", "missed", ".1f"),
    ("false", "false", ".1f"),
    ("n_missed", "miss/scan", ".2f"),
    ("n_false", "false/scan", ".2f"),
    ("id_switches", "id sw", ".0f"),
    ("fragmentations", "frag", ".0f"),
    ("ms", "CPU ms/scan", ".2f"),
    ("wall", "wall ms", ".1f"),
    ("speedup", "x faster", ".0f"),
]


def row(name: str, runs: list[MultiTargetRun], results: list[Result]) -> dict[str, Any]:
    """One table row: scores (``evaluate.multitarget.summary_row``), CPU and wall ms/scan."""
    cpu = 1000 * np.concatenate([r.cpu for r in results])
    out = summary_row(name, [score(r, res) for r, res in zip(runs, results, strict=True)], cpu)
    out["ms"] = out.pop("ms_per_scan")
    out["wall"] = 1000 * float(np.median(np.concatenate([r.seconds for r in results])))
    return out


def print_table(title: str, rows: list[dict[str, Any]]) -> None:
    from seatrack.evaluate.montecarlo import Column

    cols = [Column(k, h, f) for k, h, f in COLUMNS]
    print(f"\n{title}\n{format_table(rows, cols)}", flush=True)


def best_of(fn: Callable[[], Result], repeat: int) -> Result:
    """Run ``fn`` ``repeat`` times; keep the result with the smallest median time per scan."""
    out = [fn() for _ in range(repeat)]
    return min(out, key=lambda r: float(np.median(r.cpu)))


# ---------------------------------------------------------------------------
# Tuning
# ---------------------------------------------------------------------------
def tune_seatrack(runs: list[MultiTargetRun]) -> None:
    """Grids of the tracker parameters on the tuning runs, one at a time around the
    defaults (prints the mean GOSPA of each value)."""
    base = TrackerConfig()
    grids: dict[str, list[Any]] = {
        "q": [None, 0.03, 0.1, 0.3],  # None: the automatic noise levels
        "confirmation": ["existence", "m-of-n"],
        "confirm_existence": [0.5, 0.6, 0.7, 0.8],
        "delete_existence": [0.01, 0.05, 0.2],
        "births_per_scan": [0.01, 0.02, 0.05, 0.2],
        "mean_life": [300.0, 600.0, 1800.0, 5000.0],
        "gate_probability": [0.99, 0.999, 0.9999],
        "max_speed": [15.4, 20.6, 25.7],  # 30, 40, 50 kn
        "initial_speed_sigma": [4.1, 6.2, 8.4],  # 8, 12, 16.3 kn (16.3: max_speed / sqrt 6)
        "init_scans": [2, 3],
        "association": ["gnn", "jpda"],
    }
    for name, values in grids.items():
        for v in values:
            cfg, q = base, None
            if name == "q":
                q = v
            else:
                cfg = replace(base, **{name: v})
            g = [score(r, run_seatrack(r, cfg, q)).mean_gospa for r in runs]
            each = ", ".join(f"{x:.1f}" for x in g)
            print(f"seatrack {name}={v}: mean GOSPA {np.mean(g):.1f} ({each})", flush=True)


def tune_turns(runs: list[MultiTargetRun]) -> None:
    """Coordinated-turn models in the automatic noise IMM (off by default): turn rate,
    their acceleration noise and the variable-structure threshold, one at a time (mean
    GOSPA and the share of track-scans evaluating the turn models)."""
    import seatrack.tracking.auto as auto

    keys = ("TURN_RATE", "TURN_ACCEL", "TURN_THRESHOLD")
    saved = {k: getattr(auto, k) for k in keys}
    grid = [(1.5, 0.05, 0.0), (2.0, 0.05, 0.0), (3.0, 0.05, 0.0), (2.0, 0.15, 0.0)]
    grid += [(2.0, 0.05, t) for t in (0.05, 0.1, 0.2, 0.5)]
    try:
        for values in [(0.0, saved["TURN_ACCEL"], 0.0), *grid]:
            for k, v in zip(keys, values, strict=True):
                setattr(auto, k, v)
            g = [score(r, run_seatrack(r, TrackerConfig())).mean_gospa for r in runs]
            print(f"seatrack turn models {dict(zip(keys, values, strict=True))}: mean GOSPA "
                  f"{np.mean(g):.2f} ({', '.join(f'{x:.1f}' for x in g)})", flush=True)  # fmt: skip
    finally:
        for k, v in saved.items():
            setattr(auto, k, v)


def tune_methods(runs: list[MultiTargetRun]) -> None:
    """Every registered method as the per-track filter on the tuning runs, given only the
    sensor noise, with each automatic process-noise rule: the evidence for the rule of each
    method in the registry (``MethodRecord.noise``; methods needing range rate are skipped:
    the scenarios have none)."""
    from seatrack.filters.registry import METHODS
    from seatrack.filters.registry import method_class

    print("\nper-track filters on the tuning scenarios (mean GOSPA; * = the registry's rule)")
    for name in METHODS:
        if getattr(method_class(name), "needs_range_rate", False):
            continue
        rules = ["own", "wrap"] + (["levels"] if name == "ekf" else [])
        cells = []
        for rule in rules:
            g = np.mean([score(r, run_seatrack(r, TrackerConfig(), method=name, rule=rule))
                         .mean_gospa for r in runs])  # fmt: skip
            cells.append(f"{rule}{'*' if METHODS[name].noise == rule else ''} {g:.1f}")
        print(f"  {name:16s} " + "   ".join(cells), flush=True)


def tune_stonesoup(runs: list[MultiTargetRun], cases: list[Case]) -> dict[str, float]:
    """Coordinate descent over Stone Soup's GNN settings on the tuning runs."""
    s = dict(STONESOUP)
    grids = {
        "q": [0.03, 0.1, 0.3],
        "min_points": [2, 3, 4],
        "deleter_steps": [3, 4, 5],
        "speed_sigma": [5.0, 10.0, 20.0],
        "hold_steps": [1, 2, 3],
    }
    seen: dict[tuple[Any, ...], float] = {}

    def cost(trial: dict[str, float]) -> float:
        key = tuple(sorted(trial.items()))
        if key not in seen:
            seen[key] = float(np.mean([
                score(r, run_stonesoup(r, trial, "gnn", c.pd, c.clutter)).mean_gospa
                for r, c in zip(runs, cases, strict=True)
            ]))  # fmt: skip
            print(f"stonesoup {trial}: mean GOSPA {seen[key]:.1f}", flush=True)
        return seen[key]

    best = cost(s)
    for name, values in grids.items():
        for v in values:
            trial = {**s, name: v}
            g = cost(trial)
            if g < best:
                best, s = g, trial
    print(f"stonesoup tuned: {s} (mean GOSPA {best:.1f})")
    return s


# ---------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------
def compare(cases: list[Case], seeds: list[int], ss: dict[str, float], repeat: int,
            max_scans: int | None, jpda_ss: bool) -> None:  # fmt: skip
    for case, seed in zip(cases, seeds, strict=True):
        run = simulate(
            replace(
                case, duration=case.duration if max_scans is None else PERIOD * (max_scans - 1)
            ),
            seed,
        )
        nplots = len(run.plots) / run.scan_times.size
        rows = []
        trackers: list[tuple[str, TrackerConfig, float | None]] = [
            ("seatrack gnn (defaults)", TrackerConfig(), None),
            ("seatrack jpda (defaults)", TrackerConfig(association="jpda"), None),
            ("seatrack gnn, M-of-N 3/4", TrackerConfig(confirmation="m-of-n"), None),
            (f"seatrack gnn, one q={SINGLE_Q:g} (tuned)", TrackerConfig(), SINGLE_Q),
        ]
        for name, cfg, q in trackers:
            res = best_of(lambda cfg=cfg, q=q: run_seatrack(run, cfg, q), repeat)
            rows.append(row(name, [run], [res]))
        ss_gnn = run_stonesoup(run, ss, "gnn", case.pd, case.clutter)
        rows.append(row("stonesoup gnn (tuned)", [run], [ss_gnn]))
        if jpda_ss:
            ss_j = run_stonesoup(run, ss, "jpda", case.pd, case.clutter)
            rows.append(row("stonesoup jpda (tuned)", [run], [ss_j]))
        ref = rows[len(trackers)]["ms"]
        for r in rows:
            r["speedup"] = ref / r["ms"]
        print_table(
            f"{case.name}: {case.targets} ships at start, {case.clutter:g} clutter/scan, Pd "
            f"{case.pd}, {run.scan_times.size} scans, {nplots:.0f} plots/scan, seed {seed} "
            f"(x faster: against stonesoup gnn)",
            rows,
        )
        best_ss = min(r["gospa"] for r in rows[len(trackers) :])
        print(
            f"{case.name}: mean GOSPA / Stone Soup's better tracker: gnn "
            f"{rows[0]['gospa'] / best_ss:.3f}, jpda {rows[1]['gospa'] / best_ss:.3f} "
            f"(target <= 0.9); CPU speed-up of seatrack gnn: {rows[0]['speedup']:.0f}x "
            f"(target >= 50x)",
            flush=True,
        )


def scaling(sizes: list[int], ss: dict[str, float], ss_max: int, repeat: int, scans: int) -> None:
    rows = []
    for n in sizes:
        case = Case(f"N{n}", n, float(n), 0.9, duration=PERIOD * (scans - 1), births=0.0,
                    life=0.0, range_max=40000.0)  # fmt: skip
        run = simulate(case, EVAL_SEED + 7 * n)
        res = best_of(lambda: run_seatrack(run, TrackerConfig()), repeat)
        r: dict[str, Any] = {"targets": n, "plots": len(run.plots) / run.scan_times.size}
        s = score(run, res)
        # steady state: leave out the first scans (no tracks yet, nothing to associate)
        r["st_ms"] = 1000 * float(np.median(res.cpu[3:]))
        r["st_max"] = 1000 * float(np.max(res.cpu[3:]))
        r["st_wall"] = 1000 * float(np.median(res.seconds[3:]))
        r["st_gospa"] = s.mean_gospa
        if n <= ss_max:
            ss_res = run_stonesoup(run, ss, "gnn", case.pd, case.clutter)
            r["ss_ms"] = 1000 * float(np.median(ss_res.cpu[3:]))
            r["ss_gospa"] = score(run, ss_res).mean_gospa
            r["ratio"] = r["ss_ms"] / r["st_ms"]
        else:
            r["ss_ms"] = r["ss_gospa"] = r["ratio"] = float("nan")
        rows.append(r)
        print(f"  {n} targets done", flush=True)
    from seatrack.evaluate.montecarlo import Column

    cols = [
        Column("targets", "ships", "d"), Column("plots", "plots/scan", ".0f"),
        Column("st_ms", "seatrack CPU ms/scan", ".2f"), Column("st_max", "max ms", ".1f"),
        Column("st_wall", "wall ms", ".1f"),
        Column("st_gospa", "seatrack GOSPA", ".0f"),
        Column("ss_ms", "stonesoup gnn CPU ms/scan", ".0f"),
        Column("ss_gospa", "stonesoup GOSPA", ".0f"), Column("ratio", "x faster", ".0f"),
    ]  # fmt: skip
    print(f"\nscaling: ships = clutter plots per scan, Pd 0.9, {scans} scans, range 1-40 km; "
          f"median over scans 4-{scans} (seatrack best of {repeat} runs); Stone Soup GNN "
          f"stopped above {ss_max} ships\n{format_table(rows, cols)}")  # fmt: skip


def localisation(runs: list[MultiTargetRun]) -> None:
    """Matched position errors of seatrack's default tracker (module docstring)."""
    from scipy.optimize import linear_sum_assignment

    for k, run in enumerate(runs):
        res = run_seatrack(run, TrackerConfig())
        born = {int(tr): float(res.t[res.track == tr].min()) for tr in np.unique(res.track)}
        accel = np.zeros(run.truth_t.size)
        for i in np.unique(run.truth_id):
            m = np.flatnonzero(run.truth_id == i)
            if m.size > 1:
                dv = np.gradient(run.truth_vel[m, :2], run.truth_t[m], axis=0)
                accel[m] = np.linalg.norm(dv, axis=1)
        rows = []  # error m, truth acceleration m/s^2, track age s, range m
        for t in run.scan_times:
            ti, ei = np.flatnonzero(run.truth_t == t), np.flatnonzero(res.t == t)
            if ti.size == 0 or ei.size == 0:
                continue
            D = np.linalg.norm(run.truth_pos[ti, None, :2] - res.pos[None, ei], axis=-1)
            r, c = linear_sum_assignment(np.minimum(D, C_GOSPA) ** 2)
            for a, b in zip(r, c, strict=True):
                if D[a, b] < C_GOSPA:
                    age = t - born[int(res.track[ei[b]])]
                    rows.append(
                        (D[a, b], accel[ti[a]], age, np.linalg.norm(run.truth_pos[ti[a], :2]))
                    )
        e = np.array(rows)
        e2 = e[:, 0] ** 2
        sc = score(run, res)
        part = sc.rms_parts()
        print(f"{TUNE[k].name}: mean GOSPA {sc.mean_gospa:.1f} m; RMS parts: localisation "
              f"{part['localisation']:.1f}, missed {part['missed']:.1f}, false "
              f"{part['false']:.1f} m")  # fmt: skip
        turning = e[:, 1] > 0.02
        share = e2[turning].sum() / e2.sum()
        print(f"{TUNE[k].name}: {e.shape[0]} matched estimates, RMS {np.sqrt(e2.mean()):.1f} m; "
              f"manoeuvring truth {np.mean(turning):.0%} of them, {share:.0%} of the squared "
              f"error (RMS {np.sqrt(e2[turning].mean()):.1f} m)")  # fmt: skip
        for lo, hi in ((0, 10), (10, 25), (25, 50), (50, 100), (100, np.inf)):
            m = (e[:, 2] >= lo) & (e[:, 2] < hi) & ~turning
            share = e2[m].sum() / e2.sum()
            print(f"  straight, track age {lo:>3}-{hi:<4} s: {m.sum():5d} estimates, RMS "
                  f"{np.sqrt(e2[m].mean()):5.1f} m, {share:4.0%} of the squared error")  # fmt: skip
        for lo, hi in ((1e3, 4e3), (4e3, 8e3), (8e3, 12e3), (12e3, 16e3)):
            m = (e[:, 3] >= lo) & (e[:, 3] < hi) & ~turning & (e[:, 2] > 100)
            n = 1 + 100 / PERIOD  # scans of a track older than 100 s, at least
            floor = 2 * math.hypot(SIGMA_R, SIGMA_AZ * (lo + hi) / 2) / math.sqrt(n)
            print(f"  straight, older than 100 s, range {lo / 1e3:>2.0f}-{hi / 1e3:<2.0f} km: RMS "
                  f"{np.sqrt(e2[m].mean()):5.1f} m; straight-line fit of {n:.0f} scans, no "
                  f"process noise: {floor:5.1f} m")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="S10 only, 30 scans, scaling to 100")
    ap.add_argument("--tune", action="store_true", help="re-run the parameter searches first")
    ap.add_argument(
        "--methods", action="store_true", help="every method as the per-track filter (tuning)"
    )
    ap.add_argument("--cases", default="S10,S30,S100", help="evaluation cases to run")
    ap.add_argument("--no-scaling", action="store_true", help="skip the scaling curve")
    ap.add_argument("--repeat", type=int, default=3, help="seatrack runs per case (best time)")
    ap.add_argument("--ss-max", type=int, default=100, help="largest Stone Soup scaling case")
    ap.add_argument("--no-jpda", action="store_true", help="skip Stone Soup's JPDA")
    ap.add_argument("--localisation", action="store_true", help="where the GOSPA error is")
    args = ap.parse_args()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"machine: {os.cpu_count()} cores, load average {load:.1f} at start")
    ss = dict(STONESOUP)
    tune_runs = [simulate(c, TUNE_SEED + k) for k, c in enumerate(TUNE)]
    if args.localisation:
        localisation(tune_runs)
        return
    if args.methods:
        tune_methods(tune_runs)
    if args.tune:
        tune_seatrack(tune_runs)
        tune_turns(tune_runs)
        ss = tune_stonesoup(tune_runs, TUNE)
    q_s, q_m = noise_levels(PERIOD)
    print(
        f"seatrack defaults: {TrackerConfig()}; process noise from the ship class: "
        f"IMM of q = {q_s:.4f} and {q_m:.3f} m^2/s^3 (only the sensor noise is given)"
    )
    print(
        f"stonesoup settings: {ss}; gate probability 0.999 (Mahalanobis "
        f"{math.sqrt(gate_threshold(0.999, 2)):.2f}); JPDA with the true Pd and clutter density"
    )
    wanted = ["S10"] if args.quick else args.cases.split(",")
    picked = [(c, EVAL_SEED + k) for k, c in enumerate(EVAL) if c.name in wanted]
    compare([c for c, _ in picked], [sd for _, sd in picked], ss,
            1 if args.quick else args.repeat, 30 if args.quick else None,
            not args.no_jpda)  # fmt: skip
    sizes = [10, 30, 100] if args.quick else [10, 30, 100, 300, 1000]
    if not args.no_scaling:
        scaling(sizes, ss, min(args.ss_max, 30) if args.quick else args.ss_max, args.repeat, 17)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"load average {load:.1f} at the end")


if __name__ == "__main__":
    main()
