"""Multi-leg target model: leg-time function ``T'_ij`` of DE 3446658 (spec "Manoeuvring target").

The target moves with constant velocity on each leg; leg ``j`` starts at the manoeuvre
time ``T_Aj`` (``T_A0`` = the reference time ``t0``, the first bearing) and ends at
``T_A(j+1)`` (``+inf`` for the last leg). The time that measurement ``i`` has spent on
leg ``j`` is (spec, claim 14; the printed eq. 15 has a typo)::

    T'_ij = max(0, min(t_i - T_Aj, T_A(j+1) - T_Aj))

and the target position is ``X_i = X0 + sum_j Vx_j T'_ij`` (same for ``Y``).

State layout (spec): ``beta = (X0, Y0, Vx0, Vy0, Vx1, Vy1, ...)`` -- position at ``t0``,
then one velocity pair per leg. Written as a ``(1 + L, 2)`` array ``B`` (rows = position,
velocity of leg 0, leg 1, ...; columns = East, North) the position at time ``t_i`` is
``c_i @ B`` with the *coefficient row* ``c_i = (1, T'_i0, T'_i1, ...)``. Every Jacobian
column of a position-dependent quantity ``f(p_i)`` is then ``df/dp * c_i`` (interleaved
East/North), which is how the solver builds the multi-leg columns.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

__all__ = ["leg_starts", "leg_time_matrix", "leg_index", "state_size", "position_map"]


def leg_starts(t0: float, manoeuvres: Sequence[float] | ArrayLike = ()) -> FloatArray:
    """Start times ``(T_A0 = t0, T_A1, ...)`` of the legs (s), validated.

    Manoeuvre times must be strictly increasing and strictly after ``t0``.
    """
    m = np.asarray(manoeuvres, dtype=float).reshape(-1)
    if m.size and (not np.all(np.isfinite(m)) or np.any(np.diff(m) <= 0)):
        raise ValueError(
            f"manoeuvre times must be finite and strictly increasing, got {m.tolist()}"
        )
    if m.size and m[0] <= t0:
        raise ValueError(
            f"manoeuvre time {m[0]:g} s is not after the reference time (first bearing) {t0:g} s"
        )
    return np.concatenate([[float(t0)], m])


def leg_time_matrix(t: ArrayLike, starts: ArrayLike) -> FloatArray:
    """Coefficient rows ``c_i = (1, T'_i0, T'_i1, ...)`` (spec eq. 15 / claim 14).

    Parameters
    ----------
    t : (..., N) s
        Measurement times (absolute, same clock as ``starts``).
    starts : (L,) s
        Leg start times from :func:`leg_starts` (``starts[0]`` = reference time ``t0``).

    Returns
    -------
    (..., N, 1 + L) : first column 1 (position at ``t0``), then the time spent on each leg.
    """
    tt = np.asarray(t, dtype=float)[..., None]
    s = np.asarray(starts, dtype=float)
    ends = np.empty(s.shape)
    ends[:-1] = s[1:]
    ends[-1:] = np.inf
    out = np.empty(tt.shape[:-1] + (1 + s.size,))
    out[..., 0] = 1.0
    np.maximum(0.0, np.minimum(tt - s, ends - s), out=out[..., 1:])
    return out


def leg_index(t: ArrayLike, starts: ArrayLike) -> NDArray[np.int64]:
    """Index of the leg that time ``t`` falls in (``T_Aj <= t < T_A(j+1)``; before ``t0``: 0)."""
    s = np.asarray(starts, dtype=float)
    j = np.searchsorted(s, np.asarray(t, dtype=float), side="right") - 1
    return np.minimum(np.maximum(j, 0), s.size - 1).astype(np.int64)


def state_size(n_legs: int) -> int:
    """Number of state components for ``n_legs`` legs: ``2 + 2 n_legs`` (spec: 2J + 4)."""
    return 2 + 2 * n_legs


def position_map(c: ArrayLike) -> FloatArray:
    """Matrix ``M`` with ``position = M @ beta`` for a coefficient row ``c`` (``(..., 2, n)``).

    ``M = kron(c, I2)``: d(position)/d(beta), used to propagate covariances to any time.
    """
    cc = np.asarray(c, dtype=float)
    eye = np.eye(2)
    return (cc[..., None, :, None] * eye[:, None, :]).reshape(cc.shape[:-1] + (2, 2 * cc.shape[-1]))
