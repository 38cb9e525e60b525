"""Live AIS tracking: each vessel tracked one report at a time with the AIS tracker's model.

The filter is the causal forward filter of :mod:`seatrack.filters.ais` (coordinated-turn
EKF with the chi-square gate, the plausibility tests, manoeuvre inflation, SOG/COG update,
physical limits, stale-position and long-gap tests, re-initialisation after repeated
outliers), stepped report by report with the same compiled pieces as the batch kernel
(:func:`~seatrack.filters.ais.ct.ct_f_jac`, :func:`~seatrack.filters.ais.ct.update2`, ...),
compiled as one call per report (:func:`seatrack.live.ais_step.causal_step`).
Its configuration is :func:`causal_config`: the batch tracker with
``smooth=False, revisit_passes=0, estimate_noise=False, refine=False`` (every decision made
from the past only, the report noise ``sigma_pos_m``); on the same reports the live states
equal :func:`seatrack.filters.ais.track_reports` with that configuration (tested).

Ordering. Each vessel keeps the reports of its last ``window_s`` seconds (message time)
with the filter state before one report in :data:`SNAP_EVERY` (and a few older reports
back to such a state). A report at or after the vessel's latest time is filtered at once;
an earlier one within the window is inserted in time order and the vessel re-run from the
latest state kept before it (the picture then equals the one of the reports in time
order); an older one is ``late`` and not used (so is an earlier one right after
a restart from the store, whose windows start empty). Each vessel's tangent plane is
centred on its first report (as the batch tracker's, in time order).
"""

from __future__ import annotations

import bisect
import functools
import math
import struct
from array import array
from dataclasses import dataclass
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais import AisTrackerConfig
from seatrack.filters.ais import AisTracks
from seatrack.filters.ais import TrackStates
from seatrack.filters.ais.kernel import KernelParams
from seatrack.filters.ais.kernel import kernel_params
from seatrack.filters.ais.tracks import ReportPlanes
from seatrack.filters.ais.tracks import tracks_from_states
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import geodetic_to_enu
from seatrack.geometry import north_convergence
from seatrack.live.ais_step import NO_ESTIMATE
from seatrack.live.ais_step import NX
from seatrack.live.ais_step import SCALARS
from seatrack.live.ais_step import causal_step
from seatrack.live.ais_step import param_array

FloatArray = NDArray[np.float64]
_SEGMENT = SCALARS.index("segment")
_NS = len(SCALARS)
_param_array = functools.lru_cache(maxsize=8)(param_array)  # one array per configuration

__all__ = [
    "SNAP_EVERY", "AisReport", "LiveAis", "VesselFilter", "causal_config", "plane_reports",
]  # fmt: skip


def causal_config(base: AisTrackerConfig | None = None) -> AisTrackerConfig:
    """The AIS tracker configuration whose output is causal (each estimate from the past
    reports only): ``base`` without smoothing, revisit passes, noise estimate and
    refinement pass."""
    return replace(
        base or AisTrackerConfig(), smooth=False, revisit_passes=0, estimate_noise=False,
        refine=False,
    )  # fmt: skip


@dataclass(slots=True)
class AisReport:
    """One decoded position report in its vessel's plane: time (Unix s), East/North (m),
    the SOG/COG velocity ``v0`` (m/s, plane axes; NaN unknown), SOG (m/s) and COG (rad,
    plane North; NaN unknown), and its WGS84 position and reported values for the store."""

    mmsi: int
    t: float
    x: float
    y: float
    v0x: float
    v0y: float
    sog: float
    cog: float
    lat: float
    lon: float
    perf_s: float = 0.0


@dataclass(slots=True)
class Estimate:
    """The filter's output for one report: state ``[x, y, vx, vy, w]`` (plane, SI), its
    1-sigma ``std`` (x, y, speed, course, turn rate), the outlier kind, the segment number
    (1, 2, ... within the vessel) and the NIS (NaN for a segment's first report)."""

    t: float
    state: FloatArray
    std: FloatArray
    kind: int
    segment: int
    nis: float

    def numbers(self) -> list[float]:
        """The estimate as numbers (the store's ``estimate`` column)."""
        return [self.t, *self.state.tolist(), *self.std.tolist(), self.kind, self.segment,
                self.nis]  # fmt: skip

    @classmethod
    def from_numbers(cls, v: list[float]) -> Estimate:
        a = np.asarray(v, dtype=float)
        return cls(float(a[0]), a[1:6].copy(), a[6:11].copy(), int(a[11]), int(a[12]), float(a[13]))


