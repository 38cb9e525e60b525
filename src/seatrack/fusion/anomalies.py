"""AIS anomalies that need no radar: shared MMSIs, implausible jumps, reporting gaps.

* **Identity conflict** -- two vessels transmitting one MMSI show as one report stream
  that alternates between two trajectories. :func:`split_identities` follows each MMSI's
  reports in time order with up to ``max_trajectories`` hypotheses: a report goes to the
  trajectory whose dead-reckoned position (last position plus the last velocity times the
  elapsed time) it is nearest to, among those it can be reached from at a plausible
  speed; a report that fits none starts a new trajectory. Trajectories that end with at
  least ``min_reports`` reports are vessels; when two of them overlap in time, their
  reports are flagged ``identity_conflict`` and tracked as separate vessels. A report
  after a silence longer than ``expiry`` continues the MMSI's latest trajectory when it
  can be reached from there at a plausible speed.
* **Jump** -- a report that fits no trajectory and whose new trajectory stays shorter
  than ``min_reports`` reports is an implausible position (flagged ``jump``, not tracked);
  when the new trajectory lasts but does not overlap the old one (the stream moved for
  good, e.g. a spoofed position), its first report is flagged ``jump`` and the new
  trajectory is tracked as the MMSI's next vessel (``sub`` + 1).
* **Gap** -- a vessel silent for longer than ``gap_factor`` times its own median reporting
  interval (and at least ``min_gap_s``): the report that ends the silence is flagged
  ``gap`` (:func:`reporting_gaps`). The same limit is the age after which the fusion
  stops predicting the vessel's last state.

Positions are metres in one East-North plane (the radar's); times seconds.
"""

from __future__ import annotations

import bisect
import math
from array import array
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais.kernel import vessel_starts
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import velocity_from_course

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "SplitConfig",
    "Split",
    "Trajectories",
    "follow_report",
    "split_identities",
    "reporting_gaps",
    "gap_limits",
    "RecentIntervals",
    "DEFAULT_GAP_FACTOR",
    "DEFAULT_MIN_GAP_S",
]

#: default gap limit keys (``[fusion]`` ``gap_factor`` and ``min_gap_s``): a gap is a
#: silence longer than this many of the vessel's median reporting intervals, and at least
#: ``DEFAULT_MIN_GAP_S`` (s)
DEFAULT_GAP_FACTOR = 2.5
DEFAULT_MIN_GAP_S = 30.0


@dataclass(frozen=True)
class SplitConfig:
    """Keys of :func:`split_identities` (SI: m/s, m, s)."""

    #: fastest plausible speed between two reports of one vessel (m/s)
    max_speed: float = 50.0 * KNOT_MPS
    #: distance allowed on top of ``max_speed * dt`` (position noise, antenna offsets) (m)
    slack: float = 300.0
    #: a trajectory silent this long ends (s)
    expiry: float = 900.0
    #: fewest reports of a trajectory that is a vessel rather than a jump
    min_reports: int = 3
    #: most simultaneous trajectories on one MMSI
    max_trajectories: int = 3


@dataclass(frozen=True)
class Split:
    """Result of :func:`split_identities`, one entry per report.

    ``vessel`` numbers the trajectories (vessels) 0..V-1 (-1 for jumps); ``sub`` is the
    trajectory's rank within its MMSI (0 for the first); ``jump`` and ``conflict`` are the
    flags; ``vessel_mmsi`` and ``vessel_sub`` describe each vessel.
    """

    vessel: IntArray
    sub: IntArray
    jump: NDArray[np.bool_]
    conflict: NDArray[np.bool_]
    vessel_mmsi: IntArray
    vessel_sub: IntArray


@dataclass
class Trajectories:
    """The trajectories of one MMSI followed so far: per trajectory its last report's
    time ``t`` (s), position ``xy`` (m) and velocity ``v`` (m/s; NaN unknown)."""

    t: list[float]
    xy: list[tuple[float, float]]
    v: list[tuple[float, float]]

    @classmethod
    def empty(cls) -> Trajectories:
        return cls([], [], [])


