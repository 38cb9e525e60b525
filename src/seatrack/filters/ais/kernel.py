"""The compiled kernel of the AIS tracker: one forward filter + RTS pass over many vessels.

Inputs, parameters and outputs are named tuples (:class:`KernelInputs`,
:class:`KernelParams`, :class:`KernelOutputs`), passed to the compiled code as they are. Rows
are sorted by (vessel, time); vessel ``v`` owns rows ``starts[v]:starts[v + 1]``. Vessels are
independent: they are split into chunks of about equal row counts that run on all cores
(``numba.prange``); each chunk has its own scratch arrays, so the result does not depend on
the number of threads (segment ids are the row index of the segment's first report).

``_track_flat`` is one long compiled loop on purpose: split into helpers that take the named
tuples (``inline="always"`` or not) the same kernel ran 1.7-2x slower (200-220k against
300-370k reports/s on one thread, measured back to back), the cost of passing tuples of
arrays at every call; the named tuples are unpacked once per chunk instead.

The per-report logic (see :mod:`seatrack.filters.ais` for the method): stale-position test,
long-gap split or gap outlier, segment start, CT prediction, chi-square gate, plausibility
test (implied speed from the last accepted report, implied acceleration from the distance to
the prediction), covariance inflation for a plausible manoeuvre, position update with the
report's timestamp offset, SOG/COG update, physical limits; the RTS smoother closes each
segment.
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple

import numba
import numpy as np
from numba import njit
from numba import prange
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.filters.ais.config import NX
from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.ct import constrain
from seatrack.filters.ais.ct import constrain_rows
from seatrack.filters.ais.ct import ct_f_jac
from seatrack.filters.ais.ct import ct_q
from seatrack.filters.ais.ct import sogcog
from seatrack.filters.ais.ct import update2
from seatrack.filters.ais.smoother import derived_std
from seatrack.filters.ais.smoother import smooth_segment
from seatrack.geometry import KNOT_MPS
from seatrack.kalman import predict_core
from seatrack.kalman import update_core
from seatrack.kalman import wrap_angle

FloatArray = NDArray[np.float64]

__all__ = [
    "OutlierKind",
    "Force",
    "OUTLIER_KINDS",
    "KernelInputs",
    "KernelParams",
    "KernelOutputs",
    "kernel_params",
    "run_kernel",
    "vessel_chunks",
    "vessel_layout",
    "thread_chunks",
    "vessel_index",
    "take_rows",
    "largest_vessel",
    "vessel_rows",
    "vessel_starts",
]


class OutlierKind(IntEnum):
    """Why a report was flagged as an outlier (``TrackStates.outlier_kind``)."""

    NONE = 0
    #: outside the gate and physically implausible
    IMPLAUSIBLE_JUMP = 1
    #: the previous position repeated while the vessel moves
    STALE_POSITION = 2
    #: implausible jump across a gap longer than ``max_gap_s`` (no estimate)
    IMPLAUSIBLE_AFTER_GAP = 3


#: outlier kind -> the reason written to TRACKS.csv
OUTLIER_KINDS = {
    int(OutlierKind.IMPLAUSIBLE_JUMP): "implausible jump",
    int(OutlierKind.STALE_POSITION): "stale position",
    int(OutlierKind.IMPLAUSIBLE_AFTER_GAP): "implausible after gap",
}


class Force(IntEnum):
    """A decision imposed on the kernel for a report (revisit and refinement passes)."""

    #: the kernel decides
    FREE = 0
    #: use the report whatever the gate and plausibility tests say
    ACCEPT = 1
    #: reject the report as an implausible jump
    REJECT = 2


class KernelInputs(NamedTuple):
    """Rows sorted by (vessel, time). ``starts`` (V + 1,) vessel boundaries; ``t`` (N,) s;
    ``z`` (N, 2) positions (m); ``use`` (N,) bool (False = withheld); ``force`` (N,) int8
    :class:`Force`; ``v0`` (N, 2) SOG/COG velocity (m/s, zero where unknown) and ``known``
    (N,) bool; ``sog`` (N,) m/s and ``cog`` (N,) rad (NaN unknown); ``sig`` (N, 2) report
    noise ``(sigma_pos m, sigma_time s)``; ``toff`` (N,) timestamp offsets (s)."""

    starts: NDArray[np.int64]
    t: FloatArray
    z: FloatArray
    use: NDArray[np.bool_]
    force: NDArray[np.int8]
    v0: FloatArray
    known: NDArray[np.bool_]
    sog: FloatArray
    cog: FloatArray
    sig: FloatArray
    toff: FloatArray


class KernelParams(NamedTuple):
    """Configuration in the kernel's units (SI, radians); see :class:`AisTrackerConfig`."""

    use_vel: bool
    use_sog_alone: bool
    sigma_sog: float
    sigma_cog: float
    vmin: float
    sigma_pos: float
    q: float
    q_w: float
    gate: float
    vmax: float
    amax: float
    w_max: float
    nsig: float
    tres: float
    max_gap: float
    reinit_after: int
    init_v_std: float
    init_v_std_known: float
    init_w_std: float
    smooth: bool


