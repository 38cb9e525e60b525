"""Refinement pass of the AIS tracker: timestamp offsets, noise without the outliers, and a
per-vessel choice between a steady and a manoeuvring process noise."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.kernel import Force, KernelOutputs, OutlierKind
from seatrack.filters.ais.noise import position_noise
from seatrack.filters.ais.offsets import pos_cov, timestamp_offsets
from seatrack.filters.ais.plausibility import Rows, merge_outputs, run_rows

FloatArray = NDArray[np.float64]

__all__ = ["refine_pass"]


def refine_pass(
    rows: Rows, out: KernelOutputs, cfg: AisTrackerConfig
) -> tuple[KernelOutputs, FloatArray]:
    """Refinement pass: whole-second timestamp offsets, report noise without the outliers,
    and a per-vessel choice of process noise (rows sorted by (vessel, time); ``out`` = the
    kernel outputs of the passes before, whose outlier decisions are kept).

    1. Offsets of the accepted reports from the track ``out`` (:func:`timestamp_offsets`,
       smoothed residuals): a first estimate that seeds step 3.
    2. Report noise re-estimated from the accepted reports only (:func:`position_noise`;
       the first estimate also saw the outliers); for vessels with offsets on the corrected
       times, with the timestamp-sigma floor ``sigma_time_fine_s``.
    3. All vessels filtered with the steady acceleration PSD ``q_accel_steady`` and the
       offsets in the measurement model; the offsets estimated again from that track
       (leave-one-out residuals; the steady track follows single glitches less) -- this
       estimate decides whether the file shows offsets at all -- up to ``offset_passes``
       times, re-filtering the vessels whose offsets changed (noise re-estimated).
    4. All vessels filtered with ``q_accel`` and the same offsets; per vessel, the track
       (``q_accel`` or ``q_accel_steady``) whose reports have the larger prediction
       log-likelihood is kept (a two-model choice per vessel: steady ships vs manoeuvring
       craft).
    """
    vs, ts, zs, us, sig = rows.vessel, rows.t, rows.z, rows.use, rows.sig
    usable = us & (out.kind == OutlierKind.NONE) & (out.segment >= 0)
    # first estimate from the (manoeuvring, coarse-noise) track: the smoothed residual
    off = timestamp_offsets(
        zs, out.state, pos_cov(out.std), sig, np.zeros(ts.size), usable, cfg, leave_one_out=False
    )
    uv, inv_v = np.unique(vs, return_inverse=True)

    def per_vessel(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """Rows of the vessels with any row in ``mask``."""
        return (np.bincount(inv_v, mask, uv.size) > 0)[inv_v]

    def noise(off: FloatArray) -> FloatArray:
        """Report noise again, from the accepted reports only (the first estimate also
        saw the outliers) and, for vessels with offsets, on the corrected times."""
        moved = per_vessel(off != 0.0)
        if cfg.estimate_noise:
            fine = replace(cfg, sigma_time_min_s=cfg.sigma_time_fine_s)
            sig_f = position_noise(vs, ts - off, zs, usable, fine)
            sig_f[:, 1] = np.where(moved, np.minimum(sig_f[:, 1], sig[:, 1]), sig[:, 1])
        else:
            sig_f = sig.copy()
            sig_f[moved, 1] = cfg.sigma_time_fine_s
        return sig_f

    sig_f = noise(off)
    force_f = rows.force.copy()
    force_f[usable] = Force.ACCEPT  # the outlier decisions of the passes before are kept
    force_f[us & (out.kind == OutlierKind.IMPLAUSIBLE_JUMP)] = Force.REJECT

    def run(sub: NDArray[np.bool_], c: AisTrackerConfig) -> KernelOutputs:
        return run_rows(rows.take(sub, sig=sig_f, force=force_f, toff=off), c)

    steady = replace(cfg, q_accel=cfg.q_accel_steady or cfg.q_accel)
    alt = run(np.ones(ts.size, dtype=bool), steady)
    for _ in range(cfg.offset_passes):
        # offsets again from the steady track (it follows single glitches less; this
        # estimate, not the first, decides whether the file shows offsets at all)
        new = timestamp_offsets(zs, alt.state, pos_cov(alt.std), sig_f, off, usable, cfg)
        again = per_vessel(new != off)
        if not again.any():
            break
        off = new
        sig_f = noise(off)
        merge_outputs(alt, again, run(again, steady))
    # vessels the steady model fits badly (mean NIS above steady_nis_ratio x its 2 dof)
    # are filtered with q_accel too; per vessel the track whose reports have the larger
    # prediction log-likelihood is kept
    fin = np.isfinite(alt.nis)
    n_fin = np.maximum(np.bincount(inv_v[fin], None, uv.size), 1)
    mean_nis = np.bincount(inv_v[fin], alt.nis[fin], uv.size) / n_fin
    cand = (mean_nis > 2.0 * cfg.steady_nis_ratio)[inv_v]
    if cfg.q_accel_steady > 0 and cand.any():
        # the q_accel track: the passes before for vessels without offsets (same model
        # but for the noise estimate), else filtered again with the offsets
        hi = KernelOutputs(*(a.copy() for a in out))
        moved = per_vessel(off != 0.0)
        if (cand & moved).any():
            merge_outputs(hi, cand & moved, run(cand & moved, cfg))
        fin = cand & np.isfinite(hi.loglik) & np.isfinite(alt.loglik)
        ll = np.bincount(inv_v[fin], hi.loglik[fin], uv.size)
        ll_alt = np.bincount(inv_v[fin], alt.loglik[fin], uv.size)
        take = cand & (ll > ll_alt)[inv_v]
        merge_outputs(alt, take, KernelOutputs(*(a[take] for a in hi)))
    return alt, off
