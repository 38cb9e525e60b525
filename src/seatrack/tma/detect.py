"""Leg-change (target manoeuvre) detection from the bearing residuals.

The patent takes manoeuvre times ``T_Aj`` from an external detector (spectral change of
the target noise); the spec asks, beyond the patent, for detection from the data itself.
Here: greedy model selection with a likelihood-ratio / BIC test.

1. Solve the one-leg model (cost ``Q_1``; the weighted cost is ``-2 log L`` up to a
   constant for Gaussian bearing noise).
2. For every candidate change time -- each bearing time leaving at least
   ``min_leg_bearings`` bearings in every leg -- solve the model with one more leg,
   warm-started from the current solution (the split leg's velocity duplicated). All
   candidates are solved together as one numpy batch, each also from the automatic
   start. Keep the best (cost ``Q_2``).
3. Accept the extra leg if ``Q_1 - Q_2 > penalty`` (default BIC: 3 ln(N) -- two velocity
   components and one change time per extra leg). After accepting, every change time is
   re-scanned with the others held fixed, until no time moves (``max_passes``).
4. Repeat up to ``max_legs`` legs.

The test assumes the bearing sigma is right; with an underestimated sigma it finds legs
that are not there (check ``residual_rms`` against sigma).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.tma.legs import leg_index, leg_starts
from seatrack.tma.solver import (
    Bearings,
    TMAConfig,
    TMASolution,
    _auto_start,
    _lm,
    _Problem,
    _solve_group,
    solve,
)
from seatrack.tma.support import SupportValue

FloatArray = NDArray[np.float64]

__all__ = ["LegDetection", "detect_legs"]


@dataclass(frozen=True)
class LegDetection:
    """Result of :func:`detect_legs`.

    Attributes
    ----------
    manoeuvres : detected leg start times after the first bearing, s.
    solution : the TMA solution with those legs (``manoeuvres_detected = True``).
    costs : best weighted cost for 1, 2, ... legs (as far as the search went).
    penalty : cost decrease required per extra leg.
    """

    manoeuvres: FloatArray
    solution: TMASolution
    costs: tuple[float, ...]
    penalty: float


def _split(beta: FloatArray, starts: FloatArray, t_new: float) -> FloatArray:
    """State for one more leg starting at ``t_new``: the split leg's velocity duplicated."""
    B = beta.reshape(-1, 2)
    j = int(leg_index(t_new, starts))
    return np.concatenate([B[: 2 + j], B[1 + j : 2 + j], B[2 + j :]]).reshape(-1)


def _best_of(
    bearings: Bearings,
    support: Sequence[SupportValue],
    sigma: float | None,
    cfg: TMAConfig,
    candidates: list[tuple[list[float], FloatArray]],
    auto: bool = True,
) -> tuple[int, float, FloatArray]:
    """Solve every (manoeuvre times, initial state) candidate in one batch; best index."""
    t0 = float(bearings.t[0])
    starts = [leg_starts(t0, m) for m, _ in candidates]
    probs = [_Problem.build(bearings, support, s, cfg, sigma) for s in starts]
    warm = np.stack([b for _, b in candidates])
    if auto:  # each candidate also from the automatic start (the warm start may be far off)
        fresh = _auto_start([(bearings, support, s, None) for s in starts], cfg, sigma)
        warm = np.concatenate([warm, fresh])
        probs = probs + probs
    res = _lm(_Problem.stack(probs), warm, cfg, cfg.max_iterations)
    cost = np.where(np.isfinite(res.cost), res.cost, np.inf)
    k = int(np.argmin(cost))
    return k % len(candidates), float(cost[k]), res.beta[k]