class KernelOutputs(NamedTuple):
    """Per row: ``state`` (N, 5) smoothed ``[x, y, vx, vy, w]``; ``std`` (N, 6) 1-sigma of x,
    y, speed, course, turn rate and (last) the x-y covariance; ``kind`` (N,) int8
    :class:`OutlierKind`; ``segment`` (N,) id (-1 none); ``nis`` (N,) of the report against
    the prediction; ``loglik`` (N,) its Gaussian prediction log-likelihood."""

    state: FloatArray
    std: FloatArray
    kind: NDArray[np.int8]
    segment: NDArray[np.int64]
    nis: FloatArray
    loglik: FloatArray


_LOG_2PI = math.log(2.0 * math.pi)  # 2-D Gaussian: -0.5 (d2 + log det S) - log(2 pi)


@njit(cache=True)
def _close(k0, k1, a, rows, xs, Ps, has, smooth, out_x, out_std, std):  # pragma: no cover
    """Smooth scratch rows ``k0..k1`` (inclusive) of the vessel starting at row ``a``
    (``rows``: the filter rows ``(xp, Pp, Fk, xf, Pf)``); write the state, the 1-sigma of
    :func:`derived_std` and (last column) the x-y covariance."""
    if k1 < k0:
        return
    xp, Pp, Fk, xf, Pf = rows
    smooth_segment(k0, k1, xp, Pp, Fk, xf, Pf, xs, Ps, has, smooth)
    for kk in range(k0, k1 + 1):
        if has[kk]:
            r = a + kk
            for j in range(NX):
                out_x[r, j] = xs[kk, j]
            derived_std(xs[kk], Ps[kk], std)
            for j in range(NX):
                out_std[r, j] = std[j]
            out_std[r, NX] = Ps[kk, 0, 1]


@njit(cache=True)
def _init_at(k, z, v0, known, sig, toff, prior, rows):  # pragma: no cover
    """Initialise a segment in scratch row ``k`` of the filter rows ``(xp, Pp, Fk, xf, Pf)``
    from one report: position ``z`` (moved on by ``v0 toff`` for a report stamped ``toff``
    seconds late), velocity ``v0`` (from SOG/COG) if ``known`` else zero, with the matching
    prior sigma of ``prior = (v_std, v_std_known, w_std)`` (m/s, m/s, rad/s); position
    covariance = the report's measurement noise ``sig = (sigma_pos, sigma_time)`` (m, s),
    see :func:`position_noise`."""
    v_std, v_std_known, w_std = prior
    xp, Pp, Fk, xf, Pf = rows
    vx = v0[0] if known else 0.0
    vy = v0[1] if known else 0.0
    sv = v_std_known if known else v_std
    for j in range(NX):
        xf[k, j] = 0.0
        for jj in range(NX):
            Pf[k, j, jj] = 0.0
            Fk[k, j, jj] = 1.0 if j == jj else 0.0
    xf[k, 0] = z[0] + vx * toff
    xf[k, 1] = z[1] + vy * toff
    xf[k, 2] = vx
    xf[k, 3] = vy
    # measurement covariance of the report (timestamp-jitter term along the velocity)
    st2 = sig[1] * sig[1]
    Pf[k, 0, 0] = sig[0] * sig[0] + st2 * vx * vx
    Pf[k, 1, 1] = sig[0] * sig[0] + st2 * vy * vy
    Pf[k, 0, 1] = Pf[k, 1, 0] = st2 * vx * vy
    Pf[k, 2, 2] = Pf[k, 3, 3] = sv * sv
    Pf[k, 4, 4] = w_std * w_std
    xp[k] = xf[k]
    Pp[k] = Pf[k]


