"""Rotating-radar echo simulator for landmark navigation (spec ``landmark_nav.md``,
"Echo trap" and "Beyond the patent").

A boat follows a route built with :func:`seatrack.simulate.trajectory` (heading = course,
radar antenna ``a`` metres aft of the reference point). The radar antenna turns at a
constant rate (``period`` s per revolution, angle relative to the bow, clockwise) and
transmits pulses at ``prf``; every above-threshold video sample becomes one echo point
``(time_s, antenna angle, range bin centre)``.

* Point reflectors echo on every pulse whose beam (``beam_width``) covers them, at the
  range bin of their true range plus a Gaussian spread, each pulse detected with
  probability ``p_pulse``.
* Contour elements are straight segments (``contour_length`` m) through the reference point
  along ``orientation``; each pulse whose beam axis hits the segment (at more than
  ``min_incidence`` from grazing) echoes at the intersection range.
* A landmark is missed for a whole revolution with probability ``p_miss`` and echoes
  nothing during the ``hidden`` intervals.
* Clutter: uniform in area over the radar disc, ``clutter_density`` false samples per m^2
  per revolution (Poisson), each on a pulse and range bin.
* The navigator's map carries independent Gaussian coordinate errors (``map_error_std``).
* A gyro log samples the true turn rate at ``gyro_rate`` Hz with white noise and a bias.

Everything is vectorised over (revolution, landmark) pairs and pulses; no loop per pulse.
"""

from __future__ import annotations

from collections.abc import Callable
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field

import numpy as np
from numpy.typing import NDArray

from seatrack.geometry import TWO_PI
from seatrack.geometry import bearing
from seatrack.geometry import wrap_2pi
from seatrack.geometry import wrap_pi
from seatrack.navigation.landmarks import LandmarkMap
from seatrack.simulate.trajectories import Leg
from seatrack.simulate.trajectories import Trajectory
from seatrack.simulate.trajectories import trajectory

FloatArray = NDArray[np.float64]

__all__ = [
    "RadarConfig",
    "EchoEnvironment",
    "EchoLog",
    "RadarRun",
    "river_route",
    "channel_landmarks",
    "simulate_radar",
]


@dataclass(frozen=True)
class RadarConfig:
    """Rotating radar.

    Attributes
    ----------
    period : s per antenna revolution (2.5).
    beam_width : rad, two-way horizontal beam width.
    prf : pulses per second.
    bin_m : range bin (6 m = 25 MHz sampling).
    range_limit : m.
    min_range : m, blind range near the antenna.
    antenna_offset : m, antenna aft of the reference point F.
    """

    period: float = 2.5
    beam_width: float = float(np.radians(1.2))
    prf: float = 2000.0
    bin_m: float = 6.0
    range_limit: float = 3000.0
    min_range: float = 50.0
    antenna_offset: float = 0.0


@dataclass(frozen=True)
class EchoEnvironment:
    """Landmark, clutter and sensor-error settings of one simulated passage."""

    clutter_density: float = 1e-5
    p_miss: float = 0.2
    p_pulse: float = 0.9
    point_spread: float = 2.0
    contour_length: float = 120.0
    min_incidence: float = float(np.radians(10.0))
    map_error_std: float = 3.0
    hidden: Sequence[tuple[float, float]] = field(default_factory=tuple)
    gyro_rate: float = 10.0
    gyro_sigma: float = float(np.radians(0.05))
    gyro_bias: float = 0.0


@dataclass(frozen=True)
class EchoLog:
    """Echo points, sorted by time.

    Attributes
    ----------
    t : (K,) s
    antenna : (K,) rad, antenna angle relative to the bow, clockwise, [0, 2 pi)
    range : (K,) m, range-bin centre
    amplitude : (K,) dB above threshold (simulated)
    source : (K,) int, landmark number or -1 for clutter (truth, not written to files)
    """

    t: FloatArray
    antenna: FloatArray
    range: FloatArray
    amplitude: FloatArray
    source: NDArray[np.int64]


