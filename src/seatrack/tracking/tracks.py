"""Per-track bookkeeping of the multi-target tracker and the plots waiting to start tracks.

Both are columns of arrays aligned with a batch (the live tracks, the waiting plots): the
tracker selects and appends rows as tracks are deleted and born, scan by scan.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import Plots

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["TrackTable", "PendingPlots", "concat_plots"]


@dataclass
class TrackTable:
    """Bookkeeping of the live tracks, aligned with their state batch.

    Attributes
    ----------
    id : track ids (from 1, never reused)
    logit : log-odds of each track's existence probability
    confirmed : reported at some scan (M-of-N: confirmed)
    hits, age, misses : plots used, scans since birth (the two initiating scans count),
        misses in a row
    """

    id: IntArray
    logit: FloatArray
    confirmed: NDArray[np.bool_]
    hits: IntArray
    age: IntArray
    misses: IntArray

    @classmethod
    def empty(cls) -> TrackTable:
        z = np.zeros(0, np.int64)
        return cls(z, np.zeros(0), np.zeros(0, bool), z.copy(), z.copy(), z.copy())

    def __len__(self) -> int:
        return int(self.id.size)

    def take(self, idx: NDArray[Any]) -> TrackTable:
        return TrackTable(*(getattr(self, f.name)[idx] for f in fields(self)))

    @staticmethod
    def concat(parts: Sequence[TrackTable]) -> TrackTable:
        return TrackTable(
            *(np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(TrackTable))
        )


@dataclass
class PendingPlots:
    """Free plots of the last scans, waiting to pair with a later plot.

    Attributes
    ----------
    plots : the plots; ``pos`` and ``cov`` their Cartesian positions and covariances
    seq : sequence numbers (order of arrival over all scans)
    scan : number of the scan each came in
    log_prior : log prior odds that each is the first plot of a target
    """

    plots: Plots
    pos: FloatArray
    cov: FloatArray
    seq: IntArray
    scan: IntArray
    log_prior: FloatArray

    def __len__(self) -> int:
        return int(self.seq.size)

    def take(self, idx: NDArray[Any]) -> PendingPlots:
        return PendingPlots(
            self.plots.take(idx), self.pos[idx], self.cov[idx], self.seq[idx], self.scan[idx],
            self.log_prior[idx],
        )  # fmt: skip

    @staticmethod
    def concat(parts: Sequence[PendingPlots]) -> PendingPlots:
        return PendingPlots(
            concat_plots([p.plots for p in parts]),
            *(np.concatenate([getattr(p, n) for p in parts])
              for n in ("pos", "cov", "seq", "scan", "log_prior")),
        )  # fmt: skip


def concat_plots(parts: Sequence[Plots]) -> Plots:
    """One set of plots from several (same optional columns)."""

    def cat(name: str) -> Any:
        arrs = [getattr(p, name) for p in parts]
        return None if any(a is None for a in arrs) else np.concatenate(arrs)

    return Plots(
        cat("t"), cat("range"), cat("azimuth"), cat("elevation"), cat("range_rate"),
        cat("sensor"), cat("sensor_vel"), cat("line"),
    )  # fmt: skip
