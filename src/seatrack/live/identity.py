"""AIS anomalies in the live process: shared MMSIs split into tracks, jumps and gaps
flagged, report by report (causally), by the rules of :mod:`seatrack.fusion.anomalies`.

Each MMSI's position reports are followed in arrival order by
:func:`~seatrack.fusion.anomalies.follow_report` (the batch splitter's step), in one
East-North plane (the radar's when a radar is configured, as ``seatrack fuse``; else a
plane about the first report of each MMSI). A report gets the trajectory label the batch
gives it when the MMSI's reports arrive in time order. A trajectory is a vessel

* at once when it is the MMSI's first (a new vessel is tracked from its first report);
* otherwise once it has ``min_reports`` reports: until then its reports are "held": they
  go to the MMSI's last tracked vessel, whose filter judges them (as without the split:
  usually rejected as implausible jumps); from its ``min_reports``-th report on it is
  tracked as the MMSI's next vessel (``sub`` 1, 2, ...). Reports of a trajectory that
  never gets there stay held (the batch calls them jumps).

A vessel is tracked under its key :func:`vessel_key` (the MMSI itself for ``sub`` 0).
Flags of a report are decided when it is tracked as its own vessel's (for a held report:
when its trajectory becomes a vessel), from what is known then:

* ``identity_conflict``: its vessel and another vessel of the MMSI overlap in time (the
  spans of their reports known when the report is tracked);
* ``jump``: it started a new trajectory while another was alive, or out of reach, and is
  not in conflict; a held report is shown at once as a ``jump`` of the vessel it goes to;
* ``gap``: it ends a silence of its vessel longer than
  :func:`~seatrack.fusion.anomalies.gap_limits` of the vessel's report intervals so far
  (the last ``HISTORY`` reports, this one included).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import field
from typing import Any
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from seatrack.fusion.anomalies import DEFAULT_GAP_FACTOR
from seatrack.fusion.anomalies import DEFAULT_MIN_GAP_S
from seatrack.fusion.anomalies import RecentIntervals
from seatrack.fusion.anomalies import SplitConfig
from seatrack.fusion.anomalies import Trajectories
from seatrack.fusion.anomalies import follow_report
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import geodetic_to_enu
from seatrack.geometry import velocity_from_course

FloatArray = NDArray[np.float64]

__all__ = ["HISTORY", "Flags", "LiveIdentities", "split_key", "vessel_key"]

#: report times kept per vessel for its gap limit
HISTORY = 64
#: the key of an MMSI's vessel ``sub`` is ``mmsi + sub * SUB_STEP`` (MMSIs have 9 digits)
SUB_STEP = 1_000_000_000


def vessel_key(mmsi: int, sub: int) -> int:
    """The tracking key of the MMSI's vessel ``sub`` (the MMSI itself for 0)."""
    return int(mmsi) + int(sub) * SUB_STEP


def split_key(key: int) -> tuple[int, int]:
    """``(mmsi, sub)`` of a tracking key (:func:`vessel_key`)."""
    return int(key) % SUB_STEP, int(key) // SUB_STEP


class Flags(NamedTuple):
    """The anomaly flags of a vessel's last report (see the module docstring)."""

    gap: bool = False
    jump: bool = False
    identity_conflict: bool = False


@dataclass
class _Trajectory:
    sub: int = -1  # vessel number within the MMSI (-1: not a vessel yet)
    first_t: float = math.inf
    last_t: float = -math.inf
    moved: list[bool] = field(default_factory=list)  # per held report
    held_rows: list[tuple[float, ...]] = field(default_factory=list)  # held reports
    recent: RecentIntervals = field(default_factory=lambda: RecentIntervals(HISTORY))


@dataclass
class _Mmsi:
    follow: Trajectories = field(default_factory=Trajectories.empty)
    traj: list[_Trajectory] = field(default_factory=list)
    vessels: int = 0
    latest_t: float = -math.inf
    last_vessel: int = -1  # trajectory label last tracked
    origin: tuple[float, float] | None = None  # plane origin without a radar (deg)


