"""Turning-target radar plot filter (CN 104407337 A; spec ``specs/turning.md``).

A constant-velocity EKF on radar plots (range, azimuth[, elevation]) whose process noise
is raised for the next scan only when a second filter, running on the EKF's heading,
decides by a fuzzy sequential vote that the turn rate is rising or falling.

Steps of the spec, each a small pure function here (arrays in, arrays out; the ones that
are plain arithmetic broadcast over leading dimensions):

* S1 :func:`ekf_step` -- CV-EKF predict + update on one plot (``seatrack.kalman``,
  ``seatrack.models``); :func:`initial_state` starts it from the first plot.
* S2 :func:`velocity_significance` (``d_t``), :func:`heading`, :func:`heading_variance`,
  :func:`heading_filter_init` / :func:`heading_filter_step` (the (b, omega) filter with
  the wrapped heading innovation).
* S3 :func:`turn_rate_significance` (``d_omega``) and :func:`push_turn_rate` (FIFO queue).
* S4 :func:`fuzzy_vote` (rising / falling count vote with the ``delta_omega`` threshold).
* S5 :func:`noise_gain` ``c(delta_omega)``; the gain applies to the next prediction only
  and returns to 1 (nominal ``Q``) on any scan where S5 does not fire.
* S6 the output point: :class:`TurningStep` (one scan) / :class:`TurningTrack` (a run).

:class:`TurningFilter` is the thin stateful shell that strings the steps together;
:func:`track_plots` is the ``seatrack track --method turning`` runner.

Conventions: x East, y North, z Up; SI units and radians inside. Heading and azimuth are
clockwise from North (``atan2(vE, vN)``); the heading-filter state and every angle
difference are wrapped to ``(-pi, pi]`` (the spec writes ``[-pi, pi)``; the project
convention is used, the two differ only at the single point ``-pi``). The turn rate is
``d(heading)/dt``, i.e. positive clockwise (to starboard), as in
:class:`seatrack.models.CoordinatedTurn`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from enum import IntEnum
from functools import lru_cache
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seatrack import kalman
from seatrack.geometry import bearing, wrap_pi
from seatrack.models import RangeBearing, RangeBearingElevation
from seatrack.models.measurement import (
    range_bearing_elevation_jacobian,
    range_bearing_jacobian,
)
from seatrack.models.motion import cv_noise, cv_transition

FloatArray = NDArray[np.float64]

__all__ = [
    "TurnState",
    "TurningConfig",
    "HeadingEstimate",
    "TurningStep",
    "TurningTrack",
    "TurningFilter",
    "initial_state",
    "ekf_step",
    "velocity_significance",
    "heading",
    "heading_jacobian",
    "heading_variance",
    "heading_filter_noise",
    "heading_filter_init",
    "heading_filter_step",
    "turn_rate_significance",
    "push_turn_rate",
    "fuzzy_vote",
    "noise_gain",
    "track_plots",
]


class TurnState(IntEnum):
    """Decision of the fuzzy sequential test (spec S4) at one scan."""

    STRAIGHT = 0  #: no decision fired (includes "not enough significant turn rates yet")
    RISING = 1  #: turn rate increasing (algebraically; clockwise positive)
    FALLING = 2  #: turn rate decreasing

    @property
    def label(self) -> str:
        return self.name.lower()


# ---------------------------------------------------------------------------
# Configuration
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class TurningConfig:
    """Parameters of the turning-target filter (defaults from ``specs/turning.md``).

    Parameters
    ----------
    q_nominal : float
        S1 nominal process noise: white-acceleration PSD of the CV-EKF, m^2/s^3
        ([reading] continuous white-noise acceleration, ``Q_nom = q cv_noise``). Not
        given in the patent; choose for the target class (tuned values in
        ``benchmarks/turning.py``).
    sigma_range, sigma_azimuth, sigma_elevation : float
        Plot noise standard deviations, m, rad, rad (radar property, not the patent's).
    sigma_velocity0 : float
        Standard deviation of the initial velocity (m/s per axis): the EKF starts at the
        first plot with zero velocity ([reading] initialisation is not described).
    velocity_threshold : float or None
        S2 threshold on ``d_t = sum v_i^2 / sigma_i^2``; ``None`` = N, the number of
        velocity components (2 or 3), as in the spec.
    heading_cross_covariance : bool
        S2 heading variance from the full 2x2 horizontal velocity covariance instead of
        the spec's diagonal-only formula (default False = the spec).
    sigma_omega0 : float
        S2 initial turn-rate standard deviation of the heading filter, rad/s
        ([reading] "large, configurable"; 0.1 rad/s ~ 5.7 deg/s).
    q_heading : float
        S2 heading-filter process noise ``q`` (rad^2/s^3), spec value 1e-6.
    heading_noise : {"continuous", "diagonal"}
        S2 form of the heading-filter noise ([reading]): ``q [[D^3/3, D^2/2], [D^2/2, D]]``
        or ``q diag(D^3/3, D)``.
    turn_rate_threshold : float
        S3 threshold on ``d_omega = |omega / sigma_omega|`` (spec: 1).
    queue_length : int
        S3/S4 ``M`` (> 3; not given in the patent, default 5).
    count_min : int or None
        S4 count condition ``N >= K``; ``None`` = ``M - 2`` ([reading] "fuzzy" vote
        tolerating one violated comparison).
    delta_omega_threshold : float
        S4 threshold on ``delta_omega = |omega_M - omega_1|``, rad/s (spec: 0.02).
    gain_reference, gain_power, gain_max : float
        S5 ``c = clip((delta_omega / gain_reference) ** gain_power, 1, gain_max)``
        ([reading] formula missing; default ``(delta_omega / 0.02)^2`` capped at 100).
    """

    q_nominal: float = 0.5
    sigma_range: float = 50.0
    sigma_azimuth: float = math.radians(0.1)
    sigma_elevation: float = math.radians(0.1)
    sigma_velocity0: float = 300.0
    velocity_threshold: float | None = None
    heading_cross_covariance: bool = False
    sigma_omega0: float = 0.1
    q_heading: float = 1e-6
    heading_noise: Literal["continuous", "diagonal"] = "continuous"
    turn_rate_threshold: float = 1.0
    queue_length: int = 5
    count_min: int | None = None
    delta_omega_threshold: float = 0.02
    gain_reference: float = 0.02
    gain_power: float = 2.0
    gain_max: float = 100.0

    def __post_init__(self) -> None:
        positive = (
            "q_nominal",
            "sigma_range",
            "sigma_azimuth",
            "sigma_elevation",
            "sigma_velocity0",
            "sigma_omega0",
            "q_heading",
            "gain_reference",
        )
        for name in positive:
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"turning config: {name} must be a positive number, got {v!r}")
        for name in ("turn_rate_threshold", "delta_omega_threshold", "gain_power"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise ValueError(f"turning config: {name} must be a number >= 0, got {v!r}")
        if self.velocity_threshold is not None and not self.velocity_threshold >= 0:
            raise ValueError(
                f"turning config: velocity_threshold must be >= 0 or None, "
                f"got {self.velocity_threshold!r}"
            )
        if not (isinstance(self.gain_max, int | float) and self.gain_max >= 1):
            raise ValueError(f"turning config: gain_max must be >= 1, got {self.gain_max!r}")
        if self.heading_noise not in ("continuous", "diagonal"):
            raise ValueError(
                f"turning config: heading_noise must be 'continuous' or 'diagonal', "
                f"got {self.heading_noise!r}"
            )
        M = self.queue_length
        if not (isinstance(M, int) and not isinstance(M, bool) and M > 3):
            raise ValueError(f"turning config: queue_length M must be an integer > 3, got {M!r}")
        K = self.count
        if not (isinstance(K, int) and 1 <= K <= M - 1):
            raise ValueError(
                f"turning config: count_min K must be an integer in [1, M-1] = [1, {M - 1}], "
                f"got {K!r}"
            )

    @property
    def count(self) -> int:
        """The count rule ``K`` actually used (``M - 2`` unless set)."""
        return self.queue_length - 2 if self.count_min is None else self.count_min

    def replace(self, **changes: Any) -> TurningConfig:
        """A copy with some fields changed (validated)."""
        return TurningConfig(**{**{f.name: getattr(self, f.name) for f in fields(self)}, **changes})


# ---------------------------------------------------------------------------
# S1: constant-velocity EKF on plots
# ---------------------------------------------------------------------------
@lru_cache(maxsize=256)
def _cv_matrices(dt: float, q: float, d: int) -> tuple[FloatArray, FloatArray]:
    """``(F, Q)`` of the CV model with PSD ``q`` (cached: radar scans repeat the same ``dt``).

    The cached arrays are shared: callers must not modify them in place (they are kept
    writeable because Numba compiles a separate specialisation for read-only arrays).
    """
    return cv_transition(dt, d), cv_noise(dt, q, d)


def measurement_model(d: int) -> RangeBearing | RangeBearingElevation:
    """Plot model for a CV state in ``d`` = 2 (range, azimuth) or 3 (+ elevation) dimensions."""
    if d == 2:
        return RangeBearing(n=4, pos=(0, 1))
    if d == 3:
        return RangeBearingElevation(n=6, pos=(0, 1, 2))
    raise ValueError(f"radar dimension must be 2 or 3, got {d}")


def plot_covariance(
    sigma_range: float, sigma_azimuth: float, sigma_elevation: float, d: int
) -> FloatArray:
    """Diagonal plot-noise covariance ``R`` (m^2, rad^2) for a ``d``-D radar."""
    s = [sigma_range, sigma_azimuth, sigma_elevation][:d]
    return np.diag(np.square(s))


def initial_state(
    z: ArrayLike, R: ArrayLike, sigma_velocity0: float, sensor: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """CV state and covariance from one plot ([reading]; spec S1 gives no initialisation).

    Position = the plot converted to ENU (plus the sensor position); its covariance is
    ``G R G^T`` with ``G = (dh/dp)^-1`` the inverse of the plot Jacobian (first-order
    converted-measurement covariance). Velocity 0 with standard deviation
    ``sigma_velocity0`` per axis, uncorrelated.

    Parameters
    ----------
    z : (d,) range (m), azimuth (rad, clockwise from North)[, elevation (rad)].
    R : (d, d) plot covariance.
    sigma_velocity0 : m/s.
    sensor : (3,) sensor position (East, North, Up), m; default origin.
    """
    zz = np.asarray(z, dtype=float)
    d = zz.size
    r, az = zz[0], zz[1]
    el = zz[2] if d == 3 else 0.0
    ce = math.cos(el)
    rel = np.array([r * ce * math.sin(az), r * ce * math.cos(az), r * math.sin(el)])[:d]
    s = np.zeros(3) if sensor is None else np.asarray(sensor, dtype=float)
    J = range_bearing_jacobian(rel) if d == 2 else range_bearing_elevation_jacobian(rel)
    G = np.linalg.inv(J)
    x = np.zeros(2 * d)
    x[:d] = rel + s[:d]
    P = np.zeros((2 * d, 2 * d))
    P[:d, :d] = kalman.symmetrize(G @ np.asarray(R, dtype=float) @ G.T)
    P[d:, d:] = np.eye(d) * sigma_velocity0**2
    return x, P


def ekf_step(
    x: ArrayLike,
    P: ArrayLike,
    z: ArrayLike,
    dt: float,
    Q: ArrayLike,
    R: ArrayLike,
    sensor: ArrayLike | None = None,
) -> kalman.UpdateResult:
    """S1: one constant-velocity EKF cycle (predict over ``dt`` with ``Q``, update on ``z``).

    Broadcasts over leading dimensions of ``x``, ``P``, ``z``, ``Q``, ``sensor`` (used by
    the benchmark to run many fixed-``Q`` EKFs as one batch).

    Parameters
    ----------
    x, P : (..., 2d), (..., 2d, 2d) state ``[x, y, (z), vx, vy, (vz)]`` and covariance.
    z : (..., d) plot: range (m), azimuth (rad)[, elevation (rad)].
    dt : s since the previous plot.
    Q : (..., 2d, 2d) process noise for this cycle (``c * Q_nom`` in the method).
    R : (d, d) plot covariance.
    sensor : (..., 3) sensor position, m.

    Returns
    -------
    kalman.UpdateResult (posterior ``x``, ``P``, wrapped innovation ``y``, ``S``, NIS, ...).
    """
    xx = np.asarray(x, dtype=float)
    d = xx.shape[-1] // 2
    F = _cv_matrices(float(dt), 1.0, d)[0] if np.ndim(dt) == 0 else cv_transition(dt, d)
    xp, Pp = kalman.predict(xx, np.asarray(P, dtype=float), F, Q)
    h = measurement_model(d)
    return kalman.extended_update(xp, Pp, z, h.h(xp, sensor), h.jacobian(xp, sensor), R, h.angular)


# ---------------------------------------------------------------------------
# S2: velocity significance, heading, heading / turn-rate filter
# ---------------------------------------------------------------------------
def velocity_significance(v: ArrayLike, var: ArrayLike) -> Any:
    """S2 ``d_t = sum_i v_i^2 / sigma_i^2`` over the last axis (N = 2 or 3 terms).

    A chi-square statistic with N degrees of freedom under ``v = 0``; the velocity is
    used for the turn rate when ``d_t > N`` ([reading] of the missing formula).

    Parameters
    ----------
    v : (..., N) velocity, m/s.
    var : (..., N) variances ``sigma_i^2`` (diagonal of P), m^2/s^2.
    """
    vv = np.asarray(v, dtype=float)
    return np.sum(vv**2 / np.asarray(var, dtype=float), axis=-1)


def heading(v: ArrayLike) -> Any:
    """S2 heading ``b = atan2(v_E, v_N)`` (rad, clockwise from North) wrapped to ``(-pi, pi]``."""
    vv = np.asarray(v, dtype=float)
    return wrap_pi(bearing(vv[..., 0], vv[..., 1]))


def heading_jacobian(v: ArrayLike) -> FloatArray:
    """``d b / d(v_E, v_N) = [v_N, -v_E] / (v_E^2 + v_N^2)`` (rad s/m), shape ``(..., 2)``."""
    vv = np.asarray(v, dtype=float)
    s2 = vv[..., 0] ** 2 + vv[..., 1] ** 2
    return np.stack([vv[..., 1] / s2, -vv[..., 0] / s2], -1)


def heading_variance(v: ArrayLike, cov: ArrayLike) -> Any:
    """S2 heading variance ``sigma_b^2`` (rad^2), first order in the velocity error.

    With ``cov`` the variances ``(..., 2)`` ``(sigma_E^2, sigma_N^2)`` this is the spec's
    ``(v_N^2 sigma_E^2 + v_E^2 sigma_N^2) / (v_E^2 + v_N^2)^2``; with a full ``(..., 2, 2)``
    covariance it is ``J C J^T`` (J from :func:`heading_jacobian`), which adds the
    cross term the spec leaves out.
    """
    vv = np.asarray(v, dtype=float)[..., :2]
    C = np.asarray(cov, dtype=float)
    J = heading_jacobian(vv)
    if C.ndim >= 2 and C.shape[-2:] == (2, 2) and C.ndim == vv.ndim + 1:
        return np.einsum("...i,...ij,...j->...", J, C, J)
    return np.sum(J**2 * C[..., :2], axis=-1)


def heading_filter_noise(dt: float, q: float, form: str = "continuous") -> FloatArray:
    """S2 heading-filter process noise ``Q_b`` (state ``(b, omega)``), rad^2 and rad^2/s^2.

    ``continuous``: ``q [[D^3/3, D^2/2], [D^2/2, D]]`` (white turn-acceleration; the
    1-D :func:`seatrack.models.motion.cv_noise`); ``diagonal``: ``q diag(D^3/3, D)``.
    """
    Q = cv_noise(dt, q, 1)
    if form == "diagonal":
        return np.diag(np.diag(Q))
    if form != "continuous":
        raise ValueError(f"heading_noise must be 'continuous' or 'diagonal', got {form!r}")
    return Q


def heading_filter_init(
    b: float, var_b: float, sigma_omega0: float
) -> tuple[FloatArray, FloatArray]:
    """S2 first call: ``s = (b, 0)``, ``P0 = diag(sigma_b^2, sigma_omega0^2)``."""
    return np.array([float(wrap_pi(b)), 0.0]), np.diag([var_b, sigma_omega0**2])


_H_HEADING = np.array([[1.0, 0.0]])
_ANGULAR_HEADING = np.array([True])


@dataclass(frozen=True, slots=True)
class HeadingEstimate:
    """Output of the heading / turn-rate filter (spec S2).

    Attributes
    ----------
    s : (2,) ``(b, omega)``: heading (rad, ``(-pi, pi]``) and turn rate (rad/s, clockwise +).
    P : (2, 2) covariance; ``P[1, 1] = sigma_omega^2``.
    innovation : float -- wrapped heading innovation ``wrap(b_t - b')``, rad.
    gain : (2,) ``(r_b, r_omega)``.
    """

    s: FloatArray
    P: FloatArray
    innovation: float
    gain: FloatArray

    @property
    def turn_rate(self) -> float:
        return float(self.s[1])

    @property
    def turn_rate_std(self) -> float:
        return math.sqrt(max(float(self.P[1, 1]), 0.0))


def heading_filter_step(
    s: ArrayLike,
    P: ArrayLike,
    b: float,
    var_b: float,
    dt: float,
    q: float = 1e-6,
    form: str = "continuous",
) -> HeadingEstimate:
    """S2 later calls: predict ``b' = b + omega D`` (wrapped), ``omega' = omega``, update on ``b``.

    The innovation ``e = wrap(b_t - b')`` is wrapped to ``(-pi, pi]`` by
    :func:`seatrack.kalman.extended_update` (angular component), so a heading crossing
    North (or +-pi) is a small innovation, not a 2 pi jump. Gains
    ``r_b = P'11 / (P'11 + sigma_b^2)``, ``r_omega = P'21 / (P'11 + sigma_b^2)``; the
    covariance uses the Joseph form (equal to ``(I - KH) P'`` in exact arithmetic).
    """
    F, Qc = _cv_matrices(float(dt), float(q), 1)
    Qb = Qc if form == "continuous" else heading_filter_noise(dt, q, form)
    sp, Pp = kalman.predict(np.asarray(s, dtype=float), np.asarray(P, dtype=float), F, Qb)
    sp[0] = wrap_pi(sp[0])
    u = kalman.extended_update(
        sp,
        Pp,
        np.array([float(b)]),
        sp[:1],
        _H_HEADING,
        np.array([[float(var_b)]]),
        _ANGULAR_HEADING,
    )
    u.x[0] = wrap_pi(u.x[0])
    return HeadingEstimate(u.x, u.P, float(u.y[0]), u.K[:, 0].copy())


# ---------------------------------------------------------------------------
# S3 - S5: turn-rate significance, queue, fuzzy vote, noise gain
# ---------------------------------------------------------------------------
def turn_rate_significance(omega: ArrayLike, var_omega: ArrayLike) -> Any:
    """S3 ``d_omega = |omega / sigma_omega|`` (significant when > threshold, spec 1)."""
    return np.abs(np.asarray(omega, dtype=float)) / np.sqrt(np.asarray(var_omega, dtype=float))


def push_turn_rate(queue: Sequence[float], omega: float, M: int) -> tuple[tuple[float, ...], bool]:
    """S3/S4 FIFO queue: append ``omega`` at the tail; if the length then exceeds ``M``,
    drop the head so ``M`` values remain and report ``ready`` (go to S4).

    Returns
    -------
    queue : tuple, oldest first (at most ``M`` values).
    ready : bool -- True when S4 runs on this scan.
    """
    q = (*queue, float(omega))
    if len(q) > M:
        return q[len(q) - M :], True
    return q, False


def fuzzy_vote(
    window: ArrayLike, count_min: int, delta_omega_threshold: float = 0.02
) -> tuple[TurnState, float]:
    """S4 fuzzy sequential decision on the last ``M`` turn rates ``omega_1 .. omega_M``.

    Rising if ``N_1 = #{omega_{k+1} > omega_k} >= K`` and ``delta_omega > threshold``;
    otherwise falling if ``N_2 = #{omega_{k+1} < omega_k} >= K`` and
    ``delta_omega > threshold``; otherwise straight. ``delta_omega = |omega_M - omega_1|``.

    Returns
    -------
    state : TurnState
    delta_omega : float, rad/s (returned whatever the decision).
    """
    w = np.asarray(window, dtype=float)
    diff = np.diff(w)
    delta = float(abs(w[-1] - w[0]))
    if delta > delta_omega_threshold:
        if int(np.count_nonzero(diff > 0)) >= count_min:
            return TurnState.RISING, delta
        if int(np.count_nonzero(diff < 0)) >= count_min:
            return TurnState.FALLING, delta
    return TurnState.STRAIGHT, delta


def noise_gain(
    delta_omega: ArrayLike,
    reference: float = 0.02,
    power: float = 2.0,
    gain_max: float = 100.0,
) -> Any:
    """S5 process-noise gain ``c = clip((delta_omega / reference) ** power, 1, gain_max)``.

    ([reading] of the missing formula: ``c >= 1`` growing with the size of the turn-rate
    change, capped.) Broadcasts over ``delta_omega``.
    """
    c = np.clip((np.asarray(delta_omega, dtype=float) / reference) ** power, 1.0, gain_max)
    return c if c.ndim else float(c)


# ---------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class TurningStep:
    """S6 output for one scan.

    Attributes
    ----------
    t : s.
    x : (2d,) state ``[x, y, (z), vx, vy, (vz)]``; P : (2d, 2d) covariance.
    speed : horizontal speed, m/s.
    heading : rad, clockwise from North, ``[0, 2 pi)`` (from the EKF velocity).
    turn_rate, turn_rate_std : rad/s (NaN until the heading filter has started).
    d_velocity : S2 statistic ``d_t``; d_turn_rate : S3 ``d_omega`` (NaN when not computed).
    state : S4 decision made at this scan.
    q_gain : gain ``c`` applied to ``Q_nom`` in this scan's prediction.
    next_q_gain : gain decided at this scan (S5) for the next prediction.
    """

    t: float
    x: FloatArray
    P: FloatArray
    speed: float
    heading: float
    turn_rate: float
    turn_rate_std: float
    d_velocity: float
    d_turn_rate: float
    state: TurnState
    q_gain: float
    next_q_gain: float


@dataclass(frozen=True)
class TurningTrack:
    """:class:`TurningStep` fields stacked over the scans of one track (leading axis = scan)."""

    t: FloatArray
    x: FloatArray
    P: FloatArray
    speed: FloatArray
    heading: FloatArray
    turn_rate: FloatArray
    turn_rate_std: FloatArray
    d_velocity: FloatArray
    d_turn_rate: FloatArray
    state: NDArray[np.int64]
    q_gain: FloatArray
    next_q_gain: FloatArray

    @classmethod
    def from_steps(cls, steps: Sequence[TurningStep]) -> TurningTrack:
        if not steps:
            raise ValueError("no scans to stack")
        cols: dict[str, Any] = {}
        for f in fields(cls):
            vals = [getattr(s, f.name) for s in steps]
            cols[f.name] = np.array(vals, dtype=np.int64 if f.name == "state" else float)
        return cls(**cols)


# ---------------------------------------------------------------------------
# The stateful filter
# ---------------------------------------------------------------------------
class TurningFilter:
    """Turning-target filter of CN 104407337 (spec S1-S6) for one track.

    Parameters
    ----------
    config : TurningConfig
    d : int
        2 (plots = range, azimuth) or 3 (range, azimuth, elevation).

    Examples
    --------
    >>> f = TurningFilter(TurningConfig(), d=2)
    >>> step = f.step(0.0, [10_000.0, 0.5])          # first plot initialises the track
    """

    def __init__(self, config: TurningConfig | None = None, d: int = 2) -> None:
        self.config = config if config is not None else TurningConfig()
        measurement_model(d)  # validates d
        self.d = d
        c = self.config
        self.R = plot_covariance(c.sigma_range, c.sigma_azimuth, c.sigma_elevation, d)
        self._v_threshold = float(d) if c.velocity_threshold is None else c.velocity_threshold
        self.reset()

    def reset(self) -> None:
        """Forget the track (the next plot initialises it)."""
        self.t: float | None = None
        self.x: FloatArray | None = None
        self.P: FloatArray | None = None
        self.gain = 1.0  # c for the next prediction (S5)
        self.heading_s: FloatArray | None = None
        self.heading_P: FloatArray | None = None
        self.heading_t: float | None = None
        self.queue: tuple[float, ...] = ()

    def step(self, t: float, z: ArrayLike, sensor: ArrayLike | None = None) -> TurningStep:
        """Process the plot ``z`` (range m, azimuth rad[, elevation rad]) taken at time ``t`` s."""
        c = self.config
        d = self.d
        zz = np.asarray(z, dtype=float)
        if zz.shape != (d,) or not np.all(np.isfinite(zz)):
            raise ValueError(f"plot at t={t} must be {d} finite values, got {zz.tolist()}")
        sens = np.zeros(3) if sensor is None else np.asarray(sensor, dtype=float)
        applied = self.gain
        # ---- S1
        if self.x is None or self.P is None or self.t is None:
            self.x, self.P = initial_state(zz, self.R, c.sigma_velocity0, sens)
            applied = 1.0
        else:
            dt = float(t) - self.t
            if not dt > 0:
                raise ValueError(f"plot times must increase: {t} after {self.t}")
            Q = _cv_matrices(dt, c.q_nominal, d)[1]
            u = ekf_step(self.x, self.P, zz, dt, Q * applied if applied != 1.0 else Q, self.R, sens)
            self.x, self.P = u.x, u.P
        self.t = float(t)
        x, P = self.x, self.P
        v = x[d:]
        var_v = np.diag(P)[d:]
        # ---- S2
        state = TurnState.STRAIGHT
        next_gain = 1.0  # S5 return to Q_nom unless the decision fires
        d_t = float(velocity_significance(v, var_v))
        d_w = math.nan
        if d_t > self._v_threshold:
            b = float(heading(v))
            cov = P[d : d + 2, d : d + 2] if c.heading_cross_covariance else var_v[:2]
            var_b = float(heading_variance(v[:2], cov))
            if self.heading_s is None or self.heading_P is None or self.heading_t is None:
                self.heading_s, self.heading_P = heading_filter_init(b, var_b, c.sigma_omega0)
            else:
                est = heading_filter_step(
                    self.heading_s,
                    self.heading_P,
                    b,
                    var_b,
                    self.t - self.heading_t,
                    c.q_heading,
                    c.heading_noise,
                )
                self.heading_s, self.heading_P = est.s, est.P
            self.heading_t = self.t
            omega = float(self.heading_s[1])
            # ---- S3
            d_w = float(turn_rate_significance(omega, self.heading_P[1, 1]))
            if d_w > c.turn_rate_threshold:
                self.queue, ready = push_turn_rate(self.queue, omega, c.queue_length)
                if ready:
                    # ---- S4
                    state, delta = fuzzy_vote(self.queue, c.count, c.delta_omega_threshold)
                    if state is not TurnState.STRAIGHT:
                        # ---- S5
                        next_gain = float(
                            noise_gain(delta, c.gain_reference, c.gain_power, c.gain_max)
                        )
        self.gain = next_gain
        # ---- S6
        speed = math.hypot(v[0], v[1])
        if self.heading_s is not None and self.heading_P is not None:
            w, sw = float(self.heading_s[1]), math.sqrt(self.heading_P[1, 1])
        else:
            w, sw = math.nan, math.nan
        return TurningStep(
            self.t,
            x.copy(),
            P.copy(),
            speed,
            float(bearing(v[0], v[1])),
            w,
            sw,
            d_t,
            d_w,
            state,
            applied,
            next_gain,
        )

    def run(self, t: ArrayLike, z: ArrayLike, sensor: ArrayLike | None = None) -> TurningTrack:
        """Filter a whole track from a fresh start: ``t`` (N,), ``z`` (N, d), ``sensor`` (N, 3)."""
        self.reset()
        tt = np.asarray(t, dtype=float)
        zz = np.asarray(z, dtype=float)
        ss = np.zeros((tt.size, 3)) if sensor is None else np.asarray(sensor, dtype=float)
        return TurningTrack.from_steps([self.step(tt[k], zz[k], ss[k]) for k in range(tt.size)])


# ---------------------------------------------------------------------------
# seatrack track --method turning
# ---------------------------------------------------------------------------
#: config keys of :func:`track_plots` given in degrees (converted at this edge)
_DEGREE_KEYS = {
    "sigma_azimuth_deg": "sigma_azimuth",
    "sigma_elevation_deg": "sigma_elevation",
    "sigma_omega0_dps": "sigma_omega0",
    "delta_omega_threshold_dps": "delta_omega_threshold",
    "gain_reference_dps": "gain_reference",
}
_SI_KEYS = {
    "q": "q_nominal",
    "sigma_range_m": "sigma_range",
    "sigma_velocity0_mps": "sigma_velocity0",
}


def config_from_mapping(config: Mapping[str, Any]) -> TurningConfig:
    """Build a :class:`TurningConfig` from a ``--config`` mapping.

    Keys: any :class:`TurningConfig` field name (SI units, radians), or the edge forms
    ``q`` (m^2/s^3), ``sigma_range_m``, ``sigma_velocity0_mps``, ``sigma_azimuth_deg``,
    ``sigma_elevation_deg``, ``sigma_omega0_dps``, ``delta_omega_threshold_dps``,
    ``gain_reference_dps`` (degrees, deg/s). ``sigma_range_rate_mps``, one of the keys every
    track method accepts (:data:`seatrack.filters.registry.COMMON_CONFIG_KEYS`), is
    accepted and ignored: the method does not use range rate. Unknown keys raise
    ``ValueError``.
    """
    names = {f.name for f in fields(TurningConfig)}
    kw: dict[str, Any] = {}
    for key, val in config.items():
        if key == "sigma_range_rate_mps":
            continue
        if key in _DEGREE_KEYS:
            kw[_DEGREE_KEYS[key]] = math.radians(float(val))
        elif key in _SI_KEYS:
            kw[_SI_KEYS[key]] = float(val)
        elif key in names:
            kw[key] = val
        else:
            known = sorted(names | set(_DEGREE_KEYS) | set(_SI_KEYS))
            raise ValueError(f"turning: unknown config key {key!r}; known keys: {', '.join(known)}")
    return TurningConfig(**kw)


def track_plots(plots: Any, config: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """Run the turning-target filter over one :class:`seatrack.io.plots.PlotTrack`.

    Returns one value per plot for the common columns (``x_m`` ... ``std_z_m``; ``z_m``,
    ``vz_mps`` and ``std_z_m`` are NaN for 2-D plots) plus ``speed_mps`` (horizontal),
    ``heading_deg`` ([0, 360), clockwise from North), ``turn_rate_dps`` (clockwise
    positive; NaN until the heading filter starts), ``turn_rate_std_dps``, ``turn_state``
    (``straight`` / ``rising`` / ``falling``) and ``q_gain`` (gain applied to ``Q_nom``
    in that scan's prediction).
    """
    cfg = config_from_mapping(config)
    d = 3 if plots.elevation is not None else 2
    cols = [plots.range, plots.azimuth] + ([plots.elevation] if d == 3 else [])
    z = np.stack(cols, -1)
    res = TurningFilter(cfg, d).run(plots.t, z, plots.sensor)
    n = res.t.size
    nan = np.full(n, np.nan)
    std = np.sqrt(np.diagonal(res.P, axis1=-2, axis2=-1))
    out: dict[str, np.ndarray] = {
        "x_m": res.x[:, 0],
        "y_m": res.x[:, 1],
        "z_m": res.x[:, 2] if d == 3 else nan,
        "vx_mps": res.x[:, d],
        "vy_mps": res.x[:, d + 1],
        "vz_mps": res.x[:, 5] if d == 3 else nan.copy(),
        "std_x_m": std[:, 0],
        "std_y_m": std[:, 1],
        "std_z_m": std[:, 2] if d == 3 else nan.copy(),
        "speed_mps": res.speed,
        "heading_deg": np.degrees(res.heading),
        "turn_rate_dps": np.degrees(res.turn_rate),
        "turn_rate_std_dps": np.degrees(res.turn_rate_std),
        "turn_state": np.array([TurnState(s).label for s in res.state]),
        "q_gain": res.q_gain,
    }
    return out
