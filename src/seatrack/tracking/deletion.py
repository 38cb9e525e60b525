"""Track deletion: consecutive misses and covariance growth.

A confirmed track is deleted after ``max_misses`` consecutive scans without a plot, or as
soon as its position uncertainty -- the standard deviation along the major axis of its
position covariance, ``sqrt(lambda_max(P_pos))`` -- exceeds ``max_position_std``: a track
that uncertain no longer says where the target is, and its gate would swallow plots of
other targets. Tentative tracks are deleted by their M-of-N rule
(:func:`seatrack.tracking.initiation.hopeless`) or by the same covariance test.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = ["position_std", "to_delete"]


def position_std(P: FloatArray, d: int) -> FloatArray:
    """Major-axis standard deviation (m) of the position block ``P[:, :d, :d]``."""
    if P.shape[0] == 0:
        return np.zeros(0)
    raw = P[:, :d, :d]
    finite: NDArray[np.bool_] = np.asarray(np.isfinite(raw).all(axis=(-1, -2)))
    block = np.where(finite[:, None, None], raw, 0.0)
    if d == 2:  # closed form
        a, b, c = block[:, 0, 0], block[:, 0, 1], block[:, 1, 1]
        lam = 0.5 * (a + c) + np.sqrt(0.25 * (a - c) ** 2 + b**2)
    else:
        lam = np.linalg.eigvalsh(block)[:, -1]
    return np.where(finite, np.sqrt(np.maximum(lam, 0.0)), np.nan)


def to_delete(
    misses: IntArray, P: FloatArray, d: int, max_misses: int, max_position_std: float
) -> NDArray[np.bool_]:
    """Tracks with at least ``max_misses`` consecutive misses or a position std above
    ``max_position_std`` (m), or a non-finite covariance."""
    std = position_std(P, d)
    return np.asarray((misses >= max_misses) | ~(std <= max_position_std))
