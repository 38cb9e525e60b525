"""Two-sided physical plausibility of AIS reports and the revisit passes that use it.

The kernel decides causally (a report against the past). A revisit pass judges each report
against its accepted neighbours on both sides (:func:`neighbour_plausibility`): an outlier
that is plausible on both sides is accepted, an accepted report that is implausible is
rejected, and the vessels concerned are filtered again (:func:`revisit`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba import prange
from numpy.typing import NDArray

from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.kernel import Force
from seatrack.filters.ais.kernel import KernelInputs
from seatrack.filters.ais.kernel import KernelOutputs
from seatrack.filters.ais.kernel import OutlierKind
from seatrack.filters.ais.kernel import largest_vessel
from seatrack.filters.ais.kernel import run_kernel
from seatrack.filters.ais.kernel import take_rows
from seatrack.filters.ais.kernel import thread_chunks
from seatrack.filters.ais.kernel import vessel_rows
from seatrack.geometry import KNOT_MPS

FloatArray = NDArray[np.float64]

__all__ = ["neighbour_plausibility", "revisit", "merge_outputs"]


def merge_outputs(out: KernelOutputs, rows: NDArray[np.bool_], new: KernelOutputs) -> None:
    """Write kernel outputs ``new`` of the rows ``rows`` into ``out``; their segment ids are
    moved past those of ``out`` so that ids stay unique."""
    seg = new.segment
    seg[:] = np.where(seg >= 0, seg + int(out.segment.max(initial=0)) + 1, -1)
    for a_out, a_new in zip(out, new, strict=True):
        np.asarray(a_out)[rows] = a_new


def neighbour_plausibility(
    vessel: NDArray[np.int64],
    t: FloatArray,
    xy: FloatArray,
    accepted: NDArray[np.bool_],
    config: AisTrackerConfig,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Two-sided physical plausibility of each report against its accepted neighbours.

    Rows must be sorted by (vessel, time). For every row, with ``p``/``n`` the nearest
    *other* accepted report of the same vessel before/after it (NaN results where none):

    * ``v_prev = (|z - z_p| - d0) / (t - t_p + tau)``, ``v_next`` likewise (m/s);
    * ``a_chord = 2 (e - d0) / ((t - t_p + tau)(t_n - t + tau))`` (m/s^2), where ``e`` is
      the distance from ``z`` to the straight line between ``z_p`` and ``z_n`` at time
      ``t``: the smallest constant acceleration that takes a vessel from the chord out to
      the report and back;

    with the noise allowance ``d0 = n_sigma sqrt(2) sigma_pos`` and the timestamp
    resolution ``tau`` (so that only reports implausible under the most generous reading
    of the timestamps and noise score high). Compiled, vessel by vessel on all threads.
    """
    n = t.size
    v_prev, v_next, a_chord = np.empty(n), np.empty(n), np.empty(n)
    if n:
        _plausibility_kernel(
            *vessel_rows(vessel, t, xy, accepted),
            *_allowances(config)[:2],
            v_prev,
            v_next,
            a_chord,
        )
    return v_prev, v_next, a_chord


def _allowances(cfg: AisTrackerConfig) -> tuple[float, float, float, float]:
    """Noise allowance ``d0`` (m), timestamp resolution (s), largest speed (m/s) and
    acceleration (m/s^2) of the plausibility tests."""
    d0 = cfg.n_sigma * math.sqrt(2.0) * cfg.sigma_pos_m
    return d0, cfg.time_resolution_s, cfg.max_speed_kn * KNOT_MPS, cfg.max_accel_mps2


@njit(cache=True, nogil=True)
def _vessel_plausibility(
    a, b, t, z, accepted, d0, tau, v_prev, v_next, a_chord, nxt
):  # pragma: no cover - compiled
    """:func:`neighbour_plausibility` of the rows ``a..b-1`` of one vessel; ``nxt``
    (scratch of ``b - a``) receives the next accepted row after each row (-1: none)."""
    n_idx = -1
    for i in range(b - 1, a - 1, -1):
        nxt[i - a] = n_idx
        if accepted[i]:
            n_idx = i
    p = -1  # the previous accepted row
    for i in range(a, b):
        nn = nxt[i - a]
        dtp = t[i] - t[p] + tau if p >= 0 else 1.0
        dtn = t[nn] - t[i] + tau if nn >= 0 else 1.0
        v_prev[i] = np.nan
        v_next[i] = np.nan
        a_chord[i] = np.nan
        if p >= 0:
            v_prev[i] = (math.hypot(z[i, 0] - z[p, 0], z[i, 1] - z[p, 1]) - d0) / dtp
        if nn >= 0:
            v_next[i] = (math.hypot(z[nn, 0] - z[i, 0], z[nn, 1] - z[i, 1]) - d0) / dtn
        if p >= 0 and nn >= 0:
            span = t[nn] - t[p]
            w = (t[i] - t[p]) / span if span > 0 else 0.5
            cx = z[p, 0] + w * (z[nn, 0] - z[p, 0])
            cy = z[p, 1] + w * (z[nn, 1] - z[p, 1])
            e = math.hypot(z[i, 0] - cx, z[i, 1] - cy)
            a_chord[i] = 2.0 * (e - d0) / (dtp * dtn)
        if accepted[i]:
            p = i


