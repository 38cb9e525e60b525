"""Cramér–Rao lower bounds: batch (Fisher information) and posterior (recursive).

* :func:`fisher_crb` -- the CRB of a deterministic parameter estimated from measurements
  ``z = h(theta) + v``, ``v ~ N(0, W^-1)``: ``CRB = (J^T W J)^-1`` with ``J = dh/dtheta`` at
  the true parameter (e.g. bearings-only TMA, Nardone, Lindgren & Gong 1984).
* :func:`pcrb_linear` -- the posterior CRB of a linear-Gaussian system, which equals the
  Kalman filter covariance.
* :func:`pcrb` -- the Tichavský, Muravchik & Nehorai (1998) recursion for nonlinear
  measurements (and linear or nonlinear dynamics) with additive Gaussian noise; the
  expectations over the true state are taken as averages over Monte-Carlo truth samples.

Conventions: the state of step ``k`` is ``x_k``; the dynamics are
``x_{k+1} = f_k(x_k) + w_k``, ``w_k ~ N(0, Q_k)``; the measurement of step ``k`` is
``z_k = h_k(x_k) + v_k``, ``v_k ~ N(0, R_k)``. Bounds are returned as covariances
(inverse information matrices), shape ``(K + 1, n, n)`` for steps ``0..K``.

Every inverse (information matrices, covariances ``P0``, ``Q``, ``R``) is preceded by the
explicit scale-invariant rank test of :mod:`seatrack.information`; a singular matrix raises
:class:`~seatrack.information.SingularMatrixError` (a ``numpy.linalg.LinAlgError``) naming the
matrix and the step, whatever the BLAS build would have done.
"""

from __future__ import annotations

from collections.abc import Callable
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.information import SingularMatrixError
from seatrack.information import as_float64
from seatrack.information import check_information
from seatrack.information import fisher_information
from seatrack.information import invert_information
from seatrack.information import invert_jacobian_information

__all__ = [
    "SingularMatrixError",
    "crb_deterministic",
    "fisher_crb",
    "fisher_information",
    "pcrb",
    "pcrb_linear",
]

FloatArray = NDArray[np.float64]


def _spd_inverse(M: FloatArray, what: str) -> FloatArray:
    """Inverse of a symmetric positive-definite matrix after the explicit scaled rank test
    of :func:`seatrack.information.invert_information` (raises
    :class:`~seatrack.information.SingularMatrixError` naming ``what``)."""
    return invert_information(M, what)


def fisher_crb(J: ArrayLike, W: ArrayLike) -> FloatArray:
    """Cramér–Rao bound ``(J^T W J)^-1`` for a batch estimate.

    Parameters
    ----------
    J : array_like, shape (m, n)
        Measurement Jacobian at the true parameter.
    W : array_like, scalar, (m,) or (m, m)
        Inverse measurement covariance.

    Returns
    -------
    ndarray, shape (n, n)
        Lower bound on the covariance of any unbiased estimator.

    Raises
    ------
    seatrack.information.SingularMatrixError
        (a :class:`numpy.linalg.LinAlgError`) if the whitened Jacobian ``W^1/2 J`` is
        rank-deficient by the explicit scaled test (the parameters are not observable, e.g.
        bearings-only TMA without an own-ship manoeuvre). The inverse is computed from the
        SVD of the column-scaled whitened Jacobian, never by hoping LAPACK notices a singular
        matrix.
    """
    return invert_jacobian_information(J, W, "Fisher information matrix")


def _per_step(value: Any, K: int, name: str, allow_none: bool = False) -> list[Any]:
    """Expand a constant matrix or a per-step sequence to a list of ``K`` entries."""
    if value is None:
        if allow_none:
            return [None] * K
        raise ValueError(f"{name} is required")
    if isinstance(value, np.ndarray) and value.ndim == 2:
        return [value] * K
    if isinstance(value, np.ndarray) and value.ndim == 3:
        seq: Sequence[Any] = list(value)
    elif isinstance(value, (list, tuple)):
        seq = value
    else:
        arr = as_float64(value)
        if arr.ndim == 2:
            return [arr] * K
        seq = list(arr)
    if len(seq) != K:
        raise ValueError(f"{name} has {len(seq)} entries, expected {K}")
    return [None if v is None else as_float64(v) for v in seq]


