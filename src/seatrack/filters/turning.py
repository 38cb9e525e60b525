"""Turning-target radar plot filter (CN 104407337 A; spec ``docs/turning.md``).

A constant-velocity EKF on radar plots (range, azimuth[, elevation]) whose process noise
is raised for the next scan only when a second filter, running on the EKF's heading,
decides by a fuzzy sequential vote that the turn rate is rising or falling.

Steps of the spec, each a small pure function here (arrays in, arrays out; the ones that
are plain arithmetic broadcast over leading dimensions):

* S1 :func:`ekf_step` -- CV-EKF predict + update on one plot (``seatrack.kalman``,
  ``seatrack.models``); :func:`initial_state` starts it from the first plot.
* S2 in :mod:`seatrack.filters.heading` (pure reference functions; compiled in
  :mod:`seatrack.filters.turning_kernel`): ``velocity_significance`` (``d_t``),
  ``heading``, ``heading_variance``, ``heading_filter_init`` / ``heading_filter_step``
  (the (b, omega) filter with the wrapped heading innovation).
* S3 :func:`turn_rate_significance` (``d_omega``) and :func:`push_turn_rate` (FIFO queue).
* S4 :func:`fuzzy_vote` (rising / falling count vote with the ``delta_omega`` threshold).
* S5 :func:`noise_gain` ``c(delta_omega)``; the gain applies to the next prediction only
  and returns to 1 (nominal ``Q``) on any scan where S5 does not fire.
* S6 the output point: :class:`TurningStep` (one scan) / :class:`TurningTrack` (a run).

:class:`Turning` is the method on the filter contract (``seatrack track --method
turning``): the whole batch of tracks per step, S1 through :mod:`seatrack.kalman`, S2-S5
compiled (:mod:`seatrack.filters.turning_kernel`, equal to the pure functions above); its
state (heading filter, turn-rate queue, gain) is explicit in ``TrackState.aux``.
:class:`TurningFilter` is a one-track, plot-by-plot shell over it.

Conventions: x East, y North, z Up; SI units and radians inside. Heading and azimuth are
clockwise from North (``atan2(vE, vN)``); the heading-filter state and every angle
difference are wrapped to ``(-pi, pi]`` (the spec writes ``[-pi, pi)``; the project
convention is used, the two differ only at the single point ``-pi``). The turn rate is
``d(heading)/dt``, i.e. positive clockwise (to starboard), as in
:class:`seatrack.models.CoordinatedTurn`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import fields
from enum import IntEnum
from functools import lru_cache
from typing import Any
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack import kalman
from seatrack.config import Checked
from seatrack.config import param
from seatrack.filters.base import CartesianState
from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import common_columns
from seatrack.filters.base import finish_update
from seatrack.filters.base import plot_gaussian
from seatrack.filters.base import predicted
from seatrack.filters.base import speed_sigma_param
from seatrack.filters.base import step_times
from seatrack.filters.base import usable
from seatrack.filters.base import wrap_angles
from seatrack.filters.turning_kernel import turn_logic
from seatrack.geometry import bearing
from seatrack.models import RangeBearing
from seatrack.models import RangeBearingElevation
from seatrack.models.measurement import polar_measurement
from seatrack.models.motion import cv_matrices
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition
from seatrack.models.targets import TargetClass

FloatArray = NDArray[np.float64]

__all__ = [
    "sigma_omega0_param",
    "TurnState",
    "TurningConfig",
    "TurningStep",
    "TurningTrack",
    "TurningFilter",
    "Turning",
    "initial_state",
    "ekf_step",
    "turn_rate_significance",
    "push_turn_rate",
    "fuzzy_vote",
    "noise_gain",
    "heading_columns",
]


class TurnState(IntEnum):
    """Decision of the fuzzy sequential test (spec S4) at one scan."""

    STRAIGHT = 0  #: no decision fired (includes "not enough significant turn rates yet")
    RISING = 1  #: turn rate increasing (algebraically; clockwise positive)
    FALLING = 2  #: turn rate decreasing

    @property
    def label(self) -> str:
        return self.name.lower()


#: the ``turn_state`` output labels, indexed by :class:`TurnState` value
_TURN_LABELS = np.array([s.label for s in TurnState])


# ---------------------------------------------------------------------------
# Configuration
# ---------------------------------------------------------------------------
def sigma_omega0_param(doc: str) -> Any:
    """The ``sigma_omega0_dps`` field: the heading filter's initial turn-rate std (deg/s at
    the edge, 0.1 rad/s by default; bounded so that its inverse variance and its square stay
    finite)."""
    return param(
        math.degrees(0.1), key="sigma_omega0_dps", unit="deg/s", doc=doc, min=1e-6, max=1e4
    )


@dataclass(frozen=True)
class TurningConfig(Checked):
    """Parameters of the turning-target filter (defaults from ``docs/turning.md``); the
    plot noise is the shared sensor section (:class:`~seatrack.filters.base.SensorNoise`).

    Keys (``--config``) in brackets; fields are SI and radians.

    Parameters
    ----------
    q_nominal : [``q``] S1 nominal process noise: white-acceleration PSD of the CV-EKF,
        m^2/s^3 ([reading] continuous white-noise acceleration, ``Q_nom = q cv_noise``).
        Not given in the patent; choose for the target class (``benchmarks/turning.py``).
    sigma_velocity0 : [``initial_speed_sigma_mps``] standard deviation of the initial
        velocity (m/s per axis): the EKF starts at the first plot with zero velocity.
    velocity_threshold : S2 threshold on ``d_t = sum v_i^2 / sigma_i^2``; ``None`` = N, the
        number of velocity components (2 or 3), as in the spec.
    heading_cross_covariance : S2 heading variance from the full 2x2 horizontal velocity
        covariance instead of the spec's diagonal-only formula (default False = the spec).
    sigma_omega0 : [``sigma_omega0_dps``] S2 initial turn-rate std of the heading filter
        ([reading] "large, configurable"; 0.1 rad/s ~ 5.7 deg/s).
    q_heading : S2 heading-filter process noise ``q`` (rad^2/s^3), spec value 1e-6.
    heading_noise : {"continuous", "diagonal"} S2 form of the heading-filter noise
        ([reading]): ``q [[D^3/3, D^2/2], [D^2/2, D]]`` or ``q diag(D^3/3, D)``.
    turn_rate_threshold : S3 threshold on ``d_omega = |omega / sigma_omega|`` (spec: 1).
    queue_length : S3/S4 ``M`` (> 3; not given in the patent, default 5).
    count_min : S4 count condition ``N >= K``; ``None`` = ``M - 2`` ([reading] "fuzzy" vote
        tolerating one violated comparison).
    delta_omega_threshold : [``delta_omega_threshold_dps``] S4 threshold on
        ``delta_omega = |omega_M - omega_1|``, rad/s (spec: 0.02).
    gain_reference, gain_power, gain_max : S5
        ``c = clip((delta_omega / gain_reference) ** gain_power, 1, gain_max)`` ([reading]
        formula missing; default ``(delta_omega / 0.02)^2`` capped at 100);
        ``gain_reference`` key ``gain_reference_dps``.
    sigma_accel : [``sigma_accel_mps2``] the nominal noise as an acceleration std, m/s^2:
        ``q = sigma_accel^2 T`` at each scan (overrides ``q``; a ``target`` class sets it,
        :meth:`for_target`).
    """

    q_nominal: float = param(
        0.5, key="q", unit="m^2/s^3", doc="nominal white-acceleration PSD", min=0,
        exclusive_min=True,
    )  # fmt: skip
    sigma_velocity0: float = speed_sigma_param(300.0, aliases=("sigma_velocity0_mps",))
    velocity_threshold: float | None = param(None, doc="S2 threshold on d_t (None: N)", min=0)
    heading_cross_covariance: bool = param(False, doc="S2 heading variance with cross term")
    sigma_omega0: float = sigma_omega0_param("S2 initial turn-rate std")
    q_heading: float = param(
        1e-6, unit="rad^2/s^3", doc="S2 heading-filter PSD", min=0, exclusive_min=True
    )
    heading_noise: str = param(
        "continuous", choices=("continuous", "diagonal"), doc="S2 heading-filter noise form"
    )
    turn_rate_threshold: float = param(1.0, doc="S3 threshold on d_omega", min=0)
    queue_length: int = param(5, doc="S3/S4 queue length M (> 3)", max=1000)
    count_min: int | None = param(None, doc="S4 count K (None: M - 2)")
    delta_omega_threshold: float = param(
        math.degrees(0.02), key="delta_omega_threshold_dps", unit="deg/s",
        doc="S4 threshold on delta omega", min=0,
    )  # fmt: skip
    gain_reference: float = param(
        math.degrees(0.02), key="gain_reference_dps", unit="deg/s", doc="S5 gain reference",
        min=0, exclusive_min=True,
    )  # fmt: skip
    gain_power: float = param(2.0, doc="S5 gain power", min=0)
    gain_max: float = param(100.0, doc="S5 gain cap (>= 1)", min=1)
    sigma_accel: float | None = param(
        None, key="sigma_accel_mps2", unit="m/s^2",
        doc="nominal noise as an acceleration std, q = a^2 T (set by a target; overrides q)",
        min=0, exclusive_min=True, max=1e4,
    )  # fmt: skip

    @classmethod
    def for_target(cls, target: TargetClass) -> TurningConfig:
        """What the patent leaves open, from a target class: the nominal (narrow-band) noise
        of straight legs ``a_steady^2 T``, the initial speed std (the class's maximum speed)
        and turn-rate std (its maximum turn rate)."""
        return cls(
            sigma_accel=target.accel_steady,
            sigma_velocity0=target.speed_max,
            sigma_omega0=target.turn_rate_max,
        )

    def __post_init__(self) -> None:
        super().__post_init__()
        positive = (
            "q_nominal",
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
    def initial_speed_sigma(self) -> float:
        """The initiator's velocity std (m/s): ``sigma_velocity0``."""
        return self.sigma_velocity0

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
    """CV state and covariance from one plot ([reading]; spec S1 gives no initialisation):
    the one initiator :func:`seatrack.filters.base.plot_gaussian` on one plot.

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
    sd = np.sqrt(np.diagonal(np.asarray(R, dtype=float)))
    sensor_noise = SensorNoise(sd[0], sd[1], sd[2] if d == 3 else sd[1])
    s = np.zeros((1, 3)) if sensor is None else np.asarray(sensor, dtype=float)[None]
    plots = Plots(np.zeros(1), zz[:1], zz[1:2], zz[2:3] if d == 3 else None, sensor=s)
    x, P = plot_gaussian(plots, sensor_noise, sigma_velocity0, range_rate=False)
    return x[0], P[0]


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
# The filter on the contract (batched), and the one-track shell
# ---------------------------------------------------------------------------
class Turning(CartesianState):
    """The turning-target filter (spec S1-S6) on the filter contract, for a batch of tracks.

    ``TrackState.x``/``P``: the CV-EKF state ``[x, y, (z), vx, vy, (vz)]``. ``aux``: the
    heading filter ``hs (B, 2)``, ``hP (B, 2, 2)``, ``ht (B,)`` (NaN until it starts), the
    turn-rate queue ``queue (B, M)`` with ``qn (B,)`` values, the gain for the next
    prediction ``gain``, and the diagnostics of the last step (``q_gain`` applied,
    ``d_t``, ``d_w``, ``turn_state``). Every step is a few NumPy operations on the batch.
    """

    Config = TurningConfig
    dims: ClassVar[tuple[int, ...]] = (2, 3)

    def __init__(
        self,
        config: TurningConfig | None = None,
        sensor: SensorNoise | None = None,
        d: int = 2,
        range_rate: bool = False,
    ) -> None:
        self.config = c = config if config is not None else TurningConfig()
        self.sensor = sensor or SensorNoise()
        self.model = measurement_model(d)  # validates d
        self.d = d
        self.range_rate = False  # the method does not use range rate
        sn = self.sensor
        self.R = plot_covariance(sn.sigma_range, sn.sigma_azimuth, sn.sigma_elevation, d)
        self._angular = self.model.angular.astype(float)
        self.v_threshold = float(d) if c.velocity_threshold is None else c.velocity_threshold

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        st = TrackState.new(t, x, P)
        B = len(st)
        aux = self.heading_aux(B) | {"gain": np.ones(B), "q_gain": np.ones(B)}
        return st.replace(aux=aux | self.heading_logic(st.replace(aux=aux)))

    def heading_aux(self, B: int) -> dict[str, Any]:
        """Initial (empty) heading filter and turn-rate queue of ``B`` tracks."""
        return {
            "hs": np.zeros((B, 2)),
            "hP": np.zeros((B, 2, 2)),
            "ht": np.full(B, np.nan),
            "queue": np.full((B, self.config.queue_length), np.nan),
            "qn": np.zeros(B, np.int64),
        }

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        tt, dt = step_times(state, t)
        gain = state.aux["gain"]
        c = self.config
        if c.sigma_accel is None:
            F, Q = cv_matrices(dt, c.q_nominal, self.d)
        else:  # q = a^2 T each scan (a target class)
            F, Q = cv_transition(dt, self.d), cv_noise(dt, c.sigma_accel**2 * dt, self.d)
        x, P = kalman.predict(state.x, state.P, F, Q * gain[:, None, None])
        return predicted(state, tt, x, P, {"q_gain": gain, "gain": np.ones(len(state))})

    def _measurement(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        s = np.concatenate([plots.sensor[:, : self.d], plots.sensor_vel[:, : self.d]], -1)
        return polar_measurement(state.x, s, self.d, False)

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        hx, H = self._measurement(state, plots)
        y = wrap_angles(plots.polar(False) - hx, self._angular)
        return y, kalman.symmetrize(H @ state.P @ np.swapaxes(H, -1, -2) + self.R)

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        hx, H = self._measurement(state, plots)
        z, ok = usable(plots.polar(False), hx)
        with np.errstate(all="ignore"):
            res = kalman.extended_update(
                state.x, state.P, z, hx, H, self.R, self._angular, check=False
            )
            aux = self.heading_logic(state.replace(x=res.x, P=res.P))
        return finish_update(state, res.x, res.P, res.nis, res.log_likelihood, state.t, aux, ok)

    def heading_logic(self, st: TrackState) -> dict[str, Any]:
        """S2-S5 on the filtered states of a batch (compiled: :func:`turn_logic`): the new
        heading filter, queue, decision ``turn_state`` and gain for the next prediction."""
        c, d, a = self.config, self.d, st.aux
        B = len(st)
        hs, hP, ht = a["hs"].copy(), a["hP"].copy(), a["ht"].copy()
        queue, qn = a["queue"].copy(), a["qn"].copy()
        d_t, d_w, gain = np.empty(B), np.empty(B), np.empty(B)
        state = np.empty(B, np.int8)
        turn_logic(
            st.x, st.P, st.t, d, hs, hP, ht, queue, qn, self.v_threshold,
            c.heading_cross_covariance, c.sigma_omega0, c.q_heading,
            c.heading_noise == "diagonal", c.turn_rate_threshold, c.count,
            c.delta_omega_threshold, c.gain_reference, c.gain_power, c.gain_max,
            d_t, d_w, state, gain,
        )  # fmt: skip
        return {
            "hs": hs, "hP": hP, "ht": ht, "queue": queue, "qn": qn, "gain": gain,
            "d_t": d_t, "d_w": d_w, "turn_state": state,
        }  # fmt: skip

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        cols: dict[str, NDArray[Any]] = dict(common_columns(state.x, state.P, self.d))
        cols |= heading_columns(state, self.d)
        cols["q_gain"] = state.aux["q_gain"]
        return cols


def heading_columns(state: TrackState, d: int) -> dict[str, NDArray[Any]]:
    """S6 output columns of a batch: speed, heading, the heading filter's turn rate and its
    std (NaN until it starts), the fuzzy vote's ``turn_state``."""
    a = state.aux
    v = state.x[:, d:]
    started = np.isfinite(a["ht"])
    std = np.sqrt(np.maximum(a["hP"][:, 1, 1], 0.0))
    return {
        "speed_mps": np.hypot(v[:, 0], v[:, 1]),
        "heading_deg": np.degrees(bearing(v[:, 0], v[:, 1])),
        "turn_rate_dps": np.degrees(np.where(started, a["hs"][:, 1], np.nan)),
        "turn_rate_std_dps": np.degrees(np.where(started, std, np.nan)),
        "turn_state": _TURN_LABELS[a["turn_state"]],
    }


class TurningFilter:
    """One track through :class:`Turning` (a batch of one): the plot-by-plot shell.

    Parameters
    ----------
    config : TurningConfig
    d : int -- 2 (plots = range, azimuth) or 3 (range, azimuth, elevation).
    sensor : SensorNoise -- plot noise (default: the shared sensor default).

    Examples
    --------
    >>> f = TurningFilter(TurningConfig(), d=2)
    >>> step = f.step(0.0, [10_000.0, 0.5])          # first plot initialises the track
    """

    def __init__(
        self, config: TurningConfig | None = None, d: int = 2, sensor: SensorNoise | None = None
    ) -> None:
        self.filter = Turning(config, sensor, d)
        self.config = self.filter.config
        self.d = d
        self.R = self.filter.R
        self.state: TrackState | None = None

    def reset(self) -> None:
        """Forget the track (the next plot initialises it)."""
        self.state = None

    def step(self, t: float, z: ArrayLike, sensor: ArrayLike | None = None) -> TurningStep:
        """Process the plot ``z`` (range m, azimuth rad[, elevation rad]) taken at time ``t`` s."""
        d = self.d
        zz = np.asarray(z, dtype=float)
        if zz.shape != (d,) or not np.all(np.isfinite(zz)):
            raise ValueError(f"plot at t={t} must be {d} finite values, got {zz.tolist()}")
        sens = np.zeros((1, 3)) if sensor is None else np.asarray(sensor, dtype=float)[None]
        plots = Plots(
            np.array([float(t)]), zz[:1], zz[1:2], zz[2:3] if d == 3 else None, sensor=sens
        )
        f = self.filter
        if self.state is None:
            x, P = plot_gaussian(plots, f.sensor, self.config.sigma_velocity0, False)
            self.state = f.initiate(plots.t, x, P)
        else:
            if not float(t) > self.state.t[0]:
                raise ValueError(f"plot times must increase: {t} after {self.state.t[0]}")
            self.state = f.update(f.predict(self.state, plots.t), plots)
        return _step_result(self.state, d)

    def run(self, t: ArrayLike, z: ArrayLike, sensor: ArrayLike | None = None) -> TurningTrack:
        """Filter a whole track from a fresh start: ``t`` (N,), ``z`` (N, d), ``sensor`` (N, 3)."""
        self.reset()
        tt = np.asarray(t, dtype=float)
        zz = np.asarray(z, dtype=float)
        ss = np.zeros((tt.size, 3)) if sensor is None else np.asarray(sensor, dtype=float)
        return TurningTrack.from_steps([self.step(tt[k], zz[k], ss[k]) for k in range(tt.size)])


def _step_result(st: TrackState, d: int) -> TurningStep:
    """:class:`TurningStep` of the first track of a batch."""
    a = st.aux
    x, P = st.x[0].copy(), st.P[0].copy()
    v = x[d:]
    started = bool(np.isfinite(a["ht"][0]))
    w = float(a["hs"][0, 1]) if started else math.nan
    sw = math.sqrt(a["hP"][0, 1, 1]) if started else math.nan
    applied = 1.0 if st.status[0] == PlotStatus.INITIATED else float(a["q_gain"][0])
    return TurningStep(
        float(st.t[0]), x, P, math.hypot(v[0], v[1]), float(bearing(v[0], v[1])), w, sw,
        float(a["d_t"][0]), float(a["d_w"][0]), TurnState(int(a["turn_state"][0])),
        applied, float(a["gain"][0]),
    )  # fmt: skip