@njit(cache=True, nogil=True, parallel=True)
def _plausibility_kernel(
    starts, chunks, t, z, accepted, d0, tau, v_prev, v_next, a_chord
):  # pragma: no cover - compiled
    for c in prange(chunks.size - 1):
        size = largest_vessel(starts, chunks, c)
        nxt = np.empty(size, dtype=np.int64)
        for v in range(chunks[c], chunks[c + 1]):
            a, b = starts[v], starts[v + 1]
            _vessel_plausibility(a, b, t, z, accepted, d0, tau, v_prev, v_next, a_chord, nxt)


@njit(cache=True, inline="always")
def _fmax(x, y):  # pragma: no cover - compiled
    """``np.fmax`` of scalars (a NaN loses)."""
    if x != x:
        return y
    if y != y:
        return x
    return x if x >= y else y


@njit(cache=True, nogil=True)
def _revisit_vessel(
    a, b, t, z, use, flag, segment, force, par, acc, rej, score, vp, vn, ac, nxt
):  # pragma: no cover - compiled
    """One revisit pass over the vessel on rows ``a..b-1`` (see :func:`revisit`): sets
    ``force`` of the revised reports; returns whether any was revised. The other arguments
    are scratch arrays of at least ``b - a`` values."""
    d0, tau, vmax, amax = par
    m = b - a
    for k in range(m):
        acc[k] = use[a + k] and flag[a + k] == OutlierKind.NONE
    _vessel_plausibility(0, m, t[a:b], z[a:b], acc, d0, tau, vp, vn, ac, nxt)
    for k in range(m):
        i = a + k
        bad = vp[k] > vmax or vn[k] > vmax or ac[k] > amax
        rej[k] = acc[k] and bad and segment[i] >= 0 and force[i] == Force.FREE
        score[k] = _fmax(_fmax(vp[k] / vmax, vn[k] / vmax), ac[k] / amax)
    new = False
    p = -1
    for k in range(m):
        i = a + k
        nn = nxt[k]
        gross = (
            flag[i] == OutlierKind.IMPLAUSIBLE_JUMP or flag[i] == OutlierKind.IMPLAUSIBLE_AFTER_GAP
        )
        bad = vp[k] > vmax or vn[k] > vmax or ac[k] > amax
        # of adjacent accepted reports that are implausible together (a glitch and the
        # report after it), only the worst one is rejected in this pass: the other is
        # judged again against its new neighbours in the next pass
        beaten = (p >= 0 and rej[p] and score[p] >= score[k]) or (
            nn >= 0 and rej[nn] and score[nn] > score[k]
        )
        if gross and not bad and force[i] == Force.FREE:
            force[i] = Force.ACCEPT
            new = True
        elif rej[k] and not beaten:
            force[i] = Force.REJECT
            new = True
        if acc[k]:
            p = k
    return new


@njit(cache=True, nogil=True, parallel=True)
def _revisit_kernel(
    starts, chunks, t, z, use, flag, segment, force, par, changed
):  # pragma: no cover - compiled
    for c in prange(chunks.size - 1):
        size = largest_vessel(starts, chunks, c)
        acc, rej = np.empty(size, np.bool_), np.empty(size, np.bool_)
        score, vp, vn, ac = np.empty(size), np.empty(size), np.empty(size), np.empty(size)
        nxt = np.empty(size, dtype=np.int64)
        for v in range(chunks[c], chunks[c + 1]):
            changed[v] = _revisit_vessel(
                starts[v],
                starts[v + 1],
                t,
                z,
                use,
                flag,
                segment,
                force,
                par,
                acc,
                rej,
                score,
                vp,
                vn,
                ac,
                nxt,
            )


def _revisit_once(
    rows: KernelInputs, out: KernelOutputs, cfg: AisTrackerConfig
) -> NDArray[np.bool_]:
    """One revisit pass: sets ``rows.force`` of the revised reports (an outlier plausible
    on both sides is accepted, an accepted report implausible on a side rejected; a
    decision is revised at most once, so the passes end); returns the rows of the vessels
    with a revised report."""
    starts = rows.starts
    chunks = thread_chunks(starts)
    changed = np.zeros(starts.size - 1, dtype=np.bool_)
    if rows.t.size:
        _revisit_kernel(
            starts,
            chunks,
            rows.t,
            np.ascontiguousarray(rows.z),
            rows.use,
            out.kind,
            out.segment,
            rows.force,
            _allowances(cfg),
            changed,
        )
    return np.repeat(changed, np.diff(starts))


def revisit(rows: KernelInputs, out: KernelOutputs, cfg: AisTrackerConfig) -> None:
    """Up to ``revisit_passes`` passes revisiting the causal decisions with the future
    (two-sided neighbour test): outliers plausible on both sides are accepted and accepted
    reports that are implausible are rejected; the vessels concerned are filtered again.
    Updates ``rows.force`` and ``out`` in place."""
    for _ in range(cfg.revisit_passes):
        redo = _revisit_once(rows, out, cfg)
        if not redo.any():
            break
        merge_outputs(out, redo, run_kernel(take_rows(rows, redo), cfg))