def _seq_len(value: Any) -> int | None:
    if isinstance(value, (list, tuple)):
        return len(value)
    if value is not None and np.ndim(value) == 3:
        return int(np.shape(value)[0])
    return None


def _n_steps(
    n_steps: int | None, transitions: Sequence[Any], measurements: Sequence[Any], offset: int
) -> int:
    """Number of transitions ``K`` from ``n_steps`` or the lengths of per-step sequences."""
    lengths = {n for n in (_seq_len(v) for v in transitions) if n is not None}
    lengths |= {n - offset for n in (_seq_len(v) for v in measurements) if n is not None}
    if n_steps is not None:
        return int(n_steps)
    if len(lengths) == 1:
        return lengths.pop()
    if not lengths:
        raise ValueError("n_steps is required when all of F, Q, H, R are constant")
    raise ValueError(f"per-step sequences imply different numbers of steps {sorted(lengths)}")


def _measurement_info(H: FloatArray | None, R: FloatArray | None) -> FloatArray | None:
    if H is None:
        return None
    if R is None:
        raise ValueError("R is missing for a step that has H")
    Hm = np.atleast_2d(H)
    info = Hm.T @ invert_information(np.atleast_2d(R), "measurement covariance R") @ Hm
    return 0.5 * (info + info.T)


def pcrb_linear(
    P0: ArrayLike,
    F: ArrayLike | Sequence[ArrayLike],
    Q: ArrayLike | Sequence[ArrayLike],
    H: ArrayLike | Sequence[ArrayLike | None],
    R: ArrayLike | Sequence[ArrayLike | None],
    n_steps: int | None = None,
    measure_first: bool = False,
) -> FloatArray:
    """Posterior CRB of a linear-Gaussian system (Tichavský et al. 1998, eq. (21)).

    ``J_0 = P0^-1`` (plus ``H_0^T R_0^-1 H_0`` if ``measure_first``) and

    ``J_{k+1} = (Q_k + F_k J_k^-1 F_k^T)^-1 + H_{k+1}^T R_{k+1}^-1 H_{k+1}``.

    For a linear-Gaussian system the bound is attained: ``J_k^-1`` equals the Kalman
    filter covariance ``P_{k|k}`` started from ``P_{0|0} = P0``.

    Parameters
    ----------
    P0 : array_like, (n, n)
        Prior covariance of ``x_0``.
    F, Q : array_like, (n, n) constant, or sequence of ``K`` matrices (per transition
        ``k -> k+1``).
    H, R : array_like, (m, n) and (m, m) constant, or sequences of ``K`` (measurements of
        steps ``1..K``) or ``K + 1`` entries if ``measure_first`` (steps ``0..K``). A
        ``None`` entry of ``H`` means no measurement at that step (missed detection).
    n_steps : int, optional
        ``K``; required only when every matrix is constant.
    measure_first : bool
        Whether step 0 also has a measurement.

    Returns
    -------
    ndarray, shape (K + 1, n, n)
        Bound covariances ``J_k^-1`` for ``k = 0..K``.
    """
    P0m = as_float64(P0)
    K = _n_steps(n_steps, (F, Q), (H, R), int(measure_first))
    Fs = _per_step(F, K, "F")
    Qs = _per_step(Q, K, "Q")
    nm = K + int(measure_first)
    Hs = _per_step(H, nm, "H")
    Rs = _per_step(R, nm, "R", allow_none=True)
    if not measure_first:
        Hs = [None, *Hs]
        Rs = [None, *Rs]
    n = P0m.shape[0]
    out = np.empty((K + 1, n, n))
    J = _spd_inverse(P0m, "prior covariance P0")
    info0 = _measurement_info(Hs[0], Rs[0])
    if info0 is not None:
        J = J + info0
    out[0] = _spd_inverse(J, "information matrix at step 0")
    for k in range(K):
        Pp = Fs[k] @ out[k] @ Fs[k].T + Qs[k]
        J = _spd_inverse(Pp, f"predicted bound at step {k + 1}")
        info = _measurement_info(Hs[k + 1], Rs[k + 1])
        if info is not None:
            J = J + info
        out[k + 1] = _spd_inverse(J, f"information matrix at step {k + 1}")
    return out


