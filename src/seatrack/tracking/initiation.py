"""Track initiation: two-point pairs with a speed gate, and M-of-N confirmation.

**Two-point initiation.** Plots of the previous scan that no track took are paired with
this scan's free plots. A pair ``(p1, p2)`` (Cartesian positions, linearised polar
covariances ``C1``, ``C2``, time step ``dt``) passes the *speed gate* when the part of the
displacement beyond ``max_speed * dt``::

    e = (p2 - p1) * max(0, 1 - max_speed dt / |p2 - p1|)

is explainable by the noise: ``e^T (C1 + C2)^-1 e <= gamma_d`` (chi-square quantile of the
gate probability, ``d`` degrees of freedom). Candidates are found with a KD-tree (radius
``max_speed dt`` plus a noise bound), so the cost grows about linearly with the plots. Each
plot starts at most one track: the pairs are chosen by a global assignment that maximises
the number of pairs and then their likelihood under a zero-mean velocity prior with
standard deviation ``speed_sigma`` per axis (the target class's speeds, random courses;
by default ``max_speed / sqrt(6)``: speeds uniform up to ``max_speed``). Free plots wait
up to ``init_scans - 1`` scans for a partner, so a missed detection right after a
target's first plot does not delay its track.

The new track (:class:`~seatrack.tracking.initiators.TwoPointInitiator`) is the first
plot with that velocity prior (:func:`seatrack.filters.base.plot_gaussian`), predicted to
the second plot's time and updated with it by the per-track filter: the exact Bayesian
fusion of the prior and the two plots. Taking the velocity from the difference of the two
plots alone (:func:`~seatrack.filters.base.two_point_gaussian`) ignores that ships are
slow: at 10 km a 0.3 deg azimuth error is 50 m, a velocity error of ~30 m/s over a 2.5 s
scan.

**M-of-N confirmation.** A tentative track counts its hits and its age in scans from
birth (the two initiating plots count as two hits in two scans). It is confirmed as soon
as it has ``M`` hits within its first ``N`` scans -- at birth already when ``M = 2`` -- and
deleted as soon as that has become impossible.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.tracking.association import gnn
from seatrack.tracking.gating import MARGIN
from seatrack.tracking.gating import SLACK
from seatrack.tracking.gating import gate_threshold
from seatrack.tracking.gating import nis_logpdf
from seatrack.tracking.gating import pregate

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "InitPairs",
    "polar_covariance",
    "speed_gate_pairs",
    "confirmed",
    "hopeless",
]

_PAIR_BONUS = 1e6  # gain of any gated pair: more pairs first, then the likelier ones


@dataclass(frozen=True)
class InitPairs:
    """Chosen pairs: ``first`` (previous-scan plot) and ``second`` (this scan's plot)."""

    first: IntArray
    second: IntArray


def _noise_radius(
    p2: FloatArray, C2: FloatArray, sensor_pos: FloatArray, reach: float
) -> FloatArray:
    """Bound on the position noise std (m) of any plot within ``reach`` of each ``p2``."""
    d = p2.shape[1]
    tr = np.einsum("kii->k", C2)
    rho = np.linalg.norm(p2 - sensor_pos[:d], axis=1)
    # polar noise grows linearly with range: scale the cross-range part to rho + reach
    scale = (rho + reach) / np.maximum(rho, 1.0)
    return np.asarray(np.sqrt(tr) * scale)


def speed_gate_pairs(
    p1: FloatArray,
    C1: FloatArray,
    t1: FloatArray,
    p2: FloatArray,
    C2: FloatArray,
    t2: float,
    max_speed: float,
    probability: float,
    sensor_pos: FloatArray,
    speed_sigma: float | None = None,
) -> InitPairs:
    """Pairs of earlier plots ``p1 (N1, d)`` (times ``t1``) and this scan's ``p2 (N2, d)``.

    Parameters
    ----------
    p1, C1, p2, C2 : Cartesian positions (m) and covariances (m^2)
    t1 : (N1,) s -- times of the earlier plots; t2 : s -- this scan (later)
    max_speed : m/s
    probability : gate probability of the noise allowance
    sensor_pos : (3,) m -- the radar (its range scales the noise bound of the pre-search)
    speed_sigma : m/s -- velocity prior std per axis that ranks the pairs (none:
        ``max_speed / sqrt(6)``, speeds uniform up to ``max_speed``, random courses)
    """
    e = np.zeros(0, np.int64)
    if len(p1) == 0 or len(p2) == 0:
        return InitPairs(e, e.copy())
    d = p1.shape[1]
    gamma = gate_threshold(probability, d)
    dt1 = t2 - np.asarray(t1, dtype=float)
    if np.any(dt1 <= 0):
        raise ValueError("speed gate: the earlier plots must be earlier than this scan")
    reach = max_speed * float(dt1.max())
    radius = reach + MARGIN * np.sqrt(2 * gamma) * _noise_radius(p2, C2, sensor_pos, reach)
    j, i = pregate(p2, radius + SLACK, p1)
    if i.size == 0:
        return InitPairs(e, e.copy())
    dt = dt1[i]
    delta = p2[j] - p1[i]
    dist = np.linalg.norm(delta, axis=1)
    excess = delta * np.maximum(0.0, 1.0 - max_speed * dt / np.maximum(dist, 1e-9))[:, None]
    C = C1[i] + C2[j]
    ok = nis_logpdf(excess, C)[0] <= gamma
    i, j, delta, C, dt = i[ok], j[ok], delta[ok], C[ok], dt[ok]
    sigma_v = max_speed / math.sqrt(6.0) if speed_sigma is None else speed_sigma
    prior = C + np.eye(d) * ((sigma_v * dt) ** 2)[:, None, None]
    log_like = nis_logpdf(delta, prior)[1]  # -(Mahalanobis + log det + d log 2 pi) / 2
    chosen = gnn(j, i, _PAIR_BONUS + 2.0 * log_like, len(p2), len(p1))
    second = np.flatnonzero(chosen >= 0)
    return InitPairs(chosen[second], second.astype(np.int64))


def polar_covariance(plots: Plots, sensor: SensorNoise, idx: IntArray | None = None) -> FloatArray:
    """Cartesian covariance ``(N, d, d)`` of plot positions (of the plots ``idx`` when
    given): the linearised polar noise in closed form,
    ``sigma_r^2 u u^T + (r cos(el) sigma_az)^2 a a^T [+ (r sigma_el)^2 e e^T]`` with ``u``,
    ``a``, ``e`` the unit vectors along range, azimuth and elevation (equal to the
    covariance of :func:`seatrack.filters.base.plot_gaussian`, without its matrix
    inverses)."""
    sel: Any = slice(None) if idx is None else idx
    az = plots.azimuth[sel]
    sa, ca = np.sin(az), np.cos(az)
    r = plots.range[sel]
    if plots.elevation is None:
        u = np.stack([sa, ca], -1)
        a = np.stack([ca, -sa], -1)
        return np.asarray(
            sensor.sigma_range**2 * u[:, :, None] * u[:, None, :]
            + ((r * sensor.sigma_azimuth) ** 2)[:, None, None] * a[:, :, None] * a[:, None, :]
        )
    el = plots.elevation[sel]
    se, ce = np.sin(el), np.cos(el)
    u = np.stack([ce * sa, ce * ca, se], -1)
    a = np.stack([ca, -sa, np.zeros_like(sa)], -1)
    e = np.stack([-se * sa, -se * ca, ce], -1)
    outer = lambda v: v[:, :, None] * v[:, None, :]  # noqa: E731
    return np.asarray(
        sensor.sigma_range**2 * outer(u)
        + ((r * ce * sensor.sigma_azimuth) ** 2)[:, None, None] * outer(a)
        + ((r * sensor.sigma_elevation) ** 2)[:, None, None] * outer(e)
    )


# ---------------------------------------------------------------------------
# M-of-N
# ---------------------------------------------------------------------------
def confirmed(hits: IntArray, age: IntArray, m: int, n: int) -> NDArray[np.bool_]:
    """Tracks with ``M`` hits within their first ``N`` scans (``hits`` counted from birth,
    ``age`` = scans since birth, both counting the two initiating scans)."""
    return np.asarray((hits >= m) & (age <= n))


def hopeless(hits: IntArray, age: IntArray, m: int, n: int) -> NDArray[np.bool_]:
    """Tentative (not yet confirmed) tracks that can no longer reach ``M`` hits within
    their first ``N`` scans: too few hits left to come, or the window is over."""
    return np.asarray((hits + np.maximum(0, n - age) < m) | (age >= n))
