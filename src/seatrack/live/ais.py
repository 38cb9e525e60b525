"""Live AIS tracking: each vessel tracked one report at a time with the AIS tracker's model.

The filter is the causal forward filter of :mod:`seatrack.filters.ais` (coordinated-turn
EKF with the chi-square gate, the plausibility tests, manoeuvre inflation, SOG/COG update,
physical limits, stale-position and long-gap tests, re-initialisation after repeated
outliers), stepped report by report with the same compiled pieces as the batch kernel
(:func:`~seatrack.filters.ais.ct.ct_f_jac`, :func:`~seatrack.filters.ais.ct.update2`, ...).
Its configuration is :func:`causal_config`: the batch tracker with
``smooth=False, revisit_passes=0, estimate_noise=False, refine=False`` (every decision made
from the past only, the report noise ``sigma_pos_m``); on the same reports the live states
equal :func:`seatrack.filters.ais.track_reports` with that configuration (tested).

Ordering. Each vessel keeps the reports of its last ``window_s`` seconds (message time)
with the filter state before each. A report at or after the vessel's latest time is
filtered at once; an earlier one within the window is inserted in time order and the
vessel re-run from the state before it (the picture then equals the one of the reports
in time order); an older one is ``late`` and not used (so is an earlier one right after
a restart from the store, whose windows start empty). Each vessel's tangent plane is
centred on its first report (as the batch tracker's, in time order).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from dataclasses import field
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais import AisTrackerConfig
from seatrack.filters.ais import AisTracks
from seatrack.filters.ais import OutlierKind
from seatrack.filters.ais import TrackStates
from seatrack.filters.ais.ct import constrain
from seatrack.filters.ais.ct import ct_f_jac
from seatrack.filters.ais.ct import ct_q
from seatrack.filters.ais.ct import sogcog
from seatrack.filters.ais.ct import update2
from seatrack.filters.ais.kernel import KernelParams
from seatrack.filters.ais.kernel import kernel_params
from seatrack.filters.ais.smoother import derived_std
from seatrack.filters.ais.tracks import ReportPlanes
from seatrack.filters.ais.tracks import tracks_from_states
from seatrack.geometry import KNOT_MPS
from seatrack.geometry import geodetic_to_enu
from seatrack.geometry import north_convergence
from seatrack.kalman import predict_core
from seatrack.kalman import update_core
from seatrack.kalman import wrap_angle

FloatArray = NDArray[np.float64]
NX = 5

__all__ = ["AisReport", "LiveAis", "VesselFilter", "causal_config", "plane_reports"]


def causal_config(base: AisTrackerConfig | None = None) -> AisTrackerConfig:
    """The AIS tracker configuration whose output is causal (each estimate from the past
    reports only): ``base`` without smoothing, revisit passes, noise estimate and
    refinement pass."""
    return replace(
        base or AisTrackerConfig(), smooth=False, revisit_passes=0, estimate_noise=False,
        refine=False,
    )  # fmt: skip


@dataclass
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


@dataclass
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


class _Scratch:
    """Work arrays shared by all vessels (one process, one thread)."""

    def __init__(self) -> None:
        self.fx, self.F, self.Q = np.empty(NX), np.empty((NX, NX)), np.empty((NX, NX))
        self.xo, self.Po, self.Pi = np.empty(NX), np.empty((NX, NX)), np.empty((NX, NX))
        self.H = np.zeros((2, NX))
        self.H[0, 0] = self.H[1, 1] = 1.0
        self.R, self.y, self.K = np.zeros((2, 2)), np.empty(2), np.empty((NX, 2))
        self.h2, self.H2, self.y2 = np.empty(2), np.zeros((2, NX)), np.empty(2)
        self.R2, self.K2 = np.zeros((2, 2)), np.empty((NX, 2))
        self.xv, self.Pv = np.empty(NX), np.empty((NX, NX))
        self.H1, self.R1, self.y1 = np.zeros((1, NX)), np.zeros((1, 1)), np.empty(1)
        self.S1, self.K1 = np.empty((1, 1)), np.empty((NX, 1))
        self.std = np.empty(NX)


_SCRATCH = _Scratch()


@dataclass
class _State:
    init: bool = False
    segment: int = 0
    t_state: float = 0.0
    last_t: float = 0.0
    last_x: float = 0.0
    last_y: float = 0.0
    prev_t: float = math.nan
    prev_x: float = 0.0
    prev_y: float = 0.0
    run_t: float = 0.0
    n_out: int = 0
    sog_t: float = -math.inf
    sog_last: float = 0.0
    x: FloatArray = field(default_factory=lambda: np.zeros(NX))
    P: FloatArray = field(default_factory=lambda: np.zeros((NX, NX)))

    def copy(self) -> _State:
        new = object.__new__(_State)  # a plain attribute copy: 10x faster than replace()
        new.__dict__.update(self.__dict__)
        new.x, new.P = self.x.copy(), self.P.copy()
        return new

    def numbers(self) -> list[float]:
        """The state as numbers (the store's ``filter`` column)."""
        head = [float(getattr(self, f)) for f in _SCALARS]
        return head + self.x.tolist() + self.P.ravel().tolist()

    @classmethod
    def from_numbers(cls, v: list[float]) -> _State:
        n = len(_SCALARS)
        kw: dict[str, Any] = {f: v[k] for k, f in enumerate(_SCALARS)}
        kw["init"] = bool(kw["init"])
        kw["segment"], kw["n_out"] = int(kw["segment"]), int(kw["n_out"])
        x = np.array(v[n : n + NX])
        P = np.array(v[n + NX : n + NX + NX * NX]).reshape(NX, NX)
        return cls(**kw, x=x, P=P)


_SCALARS = (
    "init", "segment", "t_state", "last_t", "last_x", "last_y", "prev_t", "prev_x", "prev_y",
    "run_t", "n_out", "sog_t", "sog_last",
)  # fmt: skip


class VesselFilter:
    """The causal AIS filter of one vessel, one report at a time (the batch kernel's
    per-report logic with ``smooth=False``, no withheld rows, no timestamp offsets and
    the report noise ``sigma_pos_m``)."""

    def __init__(self, par: KernelParams) -> None:
        self.par = par
        self.s = _State()

    def snapshot(self) -> _State:
        """A copy of the filter state (to re-run from)."""
        return self.s.copy()

    def restore(self, state: _State) -> None:
        """Continue from a :meth:`snapshot`."""
        self.s = state.copy()

    def _init_at(self, r: AisReport) -> None:
        p, s = self.par, self.s
        known = math.isfinite(r.v0x) and math.isfinite(r.v0y)
        vx, vy = (r.v0x, r.v0y) if known else (0.0, 0.0)
        sv = p.init_v_std_known if known else p.init_v_std
        s.x[:] = (r.x, r.y, vx, vy, 0.0)
        s.P[:] = 0.0
        s.P[0, 0] = s.P[1, 1] = p.sigma_pos * p.sigma_pos
        s.P[2, 2] = s.P[3, 3] = sv * sv
        s.P[4, 4] = p.init_w_std * p.init_w_std
        s.segment += 1
        s.n_out = 0
        s.last_t, s.last_x, s.last_y = r.t, r.x, r.y

    def _estimate(self, t: float, kind: int = 0, nis: float = math.nan) -> Estimate:
        derived_std(self.s.x, self.s.P, _SCRATCH.std)
        return Estimate(t, self.s.x.copy(), _SCRATCH.std.copy(), kind, self.s.segment, nis)

    def step(self, r: AisReport) -> Estimate | None:
        """Filter one report (times non-decreasing); None when the report gets no
        estimate (an implausible jump across a long gap)."""
        p, s, w = self.par, self.s, _SCRATCH
        noise_dist = p.nsig * math.sqrt(2.0) * p.sigma_pos
        if r.sog == r.sog:
            s.sog_t, s.sog_last = r.t, r.sog
        stale = False
        if s.prev_t == s.prev_t and r.x == s.prev_x and r.y == s.prev_y:
            if s.init and r.t > s.run_t:
                spd = 0.0
                if r.sog == r.sog:
                    spd = r.sog
                elif r.t - s.sog_t <= p.max_gap:
                    spd = s.sog_last
                else:
                    sv = math.sqrt(0.5 * (s.P[2, 2] + s.P[3, 3]))
                    spd = math.hypot(s.x[2], s.x[3]) - p.nsig * sv
                stale = spd * (r.t - s.run_t) > noise_dist
        else:
            s.run_t = r.t
        s.prev_t, s.prev_x, s.prev_y = r.t, r.x, r.y
        if s.init and r.t - s.t_state > p.max_gap:
            v_impl = (math.hypot(r.x - s.last_x, r.y - s.last_y) - noise_dist) / (
                r.t - s.last_t + p.tres
            )
            if v_impl > p.vmax and s.n_out + 1 < p.reinit_after:
                s.n_out += 1
                return None
            s.init = False
        if not s.init:
            s.init = True
            self._init_at(r)
            s.t_state = r.t
            return self._estimate(r.t)
        dt = r.t - s.t_state
        ct_f_jac(s.x, dt, w.fx, w.F)
        ct_q(dt, p.q, p.q_w, w.Q)
        predict_core(s.x, s.P, w.F, w.Q, w.xo, w.Po)
        s.x[:] = w.fx
        s.P[:] = w.Po
        s.t_state = r.t
        if stale:
            return self._estimate(r.t, int(OutlierKind.STALE_POSITION))
        fx, Po = w.fx, w.Po
        R = w.R
        R[0, 0] = R[1, 1] = p.sigma_pos * p.sigma_pos
        R[0, 1] = R[1, 0] = 0.0
        w.y[0], w.y[1] = r.x - fx[0], r.y - fx[1]
        s00, s01, s11 = Po[0, 0] + R[0, 0], Po[0, 1], Po[1, 1] + R[1, 1]
        det = s00 * s11 - s01 * s01
        y0, y1 = w.y[0], w.y[1]
        d2 = (s11 * y0 * y0 - 2 * s01 * y0 * y1 + s00 * y1 * y1) / det
        if d2 > p.gate:
            v_impl = (math.hypot(r.x - s.last_x, r.y - s.last_y) - noise_dist) / (
                r.t - s.last_t + p.tres
            )
            tr = 0.5 * (s00 + s11)
            lam = tr + math.sqrt(max(tr * tr - det, 0.0))
            dev = math.hypot(y0, y1) - p.nsig * math.sqrt(lam)
            dte = r.t - s.last_t + p.tres
            a_impl = 2.0 * dev / (dte * dte)
            if v_impl > p.vmax or a_impl > p.amax:
                s.n_out += 1
                if s.n_out >= p.reinit_after:
                    self._init_at(r)
                    return self._estimate(r.t)
                return self._estimate(r.t, int(OutlierKind.IMPLAUSIBLE_JUMP), d2)
            np.multiply(Po, d2 / p.gate, out=w.Pi)
        else:
            w.Pi[:] = Po
        w.H[0, 2] = w.H[1, 3] = 0.0
        update2(fx, w.Pi, w.y, w.H, R, w.xo, w.Po, w.K)
        xo, Pu = w.xo, w.Po
        if p.use_vel and r.sog == r.sog and r.sog > p.vmin:
            sogcog(xo, w.h2, w.H2)
            if w.h2[0] > p.vmin:
                nis2 = math.inf
                if r.cog == r.cog:
                    w.y2[0] = r.sog - w.h2[0]
                    w.y2[1] = wrap_angle(r.cog - w.h2[1])
                    w.R2[0, 0] = p.sigma_sog * p.sigma_sog
                    w.R2[1, 1] = p.sigma_cog * p.sigma_cog
                    nis2 = update2(xo, Pu, w.y2, w.H2, w.R2, w.xv, w.Pv, w.K2)
                elif p.use_sog_alone:
                    w.y1[0] = r.sog - w.h2[0]
                    w.H1[0, :] = w.H2[0, :]
                    w.R1[0, 0] = p.sigma_sog * p.sigma_sog
                    nis2, _ = update_core(xo, Pu, w.y1, w.H1, w.R1, w.xv, w.Pv, w.S1, w.K1)
                if nis2 <= p.gate:
                    xo[:] = w.xv
                    Pu[:] = w.Pv
        constrain(xo, p.vmax, p.amax, p.w_max)
        s.n_out = 0
        s.x[:] = xo
        s.P[:] = Pu
        s.last_t, s.last_x, s.last_y = r.t, r.x, r.y
        return self._estimate(r.t, 0, d2)


@dataclass
class _Entry:
    report: AisReport
    before: _State


class _Vessel:
    """One vessel: its filter, plane origin, recent reports (for re-runs) and output."""

    def __init__(self, mmsi: int, lat0: float, lon0: float, par: KernelParams) -> None:
        self.mmsi = mmsi
        self.lat0, self.lon0 = lat0, lon0
        self.filter = VesselFilter(par)
        self.history: list[_Entry] = []
        self.times: list[float] = []
        self.estimate: Estimate | None = None
        self.report: AisReport | None = None
        self.name = ""
        self.t_restored = -math.inf  # latest report time before a restart

    @property
    def last_t(self) -> float:
        return self.times[-1] if self.times else self.t_restored

    def run(self, r: AisReport, emitted: list | None) -> Estimate | None:
        self.history.append(_Entry(r, self.filter.snapshot()))
        self.times.append(r.t)
        est = self.filter.step(r)
        if est is not None:
            self.estimate, self.report = est, r
            if emitted is not None:
                emitted.append((self, est))
        return est

    def prune(self, window_s: float) -> None:
        cut = bisect.bisect_left(self.times, self.last_t - window_s)
        if cut:
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
        lat0, lon0 = np.empty(n), np.empty(n)
        for k in range(n):
            v = self.vessels.get(int(mmsi[k]))
            if v is None:
                v = self.vessels[int(mmsi[k])] = _Vessel(int(mmsi[k]), lat[k], lon[k], self.par)
            lat0[k], lon0[k] = v.lat0, v.lon0
        en, v0, sog, cog = plane_reports(lat, lon, lat0, lon0, sog_kn, cog_deg)
        used = np.ones(n, dtype=bool)
        for k in range(n):
            rep = AisReport(
                int(mmsi[k]), float(t[k]), float(en[k, 0]), float(en[k, 1]), float(v0[k, 0]),
                float(v0[k, 1]), float(sog[k]), float(cog[k]), float(lat[k]), float(lon[k]),
                0.0 if perf_s is None else float(perf_s[k]),
            )  # fmt: skip
            used[k] = self.add_report(rep)
        return used

    def add_report(self, r: AisReport) -> bool:
        """One report in its vessel's plane; False if late (not used)."""
        v = self.vessels[r.mmsi]
        if r.t >= v.last_t:
            v.run(r, self.emitted)
        elif r.t >= v.last_t - self.window_s and v.times:
            k = bisect.bisect_right(v.times, r.t)
            redo = v.history[k:]
            v.filter.restore(redo[0].before)
            del v.history[k:]
            del v.times[k:]
            for e in [_Entry(r, redo[0].before), *redo]:
                v.run(e.report, self.emitted)
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