class LiveIdentities:
    """The causal split and flags (module docstring).

    Parameters
    ----------
    origin_deg : (lat, lon) of the plane (the radar), or None for a plane per MMSI.
    gap_factor, min_gap_s : the gap limit's keys (``[fusion]`` of ``radar.toml``).
    config : the splitter's keys.
    record : :meth:`record` from the start.
    """

    def __init__(self, origin_deg: tuple[float, float] | None = None,
                 gap_factor: float = DEFAULT_GAP_FACTOR, min_gap_s: float = DEFAULT_MIN_GAP_S,
                 config: SplitConfig | None = None,
                 record: bool = False) -> None:  # fmt: skip
        self.origin = origin_deg
        self.gap_factor, self.min_gap = gap_factor, min_gap_s
        self.cfg = config or SplitConfig()
        self.mmsis: dict[int, _Mmsi] = {}
        self.flags: dict[int, Flags] = {}  # vessel key -> flags of its last report
        self.changed: set[int] = set()  # vessel keys whose flags changed
        self.counts = {"gap": 0, "jump": 0, "identity_conflict": 0}  # reports flagged
        self.log: list[tuple[int, float, int, bool, bool, bool]] | None = None
        self.routed: list[tuple[int, float, int]] | None = None  # (mmsi, t, key) per report
        if record:
            self.record()

    def record(self) -> None:
        """Keep from now on every decided report's ``(mmsi, t, sub, gap, jump,
        conflict)`` in :attr:`log` (``sub`` -1: an untracked jump) and every report's
        ``(mmsi, t, key)`` in :attr:`routed` (for tests)."""
        self.log, self.routed = [], []

    def route(self, mmsi: NDArray[np.int64], rows: FloatArray) -> NDArray[np.int64]:
        """The tracking key of each position report (arrival order; ``rows`` (n, 5): time
        s, lat, lon deg, SOG kn, COG deg, NaN unknown)."""
        n = mmsi.size
        xy = self._plane(mmsi, rows[:, 1], rows[:, 2]).tolist()
        v = velocity_from_course(np.radians(rows[:, 4]), rows[:, 3] * KNOT_MPS).reshape(n, 2)
        vs = v.tolist()
        out_key = np.empty(n, np.int64)
        for i, (m, row) in enumerate(zip(mmsi.tolist(), rows.tolist(), strict=True)):
            st = self._mmsi(m)
            t = row[0]
            p = (xy[i][0], xy[i][1])
            if t < st.latest_t:  # out of order: to the vessel it is nearest, no flags
                out_key[i] = vessel_key(m, st.traj[self._nearest(st, p)].sub)
                continue
            st.latest_t = t
            lab, moved = follow_report(st.follow, t, p, (vs[i][0], vs[i][1]), self.cfg)
            if lab == len(st.traj):
                st.traj.append(_Trajectory())
            tr = st.traj[lab]
            tr.first_t, tr.last_t = min(tr.first_t, t), t
            if tr.sub < 0 and not st.vessels:  # the MMSI's first trajectory: a vessel
                tr.sub, st.vessels = 0, 1
            if tr.sub < 0 and len(tr.held_rows) + 1 >= self.cfg.min_reports:  # a vessel now
                tr.sub, st.vessels = st.vessels, st.vessels + 1
                for r, mv in zip(tr.held_rows, tr.moved, strict=True):  # flags decided now
                    self._track(m, st, lab, r[0], mv)
                tr.held_rows, tr.moved = [], []
            if tr.sub >= 0:
                out_key[i] = self._track(m, st, lab, t, moved)
                continue
            tr.held_rows.append(tuple(row))
            tr.moved.append(moved)
            out_key[i] = self._show_jump(m, st)
        if self.routed is not None:
            self.routed.extend(zip(mmsi.tolist(), rows[:, 0].tolist(), out_key.tolist(),
                                   strict=True))  # fmt: skip
        return out_key

    def finish(self) -> None:
        """Decide the reports still held (their trajectories never became vessels:
        jumps) -- at the end of a replay, for comparison with the batch flags."""
        for m, st in self.mmsis.items():
            for tr in st.traj:
                if tr.sub < 0 and tr.held_rows:
                    self._abandon(m, tr)

    # ---- helpers -------------------------------------------------------------------------
    def _mmsi(self, m: int) -> _Mmsi:
        """The state of MMSI ``m``, new if it has none."""
        st = self.mmsis.get(m)
        if st is None:
            st = self.mmsis[m] = _Mmsi()
        return st

    def _plane(self, mmsi: NDArray[np.int64], lat: FloatArray, lon: FloatArray) -> FloatArray:
        if self.origin is not None:
            enu = geodetic_to_enu(lat, lon, 0.0, *self.origin)
            return np.asarray(enu[..., :2]).reshape(-1, 2)
        origin = np.empty((mmsi.size, 2))
        for i, (m, la, lo) in enumerate(zip(mmsi.tolist(), lat.tolist(), lon.tolist(),
                                            strict=True)):  # fmt: skip
            st = self._mmsi(m)
            if st.origin is None:
                st.origin = (la, lo)
            origin[i] = st.origin
        enu = geodetic_to_enu(lat, lon, 0.0, origin[:, 0], origin[:, 1])
        return np.asarray(enu[..., :2]).reshape(-1, 2)

    def _nearest(self, st: _Mmsi, xy: tuple[float, float]) -> int:
        """The vessel trajectory whose last report is nearest ``xy`` (out-of-order use)."""
        f = st.follow
        cand = [j for j, tr in enumerate(st.traj) if tr.sub >= 0]
        return min(cand, key=lambda j: math.dist(xy, f.xy[j]))

    def _track(self, m: int, st: _Mmsi, lab: int, t: float, moved: bool) -> int:
        """Flag a report of a vessel trajectory; its vessel key."""
        tr = st.traj[lab]
        conflict = any(  # the spans known now overlap
            o is not tr and o.sub >= 0 and o.first_t < tr.last_t and tr.first_t < o.last_t
            for o in st.traj
        )
        rec = tr.recent
        prev = rec.times[-1] if rec.times else None
        rec.push(t)
        gap = prev is not None and t - prev > rec.limit(self.gap_factor, self.min_gap)
        jump = moved and not conflict
        key = vessel_key(m, tr.sub)
        self._flag(key, Flags(gap, jump, conflict))
        st.last_vessel = lab
        if self.log is not None:
            self.log.append((m, t, tr.sub, gap, jump, conflict))
        return key

    def _flag(self, key: int, f: Flags) -> None:
        if f.gap or f.jump or f.identity_conflict:
            c = self.counts
            c["gap"] += f.gap
            c["jump"] += f.jump
            c["identity_conflict"] += f.identity_conflict
        if self.flags.get(key) != f:
            self.flags[key] = f
            self.changed.add(key)

    def _show_jump(self, m: int, st: _Mmsi) -> int:
        """A held report: goes to the MMSI's last tracked vessel, shown as a jump."""
        key = vessel_key(m, st.traj[st.last_vessel].sub)
        f = self.flags.get(key, Flags())
        if not f.jump:
            self.flags[key] = Flags(f.gap, True, f.identity_conflict)
            self.changed.add(key)
        return key

    def resume(self, keys: list[int], t: FloatArray, lat: FloatArray, lon: FloatArray,
               sog_kn: FloatArray, cog_deg: FloatArray) -> None:  # fmt: skip
        """Start from vessels restored from a store: each key's trajectory continues from
        its last estimate (time s, position deg, speed kn, course deg); the reporting
        intervals and held reports before the restart are not known."""
        rows = np.stack([t, lat, lon, sog_kn, cog_deg], -1).reshape(-1, 5)
        mm = np.array([split_key(k)[0] for k in keys], np.int64)
        xy = [(a, b) for a, b in self._plane(mm, rows[:, 1], rows[:, 2]).tolist()]
        v = [(a, b) for a, b in velocity_from_course(
            np.radians(rows[:, 4]), rows[:, 3] * KNOT_MPS).reshape(-1, 2).tolist()]  # fmt: skip
        for i, key in enumerate(keys):
            m, sub = split_key(key)
            st = self._mmsi(m)
            f = st.follow
            f.t.append(float(t[i]))
            f.xy.append(xy[i])
            f.v.append(v[i])
            tr = _Trajectory(sub, float(t[i]), float(t[i]))
            tr.recent.push(float(t[i]))
            st.traj.append(tr)
            st.vessels = max(st.vessels, sub + 1)
            st.latest_t = max(st.latest_t, float(t[i]))
            if st.last_vessel < 0 or t[i] >= st.traj[st.last_vessel].last_t:
                st.last_vessel = len(st.traj) - 1

    def _abandon(self, m: int, tr: _Trajectory) -> None:
        """Held reports whose trajectory never became a vessel: jumps, not tracked."""
        self.counts["jump"] += len(tr.held_rows)
        if self.log is not None:
            self.log.extend((m, r[0], -1, False, True, False) for r in tr.held_rows)
        tr.held_rows, tr.moved = [], []

    def describe(self, key: int) -> dict[str, Any]:
        """The feature properties of a vessel key: ``sub`` and its flags."""
        f = self.flags.get(key, Flags())
        return {"sub": split_key(key)[1], "gap": f.gap, "jump": f.jump,
                "identity_conflict": f.identity_conflict}  # fmt: skip
