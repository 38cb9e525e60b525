"""Radar-AIS fusion inside the live process: the per-scan step of ``seatrack fuse``.

When the live process has AIS and radar inputs, every closed radar scan runs one
:meth:`seatrack.fusion.picture.Fusion.step` (docs/fusion.md): each live AIS vessel's
causal states (:class:`~seatrack.live.ais.LiveAis`, one per used report, in WGS84 with
their sigmas) become :class:`~seatrack.fusion.associate.AisStates` in the radar's plane
(:func:`~seatrack.fusion.picture.ais_states`), :func:`~seatrack.fusion.associate.predict_ais`
brings the last state at or before the scan time to it, and the associator classes the
radar tracks (``ais`` with an MMSI and identity probability, ``dark``, ``unknown``) and
flags the AIS vessels the radar should see and does not (``not_seen``).

Differences from ``seatrack fuse`` (docs/live.md, "Fusion"): the AIS states are those of
the live causal filter (:func:`~seatrack.live.ais.causal_config`), not the batch forward
filter; a vessel's prediction limit (:func:`~seatrack.fusion.anomalies.gap_limits`) uses
the report times seen so far (at most ``HISTORY`` per vessel), not the whole run's; shared
MMSIs are not split and jump reports are only those the filter rejects.
"""

from __future__ import annotations

import time
from typing import Any
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais import TrackStates
from seatrack.filters.ais.tracks import ReportPlanes
from seatrack.filters.ais.tracks import tracks_from_states
from seatrack.fusion.anomalies import gap_limits
from seatrack.fusion.associate import FusionConfig
from seatrack.fusion.coverage import Coverage
from seatrack.fusion.picture import CLASSES
from seatrack.fusion.picture import STATE_FIELDS
from seatrack.fusion.picture import Fusion
from seatrack.fusion.picture import ais_states
from seatrack.fusion.picture import track_covariance
from seatrack.live.counters import Latency

FloatArray = NDArray[np.float64]

__all__ = ["LiveFusion", "FusedTrack", "HISTORY"]

#: report times and states kept per vessel (its gap limit; the states until a scan)
HISTORY = 64
_RAW = 13  # a stored raw filter output: lat0, lon0 (deg), state (5), std (5), segment


class FusedTrack(NamedTuple):
    """A radar track's fusion result at a scan: its AIS vessel's MMSI and identity
    probability (None: none) and class (``ais`` | ``dark`` | ``unknown``)."""

    mmsi: int | None
    identity_prob: float | None
    klass: str


