"""The heading / turn-rate filter of the turning-target method (spec ``turning.md``, S2).

The turning filter (:mod:`seatrack.filters.turning`) runs a second, two-state filter on the
heading of its CV-EKF velocity: state ``(b, omega)``, heading (rad, ``(-pi, pi]``) and turn
rate (rad/s, clockwise positive), with the wrapped heading innovation. Single-track
functions (:func:`heading_filter_init`, :func:`heading_filter_step`) and their batched
forms compiled in :mod:`seatrack.filters.turning_kernel`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack import kalman
from seatrack.geometry import bearing
from seatrack.geometry import wrap_pi
from seatrack.models.motion import cv_noise
from seatrack.models.motion import cv_transition

FloatArray = NDArray[np.float64]

__all__ = [
    "H_HEADING",
    "ANGULAR_HEADING",
    "HeadingEstimate",
    "velocity_significance",
    "heading",
    "heading_jacobian",
    "heading_variance",
    "heading_filter_noise",
    "heading_filter_init",
    "heading_filter_step",
]


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


H_HEADING = np.array([[1.0, 0.0]])
ANGULAR_HEADING = np.array([True])


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
    F, Qc = cv_transition(float(dt), 1), cv_noise(float(dt), float(q), 1)
    Qb = Qc if form == "continuous" else heading_filter_noise(dt, q, form)
    sp, Pp = kalman.predict(np.asarray(s, dtype=float), np.asarray(P, dtype=float), F, Qb)
    sp[0] = wrap_pi(sp[0])
    u = kalman.extended_update(
        sp,
        Pp,
        np.array([float(b)]),
        sp[:1],
        H_HEADING,
        np.array([[float(var_b)]]),
        ANGULAR_HEADING,
    )
    u.x[0] = wrap_pi(u.x[0])
    return HeadingEstimate(u.x, u.P, float(u.y[0]), u.K[:, 0].copy())
