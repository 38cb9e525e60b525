"""Ramazanov's robust (algorithm R) and adaptive-robust (algorithm A) sonar tracking filter.

Spec: ``docs/robust.md`` (M. A. Ramazanov, "Synthesis of a robust tracking system for a
marine moving object", 2008). An active sonar on a (possibly moving) own ship measures
range ``Z^R`` and true bearing ``Z^AZ`` of a target. The filter works in the
**beam frame** (spec section "Beam frame"): the beam is steered to the predicted bearing
``Psi' = bearing(E', N')`` of the predicted relative position; along the beam (``xi``) the
predicted target sits at range ``R'`` and across it (``eta``, positive clockwise) at 0, so
each channel is a scalar linear filter with ``H = [1, 0(, 0)]``:

* range channel ``xi``: innovation ``Z^R - R'``, measurement variance ``q0 = sigma_R^2``;
* cross-range channel ``eta``: innovation ``R' * wrap(Z^AZ - Psi')`` (metres), measurement
  variance ``R'^2 sigma_AZ^2`` (``sigma_AZ`` in radians).

The covariance is kept block-diagonal in the beam frame (one ``k x k`` block per channel,
``k = 2`` for the truncated [position, velocity] state, ``k = 3`` with acceleration). The
state itself is kept in the fixed (East, North) frame, as the target's absolute state (the
own-ship motion enters through the known sensor positions, equivalent to the paper's
relative state with own-ship velocity in the position rates); the beam-frame corrections
are rotated back with the transpose of :func:`seatrack.geometry.rotation_to_beam`:
``dE = s dxi + c deta``, ``dN = c dxi - s deta`` (``c = cos Psi'``, ``s = sin Psi'``; eta
positive clockwise, like the bearing innovation), exactly the spec's formula.
The first plots initialise the filter (:func:`initial_state`: median of the first three
plots, not in the paper, so that one anomalous first plot cannot lock the filter out).

Algorithm R (spec "Algorithm R"), per channel ``c`` and step:

1. ``S' = Phi S``; ``P'^c = Phi P^c Phi^T + L0`` (constant disturbance noise ``L0``);
2. innovation ``z^c`` as above;
3. ``J^c = (z^c)^2 / (H P'^c H^T + q0^c)``; ``gamma^c = [J^c > Delta^c]``;
4. ``q1^c = (z^c)^2 / Delta^c - H P'^c H^T``;
5. ``K^c = P'^c H^T / (H P'^c H^T + (1 - gamma^c) q0^c + gamma^c q1^c)``, i.e. the
   innovation variance is ``max(S0, z^2 / Delta)``: with ``u = z / sqrt(S0)`` the influence
   function is ``psi(u) = u`` for ``|u| <= sqrt(Delta)`` and ``Delta / u`` beyond, so the
   correction grows linearly up to ``|z| = sqrt(Delta S0)`` (at most
   ``P'[:, 0] sqrt(Delta / S0)``) and then redescends as ``P'[:, 0] Delta / z``;
6. ``P^c`` by the Joseph form with the effective measurement variance
   ``(1 - gamma) q0 + gamma q1`` (equal to ``(I - K H) P'`` for this optimal-for-it gain, but
   symmetric PD under round-off); the correction is rotated back to (E, N).

Algorithm A (spec "Algorithm A", eqs. 5-9) adds a windowed divergence test: the statistics
``J^c`` of the last ``n`` steps are summed (optionally each capped at ``Delta^c`` first
[reading], so that one outlier cannot trigger adaptation) and, while ``J_sum^c >
Delta_sum^c``, extra noise ``L^c_k = P^c_{k-1} / l_factor^c`` (``P/3`` along, ``P/10`` across
the beam in the paper) is injected into that channel's prediction. ``J_k`` is computed from
the prediction *without* the injected noise (it is what decides the injection); the gain
then uses the final ``P'`` and, with ``robust_gain=True`` [reading], the robust variance of
algorithm R (otherwise the nominal ``q0``).

[reading] choices, all switches of :class:`RobustConfig`: ``robust_gain`` (robust q inside
A), ``cap_j`` (cap each J at Delta before the window sum), ``base_noise`` (A keeps the
constant ``L0`` too), ``rotate_covariance`` (re-express the channel blocks in the new beam
frame by the bearing change ``dPsi`` -- ``P^xi <- c^2 P^xi + s^2 P^eta``,
``P^eta <- s^2 P^xi + c^2 P^eta``, the diagonal blocks of the rotated block-diagonal matrix
-- the paper does not rotate). The robust outlier test in the gain (steps 3-5) is evaluated
with the final predicted covariance (for R this is the only one).

Everything is vectorised over a leading batch axis (Monte-Carlo runs or independent
tracks); the time loop is in Python, each step a handful of NumPy operations on
``(B, 2, k)`` arrays plus one call of the compiled :func:`seatrack.kalman.update`.

Units: metres, seconds, radians; x = East, y = North; bearings clockwise from North.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray
from scipy.stats import chi2

from seatrack.config import Checked
from seatrack.config import is_positive_integer
from seatrack.config import is_positive_number
from seatrack.config import require
from seatrack.geometry import angle_diff
from seatrack.geometry import bearing
from seatrack.geometry import polar_to_cart
from seatrack.geometry import rotation_to_beam
from seatrack.kalman import extended_predict
from seatrack.kalman import update
from seatrack.models.motion import ca_transition
from seatrack.models.motion import cv_noise_discrete
from seatrack.models.motion import cv_transition

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

__all__ = [
    "SonarModel",
    "RobustConfig",
    "TrackEstimates",
    "axis_transition",
    "axis_noise",
    "per_axis_to_flat",
    "beam_to_cartesian_cov",
    "cartesian_to_beam_state",
    "beam_innovations",
    "robust_variance",
    "rotate_blocks",
    "initial_state",
    "BeamState",
    "StepInfo",
    "robust_step",
    "robust_update",
    "robust_filter",
    "check_track_inputs",
]


# ---------------------------------------------------------------------------
# Configuration and results
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class SonarModel:
    """Sensor and motion model shared by the robust filters and their baselines.

    Parameters
    ----------
    sigma_range : float
        Nominal range noise standard deviation, m (``q0 = sigma_range^2``; paper 1.5 m).
    sigma_bearing : float
        Nominal bearing noise standard deviation, rad (paper 2 deg).
    sigma_a : float
        Constant disturbance ``L0`` per axis: truncated state -- std of the piecewise-constant
        white acceleration, m/s^2 (``G = [dt^2/2, dt]``, Bar-Shalom et al. 2001 sec. 6.3.2);
        full state -- std of the acceleration increment per step, m/s^2
        (``G = [dt^2/2, dt, 1]``, discrete Wiener acceleration, sec. 6.3.3).
    acceleration : bool
        False: truncated state [position, velocity] per axis (the paper's simulations);
        True: full state [position, velocity, acceleration] per axis (``j = 2``).
    init_sigma_v : float
        Prior std of each velocity component at the first plot, m/s.
    init_plots : int
        The initial position is taken from the median range and the (circular) median
        bearing of the first ``init_plots`` plots, so that one anomalous first plot cannot
        put a filter with a small covariance out of lock (not in the paper; 1 = first plot).
    init_inflation : float
        Multiplier of the nominal position variances ``sigma_R^2``, ``(R sigma_AZ)^2`` of the
        initial covariance.
    init_sigma_acc : float
        Prior std of each acceleration component (full state), m/s^2.
    """

    sigma_range: float = 1.5
    sigma_bearing: float = float(np.deg2rad(2.0))
    sigma_a: float = 0.02
    acceleration: bool = False
    init_sigma_v: float = 8.0
    init_sigma_acc: float = 0.2
    init_plots: int = 3
    init_inflation: float = 4.0

    def __post_init__(self) -> None:
        require(self, ("init_plots",), is_positive_integer, "a positive integer")
        positive = (
            "sigma_range",
            "sigma_bearing",
            "init_sigma_v",
            "init_sigma_acc",
            "init_inflation",
        )
        require(self, positive, is_positive_number, "a positive number")
        require(self, ("sigma_a",), lambda v: np.isfinite(v) and v >= 0, ">= 0")

    @property
    def order(self) -> int:
        """States per axis / channel (2 truncated, 3 full)."""
        return 3 if self.acceleration else 2


def _frozen(values: list[float]) -> FloatArray:
    a = np.array(values, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class RobustConfig(Checked):
    """Thresholds and switches of algorithms R and A (spec "Algorithm R", "Algorithm A").

    Parameters
    ----------
    delta_range, delta_bearing : float
        Outlier thresholds ``Delta^xi``, ``Delta^eta`` on ``J = z^2 / S0`` (chi-square, 1 dof;
        [reading] 3.84 = 95 %, 6.63 = 99 % quantile). Default 3.84.
    window : int
        Length ``n`` of the J window of algorithm A (paper: 2...4).
    delta_sum_range, delta_sum_bearing : float or None
        Divergence thresholds ``Delta_Sigma`` on the windowed sum; None -> the 95 % quantile
        of chi-square with ``window`` dof (7.81 for n = 3). [reading] With ``cap_j`` the sum
        cannot exceed ``window * Delta``, so a 99 % quantile (11.34) would almost never fire
        with Delta = 3.84; at 95 % one capped outlier needs the other ``n - 1`` nominal J to
        add up to more than ``Delta_Sigma - Delta`` (3.97) as well.
    l_factor_range, l_factor_bearing : float
        Injected noise ``L^c = P^c / l_factor`` (paper: 3 along the beam, 10 across it).
    robust_gain : bool
        [reading] use the robust variance of R in the gain of A (else the nominal q0).
    cap_j : bool
        [reading] cap each J at its Delta before the window sum.
    base_noise : bool
        [reading] A keeps the constant disturbance noise L0 in every prediction.
    rotate_covariance : bool
        [reading] re-block the channel covariances in the new beam frame each step
        (the paper does not).
    """

    delta_range: float = 3.84
    delta_bearing: float = 3.84
    window: int = 3
    delta_sum_range: float | None = None
    delta_sum_bearing: float | None = None
    l_factor_range: float = 3.0
    l_factor_bearing: float = 10.0
    robust_gain: bool = True
    cap_j: bool = True
    base_noise: bool = True
    rotate_covariance: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        positive = ("delta_range", "delta_bearing", "l_factor_range", "l_factor_bearing")
        require(self, positive, is_positive_number, "a positive number")
        require(self, ("window",), is_positive_integer, "a positive integer")
        sums = ("delta_sum_range", "delta_sum_bearing")
        require(
            self, sums, lambda v: v is None or is_positive_number(v), "a positive number or None"
        )

    @cached_property
    def delta(self) -> FloatArray:
        """``[Delta^xi, Delta^eta]`` (read-only, computed once)."""
        return _frozen([self.delta_range, self.delta_bearing])

    @cached_property
    def delta_sum(self) -> FloatArray:
        """``[Delta_Sigma^xi, Delta_Sigma^eta]`` (defaults resolved; read-only, computed once)."""
        d = float(chi2.ppf(0.95, self.window))
        return _frozen(
            [
                d if self.delta_sum_range is None else self.delta_sum_range,
                d if self.delta_sum_bearing is None else self.delta_sum_bearing,
            ]
        )

    @cached_property
    def l_factor(self) -> FloatArray:
        """``[l_factor^xi, l_factor^eta]`` (read-only, computed once)."""
        return _frozen([self.l_factor_range, self.l_factor_bearing])


@dataclass(frozen=True)
class TrackEstimates:
    """Filter output for a batch of tracks, one row per plot.

    Attributes
    ----------
    x : (B, N, 2k) state [x, y, vx, vy(, ax, ay)], m, m/s(, m/s^2), East/North
    P : (B, N, 2k, 2k) covariance in the same layout (Cartesian)
    outlier : (B, N, 2) bool -- [range, bearing] measurement flagged anomalous
    adapting : (B, N, 2) bool -- [along-beam, cross-beam] channel with injected noise
    """

    x: FloatArray
    P: FloatArray
    outlier: BoolArray
    adapting: BoolArray


# ---------------------------------------------------------------------------
# Pure functions
# ---------------------------------------------------------------------------
def axis_transition(dt: ArrayLike, order: int) -> FloatArray:
    """Per-axis polynomial transition ``Phi`` (spec "Filter model"): ``order`` 2 gives
    ``[[1, dt], [0, 1]]`` (:func:`~seatrack.models.motion.cv_transition` of one axis), 3 adds
    the acceleration (:func:`~seatrack.models.motion.ca_transition` of one axis)."""
    if order == 2:
        return cv_transition(dt, d=1)
    if order == 3:
        return ca_transition(dt, d=1)
    raise ValueError(f"order must be 2 or 3, got {order}")


def axis_noise(dt: ArrayLike, sigma: float, order: int) -> FloatArray:
    """Per-axis disturbance noise ``L0 = sigma^2 G G^T`` (see :class:`SonarModel`).

    Order 2: piecewise-constant white acceleration, ``G = [dt^2/2, dt]``
    (:func:`~seatrack.models.motion.cv_noise_discrete` of one axis); order 3: discrete
    Wiener-process acceleration, ``G = [dt^2/2, dt, 1]`` (Bar-Shalom et al. 2001, 6.3.3).
    """
    if order == 2:
        return cv_noise_discrete(dt, sigma, d=1)
    if order != 3:
        raise ValueError(f"order must be 2 or 3, got {order}")
    t = np.asarray(dt, dtype=float)
    g = np.stack([0.5 * t * t, t, np.ones_like(t)], -1)
    return np.asarray((sigma * sigma) * g[..., :, None] * g[..., None, :])


def per_axis_to_flat(block: ArrayLike) -> FloatArray:
    """Per-axis ``(..., k, k)`` block, same for East and North, to the flat Cartesian
    layout ``[x, y, vx, vy, ...]`` ``(..., 2k, 2k)`` (Kronecker product with I_2)."""
    b = np.asarray(block, dtype=float)
    k = b.shape[-1]
    return np.einsum("...ij,ab->...iajb", b, np.eye(2)).reshape(b.shape[:-2] + (2 * k, 2 * k))


def beam_to_cartesian_cov(Pc: ArrayLike, psi: ArrayLike) -> FloatArray:
    """Block-diagonal beam-frame covariance to the Cartesian layout.

    Parameters
    ----------
    Pc : (..., 2, k, k)
        ``[P^xi, P^eta]`` channel covariances in the beam frame of bearing ``psi``.
    psi : (...) rad
        Beam bearing.

    Returns
    -------
    (..., 2k, 2k) covariance of ``[x, y, vx, vy, ...]``:
    ``C[(i,a),(j,b)] = sum_c R[c,a] R[c,b] P^c[i,j]`` with ``R = rotation_to_beam(psi)``.
    """
    P = np.asarray(Pc, dtype=float)
    R = rotation_to_beam(psi)
    k = P.shape[-1]
    C = np.einsum("...ca,...cb,...cij->...iajb", R, R, P)
    return C.reshape(P.shape[:-3] + (2 * k, 2 * k))


def cartesian_to_beam_state(X: ArrayLike, psi: ArrayLike) -> FloatArray:
    """Per-axis state ``(..., 2, k)`` (rows East, North) to the beam frame (rows xi, eta)."""
    return np.einsum("...ca,...ai->...ci", rotation_to_beam(psi), np.asarray(X, dtype=float))


def beam_innovations(
    pos_pred: ArrayLike, sensor: ArrayLike, z_range: ArrayLike, z_bearing: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Beam bearing, predicted range and the two channel innovations (spec "Beam frame").

    Parameters
    ----------
    pos_pred : (..., 2) predicted target position (East, North), m
    sensor : (..., 2) sensor position, m
    z_range : (...) measured range, m
    z_bearing : (...) measured true bearing, rad

    Returns
    -------
    psi : (...) predicted bearing ``Psi'``, rad in [0, 2 pi)
    r_pred : (...) predicted range ``R'``, m
    innov : (..., 2) ``[Z^R - R', R' wrap(Z^AZ - Psi')]``, m
    """
    d = np.asarray(pos_pred, dtype=float) - np.asarray(sensor, dtype=float)
    psi = np.asarray(bearing(d[..., 0], d[..., 1]))
    r = np.hypot(d[..., 0], d[..., 1])
    innov = np.stack([np.asarray(z_range) - r, r * angle_diff(z_bearing, psi)], -1)
    return psi, r, innov


def robust_variance(
    innov: ArrayLike, hph: ArrayLike, q0: ArrayLike, delta: ArrayLike
) -> tuple[FloatArray, BoolArray]:
    """Effective measurement variance of algorithm R, steps 3-5.

    ``gamma = [z^2 / (hph + q0) > Delta]``; ``q = (1 - gamma) q0 + gamma (z^2 / Delta - hph)``,
    so that ``hph + q = max(hph + q0, z^2 / Delta)``. Returns ``(q, gamma)``; ``q >= q0``.
    """
    z2 = np.square(innov)
    s0 = np.asarray(hph) + np.asarray(q0)
    gamma = z2 > np.asarray(delta) * s0
    q = np.where(gamma, z2 / np.asarray(delta) - hph, q0)
    return np.asarray(q, dtype=float), np.asarray(gamma)


def rotate_blocks(Pc: ArrayLike, dpsi: ArrayLike) -> FloatArray:
    """Re-block channel covariances ``(..., 2, k, k)`` after the beam turns by ``dpsi`` rad.

    The block-diagonal covariance is rotated by ``dpsi`` and its off-diagonal blocks dropped:
    ``P^xi <- c^2 P^xi + s^2 P^eta``, ``P^eta <- s^2 P^xi + c^2 P^eta`` (the trace is kept).
    """
    P = np.asarray(Pc, dtype=float)
    c2 = np.cos(dpsi)[..., None, None] ** 2
    s2 = 1.0 - c2
    return np.stack(
        [c2 * P[..., 0, :, :] + s2 * P[..., 1, :, :], s2 * P[..., 0, :, :] + c2 * P[..., 1, :, :]],
        -3,
    )


def initial_state(
    z: ArrayLike, sensor: ArrayLike, model: SonarModel
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Initialisation from the first plots: position, zero velocity (and acceleration).

    Parameters
    ----------
    z : (..., M, 2) the first plots ``[range m, bearing rad]`` (``model.init_plots`` of them
        are used; NaN entries ignored; the first plot must be finite).
    sensor : (..., 2+) sensor position at the first plot, m.

    Returns
    -------
    X : (..., 2, k) per-axis state (rows East, North), position at the median range and
        circular-median bearing (relative to the first plot) of the first plots, placed
        relative to the sensor position at the first plot.
    Pc : (..., 2, k, k) beam-frame channel covariances ``diag(f sigma_R^2, sigma_v^2(,
        sigma_acc^2))`` and ``diag(f (R sigma_AZ)^2, ...)`` with ``f = init_inflation``.
    psi : (...) beam bearing (the initial bearing), rad.
    """
    zz = np.asarray(z, dtype=float)[..., : model.init_plots, :]
    first = zz[..., 0, 1]
    r = np.nanmedian(zz[..., 0], axis=-1)
    az = np.asarray(first + np.nanmedian(angle_diff(zz[..., 1], first[..., None]), axis=-1))
    k = model.order
    pos = np.asarray(sensor, dtype=float)[..., :2] + polar_to_cart(r, az)
    X = np.zeros(r.shape + (2, k))
    X[..., 0] = pos
    tail = [model.init_sigma_v**2, model.init_sigma_acc**2][: k - 1]
    Pc = np.zeros(r.shape + (2, k, k))
    Pc[..., 0, 0, 0] = model.init_inflation * model.sigma_range**2
    Pc[..., 1, 0, 0] = model.init_inflation * (r * model.sigma_bearing) ** 2
    for i, v in enumerate(tail, start=1):
        Pc[..., :, i, i] = v
    return X, Pc, az


def _flat_state(X: FloatArray) -> FloatArray:
    """Per-axis ``(..., 2, k)`` to flat ``(..., 2k)`` = ``[x, y, vx, vy, ...]``."""
    return np.swapaxes(X, -1, -2).reshape(X.shape[:-2] + (X.shape[-1] * 2,))


def check_track_inputs(
    t: ArrayLike, z: ArrayLike, sensor: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Validate and batch the filter inputs: ``t (N,)``, ``z (B, N, 2)``, ``sensor (B, N, 2)``.

    A single track (``z (N, 2)``, ``sensor (N, 2+)``) gets a batch axis of 1; the sensor is
    broadcast over the batch. Raises ValueError on bad shapes, non-increasing times or a
    non-finite first plot.
    """
    tt = np.asarray(t, dtype=float)
    zz = np.asarray(z, dtype=float)
    ss = np.asarray(sensor, dtype=float)
    if zz.ndim == 2:
        zz = zz[None]
    if ss.ndim == 2:
        ss = ss[None]
    if tt.ndim != 1 or zz.ndim != 3 or zz.shape[1] != tt.size or zz.shape[2] != 2:
        raise ValueError(
            f"expected t (N,) and z (B, N, 2) = [range m, bearing rad]; got {tt.shape}, {zz.shape}"
        )
    if ss.shape[-2] != tt.size or ss.shape[-1] < 2:
        raise ValueError(f"sensor must be (B, N, 2+) or (N, 2+); got {ss.shape}")
    if np.any(np.diff(tt) <= 0):
        raise ValueError("times must be strictly increasing")
    if not np.isfinite(zz[:, 0]).all():
        raise ValueError("the first plot of every track must have a finite range and bearing")
    ss = np.broadcast_to(ss[..., :2], zz.shape[:2] + (2,))
    return tt, zz, ss


# ---------------------------------------------------------------------------
# The filter
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class BeamState:
    """Filter state between plots (batch axis first).

    Attributes
    ----------
    X : (B, 2, k) per-axis state, rows East, North: [position, velocity(, acceleration)]
    Pc : (B, 2, k, k) channel covariances ``[P^xi, P^eta]`` in the beam frame of ``psi``
    psi : (B,) beam bearing of the last update, rad
    jwin : (B, 2, n) the last ``n`` (capped) statistics J, newest first (algorithm A)
    """

    X: FloatArray
    Pc: FloatArray
    psi: FloatArray
    jwin: FloatArray


@dataclass(frozen=True)
class StepInfo:
    """Diagnostics of one :func:`robust_step` (batch axis first; channel order [xi, eta]).

    Attributes
    ----------
    innov : (B, 2) beam-frame innovations, m
    q0 : (B, 2) nominal measurement variances ``[sigma_R^2, R'^2 sigma_AZ^2]``, m^2
    P_pred : (B, 2, k, k) the predicted channel covariances used in the gain
    q : (B, 2) effective measurement variances used in the gain, m^2
    outlier : (B, 2) bool, gamma of step 3
    adapting : (B, 2) bool, divergence flag of algorithm A
    """

    innov: FloatArray
    q0: FloatArray
    P_pred: FloatArray
    q: FloatArray
    outlier: BoolArray
    adapting: BoolArray


def robust_step(
    state: BeamState,
    z: ArrayLike,
    sensor: ArrayLike,
    dt: float,
    model: SonarModel,
    config: RobustConfig,
    adaptive: bool,
) -> tuple[BeamState, StepInfo]:
    """One cycle (predict, beam-frame test, robust update) of algorithm R or A.

    Parameters
    ----------
    state : BeamState at the previous plot.
    z : (B, 2) ``[range m, true bearing rad]``; NaN components skip their channel.
    sensor : (B, 2) sensor position East, North, m.
    dt : seconds since the previous plot.
    model, config, adaptive : see :func:`robust_filter`.
    """
    m, c = model, config
    k = m.order
    zz = np.asarray(z, dtype=float)
    Phi = axis_transition(dt, k)
    use_base = (not adaptive) or c.base_noise
    L0 = axis_noise(dt, m.sigma_a, k) if use_base else np.zeros((k, k))
    Pc = state.Pc
    # 1. prediction (the state in (E, N); the channel covariances in the beam frame)
    Xp = state.X @ Phi.T
    psi, r_pred, innov = beam_innovations(Xp[..., 0], sensor, zz[:, 0], zz[:, 1])
    if c.rotate_covariance:
        Pc = rotate_blocks(Pc, angle_diff(psi, state.psi))
    _, P0 = extended_predict(Xp, Pc, Phi, L0)
    return robust_update(Xp, P0, Pc, psi, r_pred, innov, state.jwin, m, c, adaptive)


def robust_update(
    Xp: FloatArray,
    P0: FloatArray,
    Pc_prev: FloatArray,
    psi: FloatArray,
    r_pred: FloatArray,
    innov: FloatArray,
    jwin: FloatArray,
    model: SonarModel,
    config: RobustConfig,
    adaptive: bool,
) -> tuple[BeamState, StepInfo]:
    """Steps 2-6 of algorithm R or A after the prediction (shared by :func:`robust_step`
    and the contract class :class:`Robust`).

    Parameters
    ----------
    Xp : (B, 2, k) predicted per-axis state; P0 : (B, 2, k, k) predicted channel blocks
        (in the new beam frame); Pc_prev : (B, 2, k, k) the previous blocks (algorithm A
        injects ``Pc_prev / l_factor``); psi, r_pred, innov : see :func:`beam_innovations`;
        jwin : (B, 2, n) the J window.
    """
    m, c = model, config
    k = m.order
    B = Xp.shape[0]
    H = np.zeros((1, k))
    H[0, 0] = 1.0
    # 2. innovations and their nominal variances (eta: R'^2 sigma_AZ^2, sigma in radians)
    q0 = np.stack([np.full(B, m.sigma_range**2), r_pred**2 * m.sigma_bearing**2], -1)
    valid = np.isfinite(innov)
    innov = np.where(valid, innov, 0.0)
    Pp = P0
    flag = np.zeros((B, 2), dtype=bool)
    if adaptive:
        # A: windowed divergence test on J computed without the injected noise
        J = innov**2 / (P0[..., 0, 0] + q0)
        if c.cap_j:
            J = np.minimum(J, c.delta)
        jwin = np.concatenate([np.where(valid, J, 0.0)[..., None], jwin[..., :-1]], -1)
        flag = jwin.sum(-1) > c.delta_sum
        Pp = P0 + np.where(flag[..., None, None], Pc_prev / c.l_factor[:, None, None], 0.0)
    # 3.-5. outlier test and robust variance with the final prediction
    q, gamma = robust_variance(innov, Pp[..., 0, 0], q0, c.delta)
    if adaptive and not c.robust_gain:
        q = q0
    gamma &= valid
    # 6. scalar Joseph-form update per channel; correction rotated back to (E, N)
    res = update(np.zeros((B, 2, k)), Pp, innov[..., None], H, q[..., None, None], False)
    dXb = np.where(valid[..., None], res.x, 0.0)
    Pc_new = np.where(valid[..., None, None], res.P, Pp)
    X = Xp + np.einsum("bca,bci->bai", rotation_to_beam(psi), dXb)
    return BeamState(X, Pc_new, psi, jwin), StepInfo(innov, q0, Pp, q, gamma, flag)


def robust_filter(
    t: ArrayLike,
    z: ArrayLike,
    sensor: ArrayLike,
    model: SonarModel | None = None,
    config: RobustConfig | None = None,
    adaptive: bool = False,
) -> TrackEstimates:
    """Run algorithm R (``adaptive=False``) or A (``adaptive=True``) over a batch of tracks.

    Parameters
    ----------
    t : (N,) s
        Plot times, strictly increasing, shared by the batch.
    z : (B, N, 2) or (N, 2)
        ``[range m, true bearing rad]`` per plot; NaN components are skipped (no update of
        that channel). The first plots initialise (:func:`initial_state`).
    sensor : (B, N, 2+) or (N, 2+)
        Sensor (own-ship) position East, North, m.
    model, config : SonarModel, RobustConfig (defaults of the spec).
    adaptive : bool
        Algorithm A (windowed divergence test and injected noise) instead of R.

    Returns
    -------
    TrackEstimates (batch axis first).
    """
    m = model or SonarModel()
    c = config or RobustConfig()
    tt, zz, ss = check_track_inputs(t, z, sensor)
    B, N, _ = zz.shape
    k = m.order
    X, Pc, psi = initial_state(zz, ss[:, 0], m)
    state = BeamState(X, Pc, psi, np.zeros((B, 2, c.window)))
    xs = np.empty((B, N, 2 * k))
    Ps = np.empty((B, N, 2 * k, 2 * k))
    outl = np.zeros((B, N, 2), dtype=bool)
    adapt = np.zeros((B, N, 2), dtype=bool)
    xs[:, 0] = _flat_state(X)
    Ps[:, 0] = beam_to_cartesian_cov(Pc, psi)
    for n in range(1, N):
        state, info = robust_step(state, zz[:, n], ss[:, n], tt[n] - tt[n - 1], m, c, adaptive)
        outl[:, n] = info.outlier
        adapt[:, n] = info.adapting
        xs[:, n] = _flat_state(state.X)
        Ps[:, n] = beam_to_cartesian_cov(state.Pc, state.psi)
    return TrackEstimates(xs, Ps, outl, adapt)
