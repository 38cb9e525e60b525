"""Target motion analysis: bearings (DE 3446658), tonal frequencies, angles on the bow and
ranges (method page ``docs/tma.md``).

One obvious entry point, :func:`solve`::

    from seatrack.tma import Bearings, SupportValue, solve
    sol = solve(Bearings(t, bearing_rad, observer_xy), support=[...], manoeuvres=None)
    sol.last.range, sol.last.sigma_range, sol.observable

plus :func:`solve_many` (every contact in one vectorised call), :class:`TMATracker`
(bearings one by one, warm-started), :func:`detect_legs` (leg changes from the data) and
:func:`crb` (Cramér–Rao bound for a true trajectory). Test scenarios are in
:mod:`seatrack.simulate.tma`, the file formats in :mod:`seatrack.io.tma`, the plot in
:mod:`seatrack.report.tma`.

Module layering inside the package (each imports only those above it): ``legs``,
``config``, ``measurements`` -> ``support`` -> ``problem`` -> ``bounds``, ``lm`` -> ``start``,
``result`` -> ``group`` -> ``detect`` -> ``solver`` -> ``tracker``.
"""

from seatrack.tma.bounds import crb
from seatrack.tma.bounds import ellipse
from seatrack.tma.bounds import operator_values
from seatrack.tma.bounds import position_crb
from seatrack.tma.config import TMAConfig
from seatrack.tma.detect import LegDetection
from seatrack.tma.detect import detect_legs
from seatrack.tma.legs import leg_starts
from seatrack.tma.legs import leg_time_matrix
from seatrack.tma.measurements import BowAngles
from seatrack.tma.measurements import Frequencies
from seatrack.tma.problem import Bearings
from seatrack.tma.problem import bearing_residuals
from seatrack.tma.result import LastEstimate
from seatrack.tma.result import TMASolution
from seatrack.tma.result import observer_deviation
from seatrack.tma.solver import solve
from seatrack.tma.solver import solve_many
from seatrack.tma.support import SupportValue
from seatrack.tma.support import support_residuals
from seatrack.tma.tracker import TMATracker

__all__ = [
    "Bearings",
    "BowAngles",
    "Frequencies",
    "LastEstimate",
    "LegDetection",
    "SupportValue",
    "TMAConfig",
    "TMASolution",
    "TMATracker",
    "bearing_residuals",
    "crb",
    "detect_legs",
    "ellipse",
    "leg_starts",
    "leg_time_matrix",
    "observer_deviation",
    "operator_values",
    "position_crb",
    "solve",
    "solve_many",
    "support_residuals",
]
