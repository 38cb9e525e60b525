"""Gating: which plots may belong to which tracks.

Two stages, so that the cost grows about linearly with the numbers of tracks and plots:

1. **Coarse spatial pre-gate** (:func:`pregate`): the plots within a radius ``r_i`` of each
   track's predicted position -- a KD-tree search, or all pairs at once when there are few
   (``B N <= 4096``). The radius bounds the Mahalanobis gate from above: the squared
   Mahalanobis distance of the position part of an innovation is at most that of the whole
   innovation, and the largest eigenvalue of the Cartesian position innovation covariance
   is at most ``trace(P_pos) + max(sigma_r, rho sigma_az, rho sigma_el)^2`` (``rho`` the
   track's range), so ``r_i = margin * sqrt(gamma * bound) + slack`` keeps every plot that
   can pass the gate (``margin`` and ``slack`` absorb the linearisation of the polar noise).
2. **Mahalanobis gate** (:func:`gate`): the filter's own innovation ``(y, S)``
   (:meth:`~seatrack.filters.base.RecursiveFilter.innovation`, one batched call over every
   candidate pair) gives ``d^2 = y^T S^-1 y``; pairs with ``d^2 <= gamma`` pass, where
   ``gamma`` is the chi-square quantile of the gate probability for ``m`` = the innovation
   dimension. The log-likelihood ``log N(y; 0, S)`` of each passing pair is kept for
   association.

Each filter's innovation lives in its own measurement space: polar (range, azimuth,
[elevation], [range rate]) for the EKF-type filters, converted Cartesian positions for the
filters on converted plots. Association weighs the innovation density against the clutter
density, which is uniform in the *polar* space (:mod:`~seatrack.tracking.clutter`), so the
density of a Cartesian innovation is carried to the polar space by the Jacobian of the
conversion, ``|d(x, y)/d(r, az)| = r`` (3-D: ``r^2 cos(el)``). :func:`innovation_space`
tells the two apart once per filter, numerically (:data:`POLAR` or :data:`CARTESIAN`).
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from seatrack.filters.base import Plots
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.kalman import chi2_ppf

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "Candidates",
    "POLAR",
    "CARTESIAN",
    "gate_threshold",
    "innovation_space",
    "log_jacobian",
    "pregate_radius",
    "pregate",
    "ball_pairs",
    "gate",
    "nis_logpdf",
]

_LOG_2PI = float(np.log(2 * np.pi))
#: pre-gate radius = MARGIN * sqrt(gamma * bound) + SLACK (m): linearisation allowance
MARGIN = 1.25
SLACK = 20.0
#: all pairs at once (no KD-tree) up to this many track-plot pairs
BRUTE_FORCE_PAIRS = 4096
#: innovation spaces (:func:`innovation_space`)
POLAR, CARTESIAN = "polar", "cartesian"


@functools.lru_cache(maxsize=64)
def gate_threshold(probability: float, m: int) -> float:
    """Chi-square quantile ``gamma`` with ``P(d^2 <= gamma) = probability`` for ``m`` dof."""
    if not 0 < probability < 1:
        raise ValueError(f"gate probability must be in (0, 1), got {probability}")
    return chi2_ppf(probability, m)


@dataclass(frozen=True)
class Candidates:
    """Track-plot pairs that passed the gate.

    Attributes
    ----------
    track, plot : (K,) int -- indices into the track batch and the scan's plots (sorted by
        track)
    nis : (K,) -- squared Mahalanobis distance of the innovation
    log_g : (K,) -- innovation log density per unit of the *polar* measurement space
    m : innovation dimension
    """

    track: IntArray
    plot: IntArray
    nis: FloatArray
    log_g: FloatArray
    m: int

    def __len__(self) -> int:
        return int(self.track.size)

    def take(self, idx: NDArray[np.bool_] | IntArray) -> Candidates:
        return Candidates(self.track[idx], self.plot[idx], self.nis[idx], self.log_g[idx], self.m)


@njit(cache=True)
def _nis_logpdf_kernel(y, S, nis, logpdf):  # pragma: no cover - compiled
    K, m = y.shape
    L = np.empty((m, m))
    w = np.empty(m)
    for k in range(K):
        ok = True
        for i in range(m):
            if not (np.isfinite(y[k, i])):
                ok = False
        logdet = 0.0
        for j in range(m):  # Cholesky S = L L^T
            if not ok:
                break
            acc = S[k, j, j]
            for p in range(j):
                acc -= L[j, p] * L[j, p]
            if not acc > 0.0:  # also NaN
                ok = False
                break
            L[j, j] = math.sqrt(acc)
            logdet += 2.0 * math.log(L[j, j])
            for i in range(j + 1, m):
                acc = S[k, i, j]
                for p in range(j):
                    acc -= L[i, p] * L[j, p]
                L[i, j] = acc / L[j, j]
        if not ok:
            nis[k] = np.inf
            logpdf[k] = -np.inf
            continue
        d2 = 0.0
        for i in range(m):  # forward substitution L w = y
            acc = y[k, i]
            for p in range(i):
                acc -= L[i, p] * w[p]
            w[i] = acc / L[i, i]
            d2 += w[i] * w[i]
        nis[k] = d2
        logpdf[k] = -0.5 * (d2 + logdet + m * 1.8378770664093453)


def nis_logpdf(y: FloatArray, S: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``y^T S^-1 y`` and ``log N(y; 0, S)`` for batches ``y (K, m)``, ``S (K, m, m)``
    (compiled Cholesky per pair).

    Pairs whose ``S`` is not positive definite, or whose ``y`` is not finite, get
    ``nis = inf`` and ``log N = -inf`` (they fail every gate).
    """
    K = y.shape[0]
    nis, logpdf = np.empty(K), np.empty(K)
    if K:
        _nis_logpdf_kernel(
            np.ascontiguousarray(y, dtype=np.float64),
            np.ascontiguousarray(S, dtype=np.float64),
            nis,
            logpdf,
        )
    return nis, logpdf


