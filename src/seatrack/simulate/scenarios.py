"""Scenarios in human-editable TOML files: own-ship, targets, sensors, Monte-Carlo set-up.

A scenario file is read with the standard-library :mod:`tomllib` and validated completely
by :func:`load_scenario`; any problem raises :class:`~seatrack.io.table.InputError` naming
the file, the key path (e.g. ``targets[1].legs[2].turn_rate_dps``) and what is wrong.
Units are explicit in the key names (``_m``, ``_deg``, ``_kn``, ``_mps``, ``_dps``, ``_s``)
and converted to SI / radians here, at the edge. Unknown keys are errors (they are
usually typos).

File layout (see ``seatrack/data/scenarios/*.toml`` for complete examples)::

    name = "demo"
    duration_s = 300.0          # simulated time span
    dt_s = 1.0                  # truth sample interval (default: shortest scan period)
    seed = 1                    # master seed
    runs = 100                  # Monte-Carlo runs for `seatrack evaluate`
    origin = { lat_deg = 54.3, lon_deg = 10.1 }   # only needed for lat/lon positions

    [ownship]                   # optional; default: at rest at the origin
    position_m = [0.0, 0.0]     # or lat_deg = ..., lon_deg = ... (, alt_m)
    course_deg = 0.0
    speed_kn = 10.0             # or speed_mps
    legs = [ { type = "turn", turn_rate_dps = 1.0, angle_deg = 90.0 } ]

    [[targets]]
    name = "T1"
    position_m = [8000.0, 6000.0]
    course_deg = 250.0
    speed_kn = 20.0
    [[targets.legs]]
    type = "straight"           # straight | turn | accelerate | speed_change | climb
    duration_s = 60.0

    [[sensors]]
    name = "radar"
    type = "radar2d"            # passive_sonar | active_sonar | radar2d | radar3d
    components = ["azimuth", "range", "range_rate"]    # default by type
    sigma = { azimuth_deg = 0.3, range_m = 20.0, range_rate_mps = 1.0 }
    epsilon = 0.0               # probability of an anomalous (outlier) component
    outlier_scale = 10.0        # variance multiplier, or per component { range_m = 10 }
    p_detect = 1.0
    clutter_density = 0.0       # expected false plots per scan
    clutter_range_m = [100.0, 20000.0]
    scan_period_s = 2.0
    platform = "ownship"        # or position_m = [x, y(, z)] for a fixed sensor

    [evaluate.ekf]              # optional: parameters of a track method in `seatrack evaluate`
    q = 2.0                     # (the sensor's sigmas are passed to every method anyway)

Leg keys (a positive turn is clockwise, to starboard):

* ``straight``: ``duration_s`` [, ``climb_rate_mps``]
* ``turn``: two of ``turn_rate_dps`` / ``angle_deg`` / ``duration_s``, or ``g`` with
  ``angle_deg`` (lateral acceleration in units of g at the speed at that point)
* ``accelerate``: ``duration_s``, ``accel_mps2`` (signed)
* ``speed_change``: ``to_speed_kn`` or ``to_speed_mps``, ``accel_mps2`` (magnitude)
* ``climb``: ``duration_s``, ``climb_rate_mps``
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.geometry import KNOT_MPS
from seatrack.geometry import geodetic_to_enu
from seatrack.io.table import MAX_TIME_S
from seatrack.io.table import MIN_SIGMA
from seatrack.io.table import InputError
from seatrack.simulate.multitarget import TargetPopulation
from seatrack.simulate.multitarget import born_targets
from seatrack.simulate.multitarget import parse_multitarget
from seatrack.simulate.multitarget import work_samples
from seatrack.simulate.sensors import Measurements
from seatrack.simulate.sensors import NoiseModel
from seatrack.simulate.sensors import observe
from seatrack.simulate.sensors import uniform_clutter
from seatrack.simulate.toml_reader import TomlReader
from seatrack.simulate.toml_reader import describe
from seatrack.simulate.toml_reader import join_key
from seatrack.simulate.trajectories import Leg
from seatrack.simulate.trajectories import Trajectory
from seatrack.simulate.trajectories import trajectory

FloatArray = NDArray[np.float64]

__all__ = [
    "SENSOR_TYPES",
    "Platform",
    "SensorConfig",
    "Scenario",
    "SensorData",
    "SimulationResult",
    "load_scenario",
    "bundled_scenario",
    "bundled_scenarios",
    "parse_scenario",
    "resolve_scenario",
]

#: sensor type -> (allowed components, default components)
SENSOR_TYPES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "passive_sonar": (("azimuth",), ("azimuth",)),
    "active_sonar": (("azimuth", "range", "range_rate"), ("azimuth", "range")),
    "radar2d": (("azimuth", "range", "range_rate"), ("azimuth", "range")),
    "radar3d": (
        ("azimuth", "range", "elevation", "range_rate"),
        ("azimuth", "range", "elevation"),
    ),
}

#: component -> (sigma key in the file, factor to SI)
_SIGMA_KEYS = {
    "azimuth": ("azimuth_deg", math.pi / 180.0),
    "range": ("range_m", 1.0),
    "elevation": ("elevation_deg", math.pi / 180.0),
    "range_rate": ("range_rate_mps", 1.0),
}
#: most samples on one time grid (truth, or one sensor's scans) in a simulated run
MAX_SAMPLES = 1_000_000
#: most samples of all platforms on all grids in a simulated run (bounds memory: ~1 GB)
MAX_POINTS = 5_000_000
#: most Monte-Carlo runs a scenario may ask for
MAX_RUNS = 100_000
#: largest outlier variance multiplier
MAX_OUTLIER_SCALE = 1e6
#: canonical order of components in measurements
_ORDER = ("azimuth", "range", "elevation", "range_rate")


@dataclass(frozen=True)
class Platform:
    """A moving platform (own-ship or target): start, initial course/speed and legs (SI)."""

    name: str
    start: FloatArray
    course: float
    speed: float
    legs: tuple[Leg, ...] = ()

    def trajectory(self, times: FloatArray) -> Trajectory:
        """Truth sampled at ``times`` (s)."""
        return trajectory(self.start, self.course, self.speed, self.legs, times=times)


@dataclass(frozen=True)
class SensorConfig:
    """One sensor (SI units, radians).

    Attributes
    ----------
    name, type : str
    components : tuple of str -- measured components in canonical order
    sigma : tuple of float -- one per component (rad, m, m/s)
    epsilon, outlier_scale : contamination (see :class:`~seatrack.simulate.NoiseModel`)
    p_detect : float
    clutter_density : float -- expected false plots per scan
    clutter_range : (lo, hi) m
    scan_period : float, s
    position : (3,) m fixed position, or None when mounted on the own-ship
    """

    name: str
    type: str
    components: tuple[str, ...]
    sigma: tuple[float, ...]
    epsilon: float = 0.0
    outlier_scale: tuple[float, ...] = (1.0,)
    p_detect: float = 1.0
    clutter_density: float = 0.0
    clutter_range: tuple[float, float] = (0.0, 0.0)
    scan_period: float = 1.0
    position: FloatArray | None = None

    @property
    def noise(self) -> NoiseModel:
        return NoiseModel(self.sigma, self.epsilon, self.outlier_scale)

    @property
    def is_passive(self) -> bool:
        return self.type == "passive_sonar"

    def scan_times(self, duration: float) -> FloatArray:
        """Scan times ``0, T, 2T, ... <= duration``."""
        n = int(math.floor(duration / self.scan_period + 1e-9)) + 1
        return self.scan_period * np.arange(n, dtype=np.float64)


@dataclass(frozen=True)
class SensorData:
    """What one sensor produced in one simulated run.

    Attributes
    ----------
    sensor : SensorConfig
    t : (N,) s scan times
    observer : Trajectory or None -- sensor platform at the scan times (own-ship), None if fixed
    truth : list of Trajectory -- each target at the scan times
    measurements : list of Measurements -- one per target (missed scans are NaN rows)
    clutter_t, clutter_range, clutter_azimuth : false plots (s, m, rad)
    clutter_sensor : (K, 3) sensor position at each false plot
    """

    sensor: SensorConfig
    t: FloatArray
    observer: Trajectory | None
    truth: list[Trajectory]
    measurements: list[Measurements]
    clutter_t: FloatArray
    clutter_range: FloatArray
    clutter_azimuth: FloatArray
    clutter_sensor: FloatArray


@dataclass(frozen=True)
class SimulationResult:
    """One simulated run: truth at ``t`` and every sensor's data."""

    scenario: Scenario
    t: FloatArray
    ownship: Trajectory
    targets: list[Trajectory]
    sensors: list[SensorData]

    def sensor(self, name: str) -> SensorData:
        for s in self.sensors:
            if s.sensor.name == name:
                return s
        raise KeyError(f"no sensor named {name!r}; have {[s.sensor.name for s in self.sensors]}")


