"""Information matrices: an explicit, scale-invariant rank test before every inverse.

Estimation code inverts information matrices ``A = J^T W J`` (Fisher information, Gauss–Newton
normal matrices) and covariances. Whether LAPACK notices a singular matrix depends on the
BLAS build and on rounding, so nothing here relies on it: every inverse is preceded by an
explicit rank decision, and a rank-deficient matrix raises :class:`SingularMatrixError` (or
is reported, for callers that want a verdict instead of an exception).

The decision is *scale-invariant*: the matrix is scaled to unit diagonal,
``As = D^-1/2 A D^-1/2`` with ``D = diag(A)`` -- equivalently the whitened Jacobian's columns
are scaled to unit norm, ``Js = W^1/2 J D^-1/2`` -- so a change of units of any parameter
(metres vs kilometres, m/s vs knots) does not change it. The *scaled singular values*
``s_i = sv(Js) = sqrt(eig(As))`` satisfy ``sum s_i^2 = n`` and are compared with the largest:

* from a Jacobian (SVD of ``Js``, :func:`check_jacobian`): rank-deficient when
  ``s_min <= rtol * s_max`` with ``rtol`` = :data:`JACOBIAN_RTOL` (1e-10). The rounding floor
  of an exactly rank-deficient Jacobian is about ``max(m, n) * eps`` (1e-16 .. 1e-12 for up to
  thousands of rows); any geometry that determines the parameters sits orders of magnitude
  above the tolerance (bearings-only TMA with one own-ship turn: ``>= 4e-4`` on 200 random
  geometries, see ``docs/tma.md``).
* from an information matrix alone (eigenvalues of ``As``, :func:`check_information`): the
  eigenvalues carry absolute errors of about ``n * eps``, so the test is on eigenvalues,
  ``lambda_min <= rtol * lambda_max`` with ``rtol = 100 n eps`` (1.3e-13 for ``n = 6``);
  in singular-value terms the tolerance is its square root.

A zero, negative or non-finite diagonal entry (a parameter no measurement touches) is rank
deficiency too; non-finite entries elsewhere are a :class:`ValueError`.

The inverse itself is computed from the scaled factorisation, ``P = D^-1/2 V S^-2 V^T D^-1/2``.
For speed a clearly regular Jacobian (scaled singular values above ``1e-4`` of the largest,
far from any tolerance) is inverted through the Cholesky factor of the small matrix
``Js^T Js``; anything nearer to singular is decided and inverted from the SVD of ``Js``
itself, which keeps the precision near ``eps * cond(Js)`` instead of ``eps * cond(Js)^2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

__all__ = [
    "EPS",
    "as_float64",
    "JACOBIAN_RTOL",
    "RankCheck",
    "SingularMatrixError",
    "check_information",
    "check_jacobian",
    "covariance_from_jacobian",
    "fisher_information",
    "information_rtol",
    "invert_information",
    "invert_jacobian_information",
    "positive_definite_mask",
    "scale_to_unit_diagonal",
    "whiten",
]

EPS = float(np.finfo(np.float64).eps)

#: relative tolerance on the scaled singular values of a whitened Jacobian
JACOBIAN_RTOL = 1e-10


def as_float64(a: ArrayLike) -> FloatArray:
    """``a`` as a float64 array (no copy when it already is one)."""
    return np.asarray(a, dtype=np.float64)


def information_rtol(n: int) -> float:
    """Default relative tolerance on the eigenvalues of a scaled ``n x n`` information matrix."""
    return 100.0 * max(n, 1) * EPS


class SingularMatrixError(np.linalg.LinAlgError):
    """An information (or covariance) matrix is singular to working precision.

    Subclass of :class:`numpy.linalg.LinAlgError`; ``check`` holds the :class:`RankCheck`.
    """

    def __init__(self, message: str, check: RankCheck | None = None) -> None:
        super().__init__(message)
        self.check = check


@dataclass(frozen=True)
class RankCheck:
    """Outcome of a scaled rank test.

    Attributes
    ----------
    rank : numerical rank (scaled singular values above ``tolerance * largest``).
    size : number of parameters ``n``.
    smallest, largest : smallest and largest scaled singular value (``sum s_i^2 = n``).
    tolerance : relative tolerance on the scaled singular values used for ``rank``.
    """

    rank: int
    size: int
    smallest: float
    largest: float
    tolerance: float

    @property
    def full_rank(self) -> bool:
        return self.rank == self.size

    @property
    def condition(self) -> float:
        """``largest / smallest`` of the scaled singular values (``inf`` when singular)."""
        return self.largest / self.smallest if self.smallest > 0 else math.inf

    def describe(self, what: str) -> str:
        """One-sentence reason for a rank-deficient matrix, naming ``what``."""
        return (
            f"{what} is singular to working precision: rank {self.rank} of {self.size} "
            f"(smallest scaled singular value {self.smallest:.3g} <= {self.tolerance:.3g} x "
            f"largest {self.largest:.3g}); not observable from these data (a combination of "
            "the parameters is undetermined)"
        )


def _finite_2d(a: ArrayLike, name: str) -> FloatArray:
    m = np.asarray(a, dtype=np.float64)
    if m.ndim != 2:
        raise ValueError(f"{name} must be 2-D, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ValueError(f"{name} has non-finite entries")
    return m


def scale_to_unit_diagonal(A: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``(As, d)`` with ``As = A / outer(d, d)``, ``d = sqrt(diag(A))``; symmetrised.

    Entries of ``d`` for non-positive diagonal entries are 0 and the matching rows/columns
    of ``As`` are 0 (the caller's rank test counts them as missing rank).
    """
    M = _finite_2d(A, "matrix")
    if M.shape[0] != M.shape[1]:
        raise ValueError(f"matrix must be square, got shape {M.shape}")
    M = 0.5 * (M + M.T)
    diag = np.diag(M)
    d = np.sqrt(np.where(diag > 0, diag, 0.0))
    inv = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    return M * np.outer(inv, inv), d


