"""Incremental TMA: feed bearings one by one, re-solve warm-started (spec "Beyond the patent").

The patent's filter works on the growing store of bearings: every new measurement extends
the Jacobian and the iteration restarts from the current estimate (spec step 6). The
tracker keeps the store, re-solves after each bearing from the previous solution and
falls back to the automatic start when the warm start does not converge or leaves a
higher cost than a fresh start would.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from seatrack.tma.config import TMAConfig
from seatrack.tma.problem import Bearings
from seatrack.tma.result import TMASolution
from seatrack.tma.solver import solve
from seatrack.tma.support import SupportValue

__all__ = ["TMATracker"]


class TMATracker:
    """Growing bearing store with warm-started re-solves.

    Parameters
    ----------
    config : :class:`~seatrack.tma.solver.TMAConfig`.
    manoeuvres : known leg start times (s); legs whose start is after the latest bearing
        are not yet in the model (the state grows as they are reached, spec "the matrix
        size follows the number of manoeuvres detected up to the current time").
    sigma : default bearing sigma, rad.
    min_bearings : bearings needed before the first solve (at least 2).
    """

    def __init__(
        self,
        config: TMAConfig | None = None,
        manoeuvres: Sequence[float] = (),
        sigma: float | None = None,
        min_bearings: int = 4,
    ) -> None:
        self.config = config or TMAConfig()
        self.manoeuvres = sorted(float(m) for m in manoeuvres)
        self.sigma = sigma if sigma is not None else self.config.sigma
        self.min_bearings = max(2, int(min_bearings))
        self._t: list[float] = []
        self._b: list[float] = []
        self._o: list[tuple[float, float]] = []
        self._s: list[float] = []
        self.support: list[SupportValue] = []
        self.solution: TMASolution | None = None
        self.history: list[TMASolution] = []

    def __len__(self) -> int:
        return len(self._t)

    def add_support(self, value: SupportValue) -> None:
        """Store a support value; used from the next solve on."""
        self.support.append(value)

    def add_manoeuvre(self, t: float) -> None:
        """Report a target manoeuvre (leg start) at time ``t`` (s)."""
        if self._t and t <= self._t[0]:
            raise ValueError(
                f"manoeuvre time {t:g} s is not after the first bearing {self._t[0]:g} s"
            )
        self.manoeuvres = sorted(self.manoeuvres + [float(t)])

    def add(
        self, t: float, bearing: float, observer: ArrayLike, sigma: float | None = None
    ) -> TMASolution | None:
        """Add one bearing (rad) at time ``t`` (s) from ``observer`` (m); re-solve.

        Returns the new solution, or ``None`` while fewer than ``min_bearings`` are stored.
        """
        o = np.asarray(observer, dtype=float).reshape(-1)
        if not (
            np.isfinite(t) and np.isfinite(bearing) and o.size >= 2 and np.all(np.isfinite(o[:2]))
        ):
            raise ValueError("bearing, time and observer position must be finite")
        if self._t and t <= self._t[-1]:
            raise ValueError(f"time {t:g} s is not after the previous bearing at {self._t[-1]:g} s")
        s = self.sigma if sigma is None else float(sigma)
        if not s > 0:
            raise ValueError(f"bearing sigma must be positive, got {s}")
        self._t.append(float(t))
        self._b.append(float(bearing))
        self._o.append((float(o[0]), float(o[1])))
        self._s.append(s)
        if len(self._t) < self.min_bearings:
            return None
        bearings = Bearings(
            np.array(self._t), np.array(self._b), np.array(self._o), np.array(self._s)
        )
        man = [m for m in self.manoeuvres if self._t[0] < m < self._t[-1]]
        n = 2 + 2 * (1 + len(man))
        initial = None
        prev = self.solution
        same_legs = prev is not None and list(prev.manoeuvres) == man[: prev.manoeuvres.size]
        if prev is not None and same_legs and prev.state.size <= n:
            B = prev.state.reshape(-1, 2)
            # new legs start with the velocity of the last known leg
            initial = np.concatenate([B.reshape(-1)] + [B[-1]] * ((n - prev.state.size) // 2))
        sol = solve(bearings, self.support, man, None, initial, self.config)
        if initial is not None and not sol.converged:
            fresh = solve(bearings, self.support, man, None, None, self.config)
            if fresh.cost < sol.cost or not sol.converged:
                sol = fresh
        self.solution = sol
        self.history.append(sol)
        return sol