@njit(cache=True, nogil=True)
def _track_flat(
    starts,
    v_lo,
    v_hi,
    t,
    z,
    use,
    force,
    v0,
    v0_known,
    sog,
    cog,
    sig,
    toff,
    use_vel,
    use_sog_alone,
    sigma_sog,
    sigma_cog,
    vmin,
    sigma_pos,
    q,
    q_w,
    gate,
    vmax,
    amax,
    w_max,
    nsig,
    tres,
    max_gap,
    reinit_after,
    init_v_std,
    init_v_std_known,
    init_w_std,
    smooth,
    out_x,
    out_std,
    out_flag,
    out_seg,
    out_nis,
    out_ll,
):  # pragma: no cover - compiled
    """Filter and smooth vessels ``v_lo..v_hi-1`` (rows ``starts[v]:starts[v + 1]``) with
    one set of scratch arrays sized for the longest of them."""
    L = 1
    for v in range(v_lo, v_hi):
        L = max(L, starts[v + 1] - starts[v])
    xp = np.zeros((L, NX))
    Pp = np.zeros((L, NX, NX))
    Fk = np.zeros((L, NX, NX))
    xf = np.zeros((L, NX))
    Pf = np.zeros((L, NX, NX))
    xs = np.zeros((L, NX))
    Ps = np.zeros((L, NX, NX))
    has = np.zeros(L, dtype=np.bool_)
    fx = np.empty(NX)
    F = np.empty((NX, NX))
    Q = np.empty((NX, NX))
    H = np.zeros((2, NX))  # position rows; columns 2, 3 carry the offset
    H[0, 0] = 1.0
    H[1, 1] = 1.0
    R = np.zeros((2, 2))
    R[0, 0] = R[1, 1] = sigma_pos * sigma_pos
    y = np.empty(2)
    Ko = np.empty((NX, 2))
    xo = np.empty(NX)
    Po = np.empty((NX, NX))
    Pi = np.empty((NX, NX))
    std = np.empty(NX)
    h2 = np.empty(2)
    H2 = np.zeros((2, NX))
    R2 = np.zeros((2, 2))
    R2[0, 0] = sigma_sog * sigma_sog
    R2[1, 1] = sigma_cog * sigma_cog
    y2 = np.empty(2)
    K2 = np.empty((NX, 2))
    H1 = np.zeros((1, NX))
    R1 = np.zeros((1, 1))
    R1[0, 0] = sigma_sog * sigma_sog
    y1 = np.empty(1)
    S1 = np.empty((1, 1))
    K1 = np.empty((NX, 1))
    xv = np.empty(NX)
    Pv = np.empty((NX, NX))
    rows = (xp, Pp, Fk, xf, Pf)  # the filter rows a segment starts in and the smoother reads
    prior = (init_v_std, init_v_std_known, init_w_std)
    noise_dist = nsig * math.sqrt(2.0) * sigma_pos  # noise allowance on a distance
    seg_id = 0
    for v in range(v_lo, v_hi):
        a, b = starts[v], starts[v + 1]
        init = False
        k_first = 0
        t_state = 0.0
        last_t = 0.0  # last accepted report
        last_x = 0.0
        last_y = 0.0
        prev_t = np.nan  # previous used report (accepted or not)
        prev_x = 0.0
        prev_y = 0.0
        run_t = 0.0
        n_out = 0
        sog_t = -np.inf  # last reported SOG of the vessel and its time
        sog_last = 0.0
        for i in range(a, b):
            k = i - a
            if use[i] and sog[i] == sog[i]:
                sog_t = t[i]
                sog_last = sog[i]
            out_seg[i] = -1
            out_nis[i] = np.nan
            out_ll[i] = np.nan
            has[k] = False
            # ---- stale position: exact repeat of the previous report while moving
            # (run_t: when the repeated position was first reported)
            stale = False
            if use[i] and prev_t == prev_t and z[i, 0] == prev_x and z[i, 1] == prev_y:
                if init and t[i] > run_t:
                    kp = k - 1
                    while kp > 0 and not has[kp]:
                        kp -= 1
                    spd = 0.0
                    if sog[i] == sog[i]:  # the reported SOG (GNSS), when there is one
                        spd = sog[i]
                    elif t[i] - sog_t <= max_gap:  # else the vessel's last reported SOG
                        spd = sog_last
                    elif has[kp]:  # else the filter speed, if significantly above zero
                        sv = math.sqrt(0.5 * (Pf[kp, 2, 2] + Pf[kp, 3, 3]))
                        spd = math.sqrt(xf[kp, 2] ** 2 + xf[kp, 3] ** 2) - nsig * sv
                    stale = spd * (t[i] - run_t) > noise_dist
            elif use[i]:
                run_t = t[i]
            if use[i]:
                prev_t = t[i]
                prev_x = z[i, 0]
                prev_y = z[i, 1]
            # ---- a long gap: implausible jump across it, or a new segment
            if init and t[i] - t_state > max_gap and use[i]:
                dxl = z[i, 0] - last_x
                dyl = z[i, 1] - last_y
                v_impl = (math.sqrt(dxl * dxl + dyl * dyl) - noise_dist) / (t[i] - last_t + tres)
                if v_impl > vmax and n_out + 1 < reinit_after and force[i] != Force.ACCEPT:
                    n_out += 1
                    out_flag[i] = OutlierKind.IMPLAUSIBLE_AFTER_GAP
                    # the row gets no estimate (the track is not propagated over the gap)
                    continue
                _close(k_first, k - 1, a, rows, xs, Ps, has, smooth, out_x, out_std, std)
                init = False
            elif init and t[i] - t_state > max_gap:
                # withheld row after a long gap: end the segment, no estimate for the row
                _close(k_first, k - 1, a, rows, xs, Ps, has, smooth, out_x, out_std, std)
                init = False
                continue
            if not init:
                if not use[i]:
                    continue  # withheld before a track exists: no estimate
                seg_id = i
                init = True
                k_first = k
                n_out = 0
                _init_at(k, z[i], v0[i], v0_known[i], sig[i], toff[i], prior, rows)
                t_state = t[i]
                last_t = t[i]
                last_x = z[i, 0]
                last_y = z[i, 1]
                has[k] = True
                out_seg[i] = seg_id
                continue
            # ---- predict to t[i] from the previous scratch row (always the one before)
            dt = t[i] - t_state
            kp = k - 1
            while not has[kp]:
                kp -= 1
            ct_f_jac(xf[kp], dt, fx, F)
            ct_q(dt, q, q_w, Q)
            predict_core(xf[kp], Pf[kp], F, Q, xo, Po)
            xp[k] = fx
            Pp[k] = Po
            Fk[k] = F
            xf[k] = fx
            Pf[k] = Po
            has[k] = True
            out_seg[i] = seg_id
            t_state = t[i]
            if not use[i]:
                continue
            if force[i] == Force.REJECT:
                out_flag[i] = (
                    OutlierKind.IMPLAUSIBLE_JUMP
                )  # rejected by the two-sided test of the first pass
                continue
            if stale and force[i] != Force.ACCEPT:
                out_flag[i] = OutlierKind.STALE_POSITION  # not counted towards re-initialisation
                continue
            # ---- gate (measurement noise of this report)
            # R = sigma_pos^2 I + sigma_time^2 v v^T: white position noise plus the
            # timestamp error tau, z = p(t + tau) ~ p(t) + v tau (v: predicted velocity)
            st2 = sig[i, 1] * sig[i, 1]
            R[0, 0] = sig[i, 0] * sig[i, 0] + st2 * fx[2] * fx[2]
            R[1, 1] = sig[i, 0] * sig[i, 0] + st2 * fx[3] * fx[3]
            R[0, 1] = R[1, 0] = st2 * fx[2] * fx[3]
            # a report stamped toff seconds late shows the position at t - toff:
            # h(x) = [x - vx toff, y - vy toff] (H linear; toff = 0 unless estimated)
            dl = toff[i]
            y[0] = z[i, 0] - (fx[0] - dl * fx[2])
            y[1] = z[i, 1] - (fx[1] - dl * fx[3])
            s00 = Po[0, 0] - 2.0 * dl * Po[0, 2] + dl * dl * Po[2, 2] + R[0, 0]
            s01 = Po[0, 1] - dl * (Po[0, 3] + Po[1, 2]) + dl * dl * Po[2, 3] + R[0, 1]
            s11 = Po[1, 1] - 2.0 * dl * Po[1, 3] + dl * dl * Po[3, 3] + R[1, 1]
            det = s00 * s11 - s01 * s01
            d2 = (s11 * y[0] * y[0] - 2 * s01 * y[0] * y[1] + s00 * y[1] * y[1]) / det
            out_nis[i] = d2
            out_ll[i] = -0.5 * (d2 + math.log(det)) - _LOG_2PI
            if d2 > gate:
                # plausibility: implied speed from the last accepted report and implied
                # acceleration from the distance to the prediction
                dxl = z[i, 0] - last_x
                dyl = z[i, 1] - last_y
                v_impl = (math.sqrt(dxl * dxl + dyl * dyl) - noise_dist) / (t[i] - last_t + tres)
                tr = 0.5 * (s00 + s11)
                lam = tr + math.sqrt(max(tr * tr - det, 0.0))
                dev = math.sqrt(y[0] * y[0] + y[1] * y[1]) - nsig * math.sqrt(lam)
                dte = t[i] - last_t + tres
                a_impl = 2.0 * dev / (dte * dte)
                if (v_impl > vmax or a_impl > amax) and force[i] != Force.ACCEPT:
                    n_out += 1
                    if n_out >= reinit_after:
                        # track lost: close the segment before i, restart at i
                        _close(k_first, k - 1, a, rows, xs, Ps, has, smooth, out_x, out_std, std)
                        seg_id = i
                        k_first = k
                        n_out = 0
                        _init_at(k, z[i], v0[i], v0_known[i], sig[i], toff[i], prior, rows)
                        last_t = t[i]
                        last_x = z[i, 0]
                        last_y = z[i, 1]
                        out_seg[i] = seg_id
                        continue
                    out_flag[i] = OutlierKind.IMPLAUSIBLE_JUMP
                    continue
                # plausible manoeuvre: inflate the prediction so the report sits on the gate
                f = d2 / gate
                for j in range(NX):
                    for jj in range(NX):
                        Pi[j, jj] = Po[j, jj] * f
                Pp[k] = Pi
            else:
                for j in range(NX):
                    for jj in range(NX):
                        Pi[j, jj] = Po[j, jj]
            H[0, 2] = H[1, 3] = -dl
            update2(fx, Pi, y, H, R, xo, Po, Ko)
            if use_vel and sog[i] == sog[i] and sog[i] > vmin:
                # velocity measurements: SOG (and COG), sequential update after the position
                sogcog(xo, h2, H2)
                if h2[0] > vmin:
                    nis2 = np.inf
                    if cog[i] == cog[i]:
                        y2[0] = sog[i] - h2[0]
                        y2[1] = wrap_angle(cog[i] - h2[1])
                        nis2 = update2(xo, Po, y2, H2, R2, xv, Pv, K2)
                    elif use_sog_alone:
                        y1[0] = sog[i] - h2[0]
                        for j in range(NX):
                            H1[0, j] = H2[0, j]
                        nis2, _ = update_core(xo, Po, y1, H1, R1, xv, Pv, S1, K1)
                    if nis2 <= gate:
                        for j in range(NX):
                            xo[j] = xv[j]
                            for jj in range(NX):
                                Po[j, jj] = Pv[j, jj]
            constrain(xo, vmax, amax, w_max)
            n_out = 0
            xf[k] = xo
            Pf[k] = Po
            last_t = t[i]
            last_x = z[i, 0]
            last_y = z[i, 1]
        if init:
            _close(k_first, b - a - 1, a, rows, xs, Ps, has, smooth, out_x, out_std, std)


