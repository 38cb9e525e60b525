"""The multi-target tracker by the name :class:`MultiTargetTracker`: the
:class:`~seatrack.tracking.roles.Tracker` with the roles of its configuration, built with
the sensor noise as the second positional argument. Everything else is
:mod:`seatrack.tracking.roles`.
"""

from __future__ import annotations

from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.tracking.roles import ScanResult
from seatrack.tracking.roles import Tracker
from seatrack.tracking.roles import TrackerConfig
from seatrack.tracking.roles import TrackerRun
from seatrack.tracking.roles import TrackStatus
from seatrack.tracking.roles import run_tracker
from seatrack.tracking.roles import usable_plots

__all__ = [
    "TrackerConfig",
    "TrackStatus",
    "ScanResult",
    "MultiTargetTracker",
    "TrackerRun",
    "run_tracker",
    "usable_plots",
]


class MultiTargetTracker(Tracker):
    """:class:`~seatrack.tracking.roles.Tracker` with the default roles of ``config``.

    Parameters
    ----------
    flt : RecursiveFilter -- the per-track filter (with its own process noise)
    sensor : SensorNoise -- nominal plot noise (initiation, pre-gates)
    config : TrackerConfig
    """

    def __init__(
        self, flt: RecursiveFilter, sensor: SensorNoise, config: TrackerConfig | None = None
    ) -> None:
        super().__init__(flt, sensor=sensor, config=config)