def pcrb(
    P0: ArrayLike,
    truth: ArrayLike,
    Q: ArrayLike | Sequence[ArrayLike],
    measurement_jacobian: Callable[[FloatArray, int], FloatArray | None],
    R: ArrayLike | Sequence[ArrayLike],
    transition_jacobian: Callable[[FloatArray, int], FloatArray] | ArrayLike | None = None,
    measure_first: bool = False,
) -> FloatArray:
    """Posterior CRB for additive-Gaussian nonlinear filtering (Tichavský et al. 1998).

    With ``F_k = df_k/dx (x_k)`` and ``H_k = dh_k/dx (x_k)`` evaluated on the true states,

    * ``D11 = E[F_k^T Q_k^-1 F_k]``, ``D12 = -E[F_k^T] Q_k^-1 = D21^T``,
    * ``D22 = Q_k^-1 + E[H_{k+1}^T R_{k+1}^-1 H_{k+1}]``,
    * ``J_{k+1} = D22 - D21 (J_k + D11)^-1 D12`` (eq. (21)).

    When the dynamics are linear (``transition_jacobian`` a constant matrix) the
    equivalent form ``J_{k+1} = (Q_k + F J_k^-1 F^T)^-1 + E[H^T R^-1 H]`` is used, which
    does not need ``Q`` to be invertible.

    Parameters
    ----------
    P0 : array_like, (n, n)
        Prior covariance of ``x_0`` (``J_0 = P0^-1``).
    truth : array_like, (runs, K + 1, n) or (K + 1, n)
        True states of Monte-Carlo runs (the expectations are averages over runs).
    Q : array_like, (n, n) or sequence of ``K`` -- process noise per transition.
    measurement_jacobian : callable ``(x, k) -> H (m, n)`` or None
        Jacobian of ``h_k`` at true state ``x`` of step ``k`` (None: no measurement).
    R : array_like, (m, m) or sequence of ``K + 1`` (indexed by step) -- measurement noise.
    transition_jacobian : callable ``(x, k) -> F (n, n)``, a constant (n, n) matrix, or
        a sequence of ``K`` matrices. Default: identity.
    measure_first : bool
        Whether step 0 is measured.

    Returns
    -------
    ndarray, shape (K + 1, n, n)
        Bound covariances ``J_k^-1``.
    """
    X = as_float64(truth)
    if X.ndim == 2:
        X = X[None]
    runs, K1, n = X.shape
    K = K1 - 1
    Qs = _per_step(Q, K, "Q")
    Rs = _per_step(R, K + 1, "R")
    linear: list[FloatArray] | None = None
    if transition_jacobian is None:
        linear = [np.eye(n)] * K
    elif not callable(transition_jacobian):
        linear = _per_step(transition_jacobian, K, "transition_jacobian")

    def expected_info(k: int) -> FloatArray | None:
        acc = np.zeros((n, n))
        seen = False
        for r in range(runs):
            Hk = measurement_jacobian(X[r, k], k)
            if Hk is None:
                continue
            info = _measurement_info(as_float64(Hk), Rs[k])
            assert info is not None
            acc += info
            seen = True
        return acc / runs if seen else None

    out = np.empty((K + 1, n, n))
    J = _spd_inverse(as_float64(P0), "prior covariance P0")
    if measure_first:
        i0 = expected_info(0)
        if i0 is not None:
            J = J + i0
    out[0] = _spd_inverse(J, "information matrix at step 0")
    for k in range(K):
        if linear is not None:
            Fk = linear[k]
            J = _spd_inverse(Fk @ out[k] @ Fk.T + Qs[k], f"predicted bound at step {k + 1}")
        else:
            assert callable(transition_jacobian)
            Qi = _spd_inverse(Qs[k], f"Q at step {k}")
            D11 = np.zeros((n, n))
            EF = np.zeros((n, n))
            for r in range(runs):
                Fk = as_float64(transition_jacobian(X[r, k], k))
                D11 += Fk.T @ Qi @ Fk
                EF += Fk
            D11 /= runs
            EF /= runs
            D12 = -EF.T @ Qi
            A = _spd_inverse(J + D11, f"J + D11 at step {k}")
            J = Qi - D12.T @ A @ D12
        info = expected_info(k + 1)
        if info is not None:
            J = J + info
        out[k + 1] = _spd_inverse(J, f"information matrix at step {k + 1}")
    return out