@njit(cache=True, nogil=True)
def _track_chunk(inp, par, out, v0, v1):  # pragma: no cover - compiled
    """Vessels ``v0..v1-1`` (the named tuples unpacked for the flat kernel)."""
    _track_flat(
        inp.starts,
        v0,
        v1,
        inp.t,
        inp.z,
        inp.use,
        inp.force,
        inp.v0,
        inp.known,
        inp.sog,
        inp.cog,
        inp.sig,
        inp.toff,
        par.use_vel,
        par.use_sog_alone,
        par.sigma_sog,
        par.sigma_cog,
        par.vmin,
        par.sigma_pos,
        par.q,
        par.q_w,
        par.gate,
        par.vmax,
        par.amax,
        par.w_max,
        par.nsig,
        par.tres,
        par.max_gap,
        par.reinit_after,
        par.init_v_std,
        par.init_v_std_known,
        par.init_w_std,
        par.smooth,
        out.state,
        out.std,
        out.kind,
        out.segment,
        out.nis,
        out.loglik,
    )


@njit(cache=True, nogil=True, parallel=True)
def _track_kernel(inp, par, out, chunks):  # pragma: no cover - compiled
    """All vessels, chunk by chunk on all threads (``chunks``: vessel-index boundaries)."""
    for c in prange(chunks.shape[0] - 1):
        _track_chunk(inp, par, out, chunks[c], chunks[c + 1])


