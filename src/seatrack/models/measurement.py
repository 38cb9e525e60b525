"""Measurement models: ``h(x)`` and analytic Jacobians.

Pure functions on the *relative* geometry (target minus sensor) come first; small model
objects then map them onto a state vector (which components are position / velocity)
and say which measurement components are angles (``angular``) so the Kalman core wraps
their innovations.

Conventions: azimuth / bearing clockwise from North (``atan2(dx, dy)``), elevation up
from the horizontal; range rate positive when the range opens (receding target).
The predicted angles are returned wrapped to ``[0, 2*pi)``; innovations are wrapped to
``(-pi, pi]`` by :func:`seatrack.kalman.extended_update`.

Every Jacobian is checked against :func:`seatrack.models.numdiff.numerical_jacobian`
in ``tests/models/test_measurement.py``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from typing import Any
from typing import Protocol

import numpy as np
from numba import njit
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import bearing as _bearing

FloatArray = NDArray[np.float64]

__all__ = [
    "MeasurementModel",
    "Bearing",
    "RangeBearing",
    "RangeBearingElevation",
    "RangeRate",
    "Position",
    "Stacked",
    "in_layout",
    "bearing_jacobian",
    "range_bearing_jacobian",
    "range_bearing_elevation_jacobian",
    "range_rate",
    "range_rate_jacobian",
    "polar_measurement",
    "polar_core",
    "sensor_frame_core",
    "near_sensor",
    "NEAR_SENSOR_SIGMAS",
]


# ---------------------------------------------------------------------------
# Pure functions of the relative vector d = target - sensor
# ---------------------------------------------------------------------------
def bearing_jacobian(d: ArrayLike) -> FloatArray:
    """d(bearing)/d(target x, y) = ``[dy, -dx] / r^2`` (rad/m), shape ``(..., 2)``."""
    dd = np.asarray(d, dtype=float)
    r2 = dd[..., 0] ** 2 + dd[..., 1] ** 2
    out = np.empty(r2.shape + (2,))
    np.divide(dd[..., 1], r2, out=out[..., 0])
    np.divide(-dd[..., 0], r2, out=out[..., 1])
    return out


def range_bearing_jacobian(d: ArrayLike) -> FloatArray:
    """Jacobian of ``[range, bearing]`` w.r.t. target ``(x, y)``, shape ``(..., 2, 2)``."""
    dd = np.asarray(d, dtype=float)
    r = np.hypot(dd[..., 0], dd[..., 1])
    row_r = np.stack([dd[..., 0] / r, dd[..., 1] / r], -1)
    return np.stack([row_r, bearing_jacobian(dd)], -2)


def range_bearing_elevation_jacobian(d: ArrayLike) -> FloatArray:
    """Jacobian of ``[range, azimuth, elevation]`` w.r.t. target ``(x, y, z)``, ``(..., 3, 3)``."""
    dd = np.asarray(d, dtype=float)
    x, y, z = dd[..., 0], dd[..., 1], dd[..., 2]
    rh2 = x**2 + y**2
    rh = np.sqrt(rh2)
    r2 = rh2 + z**2
    r = np.sqrt(r2)
    zero = np.zeros_like(x)
    row_r = np.stack([x / r, y / r, z / r], -1)
    row_a = np.stack([y / rh2, -x / rh2, zero], -1)
    row_e = np.stack([-x * z / (r2 * rh), -y * z / (r2 * rh), rh / r2], -1)
    return np.stack([row_r, row_a, row_e], -2)


def range_rate(d: ArrayLike, dv: ArrayLike) -> Any:
    """Range rate ``d . dv / |d|`` (m/s; positive = opening) for relative position/velocity;
    NaN at zero range (undefined there)."""
    dd = np.asarray(d, dtype=float)
    vv = np.asarray(dv, dtype=float)
    r = np.linalg.norm(dd, axis=-1)
    with np.errstate(invalid="ignore"):  # 0 / 0 at zero range: NaN
        return np.einsum("...i,...i->...", dd, vv) / r


def range_rate_jacobian(d: ArrayLike, dv: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Jacobian of the range rate w.r.t. relative position and velocity.

    ``d(rdot)/dp = (dv - rdot d / r) / r``, ``d(rdot)/dv = d / r`` (multimodel spec step 3).
    """
    dd = np.asarray(d, dtype=float)
    vv = np.asarray(dv, dtype=float)
    r = np.linalg.norm(dd, axis=-1)[..., None]
    rd = np.einsum("...i,...i->...", dd, vv)[..., None] / r
    return (vv - rd * dd / r) / r, dd / r


