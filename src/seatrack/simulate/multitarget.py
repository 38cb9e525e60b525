"""Multi-target scenarios: many ships born and dying, crossing and manoeuvring, seen by one
radar with missed detections and clutter -- unlabelled plots plus the truth to score them.

A :class:`TargetPopulation` (the ``[multitarget]`` table of a scenario TOML file, see
:func:`parse_multitarget`) describes the target population; the radar (noise, detection
probability, clutter, scan period, position) is a scenario sensor
(:class:`~seatrack.simulate.scenarios.SensorConfig` or anything with the same attributes).

Targets:

* ``targets`` ships at the start, then Poisson births (``births_per_scan``); each lives an
  exponential time (mean ``mean_life_s``; 0: forever) and exists only while inside the
  surveillance annulus ``range_m`` around the radar;
* start positions uniform over the annulus area, courses uniform, speeds uniform in
  ``speed_kn``;
* straight legs of exponential length (mean ``turn_interval_s``) alternating with
  manoeuvres: coordinated turns (rate uniform in ``turn_rate_dps``, angle uniform in
  ``turn_angle_deg``, either side) or, with probability ``speed_change_fraction``, a speed
  change to a new speed at ``accel_mps2``;
* ``crossings`` pairs of ships that pass the same point at the same time (in the middle
  part of the run, at angles of 20-160 degrees) before manoeuvring like the others.

Plots: each live target is detected with the sensor's ``p_detect`` and measured with its
noise; ``clutter_density`` false plots per scan (Poisson) are uniform in range over
``clutter_range_m`` and in azimuth over the full circle (range rate uniform within the
fastest target speed, elevation uniform within +-1 degree). Everything draws from one
seeded generator: a run is reproducible from its seed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.config import Checked
from seatrack.config import ConfigError
from seatrack.config import param
from seatrack.config import parse_config
from seatrack.config import to_edge
from seatrack.filters.base import Plots
from seatrack.io.table import InputError
from seatrack.simulate.sensors import NoiseModel
from seatrack.simulate.sensors import observe
from seatrack.simulate.sensors import uniform_clutter
from seatrack.simulate.trajectories import Leg
from seatrack.simulate.trajectories import Trajectory
from seatrack.simulate.trajectories import trajectory

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "TargetPopulation",
    "MultiTargetRun",
    "RadarLike",
    "parse_multitarget",
    "simulate_multitarget",
    "born_targets",
    "work_samples",
]


@dataclass(frozen=True)
class TargetPopulation(Checked):
    """The target population of a multi-target scenario (SI inside; edge units in keys)."""

    targets: int = param(10, doc="targets at the start", min=0)
    births_per_scan: float = param(0.02, unit="1/scan", doc="expected new targets per scan", min=0)
    mean_life: float = param(
        1800.0, key="mean_life_s", unit="s", doc="mean target lifetime (0: forever)", min=0
    )
    range_limits: tuple[float, float] = param(
        (1000.0, 15000.0), key="range_m", unit="m", doc="surveillance annulus (min, max range)"
    )
    speed_limits: tuple[float, float] = param(
        (3.0, 25.0), key="speed_kn", unit="kn", doc="target speeds (min, max)"
    )
    turn_interval: float = param(
        120.0, key="turn_interval_s", unit="s", doc="mean straight leg between manoeuvres",
        min=0, exclusive_min=True,
    )  # fmt: skip
    turn_rate_limits: tuple[float, float] = param(
        (0.5, 3.0), key="turn_rate_dps", unit="deg/s", doc="turn rates (min, max)"
    )
    turn_angle_limits: tuple[float, float] = param(
        (20.0, 120.0), key="turn_angle_deg", unit="deg", doc="turn angles (min, max)"
    )
    speed_change_fraction: float = param(
        0.25, doc="share of manoeuvres that are speed changes", min=0, max=1
    )
    accel: float = param(
        0.2, key="accel_mps2", unit="m/s^2", doc="acceleration of speed changes",
        min=0, exclusive_min=True,
    )  # fmt: skip
    crossings: int = param(2, doc="pairs of targets crossing each other", min=0)

    def expected_targets(self, duration_s: float, scan_s: float) -> float:
        """Targets expected over a run of ``duration_s``: those at the start, both ships of
        each crossing and the births, ``births_per_scan`` per scan of ``scan_s`` seconds."""
        n_scans = math.floor(duration_s / scan_s + 1e-9) + 1
        return self.targets + 2 * self.crossings + self.births_per_scan * n_scans

    def __post_init__(self) -> None:
        super().__post_init__()
        edge = to_edge(self)
        for key in ("range_m", "speed_kn", "turn_rate_dps", "turn_angle_deg"):
            lo_hi = edge[key]
            if len(lo_hi) != 2 or not 0 <= lo_hi[0] <= lo_hi[1]:
                raise ValueError(
                    f"{key}: expected [min, max] with 0 <= min <= max, got {list(lo_hi)}"
                )
        if self.range_limits[1] <= self.range_limits[0]:
            raise ValueError(f"range_m: max must exceed min, got {list(edge['range_m'])}")


def parse_multitarget(table: Mapping[str, Any], path: str = "<scenario>") -> TargetPopulation:
    """The ``[multitarget]`` table of a scenario file.

    Raises
    ------
    InputError
        ``PATH: multitarget: key: problem`` for an unknown key or a bad value.
    """
    try:
        return parse_config(TargetPopulation, table, source=f"{path}: multitarget")
    except ConfigError as exc:
        raise InputError(str(exc)) from None


class Scripted(Protocol):
    """A scripted target (a scenario ``Platform``): its truth at any times."""

    def trajectory(self, times: FloatArray) -> Trajectory: ...


class RadarLike(Protocol):
    """The sensor attributes the simulation uses (a scenario ``SensorConfig`` has them)."""

    components: tuple[str, ...]
    sigma: tuple[float, ...]
    p_detect: float
    clutter_density: float
    clutter_range: tuple[float, float]
    scan_period: float


@dataclass(frozen=True)
class MultiTargetRun:
    """One simulated run.

    Attributes
    ----------
    plots : every plot (targets and clutter) in time order, SI units
    origin : (N,) int -- target index of each plot, -1 for clutter
    scan_times : (K,) s
    truth_t, truth_id : (M,) -- one row per (scan, live target)
    truth_pos, truth_vel : (M, 3) m, m/s
    """

    plots: Plots
    origin: IntArray
    scan_times: FloatArray
    truth_t: FloatArray
    truth_id: IntArray
    truth_pos: FloatArray
    truth_vel: FloatArray


@dataclass(frozen=True)
class _Target:
    birth: float
    death: float
    start: FloatArray
    course: float
    speed: float
    legs: tuple[Leg, ...]


def _uniform(rng: np.random.Generator, lo_hi: Sequence[float], n: int | None = None) -> Any:
    return rng.uniform(lo_hi[0], lo_hi[1], n)


def _annulus_point(rng: np.random.Generator, lo: float, hi: float) -> FloatArray:
    r = math.sqrt(rng.uniform(lo**2, hi**2))
    a = rng.uniform(0, 2 * math.pi)
    return np.array([r * math.sin(a), r * math.cos(a), 0.0])


def _legs(cfg: TargetPopulation, rng: np.random.Generator, speed: float, span: float) -> list[Leg]:
    """Straight legs and manoeuvres covering ``span`` seconds."""
    legs: list[Leg] = []
    total = 0.0
    while total < span:
        straight = Leg(max(rng.exponential(cfg.turn_interval), 1.0))
        legs.append(straight)
        total += straight.duration
        if rng.random() < cfg.speed_change_fraction:
            to = float(_uniform(rng, cfg.speed_limits))
            if abs(to - speed) < 0.05:
                continue
            leg = Leg.speed_change(speed, to, cfg.accel)
            speed = to
        else:
            rate = float(_uniform(rng, cfg.turn_rate_limits))
            angle = float(_uniform(rng, cfg.turn_angle_limits)) * rng.choice([-1.0, 1.0])
            if rate <= 0 or angle == 0:
                continue
            leg = Leg.turn(angle, rate)
        legs.append(leg)
        total += leg.duration
    return legs


def _life(cfg: TargetPopulation, rng: np.random.Generator, birth: float) -> float:
    return birth + (rng.exponential(cfg.mean_life) if cfg.mean_life > 0 else math.inf)


def _population(
    cfg: TargetPopulation, rng: np.random.Generator, times: FloatArray
) -> list[_Target]:
    duration = float(times[-1])
    lo, hi = cfg.range_limits
    out = []
    births = [0.0] * cfg.targets
    counts = rng.poisson(cfg.births_per_scan, times.size)
    births += [float(t) for t, k in zip(times[1:], counts[1:], strict=True) for _ in range(k)]
    for b in births:
        speed = float(_uniform(rng, cfg.speed_limits))
        start, course = _annulus_point(rng, lo, hi), rng.uniform(0, 2 * math.pi)
        legs = tuple(_legs(cfg, rng, speed, duration - b))
        out.append(_Target(b, _life(cfg, rng, b), start, course, speed, legs))
    for _ in range(cfg.crossings):
        middle = (lo + 0.25 * (hi - lo), hi - 0.25 * (hi - lo))
        pc = _annulus_point(rng, *middle)
        tc = rng.uniform(0.3, 0.7) * duration
        c1 = rng.uniform(0, 2 * math.pi)
        c2 = c1 + rng.uniform(math.radians(20), math.radians(160)) * rng.choice([-1.0, 1.0])
        for course in (c1, c2):
            speed = float(_uniform(rng, cfg.speed_limits))
            v = speed * np.array([math.sin(course), math.cos(course), 0.0])
            legs = (Leg(tc), *_legs(cfg, rng, speed, duration - tc)) if tc > 0 else ()
            out.append(_Target(0.0, _life(cfg, rng, tc), pc - v * tc, course, speed, legs))
    return out


def _sensor_positions(observer: Trajectory | ArrayLike | None, times: FloatArray) -> FloatArray:
    if isinstance(observer, Trajectory):
        return np.asarray(observer.at(times), dtype=float)
    p = np.zeros(3)
    if observer is not None:
        o = np.asarray(observer, dtype=float)
        p[: o.size] = o
    return np.broadcast_to(p, (times.size, 3)).copy()


def _clip_trajectory(tr: Trajectory, keep: NDArray[np.bool_]) -> Trajectory:
    return Trajectory(*(getattr(tr, f)[keep] for f in tr.__dataclass_fields__))


def simulate_multitarget(
    cfg: TargetPopulation,
    sensor: RadarLike,
    duration: float,
    rng: np.random.Generator,
    observer: Trajectory | ArrayLike | None = None,
    scripted: Sequence[Scripted] = (),
) -> MultiTargetRun:
    """Simulate one run: targets, their plots and clutter over ``duration`` seconds.

    Parameters
    ----------
    cfg : the target population
    sensor : radar (components, sigma, p_detect, clutter_density, clutter_range, scan_period)
    duration : s -- scans at ``0, T, 2T, ... <= duration``
    rng : the only source of randomness
    observer : radar platform (a trajectory) or fixed position; default the origin
    scripted : targets scripted by legs (scenario ``[[targets]]``), alive all the run; they
        come first in the target numbering, the generated ones follow
    """
    T = float(sensor.scan_period)
    times = T * np.arange(int(math.floor(duration / T + 1e-9)) + 1, dtype=float)
    spos = _sensor_positions(observer, times)
    noise = NoiseModel(sensor.sigma)
    comps = tuple(sensor.components)
    cols: dict[str, list[FloatArray]] = {c: [] for c in comps}
    plot_t, origin = [], []
    rows: list[tuple[FloatArray, IntArray, FloatArray, FloatArray]] = []
    truths = [(k, sc.trajectory(times)) for k, sc in enumerate(scripted)]
    for k, tg in enumerate(_population(cfg, rng, times), start=len(truths)):
        live = (times >= tg.birth) & (times < tg.death)
        if not live.any():
            continue
        tr = trajectory(tg.start, tg.course, tg.speed, tg.legs, times=times[live], t0=tg.birth)
        rng_from_sensor = np.linalg.norm(tr.pos[:, :2] - spos[live, :2], axis=1)
        inside = (rng_from_sensor >= cfg.range_limits[0]) & (rng_from_sensor <= cfg.range_limits[1])
        if inside.any():
            truths.append((k, _clip_trajectory(tr, inside)))
    obs = observer if isinstance(observer, Trajectory) or observer is None else spos[0]
    for k, tr in truths:
        m = observe(tr, obs, comps, noise, rng, sensor.p_detect)
        det = m.detected
        for j, c in enumerate(comps):
            cols[c].append(m.z[det, j])
        plot_t.append(tr.t[det])
        origin.append(np.full(int(det.sum()), k, np.int64))
        rows.append((tr.t, np.full(tr.t.size, k, np.int64), tr.pos, tr.vel))
    ct, cr, ca = uniform_clutter(
        times, sensor.clutter_density, sensor.clutter_range, (0.0, 2 * math.pi), rng
    )
    vmax = cfg.speed_limits[1]
    extra = {
        "azimuth": ca,
        "range": cr,
        "elevation": rng.uniform(-math.radians(1), math.radians(1), ct.size),
        "range_rate": rng.uniform(-vmax, vmax, ct.size),
    }
    for c in comps:
        cols[c].append(extra[c])
    plot_t.append(ct)
    origin.append(np.full(ct.size, -1, np.int64))
    return _assemble(times, spos, cols, plot_t, origin, rows)


def _assemble(
    times: FloatArray,
    scan_pos: FloatArray,
    cols: Mapping[str, list[FloatArray]],
    plot_t: list[FloatArray],
    origin: list[IntArray],
    rows: list[tuple[FloatArray, IntArray, FloatArray, FloatArray]],
) -> MultiTargetRun:
    t = np.concatenate(plot_t)
    order = np.argsort(t, kind="stable")
    col = {c: np.concatenate(v)[order] for c, v in cols.items()}
    scan = np.searchsorted(times, t[order])
    scan_vel = np.zeros_like(scan_pos)
    if times.size > 1:
        scan_vel = np.stack([np.gradient(scan_pos[:, k], times) for k in range(3)], -1)
    plots = Plots(
        t[order],
        col["range"],
        col["azimuth"],
        col.get("elevation"),
        col.get("range_rate"),
        scan_pos[scan],
        scan_vel[scan],
    )
    if rows:
        tt, ti, tp, tv = (np.concatenate([r[i] for r in rows]) for i in range(4))
        o = np.lexsort((ti, tt))
        tt, ti, tp, tv = tt[o], ti[o], tp[o], tv[o]
    else:
        tt, ti, tp, tv = np.zeros(0), np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3))
    return MultiTargetRun(plots, np.concatenate(origin)[order], times, tt, ti, tp, tv)


def born_targets(
    duration: float, dt: float, sensors: Sequence[Any], population: TargetPopulation | None
) -> float:
    """Expected targets a population adds over ``duration`` s, seen at the fastest sensor's
    scan period (s); 0 without a population."""
    fastest = min((s.scan_period for s in sensors), default=dt)
    return population.expected_targets(duration, fastest) if population else 0.0


def work_samples(
    duration: float, dt: float, n_scripted: int, sensors: Sequence[Any],
    population: TargetPopulation | None = None,
) -> float:  # fmt: skip
    """Simulated samples of one run of a scenario: truth (every ``dt`` s) and scans of every
    target, the expected ones of a ``[multitarget]`` population included (what
    ``seatrack.simulate.scenarios.MAX_POINTS`` bounds); ``sensors`` have a ``scan_period``
    (s)."""
    n_targets = n_scripted + born_targets(duration, dt, sensors, population)
    scans = sum(math.floor(duration / s.scan_period + 1e-9) + 1 for s in sensors)
    return float((scans + math.floor(duration / dt + 1e-9) + 1) * (n_targets + 1))