@dataclass(frozen=True)
class RadarRun:
    """One simulated passage.

    Attributes
    ----------
    echoes : EchoLog
    gyro_t, gyro_rate : gyro log (s, rad/s clockwise)
    truth_t : (N,) s
    truth : (N, 6) true state ``[X, Y, alpha, Xdot, Ydot, alphadot]``
    true_map : LandmarkMap with the true positions
    nav_map : LandmarkMap given to the navigator (with coordinate errors)
    """

    echoes: EchoLog
    gyro_t: FloatArray
    gyro_rate: FloatArray
    truth_t: FloatArray
    truth: FloatArray
    true_map: LandmarkMap
    nav_map: LandmarkMap


def river_route(length_m: float = 10_000.0, speed: float = 4.0, dt: float = 1.0) -> Trajectory:
    """A winding river passage of about ``length_m`` at ``speed`` m/s: straight reaches joined
    by turns of 25-60 deg at 0.4-0.8 deg/s, starting at the origin heading North-East."""
    turns = [(np.radians(40), np.radians(0.6)), (np.radians(-60), np.radians(0.8)),
             (np.radians(35), np.radians(0.5)), (np.radians(-25), np.radians(0.4)),
             (np.radians(50), np.radians(0.7))]  # fmt: skip
    legs: list[Leg] = []
    turn_len = sum(abs(a) / w * speed for a, w in turns)
    straight = (length_m - turn_len) / (len(turns) + 1) / speed
    for a, w in turns:
        legs += [Leg.straight(straight), Leg.turn(a, w)]
    legs.append(Leg.straight(straight))
    return trajectory([0.0, 0.0], np.radians(30.0), speed, legs, dt=dt)


def channel_landmarks(
    route: Trajectory,
    n: int = 18,
    rng: np.random.Generator | None = None,
    contour_fraction: float = 0.35,
    point_offset: tuple[float, float] = (250.0, 900.0),
    contour_offset: tuple[float, float] = (120.0, 220.0),
) -> LandmarkMap:
    """Landmarks numbered along the channel: evenly spaced along the route, alternating
    sides; point reflectors ``point_offset`` m and contour elements (bank edges, parallel
    to the local course) ``contour_offset`` m from the axis."""
    g = rng or np.random.default_rng(0)
    p = route.pos[:, :2]
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    at = np.linspace(0.03, 0.97, n) * s[-1]
    x = np.interp(at, s, p[:, 0])
    y = np.interp(at, s, p[:, 1])
    crs = np.interp(at, s, np.unwrap(route.course))
    side = np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    is_c = g.random(n) < contour_fraction
    off = np.where(is_c, g.uniform(*contour_offset, n), g.uniform(*point_offset, n)) * side
    # right of the course is (cos c, -sin c)
    xy = np.stack([x + off * np.cos(crs), y - off * np.sin(crs)], axis=1)
    return LandmarkMap.from_arrays(xy, is_c, np.mod(crs, np.pi), [f"L{k:02d}" for k in range(n)])