@dataclass(frozen=True)
class Scenario:
    """A validated scenario (see the module docstring for the file format)."""

    name: str
    duration: float
    dt: float
    ownship: Platform
    targets: tuple[Platform, ...]
    sensors: tuple[SensorConfig, ...]
    seed: int = 0
    runs: int = 100
    description: str = ""
    path: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)
    multitarget: TargetPopulation | None = None  # generated targets (simulate.multitarget)

    @property
    def target_names(self) -> list[str]:
        return [t.name for t in self.targets]

    def simulate(self, rng: np.random.Generator) -> SimulationResult:
        """Simulate truth and measurements of every sensor, drawing only from ``rng``.

        Truth is sampled every ``dt`` from 0 to ``duration``; each sensor samples every
        target at its own scan times with :func:`seatrack.simulate.observe` and adds
        :func:`seatrack.simulate.uniform_clutter` false plots (active sensors only).
        """
        t = self.dt * np.arange(
            int(math.floor(self.duration / self.dt + 1e-9)) + 1, dtype=np.float64
        )
        own = self.ownship.trajectory(t)
        targets = [p.trajectory(t) for p in self.targets]
        data = []
        for s in self.sensors:
            ts = s.scan_times(self.duration)
            truth = [p.trajectory(ts) for p in self.targets]
            observer: Trajectory | FloatArray
            if s.position is None:
                obs_traj: Trajectory | None = self.ownship.trajectory(ts)
                assert obs_traj is not None
                observer = obs_traj
            else:
                obs_traj = None
                observer = s.position
            meas = [observe(tr, observer, s.components, s.noise, rng, s.p_detect) for tr in truth]
            if s.clutter_density > 0 and not s.is_passive:
                ct, cr, ca = uniform_clutter(
                    ts, s.clutter_density, s.clutter_range, (0.0, 2 * math.pi), rng
                )
                idx = np.searchsorted(ts, ct)
                sensor_pos = meas[0].sensor_pos if meas else np.zeros((ts.size, 3))
                cs = sensor_pos[idx] if ct.size else np.zeros((0, 3))
            else:
                ct = cr = ca = np.zeros(0)
                cs = np.zeros((0, 3))
            data.append(SensorData(s, ts, obs_traj, truth, meas, ct, cr, ca, cs))
        return SimulationResult(self, t, own, targets, data)


