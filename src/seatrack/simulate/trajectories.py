"""Own-ship and target trajectories built from legs.

A trajectory starts at a position with a course and speed and follows a list of
:class:`Leg` segments; inside a leg the turn rate (clockwise positive), the along-track
acceleration and the vertical rate are constant. That covers constant-velocity legs,
coordinated turns, accelerations / speed changes and climbs, in 2-D or 3-D.

Course and speed are closed-form in time, and so is the position (the integrals of
``(s + a t) sin(c + w t)`` and its cosine twin), evaluated for all samples at once; only
turns so slight that the closed form would cancel badly fall back to Simpson's rule on
sub-steps of at most ``max_substep`` seconds. The truth is exact to round-off.

x East, y North, z Up; metres, seconds, radians; course clockwise from North.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.config import require
from seatrack.geometry import G0
from seatrack.geometry import wrap_2pi

FloatArray = NDArray[np.float64]

__all__ = ["Leg", "Trajectory", "trajectory", "leg_times"]


@dataclass(frozen=True)
class Leg:
    """One segment of a trajectory.

    Parameters
    ----------
    duration : float
        Seconds.
    turn_rate : float
        Course rate, rad/s, positive clockwise (starboard turn).
    accel : float
        Along-track acceleration, m/s^2 (speed changes linearly).
    climb_rate : float
        Vertical velocity during the leg, m/s (Up positive).
    """

    duration: float
    turn_rate: float = 0.0
    accel: float = 0.0
    climb_rate: float = 0.0

    def __post_init__(self) -> None:
        if not np.isfinite(self.duration) or self.duration <= 0:
            raise ValueError(
                f"leg duration must be a positive number of seconds, got {self.duration}"
            )
        require(self, ("turn_rate", "accel", "climb_rate"), np.isfinite, "finite", prefix="leg ")

    @classmethod
    def straight(cls, duration: float, climb_rate: float = 0.0) -> Leg:
        """Constant-velocity leg."""
        return cls(duration, climb_rate=climb_rate)

    @classmethod
    def turn(cls, angle: float, rate: float) -> Leg:
        """Coordinated turn through ``angle`` rad (signed; + = clockwise) at ``|rate|`` rad/s."""
        if rate == 0:
            raise ValueError("turn rate must be non-zero")
        return cls(abs(angle / rate), turn_rate=float(np.sign(angle)) * abs(rate))

    @classmethod
    def turn_g(cls, angle: float, g: float, speed: float) -> Leg:
        """Coordinated turn through ``angle`` rad at lateral acceleration ``g`` (in g)."""
        return cls.turn(angle, g * G0 / speed)

    @classmethod
    def speed_change(cls, from_speed: float, to_speed: float, accel: float) -> Leg:
        """Straight leg changing speed from ``from_speed`` to ``to_speed`` at ``|accel|`` m/s^2."""
        dv = to_speed - from_speed
        if dv == 0 or accel == 0:
            raise ValueError("speed change needs different speeds and a non-zero acceleration")
        return cls(abs(dv / accel), accel=float(np.sign(dv)) * abs(accel))


@dataclass(frozen=True)
class Trajectory:
    """Sampled truth. Arrays have one row per time.

    Attributes
    ----------
    t : (N,) s
    pos : (N, 3) m, East North Up
    vel : (N, 3) m/s
    acc : (N, 3) m/s^2
    course : (N,) rad, clockwise from North, [0, 2 pi)
    speed : (N,) m/s, horizontal
    turn_rate : (N,) rad/s, clockwise positive
    """

    t: FloatArray
    pos: FloatArray
    vel: FloatArray
    acc: FloatArray
    course: FloatArray
    speed: FloatArray
    turn_rate: FloatArray

    def state(self, layout: str = "cv2") -> FloatArray:
        """Truth as a filter state: ``cv2`` [x,y,vx,vy], ``cv3`` [x,y,z,vx,vy,vz],
        ``ct2`` [x,y,vx,vy,w], ``ct3`` [x,y,z,vx,vy,vz,w], ``ca2``/``ca3`` with accelerations."""
        d = 3 if layout.endswith("3") else 2
        parts = [self.pos[:, :d], self.vel[:, :d]]
        if layout.startswith("ct"):
            parts.append(self.turn_rate[:, None])
        elif layout.startswith("ca"):
            parts.append(self.acc[:, :d])
        elif not layout.startswith("cv"):
            raise ValueError(f"unknown state layout {layout!r}; use cv2, cv3, ct2, ct3, ca2, ca3")
        return np.concatenate(parts, axis=1)

    def at(self, t: ArrayLike) -> FloatArray:
        """Position ``(..., 3)`` at arbitrary times, by cubic Hermite interpolation."""
        tt = np.asarray(t, dtype=float)
        i = np.clip(np.searchsorted(self.t, tt) - 1, 0, len(self.t) - 2)
        h = self.t[i + 1] - self.t[i]
        s = ((tt - self.t[i]) / h)[..., None]
        h = h[..., None]
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        return (
            h00 * self.pos[i]
            + h10 * h * self.vel[i]
            + h01 * self.pos[i + 1]
            + h11 * h * self.vel[i + 1]
        )


def leg_times(legs: Sequence[Leg], t0: float = 0.0) -> FloatArray:
    """Start time of each leg and the end of the last (``len(legs) + 1`` values)."""
    return t0 + np.concatenate([[0.0], np.cumsum([leg.duration for leg in legs])])


def trajectory(
    start: ArrayLike,
    course: float,
    speed: float,
    legs: Sequence[Leg],
    dt: float | None = None,
    times: ArrayLike | None = None,
    t0: float = 0.0,
    max_substep: float = 0.25,
) -> Trajectory:
    """Build a trajectory from legs and sample it.

    Parameters
    ----------
    start : (2,) or (3,) m
        Initial position (East, North[, Up]).
    course : float
        Initial course, rad clockwise from North.
    speed : float
        Initial horizontal speed, m/s (must stay >= 0).
    legs : sequence of Leg
        Segments, in order. After the last leg the motion continues straight.
    dt : float, optional
        Sample interval; samples from ``t0`` to the end of the last leg inclusive.
    times : array, optional
        Explicit sorted sample times (instead of ``dt``).
    t0 : float
        Time at the start of the first leg.
    max_substep : float
        Longest Simpson sub-step, s.
    """
    if (dt is None) == (times is None):
        raise ValueError("give exactly one of dt or times")
    bounds = leg_times(legs, t0)
    if times is None:
        assert dt is not None
        if dt <= 0:
            raise ValueError(f"dt must be positive, got {dt}")
        n = int(np.floor((bounds[-1] - t0) / dt + 1e-9)) + 1
        tt = t0 + dt * np.arange(n)
    else:
        tt = np.asarray(times, dtype=float)
        if tt.ndim != 1 or tt.size == 0 or np.any(np.diff(tt) < 0):
            raise ValueError("times must be a non-empty sorted 1-D array")
        if tt[0] < t0:
            raise ValueError(f"first sample time {tt[0]} is before the trajectory start {t0}")
    p0 = np.zeros(3)
    st = np.asarray(start, dtype=float)
    p0[: st.size] = st
    # per-leg constants, with a final open-ended straight leg
    w = np.array([leg.turn_rate for leg in legs] + [0.0])
    a = np.array([leg.accel for leg in legs] + [0.0])
    vz = np.array([leg.climb_rate for leg in legs] + [0.0])
    leg_start = bounds  # len(legs)+1 starts (the last is the open straight)

    # state at every leg start
    c_start = np.empty(len(w))
    s_start = np.empty(len(w))
    p_start = np.empty((len(w), 3))
    c, s, p = float(course), float(speed), p0.copy()
    for k in range(len(w)):
        c_start[k], s_start[k], p_start[k] = c, s, p
        if k < len(legs):
            T = legs[k].duration
            d = _displacements(
                np.array([c]),
                np.array([s]),
                w[k : k + 1],
                a[k : k + 1],
                vz[k : k + 1],
                np.array([T]),
                max_substep,
            )
            p = p + d[0]
            c = c + w[k] * T
            s = s + a[k] * T
            if s < -1e-9:
                raise ValueError(f"leg {k} makes the speed negative ({s:.3f} m/s)")
            s = max(s, 0.0)

    k_of = np.clip(np.searchsorted(leg_start, tt, side="right") - 1, 0, len(w) - 1)
    tau = tt - leg_start[k_of]
    pos = p_start[k_of] + _displacements(
        c_start[k_of], s_start[k_of], w[k_of], a[k_of], vz[k_of], tau, max_substep
    )
    crs = c_start[k_of] + w[k_of] * tau
    spd = s_start[k_of] + a[k_of] * tau
    vel = np.stack([spd * np.sin(crs), spd * np.cos(crs), vz[k_of]], -1)
    acc = np.stack(
        [
            a[k_of] * np.sin(crs) + spd * w[k_of] * np.cos(crs),
            a[k_of] * np.cos(crs) - spd * w[k_of] * np.sin(crs),
            np.zeros_like(tt),
        ],
        -1,
    )
    return Trajectory(
        tt.astype(np.float64), pos, vel, acc, np.asarray(wrap_2pi(crs)), spd, w[k_of].astype(float)
    )


def _displacements(
    c: FloatArray,
    s: FloatArray,
    w: FloatArray,
    a: FloatArray,
    vz: FloatArray,
    T: FloatArray,
    h: float,
) -> FloatArray:
    """Displacements ``(N, 3)`` after ``T`` s with course ``c + w t`` and speed ``s + a t``.

    Closed forms: straight (``w = 0``) and, for ``|w T| >= 1e-3``, the exact integrals
    ``int (s + a t) sin(c + w t) dt = [-(s + a t) cos(c + w t) / w + a sin(c + w t) / w^2]``
    (and the cosine twin), which hold for turns with or without speed change. Only turns
    so slight that these cancel badly (``0 < |w T| < 1e-3`` with ``a != 0``) use Simpson's
    rule on sub-steps of at most ``h`` s.
    """
    T = np.maximum(T, 0.0)
    out = np.zeros((T.size, 3))
    out[:, 2] = vz * T
    straight = w == 0.0
    d = s * T + 0.5 * a * T**2
    out[straight, 0] = (d * np.sin(c))[straight]
    out[straight, 1] = (d * np.cos(c))[straight]
    turn = ~straight & (np.abs(w * T) >= 1e-3)
    if turn.any():
        cc, ss, ww, aa, TT = c[turn], s[turn], w[turn], a[turn], T[turn]
        c1 = cc + ww * TT
        s1 = ss + aa * TT
        out[turn, 0] = (ss * np.cos(cc) - s1 * np.cos(c1)) / ww + aa * (
            np.sin(c1) - np.sin(cc)
        ) / ww**2
        out[turn, 1] = (s1 * np.sin(c1) - ss * np.sin(cc)) / ww + aa * (
            np.cos(c1) - np.cos(cc)
        ) / ww**2
    slight = ~straight & ~turn
    for i in np.flatnonzero(slight):
        out[i] = _displacement(c[i], s[i], w[i], a[i], vz[i], T[i], h)
    return out


def _displacement(
    c: float, s: float, w: float, a: float, vz: float, T: float, h: float
) -> FloatArray:
    """Displacement after ``T`` s with course ``c + w t`` and speed ``s + a t`` (Simpson)."""
    if T <= 0:
        return np.zeros(3)
    if w == 0.0:
        d = s * T + 0.5 * a * T**2
        return np.array([d * np.sin(c), d * np.cos(c), vz * T])
    if a == 0.0:  # exact arc
        dx = s * (np.cos(c) - np.cos(c + w * T)) / w
        dy = s * (np.sin(c + w * T) - np.sin(c)) / w
        return np.array([dx, dy, vz * T])
    m = max(2, int(np.ceil(T / h)))
    m += m % 2
    t = np.linspace(0.0, T, m + 1)
    wt = np.ones(m + 1)
    wt[1:-1:2] = 4
    wt[2:-1:2] = 2
    sp = s + a * t
    cr = c + w * t
    f = T / (3 * m)
    return np.array([f * np.sum(wt * sp * np.sin(cr)), f * np.sum(wt * sp * np.cos(cr)), vz * T])