# ---------------------------------------------------------------------------
# The filter's innovation space
# ---------------------------------------------------------------------------
def innovation_space(flt: RecursiveFilter, sensor: SensorNoise) -> str:
    """:data:`POLAR` or :data:`CARTESIAN`: the space of ``flt``'s innovations, measured.

    A track 10 km from the sensor is predicted one second and its innovations are taken
    with plots moved by small steps in range and azimuth [and elevation]; the log
    determinant of the finite-difference Jacobian ``dy/dz`` is 0 for polar innovations and
    ``(d - 1) log r`` for converted Cartesian ones.

    Raises
    ------
    ValueError
        When the Jacobian matches neither (the tracker could not weigh the filter's
        likelihoods against the clutter density).
    """
    d, r0 = flt.d, 10_000.0
    x = np.zeros((1, 2 * d))
    x[0, 1] = r0
    x[0, d + 1] = 5.0
    P = np.diag(np.r_[np.full(d, 50.0**2), np.full(d, 5.0**2)])[None]
    state = flt.predict(flt.initiate(np.zeros(1), x, P), np.ones(1))
    steps = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1e-4, 0.0), (0.0, 0.0, 1e-4)][: d + 1]
    ys = []
    for dr, da, de in steps:
        plots = Plots(
            np.ones(1), np.array([r0 + 5.0 + dr]), np.array([1e-3 + da]),
            np.array([1e-3 + de]) if d == 3 else None,
            np.array([5.0]) if flt.range_rate else None,
        )  # fmt: skip
        ys.append(np.asarray(flt.innovation(state, plots)[0][0, :d], dtype=float))
    J = np.stack([(ys[k + 1] - ys[0]) / max(steps[k + 1]) for k in range(d)], -1)
    with np.errstate(divide="ignore"):
        logdet = float(np.log(abs(np.linalg.det(J))))
    cart = (d - 1) * math.log(r0)
    if abs(logdet) < 0.1 * cart:
        return POLAR
    if abs(logdet - cart) < 0.1 * cart:
        return CARTESIAN
    raise ValueError(
        f"{type(flt).__name__}: innovations are neither polar nor converted Cartesian "
        f"(log |dy/dz| = {logdet:.2f}); the tracker cannot weigh them against the clutter"
    )


