"""Compiled scan of the multiple-model filter (spec ``multimodel.md`` steps 1-11).

:func:`step_kernel` is a ``numba.guvectorize`` kernel: one scan of one track, broadcast over
any leading (batch) dimensions. Each step of the spec is a small compiled function here;
:mod:`seatrack.filters.multimodel` documents the maths and holds the filter objects.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from seatrack.filters.imm import markov_predict_core
from seatrack.jit import gufunc
from seatrack.kalman import cholesky_core
from seatrack.kalman import forward_core
from seatrack.kalman import matmul_core
from seatrack.kalman import sym_matmul_core
from seatrack.kalman import update_core

__all__ = ["step_kernel", "mahalanobis"]

_LOG_2PI = math.log(2.0 * math.pi)


@njit(cache=True)
def mahalanobis(L, y):  # pragma: no cover - compiled
    """``y^T (L L^T)^-1 y`` by forward substitution."""
    w = np.empty(y.shape[0])
    forward_core(L, y, w)
    acc = 0.0
    for i in range(y.shape[0]):
        acc += w[i] * w[i]
    return acc


@njit(cache=True)
def _common_prediction(x, P, T, Q, gam, xc, Pb):  # pragma: no cover - compiled
    """Step 1: ``xc = Phi x`` and ``Pb = Phi P Phi^T + Gamma Q Gamma^T`` (symmetrised)."""
    n = x.shape[0]
    d = n // 2
    for i in range(d):
        xc[i] = x[i] + T * x[i + d]
        xc[i + d] = x[i + d]
    FP = np.empty((n, n))
    for j in range(n):
        for i in range(d):
            FP[i, j] = P[i, j] + T * P[i + d, j]
            FP[i + d, j] = P[i + d, j]
    for i in range(n):
        for j in range(d):
            Pb[i, j] = FP[i, j] + T * FP[i, j + d]
            Pb[i, j + d] = FP[i, j + d]
    for i in range(n):
        for j in range(n):
            Pb[i, j] += gam[i] * gam[j] * Q[i % d, j % d]
    for i in range(n):
        for j in range(i + 1, n):
            v = 0.5 * (Pb[i, j] + Pb[j, i])
            Pb[i, j] = v
            Pb[j, i] = v


@njit(cache=True)
def _spread(w, alphas, u, C):  # pragma: no cover - compiled
    """Mean ``u = sum_a w_a alpha_a`` and spread ``C = sum_a w_a (alpha_a - u)(..)^T``."""
    N, d = alphas.shape
    for i in range(d):
        u[i] = 0.0
        for j in range(d):
            C[i, j] = 0.0
    for a in range(N):
        for i in range(d):
            u[i] += w[a] * alphas[a, i]
    for a in range(N):
        for i in range(d):
            for j in range(d):
                C[i, j] += w[a] * (alphas[a, i] - u[i]) * (alphas[a, j] - u[j])


@njit(cache=True)
def _integrated_prediction(xc, Pb, beta, pi, alphas, gam, integ, bm, xp, Pp):  # pragma: no cover
    """Step 4 prior ``bm = pi beta`` and steps 10-11: integrated prediction ``xp``, ``Pp``."""
    n = xc.shape[0]
    N, d = alphas.shape
    markov_predict_core(pi.T, beta, bm)  # pi is column-stochastic
    um = np.empty(d)
    Cm = np.empty((d, d))
    _spread(bm, alphas, um, Cm)
    for i in range(n):
        xp[i] = xc[i] + gam[i] * um[i % d]
        for j in range(n):
            Pp[i, j] = Pb[i, j] + integ * gam[i] * gam[j] * Cm[i % d, j % d]


@njit(cache=True)
def _range_rate_loglik(
    a, xc, Pb, Z, L, rho, srr2, spos, svel, alphas, T, use_rr, h, c, wc, wy, y
):  # pragma: no cover - compiled
    """Step 3 for hypothesis ``a``: ``log f^D_a`` (``use_rr == 2``: conditioned on the
    position innovation, the exact joint likelihood)."""
    n = xc.shape[0]
    d = n // 2
    T2 = 0.5 * T * T
    Rh2 = 0.0
    pv = 0.0
    for i in range(d):
        p_i = xc[i] + T2 * alphas[a, i] - spos[i]
        v_i = xc[i + d] + T * alphas[a, i] - svel[i]
        Rh2 += p_i * p_i
        pv += p_i * v_i
    Rh = math.sqrt(Rh2)
    rhohat = pv / Rh
    for i in range(d):
        p_i = xc[i] + T2 * alphas[a, i] - spos[i]
        v_i = xc[i + d] + T * alphas[a, i] - svel[i]
        h[i] = (v_i - rhohat * p_i / Rh) / Rh
        h[i + d] = p_i / Rh
    s = srr2
    for i in range(n):
        hi = 0.0
        for j in range(n):
            hi += Pb[i, j] * h[j]
        s += h[i] * hi
        if i < d:
            c[i] = hi  # (H Pbar h^T)_i
    e = rho - rhohat
    if use_rr == 2.0:  # joint: condition the range rate on the position innovation
        for i in range(d):
            y[i] = Z[i] - xc[i] - T2 * alphas[a, i]
        forward_core(L, c, wc)
        forward_core(L, y, wy)
        for i in range(d):
            e -= wc[i] * wy[i]
            s -= wc[i] * wc[i]
    return -0.5 * (e * e / s + math.log(2.0 * math.pi * s))


@njit(cache=True)
def _reliabilities(lw, bm, bo):  # pragma: no cover - compiled
    """Step 4: ``beta_a ∝ exp(lw_a) bm_a`` by log-sum-exp; returns the log normaliser."""
    N = lw.shape[0]
    for a in range(N):
        lw[a] += math.log(bm[a]) if bm[a] > 0.0 else -np.inf
    mx = -np.inf
    for a in range(N):
        if lw[a] > mx:
            mx = lw[a]
    if mx > -np.inf and math.isfinite(mx):
        s = 0.0
        for a in range(N):
            s += math.exp(lw[a] - mx)
        lse = mx + math.log(s)
        for a in range(N):
            bo[a] = math.exp(lw[a] - lse)
        return lse
    for a in range(N):  # every likelihood is exactly zero even in log space: no information
        bo[a] = bm[a]
    return -np.inf


@njit(cache=True)
def _common_update(xc, Pb, Z, R, bo, alphas, gam, T2, integ, xo, Po):  # pragma: no cover
    """Steps 5-8: common gain, ``x(+)`` with the reliability-weighted input, integrated
    ``P(+)`` (Joseph form through :func:`seatrack.kalman.update_core`)."""
    n = xc.shape[0]
    N, d = alphas.shape
    H = np.zeros((d, n))
    for i in range(d):
        H[i, i] = 1.0
    yc = np.empty(d)
    for i in range(d):
        yc[i] = Z[i] - xc[i]
    So = np.empty((d, d))
    K = np.empty((n, d))
    update_core(xc, Pb, yc, H, R, xo, Po, So, K)  # xo = Phi x + K (Z - H Phi x)
    u = np.empty(d)
    C = np.empty((d, d))
    _spread(bo, alphas, u, C)
    G = np.empty((n, d))  # (I - KH) Gamma'
    for i in range(n):
        for j in range(d):
            G[i, j] = (gam[i] if i % d == j else 0.0) - K[i, j] * T2
    for i in range(n):
        s = 0.0
        for j in range(d):
            s += G[i, j] * u[j]
        xo[i] += s
    if integ == 0.0:
        return
    GC = np.empty((n, d))
    matmul_core(G, C, GC)
    sym_matmul_core(GC, G.T, Po, Po)  # Po += G C G^T (Po exactly symmetric)


@njit(cache=True)
def _copy_prediction(bm, xp, Pp, bo, xo, Po):  # pragma: no cover - compiled
    n = xp.shape[0]
    for a in range(bm.shape[0]):
        bo[a] = bm[a]
    for i in range(n):
        xo[i] = xp[i]
        for j in range(n):
            Po[i, j] = Pp[i, j]


@njit(cache=True)
def step_core(
    x, P, beta, T, Z, R, rho, srr2, spos, svel, alphas, pi, Q, use_rr, integ, xo, Po, bo, xp, Pp
):  # pragma: no cover - compiled
    """One scan of the spec's processing order; returns ``(log_likelihood, nis)``."""
    n = x.shape[0]
    d = n // 2
    N = alphas.shape[0]
    T2 = 0.5 * T * T
    gam = np.empty(n)  # Gamma = Gamma' = [T^2/2 I; T I] (diagonal blocks)
    for i in range(d):
        gam[i] = T2
        gam[i + d] = T
    xc = np.empty(n)
    Pb = np.empty((n, n))
    _common_prediction(x, P, T, Q, gam, xc, Pb)
    bm = np.empty(N)
    _integrated_prediction(xc, Pb, beta, pi, alphas, gam, integ, bm, xp, Pp)
    have_z = True
    for i in range(d):
        if not math.isfinite(Z[i]):
            have_z = False
    if not have_z:  # no plot: pure prediction
        _copy_prediction(bm, xp, Pp, bo, xo, Po)
        return np.nan, np.nan
    # step 2: S = H Pbar H^T + R and the position log-likelihoods
    S = np.empty((d, d))
    for i in range(d):
        for j in range(d):
            S[i, j] = Pb[i, j] + 0.5 * (R[i, j] + R[j, i])
    L = np.empty((d, d))
    logdet = cholesky_core(S, L)
    if not math.isfinite(logdet):
        for i in range(n):
            xo[i] = np.nan
        return np.nan, np.nan
    lw = np.empty(N)
    y = np.empty(d)
    for a in range(N):
        for i in range(d):
            y[i] = Z[i] - xc[i] - T2 * alphas[a, i]
        lw[a] = -0.5 * (mahalanobis(L, y) + logdet + d * _LOG_2PI)
    # step 3: range-rate log-likelihoods, h^a evaluated at x^a(-) relative to the sensor
    if use_rr != 0.0 and math.isfinite(rho):
        h = np.empty(n)
        c = np.empty(d)
        wc = np.empty(d)
        wy = np.empty(d)
        for a in range(N):
            lw[a] += _range_rate_loglik(
                a, xc, Pb, Z, L, rho, srr2, spos, svel, alphas, T, use_rr, h, c, wc, wy, y
            )
    lse = _reliabilities(lw, bm, bo)
    _common_update(xc, Pb, Z, R, bo, alphas, gam, T2, integ, xo, Po)
    # consistency statistic: plot against the integrated prediction
    for i in range(d):
        y[i] = Z[i] - xp[i]
        for j in range(d):
            S[i, j] = Pp[i, j] + 0.5 * (R[i, j] + R[j, i])
    nis = mahalanobis(L, y) if math.isfinite(cholesky_core(S, L)) else np.nan
    return lse, nis


@gufunc(
    "void(f8[:], f8[:,:], f8[:], f8, f8[:], f8[:,:], f8, f8, f8[:], f8[:], f8[:,:], f8[:,:],"
    " f8[:,:], f8, f8, f8[:], f8[:,:], f8[:], f8[:], f8[:,:], f8[:], f8[:])",
    "(n),(n,n),(N),(),(d),(d,d),(),(),(d),(d),(N,d),(N,N),(d,d),(),()"
    "->(n),(n,n),(N),(n),(n,n),(),()",
)
def step_kernel(
    x, P, beta, T, Z, R, rho, srr2, spos, svel, alphas, pi, Q, use_rr, integ,
    xo, Po, bo, xp, Pp, ll, nis,
):  # fmt: skip  # pragma: no cover - compiled
    """Broadcast :func:`step_core` over leading dimensions."""
    a, b = step_core(
        x, P, beta, T, Z, R, rho, srr2, spos, svel, alphas, pi, Q, use_rr, integ, xo, Po, bo, xp, Pp
    )
    ll[0] = a
    nis[0] = b
