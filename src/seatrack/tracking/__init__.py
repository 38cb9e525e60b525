"""Multi-target tracking from unlabelled plots: gating, association (GNN, JPDA),
initiation (two-point), track existence (confirmation and deletion; or M-of-N), clutter
estimation and the tracker itself, built from roles: :mod:`seatrack.tracking.roles` holds
the role protocols (``Associator``, ``Initiator``, ``TrackManager``) and their
implementations.

The layer above the filters: any :class:`~seatrack.filters.base.RecursiveFilter` is the
per-track filter. See ``docs/tracking.md``.
"""

from seatrack.tracking.roles import ScanResult
from seatrack.tracking.roles import Tracker
from seatrack.tracking.roles import TrackerConfig
from seatrack.tracking.roles import TrackerRun
from seatrack.tracking.roles import TrackStatus
from seatrack.tracking.roles import run_tracker
from seatrack.tracking.tracker import MultiTargetTracker

__all__ = [
    "Tracker",
    "TrackerConfig",
    "TrackerRun",
    "ScanResult",
    "TrackStatus",
    "run_tracker",
    "MultiTargetTracker",
]