def log_jacobian(space: str, plots: Plots) -> FloatArray:
    """``log |d(innovation)/d(polar plot)|`` per plot: 0 for :data:`POLAR`, ``(d - 1) log r
    [+ log cos(el)]`` for :data:`CARTESIAN`."""
    if space == POLAR:
        return np.zeros(len(plots))
    out = (plots.d - 1) * np.log(plots.range)
    if plots.elevation is not None:
        out = out + np.log(np.maximum(np.cos(plots.elevation), 1e-12))
    return np.asarray(out)


# ---------------------------------------------------------------------------
# Pre-gate and gate
# ---------------------------------------------------------------------------
def pregate_radius(
    state: TrackState, d: int, sensor_pos: FloatArray, sensor: SensorNoise, gamma: float
) -> FloatArray:
    """Pre-gate radius (m) of each track (see the module docstring)."""
    pos = state.x[:, :d]
    trace = np.einsum("kii->k", state.P[:, :d, :d])
    rho = np.linalg.norm(pos - sensor_pos[:d], axis=1) + 3.0 * np.sqrt(np.maximum(trace, 0.0))
    ang = max(sensor.sigma_azimuth, sensor.sigma_elevation if d == 3 else 0.0)
    noise = np.maximum(sensor.sigma_range**2, (rho * ang) ** 2)
    return np.asarray(MARGIN * np.sqrt(gamma * (trace + noise)) + SLACK)


def pregate(
    track_pos: FloatArray, radius: FloatArray, plot_pos: FloatArray
) -> tuple[IntArray, IntArray]:
    """Pairs (track, plot) whose Cartesian distance is within the track's ``radius``, in
    track order."""
    B, N = len(track_pos), len(plot_pos)
    if B == 0 or N == 0:
        e = np.zeros(0, np.int64)
        return e, e.copy()
    if B * N <= BRUTE_FORCE_PAIRS:
        diff = track_pos[:, None, :] - plot_pos[None, :, :]
        near = np.einsum("bnk,bnk->bn", diff, diff) <= (radius * radius)[:, None]
        ti, pj = np.nonzero(near)
        return ti.astype(np.int64), pj.astype(np.int64)
    counts, plot = ball_pairs(cKDTree(plot_pos), track_pos, radius)
    return np.repeat(np.arange(B, dtype=np.int64), counts), plot


def ball_pairs(tree: cKDTree, centres: FloatArray, radius: FloatArray) -> tuple[IntArray, IntArray]:
    """Points of ``tree`` within ``radius`` of each centre: counts per centre and the
    concatenated point indices (centre order)."""
    near = tree.query_ball_point(centres, radius, return_sorted=False).tolist()
    counts = np.fromiter(map(len, near), np.int64, len(near))
    return counts, np.fromiter(itertools.chain.from_iterable(near), np.int64, int(counts.sum()))


def gate(
    flt: RecursiveFilter,
    state: TrackState,
    plots: Plots,
    plot_pos: FloatArray,
    sensor: SensorNoise,
    probability: float,
    space: str = POLAR,
) -> Candidates:
    """Candidate pairs of predicted tracks ``state`` and the plots of one scan.

    Parameters
    ----------
    flt : the per-track filter (its ``innovation`` decides)
    state : tracks predicted to the scan time
    plots : the scan's plots; ``plot_pos`` their Cartesian positions ``(N, d)``, m
    sensor : nominal measurement noise (bounds the pre-gate radius)
    probability : gate probability
    space : the filter's innovation space (:func:`innovation_space`)
    """
    d = plots.d
    # the largest innovation dimension the plots allow: a conservative pre-gate
    m_max = d + int(plots.range_rate is not None)
    sp = plots.sensor.mean(0) if len(plots) else np.zeros(3)
    radius = pregate_radius(state, d, sp, sensor, gate_threshold(probability, m_max))
    ti, pj = pregate(state.x[:, :d], radius, plot_pos)
    if ti.size == 0:
        z = np.zeros(0)
        return Candidates(ti, pj, z, z.copy(), d)
    pk = plots.take(pj)
    y, S = flt.innovation(state.take(ti), pk)
    m = int(y.shape[1])
    nis, log_g = nis_logpdf(y, S)
    keep = nis <= gate_threshold(probability, m)
    if space != POLAR:
        log_g = log_g + log_jacobian(space, pk)
    return Candidates(ti[keep], pj[keep], nis[keep], log_g[keep], m)
