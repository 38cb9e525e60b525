"""Track initiation as a role of the tracker: the :class:`Initiator` protocol and the
two-point initiator with a speed gate (:class:`TwoPointInitiator`).

An initiator sees every scan once, after the associator, with the plots no track took
(``free``). It returns the tracks it starts (:class:`Births`: their states, the plots that
started them, their existence log-odds) and keeps its own memory of the plots waiting for
a partner; the engine gives the new tracks their ids and asks the track manager for their
status.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol
from typing import runtime_checkable

import numpy as np
from numpy.typing import NDArray

from seatrack.config import parse_config
from seatrack.filters.base import Plots
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import plot_gaussian
from seatrack.tracking.components import UPDATED
from seatrack.tracking.components import ScanData
from seatrack.tracking.components import TrackerConfig
from seatrack.tracking.existence import UndetectedTargets
from seatrack.tracking.existence import first_scan_share
from seatrack.tracking.existence import ipda_update
from seatrack.tracking.existence import probability
from seatrack.tracking.gating import POLAR
from seatrack.tracking.gating import log_jacobian
from seatrack.tracking.gating import nis_logpdf
from seatrack.tracking.initiation import polar_covariance
from seatrack.tracking.initiation import speed_gate_pairs
from seatrack.tracking.tracks import PendingPlots

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["Births", "Initiator", "TwoPointInitiator"]


@dataclass(frozen=True)
class Births:
    """Tracks started at a scan (``k`` of them).

    Attributes
    ----------
    state : their states at the scan time (batch ``k``)
    first : (k,) int -- sequence numbers of the earlier plots that started them (-1: none)
    second : (k,) int -- index in the scan's plots of the plot each took at this scan
    logit : (k,) -- log-odds of their existence
    hits, age : (k,) int -- plots used and scans since birth (the starting scans count)
    """

    state: TrackState
    first: IntArray
    second: IntArray
    logit: FloatArray
    hits: IntArray
    age: IntArray


@runtime_checkable
class Initiator(Protocol):
    """Starts tracks from the plots no track took.

    ``initiate`` is called once per scan (also when it has no usable plot) with the
    per-track filter, the nominal sensor noise, the scan and the indices ``free`` of its
    plots that no track took; it returns the new tracks or None.
    """

    def initiate(
        self, flt: RecursiveFilter, sensor: SensorNoise, scan: ScanData, free: IntArray
    ) -> Births | None: ...


class TwoPointInitiator:
    """Two-point initiation with a speed gate (:mod:`seatrack.tracking.initiation`).

    Free plots of the last ``init_scans - 1`` scans are paired with this scan's free
    plots when the pair's speed passes the gate (``max_speed`` and the plot noise); each
    pair starts a tentative track: the first plot with a zero-mean velocity prior (std
    ``initial_speed_sigma`` per axis) predicted to this scan and updated with the second
    plot by the filter itself. The new track's existence is the prior odds of a new
    target (:class:`~seatrack.tracking.existence.UndetectedTargets`, ``births_per_scan``),
    the scans between the plots and the second plot's likelihood ratio. The free plots
    left wait for a partner.

    Parameters
    ----------
    max_speed_kn : speed gate, kn
    initial_speed_sigma_kn : velocity std per axis of a new track, kn
    init_scans : a new track pairs plots of up to this many consecutive scans
    births_per_scan : expected new targets per scan over the region

    Unset arguments take the defaults of :class:`~seatrack.tracking.components.
    TrackerConfig`; :meth:`from_config` builds the initiator of a configuration.
    """

    def __init__(
        self,
        max_speed_kn: float | None = None,
        initial_speed_sigma_kn: float | None = None,
        init_scans: int | None = None,
        births_per_scan: float | None = None,
    ) -> None:
        given = {
            "max_speed_kn": max_speed_kn,
            "initial_speed_sigma_kn": initial_speed_sigma_kn,
            "init_scans": init_scans,
            "births_per_scan": births_per_scan,
        }
        keys = {k: v for k, v in given.items() if v is not None}
        self._setup(parse_config(TrackerConfig, keys, source="TwoPointInitiator"))

    @classmethod
    def from_config(cls, config: TrackerConfig) -> TwoPointInitiator:
        """The initiator of ``config`` (``max_speed``, ``initial_speed_sigma``,
        ``init_scans``, ``births_per_scan``; the gate probability is the scan's)."""
        self = cls.__new__(cls)
        self._setup(config)
        return self

    def _setup(self, config: TrackerConfig) -> None:
        self.max_speed = config.max_speed  #: m/s
        self.initial_speed_sigma = config.initial_speed_sigma  #: m/s
        self.init_scans = config.init_scans
        self.undetected = UndetectedTargets(config.births_per_scan)
        self.pending: list[PendingPlots] = []  # free plots of recent scans, one entry each

    def initiate(
        self, flt: RecursiveFilter, sensor: SensorNoise, scan: ScanData, free: IntArray
    ) -> Births | None:
        """Pair free plots of the last ``init_scans`` scans with this scan's free plots
        (speed gate); start a tentative track from each pair; the rest wait."""
        out = None
        if len(scan.plots):
            out = self._pair(flt, sensor, scan, free)
        self.undetected.advance(scan.pd, math.exp(scan.log_ps))
        return out

    def _pair(
        self, flt: RecursiveFilter, sensor: SensorNoise, scan: ScanData, free: IntArray
    ) -> Births | None:
        plots = scan.plots
        out = None
        cov = polar_covariance(plots, sensor, free)
        entries = self.pending
        if entries and free.size:
            cat = lambda f: np.concatenate([f(e) for e in entries])  # noqa: E731
            pairs = speed_gate_pairs(
                cat(lambda e: e.pos), cat(lambda e: e.cov), cat(lambda e: e.plots.t),
                scan.pos[free], cov, scan.t, self.max_speed, scan.pg,
                plots.sensor[0], self.initial_speed_sigma,
            )  # fmt: skip
            if pairs.first.size:
                prev = entries[0] if len(entries) == 1 else PendingPlots.concat(entries)
                out = self._births(flt, sensor, scan, prev, pairs.first, free[pairs.second])
                left = np.ones(free.size, bool)
                left[pairs.second] = False
                free, cov = free[left], cov[left]
                self.pending = _without(entries, pairs.first)
        if scan.index == 2 and out is None and entries:  # no pair: the share is small
            self._first_scan_prior(np.zeros(0), scan)
        self._wait(scan, free, cov)
        return out

    def _births(
        self,
        flt: RecursiveFilter,
        sensor: SensorNoise,
        scan: ScanData,
        prev: PendingPlots,
        i: IntArray,
        j: IntArray,
    ) -> Births:
        """Start tracks from pairs (earlier plot ``i`` of ``prev``, this scan's plot ``j``)."""
        first, second = prev.plots.take(i), scan.plots.take(j)
        new, log_g = self._start(flt, sensor, first, second, scan.t, scan.space)
        ok = new.status == UPDATED
        i, j, new, log_g = i[ok], j[ok], new.take(ok), log_g[ok]
        k = i.size
        # existence: the first plot's prior, the scans between, the second plot
        gap = scan.index - prev.scan[i]
        s = gap * scan.log_ps + (gap - 1) * math.log1p(-scan.pd)
        s = ipda_update(s, scan.log_miss_pg, math.log(scan.pd) + log_g - scan.log_lam)
        if scan.index == 2:  # the pairs tell the share of targets in the first scan
            self._first_scan_prior(s[prev.scan[i] == 1], scan)  # (prev is pending[0])
        s = s + prev.log_prior[i]
        if scan.clutter.given is None:
            r = probability(s)
            for g in np.unique(gap):  # the first plots were counted as clutter then
                scan.clutter.explain_earlier(float(r[gap == g].sum()), float(g))
        return Births(new, prev.seq[i], j, s, np.full(k, 2, np.int64), gap + 1)

    def _first_scan_prior(self, log_lr: FloatArray, scan: ScanData) -> None:
        """Prior odds of the first scan's plots from the pairs they formed at the second
        (:func:`~seatrack.tracking.existence.first_scan_share`)."""
        u = self.undetected
        share = first_scan_share(log_lr, u.first_plots, scan.pd)
        lp = u.first_scan(share, scan.pd, math.exp(scan.log_ps))
        for e in self.pending:
            e.log_prior[e.scan == 1] = lp

    def _wait(self, scan: ScanData, free: IntArray, cov: FloatArray) -> None:
        """The free plots of this scan join the waiting ones still young enough to pair with
        the next scan (one entry per scan, oldest first)."""
        n = free.size
        lp = self.undetected.log_prior_odds(scan.pd, scan.clutter.per_scan, len(scan.plots))
        keep = self.init_scans - 1
        entries = [e for e in self.pending if scan.index - int(e.scan[0]) < keep]
        if n:
            entries.append(PendingPlots(
                scan.plots.take(free), scan.pos[free], cov, scan.seq[free],
                np.full(n, scan.index, np.int64), np.full(n, lp),
            ))  # fmt: skip
        self.pending = entries

    def _start(
        self,
        flt: RecursiveFilter,
        sensor: SensorNoise,
        first: Plots,
        second: Plots,
        t: float,
        space: str,
    ) -> tuple[TrackState, FloatArray]:
        """New tracks: the first plot with a zero-mean velocity prior (std
        ``initial_speed_sigma`` per axis: the target class), predicted to this scan and
        updated with the second plot by the filter itself; and the log density of the
        second plot under the prediction (polar measurement space, from the filter's
        innovation as in gating; ``space``: the filter's innovation space)."""
        x, P = plot_gaussian(first, sensor, self.initial_speed_sigma)
        pred = flt.predict(flt.initiate(first.t, x, P), np.full(len(first), t))
        log_g = nis_logpdf(*flt.innovation(pred, second))[1]
        if space != POLAR:
            log_g = log_g + log_jacobian(space, second)
        return flt.update(pred, second), log_g


def _without(entries: list[PendingPlots], used: IntArray) -> list[PendingPlots]:
    """The waiting plots minus ``used`` (indices into the entries concatenated)."""
    out, first = [], 0
    for e in entries:
        n = len(e)
        mine = used[(used >= first) & (used < first + n)] - first
        if mine.size:
            keep = np.ones(n, bool)
            keep[mine] = False
            e = e.take(keep)
        if len(e):
            out.append(e)
        first += n
    return out
