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
from seatrack.filters.ais.kernel import vessel_starts
from seatrack.filters.ais.tracks import ReportPlanes
from seatrack.filters.ais.tracks import tracks_from_states
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


class _Reports(NamedTuple):
    """AIS filter outputs recorded for the worker, in emission order: vessel keys, times
    (s), outlier kinds and the raw numbers (n, 13): plane origin lat0, lon0 (deg), state
    (5), std (5), segment."""

    key: NDArray[np.int64]
    t: FloatArray
    kind: NDArray[np.int8]
    raw: FloatArray


def _reports(blocks: list[_Reports]) -> _Reports:
    """One :class:`_Reports` of several, in order."""
    if len(blocks) == 1:
        return blocks[0]
    if not blocks:
        return _Reports(np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int8),
                        np.zeros((0, _RAW)))  # fmt: skip
    return _Reports(*(np.concatenate(c) for c in zip(*blocks, strict=True)))


def push_times(ring: FloatArray, new: FloatArray, count: NDArray[np.int64]) -> FloatArray:
    """Rows of report times (right-aligned, NaN before the first) with ``count[r]`` more
    times each (``new[r, :count[r]]``, increasing, after the row's), keeping the last
    ``ring.shape[1]``."""
    width = ring.shape[1]
    src = np.concatenate([ring, new], axis=1)
    idx = np.arange(width)[None, :] + count[:, None]
    return np.take_along_axis(src, idx, axis=1)