# ---------------------------------------------------------------------------
# Loading and validation
# ---------------------------------------------------------------------------
_TOP_KEYS = (
    "name",
    "description",
    "duration_s",
    "dt_s",
    "seed",
    "runs",
    "origin",
    "ownship",
    "targets",
    "sensors",
    "evaluate",
    "multitarget",
)
_PLATFORM_KEYS = (
    "name",
    "position_m",
    "lat_deg",
    "lon_deg",
    "alt_m",
    "course_deg",
    "speed_kn",
    "speed_mps",
    "legs",
)
_LEG_KEYS = {
    "straight": ("type", "duration_s", "climb_rate_mps"),
    "turn": ("type", "duration_s", "turn_rate_dps", "angle_deg", "g", "climb_rate_mps"),
    "accelerate": ("type", "duration_s", "accel_mps2", "climb_rate_mps"),
    "speed_change": ("type", "to_speed_kn", "to_speed_mps", "accel_mps2", "climb_rate_mps"),
    "climb": ("type", "duration_s", "climb_rate_mps"),
}
_SENSOR_KEYS = (
    "name",
    "type",
    "components",
    "sigma",
    "epsilon",
    "outlier_scale",
    "p_detect",
    "clutter_density",
    "clutter_range_m",
    "scan_period_s",
    "platform",
    "position_m",
)


