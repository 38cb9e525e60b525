"""Measurements beside bearings: tonal frequencies (Doppler) and angles on the bow (ATB).

Conventions (x East, y North; angles in radians clockwise from North; SI units):

* ``p(t)`` target position, ``o(t)`` own-ship (observer) position, ``R = |p - o|`` and
  ``u = (p - o) / R`` the unit line of sight from the own ship to the target.
* Line-of-sight speeds, positive *closing*: ``v_own,los = v_own . u`` (own ship moving
  towards the target) and ``v_tgt,los = -v_tgt . u`` (target moving towards the own ship).
* **Received frequency** of a tonal radiated at the base frequency ``f0`` (Hz), sound speed
  ``c`` (m/s), first-order-exact moving source and moving receiver::

      f = f0 (c + v_own,los) / (c - v_tgt,los) = f0 (c + v_own . u) / (c + v_tgt . u)

  so a closing geometry raises the frequency. ``g = f / f0`` is the *Doppler ratio*.
  Its derivatives (``b = c + v_tgt . u``, ``P = I - u u^T``)::

      dg/dp     = (v_own - g v_tgt)^T P / (R b)
      dg/dv_tgt = -g u / b

* **Angle on the bow** (ATB) -- the relative bearing of the own ship seen from the target's
  bow, positive to starboard (clockwise)::

      ATB = wrap(bearing(o - p) - course(v_tgt))   in (-pi, pi]

  0 = the target heads straight at the own ship, +-pi = it heads directly away.
  ``d ATB / dp = -bearing_jacobian(o - p)`` and ``d ATB / dv = -bearing_jacobian(v)``.

Positions and velocities enter through the coefficient rows of :mod:`seatrack.tma.legs`:
``p(t_i) = c_i @ B`` and ``v(t_i) = e_i @ B`` with ``e_i`` the one-hot row of the leg that
``t_i`` falls in. Base frequencies are nuisance parameters: for the tonals whose ``f0`` is
not given, :func:`frequency_residuals` eliminates ``f0`` in closed form (weighted least
squares given the kinematic state) and projects the Jacobian accordingly (variable
projection, Kaufman's form), so the Gauss--Newton matrix is the Schur complement -- the
information of the kinematic state with ``f0`` unknown.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from dataclasses import field

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import bearing
from seatrack.geometry import wrap_pi
from seatrack.models.measurement import bearing_jacobian

FloatArray = NDArray[np.float64]

__all__ = [
    "SOUND_SPEED",
    "BowAngles",
    "Frequencies",
    "bow_angle",
    "bow_angle_residuals",
    "doppler_ratio",
    "frequency_residuals",
    "observer_velocity",
]

#: default speed of sound in sea water, m/s
SOUND_SPEED = 1500.0


def _vector(a: ArrayLike, n: int, name: str) -> FloatArray:
    v = np.asarray(a, dtype=float).reshape(-1)
    if v.size != n:
        raise ValueError(f"{name} has {v.size} values for {n} times")
    return v


def _xy(a: ArrayLike, n: int, name: str) -> FloatArray:
    v = np.asarray(a, dtype=float)
    if v.ndim != 2 or v.shape[0] != n or v.shape[1] < 2:
        raise ValueError(f"{name} must have shape ({n}, 2), got {v.shape}")
    return np.ascontiguousarray(v[:, :2])


def _finite(name: str, a: FloatArray) -> None:
    if not a.size:
        return
    bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(a.shape[0], -1)), axis=1))
    if bad.size:
        raise ValueError(f"{name} is not finite at index {bad[0]}")


def _sigma(s: ArrayLike, n: int, name: str) -> FloatArray:
    v = np.broadcast_to(np.asarray(s, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(v) & (v > 0)):
        raise ValueError(f"{name} sigma must be finite and positive")
    return v


@dataclass(frozen=True)
class Frequencies:
    """Received tonal frequencies of one contact (SI units).

    Parameters
    ----------
    t : (F,) s, measurement times (any order; not before the contact's first bearing).
    frequency : (F,) Hz, received frequency (positive).
    observer : (F, 2) m, own-ship position (East, North).
    observer_velocity : (F, 2) m/s, own-ship velocity (see :func:`observer_velocity`).
    sigma : (F,) or scalar, Hz, standard deviation of each frequency.
    tonal : (F,) tonal ids (strings); one base frequency per tonal. Default: one tonal ``"1"``.
    base_frequency : mapping tonal id -> known base frequency ``f0`` (Hz); tonals not in it
        have ``f0`` estimated.
    """

    t: FloatArray
    frequency: FloatArray
    observer: FloatArray
    observer_velocity: FloatArray
    sigma: FloatArray
    tonal: NDArray[np.str_] | None = None
    base_frequency: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).reshape(-1)
        n = t.size
        f = _vector(self.frequency, n, "frequency")
        o = _xy(self.observer, n, "observer")
        v = _xy(self.observer_velocity, n, "observer_velocity")
        for name, a in (("t", t), ("frequency", f), ("observer", o), ("observer_velocity", v)):
            _finite(name, a)
        if np.any(f <= 0):
            raise ValueError(f"frequency must be positive, got {f[f <= 0][0]:g} Hz")
        ton = np.full(n, "1") if self.tonal is None else np.asarray(self.tonal).astype(str)
        if ton.shape != (n,):
            raise ValueError(f"tonal has shape {ton.shape} for {n} times")
        base = {str(k): float(x) for k, x in self.base_frequency.items()}
        for k, x in base.items():
            if not (np.isfinite(x) and x > 0):
                raise ValueError(f"base frequency of tonal {k!r} must be positive, got {x}")
        for name, val in (("t", t), ("frequency", f), ("observer", o), ("observer_velocity", v)):
            object.__setattr__(self, name, val)
        object.__setattr__(self, "sigma", _sigma(self.sigma, n, "frequency"))
        object.__setattr__(self, "tonal", ton)
        object.__setattr__(self, "base_frequency", base)

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def tonals(self) -> list[str]:
        """Tonal ids in order of first appearance."""
        assert self.tonal is not None
        _, first = np.unique(self.tonal, return_index=True)
        return [str(x) for x in self.tonal[np.sort(first)]]

    def subset(self, index: NDArray[np.int64]) -> Frequencies:
        """The rows ``index`` (same tonals' base frequencies)."""
        assert self.tonal is not None
        return Frequencies(
            self.t[index], self.frequency[index], self.observer[index],
            self.observer_velocity[index], self.sigma[index], self.tonal[index],
            self.base_frequency,
        )  # fmt: skip


@dataclass(frozen=True)
class BowAngles:
    """Angles on the bow of one contact (radians; see the module docstring).

    Parameters
    ----------
    t : (A,) s; angle : (A,) rad, ATB in any wrap; observer : (A, 2) m; sigma : (A,) rad.
    """

    t: FloatArray
    angle: FloatArray
    observer: FloatArray
    sigma: FloatArray

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).reshape(-1)
        n = t.size
        a = _vector(self.angle, n, "angle")
        o = _xy(self.observer, n, "observer")
        for name, val in (("t", t), ("angle", a), ("observer", o)):
            _finite(name, val)
            object.__setattr__(self, name, val)
        object.__setattr__(self, "sigma", _sigma(self.sigma, n, "ATB"))

    def __len__(self) -> int:
        return int(self.t.size)

    def subset(self, index: NDArray[np.int64]) -> BowAngles:
        """The rows ``index``."""
        return BowAngles(self.t[index], self.angle[index], self.observer[index], self.sigma[index])


def observer_velocity(t: ArrayLike, observer: ArrayLike) -> FloatArray:
    """Own-ship velocity ``(N, 2)`` (m/s) from positions by second-order finite differences
    (one-sided at the ends; repeated times share their neighbours' difference)."""
    tt = np.asarray(t, dtype=float).reshape(-1)
    o = np.asarray(observer, dtype=float)[:, :2]
    if tt.size < 2:
        return np.zeros((tt.size, 2))
    ut, inv = np.unique(tt, return_inverse=True)
    if ut.size < 2:
        return np.zeros((tt.size, 2))
    ou = np.stack([np.bincount(inv, o[:, k]) / np.bincount(inv) for k in range(2)], axis=1)
    v = np.gradient(ou, ut, axis=0, edge_order=2 if ut.size > 2 else 1)
    return np.asarray(v[inv], dtype=float)


def doppler_ratio(
    d: ArrayLike, v_own: ArrayLike, v_tgt: ArrayLike, c: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Doppler ratio ``g = (c + v_own . u) / (c + v_tgt . u)`` and its derivatives.

    Parameters
    ----------
    d : (..., 2) m, target minus own-ship position; v_own, v_tgt : (..., 2) m/s; c : m/s.

    Returns
    -------
    g : (...,) dimensionless; dg_dp : (..., 2) per m; dg_dv : (..., 2) per m/s (target
    velocity).
    """
    dd = np.asarray(d, dtype=float)
    vo = np.asarray(v_own, dtype=float)
    vt = np.asarray(v_tgt, dtype=float)
    R = np.hypot(dd[..., 0], dd[..., 1])
    R = np.where(R > 0, R, 1.0)
    ux, uy = dd[..., 0] / R, dd[..., 1] / R
    a = c + vo[..., 0] * ux + vo[..., 1] * uy
    b = c + vt[..., 0] * ux + vt[..., 1] * uy
    g = a / b
    wx, wy = vo[..., 0] - g * vt[..., 0], vo[..., 1] - g * vt[..., 1]
    wu = wx * ux + wy * uy
    Rb = R * b
    dg_dp = np.stack([(wx - wu * ux) / Rb, (wy - wu * uy) / Rb], axis=-1)
    gb = -g / b
    dg_dv = np.stack([gb * ux, gb * uy], axis=-1)
    return g, dg_dp, dg_dv


def bow_angle(d: ArrayLike, v_tgt: ArrayLike) -> FloatArray:
    """ATB (rad, ``(-pi, pi]``) for target-minus-observer ``d (..., 2)`` and velocity."""
    dd = np.asarray(d, dtype=float)
    vt = np.asarray(v_tgt, dtype=float)
    return np.asarray(
        wrap_pi(bearing(-dd[..., 0], -dd[..., 1]) - bearing(vt[..., 0], vt[..., 1])), dtype=float
    )


def _positions(B: FloatArray, C: FloatArray, E: FloatArray) -> tuple[FloatArray, FloatArray]:
    return C @ B, E @ B


def _columns(C: FloatArray, E: FloatArray, gp: FloatArray, gv: FloatArray) -> FloatArray:
    """Jacobian rows ``(..., N, 2(1 + L))`` of ``f(p_i, v_i)`` from ``df/dp``, ``df/dv``."""
    J = np.empty(C.shape[:-1] + (2 * C.shape[-1],))
    for k in range(2):  # East, North columns
        J[..., k::2] = C * gp[..., k : k + 1] + E * gv[..., k : k + 1]
    return J


def frequency_residuals(
    beta: ArrayLike,
    C: ArrayLike,
    E: ArrayLike,
    observer: ArrayLike,
    v_own: ArrayLike,
    z: ArrayLike,
    w: ArrayLike,
    onehot: ArrayLike,
    f0_fixed: ArrayLike,
    c: float,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Frequency residuals with the unknown base frequencies eliminated, batched.

    Parameters
    ----------
    beta : (..., n) kinematic state; C, E : (..., F, 1 + L) position / velocity coefficient
        rows; observer : (..., F, 2) m; v_own : (..., F, 2) m/s; z : (..., F) Hz;
    w : (..., F) weights ``1/sigma^2`` (Hz^-2); onehot : (..., F, T) tonal membership;
    f0_fixed : (..., T) known base frequency (Hz) or NaN where estimated; c : m/s.

    Returns
    -------
    r : (..., F) Hz, ``z - f0 g``; J : (..., F, n) the projected Jacobian (Hz per state unit;
    the Gauss--Newton matrix ``J^T W J`` is the information of ``beta`` with the unknown
    ``f0`` eliminated); f0 : (..., T) Hz, the given or the weighted least-squares base
    frequency at ``beta``; G : (..., F) the Doppler ratios ``g`` (``d h / d f0``).
    """
    b = np.asarray(beta, dtype=float)
    CC = np.asarray(C, dtype=float)
    EE = np.asarray(E, dtype=float)
    B = b.reshape(b.shape[:-1] + (-1, 2))
    p, v = _positions(B, CC, EE)
    g, gp, gv = doppler_ratio(p - np.asarray(observer, dtype=float), v_own, v, c)
    O = np.asarray(onehot, dtype=float)
    ww = np.asarray(w, dtype=float)
    zz = np.asarray(z, dtype=float)
    fixed = np.asarray(f0_fixed, dtype=float)
    est = np.isnan(fixed)
    wg = (ww * g)[..., None] * O  # (..., F, T)
    sgg = np.sum(wg * g[..., None], axis=-2)
    sfg = np.sum(wg * zz[..., None], axis=-2)
    ok = sgg > 0
    f0_ls = np.where(ok, sfg / np.where(ok, sgg, 1.0), 0.0)
    f0 = np.where(est, f0_ls, np.nan_to_num(fixed))
    f0_row = np.sum(O * f0[..., None, :], axis=-1)
    r = zz - f0_row * g
    J = f0_row[..., None] * _columns(CC, EE, gp, gv)
    # variable projection: remove from each row the part explained by a change of f0
    proj = np.swapaxes(wg, -1, -2) @ J  # (..., T, n)
    scale = np.where(est & ok, 1.0 / np.where(ok, sgg, 1.0), 0.0)
    J = J - g[..., None] * (O @ (proj * scale[..., None]))
    return np.asarray(r, dtype=float), np.asarray(J, dtype=float), f0, np.asarray(g)


def bow_angle_residuals(
    beta: ArrayLike, C: ArrayLike, E: ArrayLike, observer: ArrayLike, z: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """ATB residuals ``wrap(z - h)`` (rad) and Jacobian ``dh/dbeta``, batched.

    ``C``, ``E`` : (..., A, 1 + L) position / velocity coefficient rows; observer (..., A, 2).
    """
    b = np.asarray(beta, dtype=float)
    CC = np.asarray(C, dtype=float)
    EE = np.asarray(E, dtype=float)
    B = b.reshape(b.shape[:-1] + (-1, 2))
    p, v = _positions(B, CC, EE)
    d = p - np.asarray(observer, dtype=float)
    h = bow_angle(d, v)
    r = wrap_pi(np.asarray(z, dtype=float) - h)
    with np.errstate(invalid="ignore", divide="ignore"):
        gp = -bearing_jacobian(-d)  # d bearing(o - p) / dp
        gv = -bearing_jacobian(v)  # -d course(v) / dv
    J = _columns(CC, EE, np.nan_to_num(gp), np.nan_to_num(gv))
    return np.asarray(r, dtype=float), J