def check_information(A: ArrayLike, rtol: float | None = None) -> RankCheck:
    """Scaled rank test of a symmetric information (or covariance) matrix.

    Parameters
    ----------
    A : (n, n) symmetric matrix.
    rtol : relative tolerance on the *eigenvalues* of the unit-diagonal matrix; default
        :func:`information_rtol` (``100 n eps``).
    """
    As, d = scale_to_unit_diagonal(A)
    n = As.shape[0]
    tol = information_rtol(n) if rtol is None else float(rtol)
    if n == 0:
        return RankCheck(0, 0, 0.0, 0.0, math.sqrt(tol))
    lam = np.linalg.eigvalsh(As)
    lmax = float(lam[-1])
    rank = int(np.sum(lam > tol * lmax)) if lmax > 0 else 0
    rank = min(rank, int(np.sum(d > 0)))
    smallest = math.sqrt(max(float(lam[0]), 0.0)) if np.all(d > 0) else 0.0
    return RankCheck(rank, n, smallest, math.sqrt(max(lmax, 0.0)), math.sqrt(tol))


def positive_definite_mask(M: ArrayLike, rtol: float | None = None) -> NDArray[np.bool_]:
    """Batched scaled test: which of the symmetric matrices ``M (..., n, n)`` are positive
    definite to working precision (positive diagonal, smallest eigenvalue of the unit-diagonal
    matrix above ``rtol`` times its largest; default :func:`information_rtol`).

    Non-finite matrices are reported as not positive definite."""
    A = np.asarray(M, dtype=np.float64)
    n = A.shape[-1]
    tol = information_rtol(n) if rtol is None else float(rtol)
    finite = np.all(np.isfinite(A), axis=(-2, -1))
    A = np.where(finite[..., None, None], A, np.eye(n))
    diag = np.diagonal(A, axis1=-2, axis2=-1)
    pos = np.all(diag > 0, axis=-1)
    d = 1.0 / np.sqrt(np.where(diag > 0, diag, 1.0))
    As = A * d[..., :, None] * d[..., None, :]
    lam = np.linalg.eigvalsh(0.5 * (As + np.swapaxes(As, -1, -2)))
    return np.asarray(finite & pos & (lam[..., 0] > tol * lam[..., -1]))


def invert_information(
    A: ArrayLike, what: str = "information matrix", rtol: float | None = None
) -> FloatArray:
    """Inverse of a symmetric positive-definite matrix after the scaled rank test.

    Raises
    ------
    SingularMatrixError
        When :func:`check_information` finds it rank-deficient or it is not positive
        definite (a negative eigenvalue of the scaled matrix beyond the tolerance).
    """
    chk = check_information(A, rtol)
    if not chk.full_rank:
        raise SingularMatrixError(chk.describe(what), chk)
    As, d = scale_to_unit_diagonal(A)
    lam, V = np.linalg.eigh(As)
    if lam[0] <= 0:  # cannot happen after a passed test; kept as an explicit guard
        raise SingularMatrixError(f"{what} is not positive definite", chk)
    inv_s = (V / lam) @ V.T
    P = inv_s / np.outer(d, d)
    return np.asarray(0.5 * (P + P.T), dtype=np.float64)


def _weights_root(W: ArrayLike, m: int) -> tuple[str, FloatArray]:
    w = np.asarray(W, dtype=np.float64)
    if not np.all(np.isfinite(w)):
        raise ValueError("weights must be finite")
    if w.ndim == 0:
        if w < 0:
            raise ValueError(f"weight must be non-negative, got {float(w)}")
        return "scalar", np.sqrt(w)
    if w.ndim == 1:
        if w.size != m:
            raise ValueError(f"weight vector has {w.size} entries for {m} measurements")
        if np.any(w < 0):
            raise ValueError("weights must be non-negative")
        return "vector", np.sqrt(w)
    if w.shape != (m, m):
        raise ValueError(f"weight matrix shape {w.shape} does not match {m} measurements")
    chk = check_information(w)
    if not chk.full_rank:
        raise ValueError(chk.describe("weight matrix (inverse measurement covariance)"))
    lam, V = np.linalg.eigh(0.5 * (w + w.T))
    if lam[0] <= 0:
        raise ValueError("weight matrix (inverse measurement covariance) is not positive definite")
    return "matrix", (V * np.sqrt(lam)).T  # R^T R = W