def _speed(
    r: TomlReader, tab: Mapping[str, Any], prefix: str, kn: str, mps: str, required: bool
) -> float | None:
    if kn in tab and mps in tab:
        raise r.error(join_key(prefix, kn), f"give either {kn} or {mps}, not both")
    if kn in tab:
        return r.req(tab, prefix, kn, minimum=0.0) * KNOT_MPS
    if mps in tab:
        return r.req(tab, prefix, mps, minimum=0.0)
    if required:
        raise r.error(join_key(prefix, kn), f"missing required key (speed as {kn} or {mps})")
    return None


def _leg(r: TomlReader, raw: Any, prefix: str, speed: float) -> tuple[Leg, float]:
    """Parse one leg; returns it and the speed at its end."""
    tab = r.table(raw, prefix)
    kind = r.string(tab, prefix, "type")
    if kind not in _LEG_KEYS:
        raise r.error(
            join_key(prefix, "type"),
            f"unknown leg type {kind!r}; use one of {', '.join(_LEG_KEYS)}",
        )
    r.check_keys(tab, prefix, _LEG_KEYS[kind])
    climb = r.number(tab, prefix, "climb_rate_mps", default=0.0)
    assert climb is not None
    deg = math.pi / 180.0
    if kind == "straight":
        leg = Leg(r.req(tab, prefix, "duration_s", positive=True), climb_rate=climb)
    elif kind == "climb":
        leg = Leg(
            r.req(tab, prefix, "duration_s", positive=True),
            climb_rate=r.req(tab, prefix, "climb_rate_mps"),
        )
    elif kind == "accelerate":
        leg = Leg(
            r.req(tab, prefix, "duration_s", positive=True),
            accel=r.req(tab, prefix, "accel_mps2"),
            climb_rate=climb,
        )
    elif kind == "speed_change":
        to = _speed(r, tab, prefix, "to_speed_kn", "to_speed_mps", required=True)
        assert to is not None
        acc = r.req(tab, prefix, "accel_mps2", positive=True)
        if abs(to - speed) < 1e-12:
            raise r.error(
                prefix, f"speed_change to the current speed ({speed:.3f} m/s) does nothing"
            )
        leg = Leg.speed_change(speed, to, acc)
        leg = Leg(leg.duration, accel=leg.accel, climb_rate=climb)
    else:  # turn
        given = [k for k in ("turn_rate_dps", "angle_deg", "duration_s", "g") if k in tab]
        if "g" in tab:
            if set(given) != {"g", "angle_deg"}:
                raise r.error(join_key(prefix, "g"), "a g-load turn needs exactly g and angle_deg")
            g = r.req(tab, prefix, "g", positive=True, maximum=100.0)
            if speed <= 0:
                raise r.error(join_key(prefix, "g"), "a g-load turn needs a non-zero speed")
            angle = r.req(tab, prefix, "angle_deg") * deg
            if angle == 0:
                raise r.error(join_key(prefix, "angle_deg"), "turn angle must be non-zero")
            leg = Leg.turn_g(angle, g, speed)
        elif len(given) != 2:
            raise r.error(
                prefix,
                "a turn needs exactly two of turn_rate_dps, angle_deg, duration_s "
                f"(or g with angle_deg); got {', '.join(given) or 'none'}",
            )
        elif "turn_rate_dps" in tab and "duration_s" in tab:
            leg = Leg(
                r.req(tab, prefix, "duration_s", positive=True),
                turn_rate=r.req(tab, prefix, "turn_rate_dps") * deg,
            )
        elif "turn_rate_dps" in tab:
            rate = r.req(tab, prefix, "turn_rate_dps") * deg
            angle = r.req(tab, prefix, "angle_deg") * deg
            if rate == 0 or angle == 0:
                raise r.error(prefix, "turn_rate_dps and angle_deg must be non-zero")
            leg = Leg.turn(angle, rate)
        else:
            dur = r.req(tab, prefix, "duration_s", positive=True)
            leg = Leg(dur, turn_rate=r.req(tab, prefix, "angle_deg") * deg / dur)
        leg = Leg(leg.duration, turn_rate=leg.turn_rate, climb_rate=climb)
    if leg.duration > MAX_TIME_S:
        raise r.error(prefix, f"this leg lasts {leg.duration:.3g} s; at most {MAX_TIME_S:g} s")
    end = speed + leg.accel * leg.duration
    if end < -1e-9:
        raise r.error(prefix, f"this leg makes the speed negative ({end:.3f} m/s)")
    return leg, max(end, 0.0)


