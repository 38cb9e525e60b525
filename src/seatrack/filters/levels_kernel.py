"""Compiled kernels of the process-noise-level IMM (:mod:`seatrack.filters.levels`).

One scan of the level IMM for a whole batch of tracks is three calls:

* :func:`level_predict_core` -- IMM mixing, the constant-velocity prediction of every
  level with its PSD and the moment-matched combination;
* :func:`level_update_core` -- for every level: the polar ``h(x)`` and Jacobian, the
  wrapped innovation and the update of the level's rule (:class:`Rule`: the exact update
  under Gaussian or contaminated-Gaussian plot noise with its likelihood, algorithm R's
  robust variance, or the Huber / Student-t iteratively reweighted update);
* :func:`level_combine_core` -- the level probabilities in log space, the combination,
  the channel outlier scores and the NIS of the combined prediction.

The arithmetic is that of the NumPy composition they replace (:func:`mixture_core` is the
update of :func:`seatrack.filters.levels.mixture_update`; the mixing and combination are
:func:`seatrack.filters.imm.mix_core` and :func:`~seatrack.filters.imm.combine_core`; the
reweighting is :func:`seatrack.filters.robust_baselines.reweighted_update` with a
diagonal ``R``):
``tests/filters/test_levels_kernel.py`` checks them against it. A non-positive-definite
innovation covariance gives NaN, which the caller rejects.
"""

from __future__ import annotations

import math
from enum import IntEnum

import numpy as np
from numba import njit

from seatrack.filters.imm import combine_core
from seatrack.filters.imm import mix_core
from seatrack.kalman import cholesky_core
from seatrack.kalman import cholesky_m
from seatrack.kalman import forward_core
from seatrack.kalman import forward_m
from seatrack.kalman import matmul_core
from seatrack.kalman import wrap_angle
from seatrack.models.measurement import polar_core
from seatrack.models.measurement import sensor_frame_core
from seatrack.models.motion import along_track_core
from seatrack.models.motion import cv_predict_core

__all__ = [
    "Rule",
    "dims",
    "mixture_work",
    "mixture_item",
    "mixture_core",
    "level_predict_core",
    "level_update_core",
    "level_combine_core",
    "frame_innovation_core",
]

_LOG_2PI = math.log(2.0 * math.pi)


class Rule(IntEnum):
    """The measurement update of the levels (``rule`` of :func:`level_update_core`)."""

    MIXTURE = 0  #: exact update, Gaussian or contaminated-Gaussian plot noise
    RAMAZANOV = 1  #: algorithm R's robust variance; contaminated likelihood
    HUBER = 2  #: Huber IRLS with per-channel thresholds; contaminated likelihood
    STUDENT_T = 3  #: VB Student-t with per-channel degrees of freedom; contaminated likelihood