class _State:
    """A vessel filter's state in one float64 array ``a`` (the store's ``filter`` column):
    the scalars of :data:`~seatrack.live.ais_step.SCALARS` (view ``st``), the state ``x``
    and its covariance ``P`` (views)."""

    __slots__ = ("P", "a", "st", "x")

    def __init__(self, a: FloatArray | None = None) -> None:
        if a is None:
            a = np.zeros(_NS + NX + NX * NX)
            a[SCALARS.index("prev_t")] = math.nan
            a[SCALARS.index("sog_t")] = -math.inf
        self.a = a
        self.st = a[:_NS]
        self.x = a[_NS : _NS + NX]
        self.P = a[_NS + NX :].reshape(NX, NX)

    def numbers(self) -> list[float]:
        """The state as numbers (the store's ``filter`` column)."""
        return self.a.tolist()

    @classmethod
    def from_numbers(cls, v: list[float]) -> _State:
        return cls(np.array(v[: _NS + NX + NX * NX], dtype=float))


class VesselFilter:
    """The causal AIS filter of one vessel, one report at a time (the batch kernel's
    per-report logic with ``smooth=False``, no withheld rows, no timestamp offsets and
    the report noise ``sigma_pos_m``; compiled: :func:`~seatrack.live.ais_step.causal_step`)."""

    def __init__(self, par: KernelParams, state: FloatArray | None = None) -> None:
        self.par = par
        self.p = _param_array(par)
        self.s = _State(state)

    def snapshot(self) -> FloatArray:
        """A copy of the filter state (to re-run from), as one array."""
        return self.s.a.copy()

    def restore(self, state: FloatArray) -> None:
        """Continue from a :meth:`snapshot`."""
        self.s = _State(state.copy())

    def step(self, r: AisReport) -> Estimate | None:
        """Filter one report (times non-decreasing); None when the report gets no
        estimate (an implausible jump across a long gap)."""
        s = self.s
        std = np.empty(NX)
        status, kind, nis = causal_step(
            self.p, s.st, s.x, s.P, r.t, r.x, r.y, r.v0x, r.v0y, r.sog, r.cog, std
        )
        if status == NO_ESTIMATE:
            return None
        return Estimate(r.t, s.x.copy(), std, kind, int(s.st[_SEGMENT]), nis)


_NF = _NS + NX + NX * NX  # numbers of a filter state
_REPORT = ("t", "x", "y", "v0x", "v0y", "sog", "cog", "lat", "lon", "perf_s")
_NR = len(_REPORT)
#: a vessel's history keeps the filter state before one report in this many (and always
#: before its first entry); a re-run starts from the latest kept state at or before the
#: report inserted, re-filtering the reports in between as they were
SNAP_EVERY = 4


_PACK = struct.Struct(f"<{_NR}d")  # a report's numbers in an entry


def _entry(r: AisReport, before: FloatArray | None) -> bytes:
    """A history entry as bytes: the report's numbers (float64), after the filter state
    before the report when ``before`` is given (memory: one small object per report, a
    state in one entry of :data:`SNAP_EVERY`)."""
    rep = _PACK.pack(r.t, r.x, r.y, r.v0x, r.v0y, r.sog, r.cog, r.lat, r.lon, r.perf_s)
    return rep if before is None else before.tobytes() + rep


def _entry_state(e: bytes) -> FloatArray:
    """The filter state of a history entry that holds one."""
    return np.frombuffer(e, np.float64, _NF)


def _entry_report(mmsi: int, e: bytes) -> AisReport:
    """The report of a history entry."""
    return AisReport(mmsi, *_PACK.unpack_from(e, len(e) - _PACK.size))