def _position(
    r: TomlReader, tab: Mapping[str, Any], prefix: str, origin: tuple[float, float, float] | None
) -> FloatArray:
    has_xy = "position_m" in tab
    has_ll = "lat_deg" in tab or "lon_deg" in tab
    if has_xy and has_ll:
        raise r.error(
            join_key(prefix, "position_m"), "give either position_m or lat_deg/lon_deg, not both"
        )
    if has_ll:
        lat = r.req(tab, prefix, "lat_deg", minimum=-90.0, maximum=90.0)
        lon = r.req(tab, prefix, "lon_deg", minimum=-180.0, maximum=360.0)
        alt = r.number(tab, prefix, "alt_m", default=0.0)
        if origin is None:
            raise r.error(
                join_key(prefix, "lat_deg"),
                "lat/lon positions need a top-level origin = { lat_deg, lon_deg }",
            )
        return np.asarray(geodetic_to_enu(lat, lon, alt or 0.0, *origin), dtype=np.float64)
    if "alt_m" in tab:
        raise r.error(
            join_key(prefix, "alt_m"), "alt_m goes with lat_deg/lon_deg; use a 3-element position_m"
        )
    if has_xy:
        p = r.vector(tab, prefix, "position_m", (2, 3))
        return np.concatenate([p, np.zeros(3 - p.size)])
    raise r.error(join_key(prefix, "position_m"), "missing required key (or lat_deg/lon_deg)")


def _platform(
    r: TomlReader,
    raw: Any,
    prefix: str,
    default_name: str,
    origin: tuple[float, float, float] | None,
) -> Platform:
    tab = r.table(raw, prefix)
    r.check_keys(tab, prefix, _PLATFORM_KEYS)
    name = r.string(tab, prefix, "name", default=default_name)
    start = _position(r, tab, prefix, origin)
    course = r.req(tab, prefix, "course_deg") * math.pi / 180.0
    speed = _speed(r, tab, prefix, "speed_kn", "speed_mps", required=True)
    assert speed is not None
    legs_raw = tab.get("legs", [])
    if not isinstance(legs_raw, list):
        raise r.error(
            join_key(prefix, "legs"), f"expected a list of leg tables, got {describe(legs_raw)}"
        )
    legs = []
    v = speed
    for i, lr in enumerate(legs_raw):
        leg, v = _leg(r, lr, f"{join_key(prefix, 'legs')}[{i}]", v)
        legs.append(leg)
    return Platform(name, start, course, speed, tuple(legs))