def dims(n: int, m: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Tuples of lengths ``n`` (state) and ``m`` (plot) for the kernels' ``tn``, ``tm``:
    numba compiles one specialisation per length, with the sizes as constants."""
    return (0.0,) * n, (0.0,) * m


@njit(cache=True)
def mixture_work(n, m, C):  # pragma: no cover - compiled
    """Scratch arrays of :func:`mixture_item` for states of size ``n``, ``m`` channels and
    ``C`` outlier patterns."""
    return (
        np.empty((n, m)),  # P H^T
        np.empty((m, m)),  # H P H^T
        np.empty((m, m)),  # S_g
        np.empty((m, m)),  # chol S_g
        np.empty((C, m, m)),  # S_g^-1
        np.empty((C, m)),  # u_g
        np.empty(C),  # log weights
        np.empty(m),
        np.empty(m),
        np.empty((m, m)),  # W
        np.empty((n, m)),  # P H^T W
    )


@njit(cache=True, inline="always")
def _hph_into(P, H, ws):  # pragma: no cover - compiled
    """``P H^T`` and ``H P H^T`` into the scratch ``ws`` of :func:`mixture_work`; returns
    the latter."""
    matmul_core(P, H.T, ws[0])
    matmul_core(H, ws[0], ws[1])
    return ws[1]


@njit(cache=True, inline="always")
def _innovation_factor(HPH, w, S, L, m):  # pragma: no cover - compiled
    """Cholesky factor ``L`` of the innovation covariance ``S = sym(H P H^T) + diag(w)``;
    returns ``log det S`` (NaN when not positive definite)."""
    for a in range(m):
        for c in range(m):
            S[a, c] = 0.5 * (HPH[a, c] + HPH[c, a])
        S[a, a] += w[a]
    return cholesky_m(S, L, m)


@njit(cache=True, inline="always")
def _pattern_factor(HPH, r, k, Gg, S, L, w, m):  # pragma: no cover - compiled
    """:func:`_innovation_factor` with the plot noise ``diag(r * k^Gg)`` of the outlier
    pattern ``Gg (m,)`` (``w``: scratch)."""
    for a in range(m):
        w[a] = r[a] * (k[a] if Gg[a] > 0.0 else 1.0)
    return _innovation_factor(HPH, w, S, L, m)


@njit(cache=True, inline="always")
def _log_sum_exp(lw):  # pragma: no cover - compiled
    """``log sum exp(lw)`` of a finite vector, shifted by its maximum."""
    top = lw.max()
    tot = 0.0
    for g in range(lw.size):
        tot += math.exp(lw[g] - top)
    return top + math.log(tot)


@njit(cache=True, inline="always")
def _correction(P, D, u, U, V, dx, Po, n, m):  # pragma: no cover - compiled
    """The state correction ``dx = D u`` and ``Po = P - U V^T`` (``n x m`` factors; the
    upper triangle computed and mirrored, so ``Po`` is exactly symmetric)."""
    for a in range(n):
        v = 0.0
        for c in range(m):
            v += D[a, c] * u[c]
        dx[a] = v
        for b in range(a, n):
            v = P[a, b]
            for c in range(m):
                v -= U[a, c] * V[b, c]
            Po[a, b] = v
            Po[b, a] = v


@njit(cache=True, inline="always")
def gauss_given(P, PHt, HPH, y, r, dx, Po, ws, tn, tm):  # pragma: no cover - compiled
    """The Kalman update of ``(x, P)`` on the innovation ``y`` with plot noise ``diag(r)``,
    given ``P H^T`` and ``H P H^T``: ``L L^T = S = sym(H P H^T) + diag(r)``,
    ``A = L^-1 H P``, ``dx = A^T L^-1 y``, ``Po = P - A^T A`` (upper triangle, mirrored).
    Returns the log-likelihood; NaN (``dx`` NaN, ``Po`` unset) when ``S`` is not positive
    definite. ``ws``: :func:`mixture_work` scratch (``S``, ``L``, ``u``, ``A`` slots)."""
    S, L, ub, A = ws[2], ws[3], ws[8], ws[10]
    n = len(tn)
    m = len(tm)
    logdet = _innovation_factor(HPH, r, S, L, m)
    if not logdet == logdet:
        for a in range(n):
            dx[a] = np.nan
        return np.nan
    forward_m(L, y, ub, m)
    q = 0.0
    for a in range(m):
        q += ub[a] * ub[a]
    for j in range(n):  # row j of A^T = L^-1 applied to row j of P H^T
        for a in range(m):
            v = PHt[j, a]
            for b in range(a):
                v -= L[a, b] * A[j, b]
            A[j, a] = v / L[a, a]
    _correction(P, A, ub, A, A, dx, Po, n, m)
    return -0.5 * (q + logdet + m * _LOG_2PI)


@njit(cache=True, inline="always")
def mixture_loglik(HPH, y, r, G, logp, k, pout, ws, tm):  # pragma: no cover - compiled
    """The log-likelihood and the posterior channel outlier probabilities ``pout`` of
    :func:`mixture_item`, without its update, given ``H P H^T``: per pattern one ``m x m``
    factorisation and one forward solve (``|L^-1 y|^2``), no inverse and no gain. NaN when
    an ``S_g`` is not positive definite (``pout`` unset)."""
    S, L, lw, e, ub = ws[2], ws[3], ws[6], ws[7], ws[8]
    m = len(tm)
    C = G.shape[0]
    for g in range(C):
        logdet = _pattern_factor(HPH, r, k, G[g], S, L, e, m)
        if not logdet == logdet:
            return np.nan
        forward_m(L, y, ub, m)
        q = 0.0
        for a in range(m):
            q += ub[a] * ub[a]
        lw[g] = logp[g] - 0.5 * (q + logdet + m * _LOG_2PI)
    lse = _log_sum_exp(lw)
    for a in range(m):
        pout[a] = 0.0
    for g in range(C):
        w = math.exp(lw[g] - lse)
        for a in range(m):
            pout[a] += w * G[g, a]
    return lse


@njit(cache=True)
def mixture_item(P, y, H, r, G, logp, k, dx, Po, pout, ws, tn, tm):  # pragma: no cover
    """:func:`mixture_given` with ``P H^T`` and ``H P H^T`` computed into ``ws``."""
    _hph_into(P, H, ws)
    return mixture_given(P, ws[0], ws[1], y, r, G, logp, k, dx, Po, pout, ws, tn, tm)


@njit(cache=True)
def mixture_given(P, PHt, HPH, y, r, G, logp, k, dx, Po, pout, ws, tn, tm):  # pragma: no cover
    """Update of one Gaussian ``(x, P)`` on the innovation ``y`` under plot noise that is,
    per pattern ``g``, ``N(0, diag(r * k^G_g))`` with prior ``exp(logp_g)``.

    With ``u_g = S_g^-1 y`` and weights ``w_g ∝ pi_g N(y; 0, S_g)`` the collapsed posterior
    is exactly ``x + P H^T u``, ``P - P H^T W H P`` with ``u = sum w_g u_g`` and
    ``W = sum w_g (S_g^-1 - (u_g - u)(u_g - u)^T)`` -- every pattern costs an ``m x m``
    factorisation only. Writes the state correction ``dx``, ``Po`` and the posterior
    outlier probability of each channel ``pout``; returns the log-likelihood. A
    non-positive-definite ``S_g`` gives NaN (``dx`` NaN, ``Po`` and ``pout`` unset).

    ``tn``, ``tm``: tuples of length ``n`` and ``m`` (:func:`dims`): the sizes are then
    compile-time constants and the small loops unrolled (a third of the time saved,
    measured on 200 levels, 8 patterns; the same arithmetic). A single pattern without
    outlier channels is the Kalman update :func:`gauss_given`.
    """
    C = G.shape[0]
    if C == 1 and G[0].max() == 0.0:
        for a in range(len(tm)):
            pout[a] = 0.0
        return gauss_given(P, PHt, HPH, y, r, dx, Po, ws, tn, tm)
    S, L, Si, u, lw, e, ub, W, PW = ws[2:]
    n = len(tn)
    m = len(tm)
    for g in range(C):
        logdet = _pattern_factor(HPH, r, k, G[g], S, L, e, m)
        if not logdet == logdet:
            for a in range(n):
                dx[a] = np.nan
            return np.nan
        for col in range(m):  # S^-1 column by column
            for a in range(m):
                e[a] = 1.0 if a == col else 0.0
            forward_m(L, e, ub, m)
            for a in range(m - 1, -1, -1):
                v = ub[a]
                for b in range(a + 1, m):
                    v -= L[b, a] * Si[g, b, col]
                Si[g, a, col] = v / L[a, a]
        q = 0.0
        for a in range(m):
            v = 0.0
            for b in range(m):
                v += Si[g, a, b] * y[b]
            u[g, a] = v
            q += y[a] * v
        lw[g] = logp[g] - 0.5 * (q + logdet + m * _LOG_2PI)
    lse = _log_sum_exp(lw)
    for a in range(m):
        ub[a] = 0.0
        pout[a] = 0.0
        for c in range(m):
            W[a, c] = 0.0
    for g in range(C):
        w = math.exp(lw[g] - lse)
        for a in range(m):
            ub[a] += w * u[g, a]
            pout[a] += w * G[g, a]
            for c in range(m):
                W[a, c] += w * (Si[g, a, c] - u[g, a] * u[g, c])
    for a in range(m):
        for c in range(m):
            W[a, c] += ub[a] * ub[c]
    matmul_core(PHt, W, PW)
    _correction(P, PHt, ub, PW, PHt, dx, Po, n, m)
    return lse


@njit(cache=True)
def mixture_core(P, y, H, r, G, logp, k, dx, Po, ll, pout, tn, tm):  # pragma: no cover
    """:func:`mixture_item` over a batch: ``P (N, n, n)``, ``y (N, m)``, ``H (N, m, n)``,
    ``r (N, m)``, ``logp (N, C)``; writes ``dx (N, n)``, ``Po``, ``ll (N,)``, ``pout``."""
    ws = mixture_work(dx.shape[1], y.shape[1], G.shape[0])
    for i in range(dx.shape[0]):
        ll[i] = mixture_item(P[i], y[i], H[i], r[i], G, logp[i], k, dx[i], Po[i], pout[i], ws,
                             tn, tm)  # fmt: skip


@njit(cache=True)
def level_predict_core(
    X, PP, mu, PI, q, F, Q1, xp, Pp, ratio, Xo, PPo, c, x, P
):  # pragma: no cover - compiled  # fmt: skip
    """Mixing, prediction and combination of level states ``X (B, M, n)``, ``PP`` with
    probabilities ``mu (B, M)``, transitions ``PI (B', M, M)``, PSDs ``q (B', M)`` and the
    unit-PSD CV pair ``F``, ``Q1 (B', n, n)`` (``B'`` is 1 or ``B``: a regular scan shares
    one). With ``ratio`` < 1 each track's white acceleration is shaped along / across the
    velocity of its combined estimate ``xp (B, n)``, ``Pp (B, n, n)``
    (:func:`seatrack.models.motion.along_track_core`): ``Q = q blk (x) A`` where
    ``Q1 = blk (x) I``. Writes the predicted levels ``Xo``, ``PPo``, probabilities ``c``
    and the combined ``x``, ``P``."""
    B, M, n = X.shape
    d = n // 2
    valid = np.ones((M, n))
    X0 = np.empty((M, n))
    P0 = np.empty((M, n, n))
    Q = np.empty((n, n))
    FP = np.empty((n, n))
    A = np.eye(d)
    zero = np.zeros(M)
    mu_c = np.empty(M)
    out = np.arange(n) * 1.0
    for b in range(B):
        bi = b if PI.shape[0] > 1 else 0
        bq = b if q.shape[0] > 1 else 0
        bf = b if F.shape[0] > 1 else 0
        mix_core(X[b], PP[b], mu[b], PI[bi], valid, X0, P0, c[b])
        if ratio < 1.0:
            along_track_core(xp[b, d:], Pp[b, d:, d:], ratio, A)
        for j in range(M):
            for a in range(n):
                for e in range(n):
                    blk = Q1[bf, (a // d) * d, (e // d) * d]
                    Q[a, e] = q[bq, j] * (blk * A[a % d, e % d])
            cv_predict_core(X0[j], P0[j], F[bf, 0, d], Q, Xo[b, j], PPo[b, j], FP, d)
        combine_core(Xo[b], PPo[b], c[b], zero, out, mu_c, x[b], P[b])


@njit(cache=True)
def _ramazanov(x, P, y, r, G, logp, k, par, xo, Po, o, ws, rw, tmp, tn, tm):  # pragma: no cover
    """Algorithm R's robust variance per channel, then the Gaussian update; returns the
    contaminated log-likelihood (nominal ``r``). ``par = [Delta_c]``; ``ws`` holds
    ``P H^T`` and ``H P H^T`` (:func:`_hph_into`)."""
    PHt, HPH = ws[0], ws[1]
    n = len(tn)
    m = len(tm)
    for a in range(m):
        y2 = y[a] * y[a]
        out = y2 / (HPH[a, a] + r[a]) > par[a]
        o[a] = 1.0 if out else 0.0
        rw[a] = y2 / par[a] - HPH[a, a] if out else r[a]
    gauss_given(P, PHt, HPH, y, rw, xo, Po, ws, tn, tm)
    for a in range(n):
        xo[a] = x[a] + xo[a]
    return mixture_loglik(HPH, y, r, G, logp, k, tmp, ws, tm)


@njit(cache=True)
def _measurement_step(M, y, w, e, hpo, S, L, t, v, tm):  # pragma: no cover - compiled
    """The residual ``e = y - M S^-1 y`` and ``hpo = diag(M - M S^-1 M)`` of a Kalman update
    with plot noise ``diag(w)``, ``S = M + diag(w)``, from ``M = H P H^T`` alone: the
    update's ``y - H dx`` and ``diag(H P+ H^T)`` without the state (``t``, ``v``: scratch);
    NaN when ``S`` is not positive definite; ``tm``: :func:`dims` (``m`` a constant)."""
    m = len(tm)
    logdet = _innovation_factor(M, w, S, L, m)
    if not logdet == logdet:  # not positive definite: the update is NaN, as mixture_item's
        for a in range(m):
            e[a] = np.nan
            hpo[a] = np.nan
        return
    for col in range(m + 1):  # S^-1 y, then S^-1 M[:, col - 1]
        for a in range(m):
            t[a] = y[a] if col == 0 else M[a, col - 1]
        forward_m(L, t, v, m)
        for a in range(m - 1, -1, -1):  # back substitution, L^T
            s = v[a]
            for b in range(a + 1, m):
                s -= L[b, a] * v[b]
            v[a] = s / L[a, a]
        if col == 0:
            for a in range(m):
                s = 0.0
                for b in range(m):
                    s += M[a, b] * v[b]
                e[a] = y[a] - s
        else:
            s = 0.0
            for b in range(m):
                s += M[b, col - 1] * v[b]
            hpo[col - 1] = M[col - 1, col - 1] - s


@njit(cache=True)
def _reweighted(x, P, y, r, rule, par, thr, xo, Po, ws, rw, e, tmp, dx, tn, tm):  # pragma: no cover
    """Huber IRLS (``rule`` HUBER, threshold ``thr[c]`` of each channel) or VB Student-t
    (STUDENT_T, ``thr[c]`` degrees of freedom) update with the nominal ``R = diag(r)``,
    ``par = [iterations]``; ``ws`` holds ``P H^T`` and ``H P H^T`` (:func:`_hph_into`).
    The iterations between the weights run in plot space (:func:`_measurement_step` on
    ``H P H^T``); only the last weights update the state."""
    n = len(tn)
    m = len(tm)
    huber = rule == 2
    iterations = int(par[0])
    M, S, L, t, v = ws[1], ws[2], ws[3], ws[7], ws[8]
    if huber:  # the first Huber weights come from the innovation itself
        for a in range(m):
            e[a] = y[a]
    else:  # the VB iteration starts at the plain update
        _measurement_step(M, y, r, e, tmp, S, L, t, v, tm)
    for it in range(iterations):
        if it > 0:
            _measurement_step(M, y, rw, e, tmp, S, L, t, v, tm)
        for a in range(m):
            # the variances r / w of the weights, written without dividing by a weight
            # (an infinite residual of a 1e308 plot makes it 0 and the variance infinite)
            if huber:  # w = min(1, c / |u|); a NaN residual stays NaN
                u = abs(e[a]) / math.sqrt(r[a])
                rw[a] = r[a] if u <= thr[a] else r[a] * (u / thr[a])
            else:  # w = (nu + 1) / (nu + E[e^2] / r)
                aa = (e[a] * e[a] + tmp[a]) / r[a]
                rw[a] = r[a] * ((thr[a] + aa) / (thr[a] + 1.0))
    gauss_given(P, ws[0], M, y, rw, dx, Po, ws, tn, tm)
    for a in range(n):
        xo[a] = x[a] + dx[a]


@njit(cache=True, inline="always")
def _plot_frame(
    Xb, sr, d, rr, zin, okb, nearb, r, angular, hx, H, zb, rb, wrap
):  # pragma: no cover
    """The predicted plots ``hx (M, m)`` and Jacobians ``H`` of the states ``Xb (M, n)``
    (sensor rows ``sr``), the plot ``zb`` in the same frame, its variances ``rb`` and the
    channels to wrap: polar (:func:`seatrack.models.measurement.polar_core`), or -- for a
    plot next to the sensor (``nearb``; :func:`seatrack.models.measurement.near_sensor`) --
    range, azimuth [and elevation] replaced by the linear position in the frame of the
    plot's direction (:func:`seatrack.models.measurement.sensor_frame_core`): the plot is
    ``[range, 0, (0)]``, the across variances ``(range^2 + sigma_r^2) cos^2(el) sigma_az^2``
    and ``(range^2 + sigma_r^2) sigma_el^2``. An unusable plot (``okb`` false) is replaced
    by the first state's prediction."""
    polar_core(Xb, sr, d, rr, hx, H)
    for a in range(zb.shape[0]):
        rb[a] = r[a]
        wrap[a] = angular[a] > 0.0
        h0 = hx[0, a]
        zb[a] = zin[a] if okb else (h0 if np.isfinite(h0) else 0.0)
    if nearb:
        el = zin[2] if d == 3 else 0.0
        sensor_frame_core(Xb, sr, d, zin[1], el, hx, H)
        spread = zin[0] * zin[0] + r[0]
        ce = math.cos(el)
        for a in range(1, d):
            zb[a] = 0.0
            wrap[a] = False
            rb[a] = spread * (ce * ce * r[1] if a == 1 else r[2])


@njit(cache=True, inline="always")
def _innovation_item(
    x, P, z, nearb, s, d, rr, angular, r, hx, H, y, HP, A, S, zb, rb, wrap
):  # pragma: no cover - compiled
    """The innovation ``y`` of plot ``z`` against the prediction ``(x, P)`` and its
    covariance ``S``, in the plot's frame (:func:`_plot_frame`; the other arguments:
    scratch)."""
    m = z.shape[0]
    n = x.shape[0]
    _plot_frame(x.reshape((1, n)), s.reshape((1, s.shape[0])), d, rr, z, True, nearb, r,
                angular, hx, H, zb, rb, wrap)  # fmt: skip
    for a in range(m):
        v = zb[a] - hx[0, a]
        y[a] = wrap_angle(v) if wrap[a] else v
    matmul_core(H[0], P, HP)
    matmul_core(HP, H[0].T, A)
    for a in range(m):
        A[a, a] += rb[a]
    for a in range(m):
        for c in range(m):
            S[a, c] = 0.5 * (A[a, c] + A[c, a])


@njit(cache=True)
def frame_innovation_core(x, P, z, near, s, d, rr, angular, r, Y, S):  # pragma: no cover
    """:func:`_innovation_item` over a batch: predictions ``x (B, n)``, ``P``, plots
    ``z (B, m)``, flags ``near (B,)``, sensors ``s (B, 2d)``; writes ``Y (B, m)`` and
    ``S (B, m, m)`` (the gating of :meth:`seatrack.filters.levels.LevelIMM.innovation`
    in the frame its update uses)."""
    B, n = x.shape
    m = z.shape[1]
    hx, H = np.empty((1, m)), np.empty((1, m, n))
    HP, A = np.empty((m, n)), np.empty((m, m))
    zb, rb, wrap = np.empty(m), np.empty(m), np.empty(m, np.bool_)
    for b in range(B):
        _innovation_item(x[b], P[b], z[b], near[b], s[b], d, rr, angular, r, hx, H, Y[b], HP, A,
                         S[b], zb, rb, wrap)  # fmt: skip


@njit(cache=True)
def _nis(
    x, P, z, nearb, s, d, rr, angular, r, hx, H, y, HP, A, S, L, w, zb, rb, wrap
):  # pragma: no cover
    """``y^T S^-1 y`` of plot ``z`` against the combined prediction ``(x, P)``, in the
    plot's frame (:func:`_innovation_item`; the other arguments: scratch)."""
    m = z.shape[0]
    _innovation_item(x, P, z, nearb, s, d, rr, angular, r, hx, H, y, HP, A, S, zb, rb, wrap)
    logdet = cholesky_core(S, L)
    if not logdet == logdet:  # NaN: not positive definite
        return np.nan
    forward_core(L, y, w)
    acc = 0.0
    for a in range(m):
        acc += w[a] * w[a]
    return acc


@njit(cache=True)
def level_update_core(
    X, PP, z, ok, near, s, d, rr, angular, r, rule, G, logp, k, par, thr, Xo, PPo, ll, o, Y, Hs,
    tn, tm,
):  # pragma: no cover - compiled  # fmt: skip
    """The update of every level of every track.

    Inputs: level states ``X (B, M, n)``, ``PP``; plots ``z (B, m)`` (range, azimuth,
    [elevation], [range rate]; rad, m/s) with ``ok (B,)`` false for unusable ones (they
    are updated on the level-0 prediction instead, without warnings; the caller rejects
    them) and ``near (B,)`` true for the plots next to the sensor (updated in the frame
    of their azimuth, :func:`_plot_frame`), sensor ``s (B, 2d)``; ``angular (m,)`` 1 for
    the wrapped channels; nominal variances ``r (m,)``; the ``rule`` (:class:`Rule`),
    outlier patterns ``G (C, m)`` with per-track log priors ``logp (B, C)`` (or one row
    ``(1, C)`` for all) and scales ``k (m,)``, the rule's parameters ``par`` and the Huber
    thresholds / Student-t degrees of freedom of each track's channels ``thr (B, m)`` (or
    one row for all; unused by the other rules); ``tn``, ``tm`` = :func:`dims`.

    Outputs: updated levels ``Xo``, ``PPo``, their log-likelihoods ``ll (B, M)`` (the
    contaminated-Gaussian one of the nominal ``r`` for every rule; zero for unusable
    plots), channel outlier scores ``o (B, M, m)`` (algorithm R's flags under RAMAZANOV,
    else the posterior outlier probabilities of the contaminated model), the wrapped
    innovations ``Y (B, M, m)`` and the Jacobians ``Hs (B, M, m, n)``.
    """
    B, M, n = X.shape
    m = z.shape[1]
    ws = mixture_work(n, m, G.shape[0])
    hx = np.empty((M, m))
    sr = np.empty((M, s.shape[1]))
    zb = np.empty(m)
    rb = np.empty(m)
    wrap = np.empty(m, np.bool_)
    rw = np.empty(m)
    e = np.empty(m)
    tmp = np.empty(m)
    dx = np.empty(n)
    for b in range(B):
        lp = logp[b if logp.shape[0] > 1 else 0]
        th = thr[b if thr.shape[0] > 1 else 0]
        for j in range(M):
            sr[j] = s[b]
        H = Hs[b]
        _plot_frame(X[b], sr, d, rr, z[b], ok[b], near[b], r, angular, hx, H, zb, rb, wrap)
        for j in range(M):
            y = Y[b, j]
            for a in range(m):
                v = zb[a] - hx[j, a]
                y[a] = wrap_angle(v) if wrap[a] else v
            P = PP[b, j]
            _hph_into(P, H[j], ws)  # P H^T, H P H^T: shared by the rule and the likelihood
            if rule == 0:
                v = mixture_given(P, ws[0], ws[1], y, rb, G, lp, k, Xo[b, j], PPo[b, j], o[b, j],
                                  ws, tn, tm)  # fmt: skip
                for a in range(n):
                    Xo[b, j, a] = X[b, j, a] + Xo[b, j, a]
            elif rule == 1:
                v = _ramazanov(X[b, j], P, y, rb, G, lp, k, par, Xo[b, j], PPo[b, j], o[b, j], ws,
                               rw, tmp, tn, tm)  # fmt: skip
            else:
                _reweighted(X[b, j], P, y, rb, rule, par, th, Xo[b, j], PPo[b, j], ws, rw, e, tmp,
                            dx, tn, tm)  # fmt: skip
                # the contaminated likelihood and outlier probabilities (nominal r)
                v = mixture_loglik(ws[1], y, rb, G, lp, k, o[b, j], ws, tm)
            ll[b, j] = v if ok[b] else 0.0


@njit(cache=True)
def level_combine_core(
    Xo, PPo, mu, ll, o, ok, near, xp, Pp, z, s, d, rr, angular, r, muo, x, P, tot, outl, nis
):  # pragma: no cover - compiled  # fmt: skip
    """Level probabilities ``muo`` from the predicted ``mu (B, M)`` and the levels'
    log-likelihoods ``ll``, the combined ``x``, ``P`` of the updated levels ``Xo``, ``PPo``,
    the mixture log-likelihood ``tot (B,)``, the probability-weighted channel outlier
    scores ``outl (B, m)`` of ``o (B, M, m)`` and the NIS of plot ``z`` against the
    combined prediction ``xp``, ``Pp`` (NaN where not ``ok``); the other inputs as
    :func:`level_update_core`."""
    B, M, n = Xo.shape
    m = z.shape[1]
    out = np.arange(n) * 1.0
    hx = np.empty((1, m))
    H = np.empty((1, m, n))
    y = np.empty(m)
    HP, A, S, L, w = np.empty((m, n)), np.empty((m, m)), np.empty((m, m)), np.empty((m, m)), y * 0
    zb, rb, wrap = np.empty(m), np.empty(m), np.empty(m, np.bool_)
    for b in range(B):
        tot[b] = combine_core(Xo[b], PPo[b], mu[b], ll[b], out, muo[b], x[b], P[b])
        for a in range(m):
            v = 0.0
            for j in range(M):
                v += muo[b, j] * o[b, j, a]
            outl[b, a] = v
        if ok[b]:
            nis[b] = _nis(xp[b], Pp[b], z[b], near[b], s[b], d, rr, angular, r, hx, H, y, HP, A,
                          S, L, w, zb, rb, wrap)  # fmt: skip
        else:
            nis[b] = np.nan
