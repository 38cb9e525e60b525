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

FloatArray = NDArray[np.float64]

__all__ = ["LiveFusion", "FusedTrack", "HISTORY"]

#: report times kept per vessel for its gap limit
HISTORY = 64


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
        self.fusion = Fusion(self.coverage, self._states(), self.config)
        self.tracks: dict[int, FusedTrack] = {}  # radar track id -> result at the last scan
        self.not_seen: set[int] = set()  # MMSIs not seen at the last scan
        self.scan_t = -np.inf

    def add_estimates(self, emitted: list) -> None:
        """``(vessel, Estimate)`` pairs of :attr:`LiveAis.emitted`, in emission order. A
        vessel re-run from an earlier report emits again from that report on: its states
        from that time on are replaced."""
        if not emitted:
            return
        n = len(emitted)
        t = np.array([e.t for _, e in emitted])
        state = np.array([e.state for _, e in emitted]).reshape(n, 5)
        std = np.array([e.std for _, e in emitted]).reshape(n, 5)
        kind = np.array([e.kind for _, e in emitted], dtype=np.int8)
        seg = np.array([e.segment for _, e in emitted], dtype=np.int64)
        planes = ReportPlanes(n, np.arange(n), np.array([v.lat0 for v, _ in emitted]),
                              np.array([v.lon0 for v, _ in emitted]))  # fmt: skip
        st = TrackStates(state, std, kind > 0, kind, seg, np.full(n, np.nan), np.zeros(n))
        tr = tracks_from_states(planes, st)
        cols = np.stack([getattr(tr, f) for f in STATE_FIELDS], -1)
        restarted: set[int] = set()
        for k, (v, _) in enumerate(emitted):
            j = self.index.get(v.mmsi)
            if j is None:
                j = self.index[v.mmsi] = len(self.mmsi)
                self.mmsi.append(v.mmsi)
                self.rows.append({})
                self.times.append([])
            tk = float(t[k])
            if j not in restarted:  # the first emission of this batch: drop later states
                restarted.add(j)
                rows, times = self.rows[j], self.times[j]
                for old in [s for s in rows if s >= tk]:
                    del rows[old]
                while times and times[-1] >= tk:
                    times.pop()
            self.times[j].append(tk)
            del self.times[j][:-HISTORY]
            # as the batch fusion: states of non-outlier reports with a position and velocity
            if kind[k] == 0 and bool(np.isfinite(cols[k, [0, 1, 4, 5]]).all()):
                self.rows[j][tk] = tuple(cols[k])

    def _states(self) -> Any:
        """The stored states as :class:`AisStates` (sorted by vessel, then time)."""
        vessel = [j for j, r in enumerate(self.rows) for _ in r]
        t = [s for r in self.rows for s in sorted(r)]
        vals = [r[s] for r in self.rows for s in sorted(r)]
        a = np.array(vals, dtype=float).reshape(-1, len(STATE_FIELDS))
        cols = {f: a[:, i] for i, f in enumerate(STATE_FIELDS)}
        nv = len(self.rows)
        tv = [(j, s) for j, ts in enumerate(self.times) for s in ts]
        limit = gap_limits(np.array([j for j, _ in tv], np.int64), np.array([s for _, s in tv]),
                           nv, self.config.gap_factor, self.config.min_gap)  # fmt: skip
        return ais_states(self.coverage, np.array(vessel, np.int64), np.array(t, float), cols,
                          limit)  # fmt: skip

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

    @property
    def n_dark(self) -> int:
        """Radar tracks classed ``dark`` at the last scan."""
        return sum(1 for f in self.tracks.values() if f.klass == "dark")
