"""Track many vessels at once in local planes: :func:`track_vessels` (sorting, noise
estimate, kernel, revisit passes, refinement pass, segment numbering).

The steps are public for tables split into vessel groups (:func:`track_vessel_groups`, and
the bounded-memory and Dask pipelines of :mod:`seatrack.io.ais`): :func:`prepare_rows`,
:func:`first_track`, the refinement pass (:mod:`~seatrack.filters.ais.refine`, whose offset
prior is shared by all groups) and :func:`track_states`. The result does not depend on how
the vessels are grouped."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.filters.ais.config import NX
from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.kernel import Force
from seatrack.filters.ais.kernel import KernelInputs
from seatrack.filters.ais.kernel import KernelOutputs
from seatrack.filters.ais.kernel import run_kernel
from seatrack.filters.ais.kernel import vessel_index
from seatrack.filters.ais.kernel import vessel_starts
from seatrack.filters.ais.noise import position_noise
from seatrack.filters.ais.plausibility import revisit
from seatrack.filters.ais.refine import Refinement
from seatrack.filters.ais.refine import refine_groups

FloatArray = NDArray[np.float64]

__all__ = [
    "TrackStates",
    "VesselInputs",
    "track_vessels",
    "track_vessel_groups",
    "prepare_rows",
    "first_track",
    "track_states",
]


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
        Number of the track segment within its vessel, 1, 2, ... in time order (tracks
        split at gaps / re-initialisations); -1 without estimate.
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


@dataclass(frozen=True)
class VesselInputs:
    """Reports of many vessels, any row order (see :func:`track_vessels` for the fields)."""

    vessel: NDArray[np.int64]
    t: FloatArray
    xy: FloatArray
    use: NDArray[np.bool_] | None = None
    v0: FloatArray | None = None
    sog: FloatArray | None = None
    cog: FloatArray | None = None


def prepare_rows(
    inputs: VesselInputs, cfg: AisTrackerConfig
) -> tuple[KernelInputs, NDArray[np.int64] | None]:
    """Rows sorted by (vessel, time) (stable: equal times keep their input order) with the
    estimated report noise, and the sort order (None when the inputs were sorted)."""
    vid = np.asarray(inputs.vessel, dtype=np.int64)
    tt = np.asarray(inputs.t, dtype=np.float64)
    z = np.asarray(inputs.xy, dtype=np.float64)
    n = tt.size
    if z.shape != (n, 2) or vid.shape != (n,):
        raise ValueError(f"vessel (N,), t (N,) and xy (N, 2) needed; got {vid.shape}, {z.shape}")
    if not (np.isfinite(tt).all() and np.isfinite(z).all()):
        raise ValueError("times and positions must be finite (reject bad rows first)")
    order: NDArray[np.int64] | None = None
    if not _sorted(vid, tt):
        order = np.lexsort((tt, vid))

    def opt(a: ArrayLike | None, shape: tuple[int, ...], fill: float) -> NDArray:
        x = np.full(shape, fill) if a is None else np.asarray(a, dtype=np.float64)
        return x if order is None else x[order]

    def take(a: NDArray) -> NDArray:
        return a if order is None else a[order]

    u = np.ones(n, dtype=bool) if inputs.use is None else np.asarray(inputs.use, dtype=bool)
    vs, ts, zs, us = take(vid), take(tt), np.ascontiguousarray(take(z)), take(u)
    vo = np.array(opt(inputs.v0, (n, 2), np.nan), order="C")  # a copy: zeroed below
    known: NDArray[np.bool_] = np.asarray(np.isfinite(vo).all(axis=1))
    vo[~known] = 0.0
    if cfg.estimate_noise:
        sig = position_noise(vs, ts, zs, us, cfg)
    else:
        sig = np.zeros((n, 2))
        sig[:, 0] = cfg.sigma_pos_m
    rows = KernelInputs(
        starts=vessel_starts(vs),
        t=ts,
        z=zs,
        use=us,
        force=np.full(n, Force.FREE, dtype=np.int8),
        v0=vo,
        known=known,
        sog=opt(inputs.sog, (n,), np.nan),
        cog=opt(inputs.cog, (n,), np.nan),
        sig=sig,
        toff=np.zeros(n),
    )
    return rows, order


def _sorted(vessel: NDArray[np.int64], t: FloatArray) -> bool:
    """Rows already in (vessel, time) order."""
    if vessel.size < 2:
        return True
    v1, v0 = vessel[1:], vessel[:-1]
    return bool(np.all((v1 > v0) | ((v1 == v0) & (t[1:] >= t[:-1]))))


def first_track(rows: KernelInputs, cfg: AisTrackerConfig) -> KernelOutputs:
    """The kernel and the revisit passes (``rows.force`` is updated)."""
    out = run_kernel(rows, cfg)
    revisit(rows, out, cfg)
    return out


def track_states(
    rows: KernelInputs, out: KernelOutputs, toff: FloatArray, order: NDArray[np.int64] | None
) -> TrackStates:
    """:class:`TrackStates` in input order from the outputs over the sorted rows (``order``
    of :func:`prepare_rows`); segments numbered 1, 2, ... within each vessel in time order."""
    seg = out.segment.copy()
    has = np.flatnonzero(seg >= 0)
    if has.size:
        ids, first, which = np.unique(seg[has], return_index=True, return_inverse=True)
        by_first = np.argsort(first, kind="stable")  # segments in (vessel, time) order
        ves = vessel_index(rows.starts)[has[first[by_first]]]
        start = np.r_[True, ves[1:] != ves[:-1]]
        pos = np.arange(ids.size)
        num = pos - np.maximum.accumulate(np.where(start, pos, 0)) + 1
        rank = np.empty(ids.size, dtype=np.int64)
        rank[by_first] = num
        seg[has] = rank[which.ravel()]
    toff = np.asarray(toff, dtype=np.float64)
    if order is None:
        return TrackStates(out.state, out.std[:, :NX], out.kind > 0, out.kind, seg, out.nis, toff)
    inv = np.empty_like(order)
    inv[order] = np.arange(order.size)
    return TrackStates(
        out.state[inv],
        out.std[inv, :NX],
        out.kind[inv] > 0,
        out.kind[inv],
        seg[inv],
        out.nis[inv],
        toff[inv],
    )


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
    inputs = VesselInputs(
        *(None if a is None else np.asarray(a) for a in (vessel, t, xy, use, v0, sog, cog))  # type: ignore[arg-type]
    )
    return track_vessel_groups([inputs], config)[0]


def track_vessel_groups(
    groups: list[VesselInputs], config: AisTrackerConfig | None = None
) -> list[TrackStates]:
    """:func:`track_vessels` of vessel groups held in memory (each vessel in one group);
    the result is the same as for one table of all groups (the offset prior is shared)."""
    cfg = config or AisTrackerConfig()
    prepared = [prepare_rows(g, cfg) for g in groups]
    outs = [first_track(rows, cfg) for rows, _ in prepared]
    if cfg.refine:
        live = [k for k, (rows, _) in enumerate(prepared) if rows.t.size]
        refs = [Refinement(prepared[k][0], outs[k], cfg) for k in live]
        done = dict(zip(live, refine_groups(refs, cfg), strict=True))
    else:
        done = {}
    result = []
    for k, (rows, order) in enumerate(prepared):
        out, toff = done.get(k, (outs[k], np.zeros(rows.t.size)))
        result.append(track_states(rows, out, toff, order))
    return result
