"""Compiled Rauch-Tung-Striebel smoother of the AIS tracker (BLK 8.6), written out for the
5-state (no BLAS calls), and the 1-sigma of the derived quantities of a state."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from seatrack.filters.ais.config import NX

__all__ = ["derived_std", "rts_step", "smooth_segment"]


@njit(cache=True)
def derived_std(x, P, out_std):  # pragma: no cover - compiled
    """1-sigma of x, y, speed, course and turn rate from the state covariance (linearised)."""
    out_std[0] = math.sqrt(max(P[0, 0], 0.0))
    out_std[1] = math.sqrt(max(P[1, 1], 0.0))
    vx, vy = x[2], x[3]
    s2 = vx * vx + vy * vy
    if s2 > 1e-12:
        s = math.sqrt(s2)
        ux, uy = vx / s, vy / s
        out_std[2] = math.sqrt(
            max(ux * ux * P[2, 2] + 2 * ux * uy * P[2, 3] + uy * uy * P[3, 3], 0)
        )
        # course = atan2(vx, vy): d/dvx = vy/s^2, d/dvy = -vx/s^2
        gx, gy = vy / s2, -vx / s2
        out_std[3] = math.sqrt(
            max(gx * gx * P[2, 2] + 2 * gx * gy * P[2, 3] + gy * gy * P[3, 3], 0)
        )
    else:
        out_std[2] = math.sqrt(max(0.5 * (P[2, 2] + P[3, 3]), 0.0))
        out_std[3] = math.pi  # course undefined at rest
    out_std[4] = math.sqrt(max(P[4, 4], 0.0))


@njit(cache=True)
def rts_step(xf, Pf, F, xp, Pp, xs_n, Ps_n, xs, Ps, A, L, X, D):  # pragma: no cover
    """One RTS step (BLK 8.6): ``C = Pf F^T Pp^-1``, ``xs = xf + C (xs_n - xp)``,
    ``Ps = Pf + C (Ps_n - Pp) C^T``; ``C^T`` solved from ``Pp C^T = F Pf`` by Cholesky.
    Small fixed-size loops (no BLAS calls: 5x5 matrices)."""
    n = NX
    for i in range(n):  # A = F Pf
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += F[i, k] * Pf[k, j]
            A[i, j] = acc
    for j in range(n):  # Pp = L L^T
        d = Pp[j, j]
        for k in range(j):
            d -= L[j, k] * L[j, k]
        d = math.sqrt(max(d, 1e-300))
        L[j, j] = d
        for i in range(j + 1, n):
            acc = Pp[i, j]
            for k in range(j):
                acc -= L[i, k] * L[j, k]
            L[i, j] = acc / d
    for c in range(n):  # X = Pp^-1 A  (X = C^T)
        for i in range(n):
            acc = A[i, c]
            for k in range(i):
                acc -= L[i, k] * X[k, c]
            X[i, c] = acc / L[i, i]
        for i in range(n - 1, -1, -1):
            acc = X[i, c]
            for k in range(i + 1, n):
                acc -= L[k, i] * X[k, c]
            X[i, c] = acc / L[i, i]
    for i in range(n):  # xs = xf + C (xs_n - xp),  C[i, k] = X[k, i]
        acc = xf[i]
        for k in range(n):
            acc += X[k, i] * (xs_n[k] - xp[k])
        xs[i] = acc
    for i in range(n):  # D = C (Ps_n - Pp)
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += X[k, i] * (Ps_n[k, j] - Pp[k, j])
            D[i, j] = acc
    for i in range(n):  # Ps = Pf + D C^T (symmetric)
        for j in range(i, n):
            acc = 0.0
            for k in range(n):
                acc += D[i, k] * X[k, j]
            v = 0.5 * (Pf[i, j] + Pf[j, i]) + acc
            Ps[i, j] = v
            Ps[j, i] = v


@njit(cache=True)
def smooth_segment(k0, k1, xp, Pp, Fk, xf, Pf, xs, Ps, has, smooth):  # pragma: no cover
    """RTS smoother over the scratch rows ``k0..k1`` (inclusive) that have a state; the
    next row of row ``k`` is the next one with a state (BLK 8.6)."""
    kn = k1
    while kn >= k0 and not has[kn]:
        kn -= 1
    if kn < k0:
        return
    xs[kn] = xf[kn]
    Ps[kn] = Pf[kn]
    A = np.empty((NX, NX))
    L = np.zeros((NX, NX))
    X = np.empty((NX, NX))
    D = np.empty((NX, NX))
    for k in range(kn - 1, k0 - 1, -1):
        if not has[k]:
            continue
        if smooth:
            rts_step(xf[k], Pf[k], Fk[kn], xp[kn], Pp[kn], xs[kn], Ps[kn], xs[k], Ps[k], A, L, X, D)
        else:
            xs[k] = xf[k]
            Ps[k] = Pf[k]
        kn = k
