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

from dataclasses import dataclass
from typing import Literal

import numpy as np
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


def _trig_moments(
    ang: FloatArray, sigma: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Moments of sin/cos of ``ang - v``, ``v ~ N(0, sigma^2)``.

    Returns ``lam, E[sin], E[cos], E[sin^2], E[cos^2], E[sin cos]`` with
    ``lam = exp(-sigma^2 / 2)``.
    """
    lam = np.exp(-0.5 * sigma**2)
    lam4 = lam**4  # exp(-2 sigma^2) = E[cos 2v]
    s, c = np.sin(ang), np.cos(ang)
    c2, s2 = np.cos(2 * ang), np.sin(2 * ang)
    return lam, lam * s, lam * c, 0.5 * (1 - lam4 * c2), 0.5 * (1 + lam4 * c2), 0.5 * lam4 * s2


def _unbiased(
    r: FloatArray,
    a: FloatArray,
    e: FloatArray | None,
    sr: FloatArray,
    sa_: FloatArray,
    se_: FloatArray | None,
) -> tuple[FloatArray, FloatArray]:
    """Unbiased converted relative position and measurement-conditioned covariance."""
    la, Esa, Eca, Esa2, Eca2, Esca = _trig_moments(a, sa_)
    r2 = r**2 + sr**2  # E[r_true^2 | measured]
    if e is None:
        u = np.stack([r * np.sin(a), r * np.cos(a)], -1) / la[..., None]
        mu = np.stack([r * Esa, r * Eca], -1)
        M2 = np.stack(
            [np.stack([r2 * Esa2, r2 * Esca], -1), np.stack([r2 * Esca, r2 * Eca2], -1)], -2
        )
    else:
        assert se_ is not None
        le, Ese, Ece, Ese2, Ece2, Esce = _trig_moments(e, se_)
        ce, sn = np.cos(e), np.sin(e)
        u = np.stack(
            [r * ce * np.sin(a) / (la * le), r * ce * np.cos(a) / (la * le), r * sn / le], -1
        )
        mu = np.stack([r * Ece * Esa, r * Ece * Eca, r * Ese], -1)
        xx = r2 * Ece2 * Esa2
        yy = r2 * Ece2 * Eca2
        xy = r2 * Ece2 * Esca
        xz = r2 * Esce * Esa
        yz = r2 * Esce * Eca
        zz = r2 * Ese2
        M2 = np.stack(
            [np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)],
            -2,
        )
    um = u[..., :, None] * mu[..., None, :]
    R = M2 - um - np.swapaxes(um, -1, -2) + u[..., :, None] * u[..., None, :]
    return u, R


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
        u, R = _unbiased(r, a, e, sr, sa_, se_)
    z = u
    if sensor is not None:
        s = np.asarray(sensor, dtype=float)[..., :d]
        z = u + s
    if sensor_cov is not None:
        R = R + np.asarray(sensor_cov, dtype=float)
    R = 0.5 * (R + np.swapaxes(R, -1, -2))
    return ConvertedMeasurement(np.asarray(z, dtype=float), R)