def kernel_params(cfg: AisTrackerConfig) -> KernelParams:
    """:class:`KernelParams` of a configuration (knots and degrees converted)."""
    return KernelParams(
        use_vel=bool(cfg.use_sog_cog),
        use_sog_alone=bool(cfg.use_sog_alone),
        sigma_sog=float(cfg.sigma_sog_kn * KNOT_MPS),
        sigma_cog=math.radians(cfg.sigma_cog_deg),
        vmin=float(cfg.min_speed_kn * KNOT_MPS),
        sigma_pos=float(cfg.sigma_pos_m),
        q=float(cfg.q_accel),
        q_w=float(cfg.q_turn),
        gate=float(cfg.gate),
        vmax=float(cfg.max_speed_kn * KNOT_MPS),
        amax=float(cfg.max_accel_mps2),
        w_max=math.radians(cfg.max_turn_rate_dps),
        nsig=float(cfg.n_sigma),
        tres=float(cfg.time_resolution_s),
        max_gap=float(cfg.max_gap_s),
        reinit_after=int(cfg.reinit_after),
        init_v_std=float(cfg.init_speed_std_mps),
        init_v_std_known=float(cfg.init_sogcog_std_mps),
        init_w_std=math.radians(cfg.init_turn_std_dps),
        smooth=bool(cfg.smooth),
    )


