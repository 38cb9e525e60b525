"""Bearings-only target motion analysis (spec ``specs/tma.md``, DE 3446658).

One obvious entry point, :func:`solve`::

    from seatrack.tma import Bearings, SupportValue, solve
    sol = solve(Bearings(t, bearing_rad, observer_xy), support=[...], manoeuvres=None)
    sol.last.range, sol.last.sigma_range, sol.observable

plus :func:`solve_many` (every contact in one vectorised call), :class:`TMATracker`
(bearings one by one, warm-started), :func:`detect_legs` (leg changes from the data),
:func:`crb` (Cramér–Rao bound for a true trajectory) and :func:`classic_scenario`.
"""

from seatrack.tma.bounds import crb, ellipse, operator_values, position_crb
from seatrack.tma.detect import LegDetection, detect_legs
from seatrack.tma.legs import leg_starts, leg_time_matrix
from seatrack.tma.scenario import TMAScenario, classic_scenario, scenario_from_trajectories
from seatrack.tma.solver import (
    Bearings,
    LastEstimate,
    TMAConfig,
    TMASolution,
    bearing_residuals,
    observer_deviation,
    solve,
    solve_many,
)
from seatrack.tma.support import SupportValue, support_residuals
from seatrack.tma.tracker import TMATracker

__all__ = [
    "Bearings",
    "LastEstimate",
    "LegDetection",
    "SupportValue",
    "TMAConfig",
    "TMAScenario",
    "TMASolution",
    "TMATracker",
    "bearing_residuals",
    "classic_scenario",
    "crb",
    "detect_legs",
    "ellipse",
    "leg_starts",
    "leg_time_matrix",
    "observer_deviation",
    "operator_values",
    "position_crb",
    "scenario_from_trajectories",
    "solve",
    "solve_many",
    "support_residuals",
]
