"""Automatic start of the TMA iteration (spec step 1 and "robust start", beyond the patent).

Without a user guess every problem gets several starts:

* *two-range* starts -- the target at range ``r1`` on the first bearing and at range ``r2``
  on the last bearing, joined by a constant velocity, for ``r1, r2`` on a log-spaced grid
  (``TMAConfig.start_ranges``: 7 x 7 = 49 starts by default);
* the pseudo-linear estimate -- the bearing lines written as linear equations
  ``cos(B_i) (X_i - X_Ei) - sin(B_i) (Y_i - Y_Ei) = 0`` and solved in least squares.

All starts of all problems are iterated together as one numpy batch for at most
``start_iterations`` LM trials on at most ``start_max_bearings`` evenly spaced bearings; the
start with the lowest cost is kept and refined on all the data by the caller.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from seatrack.tma.config import TMAConfig
from seatrack.tma.lm import levenberg_marquardt
from seatrack.tma.problem import Bearings
from seatrack.tma.problem import Problem
from seatrack.tma.problem import decimate
from seatrack.tma.support import SupportValue

FloatArray = NDArray[np.float64]

__all__ = ["StartSearch", "auto_start", "decimate", "pseudolinear", "two_range_starts"]


@dataclass(frozen=True)
class StartSearch:
    """Best start per problem after the batch search.

    Attributes
    ----------
    beta : (K, n) the chosen (lowest-cost) iterate of each problem.
    iterations : (K,) LM trials spent on the chosen start.
    iterations_total : (K,) LM trials spent on all starts of the problem.
    """

    beta: FloatArray
    iterations: NDArray[np.int64]
    iterations_total: NDArray[np.int64]


@lru_cache(maxsize=16)
def _range_pairs(lo: float, hi: float, k: int) -> tuple[FloatArray, FloatArray]:
    """Every pair ``(r1, r2)`` of ``k`` log-spaced ranges in ``[lo, hi]`` (m), r1 slowest;
    read-only (shared by every problem)."""
    ranges = np.geomspace(lo, hi, k)
    r1, r2 = (a.ravel() for a in np.meshgrid(ranges, ranges, indexing="ij"))
    r1.flags.writeable = r2.flags.writeable = False
    return r1, r2


def two_range_starts(bearings: Bearings, n: int, cfg: TMAConfig) -> FloatArray:
    """Starts with the target at range r1 on the first and r2 on the last bearing (S, n)."""
    lo, hi, k = cfg.start_ranges
    r1, r2 = _range_pairs(lo, hi, int(k))
    b0, b1 = bearings.bearing[0], bearings.bearing[-1]
    u0 = np.array([np.sin(b0), np.cos(b0)])
    u1 = np.array([np.sin(b1), np.cos(b1)])
    p0 = bearings.observer[0] + r1[:, None] * u0
    p1 = bearings.observer[-1] + r2[:, None] * u1
    v = (p1 - p0) / (bearings.t[-1] - bearings.t[0])
    return np.concatenate([p0] + [v] * ((n - 2) // 2), axis=1)


def pseudolinear(prob: Problem, n: int) -> FloatArray | None:
    """Pseudo-linear estimate ``cos(B) (X - X_E) - sin(B) (Y - Y_E) = 0`` (weighted least
    squares, minimum-norm when the lines do not fix the state); None if not finite."""
    s, c = np.sin(prob.z), np.cos(prob.z)
    m = n // 2
    A = np.zeros((prob.z.size, n))
    A[:, 0::2] = c[:, None] * prob.C[:, :m]
    A[:, 1::2] = -s[:, None] * prob.C[:, :m]
    y = c * prob.obs[:, 0] - s * prob.obs[:, 1]
    sw = np.sqrt(prob.wb)
    sol, *_ = np.linalg.lstsq(A * sw[:, None], y * sw, rcond=None)
    return np.asarray(sol, dtype=float) if np.all(np.isfinite(sol)) else None


def auto_start(
    items: Sequence[tuple[Bearings, Sequence[SupportValue], FloatArray]],
    cfg: TMAConfig,
    sigma: float,
) -> StartSearch:
    """Best start per problem ``(bearings, support, leg starts)``; all starts of all problems
    iterated as one batch (equal state size required). ``sigma`` (rad) is the default
    bearing sigma."""
    n = 2 + 2 * items[0][2].size
    starts_list, probs = [], []
    for b, s, st in items:
        idx = decimate(len(b), cfg.start_max_bearings)
        p = Problem.build(b, s, st, sigma, cfg.support_residual == "square", idx, cfg.sound_speed)
        S = two_range_starts(b, n, cfg)
        if cfg.start_pseudolinear:
            ple = pseudolinear(p, n)
            S = np.vstack([S, ple if ple is not None else S[:1]])
        starts_list.append(S)
        probs.append(p)
    n_s = starts_list[0].shape[0]
    K = len(items)
    batch = Problem.stack(probs).repeat(n_s)
    res = levenberg_marquardt(batch, np.concatenate(starts_list), cfg, cfg.start_iterations)
    costs = np.where(np.isfinite(res.cost), res.cost, np.inf).reshape(K, n_s)
    best = np.argmin(costs, axis=1)
    its = res.iterations.reshape(K, n_s)
    rows = np.arange(K)
    return StartSearch(res.beta.reshape(K, n_s, n)[rows, best], its[rows, best], its.sum(axis=1))
