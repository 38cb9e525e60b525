"""Radar-AIS fusion inside the live process: the per-scan step of ``seatrack fuse``, run
in a worker thread.

When the live process has AIS and radar inputs, every closed radar scan runs one
:meth:`seatrack.fusion.picture.Fusion.step` (docs/fusion.md): each live AIS vessel's
causal states (:class:`~seatrack.live.ais.LiveAis`, one per used report) are brought to
the radar's plane (the same conversions as the batch fusion: the vessel's plane to WGS84
by :func:`~seatrack.filters.ais.tracks.tracks_from_states`, then
:func:`~seatrack.fusion.picture.ais_states`, once per state),
:func:`~seatrack.fusion.associate.predict_ais` brings the last state at or before the
scan time to it, and the associator classes the radar tracks (``ais`` with an MMSI and
identity probability, ``dark``, ``unknown``) and flags the AIS vessels the radar should
see and does not (``not_seen``).

Threads. The event loop only records (:meth:`LiveFusion.add_estimates`, a few
microseconds per AIS report) and hands each closed scan over (:meth:`LiveFusion.scan`);
the fusion itself runs in one worker thread (:meth:`LiveFusion.start`), whose compiled
kernels run on one thread (``nogil``) and whose NumPy work releases the GIL. Scans wait in a bounded
queue (``queue_size``); when it is full the oldest waiting scan is dropped (the newest
wins; the AIS states recorded before it are kept for the next one) and counted in
``dropped``. Without :meth:`~LiveFusion.start` a scan is fused at once, in the caller.

Differences from ``seatrack fuse`` (docs/live.md, "Fusion"): the AIS states are those of
the live causal filter (:func:`~seatrack.live.ais.causal_config`), not the batch forward
filter; a vessel's prediction limit (:func:`~seatrack.fusion.anomalies.gap_limits`) uses
the report times seen so far (at most ``HISTORY`` per vessel), not the whole run's.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from typing import Any
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais import TrackStates
from seatrack.filters.ais.tracks import ReportPlanes
from seatrack.filters.ais.tracks import tracks_from_states
from seatrack.fusion.anomalies import RecentIntervals
from seatrack.fusion.associate import AisStates
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
_RAW = 13  # a raw filter output: lat0, lon0 (deg), state (5), std (5), segment
_PLANE = 12  # a state in the radar's plane: pos (2), vel (2), pos_cov (4), vel_cov (4)


class FusedTrack(NamedTuple):
    """A radar track's fusion result at a scan: its AIS vessel's key (the MMSI, or for a
    shared MMSI's further vessels :func:`~seatrack.live.identity.vessel_key`) and identity
    probability (None: none) and class (``ais`` | ``dark`` | ``unknown``)."""

    mmsi: int | None
    identity_prob: float | None
    klass: str


class _Scan(NamedTuple):
    """A closed scan handed to the worker: time (s), radar track ids, positions (n, 2) m
    and East/North sigmas (m) in the radar's plane."""

    t: float
    ids: NDArray[np.int64]
    pos: FloatArray
    std_x: FloatArray
    std_y: FloatArray


#: rows converted between tuples and arrays per NumPy call: each call holds the GIL, and
#: the event loop waits for it (a 20,000-row table at once: 15-25 ms)
_CHUNK = 2048


def _table(rows: list[tuple[float, ...]], width: int) -> FloatArray:
    """``np.array(rows)`` (n, width), built ``_CHUNK`` rows per call."""
    out = np.empty((len(rows), width))
    for k in range(0, len(rows), _CHUNK):
        out[k : k + _CHUNK] = rows[k : k + _CHUNK]
    return out


def _rows(a: FloatArray) -> list[tuple[float, ...]]:
    """The rows of ``a`` as tuples of floats, ``_CHUNK`` rows per call."""
    out: list[tuple[float, ...]] = []
    for k in range(0, a.shape[0], _CHUNK):
        out.extend(map(tuple, a[k : k + _CHUNK].tolist()))
    return out


class LiveFusion:
    """The fusion of the live AIS vessels with the radar tracks, one step per scan.

    Parameters
    ----------
    setup : RadarSetup
        The radar (position, noise, coverage).
    config : FusionConfig
        The ``[fusion]`` table of ``radar.toml``.
    queue_size : int
        Scans waiting for the worker at most (the oldest is dropped beyond).
    """

    def __init__(self, setup: Any, config: FusionConfig | None = None,
                 queue_size: int = 1) -> None:  # fmt: skip
        if queue_size < 1:
            raise ValueError("LiveFusion: queue_size must be at least 1")
        self.config = config or FusionConfig()
        self.sensor = setup.sensor
        self.coverage = Coverage.of(setup.site, self.config.land_mask, self.config.land_cell)
        self.queue_size = queue_size
        # recorded by the event loop, taken by the worker
        self._pending: list[tuple[int, float, int, tuple[float, ...]]] = []
        self._queue: deque[tuple[list, _Scan]] = deque()
        self._cond = threading.Condition()
        self._busy = False
        self._closing = False
        self._thread: threading.Thread | None = None
        # the worker's state
        self.index: dict[int, int] = {}  # vessel key -> vessel id of the fusion
        self.mmsi: list[int] = []  # vessel id -> key (the MMSI)
        self.rows: list[dict[float, tuple[float, ...]]] = []  # per vessel: time -> state
        self.recent: list[RecentIntervals] = []  # per vessel: report times, gap limit
        self.limit: list[float] = []  # per vessel: gap limit (s)
        self._stale: set[int] = set()  # vessels whose gap limit needs recomputing
        self._raw: dict[tuple[int, float], None] = {}  # (vessel, time) of raw states
        self.fusion = Fusion(self.coverage, self._states(), self.config)
        # results, replaced whole by the worker (read by the event loop)
        self.tracks: dict[int, FusedTrack] = {}  # radar track id -> result at the last scan
        self.not_seen: set[int] = set()  # MMSIs not seen at the last scan
        self.scan_t = -np.inf
        self.version = 0  # fused scans published
        self.dropped = 0  # scans dropped from the full queue
        self.errors: dict[str, int] = {}  # exceptions of the worker, by type
        self.latency = Latency(2_000)  # seconds per fusion step (``/api/health``)
        self.last_step_s = float("nan")  # the last fusion step (s)
        self._steps: deque[float] = deque(maxlen=2_000)

    # ---- event loop side ------------------------------------------------------------------
    def add_estimates(self, emitted: list) -> None:
        """Record ``(vessel, Estimate)`` pairs of :attr:`LiveAis.emitted`, in emission
        order, for the next scan (plain numbers: the objects may change later)."""
        new = [
            (v.mmsi, e.t, e.kind,
             (v.lat0, v.lon0, *e.state.tolist(), *e.std.tolist(), e.segment))
            for v, e in emitted
        ]  # fmt: skip
        if new:
            with self._cond:
                self._pending.extend(new)

    def scan(self, t: float, ids: NDArray[np.int64], status: Any, cols: dict[str, Any]) -> None:
        """Hand over the radar tracks reported at the scan ``t`` (a
        :attr:`LiveRadar.listeners` callback: ids, statuses, filter columns) with the AIS
        states recorded before it; fused at once without a worker."""
        del status
        ids = np.array(ids, np.int64)
        if ids.size:
            pos = np.stack([np.asarray(cols["x_m"], float), np.asarray(cols["y_m"], float)], -1)
            std_x, std_y = np.array(cols["std_x_m"], float), np.array(cols["std_y_m"], float)
            item = _Scan(float(t), ids, pos, std_x, std_y)
        else:
            item = _Scan(float(t), ids, np.zeros((0, 2)), np.zeros(0), np.zeros(0))
        with self._cond:
            est, self._pending = self._pending, []
            if len(self._queue) >= self.queue_size:
                old, _ = self._queue.popleft()
                self.dropped += 1
                if self._queue:
                    self._queue[0] = (old + self._queue[0][0], self._queue[0][1])
                else:
                    est = old + est
            self._queue.append((est, item))
            self._cond.notify_all()
        if self._thread is None:
            self._run_one()

    def step_times(self) -> list[float]:
        """The last (up to 2,000) fusion steps' durations (s), oldest first."""
        return list(self._steps)

    @property
    def waiting(self) -> int:
        """Scans waiting for the worker."""
        return len(self._queue)

    def start(self) -> None:
        """Fuse the scans in a worker thread from now on."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._work, name="seatrack-fusion",
                                            daemon=True)  # fmt: skip
            self._thread.start()

    def wait_idle(self, timeout: float | None = None) -> bool:
        """Block until every handed-over scan is fused (True) or ``timeout`` s passed."""
        with self._cond:
            return self._cond.wait_for(lambda: not self._queue and not self._busy, timeout)

    def close(self) -> None:
        """Fuse the waiting scans and stop the worker."""
        with self._cond:
            self._closing = True
            self._cond.notify_all()
        if self._thread is not None:
            self._thread.join()
            self._thread = None

    # ---- worker side ----------------------------------------------------------------------
    def _work(self) -> None:
        while True:
            with self._cond:
                self._cond.wait_for(lambda: self._queue or self._closing)
                if not self._queue:
                    return
            self._run_one()

    def _run_one(self) -> None:
        """Fuse the oldest waiting scan (exceptions counted, never raised). The compiled
        kernels run on the calling thread only: on a loaded machine a parallel launch for
        a thousand rows waits for its team longer than it computes, and the event loop
        keeps the other core."""
        import numba

        with self._cond:
            if not self._queue:
                return
            est, item = self._queue.popleft()
            self._busy = True
        threads = numba.get_num_threads()  # per calling thread
        numba.set_num_threads(1)
        try:
            tic = time.perf_counter()
            self._apply(est)
            self._step(item)
            self.last_step_s = time.perf_counter() - tic
            self._steps.append(self.last_step_s)
            self.latency.add(self.last_step_s)
        except Exception as exc:  # a failing step never stops the worker or the radar
            name = type(exc).__name__  # a new dict: the event loop may be reading it
            self.errors = {**self.errors, name: self.errors.get(name, 0) + 1}
        finally:
            numba.set_num_threads(threads)
            with self._cond:
                self._busy = False
                self._cond.notify_all()

    def _apply(self, recorded: list) -> None:
        """Fold recorded estimates in. A vessel re-run from an earlier report emits again
        from that report on: its states after that time are dropped (the re-run emits
        them again), one at the same time replaced. Outliers keep their report time
        (for the gap limit) but no state, as in the batch fusion."""
        for key, tk, kind, raw in recorded:
            j = self.index.get(key)
            if j is None:
                j = self.index[key] = len(self.mmsi)
                self.mmsi.append(key)
                self.rows.append({})
                self.recent.append(RecentIntervals(HISTORY))
                self.limit.append(self.config.min_gap)
            rows, rec = self.rows[j], self.recent[j]
            if rec.times and rec.times[-1] > tk:  # a re-run's first report: drop later ones
                for old in [s for s in rows if s > tk]:
                    del rows[old]
                rec.rewind(tk)
            self._stale.add(j)
            rec.push(tk)
            if kind == 0:
                rows[tk] = raw
                self._raw[j, tk] = None
                if len(rows) > HISTORY:  # bounded without scans: the oldest (in time order)
                    del rows[next(iter(rows))]

    def _limits(self) -> FloatArray:
        """Per vessel the longest silence before it is no longer predicted (s), of its
        report times seen (recomputed for the vessels with new reports)."""
        cfg = self.config
        for j in self._stale:
            self.limit[j] = self.recent[j].limit(cfg.gap_factor, cfg.min_gap)
        self._stale.clear()
        return np.array(self.limit, dtype=float)

    def _convert(self) -> None:
        """The raw states recorded since the last scan, in the radar's plane (each state
        converted once); those without a position and velocity are dropped (as in the
        batch fusion)."""
        rows = self.rows
        new = [(rows[j], s) for j, s in self._raw if len(rows[j].get(s, ())) == _RAW]
        self._raw.clear()
        if not new:
            return
        a = _table([r[s] for r, s in new], _RAW)
        n = len(new)
        kind = np.zeros(n, np.int8)
        st = TrackStates(a[:, 2:7], a[:, 7:12], kind > 0, kind, a[:, 12].astype(np.int64),
                         np.full(n, np.nan), np.zeros(n))  # fmt: skip
        tr = tracks_from_states(ReportPlanes(n, np.arange(n), a[:, 0], a[:, 1]), st)
        cols = {f: getattr(tr, f) for f in STATE_FIELDS}
        ok = np.isfinite(cols["lat"]) & np.isfinite(cols["speed"]) & np.isfinite(cols["course"])
        s = ais_states(self.coverage, np.arange(n), np.zeros(n), cols, np.zeros(n))
        flat = _rows(np.concatenate([s.pos, s.vel, s.pos_cov.reshape(n, 4),
                                     s.vel_cov.reshape(n, 4)], axis=1))  # fmt: skip
        for (r, t), v, good in zip(new, flat, ok.tolist(), strict=True):
            if good:
                r[t] = tuple(v)
            else:
                del r[t]

    def _states(self) -> AisStates:
        """The stored states as :class:`AisStates` (by vessel, then time: each vessel's
        states are kept in time order)."""
        self._convert()
        vessel = np.fromiter((j for j, r in enumerate(self.rows) for _ in r), np.int64)
        t = np.fromiter((s for r in self.rows for s in r), float, vessel.size)
        a = _table([v for r in self.rows for v in r.values()], _PLANE)
        n = t.size
        return AisStates(vessel, t, a[:, 0:2], a[:, 2:4], a[:, 4:8].reshape(n, 2, 2),
                         a[:, 8:12].reshape(n, 2, 2), self._limits())  # fmt: skip

    def _prune(self, t: float) -> None:
        """Keep per vessel the last state at or before ``t`` and the later ones (scans
        come in time order)."""
        for r in self.rows:
            if len(r) > 1:
                before = [s for s in r if s <= t]
                for s in before[:-1]:
                    del r[s]

    def _step(self, item: _Scan) -> None:
        """One fusion step; the results replace :attr:`tracks` and :attr:`not_seen`."""
        self.fusion.set_states(self._states())
        ids = item.ids
        cov = (track_covariance(item.pos, item.std_x, item.std_y, self.sensor)
               if ids.size else np.zeros((0, 2, 2)))  # fmt: skip
        res = self.fusion.step(item.t, ids, item.pos, cov)
        found = res.ais_vessel >= 0
        vessel = res.ais_vessel.tolist()
        prob = res.identity_prob.tolist()
        klass = res.klass.tolist()
        self.tracks = {
            tid: FusedTrack(self.mmsi[vessel[k]] if found[k] else None,
                            prob[k] if found[k] else None, CLASSES[klass[k]])
            for k, tid in enumerate(ids.tolist())
        }  # fmt: skip
        self.not_seen = {self.mmsi[int(v)] for v in res.vessel[res.not_seen]}
        self.scan_t = item.t
        self._prune(item.t)
        self.version += 1

    @property
    def n_dark(self) -> int:
        """Radar tracks classed ``dark`` at the last scan."""
        return sum(1 for f in self.tracks.values() if f.klass == "dark")