def ring_limits(ring: FloatArray, gap_factor: float, min_gap_s: float) -> FloatArray:
    """Per row of report times (:func:`push_times`): ``max(gap_factor * median interval,
    min_gap_s)``, ``min_gap_s`` with fewer than two times -- the numbers of
    :meth:`~seatrack.fusion.anomalies.RecentIntervals.limit` for the same times."""
    d = np.sort(np.diff(ring, axis=1), axis=1)  # NaN (missing) last
    m = np.count_nonzero(np.isfinite(d), axis=1)
    lo = np.take_along_axis(d, np.maximum((m - 1) // 2, 0)[:, None], axis=1)[:, 0]
    hi = np.take_along_axis(d, np.maximum(m // 2, 0)[:, None], axis=1)[:, 0]
    with np.errstate(invalid="ignore"):
        lim = np.maximum(gap_factor * (0.5 * (lo + hi)), min_gap_s)
    return np.where(m > 0, lim, min_gap_s)


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
        self._pending: list[_Reports] = []
        self._queue: deque[tuple[list[_Reports], _Scan]] = deque()
        self._cond = threading.Condition()
        self._busy = False
        self._closing = False
        self._thread: threading.Thread | None = None
        # the worker's state: per vessel (id = order of first report) its key and its last
        # HISTORY report times (rows right-aligned, NaN before the first) with their gap
        # limit; the states in the radar's plane, sorted by (vessel, time)
        self.mmsi: list[int] = []  # vessel id -> key (the MMSI)
        self._sorted_keys = (np.zeros(0, np.int64), np.zeros(0, np.int64))  # keys, their ids
        self._ring = np.full((0, HISTORY), np.nan)
        self._limit = np.zeros(0)
        self._sv = np.zeros(0, np.int64)
        self._st = np.zeros(0)
        self._sa = np.zeros((0, _PLANE))
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
        order, for the next scan (copied to arrays: the objects may change later)."""
        n = len(emitted)
        if not n:
            return
        raw = np.empty((n, _RAW))
        raw[:, 0] = np.fromiter((v.lat0 for v, _ in emitted), float, n)
        raw[:, 1] = np.fromiter((v.lon0 for v, _ in emitted), float, n)
        raw[:, 2:7] = np.array([e.state for _, e in emitted])
        raw[:, 7:12] = np.array([e.std for _, e in emitted])
        raw[:, 12] = np.fromiter((e.segment for _, e in emitted), float, n)
        block = _Reports(
            np.fromiter((v.mmsi for v, _ in emitted), np.int64, n),
            np.fromiter((e.t for _, e in emitted), float, n),
            np.fromiter((e.kind for _, e in emitted), np.int8, n),
            raw,
        )
        with self._cond:
            self._pending.append(block)

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

    def _apply(self, recorded: list[_Reports]) -> None:
        """Fold recorded estimates in. A vessel re-run from an earlier report emits again
        from that report on: its report times and states after that time are dropped (the
        re-run emits them again), a state at the same time replaced. Outliers keep their
        report time (for the gap limit) but no state, as in the batch fusion. Vessels
        whose times only grow are folded in whole arrays; a re-run vessel report by
        report (:meth:`_rerun`)."""
        r = _reports(recorded)
        if r.t.size == 0:
            return
        vid = self._vessel_ids(r.key)
        order = np.argsort(vid, kind="stable")  # by vessel, in emission order
        js, ts = vid[order], r.t[order]
        first = np.r_[True, js[1:] != js[:-1]]
        prev = np.where(first, self._ring[js, -1], np.r_[np.nan, ts[:-1]])
        rerun = np.unique(js[ts < prev])  # a time before the vessel's previous one
        regular = ~np.isin(js, rerun)
        self._push(js[regular], ts[regular])
        new = order[regular & (r.kind[order] == 0)]
        keep = np.ones(self._sv.size, bool)
        if rerun.size:
            extra = [self._rerun(v, order[js == v], r, keep) for v in rerun.tolist()]
            new = np.concatenate([new, *extra])
        touched = np.unique(js)
        cfg = self.config
        self._limit[touched] = ring_limits(self._ring[touched], cfg.gap_factor, cfg.min_gap)
        self._merge(keep, vid[new], r.t[new], r.raw[new])

    def _vessel_ids(self, keys: NDArray[np.int64]) -> NDArray[np.int64]:
        """The fusion's vessel id of each key (new keys get the next ids, in key order)."""
        uk, inv = np.unique(keys, return_inverse=True)
        sk, sid = self._sorted_keys
        pos = np.minimum(np.searchsorted(sk, uk), max(sk.size - 1, 0))
        found = (sk[pos] == uk) if sk.size else np.zeros(uk.size, bool)
        ids = np.where(found, sid[pos] if sk.size else 0, -1)
        fresh = uk[~found]
        if fresh.size:
            ids[~found] = len(self.mmsi) + np.arange(fresh.size)
            self.mmsi.extend(fresh.tolist())
            sk, sid = np.r_[sk, fresh], np.r_[sid, ids[~found]]
            order = np.argsort(sk, kind="stable")
            self._sorted_keys = (sk[order], sid[order])
            grow = fresh.size
            self._ring = np.concatenate([self._ring, np.full((grow, HISTORY), np.nan)])
            self._limit = np.r_[self._limit, np.full(grow, self.config.min_gap)]
        return ids[inv.reshape(-1)]

    def _push(self, js: NDArray[np.int64], ts: FloatArray) -> None:
        """Append report times, grouped by vessel in time order, to the vessels' rows."""
        if js.size == 0:
            return
        bounds = vessel_starts(js)
        start, count = bounds[:-1], np.diff(bounds)
        q = np.arange(js.size) - np.repeat(start, count)  # position within its vessel
        new = np.full((start.size, int(count.max())), np.nan)
        new[np.repeat(np.arange(start.size), count), q] = ts
        v = js[start]
        self._ring[v] = push_times(self._ring[v], new, count)

    def _rerun(self, v: int, rows: NDArray[np.int64], r: _Reports,
               keep: NDArray[np.bool_]) -> NDArray[np.int64]:  # fmt: skip
        """Vessel ``v``'s reports ``rows`` (emission order), one by one: its report times
        rewound and pushed, its stored states dropped (``keep``) or replaced; returns the
        rows whose states it keeps."""
        times = [x for x in self._ring[v].tolist() if x == x]
        mine = np.flatnonzero(self._sv == v)
        old = dict(zip(self._st[mine].tolist(), mine.tolist(), strict=True))  # time -> row
        new: dict[float, int] = {}  # time -> report row
        for i, tk, kind in zip(rows.tolist(), r.t[rows].tolist(), r.kind[rows].tolist(),
                               strict=True):  # fmt: skip
            if times and times[-1] > tk:
                times = [x for x in times if x <= tk]
                old = {s: k for s, k in old.items() if s <= tk}
                new = {s: k for s, k in new.items() if s <= tk}
            times.append(tk)
            if kind == 0:
                old.pop(tk, None)
                new[tk] = i
        times = times[-HISTORY:]
        self._ring[v] = np.nan
        self._ring[v, HISTORY - len(times) :] = times
        keep[mine] = False
        keep[list(old.values())] = True
        return np.array(list(new.values()), np.int64)

    def _merge(self, keep: NDArray[np.bool_], v: NDArray[np.int64], t: FloatArray,
               raw: FloatArray) -> None:  # fmt: skip
        """The stored states ``keep`` and the raw states of vessels ``v`` at ``t`` (brought
        to the radar's plane), sorted by (vessel, time); a new state replaces a stored one
        at the same time, and the later of two new ones wins; states without a position
        and velocity are dropped (as in the batch fusion); at most ``HISTORY`` per vessel
        (the latest)."""
        plane, ok = self._plane(raw)
        all_v = np.r_[self._sv[keep], v]
        all_t = np.r_[self._st[keep], t]
        good = np.r_[np.ones(int(keep.sum()), bool), ok]
        order = np.lexsort((np.arange(all_v.size), all_t, all_v))
        sv, st = all_v[order], all_t[order]
        last = np.r_[(sv[1:] != sv[:-1]) | (st[1:] != st[:-1]), True]  # of equal (v, t)
        pick = order[last & good[order]]
        sv = all_v[pick]
        # at most HISTORY per vessel: rank from each vessel's last state
        bounds = vessel_starts(sv)
        rank = np.repeat(bounds[1:] - 1, np.diff(bounds)) - np.arange(sv.size)
        cap = pick[rank < HISTORY]
        self._sv, self._st = all_v[cap], all_t[cap]
        self._sa = np.concatenate([self._sa[keep], plane])[cap]

    def _plane(self, raw: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
        """Raw filter outputs (n, 13) as states in the radar's plane (n, 12): position,
        velocity, position and velocity covariances; and which have a position and
        velocity."""
        n = raw.shape[0]
        if n == 0:
            return np.zeros((0, _PLANE)), np.zeros(0, bool)
        kind = np.zeros(n, np.int8)
        st = TrackStates(raw[:, 2:7], raw[:, 7:12], kind > 0, kind, raw[:, 12].astype(np.int64),
                         np.full(n, np.nan), np.zeros(n))  # fmt: skip
        tr = tracks_from_states(ReportPlanes(n, np.arange(n), raw[:, 0], raw[:, 1]), st)
        cols = {f: getattr(tr, f) for f in STATE_FIELDS}
        ok = np.isfinite(cols["lat"]) & np.isfinite(cols["speed"]) & np.isfinite(cols["course"])
        s = ais_states(self.coverage, np.arange(n), np.zeros(n), cols, np.zeros(n))
        plane = np.concatenate([s.pos, s.vel, s.pos_cov.reshape(n, 4), s.vel_cov.reshape(n, 4)],
                               axis=1)  # fmt: skip
        return plane, ok

    def _states(self) -> AisStates:
        """The stored states as :class:`AisStates` (by vessel, then time)."""
        a, n = self._sa, self._st.size
        return AisStates(self._sv, self._st, a[:, 0:2], a[:, 2:4], a[:, 4:8].reshape(n, 2, 2),
                         a[:, 8:12].reshape(n, 2, 2), self._limit.copy())  # fmt: skip

    def _prune(self, t: float) -> None:
        """Keep per vessel the last state at or before ``t`` and the later ones (scans
        come in time order)."""
        sv, le = self._sv, self._st <= t
        last_le = le & np.r_[(sv[1:] != sv[:-1]) | ~le[1:], True]
        keep = ~le | last_le
        self._sv, self._st, self._sa = sv[keep], self._st[keep], self._sa[keep]

    def _vessel_of(self, key: int) -> int | None:
        """The fusion's vessel id of a key (None: not seen)."""
        sk, sid = self._sorted_keys
        p = int(np.searchsorted(sk, key))
        return int(sid[p]) if p < sk.size and sk[p] == key else None

    def states_of(self, key: int) -> dict[float, tuple[float, ...]]:
        """The stored states of a vessel key by time (12 numbers in the radar's plane:
        position, velocity, position and velocity covariances)."""
        j = self._vessel_of(key)
        rows = np.flatnonzero(self._sv == j) if j is not None else np.zeros(0, np.int64)
        return {t: tuple(a) for t, a in zip(self._st[rows].tolist(), self._sa[rows].tolist(),
                                            strict=True)}  # fmt: skip

    def report_times(self, key: int) -> list[float]:
        """The report times of a vessel key the gap limit is taken of (the last
        ``HISTORY``)."""
        j = self._vessel_of(key)
        return [] if j is None else [x for x in self._ring[j].tolist() if x == x]

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