def follow_report(
    tr: Trajectories, t: float, xy: tuple[float, float], v: tuple[float, float],
    cfg: SplitConfig,
) -> tuple[int, bool]:  # fmt: skip
    """Trajectory label of the MMSI's next report (time order) at ``t``, ``xy``, ``v``,
    and whether it started a new trajectory while another was alive or out of reach (an
    implausible move); ``tr`` is updated (module docstring). Used report by report by
    :func:`split_identities` and by a live process (plain floats: a few microseconds)."""
    x, y = xy
    best, best_err = -1, math.inf
    for j, tj in enumerate(tr.t):
        dt = t - tj
        if dt > cfg.expiry:
            continue
        xj, yj = tr.xy[j]
        if math.hypot(x - xj, y - yj) > cfg.max_speed * dt + cfg.slack:
            continue
        vx, vy = tr.v[j]
        if not (math.isfinite(vx) and math.isfinite(vy)):
            vx = vy = 0.0
        err = math.hypot(x - xj - vx * dt, y - yj - vy * dt)
        if err < best_err:
            best, best_err = j, err
    moved = False
    if best < 0:
        alive = [j for j, tj in enumerate(tr.t) if t - tj <= cfg.expiry]
        latest = max(range(len(tr.t)), key=tr.t.__getitem__) if tr.t else -1
        reach = False
        if latest >= 0:
            xl, yl = tr.xy[latest]
            reach = math.hypot(x - xl, y - yl) <= cfg.max_speed * (t - tr.t[latest]) + cfg.slack
        moved = bool(alive) or (latest >= 0 and not reach)
        if not alive and reach:  # after a long silence, within reach: continued
            best = latest
        elif len(alive) >= cfg.max_trajectories:  # no room: the stalest one is replaced
            best = min(alive, key=tr.t.__getitem__)
        else:
            best = len(tr.t)
            tr.t.append(t)
            tr.xy.append(xy)
            tr.v.append(v)
    tr.t[best], tr.xy[best], tr.v[best] = t, xy, v
    return best, moved


def _follow(
    t: FloatArray, xy: FloatArray, v: FloatArray, cfg: SplitConfig
) -> tuple[IntArray, NDArray[np.bool_]]:
    """Trajectory label of each report of one MMSI (time order), and whether the report
    started a new trajectory while another was alive (:func:`follow_report`)."""
    n = t.size
    label = np.empty(n, np.int64)
    moved = np.zeros(n, bool)
    tr = Trajectories.empty()
    for i, (ti, p, u) in enumerate(zip(t.tolist(), xy.tolist(), v.tolist(), strict=True)):
        label[i], moved[i] = follow_report(tr, ti, (p[0], p[1]), (u[0], u[1]), cfg)
    return label, moved


def split_identities(
    mmsi: IntArray,
    t: FloatArray,
    xy: FloatArray,
    sog_kn: FloatArray,
    cog_deg: FloatArray,
    config: SplitConfig | None = None,
) -> Split:
    """Split each MMSI's reports into trajectories (see the module docstring).

    Parameters
    ----------
    mmsi, t : (N,) the reports' MMSI and time (s); any order.
    xy : (N, 2) East, North (m) in one plane.
    sog_kn, cog_deg : (N,) reported speed (kn) and course (deg true); NaN when absent
        (the velocity is then the difference from the trajectory's previous report).
    """
    cfg = config or SplitConfig()
    n = t.size
    v = velocity_from_course(np.radians(cog_deg), np.asarray(sog_kn) * KNOT_MPS)
    order = np.lexsort((t, mmsi))
    vessel = np.full(n, -1, np.int64)
    sub = np.full(n, -1, np.int64)
    jump = np.zeros(n, bool)
    conflict = np.zeros(n, bool)
    v_mmsi: list[int] = []
    v_sub: list[int] = []
    bounds = vessel_starts(mmsi[order])  # the runs of one MMSI
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        rows = order[a:b]
        lab, moved = _follow(t[rows], xy[rows], v[rows], cfg)
        sizes = np.bincount(lab)
        real = np.flatnonzero(sizes >= cfg.min_reports)
        if real.size == 0:  # a short stream: one vessel, nothing to judge it by
            real = np.array([int(np.argmax(sizes))])
        first_t = np.array([t[rows][lab == j].min() for j in real])
        real = real[np.argsort(first_t, kind="stable")]
        spans = [(t[rows][lab == j].min(), t[rows][lab == j].max()) for j in real]
        for rank, j in enumerate(real):
            mine = rows[lab == j]
            vessel[mine] = len(v_mmsi)
            sub[mine] = rank
            v_mmsi.append(int(mmsi[rows[0]]))
            v_sub.append(rank)
            lo, hi = spans[rank]
            if any(o_lo < hi and lo < o_hi for r, (o_lo, o_hi) in enumerate(spans) if r != rank):
                conflict[mine] = True
        jump[rows[~np.isin(lab, real)]] = True
        jump[rows[moved & ~conflict[rows]]] = True  # the first report after a jump
    return Split(
        vessel, sub, jump, conflict, np.asarray(v_mmsi, np.int64), np.asarray(v_sub, np.int64)
    )