def _sensor(r: TomlReader, raw: Any, prefix: str, index: int, duration: float) -> SensorConfig:
    tab = r.table(raw, prefix)
    r.check_keys(tab, prefix, _SENSOR_KEYS)
    name = r.string(tab, prefix, "name", default=f"sensor{index + 1}")
    kind = r.string(tab, prefix, "type")
    if kind not in SENSOR_TYPES:
        raise r.error(
            join_key(prefix, "type"),
            f"unknown sensor type {kind!r}; use one of {', '.join(SENSOR_TYPES)}",
        )
    allowed, default = SENSOR_TYPES[kind]
    comps: tuple[str, ...] = default
    if "components" in tab:
        raw_c = tab["components"]
        kp = join_key(prefix, "components")
        if not isinstance(raw_c, list) or not raw_c or not all(isinstance(c, str) for c in raw_c):
            raise r.error(kp, f"expected a non-empty list of strings, got {describe(raw_c)}")
        names = ["azimuth" if c == "bearing" else c for c in raw_c]
        for c in names:
            if c not in allowed:
                raise r.error(
                    kp,
                    f"component {c!r} is not measured by a {kind}; allowed: {', '.join(allowed)}",
                )
        if len(set(names)) != len(names):
            raise r.error(kp, "duplicate component")
        for c in default:
            if c not in names:
                raise r.error(kp, f"a {kind} must measure {', '.join(default)}")
        comps = tuple(c for c in _ORDER if c in names)
    sig_tab = r.table(tab.get("sigma"), join_key(prefix, "sigma")) if "sigma" in tab else None
    if sig_tab is None:
        raise r.error(
            join_key(prefix, "sigma"), "missing required key (a table of noise standard deviations)"
        )
    sp = join_key(prefix, "sigma")
    r.check_keys(sig_tab, sp, [_SIGMA_KEYS[c][0] for c in comps])
    sigma = tuple(
        r.req(sig_tab, sp, _SIGMA_KEYS[c][0], positive=True, minimum=MIN_SIGMA) * _SIGMA_KEYS[c][1]
        for c in comps
    )
    eps = r.number(tab, prefix, "epsilon", default=0.0, minimum=0.0, maximum=1.0)
    scale_raw = tab.get("outlier_scale", 1.0)
    op = join_key(prefix, "outlier_scale")
    if isinstance(scale_raw, dict):
        r.check_keys(scale_raw, op, [_SIGMA_KEYS[c][0] for c in comps])
        scale = tuple(
            r.number(
                scale_raw,
                op,
                _SIGMA_KEYS[c][0],
                default=1.0,
                minimum=1.0,
                maximum=MAX_OUTLIER_SCALE,
            )
            or 1.0
            for c in comps
        )
    else:
        s = r.number(
            tab, prefix, "outlier_scale", default=1.0, minimum=1.0, maximum=MAX_OUTLIER_SCALE
        )
        scale = (s or 1.0,) * len(comps)
    p_detect = r.number(tab, prefix, "p_detect", default=1.0, minimum=0.0, maximum=1.0)
    clutter = r.number(tab, prefix, "clutter_density", default=0.0, minimum=0.0)
    assert eps is not None and p_detect is not None and clutter is not None
    if kind == "passive_sonar" and clutter > 0:
        raise r.error(
            join_key(prefix, "clutter_density"), "clutter is simulated for active sensors only"
        )
    crange = (0.0, 0.0)
    if "clutter_range_m" in tab:
        cr = r.vector(tab, prefix, "clutter_range_m", (2,))
        if not 0 <= cr[0] < cr[1]:
            raise r.error(
                join_key(prefix, "clutter_range_m"), f"need 0 <= min < max, got {cr.tolist()}"
            )
        crange = (float(cr[0]), float(cr[1]))
    elif clutter > 0:
        raise r.error(join_key(prefix, "clutter_range_m"), "required when clutter_density > 0")
    period = r.req(tab, prefix, "scan_period_s", positive=True)
    if period > duration:
        raise r.error(
            join_key(prefix, "scan_period_s"), f"longer than the scenario duration ({duration:g} s)"
        )
    position = None
    platform = r.string(
        tab, prefix, "platform", default="ownship" if "position_m" not in tab else "fixed"
    )
    if platform not in ("ownship", "fixed"):
        raise r.error(
            join_key(prefix, "platform"), f"must be 'ownship' or 'fixed', got {platform!r}"
        )
    if platform == "fixed":
        if "position_m" not in tab:
            raise r.error(join_key(prefix, "position_m"), "a fixed sensor needs position_m")
        p = r.vector(tab, prefix, "position_m", (2, 3))
        position = np.concatenate([p, np.zeros(3 - p.size)])
    elif "position_m" in tab:
        raise r.error(join_key(prefix, "position_m"), "an own-ship sensor has no position_m")
    return SensorConfig(
        name, kind, comps, sigma, eps, scale, p_detect, clutter, crange, period, position
    )


