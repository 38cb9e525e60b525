"""Run a recursive filter over every labelled track of a file, with gross errors gated.

:func:`run_tracks` is the driver of ``seatrack track`` (:func:`seatrack.filters.registry.run`):
step ``k`` processes the ``k``-th plot of every track that has one, as one batch through the
filter contract (:class:`~seatrack.filters.base.RecursiveFilter`).

Bad plots never break a track. A non-finite plot, or one whose update is not finite, is
REJECTED by the filter itself (:func:`~seatrack.filters.base.finish_update`). A finite but
absurd plot -- a range of a millimetre, or of 9,000 km, in a file of ships at 20 km -- is
numerically fine and would drag the track by its whole error times the gain (millions of
metres for tens of scans: measured on the ``benchmarks/track_methods.py`` file with 40 such
plots). With a ``gate``, the driver rejects a plot whose normalised innovation squared
against the prediction exceeds it and keeps the prediction (status REJECTED, its NIS
reported). A track that rejects ``restart_after`` plots in a row has lost its target (or a
wild first plot started it far away): it is started again on the last of them (INITIATED).

:data:`GROSS_NIS` (10^4: an innovation of 100 sigma) is the gate of every registered method
but the ``-spec`` ones (their sources have none): on the nine scenario families of
``benchmarks/defaults.py`` (12 runs each) no such method exceeds a NIS of 400 on clean or
20 %-contaminated plots except the plain fixed-q ``ekf`` / ``ekf-rb`` baselines on
aircraft and fighters, whose worst innovations there are lags of a diverging filter.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import FloatArray
from seatrack.filters.base import IntArray
from seatrack.filters.base import Plots
from seatrack.filters.base import PlotStatus
from seatrack.filters.base import RecursiveFilter
from seatrack.filters.base import TrackState
from seatrack.progress import Progress

__all__ = ["GROSS_NIS", "RESTART_AFTER", "run_tracks"]

#: normalised innovation squared above which a plot is a gross error (100 sigma)
GROSS_NIS = 1e4
#: gross errors in a row after which a track is started again on the last one
RESTART_AFTER = 3

Initiate = Callable[[Plots], tuple[FloatArray, FloatArray]]


def run_tracks(
    flt: RecursiveFilter,
    plots: Plots,
    track_index: IntArray,
    initiate: Initiate,
    gate: float = math.inf,
    restart_after: int = RESTART_AFTER,
    progress: Progress | None = None,
) -> dict[str, NDArray[Any]]:
    """Run ``flt`` over labelled tracks, all tracks as one batch per step.

    Parameters
    ----------
    flt : any :class:`~seatrack.filters.base.RecursiveFilter`.
    plots : all plots of a file; the plots of each track in time order.
    track_index : (N,) int -- track number ``0..T-1`` of each plot.
    initiate : plots -> Cartesian ``(x, P)`` of the first plot of each track
        (e.g. ``lambda p: plot_gaussian(p, sensor, speed_sigma)``).
    gate : normalised innovation squared above which a plot is rejected as a gross error
        (``inf``: none; :data:`GROSS_NIS` for the registered methods).
    restart_after : gross errors in a row after which the track starts again (>= 1).
    progress : told of the plots done before every step.

    Returns
    -------
    Output columns, one value per plot in the input order: ``flt.columns`` plus ``status``
    (a :class:`~seatrack.filters.base.PlotStatus` label) and ``nis``.
    """
    if restart_after < 1:
        raise ValueError(f"restart_after must be >= 1, got {restart_after}")
    N = len(plots)
    if N == 0:
        return {}
    ti = np.asarray(track_index, dtype=np.int64)
    T = int(ti.max()) + 1
    derive = getattr(flt, "derive", None)
    if derive is not None:  # state-independent per-plot quantities, once for the file
        plots = dataclasses.replace(plots, derived=derive(plots))
    # rank of each plot within its track (stable: input order)
    order = np.argsort(ti, kind="stable")
    starts = np.searchsorted(ti[order], np.arange(T))
    rank = np.empty(N, np.int64)
    rank[order] = np.arange(N) - starts[ti[order]]
    by_rank = np.argsort(rank, kind="stable")
    bounds = np.searchsorted(rank[by_rank], np.arange(int(rank.max()) + 2))
    out: dict[str, NDArray[Any]] = {}
    ids = np.arange(T)
    gross = np.zeros(T, np.int64)  # gross errors in a row, per track
    rows = by_rank[bounds[0] : bounds[1]]  # the first plot of every track
    state = _start(flt, initiate, plots.take(rows[np.argsort(ti[rows])]))
    _emit(flt, state, rows[np.argsort(ti[rows])], out, N)
    started = state.status == PlotStatus.INITIATED
    for k in range(1, bounds.size - 1):
        if progress is not None:
            progress.update(bounds[k])
        rows = by_rank[bounds[k] : bounds[k + 1]]
        tracks = ti[rows]
        pk = plots.take(rows)
        if tracks.size == T and started.all() and np.array_equal(tracks, ids):
            state = _step(flt, initiate, state, pk, gross, gate, restart_after)
            _emit(flt, state, rows, out, N)  # every track, in order
            continue
        new = ~started[tracks]
        if new.any():  # tracks whose start was rejected: start again on this plot
            s = _start(flt, initiate, pk.take(new))
            state = state.put(tracks[new], s)
            started[tracks[new]] = s.status == PlotStatus.INITIATED
            _emit(flt, s, rows[new], out, N)
        run = ~new
        if run.any():
            idx = tracks[run]
            g = gross[idx]
            s = _step(flt, initiate, state.take(idx), pk.take(run), g, gate, restart_after)
            gross[idx] = g
            state = state.put(idx, s)
            _emit(flt, s, rows[run], out, N)
    labels = np.array([s.label for s in PlotStatus])
    out["status"] = labels[out["status"]]
    return out


def _step(
    flt: RecursiveFilter,
    initiate: Initiate,
    state: TrackState,
    plots: Plots,
    gross: IntArray,
    gate: float,
    restart_after: int,
) -> TrackState:
    """Predict and update a batch on one plot each; plots beyond the ``gate`` are rejected
    (the prediction kept, their NIS reported), and a track with ``restart_after`` of them
    in a row starts again on its plot. ``gross`` (per track) is updated in place."""
    pred = flt.predict(state, plots.t)
    s = flt.update(pred, plots)
    bad = s.nis > gate  # NaN (rejected plots) compares False
    gross[:] = np.where(bad, gross + 1, np.where(s.status == PlotStatus.UPDATED, 0, gross))
    if not bad.any():
        return s
    status = np.full(len(s), PlotStatus.REJECTED, np.int8)
    kept = pred.replace(nis=s.nis, status=status)
    s = s.where(bad, kept)
    lost = gross >= restart_after
    if lost.any():
        fresh = _start(flt, initiate, plots.take(lost))
        ok = fresh.status == PlotStatus.INITIATED
        s = s.put(np.flatnonzero(lost)[ok], fresh.take(ok))
        gross[np.flatnonzero(lost)[ok]] = 0
    return s


def _start(flt: RecursiveFilter, initiate: Initiate, plots: Plots) -> TrackState:
    """Initiate tracks on plots; a plot that gives a non-finite start is REJECTED (the
    track starts on its next plot)."""
    with np.errstate(all="ignore"):
        x0, P0 = initiate(plots)
    s = flt.initiate(plots.t, x0, P0)
    ok = np.isfinite(s.x).all(-1) & np.isfinite(s.P).all((-1, -2))
    if ok.all():
        return s
    status = np.where(ok, PlotStatus.INITIATED, PlotStatus.REJECTED).astype(np.int8)
    return s.replace(status=status)


def _emit(
    flt: RecursiveFilter, s: TrackState, rows: IntArray, out: dict[str, NDArray[Any]], N: int
) -> None:
    """Write the output columns of batch ``s`` at ``rows``."""
    cols = flt.columns(s)
    cols["status"] = s.status
    cols["nis"] = s.nis
    for name, v in cols.items():
        arr = out.get(name)
        if arr is None:
            arr = out[name] = np.empty(N, dtype=np.asarray(v).dtype)
        arr[rows] = v
