"""Kalman core: predict / update for linear and extended Kalman filters.

The small, stable public API every method in seatrack builds on:

* :func:`predict` ``(x, P, F, Q) -> (x, P)``
* :func:`update` ``(x, P, z, H, R) -> UpdateResult``
* :func:`extended_update` ``(x, P, z, hx, H, R, angular) -> UpdateResult`` -- nonlinear
  measurement, given the predicted measurement ``h(x)`` and its Jacobian ``H``; the
  innovation of every component flagged in ``angular`` is wrapped to ``(-pi, pi]``.
* :func:`extended_predict` -- nonlinear motion ``f(x)`` with Jacobian ``F``.

Compiled building blocks, for other Numba kernels (e.g. a whole filter loop compiled in
one piece) so that they reuse this update rather than re-deriving it:
:func:`predict_core` ``(x, P, F, Q, xo, Po)``, :func:`cov_core` ``(P, F, Q, Po)``
(``Po = F P F^T + Q``), :func:`update_core`
``(x, P, y, H, R, xo, Po, So, Ko) -> (nis, loglik)`` (Joseph form, given the innovation),
:func:`cholesky_core` ``(S, L) -> log det S``, :func:`forward_core` ``(L, y, w)`` and
:func:`wrap_angle` (scalar wrap to ``(-pi, pi]``). They write into the output arrays
and must be called from compiled code with contiguous float64 arrays.

Shapes and broadcasting
-----------------------
States are 1-D (``(n,)``), never column vectors. Every argument may carry leading
dimensions (``(..., n)``, ``(..., n, n)``, ...) that broadcast against each other, so a
single track, 10,000 tracks or a Monte-Carlo ensemble go through the *same* code: the
kernels are NumPy generalised ufuncs compiled with Numba (``guvectorize``), which loop
over the leading dimensions in machine code. That is why one predict+update costs a few
microseconds instead of tens, and why a batch costs a fraction of a microsecond per track.

Numerics
--------
* Covariance update in Joseph form ``(I-KH) P (I-KH)^T + K R K^T`` and re-symmetrised,
  so ``P`` stays symmetric positive semi-definite under round-off.
* The innovation covariance ``S`` is factorised by Cholesky; the gain, the normalised
  innovation squared (NIS) and the Gaussian log-likelihood
  ``-0.5 (NIS + log det(2 pi S))`` all come from that factor (log space throughout).
* A non-positive-definite ``S`` raises :class:`numpy.linalg.LinAlgError`.

References
----------
Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to Tracking and Navigation*,
Wiley 2001, sections 5.2 (KF), 5.2.3 (Joseph form), 10.3 (EKF).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.information import as_float64
from seatrack.jit import gufunc

FloatArray = NDArray[np.float64]

__all__ = [
    "chi2_cdf",
    "chi2_ppf",
    "matmul_core",
    "sym_matmul_core",
    "cov_core",
    "mahalanobis",
    "cholesky_core",
    "cholesky_m",
    "forward_core",
    "forward_m",
    "predict_core",
    "update_core",
    "wrap_angle",
    "UpdateResult",
    "predict",
    "extended_predict",
    "update",
    "extended_update",
    "nis_log_likelihood",
    "symmetrize",
]

_LOG_2PI = math.log(2.0 * math.pi)


# ---------------------------------------------------------------------------
# Compiled kernels (one core each, broadcast by the gufunc machinery)
# ---------------------------------------------------------------------------
@njit(cache=True, inline="always")
def matmul_core(A, B, out):  # pragma: no cover - compiled
    """``out = A B`` (each entry summed over ``k`` in ascending order)."""
    for i in range(A.shape[0]):
        for j in range(B.shape[1]):
            s = 0.0
            for k in range(A.shape[1]):
                s += A[i, k] * B[k, j]
            out[i, j] = s


@njit(cache=True, inline="always")
def sym_matmul_core(A, B, C, out):  # pragma: no cover - compiled
    """``out = A B + (C + C^T) / 2`` for a product ``A B`` symmetric in exact arithmetic:
    computed on and above the diagonal and mirrored, so ``out`` is exactly symmetric.
    ``C`` may be ``out`` itself when it is exactly symmetric (``out += A B``)."""
    n = out.shape[0]
    for i in range(n):
        for j in range(i, n):
            s = 0.0
            for k in range(A.shape[1]):
                s += A[i, k] * B[k, j]
            v = s + 0.5 * (C[i, j] + C[j, i])
            out[i, j] = v
            out[j, i] = v


@njit(cache=True)
def cov_core(P, F, Q, Po):  # pragma: no cover - compiled
    """``Po = F P F^T + Q`` (symmetrised).

    The two products are :func:`matmul_core` and :func:`sym_matmul_core` written out:
    calling them here costs 3-5 % on the batched prediction (measured, best of 200
    interleaved runs), the hottest kernel of every filter."""
    n = P.shape[0]
    FP = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            s = 0.0
            for k in range(n):
                s += F[i, k] * P[k, j]
            FP[i, j] = s
    for i in range(n):
        for j in range(i, n):
            s = 0.0
            for k in range(n):
                s += FP[i, k] * F[j, k]
            v = s + 0.5 * (Q[i, j] + Q[j, i])
            Po[i, j] = v
            Po[j, i] = v


@njit(cache=True)
def predict_core(x, P, F, Q, xo, Po):  # pragma: no cover - compiled
    """``xo = F x``; ``Po = F P F^T + Q`` (symmetrised)."""
    n = x.shape[0]
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += F[i, j] * x[j]
        xo[i] = s
    cov_core(P, F, Q, Po)


@gufunc(
    "void(f8[:], f8[:,:], f8[:,:], f8[:,:], f8[:], f8[:,:])",
    "(n),(n,n),(n,n),(n,n)->(n),(n,n)",
)
def _predict_kernel(x, P, F, Q, xo, Po):  # pragma: no cover - compiled
    predict_core(x, P, F, Q, xo, Po)


@gufunc("void(f8[:,:], f8[:,:], f8[:,:], f8[:,:])", "(n,n),(n,n),(n,n)->(n,n)")
def _cov_predict_kernel(P, F, Q, Po):  # pragma: no cover - compiled
    cov_core(P, F, Q, Po)


@njit(cache=True)
def cholesky_core(S, L):  # pragma: no cover - compiled
    """Cholesky ``S = L L^T`` of a small SPD matrix into ``L``; returns ``log det S``.

    Returns NaN (``L`` then incomplete) when ``S`` is not positive definite.
    """
    return cholesky_m(S, L, S.shape[0])


@njit(cache=True, inline="always")
def cholesky_m(S, L, m):  # pragma: no cover - compiled
    """:func:`cholesky_core` of the leading ``m x m`` block, inlined: a caller that knows
    ``m`` at compile time (e.g. ``len`` of a tuple) gets fully unrolled loops."""
    L[:, :] = 0.0
    logdet = 0.0
    for j in range(m):
        d = S[j, j]
        for k in range(j):
            d -= L[j, k] * L[j, k]
        if not d > 0.0:
            return np.nan
        d = math.sqrt(d)
        L[j, j] = d
        logdet += 2.0 * math.log(d)
        for i in range(j + 1, m):
            v = S[i, j]
            for k in range(j):
                v -= L[i, k] * L[j, k]
            L[i, j] = v / d
    return logdet


@njit(cache=True)
def forward_core(L, y, w):  # pragma: no cover - compiled
    """Forward substitution ``w = L^-1 y`` for lower-triangular ``L``."""
    forward_m(L, y, w, y.shape[0])


@njit(cache=True, inline="always")
def forward_m(L, y, w, m):  # pragma: no cover - compiled
    """:func:`forward_core` of the first ``m`` components, inlined (see :func:`cholesky_m`)."""
    for i in range(m):
        v = y[i]
        for k in range(i):
            v -= L[i, k] * w[k]
        w[i] = v / L[i, i]


@njit(cache=True)
def update_core(x, P, y, H, R, xo, Po, So, Ko):  # pragma: no cover - compiled
    """Joseph-form update given the innovation ``y``; returns (nis, loglik)."""
    n = x.shape[0]
    m = y.shape[0]
    # one scratch allocation for every temporary (views below): allocations dominate
    # the cost of small updates in batch mode
    buf = np.empty(2 * n * m + m * m + 2 * m + 2 * n * n)
    o = 0
    PHt = buf[o : o + n * m].reshape((n, m))
    o += n * m
    L = buf[o : o + m * m].reshape((m, m))
    o += m * m
    w = buf[o : o + m]
    o += m
    t = buf[o : o + m]
    o += m
    A = buf[o : o + n * n].reshape((n, n))
    o += n * n
    AP = buf[o : o + n * n].reshape((n, n))
    o += n * n
    KR = buf[o : o + n * m].reshape((n, m))
    matmul_core(P, H.T, PHt)  # P H^T  (n, m)
    sym_matmul_core(H, PHt, R, So)  # S = H P H^T + R, symmetrised
    # Cholesky S = L L^T; w = L^-1 y; nis = w.w
    logdet = cholesky_core(So, L)
    if not logdet == logdet:  # NaN: S not positive definite
        for i in range(n):
            xo[i] = np.nan
        return np.nan, np.nan
    forward_core(L, y, w)
    nis = 0.0
    for i in range(m):
        nis += w[i] * w[i]
    # K = PHt S^-1: solve L L^T K^T = PHt^T row by row of PHt
    for r in range(n):
        forward_core(L, PHt[r], t)
        for i in range(m - 1, -1, -1):
            s = t[i]
            for k in range(i + 1, m):
                s -= L[k, i] * Ko[r, k]
            Ko[r, i] = s / L[i, i]
    # state
    for i in range(n):
        s = x[i]
        for k in range(m):
            s += Ko[i, k] * y[k]
        xo[i] = s
    # Joseph form: A = I - K H ; P+ = A P A^T + K R K^T
    for i in range(n):
        for j in range(n):
            s = 0.0
            for k in range(m):
                s += Ko[i, k] * H[k, j]
            A[i, j] = (1.0 if i == j else 0.0) - s
    matmul_core(A, P, AP)
    matmul_core(Ko, R, KR)
    for i in range(n):
        for j in range(i, n):
            s = 0.0
            for k in range(n):
                s += AP[i, k] * A[j, k]
            for k in range(m):
                s += KR[i, k] * Ko[j, k]
            Po[i, j] = s
            Po[j, i] = s
    return nis, -0.5 * (nis + logdet + m * _LOG_2PI)


@njit(cache=True)
def wrap_angle(a):  # pragma: no cover - compiled
    w = (a + math.pi) % (2.0 * math.pi) - math.pi
    if w <= -math.pi:
        w += 2.0 * math.pi
    return w


@njit(cache=True)
def _linear_innovation(x, z, H, yo):  # pragma: no cover - compiled
    m = z.shape[0]
    n = x.shape[0]
    for i in range(m):
        s = z[i]
        for k in range(n):
            s -= H[i, k] * x[k]
        yo[i] = s


@njit(cache=True)
def _angular_innovation(z, hx, angular, yo):  # pragma: no cover - compiled
    for i in range(z.shape[0]):
        d = z[i] - hx[i]
        if angular[i] != 0.0:
            d = wrap_angle(d)
        yo[i] = d


@gufunc(
    "void(f8[:], f8[:,:], f8[:], f8[:], f8[:,:], f8[:,:], f8[:],"
    " f8[:], f8[:,:], f8[:], f8[:,:], f8[:], f8[:], f8[:,:])",
    "(n),(n,n),(m),(m),(m,n),(m,m),(m)->(n),(n,n),(m),(m,m),(),(),(n,m)",
)
def _update_kernel(x, P, z, hx, H, R, angular, xo, Po, yo, So, nis, ll, Ko):  # pragma: no cover
    _angular_innovation(z, hx, angular, yo)
    a, b = update_core(x, P, yo, H, R, xo, Po, So, Ko)
    nis[0] = a
    ll[0] = b


@gufunc(
    "void(f8[:], f8[:,:], f8[:], f8[:,:], f8[:,:],"
    " f8[:], f8[:,:], f8[:], f8[:,:], f8[:], f8[:], f8[:,:])",
    "(n),(n,n),(m),(m,n),(m,m)->(n),(n,n),(m),(m,m),(),(),(n,m)",
)
def _linear_update_kernel(x, P, z, H, R, xo, Po, yo, So, nis, ll, Ko):  # pragma: no cover
    _linear_innovation(x, z, H, yo)
    a, b = update_core(x, P, yo, H, R, xo, Po, So, Ko)
    nis[0] = a
    ll[0] = b


@njit(cache=True)
def _linear_update_single(x, P, z, H, R, xo, Po, yo, So, Ko):  # pragma: no cover - compiled
    _linear_innovation(x, z, H, yo)
    return update_core(x, P, yo, H, R, xo, Po, So, Ko)


@njit(cache=True)
def _extended_update_single(x, P, z, hx, H, R, angular, xo, Po, yo, So, Ko):  # pragma: no cover
    _angular_innovation(z, hx, angular, yo)
    return update_core(x, P, yo, H, R, xo, Po, So, Ko)


# ---------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------
@dataclass(slots=True)
class UpdateResult:
    """Result of a Kalman measurement update (all arrays keep the leading dimensions).

    (A plain slotted dataclass rather than a frozen one: frozen construction costs
    ~0.5 us, a sixth of a whole update.)

    Attributes
    ----------
    x : ndarray (..., n)
        Updated (posterior) state.
    P : ndarray (..., n, n)
        Updated covariance (Joseph form, symmetric).
    y : ndarray (..., m)
        Innovation ``z - h(x)`` (angle components wrapped to ``(-pi, pi]``).
    S : ndarray (..., m, m)
        Innovation covariance ``H P H^T + R``.
    nis : ndarray (...) or float
        Normalised innovation squared ``y^T S^-1 y`` (chi-square with m dof if consistent).
    log_likelihood : ndarray (...) or float
        ``log N(y; 0, S)`` (natural log).
    K : ndarray (..., n, m)
        Kalman gain.
    """

    x: FloatArray
    P: FloatArray
    y: FloatArray
    S: FloatArray
    nis: Any
    log_likelihood: Any
    K: FloatArray


def _check(ll: Any, S: FloatArray) -> None:
    if type(ll) is float or np.ndim(ll) == 0:
        if not math.isfinite(ll):
            raise np.linalg.LinAlgError(
                f"innovation covariance S is not positive definite (S = {S.tolist()}); "
                "check R and P for negative or NaN entries"
            )
    elif not np.isfinite(ll).all():
        bad = np.argwhere(~np.isfinite(ll))[0]
        raise np.linalg.LinAlgError(
            f"innovation covariance S is not positive definite for batch element "
            f"{tuple(int(i) for i in bad)}; check R and P for negative or NaN entries"
        )


def _is_single(ndim_sum: int, *arrays: Any) -> bool:
    """True when the arguments carry no leading (batch) dimensions.

    Such calls go straight to the compiled single-state function; everything else goes
    through the broadcasting gufunc. Both wrap the *same* compiled core (``predict_core``,
    ``update_core``); only the dispatch differs (the gufunc machinery costs ~0.3 us per
    output array, a third of a 4-state update). Each argument has at least its core
    number of dimensions, so the sum equals ``ndim_sum`` only when none has more.
    """
    try:
        return sum([a.ndim for a in arrays]) == ndim_sum
    except AttributeError:  # lists, scalars: let the gufunc convert them
        return False


def _outputs(n: int, m: int) -> tuple[FloatArray, ...]:
    e = np.empty
    return e(n), e((n, n)), e(m), e((m, m)), e((n, m))


def predict(
    x: ArrayLike, P: ArrayLike, F: ArrayLike, Q: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Kalman prediction ``x <- F x``, ``P <- F P F^T + Q``.

    Parameters
    ----------
    x : array (..., n)
        State.
    P : array (..., n, n)
        Covariance.
    F : array (..., n, n)
        State-transition matrix.
    Q : array (..., n, n)
        Process-noise covariance.

    Returns
    -------
    x, P : predicted state ``(..., n)`` and covariance ``(..., n, n)`` (symmetric).
    """
    if _is_single(7, x, P, F, Q):
        # outputs allocated here: boxing arrays created inside compiled code costs more
        n = x.shape[0]  # type: ignore[union-attr]
        xo, Po = np.empty(n), np.empty((n, n))
        predict_core(x, P, F, Q, xo, Po)
        return xo, Po
    # the gufunc casts its inputs itself (lists, ints) and broadcasts leading dimensions
    return _predict_kernel(x, P, F, Q)  # type: ignore[no-any-return]