def _list_of_tables(r: TomlReader, doc: Mapping[str, Any], key: str, required: bool) -> list[Any]:
    if key not in doc:
        if required:
            raise r.error(key, f"missing required key (at least one [[{key}]] table)")
        return []
    v = doc[key]
    if not isinstance(v, list) or (required and not v):
        raise r.error(key, f"expected a non-empty array of tables [[{key}]], got {describe(v)}")
    return v


def parse_scenario(doc: Mapping[str, Any], path: str = "<scenario>") -> Scenario:
    """Validate a parsed TOML document (see :func:`load_scenario`)."""
    r = TomlReader(path)
    r.check_keys(doc, "", _TOP_KEYS)
    name = r.string(doc, "", "name", default=Path(path).stem)
    description = r.string(doc, "", "description", default="")
    duration = r.req(doc, "", "duration_s", positive=True)
    seed = r.integer(doc, "", "seed", 0, 0)
    runs = r.integer(doc, "", "runs", 100, 1, MAX_RUNS)
    origin = None
    if "origin" in doc:
        ot = r.table(doc["origin"], "origin")
        r.check_keys(ot, "origin", ("lat_deg", "lon_deg", "alt_m"))
        origin = (
            r.req(ot, "origin", "lat_deg", minimum=-90.0, maximum=90.0),
            r.req(ot, "origin", "lon_deg", minimum=-180.0, maximum=360.0),
            r.number(ot, "origin", "alt_m", default=0.0) or 0.0,
        )
    if "ownship" in doc:
        own = _platform(r, doc["ownship"], "ownship", "ownship", origin)
    else:
        own = Platform("ownship", np.zeros(3), 0.0, 0.0)
    targets = tuple(
        _platform(r, t, f"targets[{i}]", f"T{i + 1}", origin)
        for i, t in enumerate(_list_of_tables(r, doc, "targets", True))
    )
    names = [t.name for t in targets]
    for i, n in enumerate(names):
        if names.index(n) != i:
            raise r.error(f"targets[{i}].name", f"duplicate target name {n!r}")
    sensors = tuple(
        _sensor(r, s, f"sensors[{i}]", i, duration)
        for i, s in enumerate(_list_of_tables(r, doc, "sensors", True))
    )
    snames = [s.name for s in sensors]
    for i, n in enumerate(snames):
        if snames.index(n) != i:
            raise r.error(f"sensors[{i}].name", f"duplicate sensor name {n!r}")
    dt_default = min(s.scan_period for s in sensors)
    dt = r.number(doc, "", "dt_s", default=dt_default, positive=True)
    assert dt is not None
    if dt > duration:
        raise r.error("dt_s", f"longer than duration_s ({duration:g} s)")
    mt = doc.get("multitarget")
    population = None if mt is None else parse_multitarget(r.table(mt, "multitarget"), path)
    _check_work(r, duration, dt, len(targets), sensors, population)
    extra = _method_tables(r, doc.get("evaluate", {}))
    return Scenario(
        name, duration, dt, own, targets, sensors, seed, runs, description, path, extra, population
    )


