"""Refinement pass of the AIS tracker: timestamp offsets, noise without the outliers, and a
per-vessel choice between a steady and a manoeuvring process noise.

The pass is a :class:`Refinement` driven in steps, because the prior of the timestamp
offsets is estimated from *all* vessels together: a table split into vessel groups (bounded
memory, processes, a Dask cluster) runs each step on every group and estimates the prior
between steps from the counts of all groups (:func:`drive`), which gives the same result as
one table. :func:`refine_pass` drives one table, :func:`refine_groups` groups in memory.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from collections.abc import Sequence
from dataclasses import replace
from typing import Any
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.ais.config import AisTrackerConfig
from seatrack.filters.ais.kernel import Force
from seatrack.filters.ais.kernel import KernelInputs
from seatrack.filters.ais.kernel import KernelOutputs
from seatrack.filters.ais.kernel import OutlierKind
from seatrack.filters.ais.kernel import run_kernel
from seatrack.filters.ais.kernel import take_rows
from seatrack.filters.ais.kernel import vessel_index
from seatrack.filters.ais.noise import position_noise
from seatrack.filters.ais.offsets import OffsetInputs
from seatrack.filters.ais.offsets import OffsetScores
from seatrack.filters.ais.offsets import apply_offsets
from seatrack.filters.ais.offsets import estimate_prior
from seatrack.filters.ais.offsets import prior_counts
from seatrack.filters.ais.offsets import std_offset_scores
from seatrack.filters.ais.plausibility import merge_outputs

FloatArray = NDArray[np.float64]

__all__ = [
    "GroupRunner",
    "InMemory",
    "Refinement",
    "drive",
    "n_ident",
    "refine_groups",
    "refine_pass",
]


class Refinement:
    """The refinement pass of one vessel group (rows sorted by (vessel, time); ``out`` =
    the kernel outputs of the passes before, whose outlier decisions are kept).

    1. Offsets of the accepted reports from the track ``out`` (smoothed residuals,
       :meth:`scores` then :meth:`seed`): a first estimate that seeds step 3.
    2. Report noise re-estimated from the accepted reports only (:func:`position_noise`;
       the first estimate also saw the outliers); for vessels with offsets on the corrected
       times, with the timestamp-sigma floor ``sigma_time_fine_s``.
    3. All vessels filtered with the steady acceleration PSD ``q_accel_steady`` and the
       offsets in the measurement model; the offsets estimated again from that track
       (leave-one-out residuals; the steady track follows single glitches less) -- this
       estimate decides whether the data show offsets at all -- up to ``offset_passes``
       times (:meth:`update`), re-filtering the vessels whose
       offsets changed (noise re-estimated).
    4. All vessels filtered with ``q_accel`` and the same offsets (:meth:`finish`); per
       vessel, the track (``q_accel`` or ``q_accel_steady``) whose reports have the larger
       prediction log-likelihood is kept (steady ships vs manoeuvring craft).
    """

    #: the attributes holding per-row arrays (what a runner may hold elsewhere, see
    #: :meth:`__getattr__`), and of those the ones the steps replace or change (all
    #: four whenever :attr:`version` grows)
    PARTS = ("rows", "out", "alt", "sig_f", "off", "current")
    STATE = ("alt", "sig_f", "off", "current")
    #: set by a runner holding the parts elsewhere (see :meth:`__getattr__`)
    load_part: Callable[[str], Any]

    def __init__(self, rows: KernelInputs, out: KernelOutputs, cfg: AisTrackerConfig) -> None:
        self.rows, self.out, self.cfg = rows, out, cfg
        self.usable = rows.use & (out.kind == OutlierKind.NONE) & (out.segment >= 0)
        self.starts = rows.starts
        self.force_f = rows.force.copy()
        self.force_f[self.usable] = Force.ACCEPT  # the decisions of the passes before
        self.force_f[rows.use & (out.kind == OutlierKind.IMPLAUSIBLE_JUMP)] = Force.REJECT
        self.steady = replace(cfg, q_accel=cfg.q_accel_steady or cfg.q_accel)
        #: grows with every step that changes the state (offsets, noise, tracks, scores)
        self.version = 0
        # set by seed (the first track and noise before)
        self.alt: KernelOutputs | None = None
        self.sig_f: FloatArray | None = None
        self.off: FloatArray | None = None
        # first estimate from the (manoeuvring, coarse-noise) track: the smoothed residual
        first = OffsetInputs(rows.z, out.state, rows.sig, np.zeros(rows.t.size), self.usable)
        self.current = std_offset_scores(first, out.std, cfg, leave_one_out=False)

    def __getattr__(self, name: str) -> Any:
        """A part of :attr:`PARTS` held elsewhere: a runner that keeps the parts of many
        groups in files deletes the attributes and sets ``load_part(name)``, which this
        calls on first use."""
        load = self.__dict__.get("load_part")
        if load is None or name not in self.PARTS:
            raise AttributeError(name)
        value = load(name)
        setattr(self, name, value)
        return value

    def scores(self) -> OffsetScores:
        """The offset scores whose prior the next step needs."""
        return self.current

    def _per_vessel(self, mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """Rows of the vessels with any row in ``mask``."""
        if mask.size == 0:
            return mask
        return np.repeat(np.logical_or.reduceat(mask, self.starts[:-1]), np.diff(self.starts))

    def _noise(self) -> FloatArray:
        """Report noise again, from the accepted reports only and, for vessels with
        offsets, on the corrected times."""
        cfg, rows, off = self.cfg, self.rows, self.off
        assert off is not None
        moved = self._per_vessel(off != 0.0)
        if cfg.estimate_noise:
            fine = replace(cfg, sigma_time_min_s=cfg.sigma_time_fine_s)
            sig_f = position_noise(
                vessel_index(rows.starts), rows.t - off, rows.z, self.usable, fine
            )
            sig_f[:, 1] = np.where(moved, np.minimum(sig_f[:, 1], rows.sig[:, 1]), rows.sig[:, 1])
        else:
            sig_f = rows.sig.copy()
            sig_f[moved, 1] = cfg.sigma_time_fine_s
        return sig_f

    def _run(self, sub: NDArray[np.bool_] | None, c: AisTrackerConfig) -> KernelOutputs:
        """The kernel over the vessels of the rows ``sub`` (None: all) with the refined
        noise, decisions and offsets."""
        assert self.sig_f is not None and self.off is not None
        rows = take_rows(self.rows, sub, sig=self.sig_f, force=self.force_f, toff=self.off)
        return run_kernel(rows, c)

    def _loo_scores(self) -> OffsetScores:
        """Leave-one-out offset scores from the steady track."""
        alt = self.alt
        assert alt is not None and self.sig_f is not None and self.off is not None
        inputs = OffsetInputs(self.rows.z, alt.state, self.sig_f, self.off, self.usable)
        return std_offset_scores(inputs, alt.std, self.cfg)

    def seed(self, prior: FloatArray | None) -> None:
        """Steps 1-3: seed offsets under ``prior``, noise, the steady track and its
        leave-one-out scores."""
        self.off = apply_offsets(self.current, prior, self.cfg)
        self.sig_f = self._noise()
        self.alt = self._run(None, self.steady)
        self.current = self._loo_scores()
        self.version += 1

    def update(self, prior: FloatArray | None, more: bool) -> bool:
        """Offsets again under ``prior``; the vessels whose offsets changed are filtered
        again (noise re-estimated); ``more``: another offset pass follows (its scores are
        computed). Returns True if any offset changed."""
        new = apply_offsets(self.current, prior, self.cfg)
        again = self._per_vessel(new != self.off)
        if not again.any():
            return False
        self.off = new
        self.sig_f = self._noise()
        assert self.alt is not None
        merge_outputs(self.alt, again, self._run(again, self.steady))
        if more:
            self.current = self._loo_scores()
        self.version += 1
        return True

    def finish(self) -> tuple[KernelOutputs, FloatArray]:
        """Step 4; returns the kernel outputs and the offsets (s) of every row."""
        cfg, alt, off = self.cfg, self.alt, self.off
        assert alt is not None and off is not None, "finish() before seed()"
        inv_v, nv = vessel_index(self.starts), self.starts.size - 1
        # vessels the steady model fits badly (mean NIS above steady_nis_ratio x its 2 dof)
        # are filtered with q_accel too; per vessel the track whose reports have the larger
        # prediction log-likelihood is kept
        fin = np.isfinite(alt.nis)
        n_fin = np.maximum(np.bincount(inv_v[fin], None, nv), 1)
        mean_nis = np.bincount(inv_v[fin], alt.nis[fin], nv) / n_fin
        cand = (mean_nis > 2.0 * cfg.steady_nis_ratio)[inv_v]
        if cfg.q_accel_steady > 0 and cand.any():
            # the q_accel track: the passes before for vessels without offsets (same model
            # but for the noise estimate), else filtered again with the offsets
            hi = KernelOutputs._make(a.copy() for a in self.out)
            moved = self._per_vessel(off != 0.0)
            if (cand & moved).any():
                merge_outputs(hi, cand & moved, self._run(cand & moved, cfg))
            fin = cand & np.isfinite(hi.loglik) & np.isfinite(alt.loglik)
            ll = np.bincount(inv_v[fin], hi.loglik[fin], nv)
            ll_alt = np.bincount(inv_v[fin], alt.loglik[fin], nv)
            take = cand & (ll > ll_alt)[inv_v]
            merge_outputs(alt, take, KernelOutputs._make(a[take] for a in hi))
        return alt, off


class GroupRunner(Protocol):
    """Vessel groups whose :class:`Refinement` states are held somewhere (memory, spill
    files, a cluster): :meth:`each` calls a function on every state (which it keeps, with
    any change) and returns the results in group order; :meth:`counts` is the sum of
    :func:`prior_counts` of the current scores of all groups under a prior."""

    def each(self, f: Callable[[Refinement], Any]) -> list[Any]: ...

    def counts(self, prior: FloatArray) -> NDArray[np.int64]: ...

    def n_ident(self) -> int: ...


class InMemory:
    """:class:`GroupRunner` of states held in a list."""

    def __init__(self, groups: Sequence[Refinement]) -> None:
        self.groups = list(groups)

    def each(self, f: Callable[[Refinement], Any]) -> list[Any]:
        return [f(g) for g in self.groups]

    def counts(self, prior: FloatArray) -> NDArray[np.int64]:
        parts = [prior_counts(g.scores(), prior) for g in self.groups]
        return np.sum(np.asarray(parts, dtype=np.int64).reshape(len(parts), -1), axis=0)

    def n_ident(self) -> int:
        return sum(n_ident(g) for g in self.groups)


def n_ident(r: Refinement) -> int:
    """Number of identifiable reports of a group's current scores."""
    return int(np.count_nonzero(r.scores().ident))


