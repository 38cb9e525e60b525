"""Merging per-hypothesis track states (the JPDA update) by moment matching.

JPDA updates each track once per association hypothesis (each gated plot, and the miss),
then replaces the mixture by one Gaussian with the same first two moments::

    x = sum_h w_h x_h,      P = sum_h w_h (P_h + (x_h - x)(x_h - x)^T)

This works for any filter on the contract whose state components are linear quantities
(positions, velocities, turn rate, accelerations...). Everything else of the state -- the
``aux`` fields (e.g. the model probabilities and model states of an IMM), the status, NIS
and likelihood -- is taken from the dominant hypothesis. A filter that knows better (angle
components, nested mixtures) provides its own ``merge(states, weights, owner, n)`` method
with the signature of :func:`merge_hypotheses`, and is used instead.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack.filters.base import TrackState

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["merge_hypotheses", "moment_match"]


def moment_match(
    x: FloatArray, P: FloatArray, w: FloatArray, owner: IntArray, n: int
) -> tuple[FloatArray, FloatArray]:
    """Mean ``(n, k)`` and covariance ``(n, k, k)`` of the weighted mixture of each owner.

    ``x (H, k)``, ``P (H, k, k)``, ``w (H,)`` (normalised here per owner), ``owner (H,)`` in
    ``0..n-1``; every owner needs at least one hypothesis.
    """
    order = np.argsort(owner, kind="stable")
    o = owner[order]
    starts = np.searchsorted(o, np.arange(n))
    if o.size == 0 or np.any(np.diff(np.append(starts, o.size)) == 0):
        raise ValueError("every track needs at least one hypothesis")
    ww, xx = w[order], x[order]
    wn = ww / np.add.reduceat(ww, starts)[o]
    mean = np.add.reduceat(wn[:, None] * xx, starts, axis=0)
    dx = xx - mean[o]
    spread = wn[:, None, None] * (P[order] + dx[:, :, None] * dx[:, None, :])
    cov = np.add.reduceat(spread, starts, axis=0)
    return mean, 0.5 * (cov + np.swapaxes(cov, -1, -2))


def _dominant(w: FloatArray, owner: IntArray, n: int) -> IntArray:
    order = np.lexsort((-w, owner))
    first = np.ones(order.size, bool)
    first[1:] = owner[order][1:] != owner[order][:-1]
    out = np.empty(n, np.int64)
    out[owner[order][first]] = order[first]
    return out


def merge_hypotheses(
    flt: Any, states: TrackState, weights: FloatArray, owner: IntArray, n: int
) -> TrackState:
    """One state per track from its weighted hypotheses.

    Parameters
    ----------
    flt : the filter; its own ``merge`` is used when it has one
    states : (H,) hypothesis states (e.g. updated with each gated plot, and the prediction)
    weights : (H,) association probabilities (normalised per track here)
    owner : (H,) track index ``0..n-1`` of each hypothesis
    n : number of tracks (each must own at least one hypothesis)

    Returns
    -------
    TrackState of ``n`` tracks: moment-matched ``x`` and ``P``, the rest from each track's
    dominant hypothesis.
    """
    own = getattr(flt, "merge", None)
    if callable(own):
        return own(states, weights, owner, n)  # type: ignore[no-any-return]
    x, P = moment_match(states.x, states.P, weights, owner, n)
    return states.take(_dominant(weights, owner, n)).replace(x=x, P=P)