def _interp_state(route: Trajectory, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    x = np.interp(t, route.t, route.pos[:, 0])
    y = np.interp(t, route.t, route.pos[:, 1])
    h = np.interp(t, route.t, np.unwrap(route.course))
    return x, y, h


def _antenna(route: Trajectory, rc: RadarConfig) -> Callable[[FloatArray], tuple[FloatArray, ...]]:
    """Antenna position East, North and own heading at times ``t`` (offset ``a`` aft)."""
    a = rc.antenna_offset

    def antenna_pos(t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        x, y, h = _interp_state(route, t)
        return x - a * np.sin(h), y - a * np.cos(h), h

    return antenna_pos


def _passes(
    route: Trajectory,
    landmarks: LandmarkMap,
    rng: np.random.Generator,
    rc: RadarConfig,
    ev: EchoEnvironment,
    antenna_pos: Callable[[FloatArray], tuple[FloatArray, ...]],
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Every beam pass over a landmark: the pulse numbers and the landmark of each pulse.

    The crossing time of every (revolution, landmark) pair is found by fixed-point
    iteration; a pass spans the beam width for a point reflector, the segment plus the beam
    for a contour element. Passes are missed with probability ``env.p_miss``.
    """
    T, t0, t1 = rc.period, float(route.t[0]), float(route.t[-1])
    n_rev = int(np.floor((t1 - t0) / T))
    L, nL, hb = landmarks.xy, len(landmarks), 0.5 * rc.beam_width
    t_rev = t0 + T * np.arange(n_rev)[:, None] + np.zeros((1, nL))
    tc = t_rev + 0.5 * T
    for _ in range(4):
        ex, ey, h = antenna_pos(tc)
        rel = wrap_2pi(bearing(L[:, 0] - ex, L[:, 1] - ey) - h)
        tc = t_rev + T * rel / TWO_PI
    ex, ey, h = antenna_pos(tc)
    rng_c = np.hypot(L[:, 0] - ex, L[:, 1] - ey)
    ok = (rng_c > rc.min_range) & (rng_c < rc.range_limit + 0.5 * ev.contour_length) & (tc <= t1)
    ok &= rng.random(ok.shape) >= ev.p_miss
    rev_i, lm_i = np.nonzero(ok)
    tcs = tc[rev_i, lm_i]
    # angular extent of each pass (relative to the crossing): beam for points, segment + beam
    lo = np.full(tcs.size, -hb)
    hi = np.full(tcs.size, hb)
    cont = landmarks.is_contour[lm_i]
    if cont.any():
        ci = lm_i[cont]
        ux, uy = np.sin(landmarks.orientation[ci]), np.cos(landmarks.orientation[ci])
        half = 0.5 * ev.contour_length
        ex_c, ey_c, _ = antenna_pos(tcs[cont])
        b0 = bearing(L[ci, 0] - ex_c, L[ci, 1] - ey_c)
        d1 = wrap_pi(bearing(L[ci, 0] + half * ux - ex_c, L[ci, 1] + half * uy - ey_c) - b0)
        d2 = wrap_pi(bearing(L[ci, 0] - half * ux - ex_c, L[ci, 1] - half * uy - ey_c) - b0)
        lo[cont] = np.minimum(d1, d2) - hb
        hi[cont] = np.maximum(d1, d2) + hb
    p_lo = np.ceil((tcs + lo * T / TWO_PI - t0) * rc.prf).astype(np.int64)
    p_hi = np.floor((tcs + hi * T / TWO_PI - t0) * rc.prf).astype(np.int64)
    cnt = np.maximum(p_hi - p_lo + 1, 0)
    owner = np.repeat(np.arange(tcs.size), cnt)
    pulse = p_lo[owner] + (np.arange(owner.size) - np.repeat(np.cumsum(cnt) - cnt, cnt))
    return pulse, lm_i[owner]


def _landmark_echoes(
    pulse: NDArray[np.int64],
    lid: NDArray[np.int64],
    landmarks: LandmarkMap,
    rng: np.random.Generator,
    rc: RadarConfig,
    ev: EchoEnvironment,
    t0: float,
    antenna_pos: Callable[[FloatArray], tuple[FloatArray, ...]],
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Pulse, range bin and landmark of every landmark echo sample: point reflectors inside
    the beam, contour elements where the beam axis meets the segment at a usable incidence."""
    L, hb = landmarks.xy, 0.5 * rc.beam_width
    tp = t0 + pulse / rc.prf
    ex, ey, h = antenna_pos(tp)
    beam_dir = wrap_2pi(TWO_PI * (tp - t0) / rc.period) + h  # true bearing of the beam axis
    is_c = landmarks.is_contour[lid]
    dx, dy = L[lid, 0] - ex, L[lid, 1] - ey
    r_true = np.hypot(dx, dy)
    keep = np.abs(wrap_pi(bearing(dx, dy) - beam_dir)) <= hb
    r_echo = r_true + ev.point_spread * rng.standard_normal(r_true.size)
    if is_c.any():
        ori = landmarks.orientation[lid]
        nx_, ny_ = np.cos(ori), -np.sin(ori)  # normal of the line
        ux, uy = np.sin(beam_dir), np.cos(beam_dir)
        cos_inc = ux * nx_ + uy * ny_
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (nx_ * dx + ny_ * dy) / cos_inc
        lam = np.sin(ori) * (ex + s * ux - L[lid, 0]) + np.cos(ori) * (ey + s * uy - L[lid, 1])
        hit = (
            (np.abs(cos_inc) >= np.sin(ev.min_incidence))
            & (s > 0)
            & (np.abs(lam) <= 0.5 * ev.contour_length)
        )
        keep = np.where(is_c, hit, keep)
        r_echo = np.where(is_c, s, r_echo)
    keep &= rng.random(keep.size) < ev.p_pulse
    keep &= (r_echo > rc.min_range) & (r_echo < rc.range_limit)
    for h0, h1 in ev.hidden:
        keep &= ~((tp >= h0) & (tp <= h1))
    return pulse[keep], np.floor(r_echo[keep] / rc.bin_m).astype(np.int64), lid[keep]


def _echo_log(
    landmark: tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]],
    rng: np.random.Generator,
    rc: RadarConfig,
    ev: EchoEnvironment,
    t0: float,
    n_rev: int,
) -> EchoLog:
    """Landmark echoes plus uniform clutter (Poisson per revolution), one row per
    (pulse, range bin) sample, sorted by time then range."""
    lm_pulse, lm_bin, lm_src = landmark
    area = np.pi * (rc.range_limit**2 - rc.min_range**2)
    n_cl = int(rng.poisson(ev.clutter_density * area * n_rev))
    r_cl = np.sqrt(rng.uniform(rc.min_range**2, rc.range_limit**2, n_cl))
    cl_pulse = rng.integers(0, int(n_rev * rc.period * rc.prf), n_cl)
    cl_bin = np.floor(r_cl / rc.bin_m).astype(np.int64)
    pulse_all = np.concatenate([lm_pulse, cl_pulse])
    bin_all = np.concatenate([lm_bin, cl_bin])
    src_all = np.concatenate([lm_src, np.full(n_cl, -1)])
    amp = np.concatenate(
        [20.0 + 3.0 * rng.standard_normal(lm_pulse.size), 8.0 + 3.0 * rng.standard_normal(n_cl)]
    )
    key = pulse_all * (1 << 20) + bin_all
    _, first = np.unique(key, return_index=True)  # sorted by key = (pulse, bin)
    tt = t0 + pulse_all[first] / rc.prf
    return EchoLog(
        tt,
        np.asarray(wrap_2pi(TWO_PI * (tt - t0) / rc.period)),
        (bin_all[first] + 0.5) * rc.bin_m,
        np.maximum(amp[first], 0.1),
        src_all[first],
    )


def simulate_radar(
    route: Trajectory,
    landmarks: LandmarkMap,
    rng: np.random.Generator,
    radar: RadarConfig | None = None,
    env: EchoEnvironment | None = None,
    nav_map: LandmarkMap | None = None,
) -> RadarRun:
    """Simulate one passage (see module docstring).

    Parameters
    ----------
    route : truth trajectory (heading = course).
    landmarks : true landmark positions.
    rng : random generator (all randomness comes from it).
    radar, env : configuration.
    nav_map : map for the navigator; default: ``landmarks`` plus ``env.map_error_std``
        Gaussian errors per coordinate.
    """
    rc = radar or RadarConfig()
    ev = env or EchoEnvironment()
    t0, t1 = float(route.t[0]), float(route.t[-1])
    n_rev = int(np.floor((t1 - t0) / rc.period))
    antenna_pos = _antenna(route, rc)
    pulse, lid = _passes(route, landmarks, rng, rc, ev, antenna_pos)
    samples = _landmark_echoes(pulse, lid, landmarks, rng, rc, ev, t0, antenna_pos)
    echoes = _echo_log(samples, rng, rc, ev, t0, n_rev)
    # --- gyro log
    gt = np.arange(t0, t1, 1.0 / ev.gyro_rate)
    w_true = np.interp(gt, route.t, route.turn_rate)
    gyro = w_true + ev.gyro_bias + ev.gyro_sigma * rng.standard_normal(gt.size)
    # --- truth and navigator map
    hd = np.unwrap(route.course)
    truth = np.column_stack(
        [route.pos[:, 0], route.pos[:, 1], hd, route.vel[:, 0], route.vel[:, 1], route.turn_rate]
    )
    if nav_map is None:
        L = landmarks.xy
        nav_map = landmarks.with_xy(L + ev.map_error_std * rng.standard_normal(L.shape))
    return RadarRun(echoes, gt, gyro, route.t, truth, landmarks, nav_map)