# ---------------------------------------------------------------------------
# Model objects
# ---------------------------------------------------------------------------
class MeasurementModel(Protocol):
    """What filters need from a measurement model."""

    @property
    def angular(self) -> NDArray[np.bool_]: ...

    @property
    def ndim_meas(self) -> int: ...

    def h(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray: ...

    def jacobian(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray: ...


def _rel(x: ArrayLike, idx: tuple[int, ...], sensor: ArrayLike | None) -> FloatArray:
    p = np.asarray(x, dtype=float)[..., list(idx)]
    if sensor is None:
        return p
    s = np.asarray(sensor, dtype=float)[..., : len(idx)]
    return p - s


def _embed(block: FloatArray, idx: tuple[int, ...], n: int, lead: tuple[int, ...]) -> FloatArray:
    H = np.zeros(lead + (block.shape[-2], n))
    H[..., list(idx)] = block
    return H


@dataclass(frozen=True)
class Bearing:
    """Passive bearing (2-D). ``h(x) = [atan2(dx, dy)]``.

    Parameters
    ----------
    n : int
        State dimension.
    pos : tuple of int
        Indices of target (x, y) in the state.
    """

    n: int = 4
    pos: tuple[int, ...] = (0, 1)
    ndim_meas: int = field(default=1, init=False)

    @property
    def angular(self) -> NDArray[np.bool_]:
        return np.array([True])

    def h(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        d = _rel(x, self.pos, sensor)
        return np.asarray(_bearing(d[..., 0], d[..., 1]))[..., None]

    def jacobian(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        d = _rel(x, self.pos, sensor)
        return _embed(bearing_jacobian(d)[..., None, :], self.pos, self.n, d.shape[:-1])


@dataclass(frozen=True)
class RangeBearing:
    """Active sonar / 2-D radar: ``h(x) = [range, bearing]``."""

    n: int = 4
    pos: tuple[int, ...] = (0, 1)
    ndim_meas: int = field(default=2, init=False)

    @property
    def angular(self) -> NDArray[np.bool_]:
        return np.array([False, True])

    def h(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        d = _rel(x, self.pos, sensor)
        return np.stack([np.hypot(d[..., 0], d[..., 1]), _bearing(d[..., 0], d[..., 1])], -1)

    def jacobian(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        d = _rel(x, self.pos, sensor)
        return _embed(range_bearing_jacobian(d), self.pos, self.n, d.shape[:-1])


@dataclass(frozen=True)
class RangeBearingElevation:
    """3-D radar: ``h(x) = [range, azimuth, elevation]``."""

    n: int = 6
    pos: tuple[int, ...] = (0, 1, 2)
    ndim_meas: int = field(default=3, init=False)

    @property
    def angular(self) -> NDArray[np.bool_]:
        return np.array([False, True, True])

    def h(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        d = _rel(x, self.pos, sensor)
        rh = np.hypot(d[..., 0], d[..., 1])
        return np.stack(
            [np.hypot(rh, d[..., 2]), _bearing(d[..., 0], d[..., 1]), np.arctan2(d[..., 2], rh)],
            -1,
        )

    def jacobian(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        d = _rel(x, self.pos, sensor)
        return _embed(range_bearing_elevation_jacobian(d), self.pos, self.n, d.shape[:-1])


@dataclass(frozen=True)
class RangeRate:
    """Doppler range rate ``h(x) = [(p - s) . (v - vs) / |p - s|]`` (2-D or 3-D).

    ``sensor`` may carry the sensor velocity after its position:
    ``[sx, sy, (sz), svx, svy, (svz)]``; without it the sensor is at rest.
    """

    n: int = 6
    pos: tuple[int, ...] = (0, 1, 2)
    vel: tuple[int, ...] = (3, 4, 5)
    ndim_meas: int = field(default=1, init=False)

    @property
    def angular(self) -> NDArray[np.bool_]:
        return np.array([False])

    def _rel(self, x: ArrayLike, sensor: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
        xx = np.asarray(x, dtype=float)
        p = xx[..., list(self.pos)]
        v = xx[..., list(self.vel)]
        if sensor is not None:
            s = np.asarray(sensor, dtype=float)
            k = len(self.pos)
            p = p - s[..., :k]
            if s.shape[-1] >= 2 * k:
                v = v - s[..., k : 2 * k]
        return p, v

    def h(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        p, v = self._rel(x, sensor)
        return np.asarray(range_rate(p, v))[..., None]

    def jacobian(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        p, v = self._rel(x, sensor)
        jp, jv = range_rate_jacobian(p, v)
        H = np.zeros(p.shape[:-1] + (1, self.n))
        H[..., 0, list(self.pos)] = jp
        H[..., 0, list(self.vel)] = jv
        return H


@dataclass(frozen=True)
class Position:
    """Linear (converted) position measurement ``h(x) = x[pos]``."""

    n: int = 4
    pos: tuple[int, ...] = (0, 1)

    @property
    def ndim_meas(self) -> int:
        return len(self.pos)

    @property
    def angular(self) -> NDArray[np.bool_]:
        return np.zeros(len(self.pos), bool)

    def matrix(self) -> FloatArray:
        """The constant ``H`` matrix ``(len(pos), n)``."""
        H = np.zeros((len(self.pos), self.n))
        H[range(len(self.pos)), list(self.pos)] = 1.0
        return H

    def h(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        return _rel(x, self.pos, sensor)

    def jacobian(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        lead = np.asarray(x).shape[:-1]
        return np.broadcast_to(self.matrix(), lead + (len(self.pos), self.n)).copy()


@dataclass(frozen=True)
class Stacked:
    """Several measurement models observed together (e.g. range-azimuth-elevation + range rate).

    ``h`` and the Jacobian are the concatenations of the parts; the same ``sensor``
    argument is passed to each.
    """

    parts: Sequence[Any]

    @property
    def ndim_meas(self) -> int:
        return int(sum(p.ndim_meas for p in self.parts))

    @property
    def angular(self) -> NDArray[np.bool_]:
        return np.concatenate([p.angular for p in self.parts])

    def h(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        return np.concatenate([p.h(x, sensor) for p in self.parts], -1)

    def jacobian(self, x: ArrayLike, sensor: ArrayLike | None = None) -> FloatArray:
        return np.concatenate([p.jacobian(x, sensor) for p in self.parts], -2)


def in_layout(model: Any, n: int) -> Any:
    """The measurement ``model`` of a state of ``n`` components whose leading components are
    the model's own state (e.g. a CV model's measurement on the padded ``[x, y, vx, vy, w]``
    of a CV + CT bank): the same ``h``, its Jacobian zero on the extra components. ``None``
    when the model does not say which components it reads (no ``n`` field)."""
    if isinstance(model, Stacked):
        parts = [in_layout(p, n) for p in model.parts]
        return None if any(p is None for p in parts) else Stacked(tuple(parts))
    if dataclasses.is_dataclass(model) and any(f.name == "n" for f in dataclasses.fields(model)):
        if model.n > n:  # type: ignore[union-attr]
            raise ValueError(f"a model of {model.n} components cannot read a state of {n}")  # type: ignore[union-attr]
        return dataclasses.replace(model, n=n)  # type: ignore[type-var]
    return None


# ---------------------------------------------------------------------------
# Compiled polar plot prediction for a batch (range, azimuth, [elevation], [range rate])
# ---------------------------------------------------------------------------
@njit(cache=True)
def polar_core(x, s, d, rr, hx, H):  # pragma: no cover - compiled
    """``h(x)`` and its Jacobian for a batch: state positions ``0..d-1``, velocities
    ``d..2d-1``; sensor ``s = [position (d), velocity (d)]``. Same maths as
    :class:`RangeBearing`, :class:`RangeBearingElevation` and :class:`RangeRate`."""
    for b in range(x.shape[0]):
        for i in range(H.shape[1]):
            for j in range(H.shape[2]):
                H[b, i, j] = 0.0
        dx, dy = x[b, 0] - s[b, 0], x[b, 1] - s[b, 1]
        rh2 = dx * dx + dy * dy
        dz = x[b, 2] - s[b, 2] if d == 3 else 0.0
        r = math.sqrt(rh2 + dz * dz)
        hx[b, 0] = r
        az = math.atan2(dx, dy)
        hx[b, 1] = az + 2.0 * math.pi if az < 0.0 else az
        H[b, 1, 0], H[b, 1, 1] = dy / rh2, -dx / rh2
        for k in range(d):
            H[b, 0, k] = (x[b, k] - s[b, k]) / r
        m = 2
        if d == 3:
            rh = math.sqrt(rh2)
            hx[b, 2] = math.atan2(dz, rh)
            r2 = rh2 + dz * dz
            H[b, 2, 0], H[b, 2, 1], H[b, 2, 2] = -dx * dz / (r2 * rh), -dy * dz / (r2 * rh), rh / r2
            m = 3
        if rr:
            pv = 0.0
            for k in range(d):
                pv += (x[b, k] - s[b, k]) * (x[b, d + k] - s[b, d + k])
            rdot = pv / r
            hx[b, m] = rdot
            for k in range(d):
                p_k = x[b, k] - s[b, k]
                H[b, m, k] = ((x[b, d + k] - s[b, d + k]) - rdot * p_k / r) / r
                H[b, m, d + k] = p_k / r


@njit(cache=True, inline="always")
def sensor_frame_core(x, s, d, az, el, hx, H):  # pragma: no cover - compiled
    """Replace the range, azimuth [and elevation] rows of :func:`polar_core`'s ``hx``, ``H``
    by the position in the frame of a plot's measured direction -- azimuth ``az`` (rad,
    clockwise from North) and, in 3-D (``d = 3``), elevation ``el`` (rad, up; ignored in
    2-D): along the ray ``u = (cos el sin az, cos el cos az, sin el)``, across it
    horizontally ``v = (cos az, -sin az, 0)`` and, in 3-D, across it vertically
    ``w = (-sin el sin az, -sin el cos az, cos el)``; ``h = [u, v, (w)] . (p - s)``, linear
    in the state. The plot itself is ``[range, 0, (0)]`` in that frame, with noise
    variances ``sigma_r^2`` along and about ``(range^2 + sigma_r^2) cos^2(el) sigma_az^2``,
    ``(range^2 + sigma_r^2) sigma_el^2`` across: the update of a plot next to the sensor,
    where the polar Jacobian fails (its bearing swings by tens of degrees over the prior's
    extent)."""
    sa, ca = math.sin(az), math.cos(az)
    se, ce = (math.sin(el), math.cos(el)) if d == 3 else (0.0, 1.0)
    for b in range(x.shape[0]):
        dx, dy = x[b, 0] - s[b, 0], x[b, 1] - s[b, 1]
        dz = x[b, 2] - s[b, 2] if d == 3 else 0.0
        for i in range(d):
            for j in range(H.shape[2]):
                H[b, i, j] = 0.0
        H[b, 0, 0], H[b, 0, 1] = ce * sa, ce * ca
        H[b, 1, 0], H[b, 1, 1] = ca, -sa
        hx[b, 0] = ce * sa * dx + ce * ca * dy + se * dz
        hx[b, 1] = ca * dx - sa * dy
        if d == 3:
            H[b, 0, 2] = se
            H[b, 2, 0], H[b, 2, 1], H[b, 2, 2] = -se * sa, -se * ca, ce
            hx[b, 2] = -se * sa * dx - se * ca * dy + ce * dz


#: a plot is taken in the frame of its direction (:func:`sensor_frame_core`) when its range
#: or the prediction's is below this many times the larger of the prediction's position
#: std and the range std (the polar Jacobian's error over the prior grows as
#: (std / range)^2: 4 % at 5)
NEAR_SENSOR_SIGMAS = 5.0


def near_sensor(
    x: ArrayLike, P: ArrayLike, plot_range: ArrayLike, sensor: ArrayLike, d: int, var_range: float
) -> NDArray[np.bool_]:
    """Which plots are next to the sensor: the plot's range or the predicted one (states
    ``x (B, n)``, ``P``, positions first; sensors ``(B, >= d)``; m) below
    :data:`NEAR_SENSOR_SIGMAS` times the larger of the predicted position std
    ``sqrt(tr P_pos)`` and the range std ``sqrt(var_range)`` -- where the polar Jacobian no
    longer holds over the prior's extent. Non-finite inputs give False (compiled: it runs
    on every update and gating of the level methods)."""
    xx = np.ascontiguousarray(x, dtype=float)
    out = np.empty(xx.shape[0], dtype=np.bool_)
    _near_sensor_core(
        xx, np.ascontiguousarray(P, dtype=float), np.ascontiguousarray(plot_range, dtype=float),
        np.ascontiguousarray(sensor, dtype=float), d, float(var_range), NEAR_SENSOR_SIGMAS, out,
    )  # fmt: skip
    return out


@njit(cache=True)
def _near_sensor_core(x, P, rng, s, d, var_range, k, out):  # pragma: no cover - compiled
    for b in range(x.shape[0]):
        r2 = 0.0
        tr = 0.0
        for i in range(d):
            v = x[b, i] - s[b, i]
            r2 += v * v
            tr += P[b, i, i]
        limit = k * math.sqrt(max(tr, var_range))
        finite = math.isfinite(r2) and math.isfinite(tr) and math.isfinite(rng[b])
        out[b] = finite and min(rng[b], math.sqrt(r2)) < limit


def polar_measurement(
    x: ArrayLike, sensor: ArrayLike, d: int, range_rate: bool = False
) -> tuple[FloatArray, FloatArray]:
    """Predicted plots ``h(x) (B, m)`` and Jacobians ``(B, m, n)`` of a batch of states
    (range, azimuth in ``[0, 2 pi)``, [elevation], [range rate]), compiled.

    ``x (B, n)`` has positions ``0..d-1`` and velocities ``d..2d-1``; ``sensor (B, 2d)`` the
    sensor position and velocity.
    """
    xx = np.ascontiguousarray(x, dtype=np.float64)
    ss = np.ascontiguousarray(sensor, dtype=np.float64)
    m = d + int(range_rate)
    hx = np.empty((xx.shape[0], m))
    H = np.empty((xx.shape[0], m, xx.shape[1]))
    with np.errstate(all="ignore"):
        polar_core(xx, ss, d, bool(range_rate), hx, H)
    return hx, H