def gap_limits(
    vessel: IntArray, t: FloatArray, n_vessels: int, gap_factor: float, min_gap_s: float
) -> FloatArray:
    """Per vessel: the longest silence its own reporting rate allows (s):
    ``max(gap_factor * median interval, min_gap_s)`` (``min_gap_s`` with one report)."""
    order = np.lexsort((t, vessel))
    vs, ts = vessel[order], t[order]
    same = vs[1:] == vs[:-1]
    dt = np.diff(ts)[same]
    owner = vs[1:][same]
    out = np.full(n_vessels, min_gap_s, float)
    if dt.size:
        srt = np.lexsort((dt, owner))
        dt, owner = dt[srt], owner[srt]
        first = np.searchsorted(owner, np.arange(n_vessels))
        last = np.searchsorted(owner, np.arange(n_vessels), side="right")
        has = last > first
        med = 0.5 * (dt[np.minimum((first + last - 1) // 2, dt.size - 1)]
                     + dt[np.minimum((first + last) // 2, dt.size - 1)])  # fmt: skip
        out[has] = np.maximum(gap_factor * med[has], min_gap_s)
    return out


class RecentIntervals:
    """The last ``size`` report times of one vessel (increasing) and the intervals between
    them kept sorted, so that :meth:`limit` is :func:`gap_limits` of those times (the same
    numbers) in constant time: for a live process, report by report. Both are held as
    float64 arrays (``array('d')``, 8 bytes a number: a live process keeps one per vessel,
    and a Python float in a list or deque costs 32)."""

    __slots__ = ("_sorted", "size", "times")

    def __init__(self, size: int = 64) -> None:
        self.size = size
        self.times = array("d")
        self._sorted = array("d")

    def push(self, t: float) -> None:
        """Add a report time (not before the last one)."""
        times = self.times
        if times:
            bisect.insort(self._sorted, t - times[-1])
        times.append(t)
        if len(times) > self.size:
            first = times.pop(0)
            self._remove(times[0] - first)

    def limit(self, gap_factor: float, min_gap_s: float) -> float:
        """``max(gap_factor * median interval, min_gap_s)``; ``min_gap_s`` with fewer
        than two times (:func:`gap_limits`)."""
        d, m = self._sorted, len(self._sorted)
        if m == 0:
            return min_gap_s
        return max(gap_factor * (0.5 * (d[(m - 1) // 2] + d[m // 2])), min_gap_s)

    def _remove(self, dt: float) -> None:
        del self._sorted[bisect.bisect_left(self._sorted, dt)]


def reporting_gaps(vessel: IntArray, t: FloatArray, limit: FloatArray) -> NDArray[np.bool_]:
    """Per report: True when it ends a silence of its vessel longer than ``limit[vessel]``
    (reports with ``vessel < 0`` are never flagged)."""
    n = t.size
    out = np.zeros(n, bool)
    ok = np.flatnonzero(vessel >= 0)
    order = ok[np.lexsort((t[ok], vessel[ok]))]
    vs, ts = vessel[order], t[order]
    same = np.r_[False, vs[1:] == vs[:-1]]
    dt = np.r_[0.0, np.diff(ts)]
    out[order] = same & (dt > limit[np.maximum(vs, 0)])
    return out