class LiveFusion:
    """The fusion of the live AIS vessels with the radar tracks, one step per scan.

    Parameters
    ----------
    setup : RadarSetup
        The radar (position, noise, coverage).
    config : FusionConfig
        The ``[fusion]`` table of ``radar.toml``.
    """

    def __init__(self, setup: Any, config: FusionConfig | None = None) -> None:
        self.config = config or FusionConfig()
        self.sensor = setup.sensor
        self.coverage = Coverage.of(setup.site, self.config.land_mask, self.config.land_cell)
        self.index: dict[int, int] = {}  # mmsi -> vessel id of the fusion
        self.mmsi: list[int] = []
        self.rows: list[dict[float, tuple[float, ...]]] = []  # per vessel: time -> state
        self.times: list[list[float]] = []  # per vessel: report times (for the gap limit)
        self.limit: list[float] = []  # per vessel: gap limit (s)
        self._stale: set[int] = set()  # vessels whose gap limit needs recomputing
        self.fusion = Fusion(self.coverage, self._states(), self.config)
        self.tracks: dict[int, FusedTrack] = {}  # radar track id -> result at the last scan
        self.not_seen: set[int] = set()  # MMSIs not seen at the last scan
        self.scan_t = -np.inf
        self.latency = Latency(2_000)  # seconds per fusion step (``/api/health``)

    def add_estimates(self, emitted: list) -> None:
        """``(vessel, Estimate)`` pairs of :attr:`LiveAis.emitted`, in emission order. A
        vessel re-run from an earlier report emits again from that report on: its states
        after that time are dropped (the re-run emits them again), one at the same time
        replaced."""
        if not emitted:
            return
        # the filter's raw output is kept (outliers left out, as in the batch fusion); it is
        # converted to WGS84 states at the scan (:meth:`_states`), off the ingest path
        touched: set[int] = set()
        for v, e in emitted:
            j = self.index.get(v.mmsi)
            if j is None:
                j = self.index[v.mmsi] = len(self.mmsi)
                self.mmsi.append(v.mmsi)
                self.rows.append({})
                self.times.append([])
                self.limit.append(self.config.min_gap)
            tk = e.t
            rows, times = self.rows[j], self.times[j]
            if times and times[-1] > tk:  # the first report of a re-run: drop later states
                for old in [s for s in rows if s > tk]:
                    del rows[old]
                while times and times[-1] > tk:
                    times.pop()
            touched.add(j)
            times.append(tk)
            if len(times) > HISTORY:
                del times[0]
            if e.kind == 0:
                rows[tk] = (v.lat0, v.lon0, *e.state.tolist(), *e.std.tolist(), e.segment)
                if len(rows) > HISTORY:  # bounded without scans: the oldest (in time order)
                    del rows[next(iter(rows))]
        self._stale.update(touched)

    def _limits(self) -> FloatArray:
        """Per vessel the longest silence before it is no longer predicted (s):
        :func:`~seatrack.fusion.anomalies.gap_limits` of its report times seen (recomputed
        for the vessels with new reports)."""
        if self._stale:
            js = sorted(self._stale)
            sizes = [len(self.times[j]) for j in js]
            owner = np.repeat(np.arange(len(js)), sizes)
            times = np.fromiter((s for j in js for s in self.times[j]), float, sum(sizes))
            new = gap_limits(owner, times, len(js), self.config.gap_factor, self.config.min_gap)
            for j, lim in zip(js, new.tolist(), strict=True):
                self.limit[j] = lim
            self._stale.clear()
        return np.array(self.limit, dtype=float)

    def _convert(self) -> None:
        """The filter's plane states stored since the last scan, in WGS84 (one vectorised
        :func:`~seatrack.filters.ais.tracks.tracks_from_states`); NaN where unknown."""
        new = [(r, s) for r in self.rows for s, v in r.items() if len(v) == _RAW]
        if not new:
            return
        a = np.array([r[s] for r, s in new], float)
        n = len(new)
        kind = np.zeros(n, np.int8)
        st = TrackStates(a[:, 2:7], a[:, 7:12], kind > 0, kind, a[:, 12].astype(np.int64),
                         np.full(n, np.nan), np.zeros(n))  # fmt: skip
        tr = tracks_from_states(ReportPlanes(n, np.arange(n), a[:, 0], a[:, 1]), st)
        out = np.stack([getattr(tr, f) for f in STATE_FIELDS], -1).tolist()
        for (r, s), v in zip(new, out, strict=True):
            r[s] = tuple(v)

    def _states(self) -> Any:
        """The stored states as :class:`AisStates` (sorted by vessel, then time), those
        with a position and velocity (as the batch fusion)."""
        self._convert()
        vessel = np.array([j for j, r in enumerate(self.rows) for _ in r], np.int64)
        t = np.array([s for r in self.rows for s in sorted(r)], float)
        a = np.array([r[s] for r in self.rows for s in sorted(r)], float)
        a = a.reshape(-1, len(STATE_FIELDS))
        cols = {f: a[:, i] for i, f in enumerate(STATE_FIELDS)}
        ok = np.isfinite(cols["lat"]) & np.isfinite(cols["speed"]) & np.isfinite(cols["course"])
        cols = {f: c[ok] for f, c in cols.items()}
        return ais_states(self.coverage, vessel[ok], t[ok], cols, self._limits())

    def _prune(self, t: float) -> None:
        """Keep per vessel the last state at or before ``t`` and the later ones (scans
        come in time order)."""
        for r in self.rows:
            before = [s for s in r if s <= t]
            for s in sorted(before)[:-1]:
                del r[s]

    def scan(self, t: float, ids: NDArray[np.int64], status: Any, cols: dict[str, Any]) -> None:
        """One fusion step for the radar tracks reported at the scan ``t`` (a
        :attr:`LiveRadar.listeners` callback: ids, statuses, filter columns)."""
        del status
        tic = time.perf_counter()
        self.fusion.set_states(self._states())
        ids = np.asarray(ids, np.int64)
        if ids.size:
            pos = np.stack([np.asarray(cols["x_m"]), np.asarray(cols["y_m"])], -1)
            cov = track_covariance(pos, np.asarray(cols["std_x_m"]),
                                   np.asarray(cols["std_y_m"]), self.sensor)  # fmt: skip
        else:
            pos, cov = np.zeros((0, 2)), np.zeros((0, 2, 2))
        res = self.fusion.step(float(t), ids, pos, cov)
        found = res.ais_vessel >= 0
        self.tracks = {
            int(ids[k]): FusedTrack(
                self.mmsi[int(res.ais_vessel[k])] if found[k] else None,
                float(res.identity_prob[k]) if found[k] else None,
                CLASSES[int(res.klass[k])],
            )
            for k in range(ids.size)
        }
        self.not_seen = {self.mmsi[int(v)] for v in res.vessel[res.not_seen]}
        self.scan_t = float(t)
        self._prune(float(t))
        self.latency.add(time.perf_counter() - tic)

    @property
    def n_dark(self) -> int:
        """Radar tracks classed ``dark`` at the last scan."""
        return sum(1 for f in self.tracks.values() if f.klass == "dark")
