"""Two-sided physical plausibility of AIS reports and the revisit passes that use it.

The kernel decides causally (a report against the past). A revisit pass judges each report
against its accepted neighbours on both sides (:func:`neighbour_plausibility`): an outlier
that is plausible on both sides is accepted, an accepted report that is implausible is
rejected, and the vessels concerned are filtered again (:func:`revisit`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.kernel import (
    Force,
    KernelInputs,
    KernelOutputs,
    OutlierKind,
    run_kernel,
)
from seatrack.geometry import KNOT_MPS

FloatArray = NDArray[np.float64]

__all__ = ["Rows", "neighbours", "neighbour_plausibility", "revisit", "merge_outputs", "run_rows"]


@dataclass(frozen=True)
class Rows:
    """The kernel's inputs with the vessel id of each row, rows sorted by (vessel, time):
    time (s), position (m), use, SOG/COG velocity (m/s, zero where unknown) and whether
    known, SOG (m/s), COG (rad), report noise ``(sigma_pos, sigma_time)``, decisions
    ``force`` (:class:`~seatrack.filters.ais.kernel.Force`), offsets (s)."""

    vessel: NDArray[np.int64]
    t: FloatArray
    z: FloatArray
    use: NDArray[np.bool_]
    v0: FloatArray
    known: NDArray[np.bool_]
    sog: FloatArray
    cog: FloatArray
    sig: FloatArray
    force: NDArray[np.int8]
    toff: FloatArray

    def take(self, rows: NDArray[np.bool_], **new: NDArray) -> Rows:
        """The rows ``rows`` (whole vessels), with fields replaced by ``new`` (full length)."""
        fields = {k: new.get(k, getattr(self, k))[rows] for k in self.__dataclass_fields__}
        return Rows(**fields)

    def kernel_inputs(self) -> KernelInputs:
        """:class:`KernelInputs` (vessel boundaries from the sorted vessel ids)."""
        vs = self.vessel
        starts = np.flatnonzero(np.r_[True, vs[1:] != vs[:-1], True]).astype(np.int64)
        if vs.size == 0:
            starts = np.zeros(1, dtype=np.int64)
        return KernelInputs(
            starts,
            self.t,
            self.z,
            self.use,
            self.force,
            self.v0,
            self.known,
            self.sog,
            self.cog,
            self.sig,
            self.toff,
        )


def run_rows(rows: Rows, cfg: AisTrackerConfig) -> KernelOutputs:
    """:func:`~seatrack.filters.ais.kernel.run_kernel` over ``rows``."""
    return run_kernel(rows.kernel_inputs(), cfg)


def merge_outputs(out: KernelOutputs, rows: NDArray[np.bool_], new: KernelOutputs) -> None:
    """Write kernel outputs ``new`` of the rows ``rows`` into ``out``; their segment ids are
    moved past those of ``out`` so that ids stay unique."""
    seg = new.segment
    seg[:] = np.where(seg >= 0, seg + int(out.segment.max(initial=0)) + 1, -1)
    for a_out, a_new in zip(out, new, strict=True):
        np.asarray(a_out)[rows] = a_new


def neighbours(
    vessel: NDArray[np.int64], accepted: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.bool_], NDArray[np.bool_]]:
    """Nearest *other* accepted row of the same vessel before / after every row (rows sorted
    by (vessel, time)): indices ``prev``, ``next`` (0 where none) and their masks."""
    n = vessel.size
    pos = np.arange(n)
    acc_idx = np.where(accepted, pos, -1)
    # previous accepted strictly before: shift the running max by one
    prev = np.maximum.accumulate(np.r_[-1, acc_idx[:-1]]) if n else acc_idx
    nxt_src = np.where(accepted, pos, n)
    nxt = np.minimum.accumulate(np.r_[nxt_src[1:], n][::-1])[::-1] if n else nxt_src
    has_p = prev >= 0
    has_p[has_p] &= vessel[prev[has_p]] == vessel[has_p]
    has_n = nxt < n
    has_n[has_n] &= vessel[nxt[has_n]] == vessel[has_n]
    return np.where(has_p, prev, 0), np.where(has_n, nxt, 0), has_p, has_n


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
    of the timestamps and noise score high).
    """
    ip, inn, has_p, has_n = neighbours(vessel, accepted)
    d0 = config.n_sigma * math.sqrt(2.0) * config.sigma_pos_m
    tau = config.time_resolution_s
    dtp = t - t[ip] + tau
    dtn = t[inn] - t + tau
    dtp = np.where(has_p, dtp, 1.0)
    dtn = np.where(has_n, dtn, 1.0)
    v_prev = np.where(has_p, (np.hypot(*(xy - xy[ip]).T) - d0) / dtp, np.nan)
    v_next = np.where(has_n, (np.hypot(*(xy[inn] - xy).T) - d0) / dtn, np.nan)
    span = t[inn] - t[ip]
    w = np.where(span > 0, (t - t[ip]) / np.where(span > 0, span, 1.0), 0.5)
    chord = xy[ip] + w[:, None] * (xy[inn] - xy[ip])
    e = np.hypot(*(xy - chord).T)
    a_chord = np.where(has_p & has_n, 2.0 * (e - d0) / (dtp * dtn), np.nan)
    return v_prev, v_next, a_chord


def _revisit_once(rows: Rows, out: KernelOutputs, cfg: AisTrackerConfig) -> NDArray[np.bool_]:
    """One revisit pass: sets ``rows.force`` of the revised reports; returns them."""
    vs, force = rows.vessel, rows.force
    vmax = cfg.max_speed_kn * KNOT_MPS
    flag = out.kind
    accepted = rows.use & (flag == OutlierKind.NONE)
    v_prev, v_next, a_chord = neighbour_plausibility(vs, rows.t, rows.z, accepted, cfg)
    bad = (v_prev > vmax) | (v_next > vmax) | (a_chord > cfg.max_accel_mps2)
    free = force == Force.FREE  # a decision is revised at most once, so the loop ends
    gross = (flag == OutlierKind.IMPLAUSIBLE_JUMP) | (flag == OutlierKind.IMPLAUSIBLE_AFTER_GAP)
    acc = gross & ~bad & free
    rej = accepted & bad & (out.segment >= 0) & free
    # of adjacent accepted reports that are implausible together (a glitch and the report
    # after it), reject only the worst one in this pass: the other is judged again against
    # its new neighbours in the next pass
    score = np.fmax(np.fmax(v_prev / vmax, v_next / vmax), a_chord / cfg.max_accel_mps2)
    ip, inn, has_p, has_n = neighbours(vs, accepted)
    beaten_prev = has_p & rej[ip] & (score[ip] >= score)
    beaten_next = has_n & rej[inn] & (score[inn] > score)
    rej &= ~(beaten_prev | beaten_next)
    force[acc] = Force.ACCEPT
    force[rej] = Force.REJECT
    return acc | rej


def revisit(rows: Rows, out: KernelOutputs, cfg: AisTrackerConfig) -> None:
    """Up to ``revisit_passes`` passes revisiting the causal decisions with the future
    (two-sided neighbour test): outliers plausible on both sides are accepted and accepted
    reports that are implausible are rejected; the vessels concerned are filtered again.
    Updates ``rows.force`` and ``out`` in place."""
    for _ in range(cfg.revisit_passes):
        new = _revisit_once(rows, out, cfg)
        if not new.any():
            break
        redo = np.isin(rows.vessel, np.unique(rows.vessel[new]))
        merge_outputs(out, redo, run_rows(rows.take(redo), cfg))
