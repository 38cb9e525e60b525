"""Benchmark: turning-target filter (CN 104407337, ``docs/turning.md``) vs fixed-Q EKFs and an IMM.

Scenario sets (each run draws its own scenario from its seed; all runs of a set share
the scan times so the fixed-Q EKFs and the IMM run as one vectorised batch):

* ``aircraft`` -- 3-D radar (range 30 m, azimuth 0.1 deg, elevation 0.15 deg, scan 4 s),
  speed 100-150 m/s, climb-out at 8-15 m/s, two standard-rate (3 deg/s) turns of
  60-180 deg in random directions separated by straight legs, 600 s.
* ``ship`` -- 2-D radar (range 10 m, azimuth 0.3 deg, scan 2.5 s), speed 4-10 m/s, two
  rudder turns at 0.5-2 deg/s through 30-120 deg, 1100 s.

Headline rows (``seatrack track`` as a new user runs it: the defaults plus the sensor's
nominal noise, through the registry, all runs as the tracks of one file):

* ``turning`` -- ``--method turning``, the default (a level IMM, :mod:`seatrack.filters.
  turning_imm`), without a target class (self-tuning levels);
* ``turning +target`` -- the same with ``target = "aircraft"`` / ``"ship"``;
* ``turning-spec`` -- ``--method turning-spec``, the patent as written, its defaults.

Tuned rows (labelled; all start from the same first-plot initialisation,
:func:`seatrack.filters.turning.initial_state`):

* ``turning-spec tuned`` -- the patent's filter with its free parameters tuned on the
  TUNING seeds (``--tune`` re-runs the search; the values found are stored in ``TUNED``).
* ``turning-spec tuned q`` -- the patent's filter with the spec's gain reading
  ``c = (dw/0.02)^2``, cap 100, M = 5 (only ``q_nominal`` from the tuning).
* ``ekf-lowQ`` -- CV-EKF with the method's nominal q (narrow band).
* ``ekf-highQ`` -- CV-EKF with ``q = a_max^2 T`` for the largest turn acceleration
  ``a_max`` and scan period T (wide band).
* ``ekf-bestQ`` -- CV-EKF with the q chosen IN HINDSIGHT on the evaluation runs from a
  grid (the best any fixed-Q EKF could do; an oracle, not a realisable filter).
* ``imm tuned`` -- :class:`seatrack.filters.imm.IMM`, CV + coordinated turn, parameters
  tuned on the TUNING seeds like the method.

Metrics after a 10-scan transient: position / speed / heading RMSE on straight legs, in
turns and overall (position 3-D for the aircraft, 2-D for ships; speed and heading
horizontal); turn detection delay (first scan with turn_state != straight, or IMM
CT-probability > 0.5, the level IMM's p_manoeuvre > 0.5 for the default rows, the patent's
vote for their "(turn_state)" rows, after a turn starts; "det%" = turns detected before the
turn ends + 20 s), false alarms (fraction of straight-leg scans >= 60 s after a turn with the
indicator on), and the single-track time per scan.

Seeds and tuning: evaluation runs use ``SeedSequence(EVAL_SEED).spawn(n)``, tuning runs
``SeedSequence(TUNE_SEED).spawn(n)`` -- disjoint streams; nothing is tuned on the
evaluation runs except the hindsight ``ekf-bestQ`` baseline, by definition. ``tune()``
(method) first finds the best fixed q on the tuning runs, then grids the nominal q
(1/100 .. 1 of it), the S4 delta-omega threshold and the S5 gain scale, then runs two
coordinate-descent sweeps over those and the gain cap, M and the heading-filter q; the
objective is overall position RMSE. ``tune_imm()`` grids the IMM's model q, turn-rate
noise and switching probability on the same runs. The values found (50 tuning runs per
set) are stored in ``TUNED`` / ``TUNED_IMM``; ``--tune all|method|imm`` re-derives them.

Run: ``python benchmarks/turning.py`` (200 runs per set), ``--quick`` (20 runs),
``--tune`` (re-run the parameter search on the tuning seeds, then evaluate).
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from seatrack.evaluate.metrics import rmse
from seatrack.evaluate.montecarlo import format_table
from seatrack.evaluate.montecarlo import run_seeds
from seatrack.filters.base import SensorNoise
from seatrack.filters.imm import IMM
from seatrack.filters.turning import TurningConfig
from seatrack.filters.turning import TurningFilter
from seatrack.filters.turning import TurnState
from seatrack.filters.turning import ekf_step
from seatrack.filters.turning import initial_state
from seatrack.filters.turning import plot_covariance
from seatrack.geometry import angle_diff
from seatrack.geometry import bearing
from seatrack.models import ConstantVelocity
from seatrack.models import CoordinatedTurn
from seatrack.models import RangeBearing
from seatrack.models import RangeBearingElevation
from seatrack.models.motion import cv_noise
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory

sys.path.insert(0, str(Path(__file__).parent))
from headline import labelled_plots  # noqa: E402
from headline import nominal  # noqa: E402
from headline import run_registry  # noqa: E402

EVAL_SEED = 20261123
TUNE_SEED = 777
SKIP = 10  # transient scans excluded from every metric
DEG = math.pi / 180


# ---------------------------------------------------------------------------
# Scenarios
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Case:
    name: str
    d: int
    dt: float
    duration: float
    sigma: tuple[float, ...]
    speed: tuple[float, float]
    turn_rate: tuple[float, float]  # rad/s
    turn_angle: tuple[float, float]  # rad
    climb: tuple[float, float]  # m/s during the first leg (climb-out)
    range_: tuple[float, float]
    first_leg: tuple[float, float]
    gap: tuple[float, float]  # straight leg between the turns
    q_grid: tuple[float, ...]

    @property
    def a_max(self) -> float:
        return self.speed[1] * self.turn_rate[1]

    @property
    def q_high(self) -> float:
        return self.a_max**2 * self.dt


CASES = {
    "aircraft": Case(
        "aircraft",
        3,
        4.0,
        600.0,
        (30.0, 0.1 * DEG, 0.15 * DEG),
        (100.0, 150.0),
        (3 * DEG, 3 * DEG),
        (60 * DEG, 180 * DEG),
        (8.0, 15.0),
        (15e3, 50e3),
        (60.0, 120.0),
        (60.0, 150.0),
        tuple(np.logspace(-2, 3, 16)),
    ),
    "ship": Case(
        "ship",
        2,
        2.5,
        1100.0,
        (10.0, 0.3 * DEG),
        (4.0, 10.0),
        (0.5 * DEG, 2 * DEG),
        (30 * DEG, 120 * DEG),
        (0.0, 0.0),
        (3e3, 10e3),
        (100.0, 200.0),
        (150.0, 250.0),
        tuple(np.logspace(-5, 0, 16)),
    ),
}


@dataclass
class Batch:
    t: np.ndarray  # (N,)
    z: np.ndarray  # (R, N, d)
    pos: np.ndarray  # (R, N, 3)
    vel: np.ndarray  # (R, N, 3)
    turn_rate: np.ndarray  # (R, N)
    turns: list[list[tuple[float, float]]]  # per run: (start, end) of each turn


def scenario(case: Case, rng: np.random.Generator) -> tuple[object, list[tuple[float, float]]]:
    u = rng.uniform
    speed = u(*case.speed)
    rng_m = u(*case.range_)
    az = u(0, 2 * math.pi)
    alt = u(500.0, 1500.0) if case.d == 3 else 0.0
    start = [rng_m * math.sin(az), rng_m * math.cos(az), alt]
    course = u(0, 2 * math.pi)
    legs = [Leg.straight(u(*case.first_leg), climb_rate=u(*case.climb))]
    turns = []
    t = legs[0].duration
    for k in range(2):
        ang = u(*case.turn_angle) * rng.choice([-1.0, 1.0])
        leg = Leg.turn(ang, u(*case.turn_rate))
        turns.append((t, t + leg.duration))
        legs.append(leg)
        t += leg.duration
        if k == 0:
            g = u(*case.gap)
            legs.append(Leg.straight(g))
            t += g
    if t >= case.duration - 30:
        raise RuntimeError("scenario longer than the set duration; widen duration")
    legs.append(Leg.straight(case.duration - t))
    return trajectory(start, course, speed, legs, dt=case.dt), turns


def simulate(case: Case, seed: int, n_runs: int) -> Batch:
    comps = ("range", "azimuth", "elevation")[: case.d]
    z, pos, vel, w, turns = [], [], [], [], []
    for ss in run_seeds(seed, n_runs):
        rng = np.random.default_rng(ss)
        tr, tn = scenario(case, rng)
        m = observe(tr, None, comps, NoiseModel(case.sigma), rng)
        z.append(m.z)
        pos.append(tr.pos)
        vel.append(tr.vel)
        w.append(tr.turn_rate)
        turns.append(tn)
    return Batch(tr.t, np.array(z), np.array(pos), np.array(vel), np.array(w), turns)


# ---------------------------------------------------------------------------
# Filters (each returns estimated states (R, N, 2d) and a turn indicator (R, N) or None)
# ---------------------------------------------------------------------------
def _init(case: Case, b: Batch, sigma_v0: float) -> tuple[np.ndarray, np.ndarray]:
    R = plot_covariance(*case.sigma, *([0.0] * (3 - case.d)), case.d)
    xs, Ps = zip(*[initial_state(zz[0], R, sigma_v0) for zz in b.z], strict=True)
    return np.array(xs), np.array(Ps)


SIGMA_V0 = {"aircraft": 300.0, "ship": 20.0}


def turning_config(case: Case, **kw: float) -> TurningConfig:
    return TurningConfig(sigma_velocity0=SIGMA_V0[case.name], **kw)


def sensor_noise(case: Case) -> SensorNoise:
    s = case.sigma
    return SensorNoise(s[0], s[1], s[2] if case.d == 3 else s[1])


def run_turning(case: Case, b: Batch, cfg: TurningConfig) -> tuple[np.ndarray, np.ndarray]:
    f = TurningFilter(cfg, case.d, sensor_noise(case))
    X, S = [], []
    for zz in b.z:
        res = f.run(b.t, zz)
        X.append(res.x)
        S.append(res.state != TurnState.STRAIGHT)
    return np.array(X), np.array(S)


def run_fixed(case: Case, b: Batch, qs: np.ndarray) -> np.ndarray:
    """CV-EKFs with fixed q, batched over (q, run): returns (nq, R, N, 2d)."""
    Rm = plot_covariance(*case.sigma, *([0.0] * (3 - case.d)), case.d)
    x0, P0 = _init(case, b, SIGMA_V0[case.name])
    nq = len(qs)
    x = np.broadcast_to(x0, (nq,) + x0.shape).copy()
    P = np.broadcast_to(P0, (nq,) + P0.shape).copy()
    out = np.empty((nq,) + b.z.shape[:2] + (2 * case.d,))
    out[:, :, 0] = x
    for k in range(1, b.t.size):
        dt = b.t[k] - b.t[k - 1]
        Q = cv_noise(dt, np.asarray(qs), case.d)[:, None]
        u = ekf_step(x, P, b.z[None, :, k], dt, Q, Rm)
        x, P = u.x, u.P
        out[:, :, k] = x
    return out


@dataclass(frozen=True)
class IMMParams:
    q_cv: float
    q_ct: float
    q_omega: float
    p_stay: float
    sigma_omega0: float = 0.05


def make_imm(case: Case, p: IMMParams) -> IMM:
    d = case.d
    if d == 3:
        meas = [RangeBearingElevation(n=6), RangeBearingElevation(n=7)]
    else:
        meas = [RangeBearing(n=4), RangeBearing(n=5)]
    PI = np.array([[p.p_stay, 1 - p.p_stay], [1 - p.p_stay, p.p_stay]])
    models = [ConstantVelocity(p.q_cv, d), CoordinatedTurn(p.q_ct, p.q_omega, d)]
    return IMM(models, PI, meas, mu0=np.array([0.9, 0.1]))


def run_imm(case: Case, b: Batch, p: IMMParams) -> tuple[np.ndarray, np.ndarray]:
    imm = make_imm(case, p)
    Rm = plot_covariance(*case.sigma, *([0.0] * (3 - case.d)), case.d)
    x0, P0 = _init(case, b, SIGMA_V0[case.name])
    st = imm.initial_state(x0, P0, extra={"w": (0.0, p.sigma_omega0**2)})
    X = np.empty(b.z.shape[:2] + (2 * case.d,))
    mu = np.empty(b.z.shape[:2])
    X[:, 0], mu[:, 0] = x0, st.mu[:, 1]
    for k in range(1, b.t.size):
        step = imm.step(st, b.z[:, k], b.t[k] - b.t[k - 1], Rm)
        st = step.state
        X[:, k], mu[:, k] = step.x, st.mu[:, 1]
    return X, mu > 0.5


# ---------------------------------------------------------------------------
# Metrics
# ---------------------------------------------------------------------------
def metrics(case: Case, b: Batch, X: np.ndarray, ind: np.ndarray | None) -> dict[str, Any]:
    d = case.d
    pe = np.linalg.norm(X[..., :d] - b.pos[..., :d], axis=-1)
    spd = np.hypot(X[..., d], X[..., d + 1])
    se = spd - np.hypot(b.vel[..., 0], b.vel[..., 1])
    he = np.degrees(
        angle_diff(bearing(X[..., d], X[..., d + 1]), bearing(b.vel[..., 0], b.vel[..., 1]))
    )
    valid = np.zeros(b.t.size, bool)
    valid[SKIP:] = True
    turn = (b.turn_rate != 0) & valid
    straight = (b.turn_rate == 0) & valid
    out: dict[str, Any] = {
        "run_mse": np.mean(pe[:, SKIP:] ** 2, axis=1),  # per run, for the bootstrap
        "pos": rmse(pe[:, SKIP:], None),
        "pos_straight": rmse(pe[straight], None),
        "pos_turn": rmse(pe[turn], None),
        "spd_straight": rmse(se[straight], None),
        "spd_turn": rmse(se[turn], None),
        "hdg_straight": rmse(he[straight], None),
        "hdg_turn": rmse(he[turn], None),
    }
    if ind is not None:
        delays, n_turns = [], 0
        quiet = straight.copy()
        for r, turns in enumerate(b.turns):
            for t0, t1 in turns:
                n_turns += 1
                win = (b.t >= t0) & (b.t <= t1 + 20.0) & ind[r]
                if win.any():
                    delays.append(b.t[np.argmax(win)] - t0)
                quiet[r] &= ~((b.t >= t0) & (b.t < t1 + 60.0))
        out["delay"] = float(np.mean(delays)) if delays else math.nan
        out["det"] = 100.0 * len(delays) / n_turns
        out["false"] = 100.0 * float(ind[quiet].mean())
    return out


def time_per_step(fn, n_steps: int) -> float:
    t0 = time.perf_counter()
    fn()
    return 1e6 * (time.perf_counter() - t0) / n_steps


def single_track_times(case: Case, b: Batch, cfg: TurningConfig, ip: IMMParams) -> dict[str, float]:
    """Microseconds per scan for ONE track (no batching), averaged over 3 runs."""
    n = 3 * (b.t.size - 1)
    zs = b.z[:3]
    Rm = plot_covariance(*case.sigma, *([0.0] * (3 - case.d)), case.d)

    def turning() -> None:
        f = TurningFilter(cfg, case.d, sensor_noise(case))
        for zz in zs:
            f.run(b.t, zz)

    def ekf() -> None:
        Q = {}  # Q per scan interval, computed once (as the turning filter caches it)
        for zz in zs:
            x, P = initial_state(zz[0], Rm, SIGMA_V0[case.name])
            for k in range(1, b.t.size):
                dt = b.t[k] - b.t[k - 1]
                if dt not in Q:
                    Q[dt] = cv_noise(dt, cfg.q_nominal, case.d)
                u = ekf_step(x, P, zz[k], dt, Q[dt], Rm)
                x, P = u.x, u.P

    def imm_run() -> None:
        imm = make_imm(case, ip)
        for zz in zs:
            x, P = initial_state(zz[0], Rm, SIGMA_V0[case.name])
            st = imm.initial_state(x, P, extra={"w": (0.0, ip.sigma_omega0**2)})
            for k in range(1, b.t.size):
                st = imm.step(st, zz[k], b.t[k] - b.t[k - 1], Rm).state

    turning()  # warm-up (JIT caches)
    ekf()
    imm_run()
    return {
        "turning": time_per_step(turning, n + 3),
        "ekf": time_per_step(ekf, n),
        "imm": time_per_step(imm_run, n),
    }


# ---------------------------------------------------------------------------
# Tuning (TUNING seeds only)
# ---------------------------------------------------------------------------
#: values found by ``--tune all --tune-runs 40`` (TUNE_SEED); see tune() and tune_imm().
#: Several sit at the edge of the searched range (delta_omega_threshold 0.001, M = 4 = the
#: smallest the spec allows, IMM q_cv = q_best / 300 for ships).
TUNED: dict[str, dict[str, float]] = {
    "aircraft": {
        "q_nominal": 7.18144896677294,
        "delta_omega_threshold": 0.001,
        "gain_reference": 0.0005,
        "gain_max": 10.0,
        "queue_length": 4,
        "q_heading": 0.0001,
    },
    "ship": {
        "q_nominal": 0.004641588833612777,
        "delta_omega_threshold": 0.001,
        "gain_reference": 0.0005,
        "queue_length": 4,
    },
}
TUNED_IMM: dict[str, IMMParams] = {
    "aircraft": IMMParams(
        q_cv=0.21544346900318823, q_ct=0.21544346900318823, q_omega=1e-4, p_stay=0.98
    ),
    "ship": IMMParams(
        q_cv=0.0001547196277870926, q_ct=0.0001547196277870926, q_omega=1e-5, p_stay=0.98
    ),
}


def best_fixed_q(case: Case, b: Batch) -> float:
    """The q of the best fixed-q CV-EKF on the (tuning) batch ``b``."""
    fixed = run_fixed(case, b, np.array(case.q_grid))
    scores = [metrics(case, b, X, None)["pos"] for X in fixed]
    q_best = float(case.q_grid[int(np.argmin(scores))])
    print(
        f"[tune {case.name}] best fixed q on tuning seeds = {q_best:.3g} (pos {min(scores):.2f} m)",
        flush=True,
    )
    return q_best


def tune(case: Case, n_runs: int) -> dict[str, float]:
    """Search for the method's free parameters on the TUNING seeds (objective: overall
    position RMSE). The candidate nominal q values are scaled from the best fixed-q EKF on
    the tuning runs (the method only ever raises Q, so its nominal q sits at or below)."""
    b = simulate(case, TUNE_SEED, n_runs)
    q_best = best_fixed_q(case, b)
    # grid over the three parameters that matter most (nominal q, the S4 delta-omega
    #    threshold, the S5 gain scale), then coordinate descent over all of them and the
    #    rest (cap, M, heading-filter q), starting from the best grid point
    space: dict[str, list[float]] = {
        "q_nominal": [q_best / 30, q_best / 10, q_best / 3, q_best],
        "delta_omega_threshold": [0.02, 0.01, 0.005, 0.002, 0.001],
        "gain_reference": [0.02, 0.005, 0.002, 0.0005, 0.0002],
        "gain_max": [3.0, 10.0, 100.0, 1000.0],
        "queue_length": [4, 5, 6],
        "q_heading": [1e-6, 1e-5, 1e-4],
    }
    finer = {"q_nominal": [q_best / 100, q_best / 20, q_best / 5, q_best / 2]}
    cache: dict[tuple, float] = {}

    def score(kw: dict[str, float]) -> float:
        key = tuple(sorted(kw.items()))
        if key not in cache:
            X, _ = run_turning(case, b, turning_config(case, **kw))
            cache[key] = metrics(case, b, X, None)["pos"]
        return cache[key]

    best_s, cur = math.inf, {}
    for qn, dw, gr in itertools.product(
        space["q_nominal"], space["delta_omega_threshold"], space["gain_reference"]
    ):
        kw = {"q_nominal": qn, "delta_omega_threshold": dw, "gain_reference": gr}
        s = score(kw)
        if s < best_s:
            best_s, cur = s, kw
    print(f"[tune {case.name}] grid: {cur} -> pos {best_s:.2f} m", flush=True)
    for sweep in range(2):
        for name in ("gain_max", "queue_length", "q_heading", *list(space)[:3]):
            for v in space[name] + finer.get(name, []):
                s = score({**cur, name: v})
                if s < best_s - 1e-9:
                    best_s, cur = s, {**cur, name: v}
        print(f"[tune {case.name}] sweep {sweep}: {cur} -> pos {best_s:.2f} m", flush=True)
    return cur


def tune_imm(case: Case, n_runs: int) -> IMMParams:
    """Grid search for the IMM on the same tuning seeds (same objective)."""
    b = simulate(case, TUNE_SEED, n_runs)
    q_best = best_fixed_q(case, b)
    best_s, best_p = math.inf, None
    for f, qw, ps in itertools.product(
        [1 / 300, 1 / 100, 1 / 30, 1 / 10, 1 / 3],
        [1e-7, 1e-6, 1e-5, 1e-4, 1e-3],
        [0.9, 0.95, 0.98],
    ):
        p = IMMParams(q_best * f, q_best * f, qw, ps)
        X, _ = run_imm(case, b, p)
        s = metrics(case, b, X, None)["pos"]
        if s < best_s:
            best_s, best_p = s, p
    print(f"[tune {case.name}] imm: {best_p} -> pos {best_s:.2f} m", flush=True)
    assert best_p is not None
    return best_p


# ---------------------------------------------------------------------------
def evaluate(case: Case, n_runs: int, tuned: dict[str, float], ip: IMMParams) -> list[dict]:
    b = simulate(case, EVAL_SEED, n_runs)
    cfg = turning_config(case, **tuned)
    spec_cfg = turning_config(case, q_nominal=tuned["q_nominal"])
    grid = np.array(sorted(set(case.q_grid) | {cfg.q_nominal, case.q_high}))
    fixed = run_fixed(case, b, grid)
    scores = np.array([metrics(case, b, X, None)["pos"] for X in fixed])
    i_best = int(np.argmin(scores))
    times = single_track_times(case, b, cfg, ip)
    rows: list[dict] = []

    def add(name: str, X: np.ndarray, ind: np.ndarray | None, us: float, note: str) -> None:
        m = metrics(case, b, X, ind)
        rows.append({"case": case.name, "filter": name, "note": note, "us": us, **m})

    # headline: `seatrack track` defaults + the sensor's nominal noise (and the class)
    plots = labelled_plots(b.t, *np.moveaxis(b.z, -1, 0))
    cfg0 = nominal(*case.sigma)
    for label, method, extra in (
        ("turning", "turning", {}),
        ("turning +target", "turning", {"target": case.name}),
        ("turning-spec", "turning-spec", {}),
    ):
        t0 = time.perf_counter()
        X, _, cols = run_registry(method, plots, {**cfg0, **extra}, len(b.z))
        us = (time.perf_counter() - t0) / b.z[..., 0].size * 1e6
        ind = (
            cols["p_manoeuvre"] > 0.5 if "p_manoeuvre" in cols else cols["turn_state"] != "straight"
        )
        add(label, X, ind.reshape(X.shape[:2]), us, "defaults + nominal noise")
        if "p_manoeuvre" in cols:  # the same run, the patent's vote as the indicator
            vote = (cols["turn_state"] != "straight").reshape(X.shape[:2])
            add(f"{label} (turn_state)", X, vote, us, "same run, turn_state vote")
    # tuned rows (parameters chosen on the TUNING seeds)
    X, ind = run_turning(case, b, cfg)
    add("turning-spec tuned", X, ind, times["turning"], f"q={cfg.q_nominal:.3g} tuned")
    X, ind = run_turning(case, b, spec_cfg)
    add("turning-spec tuned q", X, ind, times["turning"], "c=(dw/.02)^2<=100,M=5")
    lo = int(np.flatnonzero(grid == cfg.q_nominal)[0])
    hi = int(np.flatnonzero(grid == case.q_high)[0])
    add("ekf-lowQ", fixed[lo], None, times["ekf"], f"q={grid[lo]:.3g}")
    add("ekf-highQ", fixed[hi], None, times["ekf"], f"q={grid[hi]:.3g}")
    add("ekf-bestQ", fixed[i_best], None, times["ekf"], f"q={grid[i_best]:.3g} hindsight")
    X, ind = run_imm(case, b, ip)
    add("imm tuned", X, ind, times["imm"], f"qw={ip.q_omega:.0e},p={ip.p_stay}")
    # overall position RMSE ratio to the hindsight-best EKF, with a 95 % bootstrap interval
    # over runs (paired: the same resampled runs for both filters)
    best = next(r for r in rows if r["filter"] == "ekf-bestQ")
    ref = best["run_mse"]
    idx = np.random.default_rng(0).integers(0, ref.size, (2000, ref.size))
    for r in rows:
        mse = r["run_mse"]
        r["ratio"] = r["pos"] / best["pos"]
        boot = np.sqrt(mse[idx].mean(axis=1) / ref[idx].mean(axis=1))
        lo, hi = np.percentile(boot, [2.5, 97.5])
        r["ci"] = f"{lo:.3f}-{hi:.3f}"
        r["win"] = 100.0 * float(np.mean(mse < ref))
    for r in rows:
        del r["run_mse"]
    return rows


COLUMNS = [
    ("case", "set"),
    ("filter", "filter"),
    ("note", "parameters"),
    ("pos", "pos", ".1f"),
    ("ratio", "/bestQ", ".3f"),
    ("ci", "95% CI"),
    ("win", "win%", ".0f"),
    ("pos_straight", "pos-str", ".1f"),
    ("pos_turn", "pos-turn", ".1f"),
    ("spd_straight", "spd-str", ".2f"),
    ("spd_turn", "spd-turn", ".2f"),
    ("hdg_straight", "hdg-str", ".2f"),
    ("hdg_turn", "hdg-turn", ".2f"),
    ("delay", "delay-s", ".1f"),
    ("det", "det%", ".0f"),
    ("false", "false%", ".1f"),
    ("us", "us/step", ".0f"),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="20 runs per set (smoke test)")
    ap.add_argument("--runs", type=int, default=None, help="evaluation runs per set (default 200)")
    ap.add_argument(
        "--tune",
        choices=("all", "method", "imm"),
        default=None,
        help="re-run the tuning search (on the tuning seeds) first",
    )
    ap.add_argument("--tune-runs", type=int, default=60)
    ap.add_argument("--cases", default="aircraft,ship")
    a = ap.parse_args()
    n = a.runs if a.runs is not None else (20 if a.quick else 200)
    rows = []
    t0 = time.perf_counter()
    for name in a.cases.split(","):
        case = CASES[name]
        tuned, ip = TUNED[name], TUNED_IMM[name]
        if a.tune in ("all", "method"):
            tuned = tune(case, a.tune_runs)
            print(f"[tune {name}] chosen: {tuned}", flush=True)
        if a.tune in ("all", "imm"):
            ip = tune_imm(case, a.tune_runs)
        rows += evaluate(case, n, tuned, ip)
    print(
        f"\nturning-target benchmark: {n} runs per set (eval seed {EVAL_SEED}, tuning seed "
        f"{TUNE_SEED}), {time.perf_counter() - t0:.0f} s"
    )
    print(
        "RMSE after a 10-scan transient: pos m (3-D aircraft, 2-D ship), speed m/s, heading deg;"
        " /bestQ = overall pos RMSE ratio to the hindsight-best fixed-q EKF (95% CI: paired"
        " bootstrap over runs; win% = runs with lower pos RMSE than it)"
    )
    print(format_table(rows, COLUMNS))
    print("targets (issue 16; headline rows = defaults + nominal noise):")
    for name in a.cases.split(","):
        r = {x["filter"]: x for x in rows if x["case"] == name}
        band = min(r["ekf-lowQ"]["pos"], r["ekf-highQ"]["pos"])
        for label in ("turning", "turning +target", "turning-spec"):
            for what, ref, lim in (("min(narrow, wide)", band, 0.95),
                                   ("hindsight best q", r["ekf-bestQ"]["pos"], 1.0)):  # fmt: skip
                ratio = r[label]["pos"] / ref
                verdict = "MET" if ratio <= lim else "NOT MET"
                print(f"  {name}: {label} / {what} = {ratio:.3f} (<= {lim}) {verdict}")


if __name__ == "__main__":
    main()
