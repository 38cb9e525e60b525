"""The causal AIS filter step of one vessel and one report, compiled (Numba, ``nogil``).

:func:`causal_step` is the per-report logic of the batch kernel of
:mod:`seatrack.filters.ais.kernel` with ``smooth=False``, no withheld rows, no timestamp
offsets and the report noise ``sigma_pos_m`` (see :mod:`seatrack.live.ais`), written as one
compiled call so that a report costs one dispatch instead of a dozen. It works in place on
the vessel's state: the scalars ``st`` (:data:`SCALARS`, in that order, as float64), the
state ``x = [x, y, vx, vy, w]`` (plane, m, m/s, rad/s) and its covariance ``P``; the work
arrays ``w`` are those of :func:`work_arrays`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from seatrack.filters.ais import OutlierKind
from seatrack.filters.ais.ct import constrain
from seatrack.filters.ais.ct import ct_f_jac
from seatrack.filters.ais.ct import ct_q
from seatrack.filters.ais.ct import sogcog
from seatrack.filters.ais.ct import update2
from seatrack.filters.ais.kernel import KernelParams
from seatrack.filters.ais.smoother import derived_std
from seatrack.kalman import predict_core
from seatrack.kalman import update_core
from seatrack.kalman import wrap_angle

__all__ = ["NX", "SCALARS", "causal_step", "param_array", "work_arrays"]

NX = 5

#: the filter's scalar state, in the order of the ``st`` array (and of the store's rows)
SCALARS = (
    "init", "segment", "t_state", "last_t", "last_x", "last_y", "prev_t", "prev_x", "prev_y",
    "run_t", "n_out", "sog_t", "sog_last",
)  # fmt: skip
_INIT, _SEG, _TS, _LT, _LX, _LY, _PT, _PX, _PY, _RT, _NOUT, _SOGT, _SOGL = range(13)

#: positions in the array of :func:`param_array`
_P_AMAX = KernelParams._fields.index("amax")
_P_GATE = KernelParams._fields.index("gate")
_P_INIT_V_STD = KernelParams._fields.index("init_v_std")
_P_INIT_V_STD_KNOWN = KernelParams._fields.index("init_v_std_known")
_P_INIT_W_STD = KernelParams._fields.index("init_w_std")
_P_MAX_GAP = KernelParams._fields.index("max_gap")
_P_NSIG = KernelParams._fields.index("nsig")
_P_Q = KernelParams._fields.index("q")
_P_Q_W = KernelParams._fields.index("q_w")
_P_REINIT_AFTER = KernelParams._fields.index("reinit_after")
_P_SIGMA_COG = KernelParams._fields.index("sigma_cog")
_P_SIGMA_POS = KernelParams._fields.index("sigma_pos")
_P_SIGMA_SOG = KernelParams._fields.index("sigma_sog")
_P_TRES = KernelParams._fields.index("tres")
_P_USE_SOG_ALONE = KernelParams._fields.index("use_sog_alone")
_P_USE_VEL = KernelParams._fields.index("use_vel")
_P_VMAX = KernelParams._fields.index("vmax")
_P_VMIN = KernelParams._fields.index("vmin")
_P_W_MAX = KernelParams._fields.index("w_max")


def param_array(par: KernelParams) -> NDArray[np.float64]:
    """The kernel parameters as one float64 array (booleans 0/1), in the order of
    :class:`~seatrack.filters.ais.kernel.KernelParams`: a compiled call takes an array far
    faster than a named tuple of twenty fields."""
    return np.array([float(v) for v in par], dtype=np.float64)


#: status of :func:`causal_step`: no estimate for the report, or an estimate in ``std``
NO_ESTIMATE, ESTIMATE = 0, 1
_STALE, _JUMP = int(OutlierKind.STALE_POSITION), int(OutlierKind.IMPLAUSIBLE_JUMP)


@njit(cache=True, nogil=True)
def work_arrays():  # pragma: no cover - compiled
    """The work arrays of :func:`causal_step` (allocated per call: cheaper inside the
    compiled code than passing them in)."""
    H = np.zeros((2, NX))
    H[0, 0] = H[1, 1] = 1.0
    return (
        np.empty(NX), np.empty((NX, NX)), np.empty((NX, NX)),  # fx, F, Q
        np.empty(NX), np.empty((NX, NX)), np.empty((NX, NX)),  # xo, Po, Pi
        H, np.zeros((2, 2)), np.empty(2), np.empty((NX, 2)),  # H, R, y, K
        np.empty(2), np.zeros((2, NX)), np.empty(2), np.zeros((2, 2)), np.empty((NX, 2)),
        np.empty(NX), np.empty((NX, NX)),  # xv, Pv
        np.zeros((1, NX)), np.zeros((1, 1)), np.empty(1), np.empty((1, 1)), np.empty((NX, 1)),
    )  # fmt: skip


@njit(cache=True, nogil=True)
def _init_at(p, st, x, P, t, rx, ry, v0x, v0y):  # pragma: no cover - compiled
    known = math.isfinite(v0x) and math.isfinite(v0y)
    vx, vy = (v0x, v0y) if known else (0.0, 0.0)
    sv = p[_P_INIT_V_STD_KNOWN] if known else p[_P_INIT_V_STD]
    x[0], x[1], x[2], x[3], x[4] = rx, ry, vx, vy, 0.0
    P[:] = 0.0
    P[0, 0] = P[1, 1] = p[_P_SIGMA_POS] * p[_P_SIGMA_POS]
    P[2, 2] = P[3, 3] = sv * sv
    P[4, 4] = p[_P_INIT_W_STD] * p[_P_INIT_W_STD]
    st[_SEG] += 1.0
    st[_NOUT] = 0.0
    st[_LT], st[_LX], st[_LY] = t, rx, ry


@njit(cache=True, nogil=True)
def causal_step(p, st, x, P, t, rx, ry, v0x, v0y, sog, cog, std):  # pragma: no cover
    """Filter one report in place: parameters ``p`` of :func:`param_array`, time ``t``
    (s), plane position ``rx``, ``ry`` (m), SOG/COG velocity ``v0x``, ``v0y`` (m/s), SOG
    (m/s) and COG (rad), NaN unknown; times non-decreasing.

    Returns ``(status, kind, nis)``: :data:`NO_ESTIMATE` when the report gets no estimate
    (an implausible jump across a long gap), else :data:`ESTIMATE` with the outlier kind
    (:class:`~seatrack.filters.ais.OutlierKind`), the NIS (NaN for a segment's first
    report) and the 1-sigma of x, y, speed, course and turn rate in ``std``.
    """
    fx, F, Q, xo, Po, Pi, H, R, y, K, h2, H2, y2, R2, K2, xv, Pv, H1, R1, y1, S1, K1 = work_arrays()
    noise_dist = p[_P_NSIG] * math.sqrt(2.0) * p[_P_SIGMA_POS]
    if sog == sog:
        st[_SOGT], st[_SOGL] = t, sog
    stale = False
    init = st[_INIT] != 0.0
    if st[_PT] == st[_PT] and rx == st[_PX] and ry == st[_PY]:
        if init and t > st[_RT]:
            spd = 0.0
            if sog == sog:
                spd = sog
            elif t - st[_SOGT] <= p[_P_MAX_GAP]:
                spd = st[_SOGL]
            else:
                sv = math.sqrt(0.5 * (P[2, 2] + P[3, 3]))
                spd = math.hypot(x[2], x[3]) - p[_P_NSIG] * sv
            stale = spd * (t - st[_RT]) > noise_dist
    else:
        st[_RT] = t
    st[_PT], st[_PX], st[_PY] = t, rx, ry
    if init and t - st[_TS] > p[_P_MAX_GAP]:
        v_impl = (math.hypot(rx - st[_LX], ry - st[_LY]) - noise_dist) / (t - st[_LT] + p[_P_TRES])
        if v_impl > p[_P_VMAX] and st[_NOUT] + 1 < p[_P_REINIT_AFTER]:
            st[_NOUT] += 1.0
            return NO_ESTIMATE, 0, math.nan
        init = False
        st[_INIT] = 0.0
    if not init:
        st[_INIT] = 1.0
        _init_at(p, st, x, P, t, rx, ry, v0x, v0y)
        st[_TS] = t
        derived_std(x, P, std)
        return ESTIMATE, 0, math.nan
    dt = t - st[_TS]
    ct_f_jac(x, dt, fx, F)
    ct_q(dt, p[_P_Q], p[_P_Q_W], Q)
    predict_core(x, P, F, Q, xo, Po)
    x[:] = fx
    P[:] = Po
    st[_TS] = t
    if stale:
        derived_std(x, P, std)
        return ESTIMATE, _STALE, math.nan
    R[0, 0] = R[1, 1] = p[_P_SIGMA_POS] * p[_P_SIGMA_POS]
    R[0, 1] = R[1, 0] = 0.0
    y[0], y[1] = rx - fx[0], ry - fx[1]
    s00, s01, s11 = Po[0, 0] + R[0, 0], Po[0, 1], Po[1, 1] + R[1, 1]
    det = s00 * s11 - s01 * s01
    y0, y1_ = y[0], y[1]
    d2 = (s11 * y0 * y0 - 2 * s01 * y0 * y1_ + s00 * y1_ * y1_) / det
    if d2 > p[_P_GATE]:
        v_impl = (math.hypot(rx - st[_LX], ry - st[_LY]) - noise_dist) / (t - st[_LT] + p[_P_TRES])
        tr = 0.5 * (s00 + s11)
        lam = tr + math.sqrt(max(tr * tr - det, 0.0))
        dev = math.hypot(y0, y1_) - p[_P_NSIG] * math.sqrt(lam)
        dte = t - st[_LT] + p[_P_TRES]
        a_impl = 2.0 * dev / (dte * dte)
        if v_impl > p[_P_VMAX] or a_impl > p[_P_AMAX]:
            st[_NOUT] += 1.0
            if st[_NOUT] >= p[_P_REINIT_AFTER]:
                _init_at(p, st, x, P, t, rx, ry, v0x, v0y)
                derived_std(x, P, std)
                return ESTIMATE, 0, math.nan
            derived_std(x, P, std)
            return ESTIMATE, _JUMP, d2
        scale = d2 / p[_P_GATE]
        for i in range(NX):
            for j in range(NX):
                Pi[i, j] = Po[i, j] * scale
    else:
        Pi[:] = Po
    H[0, 2] = H[1, 3] = 0.0
    update2(fx, Pi, y, H, R, xo, Po, K)
    Pu = Po
    if p[_P_USE_VEL] != 0.0 and sog == sog and sog > p[_P_VMIN]:
        sogcog(xo, h2, H2)
        if h2[0] > p[_P_VMIN]:
            nis2 = math.inf
            if cog == cog:
                y2[0] = sog - h2[0]
                y2[1] = wrap_angle(cog - h2[1])
                R2[0, 0] = p[_P_SIGMA_SOG] * p[_P_SIGMA_SOG]
                R2[1, 1] = p[_P_SIGMA_COG] * p[_P_SIGMA_COG]
                nis2 = update2(xo, Pu, y2, H2, R2, xv, Pv, K2)
            elif p[_P_USE_SOG_ALONE] != 0.0:
                y1[0] = sog - h2[0]
                H1[0, :] = H2[0, :]
                R1[0, 0] = p[_P_SIGMA_SOG] * p[_P_SIGMA_SOG]
                nis2, _ = update_core(xo, Pu, y1, H1, R1, xv, Pv, S1, K1)
            if nis2 <= p[_P_GATE]:
                xo[:] = xv
                Pu[:] = Pv
    constrain(xo, p[_P_VMAX], p[_P_AMAX], p[_P_W_MAX])
    st[_NOUT] = 0.0
    x[:] = xo
    P[:] = Pu
    st[_LT], st[_LX], st[_LY] = t, rx, ry
    derived_std(x, P, std)
    return ESTIMATE, 0, d2