def vessel_chunks(starts: NDArray[np.int64], n_chunks: int) -> NDArray[np.int64]:
    """Vessel-index boundaries of at most ``n_chunks`` chunks of about equal row counts."""
    n_v = starts.size - 1
    if n_v <= 0:
        return np.zeros(1, dtype=np.int64)
    k = max(1, min(n_chunks, n_v))
    cut = np.searchsorted(starts, np.linspace(0, starts[-1], k + 1)[1:-1], side="left")
    return np.unique(np.r_[0, np.clip(cut, 1, n_v - 1), n_v]).astype(np.int64)


def vessel_starts(vessel: NDArray[np.int64]) -> NDArray[np.int64]:
    """Boundaries ``(V + 1,)`` of the runs of equal vessel ids (rows sorted by vessel)."""
    vs = np.asarray(vessel)
    if vs.size == 0:
        return np.zeros(1, dtype=np.int64)
    return np.flatnonzero(np.r_[True, vs[1:] != vs[:-1], True]).astype(np.int64)


@njit(cache=True, nogil=True)
def largest_vessel(starts, chunks, c):  # pragma: no cover - compiled
    """Rows of the largest vessel of chunk ``c`` (at least 1): the size of its work arrays."""
    size = 1
    for v in range(chunks[c], chunks[c + 1]):
        size = max(size, starts[v + 1] - starts[v])
    return size


