"""Gating: which plots may belong to which tracks.

Two stages, so that the cost grows about linearly with the numbers of tracks and plots:

1. **Coarse spatial pre-gate** (:func:`pregate`): a KD-tree on the Cartesian plot positions
   returns, for each track, the plots within a radius ``r_i`` of its predicted position.
   The radius bounds the Mahalanobis gate from above: the squared Mahalanobis distance of
   the position part of an innovation is at most that of the whole innovation, and the
   largest eigenvalue of the Cartesian position innovation covariance is at most
   ``trace(P_pos) + max(sigma_r, rho sigma_az, rho sigma_el)^2`` (``rho`` the track's
   range), so ``r_i = margin * sqrt(gamma * bound) + slack`` keeps every plot that can pass
   the gate (``margin`` and ``slack`` absorb the linearisation of the polar noise).
2. **Mahalanobis gate** (:func:`gate`): the filter's own innovation ``(y, S)``
   (:meth:`~seatrack.filters.base.RecursiveFilter.innovation`, one batched call over every
   candidate pair) gives ``d^2 = y^T S^-1 y``; pairs with ``d^2 <= gamma`` pass, where
   ``gamma`` is the chi-square quantile of the gate probability for ``m`` = the innovation
   dimension. The log-likelihood ``log N(y; 0, S)`` of each passing pair is kept for
   association.

The innovation is in the plots' polar measurement space (range, azimuth, [elevation],
[range rate]) as the filter contract defines it, so the likelihoods are densities per unit
of that space -- the space the clutter density is estimated in.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.stats import chi2

from seatrack.filters.base import Plots, RecursiveFilter, SensorNoise, TrackState

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "Candidates",
    "gate_threshold",
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


@functools.lru_cache(maxsize=64)
def gate_threshold(probability: float, m: int) -> float:
    """Chi-square quantile ``gamma`` with ``P(d^2 <= gamma) = probability`` for ``m`` dof."""
    if not 0 < probability < 1:
        raise ValueError(f"gate probability must be in (0, 1), got {probability}")
    return float(chi2.ppf(probability, m))


@dataclass(frozen=True)
class Candidates:
    """Track-plot pairs that passed the gate.

    Attributes
    ----------
    track, plot : (K,) int -- indices into the track batch and the scan's plots
    nis : (K,) -- squared Mahalanobis distance of the innovation
    log_g : (K,) -- ``log N(y; 0, S)`` (per unit of the polar measurement space)
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


def nis_logpdf(y: FloatArray, S: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``y^T S^-1 y`` and ``log N(y; 0, S)`` for batches ``y (K, m)``, ``S (K, m, m)``.

    Pairs whose ``S`` is not positive definite get ``nis = inf`` (they fail every gate).
    """
    K, m = y.shape
    if K == 0:
        return np.zeros(0), np.zeros(0)
    with np.errstate(all="ignore"):
        det = np.linalg.det(S)
        ok = np.isfinite(det) & (det > 0) & np.isfinite(y).all(-1)
        Sx = np.where(ok[:, None, None], S, np.eye(m))
        w = np.linalg.solve(Sx, np.where(ok[:, None], y, 0.0)[..., None])[..., 0]
        nis = np.einsum("ki,ki->k", y, w)
        logdet = np.log(np.where(ok, det, 1.0))
    nis = np.where(ok & (nis >= 0), nis, np.inf)
    return nis, -0.5 * (nis + logdet + m * _LOG_2PI)


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
    """Pairs (track, plot) whose Cartesian distance is within the track's ``radius``."""
    if len(track_pos) == 0 or len(plot_pos) == 0:
        e = np.zeros(0, np.int64)
        return e, e.copy()
    counts, plot = ball_pairs(cKDTree(plot_pos), track_pos, radius)
    return np.repeat(np.arange(len(track_pos), dtype=np.int64), counts), plot


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
) -> Candidates:
    """Candidate pairs of predicted tracks ``state`` and the plots of one scan.

    Parameters
    ----------
    flt : the per-track filter (its ``innovation`` decides)
    state : tracks predicted to the scan time
    plots : the scan's plots; ``plot_pos`` their Cartesian positions ``(N, d)``, m
    sensor : nominal measurement noise (bounds the pre-gate radius)
    probability : gate probability
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
    y, S = flt.innovation(state.take(ti), plots.take(pj))
    m = int(y.shape[1])
    nis, log_g = nis_logpdf(y, S)
    keep = nis <= gate_threshold(probability, m)
    return Candidates(ti[keep], pj[keep], nis[keep], log_g[keep], m)
