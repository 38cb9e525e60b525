"""Track many vessels at once in local planes: :func:`track_vessels` (sorting, noise
estimate, kernel, revisit passes, refinement pass, segment numbering)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seatrack.filters.ais.config import NX, AisTrackerConfig
from seatrack.filters.ais.kernel import Force
from seatrack.filters.ais.noise import position_noise
from seatrack.filters.ais.plausibility import Rows, revisit, run_rows
from seatrack.filters.ais.refine import refine_pass

FloatArray = NDArray[np.float64]

__all__ = ["TrackStates", "track_vessels"]


@dataclass(frozen=True)
class TrackStates:
    """Per-row estimates in each vessel's local plane (same row order as the inputs).

    Attributes
    ----------
    state : ndarray (N, 5)
        Smoothed (or filtered) ``[x, y, vx, vy, w]`` (m, m/s, rad/s); NaN without estimate.
    std : ndarray (N, 5)
        1-sigma of x, y (m), speed (m/s), course (rad), turn rate (rad/s).
    outlier : ndarray of bool (N,)
        Report judged an outlier and not used.
    outlier_kind : ndarray of int8 (N,)
        0 = none, else a key of :data:`OUTLIER_KINDS` (1 outside the gate and implausible,
        2 stale position, 3 implausible jump across a long gap).
    segment : ndarray of int (N,)
        Track segment id (splits at gaps / re-initialisations); -1 without estimate.
    nis : ndarray (N,)
        NIS of the report against the prediction (NaN for first reports / unused rows).
    time_offset : ndarray (N,)
        Estimated timestamp error of the report (s, whole seconds, logged minus true time;
        :func:`timestamp_offsets`); 0 where not estimated.
    """

    state: FloatArray
    std: FloatArray
    outlier: NDArray[np.bool_]
    outlier_kind: NDArray[np.int8]
    segment: NDArray[np.int64]
    nis: FloatArray
    time_offset: FloatArray


def track_vessels(
    vessel: ArrayLike,
    t: ArrayLike,
    xy: ArrayLike,
    config: AisTrackerConfig | None = None,
    use: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    sog: ArrayLike | None = None,
    cog: ArrayLike | None = None,
) -> TrackStates:
    """Track many vessels at once in local planes (the compiled core of the AIS tracker).

    Parameters
    ----------
    vessel : array of int (N,)
        Vessel id of each report (any order; rows are grouped and time-sorted inside,
        stably, so equal times keep their input order).
    t : array (N,)
        Times, s.
    xy : array (N, 2)
        Positions East, North (m) in the vessel's local plane.
    config : AisTrackerConfig
    use : array of bool (N,), optional
        False = do not use the report (hold-out): the row still gets the track estimate.
    v0 : array (N, 2), optional
        Velocity (East, North; m/s) from SOG/COG for initialisation; NaN where unknown.
    sog : array (N,), optional
        Reported speed over ground (m/s; NaN unknown): stale-position test and, with
        ``use_sog_cog``, a velocity measurement.
    cog : array (N,), optional
        Reported course over ground (rad, clockwise from the plane's North; NaN unknown).

    Returns
    -------
    TrackStates
        In the input row order.
    """
    cfg = config or AisTrackerConfig()
    vid = np.asarray(vessel, dtype=np.int64)
    tt = np.asarray(t, dtype=np.float64)
    z = np.asarray(xy, dtype=np.float64)
    n = tt.size
    if z.shape != (n, 2) or vid.shape != (n,):
        raise ValueError(f"vessel (N,), t (N,) and xy (N, 2) needed; got {vid.shape}, {z.shape}")
    if not (np.isfinite(tt).all() and np.isfinite(z).all()):
        raise ValueError("times and positions must be finite (reject bad rows first)")
    u = np.ones(n, dtype=bool) if use is None else np.asarray(use, dtype=bool)
    sg = np.full(n, np.nan) if sog is None else np.asarray(sog, dtype=np.float64)
    cg = np.full(n, np.nan) if cog is None else np.asarray(cog, dtype=np.float64)
    vv = np.full((n, 2), np.nan) if v0 is None else np.asarray(v0, dtype=np.float64)
    order = np.lexsort((tt, vid))
    ts, zs, us, vs_ = tt[order], z[order], u[order], vid[order]
    vo = np.ascontiguousarray(vv[order])
    known: NDArray[np.bool_] = np.asarray(np.isfinite(vo).all(axis=1))
    vo[~known] = 0.0
    sgs = sg[order]
    cgs = cg[order]
    force = np.full(n, Force.FREE, dtype=np.int8)
    if cfg.estimate_noise:
        sig = position_noise(vs_, ts, zs, us, cfg)
    else:
        sig = np.zeros((n, 2))
        sig[:, 0] = cfg.sigma_pos_m
    toff = np.zeros(n)
    rows = Rows(vs_, ts, zs, us, vo, known, sgs, cgs, sig, force, toff)
    out = run_rows(rows, cfg)
    revisit(rows, out, cfg)
    if cfg.refine and n:
        out, toff = refine_pass(rows, out, cfg)
    # segment ids 1, 2, ... in order of (vessel, time)
    seg = out.segment
    has = seg >= 0
    ids, first, which = np.unique(seg[has], return_index=True, return_inverse=True)
    rank = np.empty(ids.size, dtype=np.int64)
    rank[np.argsort(first)] = np.arange(1, ids.size + 1)
    seg[has] = rank[which]
    inv = np.empty_like(order)
    inv[order] = np.arange(n)
    out_x, out_std, out_flag, out_seg, out_nis, _ = (a[inv] for a in out)
    return TrackStates(out_x, out_std[:, :NX], out_flag > 0, out_flag, out_seg, out_nis, toff[inv])
