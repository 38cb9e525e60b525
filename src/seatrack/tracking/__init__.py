"""Multi-target tracking from unlabelled plots: gating, association (GNN, JPDA),
initiation (two-point), track existence (confirmation and deletion; or M-of-N), clutter
estimation and the tracker itself.

The layer above the filters: any :class:`~seatrack.filters.base.RecursiveFilter` is the
per-track filter. See ``docs/tracking.md``.
"""

from seatrack.tracking.tracker import MultiTargetTracker
from seatrack.tracking.tracker import ScanResult
from seatrack.tracking.tracker import TrackerConfig
from seatrack.tracking.tracker import TrackerRun
from seatrack.tracking.tracker import TrackStatus
from seatrack.tracking.tracker import run_tracker

__all__ = [
    "MultiTargetTracker",
    "ScanResult",
    "TrackerConfig",
    "TrackerRun",
    "TrackStatus",
    "run_tracker",
]
