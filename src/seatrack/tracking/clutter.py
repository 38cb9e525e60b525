"""Clutter density and detection probability, from the data.

Association weighs a plot's innovation density ``g`` (per unit of the polar measurement
space: m of range x rad of azimuth [x rad of elevation] [x m/s of range rate]) against the
clutter density ``lambda`` in the same units. Clutter uniform in range and azimuth -- the
usual model of false alarms of a scanning radar -- has ``lambda = n_c / V`` with ``n_c``
the expected false plots per scan and ``V`` the volume of the surveillance region in that
space.

* :class:`SurveillanceRegion` learns ``V`` from every plot seen: the range span, the
  azimuth sector (the full circle unless the plots leave a gap of at least
  ``min_gap_deg`` in a 1-degree histogram after ``min_plots`` plots, as a sector-scanning
  radar does), and the elevation and range-rate spans when the plots have them.
* :class:`ClutterRate` estimates ``n_c`` when it is not given: the plots of each scan that
  no track explains -- the scan's plots minus the expected number of target plots among
  them (each associated plot weighted by its track's existence probability; for JPDA the
  association probabilities) -- averaged over the scans with an exponential memory of
  ``memory`` scans. The plots that start a new track are taken out of the count of their
  own, earlier scan when the track starts (:meth:`ClutterRate.explain_earlier`), so the
  first scans, which have no tracks yet, do not leave the estimate high.
* :class:`DetectionRate` estimates the detection probability: of the confirmed tracks
  updated at a scan, the share updated again at the next.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import Plots

FloatArray = NDArray[np.float64]

__all__ = ["SurveillanceRegion", "ClutterRate", "DetectionRate"]


class SurveillanceRegion:
    """Extent of the plots seen so far, in the polar measurement space."""

    def __init__(self, min_gap_deg: float = 30.0, min_plots: int = 200) -> None:
        self.min_gap_bins = int(math.ceil(min_gap_deg))
        self.min_plots = min_plots
        self.az_hist = np.zeros(360, np.int64)
        self.lo = np.full(3, np.inf)  # range, elevation, range rate
        self.hi = np.full(3, -np.inf)
        self.n = 0
        self._span: tuple[tuple[int, bool], float] | None = None  # cached azimuth span

    def update(self, plots: Plots) -> None:
        """Add the plots of one scan."""
        if len(plots) == 0:
            return
        self.n += len(plots)
        bins = np.floor(np.degrees(plots.azimuth % (2 * np.pi))).astype(np.int64) % 360
        self.az_hist += np.bincount(bins, minlength=360)
        for k, v in enumerate((plots.range, plots.elevation, plots.range_rate)):
            if v is not None:
                self.lo[k] = min(self.lo[k], float(v.min()))
                self.hi[k] = max(self.hi[k], float(v.max()))

    def azimuth_span(self) -> float:
        """Azimuth sector covered, rad (2 pi unless a large empty gap has shown)."""
        if self.n < self.min_plots:
            return 2 * math.pi
        key = (int(np.count_nonzero(self.az_hist)), True)  # the gaps change only with it
        if self._span is not None and self._span[0] == key:
            return self._span[1]
        empty = np.concatenate([self.az_hist, self.az_hist]) == 0  # circular: twice round
        edges = np.flatnonzero(np.diff(np.concatenate([[0], empty.astype(np.int8), [0]])))
        gap = min(int((edges[1::2] - edges[::2]).max(initial=0)), 360)
        span = 2 * math.pi if gap < self.min_gap_bins else math.radians(360 - gap)
        self._span = (key, span)
        return span

    def volume(self, elevation: bool, range_rate: bool) -> float:
        """Volume of the region in the innovation space of the filter (> 0)."""
        span = np.where(self.hi > self.lo, self.hi - self.lo, 0.0)
        v = max(float(span[0]), 1.0) * self.azimuth_span()
        if elevation:
            v *= max(float(span[1]), math.radians(0.1))
        if range_rate:
            v *= max(float(span[2]), 1.0)
        return v


class ClutterRate:
    """Expected false plots per scan: given, or estimated with an exponential memory."""

    def __init__(self, given: float | None = None, memory: float = 20.0) -> None:
        self.given = given
        self.forget = 1.0 - 1.0 / max(memory, 1.0)
        self.sum = 0.0
        self.weight = 0.0

    def update(self, n_clutter: float) -> None:
        """Add one scan's count of plots that no track explains."""
        self.sum = self.forget * self.sum + max(n_clutter, 0.0)
        self.weight = self.forget * self.weight + 1.0

    def explain_earlier(self, n_explained: float, scans_ago: float) -> None:
        """Plots of the scan ``scans_ago`` scans back (counted as clutter then) turned out to
        be target plots: take their expected number out of that scan's count."""
        self.sum = max(self.sum - self.forget**scans_ago * max(n_explained, 0.0), 0.0)

    @property
    def per_scan(self) -> float:
        """Expected false plots per scan (at least 0.1 so that log-densities stay finite)."""
        if self.given is not None:
            return max(self.given, 1e-6)
        if self.weight == 0:
            return 1.0
        return max(self.sum / self.weight, 0.1)


class DetectionRate:
    """Detection probability from the confirmed tracks: of the tracks updated at one scan,
    the share updated again at the next. Counting only the scan after a hit makes the
    estimate blind to how runs of misses end -- closed by a hit, or by the deletion of the
    track, which would otherwise be mistaken for the target's death and leave the long
    runs out (an estimate biased high, shortening the automatic ``max_misses``, cutting
    more runs...). A target that dies contributes one miss. A prior of ``prior`` with the
    weight of ``weight`` scans keeps the early estimate sensible."""

    def __init__(self, given: float | None = None, prior: float = 0.9, weight: float = 20.0):
        self.given = given
        self.hits = prior * weight
        self.misses = (1.0 - prior) * weight

    def update(self, hits: int, misses: int) -> None:
        """Add one scan: of the confirmed tracks updated at the last scan, how many were
        updated again (``hits``) and how many were not (``misses``)."""
        self.hits += hits
        self.misses += misses

    @property
    def pd(self) -> float:
        """The given detection probability, or the estimate."""
        if self.given is not None:
            return self.given
        return self.hits / (self.hits + self.misses)
