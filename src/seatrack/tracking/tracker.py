"""The multi-target tracker: unlabelled plots in, tracks with stable ids out.

One scan (all plots of one time) at a time, every step vectorised over the tracks:

1. predict every track to the scan time (one batched ``predict`` of the per-track filter)
   and its existence probability (:mod:`~seatrack.tracking.existence`: survival);
2. gate (:mod:`~seatrack.tracking.gating`): spatial pre-gate, then the filter's own
   innovation and a chi-square gate, one batched ``innovation`` over the candidate pairs;
3. associate every track at once (:mod:`~seatrack.tracking.association`: GNN, or exact
   JPDA over clusters) with the log likelihood ratios ``log(r Pd g / lambda)`` against
   ``log(1 - r Pd Pg)`` -- ``r`` the track's existence probability, so a doubtful track
   yields a contested plot to a sure one; ``lambda`` the clutter density (given, or
   estimated from the plots the tracks do not explain, :mod:`~seatrack.tracking.clutter`);
4. one batched ``update`` over every (track, plot) pair -- for JPDA over every hypothesis,
   merged per track by moment matching (:mod:`~seatrack.tracking.merge`) -- and the
   existence update (IPDA / JIPDA);
5. report, confirm and delete: with ``confirmation = "existence"`` (default) a track is
   reported (status confirmed or coasting) while its existence probability is at least
   ``confirm_existence`` and deleted below ``delete_existence``; with ``"m-of-n"`` by
   M-of-N hits and ``max_misses`` misses in a row. Both delete tracks whose position std
   exceeds ``max_position_std``;
6. start tentative tracks from pairs of free plots of the last scans that pass the speed
   gate (:mod:`~seatrack.tracking.initiation`), their existence from the prior odds of a
   new target and the second plot's likelihood; the free plots left wait.

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
from enum import IntEnum
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.config import check_fields
from seatrack.config import param
from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import plot_gaussian
from seatrack.tracking.association import gnn
from seatrack.tracking.association import jpda
from seatrack.tracking.clutter import ClutterRate
from seatrack.tracking.clutter import DetectionRate
from seatrack.tracking.clutter import SurveillanceRegion
from seatrack.tracking.deletion import position_std
from seatrack.tracking.deletion import to_delete
from seatrack.tracking.existence import UndetectedTargets
from seatrack.tracking.existence import first_scan_share
from seatrack.tracking.existence import ipda_update
from seatrack.tracking.existence import jipda_update
from seatrack.tracking.existence import logit
from seatrack.tracking.existence import probability
from seatrack.tracking.existence import survive
from seatrack.tracking.gating import POLAR
from seatrack.tracking.gating import Candidates
from seatrack.tracking.gating import gate
from seatrack.tracking.gating import innovation_space
from seatrack.tracking.gating import log_jacobian
from seatrack.tracking.gating import nis_logpdf
from seatrack.tracking.initiation import confirmed
from seatrack.tracking.initiation import hopeless
from seatrack.tracking.initiation import polar_covariance
from seatrack.tracking.initiation import speed_gate_pairs
from seatrack.tracking.merge import merge_hypotheses
from seatrack.tracking.tracks import PendingPlots
from seatrack.tracking.tracks import TrackTable

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "TrackerConfig",
    "TrackStatus",
    "ScanResult",
    "MultiTargetTracker",
    "TrackerRun",
    "run_tracker",
    "usable_plots",
]

#: JPDA hypotheses below this probability are not updated (their weight goes to the miss)
PRUNE = 1e-3
#: automatic deletion (M-of-N): a live target shows the run of misses with this probability
LOST = 0.001
_UPDATED = int(PlotStatus.UPDATED)


class TrackStatus(IntEnum):
    """Status of a track at a scan (the ``status`` output column)."""

    TENTATIVE = 0  #: not (or no longer) reported: existence below the threshold
    CONFIRMED = 1  #: reported, updated by a plot this scan
    COASTING = 2  #: reported, no plot this scan
    DELETED = 3  #: deleted at this scan (no output row)

    @property
    def label(self) -> str:
        return self.name.lower()


_TENTATIVE, _CONFIRMED, _COASTING = (
    int(TrackStatus.TENTATIVE),
    int(TrackStatus.CONFIRMED),
    int(TrackStatus.COASTING),
)


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
    confirmation: str = param(
        "existence", doc="track confirmation and deletion rule",
        choices=("existence", "m-of-n"),
    )  # fmt: skip
    confirm_existence: float = param(
        0.7, doc="existence: report a track while its existence probability is at least this",
        min=0, max=1, exclusive_min=True,
    )  # fmt: skip
    delete_existence: float = param(
        0.05, doc="existence: delete a track when its existence probability falls below",
        min=0, max=1,
    )  # fmt: skip
    births_per_scan: float = param(
        0.02, unit="1/scan", doc="existence: expected new targets per scan over the region",
        min=0, exclusive_min=True,
    )  # fmt: skip
    mean_life: float = param(
        1800.0, key="mean_life_s", unit="s", doc="existence: mean target lifetime (survival)",
        min=0, exclusive_min=True,
    )  # fmt: skip
    m_of_n: tuple[int, int] = param(
        (3, 4), doc="m-of-n: confirm with M hits in the first N scans (2 initiating plots count)"
    )
    max_misses: int | None = param(
        None, unit="scans",
        doc="m-of-n: delete after this many misses in a row (none: when a live target would "
        "show such a run with probability below 0.1 %, from the detection probability)",
        min=1,
    )  # fmt: skip
    max_position_std: float = param(
        1000.0, key="max_position_std_m", unit="m", doc="delete when the position std exceeds",
        min=0, exclusive_min=True,
    )  # fmt: skip
    max_speed: float = param(
        40.0, key="max_speed_kn", unit="kn", doc="speed gate of two-point initiation",
        min=1e-3, max=1e5,  # physical bounds: a new track's speed variance stays finite
    )  # fmt: skip
    initial_speed_sigma: float = param(
        12.0, key="initial_speed_sigma_kn", unit="kn",
        doc="velocity std per axis of a new track (target class: RMS speed sqrt(2) x this)",
        min=1e-3, max=1e5,  # a new track's velocity variance stays finite
    )  # fmt: skip
    association: str = param("gnn", doc="association of the tracks", choices=("gnn", "jpda"))
    clutter_memory: float = param(20.0, unit="scans", doc="memory of the clutter estimate", min=1)
    turn_rate: float = param(
        0.0, key="turn_rate_dps", unit="deg/s", min=0, max=30,
        doc="coordinated-turn models (one each way) added to the automatic process noise "
        "(0: none; 2 lowered the tuning scenarios' mean GOSPA by 1.7 % for up to 40 % more "
        "time per scan, docs/tracking.md)",
    )  # fmt: skip
    init_scans: int = param(
        3,
        unit="scans",
        doc="a new track pairs plots of up to this many consecutive scans",
        min=2,
    )

    def __post_init__(self) -> None:
        check_fields(self)  # bounds of the keys also when built directly
        mn = tuple(self.m_of_n)
        if len(mn) != 2 or any(float(v) != int(v) for v in mn):
            raise ValueError(f"m_of_n: expected two integers [M, N], got {list(mn)}")
        m, n = int(mn[0]), int(mn[1])
        if not 2 <= m <= n:
            raise ValueError(f"m_of_n: need 2 <= M <= N, got [{m}, {n}]")
        object.__setattr__(self, "m_of_n", (m, n))
        if self.delete_existence >= self.confirm_existence:
            raise ValueError(
                f"delete_existence ({self.delete_existence:g}) must be below "
                f"confirm_existence ({self.confirm_existence:g})"
            )


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
    existence : (B,) -- existence probability of each track
    plot_track : (N,) int -- id of the track each plot of the scan went to, -1 when none
    started_from : (2, k) int -- plots of *earlier* scans that started tracks: their
        sequence numbers (order of arrival over all scans) and the track ids
    deleted : ids of the tracks deleted at this scan
    clutter_per_scan : the clutter rate used
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


@dataclass
class _Scan:
    """Working data of one scan."""

    plots: Plots
    pos: FloatArray
    seq: IntArray
    t: float
    log_lam: float  # log clutter density (polar measurement space)
    pd: float
    log_ps: float  # log survival probability since the last scan
    explained: float = 0.0  # expected number of target plots among the scan's plots


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
        self.space = innovation_space(flt, sensor)
        self.state: TrackState | None = None
        self.tracks = TrackTable.empty()
        self.pending: list[PendingPlots] = []  # free plots of recent scans, one entry each
        self.region = SurveillanceRegion()
        self.clutter = ClutterRate(self.config.clutter_density, self.config.clutter_memory)
        self.detection = DetectionRate(self.config.pd)
        self.undetected = UndetectedTargets(self.config.births_per_scan)
        self.next_id = 1
        self.n_seen = 0
        self.n_scans = 0
        self.jpda_fallbacks = 0
        self._t = -math.inf
        self._existence_rule = self.config.confirmation == "existence"
        self._log_pg_miss = 0.0  # set per scan: log(1 - Pd Pg)

    # -- one scan ---------------------------------------------------------------------
    def step(self, plots: Plots, usable: IntArray | None = None) -> ScanResult:
        """Process the plots of one scan (all with the same time, later than the last).

        Plots with a non-finite value or a range <= 0 are left out (labelled -1); the
        tracks coast over them. ``usable``: the indices of the usable plots when the caller
        has checked the plots already (:func:`run_tracker` checks a whole file at once).
        """
        if len(plots) == 0:
            raise ValueError("a scan needs at least one plot")
        t = float(plots.t[0])
        if usable is None:
            if np.any(plots.t != t):
                raise ValueError("all plots of a scan must have the same time")
            usable = np.flatnonzero(usable_plots(plots))
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
        )

    def _begin(self, plots: Plots, seq: IntArray, t: float) -> _Scan:
        pd = self.detection.pd
        pg = self.config.gate_probability
        self._log_pg_miss = math.log1p(-pd * pg)
        volume = self.region.volume(plots.is_3d, self._uses_range_rate(plots))
        log_lam = math.log(self.clutter.per_scan / volume)
        dt = t - self._t if math.isfinite(self._t) else 0.0
        return _Scan(plots, plots.positions(), seq, t, log_lam, pd, -dt / self.config.mean_life)

    def _uses_range_rate(self, plots: Plots) -> bool:
        return bool(plots.range_rate is not None and self.flt.range_rate)

    def _scan(
        self, scan: _Scan
    ) -> tuple[TrackState | None, NDArray[np.int8], IntArray, IntArray, IntArray, IntArray]:
        """Existing tracks, then initiation, then the clutter and prior updates."""
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
        started = self._initiate(scan, used) if len(plots) else None
        if started is not None:
            new_state, first, second, ids, born = started
            plot_track[second] = ids
            state = new_state if state is None else TrackState.concat([state, new_state])
            status = np.concatenate([status, born])
            best = np.concatenate([best, second])
            started_from = np.stack([first, ids])
        if self.config.clutter_density is None:
            self.clutter.update(len(plots) - scan.explained)
        self.undetected.advance(scan.pd, math.exp(scan.log_ps))
        return state, status, best, plot_track, started_from, deleted

    # -- existing tracks --------------------------------------------------------------
    def _existing(
        self, scan: _Scan
    ) -> tuple[TrackState, IntArray, NDArray[np.int8], IntArray, IntArray]:
        """Predict, gate, associate, update, report and delete the existing tracks."""
        assert self.state is not None
        tr, plots = self.tracks, scan.plots
        B, N = len(self.state), len(plots)
        pred = self.flt.predict(self.state, np.full(B, scan.t))
        s_pred = survive(tr.logit, scan.log_ps)
        cand = gate(self.flt, pred, plots, scan.pos, self.sensor, self.config.gate_probability,
                    self.space)  # fmt: skip
        log_lr = math.log(scan.pd) + cand.log_g - scan.log_lam  # IPDA: log(Pd g / lambda)
        r_pred = probability(s_pred)
        log_miss = np.log1p(-r_pred * scan.pd * self.config.gate_probability)
        log_lr_r = log_lr + np.log(np.maximum(r_pred[cand.track], 1e-300))  # JIPDA weights
        if self.config.association == "jpda":
            new, best, hit, s_new = self._jpda(scan, pred, cand, log_lr_r, log_miss, s_pred)
        else:
            new, best, hit, s_new = self._gnn(scan, pred, cand, log_lr, log_lr_r, log_miss,
                                              s_pred)  # fmt: skip
        tr.logit = s_new
        used = np.full(N, -1, np.int64)
        used[best[best >= 0]] = np.flatnonzero(best >= 0)
        status = self._bookkeeping(hit, new.P)
        keep = self._survivors(new, plots.d)
        deleted = tr.id[~keep]
        if deleted.size == 0:
            return new, used, status, best, deleted
        remap = np.cumsum(keep) - 1
        u = np.maximum(used, 0)
        used = np.where((used >= 0) & keep[u], remap[u], -1)
        self.tracks = tr.take(keep)
        return new.take(keep), used, status[keep], best[keep], deleted

    def _gnn(
        self, scan: _Scan, pred: TrackState, cand: Candidates, log_lr: FloatArray,
        log_lr_r: FloatArray, log_miss: FloatArray, s_pred: FloatArray,
    ) -> tuple[TrackState, IntArray, NDArray[np.bool_], FloatArray]:  # fmt: skip
        """GNN over every track; one batched update of the assigned pairs; IPDA existence."""
        B, N = len(pred), len(scan.plots)
        best = gnn(cand.track, cand.plot, log_lr_r - log_miss[cand.track], B, N)
        ti = np.flatnonzero(best >= 0)
        hit = np.zeros(B, bool)
        lr_hit = np.full(B, -np.inf)
        new = pred
        if 4 * ti.size >= 3 * B:  # most tracks: one call on the whole batch, no plot = NaN
            pk = scan.plots.take(np.maximum(best, 0))
            pk.range[best < 0] = np.nan  # an unusable plot: the track keeps its prediction
            with np.errstate(all="ignore"):  # (the contract: a bad plot is rejected)
                new = self.flt.update(pred, pk)
            hit = (best >= 0) & (new.status == _UPDATED)
        elif ti.size:
            upd = self.flt.update(pred.take(ti), scan.plots.take(best[ti]))
            hit[ti[upd.status == _UPDATED]] = True
            new = pred.put(ti, upd)
        if ti.size:
            k = np.flatnonzero(best[cand.track] == cand.plot)  # the assigned pairs
            lr_hit[cand.track[k]] = log_lr[k]
            lr_hit[~hit] = -np.inf
        best = np.where(hit, best, -1)
        s_new = ipda_update(s_pred, self._log_pg_miss, lr_hit)
        scan.explained += float(probability(s_new[hit]).sum())
        return new, best, hit, s_new

    def _jpda(
        self, scan: _Scan, pred: TrackState, cand: Candidates, log_lr_r: FloatArray,
        log_miss: FloatArray, s_pred: FloatArray,
    ) -> tuple[TrackState, IntArray, NDArray[np.bool_], FloatArray]:  # fmt: skip
        """JIPDA over every track: marginals, hypotheses updated in one call and merged."""
        B, N = len(pred), len(scan.plots)
        res = jpda(cand.track, cand.plot, log_lr_r, log_miss, N)
        self.jpda_fallbacks += res.fallbacks
        beta_plot = np.bincount(cand.track, res.beta, minlength=B)
        pdpg = scan.pd * self.config.gate_probability
        s_new = jipda_update(s_pred, math.log(pdpg), beta_plot, res.beta0)
        scan.explained += float(res.beta.sum())
        # dominant hypothesis of each track: its most probable plot unless the miss wins
        best = np.full(B, -1, np.int64)
        top = np.full(B, -1.0)
        order = np.lexsort((-res.beta, cand.track))
        first = np.ones(order.size, bool)
        first[1:] = cand.track[order][1:] != cand.track[order][:-1]
        tt = cand.track[order][first]
        top[tt] = res.beta[order][first]
        best[tt] = cand.plot[order][first]
        best = np.where(top > res.beta0, best, -1)
        # the state given that the track exists: plots beta_ij, miss beta_i0 q_i
        r = probability(s_pred)
        q = r * (1.0 - pdpg) / np.maximum(1.0 - r * pdpg, 1e-300)
        sel = res.beta >= PRUNE
        hyp_t, hyp_p, hyp_w = cand.track[sel], cand.plot[sel], res.beta[sel]
        hit = np.zeros(B, bool)
        if hyp_t.size == 0:
            return pred, np.full(B, -1, np.int64), hit, s_new
        upd = self.flt.update(pred.take(hyp_t), scan.plots.take(hyp_p))
        ok = upd.status == _UPDATED
        hit[hyp_t[ok & (hyp_p == best[hyp_t])]] = True
        mixed = np.unique(hyp_t)
        hyps = TrackState.concat([upd, pred.take(mixed)])
        owner = np.concatenate([np.searchsorted(mixed, hyp_t), np.arange(mixed.size)])
        w = np.concatenate([np.where(ok, hyp_w, 0.0), (res.beta0 * q)[mixed]])
        new = pred.put(mixed, merge_hypotheses(self.flt, hyps, w, owner, mixed.size))
        return new, np.where(hit, best, -1), hit, s_new

    def _bookkeeping(self, hit: NDArray[np.bool_], P: FloatArray) -> NDArray[np.int8]:
        """Hits, misses, ages, confirmation; the status of every track this scan (``P``:
        their covariances)."""
        tr = self.tracks
        after_hit = tr.confirmed & (tr.misses == 0)  # reported tracks updated last scan
        self.detection.update(int((after_hit & hit).sum()), int((after_hit & ~hit).sum()))
        tr.hits = tr.hits + hit
        tr.age = tr.age + 1
        tr.misses = np.where(hit, 0, tr.misses + 1)
        return self._status(hit, P)

    def _status(self, hit: NDArray[np.bool_], P: FloatArray, first: int = 0) -> NDArray[np.int8]:
        """Report rule: existence at least ``confirm_existence``, or M-of-N confirmed; of
        the tracks from ``first`` on (``hit``, ``P``: theirs)."""
        tr, sl = self.tracks, slice(first, None)
        if self._existence_rule:
            reported = tr.logit[sl] >= logit(self.config.confirm_existence)
        else:
            reported = tr.confirmed[sl] | confirmed(tr.hits[sl], tr.age[sl], *self.config.m_of_n)
        tr.confirmed[sl] |= reported
        return np.where(reported, np.where(hit, _CONFIRMED, _COASTING), _TENTATIVE).astype(np.int8)

    def _survivors(self, state: TrackState, d: int) -> NDArray[np.bool_]:
        cfg, tr = self.config, self.tracks
        if self._existence_rule:
            gone = tr.logit < logit(cfg.delete_existence)
            gone |= ~(position_std(state.P, d) <= cfg.max_position_std)
        else:
            m, n = cfg.m_of_n
            gone = to_delete(tr.misses, state.P, d, self.max_misses, cfg.max_position_std)
            gone |= ~tr.confirmed & hopeless(tr.hits, tr.age, m, n)
        return np.asarray(~gone)

    @property
    def max_misses(self) -> int:
        """Misses in a row that delete a confirmed track under M-of-N (given, or from the
        detection probability: the shortest run a live target shows with probability below
        LOST)."""
        if self.config.max_misses is not None:
            return self.config.max_misses
        pd = min(self.detection.pd, 0.999)
        return max(2, math.ceil(math.log(LOST) / math.log1p(-pd) - 1e-9))

    # -- initiation -------------------------------------------------------------------
    def _initiate(
        self, scan: _Scan, used: IntArray
    ) -> tuple[TrackState, IntArray, IntArray, IntArray, NDArray[np.int8]] | None:
        """Pair free plots of the last ``init_scans`` scans with this scan's free plots
        (speed gate); start a tentative track from each pair; the rest wait."""
        cfg, plots = self.config, scan.plots
        free = np.flatnonzero(used < 0)
        out = None
        cov = polar_covariance(plots, self.sensor, free)
        entries = self.pending
        if entries and free.size:
            cat = lambda f: np.concatenate([f(e) for e in entries])  # noqa: E731
            pairs = speed_gate_pairs(
                cat(lambda e: e.pos), cat(lambda e: e.cov), cat(lambda e: e.plots.t),
                scan.pos[free], cov, scan.t, cfg.max_speed, cfg.gate_probability,
                plots.sensor[0], cfg.initial_speed_sigma,
            )  # fmt: skip
            if pairs.first.size:
                prev = entries[0] if len(entries) == 1 else PendingPlots.concat(entries)
                out = self._births(scan, prev, pairs.first, free[pairs.second])
                left = np.ones(free.size, bool)
                left[pairs.second] = False
                free, cov = free[left], cov[left]
                self.pending = _without(entries, pairs.first)
        if self.n_scans == 2 and out is None and entries:  # no pair: the share is small
            self._first_scan_prior(np.zeros(0), scan)
        self._wait(scan, free, cov)
        return out

    def _births(
        self, scan: _Scan, prev: PendingPlots, i: IntArray, j: IntArray
    ) -> tuple[TrackState, IntArray, IntArray, IntArray, NDArray[np.int8]]:
        """Start tracks from pairs (earlier plot ``i`` of ``prev``, this scan's plot ``j``)."""
        first, second = prev.plots.take(i), scan.plots.take(j)
        new, log_g = self._start(first, second, scan.t)
        ok = new.status == _UPDATED
        i, j, new, log_g = i[ok], j[ok], new.take(ok), log_g[ok]
        k = i.size
        # existence: the first plot's prior, the scans between, the second plot
        gap = self.n_scans - prev.scan[i]
        s = gap * scan.log_ps + (gap - 1) * math.log1p(-scan.pd)
        s = ipda_update(s, self._log_pg_miss, math.log(scan.pd) + log_g - scan.log_lam)
        if self.n_scans == 2:  # the pairs tell the share of targets in the first scan
            self._first_scan_prior(s[prev.scan[i] == 1], scan)  # (prev is pending[0])
        s = s + prev.log_prior[i]
        ids = self.next_id + np.arange(k, dtype=np.int64)
        self.next_id += k
        hits = np.full(k, 2, np.int64)
        born = TrackTable(ids, s, np.zeros(k, bool), hits, gap + 1, np.zeros(k, np.int64))
        n0 = len(self.tracks)
        self.tracks = TrackTable.concat([self.tracks, born])
        status = self._status(np.ones(k, bool), new.P, n0)
        r = probability(s)
        scan.explained += float(r.sum())
        if self.config.clutter_density is None:
            for g in np.unique(gap):  # the first plots were counted as clutter then
                self.clutter.explain_earlier(float(r[gap == g].sum()), float(g))
        return new, prev.seq[i], j, ids, status

    def _first_scan_prior(self, log_lr: FloatArray, scan: _Scan) -> None:
        """Prior odds of the first scan's plots from the pairs they formed at the second
        (:func:`~seatrack.tracking.existence.first_scan_share`)."""
        u = self.undetected
        share = first_scan_share(log_lr, u.first_plots, scan.pd)
        lp = u.first_scan(share, scan.pd, math.exp(scan.log_ps))
        for e in self.pending:
            e.log_prior[e.scan == 1] = lp

    def _wait(self, scan: _Scan, free: IntArray, cov: FloatArray) -> None:
        """The free plots of this scan join the waiting ones still young enough to pair with
        the next scan (one entry per scan, oldest first)."""
        n = free.size
        lp = self.undetected.log_prior_odds(scan.pd, self.clutter.per_scan, len(scan.plots))
        keep = self.config.init_scans - 1
        entries = [e for e in self.pending if self.n_scans - int(e.scan[0]) < keep]
        if n:
            entries.append(PendingPlots(
                scan.plots.take(free), scan.pos[free], cov, scan.seq[free],
                np.full(n, self.n_scans, np.int64), np.full(n, lp),
            ))  # fmt: skip
        self.pending = entries

    def _start(self, first: Plots, second: Plots, t: float) -> tuple[TrackState, FloatArray]:
        """New tracks: the first plot with a zero-mean velocity prior (std
        ``initial_speed_sigma`` per axis: the target class), predicted to this scan and
        updated with the second plot by the filter itself; and the log density of the
        second plot under the prediction (polar measurement space, from the filter's
        innovation as in gating)."""
        x, P = plot_gaussian(first, self.sensor, self.config.initial_speed_sigma)
        pred = self.flt.predict(self.flt.initiate(first.t, x, P), np.full(len(first), t))
        log_g = nis_logpdf(*self.flt.innovation(pred, second))[1]
        if self.space != POLAR:
            log_g = log_g + log_jacobian(self.space, second)
        return self.flt.update(pred, second), log_g

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

    @property
    def existence(self) -> FloatArray:
        """Existence probability of the live tracks."""
        return probability(self.tracks.logit)


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


def run_tracker(tracker: MultiTargetTracker, plots: Plots, all_tracks: bool = False) -> TrackerRun:
    """Feed a whole file to ``tracker`` scan by scan and collect the output rows."""
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
        scan = _slice(sorted_plots, a, b)
        keep = np.flatnonzero(good[a:b])
        t0, c0 = time.perf_counter(), time.process_time()
        res = tracker.step(scan, keep)
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
