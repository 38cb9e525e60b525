"""Motion models: transition matrices / functions, analytic Jacobians, process noise.

State layouts (1-D vectors, positions first, then velocities, then the rest):

* constant velocity (CV), ``d`` = 2 or 3 spatial dimensions: ``[x, y, (z), vx, vy, (vz)]``
* constant acceleration (CA): ``[x, y, (z), vx, vy, (vz), ax, ay, (az)]``
* coordinated turn (CT), 2-D: ``[x, y, vx, vy, omega]``; 3-D: ``[x, y, z, vx, vy, vz, omega]``
  (the vertical channel is CV). ``omega`` is the rate of change of course, rad/s,
  **positive clockwise** (to starboard), matching bearings clockwise from North:
  ``d(vx)/dt = omega * vy``, ``d(vy)/dt = -omega * vx``.

x East, y North, z Up; SI units. All functions broadcast over leading dimensions of
``x`` and ``dt`` where stated.

References
----------
Bar-Shalom, Li & Kirubarajan (2001), sections 6.2 (white-noise acceleration models),
6.3 (CA), 11.7 (coordinated turn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any
from typing import ClassVar
from typing import Protocol

import numpy as np
from numba import njit
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.jit import gufunc
from seatrack.kalman import cov_core

FloatArray = NDArray[np.float64]

__all__ = [
    "MotionModel",
    "ConstantVelocity",
    "ConstantAcceleration",
    "CoordinatedTurn",
    "cv_transition",
    "cv_noise",
    "cv_matrices",
    "cv_noise_discrete",
    "ALONG_TRACK_RATIO",
    "along_track_core",
    "cv_predict_core",
    "along_track_shape",
    "ca_transition",
    "ca_noise",
    "ct_transition",
    "ct_jacobian",
    "ct_noise",
    "ct_predict",
    "scan_psd",
]


def _kron_blocks(blocks: FloatArray, d: int) -> FloatArray:
    """Expand per-axis ``(..., k, k)`` blocks into ``(..., k*d, k*d)`` (block order)."""
    eye = np.eye(d)
    return np.einsum("...ij,ab->...iajb", blocks, eye).reshape(
        blocks.shape[:-2] + (blocks.shape[-2] * d, blocks.shape[-1] * d)
    )


def _poly_transition(dt: ArrayLike, order: int, d: int) -> FloatArray:
    t = np.asarray(dt, dtype=float)[..., None, None]
    k = order + 1
    blk = np.zeros(t.shape[:-2] + (k, k))
    fact = 1.0
    for p in range(k):
        if p:
            fact *= p
        for i in range(k - p):
            blk[..., i, i + p] = (t[..., 0, 0] ** p) / fact
    return _kron_blocks(blk, d)


def cv_transition(dt: ArrayLike, d: int = 2) -> FloatArray:
    """Constant-velocity transition ``F = [[I, dt I], [0, I]]``, shape ``(..., 2d, 2d)``."""
    return _poly_transition(dt, 1, d)


def cv_noise(dt: ArrayLike, q: ArrayLike, d: int = 2) -> FloatArray:
    """Continuous white-noise-acceleration process noise for CV (BLK 6.2.2).

    ``Q = q [[dt^3/3 I, dt^2/2 I], [dt^2/2 I, dt I]]`` with ``q`` the power spectral
    density of the acceleration, m^2/s^3. Shape ``(..., 2d, 2d)``.
    """
    t = np.asarray(dt, dtype=float)
    qq = np.asarray(q, dtype=float)
    blk = (
        np.stack([np.stack([t**3 / 3, t**2 / 2], -1), np.stack([t**2 / 2, t], -1)], -2)
        * qq[..., None, None]
    )
    return _kron_blocks(blk, d)


#: the speed, in velocity standard deviations, above which a track's direction is known
ALONG_TRACK_MIN_SIGMAS = 3.0

#: the default PSD of a manoeuvre acceleration along the track over its PSD across it (the
#: level IMM's levels and the multi-target tracker's noise levels; chosen on the tuning
#: seeds of benchmarks/defaults.py, docs/defaults.md)
ALONG_TRACK_RATIO = 0.3


@njit(cache=True, inline="always")
def cv_predict_core(x, P, T, Q, xo, Po, FP, d):  # pragma: no cover - compiled
    """Constant-velocity prediction over ``T`` (s) of ``x = [position, velocity]`` (``2d``):
    ``xo = F x``, ``Po = F P F^T + sym(Q)`` with ``F = [[I, T I], [0, I]]``, from the
    structure of ``F`` (``FP``: ``(2d, 2d)`` scratch). Bit-identical to the general
    products (:func:`seatrack.kalman.predict_core`: the terms it adds are exact zeros and
    ones, in the same order) at about 60 % of their cost."""
    n = 2 * d
    for i in range(n):
        xo[i] = x[i] + T * x[i + d] if i < d else x[i]
        for j in range(n):
            FP[i, j] = P[i, j] + T * P[i + d, j] if i < d else P[i, j]
    for i in range(n):
        for j in range(i, n):
            s = FP[i, j] + T * FP[i, j + d] if j < d else FP[i, j]
            v = s + 0.5 * (Q[i, j] + Q[j, i])
            Po[i, j] = v
            Po[j, i] = v


@njit(cache=True)
def along_track_core(v, Pv, ratio, A):  # pragma: no cover - compiled
    """Write into ``A (d, d)`` the covariance shape of a white acceleration whose PSD
    along the velocity ``v (d,)`` (m/s) is ``ratio`` times its PSD across it:
    ``A = I - (1 - ratio) u u^T``, ``u = v / |v|``. Where the direction is unknown -- the
    speed at most :data:`ALONG_TRACK_MIN_SIGMAS` times the velocity std
    ``sqrt(tr(Pv) / d)`` of the covariance ``Pv (d, d)`` (m^2/s^2) -- ``A = I``."""
    d = v.shape[0]
    s2 = 0.0
    tr = 0.0
    for k in range(d):
        s2 += v[k] * v[k]
        tr += Pv[k, k]
    known = s2 > ALONG_TRACK_MIN_SIGMAS**2 * max(tr, 0.0) / d and s2 > 0.0
    w = (1.0 - ratio) / s2 if known else 0.0
    for k in range(d):
        for m in range(d):
            A[k, m] = (1.0 if k == m else 0.0) - w * v[k] * v[m]


def along_track_shape(v: ArrayLike, Pv: ArrayLike, ratio: float) -> FloatArray:
    """Covariance shapes ``(..., d, d)`` of a manoeuvre acceleration whose PSD along the
    velocity is ``ratio`` (in (0, 1]) times its PSD across it (:func:`along_track_core`
    per track: a coordinated turn accelerates across the track; ``A = I`` while the
    direction is unknown). The white-acceleration CV noise of such a level is
    ``q [[T^3/3, T^2/2], [T^2/2, T]] (x) A`` (BLK 6.2.2 with ``I`` replaced by ``A``).

    Parameters
    ----------
    v : (..., d) velocity estimates, m/s; Pv : (..., d, d) their covariances, m^2/s^2.
    """
    vv = np.asarray(v, dtype=float)
    PP = np.broadcast_to(np.asarray(Pv, dtype=float), vv.shape + vv.shape[-1:])
    out = np.empty(vv.shape + vv.shape[-1:])
    for i in np.ndindex(vv.shape[:-1]):
        along_track_core(vv[i], np.ascontiguousarray(PP[i]), float(ratio), out[i])
    return out


@lru_cache(maxsize=256)
def _cv_pair(dt: float, q: float, d: int) -> tuple[FloatArray, FloatArray]:
    return cv_transition(dt, d), cv_noise(dt, q, d)


def cv_matrices(dt: ArrayLike, q: float, d: int = 2) -> tuple[FloatArray, FloatArray]:
    """CV ``(F, Q)`` for intervals ``dt (B,)``: one cached ``(2d, 2d)`` pair when every
    interval is the same (radar scans repeat one ``dt``; the arrays are shared, do not
    modify them), else ``(B, 2d, 2d)`` stacks."""
    t = np.asarray(dt, dtype=float)
    if t.size and np.all(t == t.flat[0]):
        return _cv_pair(float(t.flat[0]), float(q), d)
    return cv_transition(t, d), cv_noise(t, q, d)


def cv_noise_discrete(dt: ArrayLike, sigma_a: ArrayLike, d: int = 2) -> FloatArray:
    """Piecewise-constant (discrete) white-noise acceleration for CV (BLK 6.3.2).

    ``Q = sigma_a^2 G G^T`` with ``G = [dt^2/2, dt]`` per axis; ``sigma_a`` in m/s^2.
    """
    t = np.asarray(dt, dtype=float)
    s2 = np.asarray(sigma_a, dtype=float) ** 2
    g = np.stack([t**2 / 2, t], -1)
    blk = g[..., :, None] * g[..., None, :] * s2[..., None, None]
    return _kron_blocks(blk, d)


def ca_transition(dt: ArrayLike, d: int = 2) -> FloatArray:
    """Constant-acceleration transition, state ``[p, v, a]`` per block, ``(..., 3d, 3d)``."""
    return _poly_transition(dt, 2, d)


def ca_noise(dt: ArrayLike, q: ArrayLike, d: int = 2) -> FloatArray:
    """Continuous white-noise-jerk process noise for CA (BLK 6.2.3); ``q`` in m^2/s^5."""
    t = np.asarray(dt, dtype=float)
    qq = np.asarray(q, dtype=float)
    rows = [
        [t**5 / 20, t**4 / 8, t**3 / 6],
        [t**4 / 8, t**3 / 3, t**2 / 2],
        [t**3 / 6, t**2 / 2, t],
    ]
    blk = np.stack([np.stack(r, -1) for r in rows], -2) * qq[..., None, None]
    return _kron_blocks(blk, d)


# ---------------------------------------------------------------------------
# Coordinated turn
# ---------------------------------------------------------------------------
_SMALL = 1e-3  # |w T| below which the Taylor series is used (error < 1e-16 T)


def _ct_coeffs(w: FloatArray, t: FloatArray) -> tuple[FloatArray, ...]:
    """a = sin(wT)/w, b = (1-cos(wT))/w and their derivatives in w (series near 0)."""
    wt = w * t
    small = np.abs(wt) < _SMALL
    ws = np.where(small, 1.0, w)
    s, c = np.sin(wt), np.cos(wt)
    a = np.where(small, t - w**2 * t**3 / 6 + w**4 * t**5 / 120, s / ws)
    b = np.where(small, w * t**2 / 2 - w**3 * t**4 / 24, (1 - c) / ws)
    da = np.where(small, -w * t**3 / 3 + w**3 * t**5 / 30, t * c / ws - s / ws**2)
    db = np.where(
        small, t**2 / 2 - w**2 * t**4 / 8 + w**4 * t**6 / 144, t * s / ws - (1 - c) / ws**2
    )
    return a, b, da, db, s, c


def _ct_index(n: int) -> tuple[int, int, int, int, int, int | None]:
    if n == 5:
        return 0, 1, 2, 3, 4, None
    if n == 7:
        return 0, 1, 3, 4, 6, 2
    raise ValueError(f"coordinated-turn state must have 5 (2-D) or 7 (3-D) components, got {n}")


def ct_transition(x: ArrayLike, dt: ArrayLike) -> FloatArray:
    """Exact coordinated-turn propagation ``f(x)`` (clockwise-positive turn rate).

    ``vx' = vx cos(wT) + vy sin(wT)``, ``vy' = -vx sin(wT) + vy cos(wT)``;
    positions integrate the rotating velocity exactly. Near ``w = 0`` a series is used.
    """
    xx = np.asarray(x, dtype=float)
    ix, iy, ivx, ivy, iw, iz = _ct_index(xx.shape[-1])
    t = np.asarray(dt, dtype=float)
    w = xx[..., iw]
    vx, vy = xx[..., ivx], xx[..., ivy]
    a, b, _, _, s, c = _ct_coeffs(w, t)
    out = np.array(np.broadcast_to(xx, np.broadcast_shapes(xx.shape, t.shape + (1,))))
    out[..., ix] = xx[..., ix] + a * vx + b * vy
    out[..., iy] = xx[..., iy] - b * vx + a * vy
    out[..., ivx] = c * vx + s * vy
    out[..., ivy] = -s * vx + c * vy
    if iz is not None:
        out[..., iz] = xx[..., iz] + t * xx[..., 5]
    return out


def ct_jacobian(x: ArrayLike, dt: ArrayLike) -> FloatArray:
    """Analytic Jacobian ``df/dx`` of :func:`ct_transition`, shape ``(..., n, n)``."""
    xx = np.asarray(x, dtype=float)
    n = xx.shape[-1]
    ix, iy, ivx, ivy, iw, iz = _ct_index(n)
    t = np.asarray(dt, dtype=float)
    w = xx[..., iw]
    vx, vy = xx[..., ivx], xx[..., ivy]
    a, b, da, db, s, c = _ct_coeffs(w, t)
    shape = np.broadcast_shapes(xx.shape[:-1], t.shape)
    J = np.zeros(shape + (n, n))
    J[..., range(n), range(n)] = 1.0
    J[..., ix, ivx] = a
    J[..., ix, ivy] = b
    J[..., ix, iw] = da * vx + db * vy
    J[..., iy, ivx] = -b
    J[..., iy, ivy] = a
    J[..., iy, iw] = -db * vx + da * vy
    J[..., ivx, ivx] = c
    J[..., ivx, ivy] = s
    J[..., ivx, iw] = t * (-s * vx + c * vy)
    J[..., ivy, ivx] = -s
    J[..., ivy, ivy] = c
    J[..., ivy, iw] = t * (-c * vx - s * vy)
    if iz is not None:
        J[..., iz, 5] = t
    return J


def ct_noise(dt: ArrayLike, q: ArrayLike, q_omega: ArrayLike, d: int = 2) -> FloatArray:
    """Coordinated-turn process noise: CV white-noise acceleration ``q`` (m^2/s^3) on the
    kinematic part and a random walk ``q_omega * dt`` (rad^2/s^3 * s) on the turn rate."""
    t = np.asarray(dt, dtype=float)
    Qcv = cv_noise(t, q, d)
    n = 2 * d + 1
    Q = np.zeros(Qcv.shape[:-2] + (n, n))
    Q[..., : 2 * d, : 2 * d] = Qcv
    Q[..., -1, -1] = np.asarray(q_omega, dtype=float) * t
    return Q


@njit(cache=True)
def _ct_predict_core(x, P, T, q, q_omega, xo, Po):  # pragma: no cover - compiled
    """Coordinated-turn EKF prediction of one state: ``xo = f(x)``, ``Po = F P F^T + Q``
    (the maths of :func:`ct_transition`, :func:`ct_jacobian`, :func:`ct_noise`)."""
    n = x.shape[0]
    d = (n - 1) // 2
    ivx, ivy, iw = d, d + 1, n - 1
    w, vx, vy = x[iw], x[ivx], x[ivy]
    wt = w * T
    s, c = math.sin(wt), math.cos(wt)
    if abs(wt) < _SMALL:
        a = T - w**2 * T**3 / 6 + w**4 * T**5 / 120
        b = w * T**2 / 2 - w**3 * T**4 / 24
        da = -w * T**3 / 3 + w**3 * T**5 / 30
        db = T**2 / 2 - w**2 * T**4 / 8 + w**4 * T**6 / 144
    else:
        a, b = s / w, (1 - c) / w
        da, db = T * c / w - s / w**2, T * s / w - (1 - c) / w**2
    for i in range(n):
        xo[i] = x[i]
    xo[0] = x[0] + a * vx + b * vy
    xo[1] = x[1] - b * vx + a * vy
    xo[ivx] = c * vx + s * vy
    xo[ivy] = -s * vx + c * vy
    F = np.eye(n)
    F[0, ivx], F[0, ivy], F[0, iw] = a, b, da * vx + db * vy
    F[1, ivx], F[1, ivy], F[1, iw] = -b, a, -db * vx + da * vy
    F[ivx, ivx], F[ivx, ivy], F[ivx, iw] = c, s, T * (-s * vx + c * vy)
    F[ivy, ivx], F[ivy, ivy], F[ivy, iw] = -s, c, T * (-c * vx - s * vy)
    if d == 3:
        xo[2] = x[2] + T * x[5]
        F[2, 5] = T
    Q = np.zeros((n, n))
    for k in range(d):
        Q[k, k] = q * T**3 / 3
        Q[k, k + d] = Q[k + d, k] = q * T**2 / 2
        Q[k + d, k + d] = q * T
    Q[iw, iw] = q_omega * T
    cov_core(P, F, Q, Po)


@gufunc("void(f8[:], f8[:,:], f8, f8, f8, f8[:], f8[:,:])", "(n),(n,n),(),(),()->(n),(n,n)")
def _ct_predict_kernel(x, P, T, q, q_omega, xo, Po):  # pragma: no cover - compiled
    _ct_predict_core(x, P, T, q, q_omega, xo, Po)


def scan_psd(q: ArrayLike, accel: float, dt: ArrayLike) -> Any:
    """White-acceleration PSD of a scan of length ``dt``: ``q + accel^2 dt`` (m^2/s^3).

    ``accel^2 T`` makes the velocity variance added per scan that of an acceleration of
    std ``accel`` over the scan (Bar-Shalom, Li & Kirubarajan 2001, sec. 6.3.2); a plain
    ``q`` (``accel = 0``) is returned unchanged.
    """
    if accel == 0.0:
        return q
    return np.asarray(q, dtype=float) + accel**2 * np.asarray(dt, dtype=float)


def ct_predict(
    x: ArrayLike, P: ArrayLike, dt: ArrayLike, q: ArrayLike, q_omega: float
) -> tuple[FloatArray, FloatArray]:
    """Compiled coordinated-turn EKF prediction over leading dimensions: ``(f(x), F P F^T +
    Q)`` with ``F`` = :func:`ct_jacobian` and ``Q`` = :func:`ct_noise`."""
    return _ct_predict_kernel(x, P, dt, q, q_omega)  # type: ignore[no-any-return]


# ---------------------------------------------------------------------------
# Model objects (configuration in the constructor, data in the call)
# ---------------------------------------------------------------------------
def _names(d: int, prefixes: tuple[str, ...]) -> tuple[str, ...]:
    axes = ("x", "y", "z")[:d]
    return tuple(p + a for p in prefixes for a in axes)


class MotionModel(Protocol):
    """What filters need from a motion model."""

    @property
    def ndim_state(self) -> int: ...

    @property
    def position_index(self) -> tuple[int, ...]: ...

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the state components (e.g. ``("x", "y", "vx", "vy", "w")``); models
        of different size are related through these names (IMM mixing)."""
        ...

    @property
    def velocity_index(self) -> tuple[int, ...]: ...

    def transition(self, x: ArrayLike, dt: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Return ``(f(x), F)``: the propagated state and the transition Jacobian."""
        ...

    def noise(self, dt: ArrayLike) -> FloatArray:
        """Process-noise covariance ``Q(dt)``."""
        ...


class _PositionVelocityLayout:
    """The state layout of every model here: position ``[0, d)``, velocity ``[d, 2d)``."""

    d: int

    @property
    def position_index(self) -> tuple[int, ...]:
        return tuple(range(self.d))

    @property
    def velocity_index(self) -> tuple[int, ...]:
        return tuple(range(self.d, 2 * self.d))


@dataclass(frozen=True)
class _Polynomial(_PositionVelocityLayout):
    """Shared shell of the linear polynomial models (CV: order 1, CA: order 2)."""

    q: float = 0.1
    d: int = 2

    _order: ClassVar[int] = 1
    #: ``True`` when ``F`` and ``Q`` depend on ``dt`` only (filters may cache them)
    is_linear: ClassVar[bool] = True

    @property
    def ndim_state(self) -> int:
        return (self._order + 1) * self.d

    @property
    def state_names(self) -> tuple[str, ...]:
        return _names(self.d, ("", "v", "a")[: self._order + 1])

    def transition(self, x: ArrayLike, dt: ArrayLike) -> tuple[FloatArray, FloatArray]:
        F = _poly_transition(dt, self._order, self.d)
        return np.einsum("...ij,...j->...i", F, np.asarray(x, float)), F


@dataclass(frozen=True)
class ConstantVelocity(_Polynomial):
    """Constant-velocity model with continuous white-noise acceleration.

    Parameters
    ----------
    q : float
        Acceleration power spectral density, m^2/s^3 (``q = sigma_a^2 * tau`` roughly).
    d : int
        Spatial dimensions (2 or 3).
    accel : float
        An acceleration std ``a`` (m/s^2) whose PSD ``a^2 T`` is added at each scan of
        length ``T`` (:func:`scan_psd`; a target class's levels), default 0.
    """

    q: float = 0.1
    d: int = 2
    accel: float = 0.0
    _order: ClassVar[int] = 1

    def noise(self, dt: ArrayLike) -> FloatArray:
        return cv_noise(dt, scan_psd(self.q, self.accel, dt), self.d)


@dataclass(frozen=True)
class ConstantAcceleration(_Polynomial):
    """Constant-acceleration model with white-noise jerk ``q`` (m^2/s^5)."""

    q: float = 0.01
    d: int = 2
    _order: ClassVar[int] = 2

    def noise(self, dt: ArrayLike) -> FloatArray:
        return ca_noise(dt, self.q, self.d)


@dataclass(frozen=True)
class CoordinatedTurn(_PositionVelocityLayout):
    """Coordinated turn with the turn rate in the state (clockwise positive).

    Parameters
    ----------
    q : float
        Acceleration PSD on the kinematic part, m^2/s^3.
    q_omega : float
        Turn-rate random-walk PSD, rad^2/s^3.
    d : int
        2 (state ``[x, y, vx, vy, w]``) or 3 (``[x, y, z, vx, vy, vz, w]``).
    accel : float
        As :class:`ConstantVelocity`: PSD ``accel^2 T`` added at each scan, m/s^2.
    """

    q: float = 0.1
    q_omega: float = 1e-4
    d: int = 2
    accel: float = 0.0

    #: the turn rate makes the transition depend on the state
    is_linear: ClassVar[bool] = False

    @property
    def ndim_state(self) -> int:
        return 2 * self.d + 1

    @property
    def state_names(self) -> tuple[str, ...]:
        return _names(self.d, ("", "v")) + ("w",)

    def transition(self, x: ArrayLike, dt: ArrayLike) -> tuple[FloatArray, FloatArray]:
        return ct_transition(x, dt), ct_jacobian(x, dt)

    def noise(self, dt: ArrayLike) -> FloatArray:
        return ct_noise(dt, scan_psd(self.q, self.accel, dt), self.q_omega, self.d)

    def predict(self, x: ArrayLike, P: ArrayLike, dt: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """EKF prediction of ``(x, P)`` over ``dt`` in one compiled call (:func:`ct_predict`)."""
        return ct_predict(x, P, dt, scan_psd(self.q, self.accel, dt), self.q_omega)
