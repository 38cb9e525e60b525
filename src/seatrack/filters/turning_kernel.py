"""Compiled S2-S5 of the turning-target filter for a batch of tracks (spec ``turning.md``).

One call per scan runs, for every track of the batch, the velocity significance, the
heading / turn-rate filter (wrapped heading innovation, Joseph-form update), the turn-rate
queue, the fuzzy vote and the noise gain -- the same steps as the pure functions of
:mod:`seatrack.filters.turning` and :mod:`seatrack.filters.heading`, which the tests
compare it with. Arrays are updated in place (the caller passes copies).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["turn_logic"]

_TWO_PI = 2.0 * math.pi


@njit(cache=True)
def _wrap(a):  # pragma: no cover - compiled
    """Angle to (-pi, pi] (as :func:`seatrack.geometry.wrap_pi`)."""
    w = a - _TWO_PI * math.floor((a + math.pi) / _TWO_PI)
    if w <= -math.pi:
        w += _TWO_PI
    return w


@njit(cache=True)
def _heading_step(s, P, b, var_b, dt, q, diagonal):  # pragma: no cover - compiled
    """Predict the (heading, turn rate) filter over ``dt`` and update it on heading ``b``."""
    s0 = _wrap(s[0] + dt * s[1])
    s1 = s[1]
    q00, q01, q11 = q * dt**3 / 3.0, q * dt**2 / 2.0, q * dt
    if diagonal:
        q01 = 0.0
    p00 = P[0, 0] + dt * (P[1, 0] + P[0, 1]) + dt * dt * P[1, 1] + q00
    p01 = P[0, 1] + dt * P[1, 1] + q01
    p11 = P[1, 1] + q11
    S = p00 + var_b
    k0, k1 = p00 / S, p01 / S
    e = _wrap(b - s0)
    s[0] = _wrap(s0 + k0 * e)
    s[1] = s1 + k1 * e
    # Joseph form: (I - K H) P' (I - K H)^T + K R K^T, H = [1, 0]
    a00, a10 = 1.0 - k0, -k1
    P[0, 0] = a00 * a00 * p00 + k0 * k0 * var_b
    P[0, 1] = a00 * (a10 * p00 + p01) + k0 * k1 * var_b
    P[1, 0] = P[0, 1]
    P[1, 1] = a10 * (a10 * p00 + p01) + (a10 * p01 + p11) + k1 * k1 * var_b


@njit(cache=True)
def _vote(queue, K, threshold):  # pragma: no cover - compiled
    """S4 on a full queue: (decision 0/1/2, delta omega)."""
    M = queue.shape[0]
    up = 0
    down = 0
    for i in range(M - 1):
        if queue[i + 1] > queue[i]:
            up += 1
        elif queue[i + 1] < queue[i]:
            down += 1
    delta = abs(queue[M - 1] - queue[0])
    if delta > threshold:
        if up >= K:
            return 1, delta
        if down >= K:
            return 2, delta
    return 0, delta


@njit(cache=True)
def turn_logic(
    x, P, t, d, hs, hP, ht, queue, qn, v_threshold, cross, sigma_omega0, q_heading, diagonal,
    w_threshold, K, dw_threshold, g_ref, g_pow, g_max, d_t, d_w, state, gain,
):  # fmt: skip  # pragma: no cover - compiled
    """S2-S5 for every track ``i`` of the batch (see the module docstring)."""
    B = x.shape[0]
    M = queue.shape[1]
    for i in range(B):
        vE, vN = x[i, d], x[i, d + 1]
        sE, sN = P[i, d, d], P[i, d + 1, d + 1]
        dt_i = 0.0
        for k in range(d):
            dt_i += x[i, d + k] ** 2 / P[i, d + k, d + k]
        d_t[i] = dt_i
        d_w[i] = np.nan
        state[i] = 0
        gain[i] = 1.0
        if not dt_i > v_threshold:
            continue
        b = _wrap(math.atan2(vE, vN))
        s2 = vE * vE + vN * vN
        jE, jN = vN / s2, -vE / s2
        var_b = jE * jE * sE + jN * jN * sN
        if cross:
            var_b += 2.0 * jE * jN * P[i, d, d + 1]
        if ht[i] == ht[i]:  # started: predict and update
            _heading_step(hs[i], hP[i], b, var_b, t[i] - ht[i], q_heading, diagonal)
        else:
            hs[i, 0], hs[i, 1] = b, 0.0
            hP[i, 0, 0], hP[i, 0, 1], hP[i, 1, 0], hP[i, 1, 1] = var_b, 0.0, 0.0, sigma_omega0**2
        ht[i] = t[i]
        omega = hs[i, 1]
        d_w[i] = abs(omega) / math.sqrt(hP[i, 1, 1])
        if not d_w[i] > w_threshold:
            continue
        ready = qn[i] >= M
        if ready:
            for k in range(M - 1):
                queue[i, k] = queue[i, k + 1]
            queue[i, M - 1] = omega
        else:
            queue[i, qn[i]] = omega
            qn[i] += 1
            continue
        st, delta = _vote(queue[i], K, dw_threshold)
        state[i] = st
        if st != 0:
            gain[i] = min(max((delta / g_ref) ** g_pow, 1.0), g_max)