def _scan(
    index: list[int],
    make: Callable[[int], tuple[list[float], FloatArray]],
    solve_batch: Callable[[list[tuple[list[float], FloatArray]]], tuple[int, float, FloatArray]],
    max_candidates: int,
) -> tuple[list[float], float, FloatArray]:
    """Best candidate over bearing indices ``index``: all of them if there are at most
    ``max_candidates``, else a coarse evenly spaced subset and then every index between the
    best coarse candidate's neighbours."""
    if len(index) <= max_candidates:
        cands = [make(i) for i in index]
        k, c, b = solve_batch(cands)
        return cands[k][0], c, b
    step = math.ceil(len(index) / max_candidates)
    coarse = index[::step]
    cands = [make(i) for i in coarse]
    k, c, b = solve_batch(cands)
    best = (cands[k][0], c, b)
    pos = index.index(coarse[k])
    fine = [i for i in index[max(0, pos - step + 1) : pos + step] if i != coarse[k]]
    if fine:
        cands = [make(i) for i in fine]
        k, c2, b2 = solve_batch(cands)
        if c2 < c:
            best = (cands[k][0], c2, b2)
    return best


def detect_legs(
    bearings: Bearings,
    support: Sequence[SupportValue] | None = None,
    sigma: float | None = None,
    config: TMAConfig | None = None,
    max_legs: int = 3,
    min_leg_bearings: int = 4,
    penalty: float | None = None,
    max_passes: int = 10,
    max_candidates: int = 60,
) -> LegDetection:
    """Find target leg changes from the bearings (see module docstring).

    Parameters
    ----------
    bearings, support, sigma, config : as for :func:`seatrack.tma.solve`.
    max_legs : largest number of legs tried.
    min_leg_bearings : fewest bearings in any leg.
    penalty : required cost decrease per extra leg (default ``3 ln N``, BIC).
    max_passes : passes of the change-time re-placement after each accepted leg.
    max_candidates : candidate change times solved in one batch; with more bearings a
        coarse evenly spaced scan is refined around its best candidate.
    """
    cfg = config or TMAConfig()
    sup = list(support or [])
    t = bearings.t
    N = t.size
    pen = 3.0 * math.log(N) if penalty is None else float(penalty)
    sol = solve(bearings, sup, None, sigma, None, cfg)
    times: list[float] = []
    beta, cost = sol.state, sol.cost
    costs = [cost]
    t0 = float(t[0])

    def allowed(i: int, others: list[float]) -> bool:
        if i < min_leg_bearings or i > N - min_leg_bearings:
            return False
        idx = np.searchsorted(t, others)
        return bool(np.all(np.abs(idx - i) >= min_leg_bearings))

    def batch(
        auto: bool,
    ) -> Callable[[list[tuple[list[float], FloatArray]]], tuple[int, float, FloatArray]]:
        return lambda cands: _best_of(bearings, sup, sigma, cfg, cands, auto=auto)

    for _ in range(max_legs - 1):
        starts = leg_starts(t0, times)
        index = [i for i in range(N) if allowed(i, times)]
        if not index:
            break

        def split_at(
            i: int, times: list[float] = times, beta: FloatArray = beta, starts: FloatArray = starts
        ) -> tuple[list[float], FloatArray]:
            return sorted(times + [float(t[i])]), _split(beta, starts, float(t[i]))

        m_new, c_new, b_new = _scan(index, split_at, batch(True), max_candidates)
        if not cost - c_new > pen:
            costs.append(c_new)
            break
        times, beta, cost = m_new, b_new, c_new
        # re-place each change time with the others held fixed, until nothing moves
        for _pass in range(max_passes):
            moved = False
            for j in range(len(times)):
                others = times[:j] + times[j + 1 :]
                lo = times[j - 1] if j > 0 else -math.inf
                hi = times[j + 1] if j + 1 < len(times) else math.inf
                # candidates stay between the neighbours, which keeps the leg order of beta
                index = [i for i in range(N) if lo < t[i] < hi and allowed(i, others)]
                if len(index) < 2:
                    continue

                def move_to(
                    i: int, others: list[float] = others, beta: FloatArray = beta
                ) -> tuple[list[float], FloatArray]:
                    return sorted(others + [float(t[i])]), beta.copy()

                m_j, c_j, b_j = _scan(index, move_to, batch(False), max_candidates)
                if c_j < cost - 1e-9 * cost:
                    moved = moved or m_j != times
                    times, beta, cost = m_j, b_j, c_j
            if not moved:
                break
        costs.append(cost)
    starts = leg_starts(t0, times)
    final = _solve_group([(bearings, sup, starts, beta)], cfg, sigma, detected=[True])[0]
    return LegDetection(np.asarray(times, dtype=float), final, tuple(costs), pen)
