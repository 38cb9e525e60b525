"""Support values ("Stützwerte") of DE 3446658: range, speed and course with weights.

Each support value adds one row to the least-squares problem (spec "Support
measurements"). It is taken at a time ``t`` and belongs to the leg that time falls in:

* ``range`` -- distance from an observer position ``(X_R, Y_R)`` to the target at ``t``
  (e.g. a radar or active-sonar range);
* ``speed`` -- target speed on that leg (e.g. from propeller-noise counting);
* ``course`` -- target course on that leg (e.g. a periscope observation).

Every row is written ``f(u)`` of a 2-vector ``u = A @ B - offset`` where ``B`` is the
state as a ``(1 + L, 2)`` array (see :mod:`seatrack.tma.legs`): for a range ``A`` is the
coefficient row at ``t`` and ``offset`` the observer position (``u`` = relative position);
for speed and course ``A`` picks the velocity row of the leg (``u`` = velocity). Then

* range, speed: ``f = |u|`` (linear residual ``S - |u|``, Jacobian ``u/|u|``) or, as in
  the patent, squares ``S^2 - |u|^2`` with Jacobian ``2u``;
* course: ``f = bearing(u)``, residual ``wrap(S - f)``, Jacobian ``[u_y, -u_x]/|u|^2``
  (the bearing Jacobian of the velocity vector).

[reading] The spec allows linear range/speed residuals instead of squares ("same
minimiser, better scaling"); :class:`~seatrack.tma.solver.TMAConfig` ``support_residual``
selects ``"linear"`` (default) or ``"square"``. Weights are always explicit inverse
variances: ``1/sigma^2`` for linear rows; for squared rows the first-order standard
deviation of ``S^2`` is ``2 S sigma`` and the weight is ``1/(2 S sigma)^2``, so in both
forms ``(J^T W J)^-1`` stays the covariance of the estimate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.geometry import bearing
from seatrack.geometry import wrap_pi
from seatrack.models.measurement import bearing_jacobian
from seatrack.tma.legs import leg_index
from seatrack.tma.legs import leg_time_matrix

FloatArray = NDArray[np.float64]

__all__ = ["KINDS", "SupportValue", "SupportRows", "support_rows", "support_residuals"]

#: support kinds and their integer codes (0 = padding row)
KINDS = {"range": 1, "speed": 2, "course": 3}


@dataclass(frozen=True)
class SupportValue:
    """One support value (SI units, radians).

    Parameters
    ----------
    kind : "range" | "speed" | "course"
    t : float
        Time of the value, s (same clock as the bearings).
    value : float
        Range (m), speed (m/s) or course (rad, clockwise from North).
    sigma : float
        Standard deviation in the same unit; the row weight is ``1/sigma^2``.
    observer : (2,) m, optional
        Observer position (East, North) at ``t``; required for a range.
    """

    kind: str
    t: float
    value: float
    sigma: float
    observer: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"support kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        for name in ("t", "value", "sigma"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(
                    f"support {self.kind} {name} must be finite, got {getattr(self, name)}"
                )
        if self.sigma <= 0:
            raise ValueError(f"support {self.kind} sigma must be positive, got {self.sigma}")
        if self.kind in ("range", "speed") and self.value <= 0:
            raise ValueError(f"support {self.kind} value must be positive, got {self.value}")
        if self.kind == "range" and self.observer is None:
            raise ValueError("a range support value needs the observer position (X_R, Y_R)")


@dataclass(frozen=True)
class SupportRows:
    """Support values of one problem as arrays (``M`` rows; ``kind == 0`` = padding).

    Attributes
    ----------
    kind : (M,) int -- codes of :data:`KINDS`
    A : (M, 1 + L) -- coefficient row selecting ``u = A @ B``
    offset : (M, 2) m -- subtracted from ``A @ B`` (observer position for a range)
    value : (M,) -- m, m/s or rad
    weight : (M,) -- ``1/sigma^2`` in the residual's unit (already squared-form adjusted)
    square : bool -- patent's squared range/speed residuals
    """

    kind: NDArray[np.int64]
    A: FloatArray
    offset: FloatArray
    value: FloatArray
    weight: FloatArray
    square: bool = False


def support_rows(
    supports: Sequence[SupportValue], starts: ArrayLike, square: bool = False
) -> SupportRows:
    """Arrays for the support values, given the leg start times ``starts`` (s)."""
    s = np.asarray(starts, dtype=float)
    m = len(supports)
    L1 = s.size + 1
    kind = np.array([KINDS[v.kind] for v in supports], dtype=np.int64)
    A = np.zeros((m, L1))
    offset = np.zeros((m, 2))
    value = np.array([v.value for v in supports], dtype=float)
    sigma = np.array([v.sigma for v in supports], dtype=float)
    for i, v in enumerate(supports):
        if v.kind == "range":
            A[i] = leg_time_matrix(np.array([v.t]), s)[0]
            assert v.observer is not None
            offset[i] = v.observer
        else:
            A[i, 1 + int(leg_index(v.t, s))] = 1.0
    weight = 1.0 / sigma**2
    if square:
        norm = kind != KINDS["course"]
        weight = np.where(norm, 1.0 / (2.0 * value * sigma) ** 2, weight)
    return SupportRows(kind, A, offset, value, weight, square)


def support_residuals(
    B: ArrayLike,
    kind: ArrayLike,
    A: ArrayLike,
    offset: ArrayLike,
    value: ArrayLike,
    square: bool = False,
) -> tuple[FloatArray, FloatArray]:
    """Residuals ``value - f`` and Jacobians ``df/dbeta`` of support rows, batched.

    Parameters
    ----------
    B : (..., 1 + L, 2) state as rows (position at t0, velocity per leg).
    kind, A, offset, value : as in :class:`SupportRows`, with optional matching
        leading dimensions (``(..., M)`` etc.).
    square : use the patent's squared range/speed residuals.

    Returns
    -------
    r : (..., M) residuals (course residuals wrapped to ``(-pi, pi]``; padding rows 0).
    J : (..., M, 2 (1 + L)) Jacobian of the predicted value w.r.t. ``beta``.
    """
    BB = np.asarray(B, dtype=float)
    AA = np.asarray(A, dtype=float)
    k = np.asarray(kind)
    val = np.asarray(value, dtype=float)
    u = np.einsum("...mk,...kd->...md", AA, BB) - np.asarray(offset, dtype=float)
    n2 = u[..., 0] ** 2 + u[..., 1] ** 2
    nrm = np.sqrt(n2)
    is_course = k == KINDS["course"]
    is_norm = (k == KINDS["range"]) | (k == KINDS["speed"])
    safe = np.where(nrm > 0, nrm, 1.0)
    if square:
        r_norm = val**2 - n2
        g_norm = 2.0 * u
    else:
        r_norm = val - nrm
        g_norm = u / safe[..., None]
    with np.errstate(invalid="ignore", divide="ignore"):
        r_course = wrap_pi(val - bearing(u[..., 0], u[..., 1]))
        g_course = bearing_jacobian(np.where(nrm[..., None] > 0, u, 1.0))
    r = np.where(is_norm, r_norm, np.where(is_course, r_course, 0.0))
    g = np.where(is_norm[..., None], g_norm, np.where(is_course[..., None], g_course, 0.0))
    J = (AA[..., :, None] * g[..., None, :]).reshape(AA.shape[:-1] + (2 * AA.shape[-1],))
    return np.asarray(r, dtype=float), J
