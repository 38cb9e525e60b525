"""Multi-target tracking from unlabelled plots: gating, association (GNN, JPDA),
initiation (two-point), track existence (confirmation and deletion; or M-of-N), clutter
estimation and the tracker itself, built from roles (:mod:`seatrack.tracking.roles`).

The layer above the filters: any :class:`~seatrack.filters.base.RecursiveFilter` is the
per-track filter. See ``docs/tracking.md``.
"""

from seatrack.tracking.roles import GNN
from seatrack.tracking.roles import JPDA
from seatrack.tracking.roles import Associator
from seatrack.tracking.roles import ExistenceManager
from seatrack.tracking.roles import Initiator
from seatrack.tracking.roles import MofNManager
from seatrack.tracking.roles import ScanResult
from seatrack.tracking.roles import Tracker
from seatrack.tracking.roles import TrackerConfig
from seatrack.tracking.roles import TrackerRun
from seatrack.tracking.roles import TrackManager
from seatrack.tracking.roles import TrackStatus
from seatrack.tracking.roles import TwoPointInitiator
from seatrack.tracking.roles import run_tracker
from seatrack.tracking.tracker import MultiTargetTracker

__all__ = [
    "Tracker",
    "Associator",
    "Initiator",
    "TrackManager",
    "GNN",
    "JPDA",
    "TwoPointInitiator",
    "ExistenceManager",
    "MofNManager",
    "MultiTargetTracker",
    "ScanResult",
    "TrackerConfig",
    "TrackerRun",
    "TrackStatus",
    "run_tracker",
]