def whiten(J: ArrayLike, W: ArrayLike) -> FloatArray:
    """Whitened Jacobian ``W^1/2 J`` (``W`` scalar, ``(m,)`` diagonal or ``(m, m)`` SPD)."""
    Jm = _finite_2d(J, "Jacobian")
    kind, root = _weights_root(W, Jm.shape[0])
    if kind == "scalar":
        return np.asarray(root * Jm)
    if kind == "vector":
        return np.asarray(root[:, None] * Jm)
    return np.asarray(root @ Jm)


def fisher_information(J: ArrayLike, W: ArrayLike) -> FloatArray:
    """Fisher information ``J^T W J`` of Gaussian measurements (symmetrised)."""
    Jw = whiten(J, W)
    F = Jw.T @ Jw
    return np.asarray(0.5 * (F + F.T), dtype=np.float64)


#: scaled information matrices whose eigenvalue ratio exceeds this are inverted directly
#: (7 decades above the eigenvalue rounding floor ``n eps``, scaled singular values above 1e-4)
_DIRECT_RATIO = 1e-8


def _scaled_factor(Jw: FloatArray, rtol: float) -> tuple[FloatArray | None, RankCheck]:
    """Rank test and inverse factor of ``Jw / c`` (``c`` = column norms).

    Returns ``(F, check)`` with ``P = F F^T`` (``F = None`` when rank-deficient). A clearly
    regular matrix (eigenvalue ratio of ``Js^T Js`` above :data:`_DIRECT_RATIO`) is inverted
    from the eigen-decomposition of the small scaled matrix; anything closer to singular is
    decided and inverted from the SVD of ``Js`` itself (tall matrices reduced by Householder
    QR first), whose rounding floor is ``eps`` rather than ``sqrt(eps)`` in singular-value
    terms."""
    m, n = Jw.shape
    c = np.sqrt(np.einsum("ij,ij->j", Jw, Jw))
    ok = bool(np.all(c > 0))
    inv = np.where(c > 0, 1.0 / np.where(c > 0, c, 1.0), 0.0)
    Js = Jw * inv
    if ok and m >= n:
        G = Js.T @ Js
        lam = np.linalg.eigvalsh(G)
        if lam[0] > _DIRECT_RATIO * lam[-1]:  # clearly positive definite: Cholesky succeeds
            chk = RankCheck(n, n, math.sqrt(lam[0]), math.sqrt(lam[-1]), rtol)
            Linv = np.linalg.inv(np.linalg.cholesky(G))  # G^-1 = Linv^T Linv
            return Linv.T * inv[:, None], chk
    if m > 2 * n:
        Js = np.asarray(np.linalg.qr(Js, mode="r"), dtype=np.float64)
    _, s, Vt = np.linalg.svd(Js, full_matrices=False)
    smax = float(s[0]) if s.size else 0.0
    rank = min(int(np.sum(s > rtol * smax)) if smax > 0 else 0, int(np.sum(c > 0)))
    smallest = float(s[-1]) if s.size == n and ok else 0.0
    chk = RankCheck(rank, n, smallest, smax, rtol)
    if rank < n:
        return None, chk
    return Vt.T * (inv[:, None] / s), chk


def check_jacobian(Jw: ArrayLike, rtol: float | None = None) -> RankCheck:
    """Scaled rank test of a whitened Jacobian ``(m, n)`` (columns scaled to unit norm).

    ``rtol`` defaults to :data:`JACOBIAN_RTOL`. Fewer rows than columns is rank deficiency.
    """
    J = _finite_2d(Jw, "Jacobian")
    return _scaled_factor(J, JACOBIAN_RTOL if rtol is None else float(rtol))[1]


def covariance_from_jacobian(
    Jw: ArrayLike, rtol: float | None = None
) -> tuple[FloatArray | None, RankCheck]:
    """``(J_w^T J_w)^-1`` after the scaled rank test of the whitened Jacobian ``J_w``.

    Returns ``(None, check)`` when the Jacobian is rank-deficient (no inverse attempted).
    """
    J = _finite_2d(Jw, "Jacobian")
    F, chk = _scaled_factor(J, JACOBIAN_RTOL if rtol is None else float(rtol))
    if F is None:
        return None, chk
    P = F @ F.T
    return np.asarray(0.5 * (P + P.T), dtype=np.float64), chk


def invert_jacobian_information(
    J: ArrayLike, W: ArrayLike, what: str = "Fisher information matrix", rtol: float | None = None
) -> FloatArray:
    """``(J^T W J)^-1`` after the scaled rank test of ``W^1/2 J``.

    Raises
    ------
    SingularMatrixError
        When the whitened Jacobian is rank-deficient (the parameters are not all observable).
    """
    P, chk = covariance_from_jacobian(whiten(J, W), rtol)
    if P is None:
        raise SingularMatrixError(chk.describe(what), chk)
    return P
