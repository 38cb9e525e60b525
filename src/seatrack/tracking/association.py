"""Association of gated track-plot pairs: global nearest neighbour and exact JPDA.

Both work on the candidate pairs of :mod:`seatrack.tracking.gating`, each with a log
likelihood ratio ``l_ij = log(Pd g_ij / lambda)`` (``g_ij`` the innovation density of plot
``j`` under track ``i``, ``lambda`` the clutter density in the same measurement space)
against the track's miss weight ``l_i0 = log(1 - Pd Pg)``.

* **GNN** (:func:`gnn`): the joint assignment -- each track takes at most one plot, each
  plot at most one track -- that maximises ``sum l_ij`` over assigned pairs plus
  ``sum l_i0`` over unassigned tracks. A pair with ``l_ij <= l_i0`` is never worth
  assigning and is dropped. One compiled pass (:func:`gnn`) finds the clusters of tracks
  that share plots (union-find); a track alone takes its best plot, a cluster is solved
  exactly as a dense rectangular assignment of its tracks to its plots plus one "no plot"
  column per track, by the shortest augmenting path method (Crouse 2016, the algorithm of
  :func:`scipy.optimize.linear_sum_assignment`), with costs ``-(l_ij - l_i0)`` and 0.
* **JPDA** (:func:`jpda`): the marginal association probabilities ``beta_ij`` and
  ``beta_i0`` over every feasible joint event (each plot used at most once) of a cluster
  of interacting tracks, the event weight being the product of its ``exp(l)``. Tracks
  sharing no plot reduce to PDA in closed form (vectorised). Clusters are solved exactly by
  a forward-backward pass over the tracks whose nodes are the sets of already-used plots
  that later tracks can still see (the "efficient hypothesis management" net of Maskell,
  Briers & Wright 2004), so the work grows with the overlap, not with the number of joint
  events; a cluster whose net would exceed ``max_nodes`` nodes per level falls back to
  per-track PDA and is counted.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["components", "contested", "gnn", "jpda", "JpdaResult", "group_logsumexp"]


def components(
    track: IntArray, plot: IntArray, n_tracks: int, n_plots: int
) -> tuple[IntArray, IntArray, int]:
    """Connected components of the bipartite graph of pairs: labels of tracks, of plots."""
    g = coo_matrix(
        (np.ones(track.size), (track, plot + n_tracks)),
        shape=(n_tracks + n_plots, n_tracks + n_plots),
    )
    k, label = connected_components(g, directed=False)
    return label[:n_tracks].astype(np.int64), label[n_tracks:].astype(np.int64), int(k)


def contested(track: IntArray, plot: IntArray, n_tracks: int, n_plots: int) -> NDArray[np.bool_]:
    """Per pair: does its track share some plot with another track (directly or through a
    chain)? Pairs that are not contested can be decided track by track."""
    shared = np.bincount(plot, minlength=n_plots) >= 2
    hot = np.zeros(n_tracks, bool)
    hot[track[shared[plot]]] = True
    return hot[track]


def _groups(owner: IntArray, n: int) -> tuple[IntArray, IntArray]:
    order = np.argsort(owner, kind="stable")
    return order, np.searchsorted(owner[order], np.arange(n + 1))


def group_logsumexp(values: FloatArray, owner: IntArray, n: int, base: FloatArray) -> FloatArray:
    """``log(exp(base_i) + sum_{owner_k = i} exp(values_k))`` for ``i < n`` (stable)."""
    mx = base.copy()
    np.maximum.at(mx, owner, values)
    s = np.exp(base - mx) + np.bincount(owner, np.exp(values - mx[owner]), minlength=n)
    return np.asarray(mx + np.log(s))


# ---------------------------------------------------------------------------
# Global nearest neighbour
# ---------------------------------------------------------------------------
def gnn(track: IntArray, plot: IntArray, gain: FloatArray, n_tracks: int, n_plots: int) -> IntArray:
    """Best joint assignment: plot index of each track (-1: none).

    Parameters
    ----------
    track, plot : (K,) candidate pairs
    gain : (K,) -- ``l_ij - l_i0``: how much better assigning the pair is than a miss
    n_tracks, n_plots : sizes of the batch and the scan
    """
    out = np.full(n_tracks, -1, np.int64)
    keep = gain > 0
    if keep.any():
        _gnn_kernel(
            np.ascontiguousarray(track[keep], dtype=np.int64),
            np.ascontiguousarray(plot[keep], dtype=np.int64),
            np.ascontiguousarray(gain[keep], dtype=np.float64),
            n_tracks,
            n_plots,
            out,
        )
    return out


@njit(cache=True)
def _find(parent, a):  # pragma: no cover - compiled
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


@njit(cache=True)
def _gnn_kernel(track, plot, gain, n_tracks, n_plots, out):  # pragma: no cover - compiled
    """Clusters by union-find, then the best plot of lone tracks and an exact dense
    assignment of every cluster (see :func:`gnn`)."""
    K = track.size
    parent = np.arange(n_tracks + n_plots)
    for k in range(K):
        a = _find(parent, track[k])
        b = _find(parent, n_tracks + plot[k])
        if a != b:
            parent[b] = a
    root = np.empty(K, np.int64)
    for k in range(K):
        root[k] = _find(parent, track[k])
    order = np.argsort(root, kind="mergesort")
    row = np.full(n_tracks, -1, np.int64)  # local row of a track in its cluster
    col = np.full(n_plots, -1, np.int64)
    start = 0
    while start < K:
        stop = start
        while stop < K and root[order[stop]] == root[order[start]]:
            stop += 1
        nt = 0
        npl = 0
        for q in range(start, stop):
            k = order[q]
            if row[track[k]] < 0:
                row[track[k]] = nt
                nt += 1
            if col[plot[k]] < 0:
                col[plot[k]] = npl
                npl += 1
        if nt == 1:  # a lone track: its best plot
            best = order[start]
            for q in range(start + 1, stop):
                if gain[order[q]] > gain[best]:
                    best = order[q]
            out[track[best]] = plot[best]
        else:
            C = np.full((nt, npl + nt), np.inf)
            C[:, npl:] = 0.0
            rows = np.empty(nt, np.int64)
            cols = np.empty(npl, np.int64)
            for q in range(start, stop):
                k = order[q]
                C[row[track[k]], col[plot[k]]] = -gain[k]
                rows[row[track[k]]] = track[k]
                cols[col[plot[k]]] = plot[k]
            c4r = _lap(C)
            for i in range(nt):
                if c4r[i] < npl:
                    out[rows[i]] = cols[c4r[i]]
        for q in range(start, stop):  # reset the local maps
            row[track[order[q]]] = -1
            col[plot[order[q]]] = -1
        start = stop


@njit(cache=True)
def _lap(C):  # pragma: no cover - compiled
    """Minimum-cost assignment of every row of ``C (nr, nc)``, ``nr <= nc`` (``inf``:
    forbidden; a feasible assignment must exist): the column of each row. Shortest
    augmenting paths with dual variables (Crouse 2016)."""
    nr, nc = C.shape
    u = np.zeros(nr)
    v = np.zeros(nc)
    shortest = np.empty(nc)
    path = np.full(nc, -1, np.int64)
    col4row = np.full(nr, -1, np.int64)
    row4col = np.full(nc, -1, np.int64)
    SR = np.zeros(nr, np.bool_)
    SC = np.zeros(nc, np.bool_)
    remaining = np.empty(nc, np.int64)
    for cur in range(nr):
        for j in range(nc):
            remaining[j] = nc - 1 - j
            shortest[j] = np.inf
            SC[j] = False
        SR[:] = False
        n_rem = nc
        min_val = 0.0
        i = cur
        sink = -1
        while sink == -1:
            index = -1
            lowest = np.inf
            SR[i] = True
            for it in range(n_rem):
                j = remaining[it]
                r = min_val + C[i, j] - u[i] - v[j]
                if r < shortest[j]:
                    path[j] = i
                    shortest[j] = r
                if shortest[j] < lowest or (shortest[j] == lowest and row4col[j] == -1):
                    lowest = shortest[j]
                    index = it
            min_val = lowest
            if index < 0 or min_val == np.inf:  # infeasible (cannot happen with dummies)
                return col4row
            j = remaining[index]
            if row4col[j] == -1:
                sink = j
            else:
                i = row4col[j]
            SC[j] = True
            n_rem -= 1
            remaining[index] = remaining[n_rem]
        u[cur] += min_val
        for i2 in range(nr):
            if SR[i2] and i2 != cur:
                u[i2] += min_val - shortest[col4row[i2]]
        for j in range(nc):
            if SC[j]:
                v[j] -= min_val - shortest[j]
        j = sink
        while True:
            i2 = path[j]
            row4col[j] = i2
            tmp = col4row[i2]
            col4row[i2] = j
            j = tmp
            if i2 == cur:
                break
    return col4row


# ---------------------------------------------------------------------------
# JPDA
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class JpdaResult:
    """Marginal association probabilities.

    Attributes
    ----------
    beta : (K,) -- probability that candidate pair k is the true association
    beta0 : (n_tracks,) -- probability that the track has no plot (missed or outside gate)
    fallbacks : clusters too large for the exact net, solved per track (PDA)
    """

    beta: FloatArray
    beta0: FloatArray
    fallbacks: int


def jpda(
    track: IntArray,
    plot: IntArray,
    log_lr: FloatArray,
    log_miss: FloatArray,
    n_plots: int,
    max_nodes: int = 20000,
) -> JpdaResult:
    """Exact JPDA marginals over clusters of interacting tracks.

    Parameters
    ----------
    track, plot : (K,) candidate pairs
    log_lr : (K,) -- ``log(Pd g / lambda)`` of each pair
    log_miss : (n_tracks,) -- ``log(1 - Pd Pg)`` of each track
    n_plots : plots in the scan
    max_nodes : largest net level of an exact cluster (larger clusters: per-track PDA)
    """
    n = log_miss.size
    lz = group_logsumexp(log_lr, track, n, log_miss)  # per-track PDA normaliser
    beta = np.exp(log_lr - lz[track])
    beta0 = np.exp(log_miss - lz)
    fallbacks = 0
    hot = contested(track, plot, n, n_plots)
    if hot.any():
        idx_hot = np.flatnonzero(hot)
        lt, _, k = components(track[hot], plot[hot], n, n_plots)
        order, bounds = _groups(lt[track[hot]], k)
        for q in range(k):
            idx = idx_hot[order[bounds[q] : bounds[q + 1]]]
            if idx.size == 0:
                continue
            res = _cluster_marginals(track[idx], plot[idx], log_lr[idx], log_miss, max_nodes)
            if res is None:
                fallbacks += 1
                continue
            b, b0, tracks = res
            beta[idx] = b
            beta0[tracks] = b0
    return JpdaResult(beta, beta0, fallbacks)


def _cluster_marginals(
    track: IntArray, plot: IntArray, log_lr: FloatArray, log_miss: FloatArray, max_nodes: int
) -> tuple[FloatArray, FloatArray, IntArray] | None:
    """Forward-backward over the tracks of one cluster (see the module docstring)."""
    ut, it = np.unique(track, return_inverse=True)
    _, ip = np.unique(plot, return_inverse=True)
    K = ut.size
    # options of each track: (pair index, plot bit, weight); weights scaled per track
    opts: list[list[tuple[int, int, float]]] = [[] for _ in range(K)]
    miss = np.empty(K)
    for k in range(K):
        sel = np.flatnonzero(it == k)
        top = max(float(log_miss[ut[k]]), float(log_lr[sel].max()))
        miss[k] = np.exp(log_miss[ut[k]] - top)
        opts[k] = [(int(s), 1 << int(ip[s]), float(np.exp(log_lr[s] - top))) for s in sel]
    masks = [0] * K
    for k in range(K):
        for _, bit, _ in opts[k]:
            masks[k] |= bit
    later = [0] * (K + 1)  # plots seen by tracks k..K-1
    for k in range(K - 1, -1, -1):
        later[k] = later[k + 1] | masks[k]
    # forward: alpha[k] maps node (used plots still relevant) -> weight
    alpha: list[dict[int, float]] = [{0: 1.0}]
    for k in range(K):
        nxt: defaultdict[int, float] = defaultdict(float)
        keep = later[k + 1]
        for u, a in alpha[k].items():
            nxt[u & keep] += a * miss[k]
            for _, bit, w in opts[k]:
                if not u & bit:
                    nxt[(u | bit) & keep] += a * w
        if len(nxt) > max_nodes:
            return None
        s = sum(nxt.values())
        alpha.append({u: v / s for u, v in nxt.items()})
    # backward
    beta_next: dict[int, float] = {0: 1.0}
    b = np.zeros(track.size)
    b0 = np.zeros(K)
    for k in range(K - 1, -1, -1):
        keep = later[k + 1]
        cur: dict[int, float] = {}
        acc_miss = 0.0
        acc = [0.0] * len(opts[k])
        for u, a in alpha[k].items():
            v_miss = miss[k] * beta_next.get(u & keep, 0.0)
            total = v_miss
            acc_miss += a * v_miss
            for o, (_, bit, w) in enumerate(opts[k]):
                if not u & bit:
                    v = w * beta_next.get((u | bit) & keep, 0.0)
                    acc[o] += a * v
                    total += v
            cur[u] = total
        z = acc_miss + sum(acc)
        b0[k] = acc_miss / z
        for o, (s, _, _) in enumerate(opts[k]):
            b[s] = acc[o] / z
        mx = max(cur.values())
        beta_next = {u: v / mx for u, v in cur.items()}
    return b, b0, ut