def drive(groups: GroupRunner, cfg: AisTrackerConfig) -> None:
    """Run the refinement pass on vessel groups, step by step (not the last step,
    :meth:`Refinement.finish`). Between steps the offset prior is estimated from the integer
    counts of all groups (:func:`estimate_prior`), so the result is that of one table."""

    def prior() -> FloatArray | None:
        return estimate_prior(groups.counts, groups.n_ident(), cfg)

    groups.each(functools.partial(Refinement.seed, prior=prior()))
    for k in range(cfg.offset_passes):
        step = functools.partial(Refinement.update, prior=prior(), more=k + 1 < cfg.offset_passes)
        if not any(groups.each(step)):
            break


def refine_pass(
    rows: KernelInputs, out: KernelOutputs, cfg: AisTrackerConfig
) -> tuple[KernelOutputs, FloatArray]:
    """The refinement pass over one table (see :class:`Refinement`)."""
    ref = Refinement(rows, out, cfg)
    drive(InMemory([ref]), cfg)
    return ref.finish()


def refine_groups(
    groups: Sequence[Refinement], cfg: AisTrackerConfig
) -> list[tuple[KernelOutputs, FloatArray]]:
    """The refinement pass over vessel groups held in memory (same result as one table)."""
    drive(InMemory(groups), cfg)
    return [g.finish() for g in groups]
