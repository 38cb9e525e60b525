"""The multi-target tracker built from roles: unlabelled plots in, tracks with stable ids
out.

:class:`Tracker` is the engine; what it decides is delegated to three roles, each a small
protocol working on arrays of every live track at once:

* an :class:`Associator` -- :class:`GNN` (default) or :class:`JPDA`;
* an :class:`Initiator` -- :class:`TwoPointInitiator` (two-point start with a speed gate);
* a :class:`TrackManager` -- :class:`ExistenceManager` (default: IPDA / JIPDA existence)
  or :class:`MofNManager` (M-of-N).

Unset roles come from the :class:`TrackerConfig` (``association``, ``confirmation`` and
the parameters of each); the defaults are the tracker of ``seatrack track``.

One scan (all plots of one time) at a time, every step vectorised over the tracks:

1. predict every track to the scan time (one batched ``predict`` of the per-track filter)
   and its existence probability (:mod:`~seatrack.tracking.existence`: survival);
2. gate (:mod:`~seatrack.tracking.gating`): spatial pre-gate, then the filter's own
   innovation and a chi-square gate, one batched ``innovation`` over the candidate pairs,
   giving the :class:`Hypotheses`: every gated pair with its log likelihood ratio
   ``log(Pd g / lambda)`` (``lambda`` the clutter density, given or estimated from the
   plots the tracks do not explain, :mod:`~seatrack.tracking.clutter`), weighed by the
   track's existence ``r`` against ``log(1 - r Pd Pg)``, so that a doubtful track yields a
   contested plot to a sure one;
3. the associator assigns the plots and updates the tracks and their existence;
4. hits, misses and ages are counted; the detection probability is estimated from the
   confirmed tracks; the track manager reports and deletes;
5. the initiator starts tentative tracks from the plots no track took; the track manager
   gives their status.

The per-track filter is any :class:`~seatrack.filters.base.RecursiveFilter`; it brings its
own process noise and its own innovation space (:func:`~seatrack.tracking.gating.
innovation_space`). Track ids are integers from 1, given at birth (tentative tracks
included) and never reused.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from dataclasses import field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import Plots
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.progress import Progress
from seatrack.tracking.clutter import ClutterRate
from seatrack.tracking.clutter import DetectionRate
from seatrack.tracking.clutter import SurveillanceRegion
from seatrack.tracking.components import GNN
from seatrack.tracking.components import JPDA
from seatrack.tracking.components import UPDATED
from seatrack.tracking.components import Association
from seatrack.tracking.components import Associator
from seatrack.tracking.components import ExistenceManager
from seatrack.tracking.components import Hypotheses
from seatrack.tracking.components import MofNManager
from seatrack.tracking.components import ScanData
from seatrack.tracking.components import TrackerConfig
from seatrack.tracking.components import TrackManager
from seatrack.tracking.components import TrackStatus
from seatrack.tracking.deletion import position_std
from seatrack.tracking.existence import probability
from seatrack.tracking.existence import survive
from seatrack.tracking.gating import gate
from seatrack.tracking.gating import innovation_space
from seatrack.tracking.initiators import Births
from seatrack.tracking.initiators import Initiator
from seatrack.tracking.initiators import TwoPointInitiator
from seatrack.tracking.tracks import TrackTable

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

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
    "TrackerConfig",
    "TrackStatus",
    "ScanData",
    "Hypotheses",
    "Association",
    "Births",
    "ScanResult",
    "TrackerRun",
    "run_tracker",
    "usable_plots",
    "UPDATED",
]

_TENTATIVE = int(TrackStatus.TENTATIVE)


@dataclass(frozen=True)
class ScanResult:
    """What one scan did: the live tracks after it.

    Attributes
    ----------
    t : s -- the scan time
    track : (B,) int -- ids of the live tracks after the scan (tentative ones included)
    status : (B,) int8 -- :class:`TrackStatus` of each
    plot : (B,) int -- index in the scan's plots of the plot that updated the track
        (for JPDA its most probable plot), -1 when none
    state : the tracks' states (batch ``B``)
    existence : (B,) -- existence probability of each track
    plot_track : (N,) int -- id of the track each plot of the scan went to, -1 when none
    started_from : (2, k) int -- plots of *earlier* scans that started tracks: their
        sequence numbers (order of arrival over all scans) and the track ids
    deleted : ids of the tracks deleted at this scan
    clutter_per_scan : the clutter rate used
    filter : the per-track filter (for :meth:`columns`)
    """

    t: float
    track: IntArray
    status: NDArray[np.int8]
    plot: IntArray
    state: TrackState
    existence: FloatArray
    plot_track: IntArray
    started_from: IntArray
    deleted: IntArray
    clutter_per_scan: float
    filter: RecursiveFilter | None = None

    def columns(self, all_tracks: bool = False) -> dict[str, NDArray[Any]]:
        """The reported tracks (every live track with ``all_tracks``) as columns, ready for
        ``pandas.DataFrame``: ``track``, ``time_s``, the filter's columns (``x_m`` ...),
        ``status`` (``confirmed``, ``coasting``, ``tentative``), ``plot`` (index in the
        scan's plots, -1: none) and ``existence``."""
        sel = np.ones(self.track.size, bool) if all_tracks else self.status != _TENTATIVE
        labels = np.array([s.label for s in TrackStatus])
        out: dict[str, NDArray[Any]] = {
            "track": self.track[sel],
            "time_s": np.full(int(sel.sum()), self.t),
        }
        if self.filter is not None:
            out |= dict(self.filter.columns(self.state.take(np.flatnonzero(sel))))
        out["status"] = labels[self.status[sel]]
        out["plot"] = self.plot[sel]
        out["existence"] = self.existence[sel]
        return out


class Tracker:
    """Multi-target tracker over any per-track filter, built from roles.

    Parameters
    ----------
    filter : RecursiveFilter -- the per-track filter (with its own process noise)
    associator : :class:`Associator` (default from ``config.association``: :class:`GNN`
        or :class:`JPDA`)
    initiator : :class:`Initiator` (default :class:`TwoPointInitiator` of ``config``)
    manager : :class:`TrackManager` (default from ``config.confirmation``:
        :class:`ExistenceManager` or :class:`MofNManager`)
    sensor : nominal plot noise (initiation, pre-gates; default the filter's own
        ``sensor``, else :class:`~seatrack.filters.base.SensorNoise` defaults)
    config : :class:`TrackerConfig` -- the tracker-wide parameters (detection and clutter
        rates, gate probability, survival) and the defaults of the unset roles

    Examples
    --------
    >>> from seatrack.filters.ekf import EKF
    >>> from seatrack.tracking.roles import JPDA, MofNManager, Tracker
    >>> tracker = Tracker(EKF(), associator=JPDA(), manager=MofNManager(3, 4))
    >>> type(tracker.initiator).__name__
    'TwoPointInitiator'
    """

    def __init__(
        self,
        filter: RecursiveFilter,  # noqa: A002 - the role's name
        *,
        associator: Associator | None = None,
        initiator: Initiator | None = None,
        manager: TrackManager | None = None,
        sensor: SensorNoise | None = None,
        config: TrackerConfig | None = None,
    ) -> None:
        cfg = config or TrackerConfig()
        self.flt = filter
        self.sensor = sensor or getattr(filter, "sensor", None) or SensorNoise()
        self.config = cfg
        if associator is None:
            associator = JPDA() if cfg.association == "jpda" else GNN()
        if manager is None:
            rule = ExistenceManager if cfg.confirmation == "existence" else MofNManager
            manager = rule.from_config(cfg)
        self.associator: Associator = associator
        self.initiator: Initiator = initiator or TwoPointInitiator.from_config(cfg)
        self.manager: TrackManager = manager
        self.space = innovation_space(filter, self.sensor)
        self.state: TrackState | None = None
        self.tracks = TrackTable.empty()
        self.region = SurveillanceRegion()
        self.clutter = ClutterRate(cfg.clutter_density, cfg.clutter_memory)
        self.detection = DetectionRate(cfg.pd)
        self.next_id = 1
        self.n_seen = 0
        self.n_scans = 0
        self._t = -math.inf

    # -- one scan ---------------------------------------------------------------------
    def step(self, time: float, plots: Plots, usable: IntArray | None = None) -> ScanResult:
        """Process the plots of one scan at ``time`` (s, later than the last scan).

        Plots with a non-finite value or a range <= 0 are left out (labelled -1); the
        tracks coast over them, as over a scan without plots. ``usable``: the indices of
        the usable plots when the caller has checked the plots already (:func:`run_tracker`
        checks a whole file at once). Returns the live tracks
        (:meth:`ScanResult.columns` gives the reported ones as columns).
        """
        t = float(time)
        if usable is None:
            if np.any(plots.t != t):
                raise ValueError(f"all plots of a scan must have the scan time {t:g} s")
            usable = np.flatnonzero(usable_plots(plots))
        if not math.isfinite(t):
            raise ValueError(f"scan time must be finite, got {t!r}")
        if t <= self._t:
            raise ValueError(f"scan time {t:g} s is not after the previous scan ({self._t:g} s)")
        keep = usable
        seq = self.n_seen + keep
        self.n_seen += len(plots)
        self.n_scans += 1
        sub = plots if keep.size == len(plots) else plots.take(keep)
        self.region.update(sub)
        scan = self._begin(sub, seq, t)
        state, status, best, plot_track, started_from, deleted = self._scan(scan)
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
            probability(self.tracks.logit),
            full,
            started_from,
            deleted,
            self.clutter.per_scan,
            self.flt,
        )

    def _begin(self, plots: Plots, seq: IntArray, t: float) -> ScanData:
        pd = self.detection.pd
        range_rate = bool(plots.range_rate is not None and self.flt.range_rate)
        volume = self.region.volume(plots.is_3d, range_rate)
        log_lam = math.log(self.clutter.per_scan / volume)
        dt = t - self._t if math.isfinite(self._t) else 0.0
        return ScanData(
            plots, plots.positions(), seq, t, self.n_scans, log_lam, pd,
            self.config.gate_probability, -dt / self.config.mean_life, self.clutter, self.space,
        )  # fmt: skip

    def _scan(
        self, scan: ScanData
    ) -> tuple[TrackState | None, NDArray[np.int8], IntArray, IntArray, IntArray, IntArray]:
        """Existing tracks, then initiation, then the clutter update."""
        plots = scan.plots
        used = np.full(len(plots), -1, np.int64)  # batch index of the track using the plot
        deleted = np.zeros(0, np.int64)
        state: TrackState | None = None
        status, best = np.zeros(0, np.int8), np.zeros(0, np.int64)
        if self.state is not None and len(self.state):
            state, used, status, best, deleted = self._existing(scan)
        plot_track = np.full(len(plots), -1, np.int64)
        plot_track[used >= 0] = self.tracks.id[used[used >= 0]]
        started_from = np.zeros((2, 0), np.int64)
        births = self.initiator.initiate(self.flt, self.sensor, scan, np.flatnonzero(used < 0))
        if births is not None:
            ids, born = self._born(births, scan)
            plot_track[births.second] = ids
            state = births.state if state is None else TrackState.concat([state, births.state])
            status = np.concatenate([status, born])
            best = np.concatenate([best, births.second])
            started_from = np.stack([births.first, ids])
        if self.clutter.given is None:
            self.clutter.update(len(plots) - scan.explained)
        return state, status, best, plot_track, started_from, deleted

    def _existing(
        self, scan: ScanData
    ) -> tuple[TrackState, IntArray, NDArray[np.int8], IntArray, IntArray]:
        """Predict, gate, associate, update, report and delete the existing tracks."""
        assert self.state is not None
        tr, plots = self.tracks, scan.plots
        B, N = len(self.state), len(plots)
        pred = self.flt.predict(self.state, np.full(B, scan.t))
        s_pred = survive(tr.logit, scan.log_ps)
        cand = gate(self.flt, pred, plots, scan.pos, self.sensor, scan.pg, self.space)
        log_lr = math.log(scan.pd) + cand.log_g - scan.log_lam  # IPDA: log(Pd g / lambda)
        r_pred = probability(s_pred)
        log_miss = np.log1p(-r_pred * scan.pd * scan.pg)
        log_lr_r = log_lr + np.log(np.maximum(r_pred[cand.track], 1e-300))  # JIPDA weights
        hyp = Hypotheses(cand.track, cand.plot, log_lr, log_lr_r, log_miss, s_pred)
        a: Association = self.associator.associate(self.flt, pred, scan, hyp)
        new, best, hit = a.state, a.plot, a.hit
        tr.logit = a.logit
        used = np.full(N, -1, np.int64)
        used[best[best >= 0]] = np.flatnonzero(best >= 0)
        after_hit = tr.confirmed & (tr.misses == 0)  # reported tracks updated last scan
        self.detection.update(int((after_hit & hit).sum()), int((after_hit & ~hit).sum()))
        tr.hits = tr.hits + hit
        tr.age = tr.age + 1
        tr.misses = np.where(hit, 0, tr.misses + 1)
        status = self.manager.status(tr, hit)
        keep = self.manager.survivors(tr, new.P, plots.d, self.detection.pd)
        deleted = tr.id[~keep]
        if deleted.size == 0:
            return new, used, status, best, deleted
        remap = np.cumsum(keep) - 1
        u = np.maximum(used, 0)
        used = np.where((used >= 0) & keep[u], remap[u], -1)
        self.tracks = tr.take(keep)
        return new.take(keep), used, status[keep], best[keep], deleted

    def _born(self, births: Births, scan: ScanData) -> tuple[IntArray, NDArray[np.int8]]:
        """Ids and status of the new tracks; they join the track table."""
        k = births.logit.size
        ids = self.next_id + np.arange(k, dtype=np.int64)
        self.next_id += k
        z = np.zeros(k, np.int64)
        born = TrackTable(ids, births.logit, np.zeros(k, bool), births.hits, births.age, z)
        n0 = len(self.tracks)
        self.tracks = TrackTable.concat([self.tracks, born])
        status = self.manager.status(self.tracks, np.ones(k, bool), n0)
        scan.explained += float(probability(births.logit).sum())
        return ids, status

    # -- a whole file -----------------------------------------------------------------
    def run(
        self, plots: Plots, all_tracks: bool = False, progress: Progress | None = None
    ) -> TrackerRun:
        """Track every scan of a file (scans = distinct plot times, in time order);
        ``progress`` is told of the plots done after every scan."""
        return run_tracker(self, plots, all_tracks, progress)

    @property
    def position_std(self) -> FloatArray:
        """Major-axis position std (m) of the live tracks."""
        if self.state is None:
            return np.zeros(0)
        return position_std(self.state.P, self.flt.d)

    @property
    def existence(self) -> FloatArray:
        """Existence probability of the live tracks."""
        return probability(self.tracks.logit)

    @property
    def jpda_fallbacks(self) -> int:
        """Clusters the JPDA associator approximated so far (0 for other associators)."""
        return int(getattr(self.associator, "fallbacks", 0))

    @property
    def max_misses(self) -> int:
        """Misses in a row that delete a confirmed track under M-of-N (the manager's, or
        the rule of ``config`` at the current detection probability)."""
        m = self.manager if isinstance(self.manager, MofNManager) else None
        return (m or MofNManager.from_config(self.config)).max_misses(self.detection.pd)


