"""Converted measurements: radar plots (range, azimuth[, elevation]) to Cartesian position.

Shared infrastructure for every filter that tracks in Cartesian coordinates from polar
plots (multimodel spec, "Model": *Polar measurements are converted to Cartesian position
Z_k with covariance R_k ... [reading] use the standard linearised conversion, or a
debiased converted-measurement covariance*). Both readings are provided:

``"linearized"``
    ``Z = sensor + r [cos e sin a, cos e cos a, sin e]`` at the measured values and
    ``R = J diag(sigma^2) J^T`` with ``J`` the Jacobian of the conversion at the measured
    values (:func:`polar_jacobian`). Biased and optimistic when the cross-range error
    ``r sigma_a`` is large compared with ``sigma_r`` (Lerro & Bar-Shalom 1993).
``"unbiased"``
    The unbiased converted measurement (multiplicative debiasing) of Mo Longbin et al.,
    "Unbiased converted measurements for tracking", IEEE Trans. AES 34(3), 1998, with the
    *measurement-conditioned* covariance (Duan, Han & Li, "Comments on 'Unbiased converted
    measurements for tracking'", IEEE Trans. AES 40(4), 2004):
    ``Z = sensor + u``, ``u = [r ce sa / (la le), r ce ca / (la le), r se / le]`` with
    ``la = exp(-sigma_a^2/2)``, ``le = exp(-sigma_e^2/2)`` (so ``E[u | truth] = truth``), and
    ``R = E[(u - p)(u - p)^T | measured]`` where the true relative position ``p`` is the
    measured polar values minus zero-mean Gaussian noise. Writing ``mu = E[p | measured]``
    and ``M2 = E[p p^T | measured]`` (closed form from the Gaussian characteristic
    function, e.g. ``E[sin^2(a - v)] = (1 - exp(-2 sigma^2) cos 2a) / 2``),
    ``R = M2 - mu u^T - u mu^T + u u^T``. In 2-D this is exactly Longbin's eq. (11)-(13)
    with the axes swapped for azimuth clockwise from North.

Conventions: azimuth clockwise from North, elevation up from the horizontal; x East,
y North, z Up; metres and radians. A moving sensor is supported by giving its position
at each plot (``sensor``); the sensor position is taken as known exactly unless
``sensor_cov`` is given (then it is added to ``R``). Everything broadcasts over leading
dimensions. 2-D plots (no elevation) give ``d = 2`` outputs, 3-D plots ``d = 3``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numba import njit
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import polar_to_cart
from seatrack.geometry import spherical_to_cart

FloatArray = NDArray[np.float64]

__all__ = [
    "ConvertedMeasurement",
    "Conversion",
    "polar_jacobian",
    "convert_plots",
]

Conversion = Literal["linearized", "unbiased"]
_METHODS = ("linearized", "unbiased")


@dataclass(frozen=True, slots=True)
class ConvertedMeasurement:
    """Cartesian position measurement with its covariance.

    Attributes
    ----------
    z : ndarray (..., d)
        Position East, North[, Up], m, in the world frame (sensor position added).
    R : ndarray (..., d, d)
        Covariance of the conversion error ``z - true position``, m^2 (symmetric PD).
    """

    z: FloatArray
    R: FloatArray


def polar_jacobian(rng: ArrayLike, az: ArrayLike, el: ArrayLike | None = None) -> FloatArray:
    """Jacobian of the polar-to-Cartesian conversion w.r.t. ``(r, az[, el])``.

    Parameters
    ----------
    rng : array (...)
        Range, m.
    az : array (...)
        Azimuth, rad, clockwise from North.
    el : array (...), optional
        Elevation, rad, up. ``None`` for 2-D.

    Returns
    -------
    ndarray (..., d, d)
        Rows ``x, y[, z]`` (East, North, Up); columns ``r, az[, el]``.
    """
    r = np.asarray(rng, dtype=float)
    a = np.asarray(az, dtype=float)
    sa, ca = np.sin(a), np.cos(a)
    if el is None:
        r, sa, ca = np.broadcast_arrays(r, sa, ca)
        return np.stack([np.stack([sa, r * ca], -1), np.stack([ca, -r * sa], -1)], -2)
    e = np.asarray(el, dtype=float)
    se, ce = np.sin(e), np.cos(e)
    r, sa, ca, se, ce = np.broadcast_arrays(r, sa, ca, se, ce)
    return np.stack(
        [
            np.stack([ce * sa, r * ce * ca, -r * se * sa], -1),
            np.stack([ce * ca, -r * ce * sa, -r * se * ca], -1),
            np.stack([se, np.zeros_like(r), r * ce], -1),
        ],
        -2,
    )


@njit(cache=True, inline="always")
def _trig_moments(ang, sigma):  # pragma: no cover - compiled
    """``lam = exp(-sigma^2 / 2)`` and the moments ``E[sin], E[cos], E[sin^2], E[cos^2],
    E[sin cos]`` of the true angle given the measured ``ang`` (noise std ``sigma``)."""
    lam = math.exp(-0.5 * sigma**2)
    lam4 = lam**4  # exp(-2 sigma^2) = E[cos 2v]
    c2, s2 = math.cos(2.0 * ang), math.sin(2.0 * ang)
    return (
        lam, lam * math.sin(ang), lam * math.cos(ang),
        0.5 * (1 - lam4 * c2), 0.5 * (1 + lam4 * c2), 0.5 * lam4 * s2,
    )  # fmt: skip


@njit(cache=True)
def _unbiased_kernel(r, a, e, sr, sa, se, u, R):  # pragma: no cover - compiled
    """Unbiased converted relative positions ``u (N, d)`` and their measurement-conditioned
    covariances ``R (N, d, d)`` of flat plot arrays (``e`` and ``se`` empty for 2-D plots).

    With ``lam = exp(-sigma^2 / 2)`` of each angle, the moments of ``sin``/``cos`` of the
    true angle given the measured one are ``E[sin] = lam sin a``, ``E[cos] = lam cos a``,
    ``E[sin^2] = (1 - lam^4 cos 2a) / 2``, ``E[cos^2] = (1 + lam^4 cos 2a) / 2``,
    ``E[sin cos] = lam^4 sin 2a / 2``, and ``E[r_true^2] = r^2 + sigma_r^2``; the converted
    position ``u`` divides the plain conversion by the ``lam`` factors, ``mu`` is its
    conditional mean and ``M2`` its conditional second moment, ``R = M2 - u mu^T - mu u^T +
    u u^T`` (the module docstring gives the references). One plot at a time: the
    small batches of one scan pay no NumPy per-call cost."""
    d = u.shape[1]
    uu = np.empty(3)
    mu = np.empty(3)
    M2 = np.empty((3, 3))
    for i in range(r.size):
        la, Esa, Eca, Esa2, Eca2, Esca = _trig_moments(a[i], sa[i])
        r2 = r[i] ** 2 + sr[i] ** 2
        ri = r[i]
        if d == 2:
            uu[0], uu[1] = ri * math.sin(a[i]) / la, ri * math.cos(a[i]) / la
            mu[0], mu[1] = ri * Esa, ri * Eca
            M2[0, 0], M2[0, 1], M2[1, 1] = r2 * Esa2, r2 * Esca, r2 * Eca2
        else:
            le, Ese, Ece, Ese2, Ece2, Esce = _trig_moments(e[i], se[i])
            ce = math.cos(e[i])
            uu[0] = ri * ce * math.sin(a[i]) / (la * le)
            uu[1] = ri * ce * math.cos(a[i]) / (la * le)
            uu[2] = ri * math.sin(e[i]) / le
            mu[0], mu[1], mu[2] = ri * Ece * Esa, ri * Ece * Eca, ri * Ese
            M2[0, 0], M2[0, 1], M2[1, 1] = r2 * Ece2 * Esa2, r2 * Ece2 * Esca, r2 * Ece2 * Eca2
            M2[0, 2], M2[1, 2], M2[2, 2] = r2 * Esce * Esa, r2 * Esce * Eca, r2 * Ese2
        for j in range(d):
            u[i, j] = uu[j]
            for k in range(j, d):
                v = M2[j, k] - uu[j] * mu[k] - mu[j] * uu[k] + uu[j] * uu[k]
                R[i, j, k] = v
                R[i, k, j] = v


def convert_plots(
    rng: ArrayLike,
    az: ArrayLike,
    el: ArrayLike | None,
    sigma_range: ArrayLike,
    sigma_azimuth: ArrayLike,
    sigma_elevation: ArrayLike | None = None,
    sensor: ArrayLike | None = None,
    method: Conversion = "unbiased",
    sensor_cov: ArrayLike | None = None,
) -> ConvertedMeasurement:
    """Convert radar plots to Cartesian positions with a consistent covariance.

    Parameters
    ----------
    rng : array (...)
        Measured range, m (> 0).
    az : array (...)
        Measured azimuth, rad, clockwise from North.
    el : array (...) or None
        Measured elevation, rad, up; ``None`` for 2-D plots (output ``d = 2``).
    sigma_range, sigma_azimuth, sigma_elevation : array (...) or float
        Standard deviations of the polar noise (m, rad, rad). ``sigma_elevation`` is
        required with ``el``.
    sensor : array (..., 2 or 3), optional
        Sensor position at each plot (East, North[, Up]), m; default the origin. Only the
        first ``d`` components are used.
    method : {"linearized", "unbiased"}
        See the module docstring.
    sensor_cov : array (..., d, d), optional
        Covariance of the sensor position, added to ``R``.

    Returns
    -------
    ConvertedMeasurement
        ``z (..., d)`` in the world frame and ``R (..., d, d)``.

    Raises
    ------
    ValueError
        Unknown method, missing ``sigma_elevation``, non-positive range or negative sigma.
    """
    if method not in _METHODS:
        raise ValueError(f"unknown conversion {method!r}; choose one of {', '.join(_METHODS)}")
    r = np.asarray(rng, dtype=float)
    a = np.asarray(az, dtype=float)
    e = None if el is None else np.asarray(el, dtype=float)
    if np.any(r <= 0):
        raise ValueError("range must be > 0 for a polar-to-Cartesian conversion")
    sr = np.asarray(sigma_range, dtype=float)
    sa_ = np.asarray(sigma_azimuth, dtype=float)
    if e is not None and sigma_elevation is None:
        raise ValueError("sigma_elevation is required for 3-D plots (elevation given)")
    se_ = None if e is None else np.asarray(sigma_elevation, dtype=float)
    for name, s in (("sigma_range", sr), ("sigma_azimuth", sa_), ("sigma_elevation", se_)):
        if s is not None and (np.any(s < 0) or not np.all(np.isfinite(s))):
            raise ValueError(f"{name} must be finite and >= 0")
    d = 2 if e is None else 3
    shape = np.broadcast_shapes(r.shape, a.shape, () if e is None else e.shape)
    r = np.broadcast_to(r, shape)
    a = np.broadcast_to(a, shape)
    sr = np.broadcast_to(sr, shape)
    sa_ = np.broadcast_to(sa_, shape)
    if e is not None:
        assert se_ is not None
        e = np.broadcast_to(e, shape)
        se_ = np.broadcast_to(se_, shape)
    if method == "linearized":
        u = polar_to_cart(r, a) if e is None else spherical_to_cart(r, a, e)
        J = polar_jacobian(r, a, e)
        sig = np.stack([sr, sa_] if se_ is None else [sr, sa_, se_], -1)
        R = np.einsum("...ik,...k,...jk->...ij", J, sig**2, J)
    else:
        n = int(np.prod(shape))
        u, R = np.empty((n, d)), np.empty((n, d, d))
        flat = [np.ascontiguousarray(v, dtype=float).reshape(n) for v in (r, a, sr, sa_)]
        ee = np.zeros(0) if e is None else np.ascontiguousarray(e, dtype=float).reshape(n)
        se = np.zeros(0) if se_ is None else np.ascontiguousarray(se_, dtype=float).reshape(n)
        _unbiased_kernel(flat[0], flat[1], ee, flat[2], flat[3], se, u, R)
        u, R = u.reshape(shape + (d,)), R.reshape(shape + (d, d))
    z = u
    if sensor is not None:
        s = np.asarray(sensor, dtype=float)[..., :d]
        z = u + s
    if sensor_cov is not None:
        R = R + np.asarray(sensor_cov, dtype=float)
    R = 0.5 * (R + np.swapaxes(R, -1, -2))
    return ConvertedMeasurement(np.asarray(z, dtype=float), R)
