"""Error metrics and consistency statistics for estimators.

Conventions
-----------
Errors are ``estimate - truth`` in SI units (metres, m/s, radians). Angular error
components must be wrapped to (-pi, pi] by the caller (:func:`seatrack.geometry.angle_diff`)
before they reach these functions. Arrays broadcast over leading dimensions: an error
array of shape ``(..., n)`` pairs with covariances of shape ``(..., n, n)``.

Consistency tests follow Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to
Tracking and Navigation* (2001), Sec. 5.4: for a consistent filter the normalised
estimation error squared (NEES) of an ``n``-dimensional state is chi-square with ``n``
degrees of freedom, so the average over ``N`` independent Monte-Carlo runs (ANEES) times
``N`` is chi-square with ``N n`` degrees of freedom. :func:`chi2_interval` gives the
two-sided acceptance interval of that average.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray
from scipy import stats

from seatrack.information import SingularMatrixError
from seatrack.information import as_float64
from seatrack.information import positive_definite_mask

__all__ = [
    "rmse",
    "rms_over_time",
    "peak_error",
    "position_error",
    "velocity_error",
    "error_norm",
    "nees",
    "nis",
    "anees",
    "anis",
    "chi2_interval",
    "fraction_inside",
]

FloatArray = NDArray[np.float64]


def rmse(err: ArrayLike, axis: int | tuple[int, ...] | None = 0) -> Any:
    """Root-mean-square of ``err`` along ``axis``.

    Parameters
    ----------
    err : array_like
        Errors (estimate - truth). With ``err`` of shape ``(runs, steps)`` and ``axis=0``
        this is the RMSE over time; with ``axis=None`` the overall RMSE.
    axis : int, tuple of int or None
        Axis (axes) to average over. ``None`` averages over all elements.

    Returns
    -------
    ndarray or float
        ``sqrt(mean(err**2, axis))``; NaN entries are ignored (missed updates).
    """
    e = as_float64(err)
    return np.sqrt(np.nanmean(e * e, axis=axis))


def error_norm(err: ArrayLike) -> FloatArray:
    """Euclidean norm of error vectors along the last axis: shape ``(..., n) -> (...)``."""
    e = as_float64(err)
    return np.sqrt(np.sum(e * e, axis=-1))


def position_error(estimate: ArrayLike, truth: ArrayLike, dims: int = 2) -> FloatArray:
    """Euclidean position error of states laid out ``[x, y, (z), vx, vy, (vz), ...]``.

    Parameters
    ----------
    estimate, truth : array_like, shape (..., n)
        States with positions first (metres).
    dims : int
        Number of position components (2 or 3).

    Returns
    -------
    ndarray, shape (...)
        ``|p_est - p_true|`` in metres.
    """
    d = as_float64(estimate)[..., :dims] - as_float64(truth)[..., :dims]
    return error_norm(d)


def velocity_error(estimate: ArrayLike, truth: ArrayLike, dims: int = 2) -> FloatArray:
    """Euclidean velocity error (m/s) of states laid out ``[pos(dims), vel(dims), ...]``."""
    d = as_float64(estimate)[..., dims : 2 * dims] - as_float64(truth)[..., dims : 2 * dims]
    return error_norm(d)


def rms_over_time(err_norm: ArrayLike, skip: int = 0) -> float:
    """Time-averaged RMSE of an error-norm history.

    Parameters
    ----------
    err_norm : array_like, shape (runs, steps) or (steps,)
        Error magnitudes (e.g. from :func:`position_error`).
    skip : int
        Number of initial steps excluded (transient).

    Returns
    -------
    float
        ``sqrt(mean(err_norm[..., skip:]**2))`` over runs and steps, NaN ignored.
    """
    e = as_float64(err_norm)[..., skip:]
    return float(np.sqrt(np.nanmean(e * e)))


def peak_error(err_norm: ArrayLike, skip: int = 0) -> float:
    """Largest error magnitude after ``skip`` initial steps (NaN ignored)."""
    e = np.abs(as_float64(err_norm)[..., skip:])
    return float(np.nanmax(e))


def _quadratic_form(v: FloatArray, M: FloatArray) -> FloatArray:
    """``v^T M^-1 v`` for ``v (..., n)``, ``M (..., n, n)`` symmetric PD, via Cholesky.

    Every ``M`` first passes the explicit scale-invariant test of
    :func:`seatrack.information.positive_definite_mask` (not left to LAPACK).

    Raises
    ------
    seatrack.information.SingularMatrixError
        (a ``numpy.linalg.LinAlgError``) if some ``M`` is singular or not positive definite;
        the message gives the index of the first.
    """
    if v.shape[-1] != M.shape[-1] or M.shape[-1] != M.shape[-2]:
        raise ValueError(f"shape mismatch: vector {v.shape} vs matrix {M.shape}")
    shape = np.broadcast_shapes(v.shape[:-1], M.shape[:-2])
    n = v.shape[-1]
    vb = np.broadcast_to(v, (*shape, n))
    Mb = np.broadcast_to(M, (*shape, n, n))
    ok = positive_definite_mask(Mb)
    if not np.all(ok):
        idx = tuple(int(i) for i in np.argwhere(~ok)[0])
        raise SingularMatrixError(
            f"covariance at index {idx} is singular or not positive definite to working "
            "precision (scaled eigenvalue test)"
        )
    L = np.linalg.cholesky(Mb)
    # Solve L w = v; then v^T M^-1 v = |w|^2. Batched triangular solve via np.linalg.solve
    # (general solve on a triangular matrix is exact up to rounding, and broadcasts).
    w = np.linalg.solve(L, vb[..., None])[..., 0]
    return np.sum(w * w, axis=-1)


def nees(err: ArrayLike, P: ArrayLike) -> Any:
    """Normalised estimation error squared ``e^T P^-1 e`` per sample.

    Bar-Shalom et al. (2001) eq. (5.4.2-1).

    Parameters
    ----------
    err : array_like, shape (..., n)
        Estimation error (estimate - truth), angles wrapped.
    P : array_like, shape (..., n, n)
        Filter covariance (symmetric positive definite). Leading dims broadcast.

    Returns
    -------
    ndarray, shape (...)
        NEES; chi-square with ``n`` dof for a consistent estimator.
    """
    return _quadratic_form(as_float64(err), as_float64(P))


def nis(y: ArrayLike, S: ArrayLike) -> Any:
    """Normalised innovation squared ``y^T S^-1 y`` per sample (Bar-Shalom eq. 5.4.2-3).

    Parameters
    ----------
    y : array_like, shape (..., m)
        Innovation (angles wrapped to (-pi, pi]).
    S : array_like, shape (..., m, m)
        Innovation covariance.
    """
    return _quadratic_form(as_float64(y), as_float64(S))


def anees(err: ArrayLike, P: ArrayLike, axis: int | None = 0) -> Any:
    """Average NEES over Monte-Carlo runs.

    Parameters
    ----------
    err : array_like, shape (runs, ..., n)
    P : array_like, shape (runs, ..., n, n)
    axis : int or None
        Axis of the NEES array (shape ``(runs, ...)``) to average over; ``None`` for all.

    Returns
    -------
    ndarray or float
        Mean NEES (NaN entries ignored). Compare with :func:`chi2_interval(n, runs)`.
    """
    return np.nanmean(nees(err, P), axis=axis)


def anis(y: ArrayLike, S: ArrayLike, axis: int | None = 0) -> Any:
    """Average NIS over Monte-Carlo runs (see :func:`anees`)."""
    return np.nanmean(nis(y, S), axis=axis)


def chi2_interval(dof: int, n_runs: int, alpha: float = 0.05) -> tuple[float, float]:
    """Two-sided ``1 - alpha`` acceptance interval for the average of chi-square values.

    If ``q_1..q_N`` are independent chi-square(``dof``), then ``sum q_i`` is
    chi-square(``N dof``), so the average lies in
    ``[chi2.ppf(alpha/2, N dof) / N, chi2.ppf(1 - alpha/2, N dof) / N]`` with probability
    ``1 - alpha`` (Bar-Shalom et al. 2001, Sec. 5.4.2).

    Parameters
    ----------
    dof : int
        Degrees of freedom of one value (state or measurement dimension).
    n_runs : int
        Number of averaged values (Monte-Carlo runs).
    alpha : float
        Significance level (default 5 %).

    Returns
    -------
    (lo, hi) : tuple of float
    """
    if dof < 1 or n_runs < 1:
        raise ValueError(f"dof and n_runs must be >= 1, got dof={dof}, n_runs={n_runs}")
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")
    k = dof * n_runs
    lo = float(stats.chi2.ppf(alpha / 2.0, k)) / n_runs
    hi = float(stats.chi2.ppf(1.0 - alpha / 2.0, k)) / n_runs
    return lo, hi


def fraction_inside(values: ArrayLike, lo: float, hi: float) -> float:
    """Fraction of finite ``values`` inside ``[lo, hi]`` (e.g. ANEES over time vs bounds)."""
    v = as_float64(values)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return float("nan")
    return float(np.mean((v >= lo) & (v <= hi)))