def crb_deterministic(
    info: ArrayLike | Sequence[ArrayLike],
    F: ArrayLike | Sequence[ArrayLike],
    rcond: float | None = None,
    prior: ArrayLike | None = None,
) -> FloatArray:
    """Filtering CRB of a deterministic (noise-free) trajectory, with optional prior.

    With no process noise, the information about ``x_k`` from the prior and the
    measurements of steps ``0..k`` obeys

    ``J_0 = J_prior + I_0``, ``J_{k+1} = F_k^-T J_k F_k^-1 + I_{k+1}``,

    the limit ``Q -> 0`` of the Tichavský et al. (1998) recursion. Without a prior
    (``P0 -> infinity``) it equals the batch Fisher CRB of ``x_k`` from those
    measurements: the bound for a constant-velocity target tracked from its first plot.
    With the information ``J_prior`` of the prior the filters start from (e.g. a zero-mean
    velocity prior, ``diag(0, 0, 1/s^2, 1/s^2)``) it is the posterior CRB, a bound for
    estimators that use that prior as well.

    Parameters
    ----------
    info : (K + 1, n, n)
        Expected measurement information ``E[H_k^T R_k^-1 H_k]`` of each step (times the
        detection probability for missed detections without clutter).
    F : (n, n) or (K, n, n)
        Invertible transition matrices.
    rcond : float, optional
        ``J_k`` counts as singular (not yet observable) when the smallest eigenvalue of
        ``J_k`` scaled to unit diagonal is at most ``rcond`` times its largest (default
        :func:`seatrack.information.information_rtol`, ``100 n eps``); the test is
        scale-invariant (units of position and velocity do not matter).
    prior : (n, n), optional
        Prior information ``J_prior`` (inverse prior covariance; may be singular, e.g.
        none on the position), symmetric positive semi-definite.

    Returns
    -------
    ndarray, shape (K + 1, n, n)
        ``J_k^-1``; NaN where ``J_k`` is still singular (too few measurements so far).
    """
    I = np.asarray(info, dtype=np.float64)
    K1, n, _ = I.shape
    Fs = _per_step(F, K1 - 1, "F")
    out = np.full((K1, n, n), np.nan)
    J = 0.5 * (I[0] + I[0].T)
    if prior is not None:
        Jp = as_float64(prior)
        if Jp.shape != (n, n) or not np.all(np.isfinite(Jp)):
            raise ValueError(f"prior information must be a finite ({n}, {n}) matrix")
        if np.linalg.eigvalsh(0.5 * (Jp + Jp.T)).min() < -1e-12 * max(np.abs(Jp).max(), 1e-300):
            raise ValueError("prior information must be positive semi-definite")
        J = J + 0.5 * (Jp + Jp.T)
    for k in range(K1):
        if k > 0:
            Fi = np.linalg.solve(Fs[k - 1], np.eye(n))  # transition: invertible by contract
            J = Fi.T @ J @ Fi + I[k]
            J = 0.5 * (J + J.T)
        if not check_information(J, rcond).full_rank:
            continue  # not yet observable
        out[k] = _spd_inverse(J, "information")
    return out
