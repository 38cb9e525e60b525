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
from collections.abc import Callable
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.tma.config import TMAConfig
from seatrack.tma.group import Item
from seatrack.tma.group import solve_group
from seatrack.tma.legs import leg_index
from seatrack.tma.legs import leg_starts
from seatrack.tma.lm import levenberg_marquardt
from seatrack.tma.problem import Bearings
from seatrack.tma.problem import Problem
from seatrack.tma.result import TMASolution
from seatrack.tma.start import auto_start
from seatrack.tma.support import SupportValue

FloatArray = NDArray[np.float64]

__all__ = ["LegDetection", "detect_legs"]

#: a candidate: (manoeuvre times, initial state)
Candidate = tuple[list[float], FloatArray]


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


@dataclass(frozen=True)
class _Best:
    """Best candidate of a batch: times, cost, state, LM trials on its path, and its
    position in the batch's candidate list."""

    times: list[float]
    cost: float
    beta: FloatArray
    iterations: int
    index: int = 0


def _split(beta: FloatArray, starts: FloatArray, t_new: float) -> FloatArray:
    """State for one more leg starting at ``t_new``: the split leg's velocity duplicated."""
    B = beta.reshape(-1, 2)
    j = int(leg_index(t_new, starts))
    return np.concatenate([B[: 2 + j], B[1 + j : 2 + j], B[2 + j :]]).reshape(-1)


class _Search:
    """Batched candidate solves of one contact; counts every LM trial in ``total``."""

    def __init__(
        self, bearings: Bearings, support: Sequence[SupportValue], sigma: float, cfg: TMAConfig
    ) -> None:
        self.bearings, self.support, self.sigma, self.cfg = bearings, support, sigma, cfg
        self.total = 0

    def best_of(self, candidates: list[Candidate], auto: bool) -> _Best:
        """Solve every (manoeuvre times, initial state) candidate in one batch; the best.

        With ``auto`` each candidate is also solved from the automatic start (the warm
        start may be far off)."""
        b, cfg = self.bearings, self.cfg
        t0 = float(b.t[0])
        starts = [leg_starts(t0, m) for m, _ in candidates]
        square = cfg.support_residual == "square"
        probs = [
            Problem.build(b, self.support, s, self.sigma, square, None, cfg.sound_speed)
            for s in starts
        ]
        warm = np.stack([beta for _, beta in candidates])
        pre = np.zeros(len(candidates), dtype=np.int64)
        if auto:
            found = auto_start([(b, self.support, s) for s in starts], cfg, self.sigma)
            warm = np.concatenate([warm, found.beta])
            pre = np.concatenate([pre, found.iterations])
            probs = probs + probs
            self.total += int(found.iterations_total.sum())
        res = levenberg_marquardt(Problem.stack(probs), warm, cfg, cfg.max_iterations)
        self.total += int(res.iterations.sum())
        cost = np.where(np.isfinite(res.cost), res.cost, np.inf)
        k = int(np.argmin(cost))
        j = k % len(candidates)
        return _Best(
            candidates[j][0], float(cost[k]), res.beta[k], int(pre[k] + res.iterations[k]), j
        )

    def scan(
        self, index: list[int], make: Callable[[int], Candidate], auto: bool, max_candidates: int
    ) -> _Best:
        """Best candidate over bearing indices ``index``: all of them if there are at most
        ``max_candidates``, else a coarse evenly spaced subset and then every index between
        the best coarse candidate's neighbours."""
        if len(index) <= max_candidates:
            return self.best_of([make(i) for i in index], auto)
        step = math.ceil(len(index) / max_candidates)
        coarse = index[::step]
        best = self.best_of([make(i) for i in coarse], auto)
        at = index.index(coarse[best.index])
        fine = [i for i in index[max(0, at - step + 1) : at + step] if i != coarse[best.index]]
        if fine:
            b2 = self.best_of([make(i) for i in fine], auto)
            if b2.cost < best.cost:
                best = b2
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
    penalty : required cost decrease per extra leg (default ``3 ln N``, BIC, with ``N``
        the number of measurements of every kind).
    max_passes : passes of the change-time re-placement after each accepted leg.
    max_candidates : candidate change times solved in one batch; with more bearings a
        coarse evenly spaced scan is refined around its best candidate.

    The solution's ``iterations`` are the LM trials on the path of the chosen model (its
    start, the candidate solve that produced it, the final refinement); ``iterations_total``
    counts every trial of the whole search.
    """
    cfg = config or TMAConfig()
    sup = list(support or [])
    sig = cfg.sigma if sigma is None else float(sigma)
    t = bearings.t
    N = t.size
    rows = N + len(sup) + bearings.n_frequencies + bearings.n_bow_angles
    pen = 3.0 * math.log(rows) if penalty is None else float(penalty)
    t0 = float(t[0])
    one = solve_group([Item(bearings, sup, leg_starts(t0, ()))], cfg, sig)[0]
    search = _Search(bearings, sup, sig, cfg)
    search.total = one.iterations_total
    best = _Best([], one.cost, one.state, one.iterations)
    costs = [one.cost]

    def allowed(i: int, others: list[float]) -> bool:
        if i < min_leg_bearings or i > N - min_leg_bearings:
            return False
        idx = np.searchsorted(t, others)
        return bool(np.all(np.abs(idx - i) >= min_leg_bearings))

    for _ in range(max_legs - 1):
        index = [i for i in range(N) if allowed(i, best.times)]
        if not index:
            break
        cur = best
        starts = leg_starts(t0, cur.times)

        def split_at(i: int, cur: _Best = cur, starts: FloatArray = starts) -> Candidate:
            return sorted(cur.times + [float(t[i])]), _split(cur.beta, starts, float(t[i]))

        new = search.scan(index, split_at, True, max_candidates)
        if not cur.cost - new.cost > pen:
            costs.append(new.cost)
            break
        best = _replace_times(search, new, t, allowed, max_passes, max_candidates)
        costs.append(best.cost)
    final = solve_group(
        [Item(bearings, sup, leg_starts(t0, best.times), best.beta, best.iterations,
              search.total, detected=True)],
        cfg, sig,
    )[0]  # fmt: skip
    return LegDetection(np.asarray(best.times, dtype=float), final, tuple(costs), pen)


def _replace_times(
    search: _Search,
    best: _Best,
    t: FloatArray,
    allowed: Callable[[int, list[float]], bool],
    max_passes: int,
    max_candidates: int,
) -> _Best:
    """Re-place each change time with the others held fixed, until nothing moves."""
    for _pass in range(max_passes):
        moved = False
        for j in range(len(best.times)):
            times = best.times
            others = times[:j] + times[j + 1 :]
            lo = times[j - 1] if j > 0 else -math.inf
            hi = times[j + 1] if j + 1 < len(times) else math.inf
            # candidates stay between the neighbours, which keeps the leg order of beta
            index = [i for i in range(t.size) if lo < t[i] < hi and allowed(i, others)]
            if len(index) < 2:
                continue

            def move_to(i: int, others: list[float] = others, cur: _Best = best) -> Candidate:
                return sorted(others + [float(t[i])]), cur.beta.copy()

            cand = search.scan(index, move_to, False, max_candidates)
            if cand.cost < best.cost - 1e-9 * best.cost:
                moved = moved or cand.times != best.times
                best = cand
        if not moved:
            break
    return best