def _check_work(
    r: TomlReader, duration: float, dt: float, n_scripted: int, sensors: Sequence[SensorConfig],
    population: TargetPopulation | None = None,
) -> None:  # fmt: skip
    """Bound the memory and time one simulated run takes, before anything is allocated
    (the scripted targets and the expected ones of a ``[multitarget]`` population)."""
    born = born_targets(duration, dt, sensors, population)
    for i, s in enumerate(sensors):
        n = math.floor(duration / s.scan_period + 1e-9) + 1
        kp = f"sensors[{i}]"
        if n > MAX_SAMPLES:
            raise r.error(
                f"{kp}.scan_period_s",
                f"duration_s / scan_period_s gives {n:.3g} scans; at most {MAX_SAMPLES}",
            )
        if s.clutter_density * n > MAX_SAMPLES:
            raise r.error(
                f"{kp}.clutter_density",
                f"{s.clutter_density:g} false plots per scan over {n} scans; at most "
                f"{MAX_SAMPLES} in a run",
            )
    n_truth = math.floor(duration / dt + 1e-9) + 1
    if n_truth > MAX_SAMPLES:
        raise r.error(
            "dt_s", f"duration_s / dt_s gives {n_truth:.3g} truth samples; at most {MAX_SAMPLES}"
        )
    total = work_samples(duration, dt, n_scripted, sensors, population)
    if total > MAX_POINTS:
        raise r.error(
            "multitarget" if born > n_scripted else "duration_s",
            f"{total:.3g} simulated samples in one run (truth and scans of {n_scripted + born:.3g}"
            f" target(s)); at most {MAX_POINTS}: shorten the scenario or lengthen the periods"
            + (", or ask for fewer targets, births or crossings" if born else ""),
        )


def _method_tables(r: TomlReader, raw: Any) -> dict[str, Any]:
    """``[evaluate.<method>]`` tables: known method names; finite numbers, strings, booleans."""
    from seatrack.filters.registry import METHODS

    extra = dict(r.table(raw, "evaluate"))
    for m, tab in extra.items():
        kp = f"evaluate.{m}"
        if m not in METHODS:
            raise r.error(kp, f"no track method {m!r}; known: {', '.join(METHODS)}")
        for k, v in r.table(tab, kp).items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                r.number(tab, kp, k)  # finite and within the unit limit of its name
            elif not isinstance(v, (str, bool)):
                raise r.error(join_key(kp, k), f"expected a number, string or boolean, got "
                              f"{describe(v)}")  # fmt: skip
    return extra


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file.

    Raises
    ------
    InputError
        If the file is missing, is not valid TOML (the message gives the line and column),
        or any key is missing, of the wrong type, out of range or unknown; the message
        names the file and the key path, e.g. ``targets[1].legs[2].turn_rate_dps``.
    """
    p = Path(path)
    try:
        text = p.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{p}: scenario file not found") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read scenario file ({exc.strerror})") from None
    try:
        doc = tomllib.loads(text.decode("utf-8-sig"))
    except UnicodeDecodeError as exc:
        line = text[: exc.start].count(b"\n") + 1
        bad = text[exc.start : exc.start + 1].hex()
        raise InputError(
            f"{p}, line {line}: not UTF-8 text (byte 0x{bad}: {exc.reason}); TOML files are UTF-8"
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{p}: TOML syntax error: {exc}") from None
    try:
        return parse_scenario(doc, str(p))
    except ValueError as exc:  # e.g. from Leg validation
        if isinstance(exc, InputError):
            raise
        raise InputError(f"{p}: {exc}") from None


def bundled_scenarios() -> list[str]:
    """Names of the example scenarios shipped in ``seatrack/data/scenarios``."""
    d = resources.files("seatrack") / "data" / "scenarios"
    return sorted(f.name[:-5] for f in d.iterdir() if f.name.endswith(".toml"))


def bundled_scenario(name: str) -> Path:
    """Path of a bundled example scenario (``"demo"``, ``"linear_cv"``, ``"tma_classic"``)."""
    d = resources.files("seatrack") / "data" / "scenarios"
    f = d / f"{name}.toml"
    if not f.is_file():
        raise InputError(
            f"no bundled scenario {name!r}; available: {', '.join(bundled_scenarios())}"
        )
    return Path(str(f))


def resolve_scenario(arg: str | Path) -> Path:
    """A scenario given on the command line: an existing file, or a bundled name (``demo``).

    Raises
    ------
    InputError
        If neither a file nor a bundled scenario of that name exists.
    """
    p = Path(arg)
    if p.exists():
        return p
    if p.suffix == "" and p.parent == Path("."):
        names = bundled_scenarios()
        if str(arg) in names:
            return bundled_scenario(str(arg))
        raise InputError(
            f"{arg}: no such scenario file, and no bundled scenario of that name "
            f"(bundled: {', '.join(names)})"
        )
    raise InputError(f"{p}: scenario file not found")