class _Vessel:
    """One vessel: its filter, plane origin, recent reports (for re-runs) and output."""

    __slots__ = ("estimate", "filter", "history", "lat0", "lon0", "mmsi", "name", "report",
                 "since_state", "t_restored", "times")  # fmt: skip

    def __init__(
        self, mmsi: int, lat0: float, lon0: float, par: KernelParams,
        state: FloatArray | None = None,
    ) -> None:  # fmt: skip
        self.mmsi = mmsi
        self.lat0, self.lon0 = lat0, lon0
        self.filter = VesselFilter(par, state)
        self.history: list[bytes] = []  # _entry
        self.times = array("d")  # report times (float64: nothing for the GC to follow)
        self.since_state = 0  # entries after the latest one holding a state
        self.estimate: Estimate | None = None
        self.report: AisReport | None = None
        self.name = ""
        self.t_restored = -math.inf  # latest report time before a restart

    @property
    def last_t(self) -> float:
        return self.times[-1] if self.times else self.t_restored

    def run(self, r: AisReport, emitted: list | None) -> Estimate | None:
        if not self.history or self.since_state >= SNAP_EVERY - 1:
            self.history.append(_entry(r, self.filter.s.a))
            self.since_state = 0
        else:
            self.history.append(_entry(r, None))
            self.since_state += 1
        self.times.append(r.t)
        est = self.filter.step(r)
        if est is not None:
            self.estimate, self.report = est, r
            if emitted is not None:
                emitted.append((self, est))
        return est

    def with_state(self, k: int) -> int:
        """The latest entry at or before ``k`` that holds a filter state."""
        while len(self.history[k]) == _PACK.size:
            k -= 1
        return k

    def rerun(self, k: int, r: AisReport, emitted: list | None) -> None:
        """Insert ``r`` before entry ``k`` and filter again from the state kept at or
        before it (the entries before ``k`` silently: their estimates were emitted)."""
        j = self.with_state(k)
        again = [_entry_report(self.mmsi, e) for e in self.history[j:k]]
        redo = [r] + [_entry_report(self.mmsi, e) for e in self.history[k:]]
        self.filter.restore(_entry_state(self.history[j]))
        del self.history[j:]
        del self.times[j:]
        for e in again:
            self.run(e, None)
        for e in redo:
            self.run(e, emitted)

    def prune(self, window_s: float) -> None:
        """Forget the reports older than ``window_s`` before the latest, except those
        after the latest kept state before the cut."""
        cut = bisect.bisect_left(self.times, self.last_t - window_s)
        if cut:
            cut = self.with_state(min(cut, len(self.history) - 1))
            del self.history[:cut]
            del self.times[:cut]