def _empty_like(flt: RecursiveFilter) -> TrackState:
    n = len(flt.state_names)
    return TrackState.new(np.zeros(0), np.zeros((0, n)), np.zeros((0, n, n)))


@dataclass(frozen=True)
class TrackerRun:
    """A whole file through the tracker.

    Attributes
    ----------
    t, track, status : one row per (scan, reported track) -- tentative rows included only
        with ``all_tracks``
    plot : (R,) int -- index into the input plots of the plot used (-1: none)
    columns : the filter's output columns of each row
    plot_track : (N,) int -- per input plot: the id of the track it went to, -1 for clutter
        (plots of tracks never reported count as clutter unless ``all_tracks``)
    scan_times : (K,) s
    seconds_per_scan : (K,) wall time of each step
    clutter_per_scan : (K,) the clutter rate used at each scan
    confirmed_ids : ids of every track that was reported at some scan
    cpu_seconds_per_scan : (K,) processor time of each step (this process)
    existence : (R,) existence probability of the track of each row
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
    existence: FloatArray = field(default_factory=lambda: np.zeros(0))


def usable_plots(plots: Plots) -> NDArray[np.bool_]:
    """Plots the tracker can use: finite values, range > 0."""
    good = np.isfinite(plots.polar()).all(-1) & np.isfinite(plots.sensor).all(-1)
    return np.asarray(good & (plots.range > 0))


def run_tracker(
    tracker: Tracker, plots: Plots, all_tracks: bool = False, progress: Progress | None = None
) -> TrackerRun:
    """Feed a whole file to ``tracker`` scan by scan and collect the output rows
    (``progress``: told of the plots done after every scan)."""
    order = np.argsort(plots.t, kind="stable")
    in_order = bool(np.all(order == np.arange(order.size)))
    sorted_plots = plots if in_order else plots.take(order)
    good = usable_plots(sorted_plots)
    times, starts = np.unique(sorted_plots.t, return_index=True)
    bounds = np.append(starts, order.size)
    rows: dict[str, list[NDArray[Any]]] = {k: [] for k in ("t", "track", "status", "plot", "r")}
    states = []
    confirmed_ids: list[IntArray] = []
    seq_track = np.full(order.size, -1, np.int64)  # by sequence number = position in order
    secs, cpu, clutter = np.zeros(times.size), np.zeros(times.size), np.zeros(times.size)
    for k in range(times.size):
        a, b = int(bounds[k]), int(bounds[k + 1])
        if progress is not None:
            progress.update(a)
        scan = _slice(sorted_plots, a, b)
        keep = np.flatnonzero(good[a:b])
        t0, c0 = time.perf_counter(), time.process_time()
        res = tracker.step(times[k], scan, keep)
        secs[k], cpu[k] = time.perf_counter() - t0, time.process_time() - c0
        clutter[k] = res.clutter_per_scan
        seq_track[a:b] = res.plot_track
        seq_track[res.started_from[0]] = res.started_from[1]
        conf = res.status != _TENTATIVE
        confirmed_ids.append(res.track[conf])
        if all_tracks or conf.all():  # every row: no copies
            sel: Any = slice(None)
            states.append(res.state)
        else:
            sel = np.flatnonzero(conf)
            states.append(res.state.take(sel))
        n = res.track[sel].size
        if n == 0:
            states.pop()
            continue
        rows["t"].append(np.full(n, res.t))
        rows["track"].append(res.track[sel])
        rows["status"].append(res.status[sel])
        rows["plot"].append(
            np.where(res.plot[sel] >= 0, order[a + np.maximum(res.plot[sel], 0)], -1)
        )
        rows["r"].append(res.existence[sel])
    ever = np.unique(np.concatenate(confirmed_ids)) if confirmed_ids else np.zeros(0, np.int64)
    label = np.full(plots.t.size, -1, np.int64)
    label[order] = seq_track if all_tracks else np.where(np.isin(seq_track, ever), seq_track, -1)

    def cat(key: str, dtype: Any) -> NDArray[Any]:
        return np.concatenate(rows[key]) if rows[key] else np.zeros(0, dtype)

    out_cols: dict[str, NDArray[Any]] = {}
    if states:
        out_cols = dict(tracker.flt.columns(TrackState.concat(states)))
    return TrackerRun(
        cat("t", float), cat("track", np.int64), cat("status", np.int8), cat("plot", np.int64),
        out_cols, label, times, secs, clutter, ever, cpu, cat("r", float),
    )  # fmt: skip


def _slice(plots: Plots, a: int, b: int) -> Plots:
    """Plots ``a:b`` as views (no copies)."""
    sl = slice(a, b)

    def sub(x: Any) -> Any:
        return None if x is None else x[sl]

    return Plots(
        plots.t[sl], plots.range[sl], plots.azimuth[sl], sub(plots.elevation),
        sub(plots.range_rate), plots.sensor[sl], plots.sensor_vel[sl], plots.line[sl],
    )  # fmt: skip
