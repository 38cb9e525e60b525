"""The roles of the multi-target tracker: its configuration, the protocols of the
association and track-management roles, and their default implementations.

A role works on arrays of every live track at once (a batch ``B``) and every plot of the
scan (``N``); the engine (:class:`seatrack.tracking.roles.Tracker`) predicts, gates and
keeps the books, the roles decide:

* :class:`Associator` -- which plot updates which track, and the tracks' existence after
  the scan: :class:`GNN` (global nearest neighbour, IPDA existence) and :class:`JPDA`
  (joint probabilistic data association over clusters, JIPDA existence);
* :class:`TrackManager` -- which tracks are reported and which are deleted:
  :class:`ExistenceManager` (by the existence probability) and :class:`MofNManager`
  (M-of-N hits, a run of misses);
* the :class:`~seatrack.tracking.roles.Initiator` protocol and its two-point
  implementation live in :mod:`seatrack.tracking.initiators`.

The data passed to the roles are the frozen carriers :class:`ScanData` (the scan and its
rates), :class:`Hypotheses` (the gated track-plot pairs and their log likelihood ratios)
and :class:`Association` (what an associator returns).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import Any
from typing import Protocol
from typing import runtime_checkable

import numpy as np
from numpy.typing import NDArray

from seatrack.config import Checked
from seatrack.config import param
from seatrack.config import parse_config
from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import TrackState
from seatrack.tracking.association import gnn
from seatrack.tracking.association import jpda
from seatrack.tracking.clutter import ClutterRate
from seatrack.tracking.deletion import position_std
from seatrack.tracking.deletion import to_delete
from seatrack.tracking.existence import ipda_update
from seatrack.tracking.existence import jipda_update
from seatrack.tracking.existence import logit
from seatrack.tracking.existence import probability
from seatrack.tracking.initiation import confirmed
from seatrack.tracking.initiation import hopeless
from seatrack.tracking.merge import merge_hypotheses
from seatrack.tracking.tracks import TrackTable

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

__all__ = [
    "TrackerConfig",
    "TrackStatus",
    "ScanData",
    "Hypotheses",
    "Association",
    "Associator",
    "TrackManager",
    "GNN",
    "JPDA",
    "ExistenceManager",
    "MofNManager",
    "UPDATED",
]

#: JPDA hypotheses below this probability are not updated (their weight goes to the miss)
PRUNE = 1e-3
#: automatic deletion (M-of-N): a live target shows the run of misses with this probability
LOST = 0.001
#: ``PlotStatus.UPDATED`` as an integer (the filters' per-plot status)
UPDATED = int(PlotStatus.UPDATED)


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
class TrackerConfig(Checked):
    """Parameters of the multi-target tracker (the sensor noise is the filter's).

    The fields hold SI values (m/s, s, rad/s); their keys carry the edge unit
    (``max_speed_kn``, ``initial_speed_sigma_kn``, ``turn_rate_dps``, ``mean_life_s``,
    ``max_position_std_m``). From Python, set them by key and edge unit with
    :meth:`from_keys` -- ``TrackerConfig.from_keys(max_speed_kn=30)`` is 30 kn -- as a
    configuration file does; the constructor takes the SI field names
    (``TrackerConfig(max_speed=15.4)`` is 15.4 m/s).
    """

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
        super().__post_init__()
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

    @classmethod
    def from_keys(cls, **keys: Any) -> TrackerConfig:
        """The configuration from user keys in their edge units, as a file gives them
        (``max_speed_kn=30``, ``turn_rate_dps=2``, ``m_of_n=(3, 4)``); unset keys keep
        their defaults. Raises :class:`~seatrack.config.ConfigError` naming a bad key."""
        return parse_config(cls, keys, source="TrackerConfig")


# ---------------------------------------------------------------------------
# What the roles see
# ---------------------------------------------------------------------------
@dataclass
class ScanData:
    """One scan as the roles see it.

    Attributes
    ----------
    plots : the scan's usable plots (``N``); ``pos`` (N, d) their Cartesian positions, m
    seq : (N,) their sequence numbers (order of arrival over all scans)
    t : s -- the scan time
    index : number of the scan (1 for the first)
    log_lam : log clutter density in the polar measurement space
    pd : detection probability used at this scan
    pg : gate probability
    log_ps : log survival probability since the last scan
    clutter : the clutter rate (given, or estimated: ``clutter.given is None``)
    space : the per-track filter's innovation space (``"polar"`` or ``"cartesian"``,
        :func:`~seatrack.tracking.gating.innovation_space`, measured once by the engine)
    explained : expected number of target plots among the scan's plots (the roles add
        to it; what is left is clutter)
    """

    plots: Plots
    pos: FloatArray
    seq: IntArray
    t: float
    index: int
    log_lam: float
    pd: float
    pg: float
    log_ps: float
    clutter: ClutterRate
    space: str
    explained: float = 0.0

    @property
    def log_miss_pg(self) -> float:
        """``log(1 - Pd Pg)``: a track that exists, given no plot in its gate."""
        return math.log1p(-self.pd * self.pg)


@dataclass(frozen=True)
class Hypotheses:
    """The gated track-plot pairs of a scan (``K`` pairs over ``B`` tracks).

    Attributes
    ----------
    track, plot : (K,) int -- batch index of the track and index of the plot of each pair
    log_lr : (K,) -- ``log(Pd g / lambda)``: the plot's likelihood ratio target / clutter
        (``g`` its density under the track's prediction, ``lambda`` the clutter density)
    weight : (K,) -- ``log_lr + log r``: the same weighed by the track's predicted
        existence probability ``r`` (JIPDA)
    log_miss : (B,) -- ``log(1 - r Pd Pg)``: each track's weight of having no plot
    logit : (B,) -- predicted log-odds of each track's existence
    """

    track: IntArray
    plot: IntArray
    log_lr: FloatArray
    weight: FloatArray
    log_miss: FloatArray
    logit: FloatArray


@dataclass(frozen=True)
class Association:
    """What an associator decided for the ``B`` tracks.

    Attributes
    ----------
    state : the updated states (batch ``B``)
    plot : (B,) int -- plot that updated each track (its most probable one for a soft
        association), -1 for none
    hit : (B,) bool -- updated by a plot (counts as a detection for M-of-N and Pd)
    logit : (B,) -- log-odds of each track's existence after the scan
    """

    state: TrackState
    plot: IntArray
    hit: BoolArray
    logit: FloatArray


# ---------------------------------------------------------------------------
# Protocols
# ---------------------------------------------------------------------------
@runtime_checkable
class Associator(Protocol):
    """Assigns the scan's plots to the tracks and updates them, all tracks at once.

    ``associate`` receives the per-track filter, the predicted states ``pred`` (batch
    ``B``), the scan and the gated pairs; it returns the updated states, the plot of each
    track, the hits and the existence log-odds. It adds its expected number of target
    plots to ``scan.explained`` (the rest of the plots feed the clutter estimate).
    """

    def associate(
        self, flt: RecursiveFilter, pred: TrackState, scan: ScanData, hyp: Hypotheses
    ) -> Association: ...


@runtime_checkable
class TrackManager(Protocol):
    """Confirms (reports) and deletes tracks.

    ``status`` gives the :class:`TrackStatus` of the tracks from batch index ``first``
    on (``hit``: theirs) and marks the reported ones in ``tracks.confirmed``;
    ``survivors`` says which tracks live on (``P``: their covariances, ``d`` the position
    dimension, ``pd`` the current detection probability).
    """

    def status(self, tracks: TrackTable, hit: BoolArray, first: int = 0) -> NDArray[np.int8]: ...

    def survivors(self, tracks: TrackTable, P: FloatArray, d: int, pd: float) -> BoolArray: ...


# ---------------------------------------------------------------------------
# Associators
# ---------------------------------------------------------------------------
class GNN:
    """Global nearest neighbour: the assignment of plots to tracks that maximises the sum
    of ``log(r Pd g / lambda) - log(1 - r Pd Pg)`` (a track may take no plot); one batched
    update of the assigned pairs; IPDA existence with the assigned plot's likelihood ratio.
    """

    def associate(
        self, flt: RecursiveFilter, pred: TrackState, scan: ScanData, hyp: Hypotheses
    ) -> Association:
        B, N = len(pred), len(scan.plots)
        best = gnn(hyp.track, hyp.plot, hyp.weight - hyp.log_miss[hyp.track], B, N)
        ti = np.flatnonzero(best >= 0)
        hit = np.zeros(B, bool)
        lr_hit = np.full(B, -np.inf)
        new = pred
        if 4 * ti.size >= 3 * B:  # most tracks: one call on the whole batch, no plot = NaN
            pk = scan.plots.take(np.maximum(best, 0))
            pk.range[best < 0] = np.nan  # an unusable plot: the track keeps its prediction
            with np.errstate(all="ignore"):  # (the contract: a bad plot is rejected)
                new = flt.update(pred, pk)
            hit = (best >= 0) & (new.status == UPDATED)
        elif ti.size:
            upd = flt.update(pred.take(ti), scan.plots.take(best[ti]))
            hit[ti[upd.status == UPDATED]] = True
            new = pred.put(ti, upd)
        if ti.size:
            k = np.flatnonzero(best[hyp.track] == hyp.plot)  # the assigned pairs
            lr_hit[hyp.track[k]] = hyp.log_lr[k]
            lr_hit[~hit] = -np.inf
        best = np.where(hit, best, -1)
        s_new = ipda_update(hyp.logit, scan.log_miss_pg, lr_hit)
        scan.explained += float(probability(s_new[hit]).sum())
        return Association(new, best, hit, s_new)


class JPDA:
    """Joint probabilistic data association with existence (JIPDA), exact over each
    cluster of tracks sharing plots: the marginal probability of every gated pair, every
    hypothesis above ``prune`` updated in one batched call and merged per track by moment
    matching; the track's plot is its most probable one unless the miss is likelier.

    Attributes
    ----------
    prune : hypotheses below this probability are not updated (their weight goes to the
        miss)
    fallbacks : clusters too large for the exact marginals (approximated), so far
    """

    def __init__(self, prune: float = PRUNE) -> None:
        if not 0.0 <= prune < 1.0:
            raise ValueError(f"prune: must be in [0, 1), got {prune!r}")
        self.prune = float(prune)
        self.fallbacks = 0

    def associate(
        self, flt: RecursiveFilter, pred: TrackState, scan: ScanData, hyp: Hypotheses
    ) -> Association:
        B, N = len(pred), len(scan.plots)
        res = jpda(hyp.track, hyp.plot, hyp.weight, hyp.log_miss, N)
        self.fallbacks += res.fallbacks
        beta_plot = np.bincount(hyp.track, res.beta, minlength=B)
        pdpg = scan.pd * scan.pg
        s_new = jipda_update(hyp.logit, math.log(pdpg), beta_plot, res.beta0)
        scan.explained += float(res.beta.sum())
        # dominant hypothesis of each track: its most probable plot unless the miss wins
        best = np.full(B, -1, np.int64)
        top = np.full(B, -1.0)
        order = np.lexsort((-res.beta, hyp.track))
        first = np.ones(order.size, bool)
        first[1:] = hyp.track[order][1:] != hyp.track[order][:-1]
        tt = hyp.track[order][first]
        top[tt] = res.beta[order][first]
        best[tt] = hyp.plot[order][first]
        best = np.where(top > res.beta0, best, -1)
        # the state given that the track exists: plots beta_ij, miss beta_i0 q_i
        r = probability(hyp.logit)
        q = r * (1.0 - pdpg) / np.maximum(1.0 - r * pdpg, 1e-300)
        sel = res.beta >= self.prune
        hyp_t, hyp_p, hyp_w = hyp.track[sel], hyp.plot[sel], res.beta[sel]
        hit = np.zeros(B, bool)
        if hyp_t.size == 0:
            return Association(pred, np.full(B, -1, np.int64), hit, s_new)
        upd = flt.update(pred.take(hyp_t), scan.plots.take(hyp_p))
        ok = upd.status == UPDATED
        hit[hyp_t[ok & (hyp_p == best[hyp_t])]] = True
        mixed = np.unique(hyp_t)
        hyps = TrackState.concat([upd, pred.take(mixed)])
        owner = np.concatenate([np.searchsorted(mixed, hyp_t), np.arange(mixed.size)])
        w = np.concatenate([np.where(ok, hyp_w, 0.0), (res.beta0 * q)[mixed]])
        new = pred.put(mixed, merge_hypotheses(flt, hyps, w, owner, mixed.size))
        return Association(new, np.where(hit, best, -1), hit, s_new)


# ---------------------------------------------------------------------------
# Track managers
# ---------------------------------------------------------------------------
def _is_count(v: object) -> bool:
    """``v`` is a whole number (an int, or a float with an integral value)."""
    return isinstance(v, (int, float, np.integer, np.floating)) and float(v).is_integer()


def _position_std_limit(max_position_std_m: float) -> float:
    """The deletion limit on a track's position std, m: a positive finite number."""
    if not (math.isfinite(max_position_std_m) and max_position_std_m > 0):
        raise ValueError(f"max_position_std_m: must be > 0 and finite, got {max_position_std_m!r}")
    return float(max_position_std_m)


def _status(reported: BoolArray, hit: BoolArray) -> NDArray[np.int8]:
    return np.where(reported, np.where(hit, _CONFIRMED, _COASTING), _TENTATIVE).astype(np.int8)


class ExistenceManager:
    """Confirmation and deletion by the existence probability (IPDA / JIPDA): a track is
    reported while its existence probability is at least ``confirm``, deleted when it
    falls below ``delete`` or when its position std exceeds ``max_position_std_m``."""

    def __init__(
        self, confirm: float = 0.7, delete: float = 0.05, max_position_std_m: float = 1000.0
    ) -> None:
        if not 0.0 <= delete < confirm <= 1.0:
            raise ValueError(f"need 0 <= delete < confirm <= 1, got {delete!r}, {confirm!r}")
        self.confirm = float(confirm)
        self.delete = float(delete)
        self.max_position_std = _position_std_limit(max_position_std_m)

    @classmethod
    def from_config(cls, config: TrackerConfig) -> ExistenceManager:
        """The manager of ``config`` (``confirm_existence``, ``delete_existence``,
        ``max_position_std``)."""
        return cls(config.confirm_existence, config.delete_existence, config.max_position_std)

    def status(self, tracks: TrackTable, hit: BoolArray, first: int = 0) -> NDArray[np.int8]:
        sl = slice(first, None)
        reported = tracks.logit[sl] >= logit(self.confirm)
        tracks.confirmed[sl] |= reported
        return _status(reported, hit)

    def survivors(self, tracks: TrackTable, P: FloatArray, d: int, pd: float) -> BoolArray:
        gone = tracks.logit < logit(self.delete)
        gone |= ~(position_std(P, d) <= self.max_position_std)
        return np.asarray(~gone)


class MofNManager:
    """M-of-N confirmation: a tentative track is confirmed with ``m`` hits in its first
    ``n`` scans (the two initiating plots count), deleted once that has become impossible;
    a confirmed track is deleted after ``max_misses`` misses in a row (None: the shortest
    run a live target shows with probability below :data:`LOST`, from the detection
    probability) or when its position std exceeds ``max_position_std_m``."""

    def __init__(
        self,
        m: int = 3,
        n: int = 4,
        max_misses: int | None = None,
        max_position_std_m: float = 1000.0,
    ) -> None:
        if not (_is_count(m) and _is_count(n) and 2 <= m <= n):
            raise ValueError(f"need integers 2 <= m <= n, got m={m!r}, n={n!r}")
        if max_misses is not None and not (_is_count(max_misses) and max_misses >= 1):
            raise ValueError(f"max_misses: must be an integer >= 1, got {max_misses!r}")
        self.m, self.n = int(m), int(n)
        self.max_misses_given = None if max_misses is None else int(max_misses)
        self.max_position_std = _position_std_limit(max_position_std_m)

    @classmethod
    def from_config(cls, config: TrackerConfig) -> MofNManager:
        """The manager of ``config`` (``m_of_n``, ``max_misses``, ``max_position_std``)."""
        m, n = config.m_of_n
        return cls(m, n, config.max_misses, config.max_position_std)

    def max_misses(self, pd: float) -> int:
        """Misses in a row that delete a confirmed track (given, or the shortest run a live
        target detected with probability ``pd`` shows with probability below LOST)."""
        if self.max_misses_given is not None:
            return self.max_misses_given
        pd = min(pd, 0.999)
        return max(2, math.ceil(math.log(LOST) / math.log1p(-pd) - 1e-9))

    def status(self, tracks: TrackTable, hit: BoolArray, first: int = 0) -> NDArray[np.int8]:
        sl = slice(first, None)
        reported = tracks.confirmed[sl] | confirmed(tracks.hits[sl], tracks.age[sl], self.m, self.n)
        tracks.confirmed[sl] |= reported
        return _status(reported, hit)

    def survivors(self, tracks: TrackTable, P: FloatArray, d: int, pd: float) -> BoolArray:
        gone = to_delete(tracks.misses, P, d, self.max_misses(pd), self.max_position_std)
        gone |= ~tracks.confirmed & hopeless(tracks.hits, tracks.age, self.m, self.n)
        return np.asarray(~gone)