def plane_reports(
    lat: FloatArray, lon: FloatArray, lat0: FloatArray, lon0: FloatArray,
    sog_kn: FloatArray, cog_deg: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:  # fmt: skip
    """Reports in their vessels' planes (origins ``lat0``, ``lon0``, deg): East/North (m,
    (N, 2)), the SOG/COG velocity (m/s, (N, 2)), SOG (m/s) and COG referred to the plane's
    North (rad) -- the conversions of :func:`seatrack.filters.ais.tracks.prepare_reports`."""
    en = geodetic_to_enu(lat, lon, 0.0, lat0, lon0)[..., :2]
    gam = np.where(*(lambda g: (np.isfinite(g), g, 0.0))(north_convergence(lat, lon, lat0, lon0)))
    sog = sog_kn * KNOT_MPS
    cog = np.radians(cog_deg) + gam
    v0 = np.stack([sog * np.sin(cog), sog * np.cos(cog)], axis=-1)
    return en, v0, sog, cog


class LiveAis:
    """All vessels of a live AIS stream (see the module docstring).

    Parameters
    ----------
    config : AisTrackerConfig
        Made causal by :func:`causal_config`.
    window_s : float
        The out-of-order window, s of message time.
    """

    def __init__(self, config: AisTrackerConfig | None = None, window_s: float = 10.0) -> None:
        self.config = causal_config(config)
        self.par = kernel_params(self.config)
        self.window_s = float(window_s)
        self.vessels: dict[int, _Vessel] = {}
        self.changed: set[int] = set()  # since the picture's last refresh
        self.dirty: set[int] = set()  # since the store's last commit
        self.emitted: list | None = None  # (vessel, estimate) of every step, when a list

    def add(
        self, mmsi: NDArray[np.int64], t: FloatArray, lat: FloatArray, lon: FloatArray,
        sog_kn: FloatArray, cog_deg: FloatArray, perf_s: FloatArray | None = None,
    ) -> NDArray[np.bool_]:  # fmt: skip
        """Add position reports (arrival order; values checked by the caller); returns
        which were used (False = late)."""
        n = len(mmsi)
        mm, la, lo = mmsi.tolist(), lat.tolist(), lon.tolist()  # Python numbers: faster
        lat0, lon0 = np.empty(n), np.empty(n)
        vessels = self.vessels
        for k in range(n):
            v = vessels.get(mm[k])
            if v is None:
                v = vessels[mm[k]] = _Vessel(mm[k], la[k], lo[k], self.par)
            lat0[k], lon0[k] = v.lat0, v.lon0
        en, v0, sog, cog = plane_reports(lat, lon, lat0, lon0, sog_kn, cog_deg)
        cols = zip(
            mm, t.tolist(), en[:, 0].tolist(), en[:, 1].tolist(), v0[:, 0].tolist(),
            v0[:, 1].tolist(), sog.tolist(), cog.tolist(), la, lo,
            [0.0] * n if perf_s is None else perf_s.tolist(), strict=True,
        )  # fmt: skip
        used = np.array([self.add_report(AisReport(*c)) for c in cols], dtype=bool)
        return used

    def add_report(self, r: AisReport) -> bool:
        """One report in its vessel's plane; False if late (not used)."""
        v = self.vessels[r.mmsi]
        if r.t >= v.last_t:
            v.run(r, self.emitted)
        elif r.t >= v.last_t - self.window_s and v.times:
            v.rerun(bisect.bisect_right(v.times, r.t), r, self.emitted)
        else:
            return False
        v.prune(self.window_s)
        self.changed.add(r.mmsi)
        self.dirty.add(r.mmsi)
        return True

    def tracks(self, mmsis: list[int] | None = None) -> tuple[list[int], AisTracks, FloatArray]:
        """The current estimate of the vessels ``mmsis`` (default: all with one) as
        :class:`~seatrack.filters.ais.AisTracks` (WGS84, true-North courses) and their
        times (Unix s)."""
        ids = [m for m in (self.vessels if mmsis is None else mmsis)
               if self.vessels[m].estimate is not None]  # fmt: skip
        ests = [self.vessels[m].estimate for m in ids]
        n = len(ids)
        state, std = np.full((n, NX), np.nan), np.full((n, NX), np.nan)
        kind, seg, nis, t = np.zeros(n, np.int8), np.zeros(n, np.int64), np.zeros(n), np.zeros(n)
        for k, e in enumerate(ests):
            assert e is not None
            state[k], std[k], kind[k], seg[k], nis[k], t[k] = (
                e.state, e.std, e.kind, e.segment, e.nis, e.t,
            )  # fmt: skip
        planes = ReportPlanes(
            n, np.arange(n), np.array([self.vessels[m].lat0 for m in ids]),
            np.array([self.vessels[m].lon0 for m in ids]),
        )  # fmt: skip
        st = TrackStates(state, std, kind > 0, kind, seg, nis, np.zeros(n))
        return ids, tracks_from_states(planes, st), t

    def state_row(self, mmsi: int) -> tuple:
        """``(mmsi, lat0, lon0, name, t_last, filter numbers, estimate numbers | None)``."""
        v = self.vessels[mmsi]
        est = None if v.estimate is None else v.estimate.numbers()
        return (mmsi, v.lat0, v.lon0, v.name, v.last_t, v.filter.s.numbers(), est)

    def restore_vessels(
        self, mmsi: NDArray[np.int64], lat0: FloatArray, lon0: FloatArray, names: list[str],
        t_last: FloatArray, filters: FloatArray, estimates: FloatArray,
    ) -> None:  # fmt: skip
        """Vessels from the columns of :meth:`state_row` (a restart), ``filters`` and
        ``estimates`` as 2-D arrays (a row of NaN: no estimate); as
        :meth:`restore_vessel` on each row, with the states kept as rows of one array."""
        filters = np.array(filters, dtype=float, order="C")[:, :_NF]
        estimates = np.array(estimates, dtype=float, order="C")
        has_est = ~np.isnan(estimates[:, 0]) if estimates.shape[1] else np.zeros(len(mmsi), bool)
        rows = zip(mmsi.tolist(), lat0.tolist(), lon0.tolist(), names, t_last.tolist(),
                   filters, estimates, has_est.tolist(), strict=True)  # fmt: skip
        for m, la, lo, name, t, f, e, known in rows:
            v = self.vessels[m] = _Vessel(m, la, lo, self.par, f)
            v.name = name or ""
            v.t_restored = t
            if known:
                v.estimate = Estimate(e[0], e[1:6], e[6:11], int(e[11]), int(e[12]), e[13])
                self.changed.add(m)

    def restore_vessel(self, row: tuple) -> None:
        """A vessel from :meth:`state_row` (a restart): its filter goes on from that state;
        its out-of-order window starts empty."""
        mmsi, lat0, lon0, name, t_last, numbers, est = row
        v = self.vessels[int(mmsi)] = _Vessel(int(mmsi), lat0, lon0, self.par)
        v.name = name or ""
        v.t_restored = float(t_last)
        v.filter.s = _State.from_numbers(list(numbers))
        v.estimate = None if est is None else Estimate.from_numbers(list(est))
        if v.estimate is not None:
            self.changed.add(int(mmsi))