def thread_chunks(starts: NDArray[np.int64]) -> NDArray[np.int64]:
    """The chunks of vessels that the compiled stages run on numba's threads
    (:func:`vessel_chunks`, 8 per thread)."""
    return vessel_chunks(starts, 8 * numba.get_num_threads())


def vessel_layout(vessel: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Vessel boundaries (:func:`vessel_starts`) and their :func:`thread_chunks`."""
    starts = vessel_starts(vessel)
    return starts, thread_chunks(starts)


def vessel_index(starts: NDArray[np.int64]) -> NDArray[np.int64]:
    """Index of each row's vessel, ``(N,)``, from the boundaries ``starts``."""
    return np.repeat(np.arange(starts.size - 1), np.diff(starts))


def take_rows(inp: KernelInputs, rows: NDArray[np.bool_] | None, **new: NDArray) -> KernelInputs:
    """The rows ``rows`` of ``inp`` (whole vessels; None: all, not copied), with per-row
    fields replaced by ``new`` (full length); ``starts`` follows."""
    if rows is None:
        return inp._replace(**new)
    kept = {f: new.get(f, getattr(inp, f))[rows] for f in KernelInputs._fields[1:]}
    return KernelInputs(vessel_starts(vessel_index(inp.starts)[rows]), **kept)


def vessel_rows(
    vessel: NDArray[np.int64], t: ArrayLike, xy: ArrayLike, mask: ArrayLike
) -> tuple[NDArray[np.int64], NDArray[np.int64], FloatArray, FloatArray, NDArray[np.bool_]]:
    """:func:`vessel_layout` and the rows' times (s), positions (m) and mask as the
    contiguous float64 / bool arrays the compiled vessel stages read."""
    starts, chunks = vessel_layout(vessel)
    c = np.ascontiguousarray
    return starts, chunks, c(t, np.float64), c(xy, np.float64), c(mask, np.bool_)


def run_kernel(inp: KernelInputs, cfg: AisTrackerConfig) -> KernelOutputs:
    """Run the compiled tracker over the rows of ``inp`` (sorted by (vessel, time)) on all
    of numba's threads; the result does not depend on their number."""
    n = inp.t.size
    out = KernelOutputs(
        state=np.full((n, NX), np.nan),
        std=np.full((n, NX + 1), np.nan),
        kind=np.zeros(n, dtype=np.int8),
        segment=np.full(n, -1, dtype=np.int64),
        nis=np.full(n, np.nan),
        loglik=np.full(n, np.nan),
    )
    c = np.ascontiguousarray
    args = KernelInputs._make(c(a) for a in inp)
    par = kernel_params(cfg)
    chunks = thread_chunks(args.starts)
    _track_kernel(args, par, out, chunks)
    # the smoother can step outside the physical limits the filter keeps: project again
    constrain_rows(out.state, par.vmax, par.amax, par.w_max)
    return out