def extended_predict(
    fx: ArrayLike, P: ArrayLike, F: ArrayLike, Q: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """EKF prediction: the state is the already-propagated ``f(x)``; ``P <- F P F^T + Q``.

    ``F`` is the Jacobian of ``f`` at the prior state. Returns ``(fx, P)``.
    """
    return as_float64(fx), _cov_predict_kernel(P, F, Q)


def update(
    x: ArrayLike, P: ArrayLike, z: ArrayLike, H: ArrayLike, R: ArrayLike, check: bool = True
) -> UpdateResult:
    """Linear Kalman update with measurement ``z = H x + v``, ``v ~ N(0, R)``.

    Parameters
    ----------
    x : array (..., n)
    P : array (..., n, n)
    z : array (..., m)
    H : array (..., m, n)
    R : array (..., m, m)
    check : bool
        Raise when an innovation covariance is not positive definite (default). With
        ``check=False`` such elements get NaN ``x``, ``nis`` and ``log_likelihood`` (and an
        unspecified ``P``) instead, so a batch can isolate them (see
        :func:`seatrack.filters.base.finish_update`).

    Returns
    -------
    UpdateResult
        Posterior state and covariance (Joseph form), innovation, its covariance,
        NIS, log-likelihood and gain.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the innovation covariance is not positive definite (and ``check``).
    """
    if _is_single(8, x, P, z, H, R):
        xo, Po, y, S, K = _outputs(x.shape[0], z.shape[0])  # type: ignore[union-attr]
        nis, ll = _linear_update_single(x, P, z, H, R, xo, Po, y, S, K)
    else:
        xo, Po, y, S, nis, ll, K = _linear_update_kernel(x, P, z, H, R)
    if check:
        _check(ll, S)
    return UpdateResult(xo, Po, y, S, nis, ll, K)


def extended_update(
    x: ArrayLike,
    P: ArrayLike,
    z: ArrayLike,
    hx: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    angular: ArrayLike | None = None,
    check: bool = True,
) -> UpdateResult:
    """Extended Kalman update for a nonlinear measurement ``z = h(x) + v``.

    Parameters
    ----------
    x, P : prior state ``(..., n)`` and covariance ``(..., n, n)``.
    z : array (..., m)
        Measurement.
    hx : array (..., m)
        Predicted measurement ``h(x)``.
    H : array (..., m, n)
        Jacobian of ``h`` at ``x``.
    R : array (..., m, m)
        Measurement-noise covariance.
    angular : array of bool (m,), optional
        Components that are angles (rad); their innovations are wrapped to
        ``(-pi, pi]``. Measurement models expose this as ``model.angular``.
    check : bool
        As for :func:`update`.

    Returns
    -------
    UpdateResult
    """
    zz = as_float64(z)
    ang = np.zeros(zz.shape[-1]) if angular is None else np.asarray(angular, dtype=np.float64)
    if _is_single(9, x, P, zz, hx, H, R):
        xo, Po, y, S, K = _outputs(x.shape[0], zz.shape[0])  # type: ignore[union-attr]
        nis, ll = _extended_update_single(x, P, zz, hx, H, R, ang, xo, Po, y, S, K)
    else:
        xo, Po, y, S, nis, ll, K = _update_kernel(x, P, zz, hx, H, R, ang)
    if check:
        _check(ll, S)
    return UpdateResult(xo, Po, y, S, nis, ll, K)


@gufunc("void(f8[:], f8[:,:], f8[:])", "(m),(m,m)->()")
def _mahalanobis_kernel(y, S, out):  # pragma: no cover - compiled
    m = y.shape[0]
    L = np.empty((m, m))
    w = np.empty(m)
    logdet = cholesky_core(S, L)
    if not logdet == logdet:  # NaN: not positive definite
        out[0] = np.nan
        return
    forward_core(L, y, w)
    acc = 0.0
    for i in range(m):
        acc += w[i] * w[i]
    out[0] = acc


def mahalanobis(y: ArrayLike, S: ArrayLike) -> Any:
    """``y^T S^-1 y`` over leading dimensions (compiled); NaN where ``S`` is not positive
    definite or an input is not finite."""
    return _mahalanobis_kernel(y, S)


def nis_log_likelihood(y: ArrayLike, S: ArrayLike) -> tuple[Any, Any]:
    """NIS ``y^T S^-1 y`` and ``log N(y; 0, S)`` for innovations ``(..., m)``.

    Used where a likelihood is needed without a state update (e.g. model probabilities).
    """
    yy = as_float64(y)
    SS = as_float64(S)
    L = np.linalg.cholesky(SS)
    w = np.linalg.solve(L, yy[..., None])[..., 0]
    nis = np.einsum("...i,...i->...", w, w)
    logdet = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    return nis, -0.5 * (nis + logdet + yy.shape[-1] * _LOG_2PI)


def symmetrize(P: ArrayLike) -> FloatArray:
    """Return ``(P + P^T) / 2`` over the last two axes."""
    PP = as_float64(P)
    return 0.5 * (PP + np.swapaxes(PP, -1, -2))


def chi2_ppf(p: float, dof: int) -> float:
    """Chi-square quantile (gates): ``scipy.stats.chi2.ppf(p, dof)`` bit for bit -- the
    same special function, ``2 gammaincinv(dof / 2, p)``, with its edge values -- without
    importing ``scipy.stats`` (about half a second)."""
    from scipy.special import gammaincinv

    if not 0.0 <= p <= 1.0:
        return float("nan")
    if p == 0.0:
        return 0.0
    if p == 1.0:
        return float("inf")
    return float(2.0 * gammaincinv(dof / 2.0, p))


def chi2_cdf(x: float, dof: int) -> float:
    """Chi-square distribution function: ``scipy.stats.chi2.cdf(x, dof)`` bit for bit
    (``scipy.special.chdtr``) without importing ``scipy.stats``."""
    from scipy.special import chdtr

    return float(chdtr(dof, x)) if x >= 0.0 else 0.0
