"""Rauch-Tung-Striebel fixed-interval smoother for any linear-Gaussian track.

The smoother needs, per step ``k``, the filtered state ``x_k|k``, ``P_k|k``, the prediction
``x_k|k-1``, ``P_k|k-1`` and the transition matrix ``F_k`` used to make it (Bar-Shalom, Li &
Kirubarajan 2001, section 8.6):

``C_k = P_k|k F_k+1^T P_k+1|k^-1``, ``x_k|K = x_k|k + C_k (x_k+1|K - x_k+1|k)``,
``P_k|K = P_k|k + C_k (P_k+1|K - P_k+1|k) C_k^T``.

:func:`rts_smooth` works on arrays (any leading batch dimensions); :func:`smooth_track`
runs a filter of the contract over one track's plots, keeping what the smoother needs:
the filters whose :meth:`predict` stores its transition matrix in ``aux["F"]`` (the EKF)
qualify; for an EKF the result is the extended RTS smoother (linearised at the filtered
estimates).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seatrack import kalman
from seatrack.filters.base import Plots
from seatrack.filters.base import RecursiveFilter

FloatArray = NDArray[np.float64]

__all__ = ["rts_smooth", "smooth_track"]


def rts_smooth(
    x: FloatArray, P: FloatArray, x_pred: FloatArray, P_pred: FloatArray, F: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Smoothed states and covariances of a track of ``K`` steps.

    Parameters
    ----------
    x, P : (..., K, n), (..., K, n, n) -- filtered estimates ``x_k|k``, ``P_k|k``.
    x_pred, P_pred : (..., K, n), (..., K, n, n) -- predictions ``x_k|k-1``, ``P_k|k-1``
        (index 0 unused).
    F : (..., K, n, n) -- transition from step ``k - 1`` to ``k`` (index 0 unused).

    Returns
    -------
    xs, Ps : smoothed ``x_k|K`` and ``P_k|K`` (symmetric).

    Raises
    ------
    numpy.linalg.LinAlgError
        When a predicted covariance is not positive definite.
    """
    xs = np.array(x, dtype=float, copy=True)
    Ps = np.array(P, dtype=float, copy=True)
    K = xs.shape[-2]
    for k in range(K - 2, -1, -1):
        Pp = P_pred[..., k + 1, :, :]
        L = np.linalg.cholesky(Pp)  # raises LinAlgError if not positive definite
        FP = F[..., k + 1, :, :] @ P[..., k, :, :]
        # C^T = Pp^-1 F P by two triangular solves with the Cholesky factor
        Ct = np.linalg.solve(np.swapaxes(L, -1, -2), np.linalg.solve(L, FP))
        C = np.swapaxes(Ct, -1, -2)
        dx = xs[..., k + 1, :] - x_pred[..., k + 1, :]
        xs[..., k, :] = x[..., k, :] + np.einsum("...ij,...j->...i", C, dx)
        dP = Ps[..., k + 1, :, :] - Pp
        Ps[..., k, :, :] = kalman.symmetrize(P[..., k, :, :] + C @ dP @ Ct)
    return xs, Ps


def smooth_track(
    flt: RecursiveFilter,
    plots: Plots,
    initiate: Callable[[Plots], tuple[Any, Any]],
) -> tuple[FloatArray, FloatArray]:
    """Filter one track's plots (time order) with ``flt`` and smooth it (:func:`rts_smooth`).

    ``flt.predict`` must store its transition matrix in ``aux["F"]`` (e.g.
    :class:`seatrack.filters.ekf.EKF`). Returns ``(x, P)`` of shape ``(N, n)``,
    ``(N, n, n)``; a rejected plot leaves its step at the prediction, as in the filter.
    """
    first = plots.take([0])
    s = flt.initiate(first.t, *initiate(first))
    n = s.x.shape[-1]
    N = len(plots)
    xf, Pf = np.empty((N, n)), np.empty((N, n, n))
    xp, Pp, F = np.zeros((N, n)), np.zeros((N, n, n)), np.zeros((N, n, n))
    xf[0], Pf[0] = s.x[0], s.P[0]
    for k in range(1, N):
        pk = plots.take([k])
        pr = flt.predict(s, pk.t)
        if "F" not in pr.aux:
            raise TypeError(f"{type(flt).__name__}.predict keeps no transition matrix aux['F']")
        s = flt.update(pr, pk)
        xp[k], Pp[k], F[k] = pr.x[0], pr.P[0], pr.aux["F"][0]
        xf[k], Pf[k] = s.x[0], s.P[0]
    return rts_smooth(xf, Pf, xp, Pp, F)
