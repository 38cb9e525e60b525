"""Central-difference Jacobians, used by tests to check every analytic Jacobian."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import wrap_pi


def numerical_jacobian(
    f: Callable[[NDArray[np.float64]], Any],
    x: ArrayLike,
    eps: float = 1e-6,
    angular: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Central-difference Jacobian ``df/dx`` of ``f`` at a single state ``x`` (1-D).

    Parameters
    ----------
    f : callable
        Maps a 1-D state to a 1-D output.
    x : array (n,)
    eps : float
        Relative step (scaled by ``max(1, |x_i|)``).
    angular : bool array (m,), optional
        Output components that are angles; their differences are wrapped.
    """
    xx = np.asarray(x, dtype=float)
    f0 = np.atleast_1d(np.asarray(f(xx), dtype=float))
    ang = np.zeros(f0.shape, bool) if angular is None else np.asarray(angular, bool)
    J = np.zeros((f0.size, xx.size))
    for i in range(xx.size):
        h = eps * max(1.0, abs(xx[i]))
        xp, xm = xx.copy(), xx.copy()
        xp[i] += h
        xm[i] -= h
        d = np.atleast_1d(np.asarray(f(xp), float) - np.asarray(f(xm), float))
        d = np.where(ang, wrap_pi(d), d)
        J[:, i] = d / (2 * h)
    return J
