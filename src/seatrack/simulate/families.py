"""Scenario families for honest benchmarks: generators the method benchmarks do not use.

Three families, each a function ``(..., seed) -> Scenario`` (truth, plots, the sensor's
nominal noise), reproducible from the seed:

* :func:`ais_replay` -- **real vessel trajectories** from the bundled AIS samples
  (``seatrack.data.ais_sample``) as truth, observed by a simulated coastal radar or an
  active sonar. The truth is a cubic smoothing spline through the vessel's reported
  positions (``lam = sigma^2 / q``: the spline is the Bayesian smoother of a white-noise
  acceleration path with PSD ``q`` = 0.01 m^2/s^3 seen with 3 m position noise, Wahba
  1978), after removing duplicate timestamps and gross position glitches; positions and
  velocities come from the spline and its derivative. Stretches of 20 minutes are kept
  when the vessel makes way (>= 1.5 m/s throughout), turns through at least 45 deg and
  stays within 1 m/s^2 and 5 deg/s.
* :func:`random_manoeuvres` -- per target class, random sequences of straight legs,
  coordinated turns at class-typical rates and speed changes (:data:`MANOEUVRE_SPECS`):
  ship / coastal radar, submarine / active sonar, aircraft / air-traffic radar
  (1.5-3 deg/s turns at 90-150 m/s, 4 s scans, 40 m and 0.08 deg), fighter / radar with
  range rate (3-6 g turns).
* :func:`weaving` -- a zig-zag: the turn rate follows a sinusoid (heading excursions of
  20-45 deg at the class's typical turn rate), so the target is never straight and never
  in a steady turn -- structurally different from legs and turns.

Every family accepts ``epsilon``: the fraction of plot components drawn from a wide
noise (Tukey-Huber contamination as in Ramazanov's set-up, ``docs/robust.md``: variance
x10 in range, x25 in azimuth); :attr:`Scenario.outlier` says which.

Seeds: **TUNING** seeds are ``0 <= seed < 1_000_000`` and **HEADLINE** seeds
``1_000_000 <= seed < 2_000_000`` (:data:`TUNING_SEEDS`, :data:`HEADLINE_SEEDS`). Tune on
the first, report on the second. For :func:`ais_replay` the real trajectories are split
too: the vessels of the bundled samples are divided into a tuning half and a headline
half (:func:`ais_stretches`), so a headline seed never replays a vessel seen in tuning.

Plots are 2-D (range, azimuth[, range rate]); x East, y North; SI units and radians.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import BSpline
from scipy.interpolate import make_smoothing_spline

from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.geometry import G0
from seatrack.geometry import course_speed
from seatrack.geometry import wrap_2pi
from seatrack.models.targets import TargetClass
from seatrack.models.targets import target_class
from seatrack.simulate.sensors import NoiseModel
from seatrack.simulate.sensors import observe
from seatrack.simulate.trajectories import Leg
from seatrack.simulate.trajectories import Trajectory
from seatrack.simulate.trajectories import trajectory

FloatArray = NDArray[np.float64]

__all__ = [
    "TUNING_SEEDS",
    "HEADLINE_SEEDS",
    "seed_split",
    "SensorSpec",
    "COASTAL_RADAR",
    "ACTIVE_SONAR",
    "ATC_RADAR",
    "FIGHTER_RADAR",
    "OUTLIER_SCALE",
    "Scenario",
    "ManoeuvreSpec",
    "MANOEUVRE_SPECS",
    "AisStretch",
    "ais_stretches",
    "ais_replay",
    "random_manoeuvres",
    "weaving",
    "labelled_runs",
]

DEG = math.pi / 180.0

#: seeds for tuning anything (parameters, thresholds, method choices)
TUNING_SEEDS = range(0, 1_000_000)
#: seeds for the reported (headline) figures only
HEADLINE_SEEDS = range(1_000_000, 2_000_000)

#: variance multipliers of contaminated components: range, azimuth, range rate
OUTLIER_SCALE = (10.0, 25.0, 10.0)


def seed_split(seed: int) -> str:
    """``"tuning"`` or ``"headline"`` (ValueError outside both ranges)."""
    if seed in TUNING_SEEDS:
        return "tuning"
    if seed in HEADLINE_SEEDS:
        return "headline"
    raise ValueError(
        f"seed {seed} is in neither the tuning range [0, 1e6) nor the headline range [1e6, 2e6)"
    )


# ---------------------------------------------------------------------------
# Sensors
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class SensorSpec:
    """A sensor: scan interval (s) and nominal noise (m, rad, m/s; no range rate if None)."""

    name: str
    dt: float
    sigma_range: float
    sigma_azimuth: float
    sigma_range_rate: float | None = None

    @property
    def noise(self) -> SensorNoise:
        """The nominal noise as the ``[sensor]`` section every method shares."""
        rr = 1.0 if self.sigma_range_rate is None else self.sigma_range_rate
        return SensorNoise(self.sigma_range, self.sigma_azimuth, 0.5 * DEG, rr)

    @property
    def components(self) -> tuple[str, ...]:
        base = ("range", "azimuth")
        return base if self.sigma_range_rate is None else base + ("range_rate",)

    @property
    def sigmas(self) -> tuple[float, ...]:
        s = (self.sigma_range, self.sigma_azimuth)
        return s if self.sigma_range_rate is None else s + (self.sigma_range_rate,)


#: coastal surveillance radar (~24 rpm antenna)
COASTAL_RADAR = SensorSpec("coastal-radar", 2.5, 10.0, 0.3 * DEG)
#: hull-mounted / dipping active sonar (the nominal noise of Ramazanov's set-up, 1 deg)
ACTIVE_SONAR = SensorSpec("active-sonar", 2.0, 1.5, 1.0 * DEG)
#: air-traffic (terminal) radar: 4 s scans, 40 m, 0.08 deg
ATC_RADAR = SensorSpec("atc-radar", 4.0, 40.0, 0.08 * DEG)
#: pulse-Doppler radar watching a fighter: 2 s, 30 m, 0.3 deg, range rate 0.5 m/s
FIGHTER_RADAR = SensorSpec("fighter-radar", 2.0, 30.0, 0.3 * DEG, 0.5)


# ---------------------------------------------------------------------------
# Scenario
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Scenario:
    """One simulated run.

    Attributes
    ----------
    family, target, sensor_name : labels; seed, split (``tuning`` / ``headline``).
    truth : (N, 4) -- ``[x, y, vx, vy]`` at the plot times (m, m/s).
    turn_rate : (N,) rad/s (clockwise positive); manoeuvring : (N,) bool.
    plots : :class:`~seatrack.filters.base.Plots` (2-D; range rate when the sensor has it).
    sensor : :class:`~seatrack.filters.base.SensorNoise` -- the nominal noise.
    outlier : (N, m) bool -- plot components drawn from the wide noise.
    epsilon : contamination fraction; outlier_scale : variance multipliers per component.
    """

    family: str
    target: str
    sensor_name: str
    seed: int
    split: str
    truth: FloatArray
    turn_rate: FloatArray
    manoeuvring: NDArray[np.bool_]
    plots: Plots
    sensor: SensorNoise
    outlier: NDArray[np.bool_]
    epsilon: float
    outlier_scale: tuple[float, ...]

    def sensor_table(self) -> dict[str, float]:
        """What a user gives a method: the sensor's nominal noise in the documented
        configuration keys (degrees at the edge), range rate when the plots have it."""
        cfg = {
            "sigma_range_m": self.sensor.sigma_range,
            "sigma_azimuth_deg": math.degrees(self.sensor.sigma_azimuth),
        }
        if self.plots.has_range_rate:
            cfg["sigma_range_rate_mps"] = self.sensor.sigma_range_rate
        return cfg

    @property
    def dt(self) -> float:
        return float(self.plots.t[1] - self.plots.t[0])


def _observe(
    family: str,
    target: str,
    seed: int,
    traj: Trajectory,
    observer: Trajectory | FloatArray,
    sensor: SensorSpec,
    epsilon: float,
    manoeuvring: NDArray[np.bool_],
    rng: np.random.Generator,
) -> Scenario:
    if not 0.0 <= epsilon < 1.0:
        raise ValueError(f"epsilon must be in [0, 1), got {epsilon}")
    comps = sensor.components
    scale = OUTLIER_SCALE[: len(comps)]
    m = observe(traj, observer, comps, NoiseModel(sensor.sigmas, epsilon, scale), rng)
    plots = Plots(
        m.t,
        m.z[:, 0],
        m.z[:, 1],
        None,
        m.z[:, 2] if len(comps) == 3 else None,
        m.sensor_pos,
        m.sensor_vel,
    )
    truth = np.concatenate([traj.pos[:, :2], traj.vel[:, :2]], -1)
    return Scenario(
        family,
        target,
        sensor.name,
        seed,
        seed_split(seed),
        truth,
        traj.turn_rate.copy(),
        manoeuvring,
        plots,
        sensor.noise,
        m.outlier,
        float(epsilon),
        scale,
    )


def _rng(seed: int, family: str) -> np.random.Generator:
    seed_split(seed)
    tag = sum(ord(c) * 31**i for i, c in enumerate(family)) % (2**31)
    return np.random.default_rng([seed, tag])


# ---------------------------------------------------------------------------
# Family (a): real AIS trajectories replayed
# ---------------------------------------------------------------------------
#: the AIS samples replayed (the two with many manoeuvring vessels at short intervals)
AIS_FILES = ("dk_northsea_20221101_1h_selected.csv", "no_vestland_20220901.csv")
_SPLINE_SIGMA = 3.0  # m, position noise of the reports (quantisation, GNSS)
_SPLINE_Q = 0.01  # m^2/s^3, white-noise acceleration PSD of the prior path


@dataclass(frozen=True)
class AisStretch:
    """A usable stretch of a real track: source file, vessel, start time (s since the Unix
    epoch), start on the spline's clock (s from the segment's first report), duration (s),
    net course change (rad), split, and the splines x(t), y(t) (m, local East/North)."""

    source: str
    mmsi: int
    t0: float
    start: float
    duration: float
    turn: float
    split: str
    sx: BSpline
    sy: BSpline


def _vessel_segments(source: str) -> list[tuple[int, FloatArray, FloatArray]]:
    """Per vessel: time-ordered reports without duplicate times, cut at gaps > 60 s."""
    from seatrack.data import ais_sample
    from seatrack.io.ais import read_ais_csv
    from seatrack.io.ais import to_local
    from seatrack.io.ais import validate_reports

    r = validate_reports(read_ais_csv(ais_sample(source)))
    loc = to_local(r)
    out = []
    for mmsi in np.unique(r.mmsi[r.valid]):
        sel = np.flatnonzero(r.valid & (r.mmsi == mmsi))
        t, p = r.t[sel], loc.enu[sel, :2]
        keep = np.r_[True, np.diff(t) > 0]
        t, p = t[keep], p[keep]
        cuts = np.flatnonzero(np.diff(t) > 60.0) + 1
        for ts, ps in zip(np.split(t, cuts), np.split(p, cuts), strict=True):
            if ts.size >= 100:
                out.append((int(mmsi), ts, ps))
    return out


def _fit_path(t: FloatArray, p: FloatArray) -> tuple[BSpline, BSpline]:
    """Smoothing splines x(t), y(t); reports more than max(15 m, 4 robust sigma) off the
    first fit (frozen positions and catch-up jumps) are dropped and the fit repeated."""
    lam = _SPLINE_SIGMA**2 / _SPLINE_Q
    for _ in range(3):
        sx = make_smoothing_spline(t, p[:, 0], lam=lam)
        sy = make_smoothing_spline(t, p[:, 1], lam=lam)
        res = np.hypot(sx(t) - p[:, 0], sy(t) - p[:, 1])
        good = res < max(15.0, 4.0 * 1.4826 * float(np.median(res)))
        if good.all():
            break
        t, p = t[good], p[good]
    return sx, sy


@lru_cache(maxsize=4)
def ais_stretches(duration: float = 1200.0, step: float = 300.0) -> tuple[AisStretch, ...]:
    """The usable stretches of the bundled AIS samples (cached).

    Windows of ``duration`` s every ``step`` s along each gap-free vessel segment, kept
    when the spline speed stays >= 1.5 m/s, the course turns through >= 45 deg, the
    acceleration stays <= 1 m/s^2 and the turn rate <= 5 deg/s. Vessels are sorted and
    alternately assigned to the tuning and the headline split.
    """
    found: list[tuple[str, int, float, float, float, BSpline, BSpline]] = []
    for source in AIS_FILES:
        for mmsi, t, p in _vessel_segments(source):
            sx, sy = _fit_path(t - t[0], p)
            for s in np.arange(0.0, t[-1] - t[0] - duration + 1e-9, step):
                g = np.arange(s, s + duration + 1e-9, 2.0)
                vx, vy = sx.derivative()(g), sy.derivative()(g)
                ax, ay = sx.derivative(2)(g), sy.derivative(2)(g)
                spd = np.hypot(vx, vy)
                if spd.min() < 1.5 or np.hypot(ax, ay).max() > 1.0:
                    continue
                crs = np.unwrap(np.arctan2(vx, vy))
                w = np.abs(np.diff(crs)) / 2.0
                turn = float(crs.max() - crs.min())
                if turn < 45 * DEG or w.max() > 5 * DEG:
                    continue
                found.append((source, mmsi, float(t[0] + s), float(s), turn, sx, sy))
    vessels = sorted({(f[0], f[1]) for f in found})
    split = {v: ("tuning" if i % 2 == 0 else "headline") for i, v in enumerate(vessels)}
    return tuple(
        AisStretch(src, m, t0, start, duration, turn, split[(src, m)], sx, sy)
        for src, m, t0, start, turn, sx, sy in found
    )


def _stretch_trajectory(st: AisStretch, dt: float) -> Trajectory:
    """Sample a stretch every ``dt`` s (times from 0) as a Trajectory."""
    t = np.arange(0.0, st.duration + 1e-9, dt)
    tt = st.start + t
    sx, sy = st.sx, st.sy
    pos = np.zeros((t.size, 3))
    vel = np.zeros((t.size, 3))
    acc = np.zeros((t.size, 3))
    pos[:, 0], pos[:, 1] = sx(tt), sy(tt)
    vel[:, 0], vel[:, 1] = sx.derivative()(tt), sy.derivative()(tt)
    acc[:, 0], acc[:, 1] = sx.derivative(2)(tt), sy.derivative(2)(tt)
    crs, spd = course_speed(vel[:, 0], vel[:, 1])
    w = (vel[:, 1] * acc[:, 0] - vel[:, 0] * acc[:, 1]) / np.maximum(spd, 1e-9) ** 2
    return Trajectory(t, pos, vel, acc, np.asarray(wrap_2pi(crs)), np.asarray(spd), w)


def ais_replay(
    seed: int, sensor: SensorSpec = COASTAL_RADAR, epsilon: float = 0.0, duration: float = 1200.0
) -> Scenario:
    """A real vessel track (a stretch of the seed's split) seen by ``sensor``.

    A radar stands 3-10 km from the stretch's mid-point; a sonar (own ship at rest)
    0.5-1.5 km from it, so that ranges stay within active-sonar reach. Manoeuvring scans:
    ``|turn rate| > 0.2 deg/s`` or ``|along-track acceleration| > 0.02 m/s^2``.
    """
    rng = _rng(seed, "ais")
    split = seed_split(seed)
    pool = [s for s in ais_stretches(duration) if s.split == split]
    st = pool[int(rng.integers(len(pool)))]
    traj = _stretch_trajectory(st, sensor.dt)
    mid = traj.pos[traj.t.size // 2, :2]
    lo, hi = (0.5e3, 1.5e3) if "sonar" in sensor.name else (3e3, 10e3)
    ang = rng.uniform(0, 2 * np.pi)
    where = mid + rng.uniform(lo, hi) * np.array([np.sin(ang), np.cos(ang)])
    along = np.einsum("ij,ij->i", traj.acc[:, :2], traj.vel[:, :2]) / np.maximum(traj.speed, 1e-9)
    man = (np.abs(traj.turn_rate) > 0.2 * DEG) | (np.abs(along) > 0.02)
    return _observe("ais", "ship", seed, traj, where, sensor, epsilon, man, rng)


# ---------------------------------------------------------------------------
# Family (b): random manoeuvres per target class
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class ManoeuvreSpec:
    """Random-manoeuvre family of one target class.

    Attributes
    ----------
    target : class name; sensor : the sensor that watches it.
    duration : s; speed : (lo, hi) m/s initial speed.
    turn_rate : (lo, hi) rad/s of the turns -- or, when ``turn_g`` is set, the turn rate
        is ``g G0 / speed`` with ``g`` uniform in ``turn_g``.
    turn_angle : (lo, hi) rad (random sign); straight : (lo, hi) s straight legs.
    speed_change : probability that a straight leg is a speed change; accel : m/s^2 of it;
        speed_range : speeds a change may go to.
    start_range : (lo, hi) m from the sensor at the start; observer_speed : m/s of the
        sensor platform (straight, random course; 0 = fixed).
    """

    target: str
    sensor: SensorSpec
    duration: float
    speed: tuple[float, float]
    turn_rate: tuple[float, float]
    turn_angle: tuple[float, float]
    straight: tuple[float, float]
    speed_change: float
    accel: float
    speed_range: tuple[float, float]
    start_range: tuple[float, float]
    observer_speed: float = 0.0
    turn_g: tuple[float, float] | None = None


#: the class scenarios (sources of the class figures: seatrack.models.targets)
MANOEUVRE_SPECS: dict[str, ManoeuvreSpec] = {
    "ship": ManoeuvreSpec(
        "ship", COASTAL_RADAR, 1200.0, (4.0, 9.0), (0.3 * DEG, 1.5 * DEG), (30 * DEG, 120 * DEG),
        (120.0, 300.0), 0.25, 0.05, (3.0, 10.0), (3e3, 10e3),
    ),
    "submarine": ManoeuvreSpec(
        "submarine", ACTIVE_SONAR, 1200.0, (3.0, 7.0), (0.5 * DEG, 1.0 * DEG),
        (30 * DEG, 120 * DEG), (120.0, 300.0), 0.25, 0.03, (2.5, 8.0), (0.8e3, 1.5e3), 2.0,
    ),
    "aircraft": ManoeuvreSpec(
        "aircraft", ATC_RADAR, 600.0, (90.0, 150.0), (1.5 * DEG, 3.0 * DEG),
        (45 * DEG, 180 * DEG), (40.0, 120.0), 0.2, 1.0, (90.0, 150.0), (20e3, 60e3),
    ),
    "fighter": ManoeuvreSpec(
        "fighter", FIGHTER_RADAR, 300.0, (200.0, 300.0), (0.0, 0.0), (60 * DEG, 180 * DEG),
        (15.0, 40.0), 0.2, 10.0, (200.0, 300.0), (20e3, 50e3), 0.0, (3.0, 6.0),
    ),
}  # fmt: skip


def _legs(spec: ManoeuvreSpec, v0: float, rng: np.random.Generator) -> tuple[list[Leg], float]:
    legs: list[Leg] = []
    t, v = 0.0, v0
    while t < spec.duration:
        straight = float(rng.uniform(*spec.straight))
        if rng.random() < spec.speed_change:
            v1 = float(rng.uniform(*spec.speed_range))
            if abs(v1 - v) > 0.5:
                leg = Leg.speed_change(v, v1, spec.accel)
                legs.append(leg)
                t, v = t + leg.duration, v1
        legs.append(Leg.straight(straight))
        t += straight
        angle = float(rng.uniform(*spec.turn_angle)) * float(rng.choice([-1.0, 1.0]))
        if spec.turn_g is not None:
            rate = float(rng.uniform(*spec.turn_g)) * G0 / v
        else:
            rate = float(rng.uniform(*spec.turn_rate))
        legs.append(Leg.turn(angle, rate))
        t += legs[-1].duration
    return legs, v


def _observer(spec: ManoeuvreSpec, t: FloatArray, rng: np.random.Generator) -> Trajectory:
    crs = float(rng.uniform(0, 2 * np.pi))
    legs = [Leg.straight(float(t[-1]) + 1.0)]
    return trajectory(np.zeros(2), crs, spec.observer_speed, legs, times=t)


def random_manoeuvres(target: str, seed: int, epsilon: float = 0.0) -> Scenario:
    """Random legs, coordinated turns and speed changes of a ``target`` class
    (:data:`MANOEUVRE_SPECS`), seen by the class's sensor. Manoeuvring scans: inside a
    turn or a speed change."""
    spec = MANOEUVRE_SPECS.get(target)
    if spec is None:
        raise ValueError(f"no manoeuvre family for {target!r}; choose {', '.join(MANOEUVRE_SPECS)}")
    rng = _rng(seed, "manoeuvres-" + target)
    v0 = float(rng.uniform(*spec.speed))
    legs, _ = _legs(spec, v0, rng)
    t = np.arange(0.0, spec.duration + 1e-9, spec.sensor.dt)
    r0 = float(rng.uniform(*spec.start_range))
    b0 = float(rng.uniform(0, 2 * np.pi))
    start = r0 * np.array([np.sin(b0), np.cos(b0)])
    traj = trajectory(start, float(rng.uniform(0, 2 * np.pi)), v0, legs, times=t)
    obs = _observer(spec, t, rng)
    along = np.einsum("ij,ij->i", traj.acc[:, :2], traj.vel[:, :2]) / np.maximum(traj.speed, 1e-9)
    man = (traj.turn_rate != 0.0) | (np.abs(along) > 1e-9)
    return _observe("manoeuvres", target, seed, traj, obs, spec.sensor, epsilon, man, rng)


# ---------------------------------------------------------------------------
# Family (c): weaving (sinusoidal turn rate)
# ---------------------------------------------------------------------------
def weaving(target: str, seed: int, epsilon: float = 0.0) -> Scenario:
    """A zig-zag of a ``target`` class: turn rate ``w(t) = w_a sin(2 pi t / P + phi)`` with
    ``w_a`` the class's typical turn rate and heading excursions ``w_a P / (2 pi)`` of
    20-45 deg, after a straight first minute; the class's sensor and scenario geometry
    (:data:`MANOEUVRE_SPECS`). The path is built from legs of constant turn rate, each the
    mean of the sinusoid over the leg (<= P/40 long), so the truth is exact for that path.
    Every scan after the first minute counts as manoeuvring."""
    spec = MANOEUVRE_SPECS.get(target)
    if spec is None:
        raise ValueError(f"no weaving family for {target!r}; choose {', '.join(MANOEUVRE_SPECS)}")
    tc: TargetClass = target_class(target)
    rng = _rng(seed, "weaving-" + target)
    v0 = float(rng.uniform(*spec.speed))
    wa = tc.turn_rate_typical
    if target == "fighter":  # typical g at this speed
        wa = tc.accel_typical / v0
    P = 2 * np.pi * float(rng.uniform(20 * DEG, 45 * DEG)) / wa
    phi = float(rng.uniform(0, 2 * np.pi))
    t0 = 60.0
    h = min(P / 40.0, spec.sensor.dt / 2.0)
    edges = np.arange(t0, spec.duration + h, h)
    k = 2 * np.pi / P
    # mean of w_a sin(k t + phi) over [a, b]
    mean_w = wa * (np.cos(k * edges[:-1] + phi) - np.cos(k * edges[1:] + phi)) / (k * h)
    legs = [Leg.straight(t0)] + [Leg(h, turn_rate=float(w)) for w in mean_w]
    t = np.arange(0.0, spec.duration + 1e-9, spec.sensor.dt)
    r0 = float(rng.uniform(*spec.start_range))
    b0 = float(rng.uniform(0, 2 * np.pi))
    traj = trajectory(
        r0 * np.array([np.sin(b0), np.cos(b0)]), float(rng.uniform(0, 2 * np.pi)), v0, legs,
        times=t,
    )  # fmt: skip
    obs = _observer(spec, t, rng)
    return _observe("weaving", target, seed, traj, obs, spec.sensor, epsilon, t >= t0, rng)


def labelled_runs(scenarios: Sequence[Scenario]) -> Plots:
    """The plots of several runs as ONE labelled set (track ``r<i>`` = run ``i``), as
    ``seatrack track`` reads a file of many tracks: every run goes through a method in
    the same batch."""
    parts = [s.plots for s in scenarios]

    def cat(name: str) -> Any:
        vals = [getattr(p, name) for p in parts]
        return None if vals[0] is None else np.concatenate(vals)

    labels = np.concatenate([np.full(len(p), f"r{i}") for i, p in enumerate(parts)])
    fields = ("t", "range", "azimuth", "elevation", "range_rate", "sensor", "sensor_vel")
    return Plots(**{f: cat(f) for f in fields}, track=labels)
