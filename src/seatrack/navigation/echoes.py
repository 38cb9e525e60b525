"""Echo gate, echo weights and the weighted landmark measurement.

Spec ``landmark_nav.md``, "Gating, echo weighting and the measurement".

* Gate: two radii ``r_c +- dr_g`` and two arcs ``phi_c +- dtheta_g`` around the predicted
  landmark. ``dr_g = (n/2) x bin`` (8 x 6 m = 48 m); the angular half-width is adaptive,
  ``min(10 deg, angle where an edge echo's weight falls to P_min = 0.001)``.
* Every above-threshold sample in the gate is an echo point with local offsets ``dr_i``
  (along the predicted line of sight) and ``dtheta_i`` (across it, clockwise positive).
* Weight ``p_i = g(z_i) / (g(z_i) + b)``: ``g`` the Gaussian density of a true echo
  (predicted spread: echo spread plus ``h A h^T``) times the expected number of true echoes,
  ``b`` the density of false (parasitic) echoes, both per square metre.
* Statistics ``z_m = sum p z / sum p``, ``m2 = sum p z^2 / sum p`` and the refined precision
  ``1/sigma_m^2 = 1/(m2 - z_m^2) - 1/sigma_u^2`` with ``sigma_u^2 = w^2/3`` the variance of
  echoes spread uniformly over the gate of half-width ``w``. No update (a missed landmark)
  if ``sum p`` is below a threshold or the refined precision is not positive, nor (beyond
  the patent) if the echoes do not make a landmark likelier than clutter alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import polar_to_cart
from seatrack.geometry import rotation_to_beam
from seatrack.geometry import wrap_pi

FloatArray = NDArray[np.float64]

__all__ = [
    "GateConfig",
    "GateStats",
    "gate_mask",
    "local_offsets",
    "echo_weights",
    "weighted_measurement",
    "adaptive_half_angle",
]


@dataclass(frozen=True)
class GateConfig:
    """Gate and weighting parameters (spec defaults).

    Attributes
    ----------
    range_half_width : m, ``(n/2) x bin`` = 8 x 6 m.
    max_half_angle : rad, upper limit of the angular half-width (10 deg).
    min_half_angle : rad, lower limit (a little more than half a beam width) [reading].
    p_min : weight of an echo at the edge of the gate (0.001).
    clutter_density : b, false echoes per m^2 per revolution.
    expected_echoes : expected number of true echo samples from a landmark in one pass
        (scales g) [reading].
    sigma_range : m, spread of true echoes in range (bin quantisation and target extent).
    sigma_angle : rad, spread of true echoes in angle (beam width / sqrt(12) and extent).
    min_sigma : m, floor on ``sqrt(m2 - z_m^2)`` (a single echo has no spread) [reading].
    min_weight_sum : missed landmark if ``sum p`` is below this [reading].
    min_log_lr : missed landmark if the log-likelihood ratio "landmark echoes and clutter"
        versus "clutter only", ``sum log(1 + g_i / b) - expected_echoes`` (Poisson numbers
        of echoes), is below this. Beyond the patent: with a large prediction covariance a
        few false echoes near the prediction otherwise pass for the landmark.
    uniform_correction : subtract ``1/sigma_u^2`` from the precision (spec); False keeps
        ``1/(m2 - z_m^2)``.
    polar_offsets : [reading] True: ``dtheta_i = r_c (phi_i - phi_c)`` as written in the
        spec; False (default): the exact components of the echo's offset from the predicted
        landmark along / across the line of sight (equal to first order, no curvature bias
        for the long gates of contour elements).
    """

    range_half_width: float = 48.0
    max_half_angle: float = float(np.radians(10.0))
    min_half_angle: float = float(np.radians(1.5))
    p_min: float = 0.001
    clutter_density: float = 1e-5
    expected_echoes: float = 5.0
    sigma_range: float = 3.5
    sigma_angle: float = float(np.radians(0.6))
    min_sigma: float = 1.5
    min_weight_sum: float = 2.0
    min_log_lr: float = 6.0
    uniform_correction: bool = True
    polar_offsets: bool = False


@dataclass(frozen=True)
class GateStats:
    """Weighted measurement of one landmark pass.

    Attributes
    ----------
    updated : bool, False for a missed landmark (no update).
    z : (m,) m, weighted mean offsets (m = 2: range, cross-range; m = 1: normal offset).
    var : (m,) m^2, refined variances ``sigma_m^2`` (NaN when not updated).
    weight_sum : float, ``sum p``.
    n_echoes : int, echo points in the gate.
    log_lr : float, log-likelihood ratio landmark-plus-clutter vs clutter only.
    """

    updated: bool
    z: FloatArray
    var: FloatArray
    weight_sum: float
    n_echoes: int
    log_lr: float = float("nan")


def gate_mask(
    r: ArrayLike,
    phi: ArrayLike,
    r_c: float,
    phi_c: float,
    half_range: float,
    half_angle: float,
) -> NDArray[np.bool_]:
    """Echo points inside the gate.

    ``|r - r_c| <= half_range`` and ``|wrap(phi - phi_c)| <= half_angle`` (m, rad).
    """
    rr = np.asarray(r, float)
    dp = np.abs(wrap_pi(np.asarray(phi, float) - phi_c))
    return np.asarray((np.abs(rr - r_c) <= half_range) & (dp <= half_angle))


def local_offsets(
    r: ArrayLike,
    phi: ArrayLike,
    r_c: float,
    theta_c: float,
    phi_c: float,
    heading: float,
    polar: bool = False,
) -> FloatArray:
    """Offsets ``(k, 2)`` = ``[dr_i, dtheta_i]`` (m) of echo points from the predicted landmark.

    Parameters
    ----------
    r, phi : echo ranges (m) and antenna angles relative to the bow (rad).
    r_c, theta_c, phi_c : predicted range, true bearing and antenna angle of the landmark.
    heading : predicted heading alpha (rad).
    polar : spec form ``[r_i - r_c, r_c wrap(phi_i - phi_c)]``; otherwise the exact
        along / across line-of-sight components of the echo's offset.
    """
    rr = np.asarray(r, float)
    pp = np.asarray(phi, float)
    if polar:
        return np.stack([rr - r_c, r_c * wrap_pi(pp - phi_c)], axis=-1)
    d = polar_to_cart(rr, pp + heading) - polar_to_cart(r_c, theta_c)
    return np.asarray(d @ rotation_to_beam(theta_c).T)


def echo_weights(z: ArrayLike, S: ArrayLike, b: float, n_true: float) -> FloatArray:
    """Echo weights ``p_i = g(z_i) / (g(z_i) + b)``.

    Parameters
    ----------
    z : (k, m) offsets of the echo points (m = 1 or 2), metres.
    S : (m, m) covariance of a true echo's offset (echo spread plus ``h A h^T``), m^2.
    b : density of false echoes in the same units as ``g`` (per m^m).
    n_true : expected number of true echoes (``g = n_true N(z; 0, S)``).
    """
    zz = np.atleast_2d(np.asarray(z, float))
    SS = np.atleast_2d(np.asarray(S, float))
    m = SS.shape[0]
    L = np.linalg.cholesky(SS)
    w = np.linalg.solve(L, zz.T)
    q = np.einsum("ik,ik->k", w, w)
    log_g = np.log(n_true) - 0.5 * q - np.log(np.diag(L)).sum() - 0.5 * m * np.log(2 * np.pi)
    # p = g / (g + b) = 1 / (1 + b / g), evaluated in log space
    return np.asarray(1.0 / (1.0 + np.exp(np.log(b) - log_g)))


def weighted_measurement(
    z: ArrayLike, p: ArrayLike, half_width: ArrayLike, config: GateConfig
) -> GateStats:
    """Weighted mean, second moment and refined variance (spec "Statistics").

    Parameters
    ----------
    z : (k, m) echo offsets (m).
    p : (k,) echo weights.
    half_width : (m,) gate half-width in each component (m), for ``sigma_u^2 = w^2/3``.
    config : GateConfig
    """
    zz = np.atleast_2d(np.asarray(z, float))
    pp = np.asarray(p, float)
    w = np.atleast_1d(np.asarray(half_width, float))
    m = w.size
    nan = np.full(m, np.nan)
    k = int(pp.size)
    sp = float(pp.sum())
    # p = g / (g + b)  =>  log(1 + g / b) = -log(1 - p)
    llr = float(-np.log(np.clip(1.0 - pp, 1e-300, 1.0)).sum() - config.expected_echoes)
    if k == 0 or sp < config.min_weight_sum or llr < config.min_log_lr:
        return GateStats(False, nan, nan, sp, k, llr)
    zm = (pp @ zz) / sp
    m2 = (pp @ zz**2) / sp
    spread = np.maximum(m2 - zm**2, config.min_sigma**2)
    prec = 1.0 / spread
    if config.uniform_correction:
        prec = prec - 3.0 / w**2
    if np.any(prec <= 0):
        return GateStats(False, zm, nan, sp, k, llr)
    return GateStats(True, zm, 1.0 / prec, sp, k, llr)


def adaptive_half_angle(
    r_c: float, S: ArrayLike, direction: ArrayLike, config: GateConfig
) -> float:
    """Angular half-width of the gate by the P_min rule (rad).

    The weight of an echo at the predicted range and cross-range offset ``t`` falls to
    ``P_min`` where ``g(t) = b P_min / (1 - P_min)``. ``direction`` maps the cross-range
    offset to the measured components (``[0, 1]`` for a point reflector's ``[dr, dtheta]``,
    ``[-sin(theta_c - beta)]`` for a contour's normal offset). Clipped to
    ``[min_half_angle, max_half_angle]``; the maximum when the weight never falls that low
    inside it (or never rises above it).
    """
    SS = np.atleast_2d(np.asarray(S, float))
    d = np.atleast_1d(np.asarray(direction, float))
    m = SS.shape[0]
    Si = np.linalg.inv(SS)
    a = float(d @ Si @ d)  # q(t) = a t^2
    log_g0 = (
        np.log(config.expected_echoes)
        - 0.5 * np.linalg.slogdet(SS)[1]
        - 0.5 * m * np.log(2 * np.pi)
    )
    log_thr = np.log(config.clutter_density) + np.log(config.p_min / (1.0 - config.p_min))
    qstar = 2.0 * (log_g0 - log_thr)
    if qstar <= 0 or a <= 1e-300:
        return config.max_half_angle
    t = np.sqrt(qstar / a)
    return float(np.clip(t / max(r_c, 1.0), config.min_half_angle, config.max_half_angle))
