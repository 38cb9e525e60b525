"""The multi-target tracker: unlabelled plots in, tracks with stable ids out.

One scan (all plots of one time) at a time, every step vectorised over the tracks:

1. predict every track to the scan time (one batched ``predict`` of the per-track filter);
2. gate (:mod:`~seatrack.tracking.gating`): KD-tree pre-gate, then the filter's own
   innovation and a chi-square gate, one batched ``innovation`` over the candidate pairs;
3. associate confirmed tracks first (:mod:`~seatrack.tracking.association`: GNN, or exact
   JPDA over clusters), with log likelihood ratios ``log(Pd g / lambda)`` against
   ``log(1 - Pd Pg)``; ``lambda`` is the clutter density (given, or estimated from the
   plots no confirmed track explains, :mod:`~seatrack.tracking.clutter`);
4. tentative tracks take the plots the confirmed tracks left (GNN);
5. one batched ``update`` over every (track, plot) pair -- for JPDA over every hypothesis,
   merged per track by moment matching (:mod:`~seatrack.tracking.merge`);
6. confirm tentative tracks by M-of-N, delete tracks (:mod:`~seatrack.tracking.deletion`,
   :func:`~seatrack.tracking.initiation.hopeless`);
7. start tentative tracks from pairs of free plots of the previous and this scan that pass
   the speed gate (:mod:`~seatrack.tracking.initiation`); the free plots left wait for the
   next scan.

The per-track filter is any :class:`~seatrack.filters.base.RecursiveFilter`; it brings its
own process noise. Track ids are integers from 1, given at birth (tentative tracks
included) and never reused.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.config import param
from seatrack.filters.base import (
    Plots,
    PlotStatus,
    RecursiveFilter,
    SensorNoise,
    TrackState,
    plot_gaussian,
)
from seatrack.tracking.association import gnn, jpda
from seatrack.tracking.clutter import ClutterRate, DetectionRate, SurveillanceRegion
from seatrack.tracking.deletion import position_std, to_delete
from seatrack.tracking.gating import Candidates, gate
from seatrack.tracking.initiation import (
    confirmed,
    hopeless,
    polar_covariance,
    speed_gate_pairs,
)
from seatrack.tracking.merge import merge_hypotheses

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["TrackerConfig", "TrackStatus", "ScanResult", "TrackerRun", "MultiTargetTracker"]

#: JPDA hypotheses below this probability are not updated (their weight goes to the miss)
PRUNE = 1e-3
#: automatic deletion: a live target shows the run of misses with at most this probability
LOST = 0.001


class TrackStatus(IntEnum):
    """Status of a track at a scan (the ``status`` output column)."""

    TENTATIVE = 0  #: started, not yet confirmed by M-of-N
    CONFIRMED = 1  #: confirmed, updated by a plot this scan
    COASTING = 2  #: confirmed, no plot this scan
    DELETED = 3  #: deleted at this scan (no output row)

    @property
    def label(self) -> str:
        return self.name.lower()


@dataclass(frozen=True)
class TrackerConfig:
    """Parameters of the multi-target tracker (the sensor noise is the filter's)."""

    pd: float | None = param(
        None, doc="detection probability (none: estimated from the confirmed tracks)",
        min=0, max=1, exclusive_min=True,
    )  # fmt: skip
    clutter_density: float | None = param(
        None, unit="1/scan",
        doc="expected false plots per scan over the surveillance region (none: estimated)",
        min=0,
    )  # fmt: skip
    gate_probability: float = param(
        0.999, doc="probability that a target's plot falls in its gate", min=0.5, max=0.999999
    )
    m_of_n: tuple[int, int] = param(
        (3, 4), doc="confirm with M hits in the first N scans (the 2 initiating plots count)"
    )
    max_misses: int | None = param(
        None, unit="scans",
        doc="delete after this many misses in a row (none: when a live target would show "
        "such a run with probability below 0.1 %, from the detection probability)",
        min=1,
    )  # fmt: skip
    max_position_std: float = param(
        1000.0, key="max_position_std_m", unit="m", doc="delete when the position std exceeds",
        min=0, exclusive_min=True,
    )  # fmt: skip
    max_speed: float = param(
        40.0, key="max_speed_kn", unit="kn", doc="speed gate of two-point initiation",
        min=0, exclusive_min=True,
    )  # fmt: skip
    association: str = param("gnn", doc="association of confirmed tracks", choices=("gnn", "jpda"))
    clutter_memory: float = param(20.0, unit="scans", doc="memory of the clutter estimate", min=1)
    init_scans: int = param(
        3,
        unit="scans",
        doc="a new track pairs plots of up to this many consecutive scans",
        min=2,
    )

    def __post_init__(self) -> None:
        mn = tuple(self.m_of_n)
        if len(mn) != 2 or any(float(v) != int(v) for v in mn):
            raise ValueError(f"m_of_n: expected two integers [M, N], got {list(mn)}")
        m, n = int(mn[0]), int(mn[1])
        if not 2 <= m <= n:
            raise ValueError(f"m_of_n: need 2 <= M <= N, got [{m}, {n}]")
        object.__setattr__(self, "m_of_n", (m, n))


@dataclass(frozen=True)
class ScanResult:
    """What one scan did.

    Attributes
    ----------
    t : s -- the scan time
    track : (B,) int -- ids of the live tracks after the scan (tentative ones included)
    status : (B,) int8 -- :class:`TrackStatus` of each
    plot : (B,) int -- index in the scan's plots of the plot that updated the track
        (for JPDA its most probable plot), -1 when none
    state : the tracks' states (batch ``B``)
    plot_track : (N,) int -- id of the track each plot of the scan went to, -1 when none
    started_from : (2, k) int -- plots of the *previous* scan that started tracks: their
        sequence numbers (order of arrival over all scans) and the track ids
    deleted : ids of the tracks deleted at this scan
    clutter_per_scan : the clutter rate used
    """

    t: float
    track: IntArray
    status: NDArray[np.int8]
    plot: IntArray
    state: TrackState
    plot_track: IntArray
    started_from: IntArray
    deleted: IntArray
    clutter_per_scan: float


@dataclass(frozen=True)
class TrackerRun:
    """A whole file through the tracker.

    Attributes
    ----------
    t, track, status : one row per (scan, live track) -- tentative rows included only
        with ``all_tracks``
    plot : (R,) int -- index into the input plots of the plot used (-1: none)
    columns : the filter's output columns of each row
    plot_track : (N,) int -- per input plot: the id of the track it went to, -1 for clutter
        (plots of tentative tracks never confirmed count as clutter unless ``all_tracks``)
    scan_times : (K,) s
    seconds_per_scan : (K,) wall time of each step
    clutter_per_scan : (K,) the clutter rate used at each scan
    confirmed_ids : ids of every track that was confirmed at some scan
    cpu_seconds_per_scan : (K,) processor time of each step (this process)
    """

    t: FloatArray
    track: IntArray
    status: NDArray[np.int8]
    plot: IntArray
    columns: dict[str, NDArray[Any]]
    plot_track: IntArray
    scan_times: FloatArray
    seconds_per_scan: FloatArray
    clutter_per_scan: FloatArray
    confirmed_ids: IntArray = field(default_factory=lambda: np.zeros(0, np.int64))
    cpu_seconds_per_scan: FloatArray = field(default_factory=lambda: np.zeros(0))


@dataclass
class _Tracks:
    """Per-track bookkeeping, aligned with the state batch."""

    id: IntArray
    confirmed: NDArray[np.bool_]
    hits: IntArray
    age: IntArray
    misses: IntArray

    @classmethod
    def empty(cls) -> _Tracks:
        z = np.zeros(0, np.int64)
        return cls(z, np.zeros(0, bool), z.copy(), z.copy(), z.copy())

    def take(self, idx: NDArray[Any]) -> _Tracks:
        return _Tracks(
            *(a[idx] for a in (self.id, self.confirmed, self.hits, self.age, self.misses))
        )

    @staticmethod
    def concat(parts: Sequence[_Tracks]) -> _Tracks:
        names = ("id", "confirmed", "hits", "age", "misses")
        return _Tracks(*(np.concatenate([getattr(p, n) for p in parts]) for n in names))


@dataclass
class _Pending:
    """Free plots of the last scans, waiting to pair: the plots, their Cartesian positions
    and covariances, sequence numbers and scan numbers."""

    plots: Plots
    pos: FloatArray
    cov: FloatArray
    seq: IntArray
    scan: IntArray

    def take(self, idx: NDArray[Any]) -> _Pending:
        return _Pending(self.plots.take(idx), self.pos[idx], self.cov[idx], self.seq[idx],
                        self.scan[idx])  # fmt: skip

    @staticmethod
    def concat(a: _Pending, b: _Pending) -> _Pending:
        return _Pending(
            _concat_plots(a.plots, b.plots),
            np.concatenate([a.pos, b.pos]),
            np.concatenate([a.cov, b.cov]),
            np.concatenate([a.seq, b.seq]),
            np.concatenate([a.scan, b.scan]),
        )


def _concat_plots(a: Plots, b: Plots) -> Plots:
    def cat(x: Any, y: Any) -> Any:
        return None if x is None or y is None else np.concatenate([x, y])

    return Plots(
        np.concatenate([a.t, b.t]), np.concatenate([a.range, b.range]),
        np.concatenate([a.azimuth, b.azimuth]), cat(a.elevation, b.elevation),
        cat(a.range_rate, b.range_rate), np.concatenate([a.sensor, b.sensor]),
        np.concatenate([a.sensor_vel, b.sensor_vel]), np.concatenate([a.line, b.line]),
    )  # fmt: skip


class MultiTargetTracker:
    """Multi-target tracker over any per-track filter.

    Parameters
    ----------
    flt : RecursiveFilter -- the per-track filter (with its own process noise)
    sensor : SensorNoise -- nominal plot noise (initiation, pre-gates)
    config : TrackerConfig
    """

    def __init__(
        self, flt: RecursiveFilter, sensor: SensorNoise, config: TrackerConfig | None = None
    ) -> None:
        self.flt = flt
        self.sensor = sensor
        self.config = config or TrackerConfig()
        self.state: TrackState | None = None
        self.tracks = _Tracks.empty()
        self.pending: _Pending | None = None
        self.region = SurveillanceRegion()
        self.clutter = ClutterRate(self.config.clutter_density, self.config.clutter_memory)
        self.detection = DetectionRate(self.config.pd)
        self.next_id = 1
        self.n_seen = 0
        self.n_scans = 0
        self.jpda_fallbacks = 0
        self._t = -math.inf

    # -- one scan ---------------------------------------------------------------------
    def step(self, plots: Plots) -> ScanResult:
        """Process the plots of one scan (all with the same time, later than the last).

        Plots with a non-finite value or a range <= 0 are left out (labelled -1); the
        tracks coast over them.
        """
        if len(plots) == 0:
            raise ValueError("a scan needs at least one plot")
        t = float(plots.t[0])
        if np.any(plots.t != t):
            raise ValueError("all plots of a scan must have the same time")
        if t <= self._t:
            raise ValueError(f"scan time {t:g} s is not after the previous scan ({self._t:g} s)")
        good = np.isfinite(plots.polar()).all(-1) & np.isfinite(plots.sensor).all(-1)
        good &= plots.range > 0
        keep = np.flatnonzero(good)
        seq = self.n_seen + keep
        self.n_seen += len(plots)
        self.n_scans += 1
        sub = plots if keep.size == len(plots) else plots.take(keep)
        self.region.update(sub)
        state, status, best, plot_track, started_from, deleted = self._scan(sub, seq, t)
        self.state = state
        self._t = t
        full = np.full(len(plots), -1, np.int64)
        full[keep] = plot_track
        return ScanResult(
            t,
            self.tracks.id.copy(),
            status,
            np.where(best >= 0, keep[np.maximum(best, 0)], -1) if keep.size else best,
            state if state is not None else _empty_like(self.flt),
            full,
            started_from,
            deleted,
            self.clutter.per_scan,
        )

    def _scan(
        self, plots: Plots, seq: IntArray, t: float
    ) -> tuple[TrackState | None, NDArray[np.int8], IntArray, IntArray, IntArray, IntArray]:
        """Existing tracks, then initiation, on the scan's usable plots."""
        pos = plots.positions()
        used = np.full(len(plots), -1, np.int64)  # batch index of the track using the plot
        deleted = np.zeros(0, np.int64)
        state: TrackState | None = None
        status, best = np.zeros(0, np.int8), np.zeros(0, np.int64)
        if self.state is not None and len(self.state):
            state, used, status, best, deleted = self._existing(plots, pos, t)
        plot_track = np.full(len(plots), -1, np.int64)
        plot_track[used >= 0] = self.tracks.id[used[used >= 0]]
        started_from = np.zeros((2, 0), np.int64)
        started = self._initiate(plots, pos, seq, used, t) if len(plots) else None
        if started is not None:
            new_state, first, second, ids = started
            plot_track[second] = ids
            state = new_state if state is None else TrackState.concat([state, new_state])
            born = np.where(self.tracks.confirmed[-len(new_state) :], TrackStatus.CONFIRMED,
                            TrackStatus.TENTATIVE).astype(np.int8)  # fmt: skip
            status = np.concatenate([status, born])
            best = np.concatenate([best, second])
            started_from = np.stack([first, ids])
        return state, status, best, plot_track, started_from, deleted

    def _existing(
        self, plots: Plots, pos: FloatArray, t: float
    ) -> tuple[TrackState, IntArray, NDArray[np.int8], IntArray, IntArray]:
        """Predict, gate, associate, update, confirm and delete the existing tracks."""
        cfg, tr = self.config, self.tracks
        assert self.state is not None
        B, N = len(self.state), len(plots)
        pred = self.flt.predict(self.state, np.full(B, t))
        cand = gate(self.flt, pred, plots, pos, self.sensor, cfg.gate_probability)
        volume = self.region.volume(plots.is_3d, cand.m > plots.d)
        log_lam = math.log(self.clutter.per_scan / volume)
        pd = self.detection.pd
        log_lr = math.log(pd) + cand.log_g - log_lam
        log_miss = np.full(B, math.log1p(-pd * cfg.gate_probability))
        c1 = tr.confirmed[cand.track]
        if cfg.association == "jpda":
            hyp_t, hyp_p, hyp_w, miss_w, best, explained = self._jpda(
                cand.take(c1), log_lr[c1], log_miss, N
            )
        else:
            best = gnn(cand.track[c1], cand.plot[c1], log_lr[c1] - log_miss[cand.track[c1]], B, N)
            hyp_t = np.flatnonzero(best >= 0)
            hyp_p, hyp_w, miss_w = best[hyp_t], np.ones(hyp_t.size), np.zeros(0)
            explained = float(hyp_t.size)
        self.clutter.update(N - explained)
        claimed = np.zeros(N, bool)
        claimed[best[best >= 0]] = True
        # tentative tracks: GNN on the plots the confirmed tracks left
        c2 = ~c1 & ~claimed[cand.plot]
        best2 = gnn(cand.track[c2], cand.plot[c2], log_lr[c2] - log_miss[cand.track[c2]], B, N)
        t2 = np.flatnonzero(best2 >= 0)
        best = np.where(best2 >= 0, best2, best)
        new, updated = self._update(pred, plots, hyp_t, hyp_p, hyp_w, miss_w, t2, best2[t2])
        # a hit: the track's plot (JPDA: its most probable plot, not the miss) updated it
        hit = updated & (best >= 0)
        best = np.where(hit, best, -1)
        used = np.full(N, -1, np.int64)
        used[best[best >= 0]] = np.flatnonzero(best >= 0)
        status = self._bookkeeping(hit)
        keep = self._survivors(new, plots.d)
        deleted = self.tracks.id[~keep]
        if deleted.size == 0:
            return new, used, status, best, deleted
        remap = np.cumsum(keep) - 1
        u = np.maximum(used, 0)
        used = np.where((used >= 0) & keep[u], remap[u], -1)
        self.tracks = self.tracks.take(keep)
        return new.take(keep), used, status[keep], best[keep], deleted

    def _jpda(
        self, cand: Candidates, log_lr: FloatArray, log_miss: FloatArray, N: int
    ) -> tuple[IntArray, IntArray, FloatArray, FloatArray, IntArray, float]:
        """JPDA of the confirmed tracks: hypotheses to update, weights, dominant plots."""
        res = jpda(cand.track, cand.plot, log_lr, log_miss, N)
        self.jpda_fallbacks += res.fallbacks
        B = log_miss.size
        # dominant hypothesis of each track: its most probable plot unless the miss wins
        top = np.full(B, -1.0)
        best = np.full(B, -1, np.int64)
        order = np.lexsort((-res.beta, cand.track))
        first = np.ones(order.size, bool)
        first[1:] = cand.track[order][1:] != cand.track[order][:-1]
        tt = cand.track[order][first]
        top[tt] = res.beta[order][first]
        best[tt] = cand.plot[order][first]
        best = np.where(top > res.beta0, best, -1)
        keep = res.beta >= PRUNE
        return (
            cand.track[keep],
            cand.plot[keep],
            res.beta[keep],
            res.beta0,
            best,
            float(res.beta.sum()),
        )

    def _update(
        self,
        pred: TrackState,
        plots: Plots,
        hyp_t: IntArray,
        hyp_p: IntArray,
        hyp_w: FloatArray,
        miss_w: FloatArray,
        t2: IntArray,
        p2: IntArray,
    ) -> tuple[TrackState, NDArray[np.bool_]]:
        """One batched update over every (track, plot) pair; JPDA hypotheses merged."""
        B = len(pred)
        ti = np.concatenate([hyp_t, t2])
        pj = np.concatenate([hyp_p, p2])
        if ti.size == 0:
            return pred, np.zeros(B, bool)
        upd = self.flt.update(pred.take(ti), plots.take(pj))
        ok = upd.status == PlotStatus.UPDATED
        hit = np.zeros(B, bool)
        hit[ti[ok]] = True
        nh = hyp_t.size
        if miss_w.size == 0:  # GNN: every pair is the track's one update
            return pred.put(ti, upd), hit
        mixed = np.unique(hyp_t)
        if mixed.size:
            hyps = TrackState.concat([upd.take(np.arange(nh)), pred.take(mixed)])
            owner = np.concatenate([np.searchsorted(mixed, hyp_t), np.arange(mixed.size)])
            w = np.concatenate([np.where(ok[:nh], hyp_w, 0.0), miss_w[mixed]])
            pred = pred.put(mixed, merge_hypotheses(self.flt, hyps, w, owner, mixed.size))
        if t2.size:
            pred = pred.put(t2, upd.take(np.arange(nh, ti.size)))
        return pred, hit

    def _bookkeeping(self, hit: NDArray[np.bool_]) -> NDArray[np.int8]:
        """Hits, misses, ages, confirmation; the status of every track this scan."""
        tr, (m, n) = self.tracks, self.config.m_of_n
        after_hit = tr.confirmed & (tr.misses == 0)  # tracks updated at the last scan
        self.detection.update(int((after_hit & hit).sum()), int((after_hit & ~hit).sum()))
        tr.hits = tr.hits + hit
        tr.age = tr.age + 1
        tr.misses = np.where(hit, 0, tr.misses + 1)
        tr.confirmed = tr.confirmed | confirmed(tr.hits, tr.age, m, n)
        return np.where(
            tr.confirmed,
            np.where(hit, TrackStatus.CONFIRMED, TrackStatus.COASTING),
            TrackStatus.TENTATIVE,
        ).astype(np.int8)

    def _survivors(self, state: TrackState, d: int) -> NDArray[np.bool_]:
        cfg, tr = self.config, self.tracks
        m, n = cfg.m_of_n
        gone = to_delete(tr.misses, state.P, d, self.max_misses, cfg.max_position_std)
        gone |= ~tr.confirmed & hopeless(tr.hits, tr.age, m, n)
        return np.asarray(~gone)

    @property
    def max_misses(self) -> int:
        """Misses in a row that delete a confirmed track (given, or from the detection
        probability: the shortest run a live target shows with probability below LOST)."""
        if self.config.max_misses is not None:
            return self.config.max_misses
        pd = min(self.detection.pd, 0.999)
        return max(2, math.ceil(math.log(LOST) / math.log1p(-pd) - 1e-9))

    # -- initiation -------------------------------------------------------------------
    def _initiate(
        self, plots: Plots, pos: FloatArray, seq: IntArray, used: IntArray, t: float
    ) -> tuple[TrackState, IntArray, IntArray, IntArray] | None:
        """Pair free plots of the last ``init_scans`` scans with this scan's free plots
        (speed gate); start a tentative track from each pair; the rest wait."""
        cfg = self.config
        free = np.flatnonzero(used < 0)
        prev, self.pending = self.pending, None
        out = None
        cov = np.zeros((len(plots), plots.d, plots.d))
        if free.size:  # Cartesian covariances of the free plots only
            cov[free] = polar_covariance(plots.take(free), self.sensor)
        if prev is not None and free.size:
            pairs = speed_gate_pairs(
                prev.pos, prev.cov, prev.plots.t, pos[free], cov[free], t, cfg.max_speed,
                cfg.gate_probability, plots.sensor.mean(0),
            )  # fmt: skip
            if pairs.first.size:
                i, j = pairs.first, free[pairs.second]
                new, ok = self._start(prev.plots.take(i), plots.take(j), t)
                i, j, new = i[ok], j[ok], new.take(ok)
                k = i.size
                ids = self.next_id + np.arange(k, dtype=np.int64)
                self.next_id += k
                hits = np.full(k, 2, np.int64)
                age = self.n_scans - prev.scan[i] + 1
                conf = confirmed(hits, age, *cfg.m_of_n)
                born = _Tracks(ids, conf, hits, age, np.zeros(k, np.int64))
                self.tracks = _Tracks.concat([self.tracks, born])
                out = (new, prev.seq[i], j, ids)
                taken = np.zeros(len(plots), bool)
                taken[j] = True
                free = free[~taken[free]]
                rest = np.ones(len(prev.seq), bool)
                rest[i] = False
                prev = prev.take(rest)
        waiting = _Pending(plots.take(free), pos[free], cov[free], seq[free],
                           np.full(free.size, self.n_scans, np.int64))  # fmt: skip
        if prev is not None:
            waiting = _Pending.concat(
                prev.take(self.n_scans - prev.scan < cfg.init_scans - 1), waiting
            )
        self.pending = waiting if len(waiting.seq) else None
        return out

    def _start(self, first: Plots, second: Plots, t: float) -> tuple[TrackState, NDArray[np.bool_]]:
        """New tracks: the first plot with a zero-mean velocity prior (the target class),
        predicted to this scan and updated with the second plot by the filter itself."""
        sigma_v = self.config.max_speed / math.sqrt(6.0)  # uniform speed, random course
        x, P = plot_gaussian(first, self.sensor, sigma_v)
        state = self.flt.initiate(first.t, x, P)
        state = self.flt.update(self.flt.predict(state, np.full(len(first), t)), second)
        return state, np.asarray(state.status == PlotStatus.UPDATED)

    # -- a whole file -----------------------------------------------------------------
    def run(self, plots: Plots, all_tracks: bool = False) -> TrackerRun:
        """Track every scan of a file (scans = distinct plot times, in time order)."""
        return run_tracker(self, plots, all_tracks)

    @property
    def position_std(self) -> FloatArray:
        """Major-axis position std (m) of the live tracks."""
        if self.state is None:
            return np.zeros(0)
        return position_std(self.state.P, self.flt.d)


def _empty_like(flt: RecursiveFilter) -> TrackState:
    n = len(flt.state_names)
    return TrackState.new(np.zeros(0), np.zeros((0, n)), np.zeros((0, n, n)))


def run_tracker(tracker: MultiTargetTracker, plots: Plots, all_tracks: bool = False) -> TrackerRun:
    """Feed a whole file to ``tracker`` scan by scan and collect the output rows."""
    order = np.argsort(plots.t, kind="stable")
    times, starts = np.unique(plots.t[order], return_index=True)
    bounds = np.append(starts, order.size)
    rows: dict[str, list[NDArray[Any]]] = {"t": [], "track": [], "status": [], "plot": []}
    cols: list[dict[str, NDArray[Any]]] = []
    confirmed_ids: list[IntArray] = []
    seq_track = np.full(order.size, -1, np.int64)  # by sequence number = position in order
    secs, cpu, clutter = np.zeros(times.size), np.zeros(times.size), np.zeros(times.size)
    for k in range(times.size):
        idx = order[bounds[k] : bounds[k + 1]]
        scan = plots.take(idx)
        t0, c0 = time.perf_counter(), time.process_time()
        res = tracker.step(scan)
        secs[k], cpu[k] = time.perf_counter() - t0, time.process_time() - c0
        clutter[k] = res.clutter_per_scan
        seq_track[bounds[k] : bounds[k + 1]] = res.plot_track
        seq_track[res.started_from[0]] = res.started_from[1]
        conf = res.status != TrackStatus.TENTATIVE
        confirmed_ids.append(res.track[conf])
        sel = np.flatnonzero(np.ones_like(conf) if all_tracks else conf)
        if sel.size == 0:
            continue
        rows["t"].append(np.full(sel.size, res.t))
        rows["track"].append(res.track[sel])
        rows["status"].append(res.status[sel])
        rows["plot"].append(np.where(res.plot[sel] >= 0, idx[np.maximum(res.plot[sel], 0)], -1))
        cols.append(tracker.flt.columns(res.state.take(sel)))
    ever = np.unique(np.concatenate(confirmed_ids)) if confirmed_ids else np.zeros(0, np.int64)
    label = np.full(plots.t.size, -1, np.int64)
    label[order] = seq_track if all_tracks else np.where(np.isin(seq_track, ever), seq_track, -1)

    def cat(key: str, dtype: Any) -> NDArray[Any]:
        return np.concatenate(rows[key]) if rows[key] else np.zeros(0, dtype)

    out_cols = {c: np.concatenate([d[c] for d in cols]) for c in cols[0]} if cols else {}
    return TrackerRun(
        cat("t", float),
        cat("track", np.int64),
        cat("status", np.int8),
        cat("plot", np.int64),
        out_cols,
        label,
        times,
        secs,
        clutter,
        ever,
        cpu,
    )
