"""Levenberg–Marquardt (damped Gauss–Newton) on a batch of TMA problems.

Spec step 3 in standard form: ``delta_beta = (J^T W J)^-1 J^T W r``, damped as
``(J^T W J + lambda D) delta_beta = J^T W r`` with ``D = diag(J^T W J)``. The system is
solved in scaled form: with ``S = D^-1/2`` it reads ``(S A S + lambda I) y = S g``,
``delta_beta = S y``. The scaled matrix has unit diagonal and eigenvalues in
``[lambda, n + lambda]``, so the solve is well posed for every ``lambda >= 1e-12`` by
construction (no reliance on LAPACK to flag a singular matrix), and a step is taken only if
the weighted cost decreases -- the iteration never diverges.

Convergence (spec step 5): the position change at the last bearing time
``||Delta p(T_M)|| = ||sum_j Delta V_j T'_Mj + Delta P0||`` below ``position_tolerance`` on an
accepted, nearly undamped step, or a relative cost decrease below ``cost_tolerance``, or a
rejected nearly undamped step whose predicted gain is negligible (already at the minimum).

``iterations`` counts LM *trials* (each one Jacobian, one linear solve, one residual
evaluation), accepted or rejected.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seatrack.tma.config import TMAConfig
from seatrack.tma.problem import Problem

FloatArray = NDArray[np.float64]

__all__ = ["LMResult", "levenberg_marquardt"]

_LAMBDA_MIN = 1e-12
_TINY = 1e-300


@dataclass(frozen=True)
class LMResult:
    """Batch result: ``beta (K, n)``, ``cost (K,)``, ``iterations (K,)`` (trials),
    ``converged (K,)``, residuals ``r (K, R)`` and Jacobian ``J (K, R, n)`` at ``beta``."""

    beta: FloatArray
    cost: FloatArray
    iterations: NDArray[np.int64]
    converged: NDArray[np.bool_]
    r: FloatArray
    J: FloatArray


def _damped_step(A: FloatArray, g: FloatArray, lam: FloatArray) -> FloatArray:
    """Solve ``(A + lam diag(A)) step = g`` per batch entry in unit-diagonal scaled form."""
    n = A.shape[-1]
    diag = np.arange(n)
    D = A[:, diag, diag]
    D = np.maximum(D, 1e-12 * D.max(axis=1, keepdims=True) + _TINY)
    s = 1.0 / np.sqrt(D)
    As = A * (s[:, :, None] * s[:, None, :])
    As[:, diag, diag] += lam[:, None]
    rhs = s * g
    if not (np.isfinite(As).all() and np.isfinite(rhs).all()):
        # non-finite entries (a start at infinity): a zero step, which is then rejected
        bad = ~np.all(np.isfinite(As.reshape(As.shape[0], -1)), axis=1)
        bad |= ~np.all(np.isfinite(rhs), axis=1)
        As[bad] = np.eye(n)
        rhs[bad] = 0.0
    y = np.linalg.solve(As, rhs[..., None])[..., 0]
    return np.asarray(s * y, dtype=float)


def levenberg_marquardt(
    prob: Problem, beta0: FloatArray, cfg: TMAConfig, max_iter: int
) -> LMResult:
    """Damped Gauss–Newton on a batch ``prob`` from ``beta0 (K, n)``; at most ``max_iter``
    trials per entry (see module docstring)."""
    beta = np.array(beta0, dtype=float)
    K, n = beta.shape
    m = n // 2
    w = prob.weights
    r, J = prob.evaluate(beta)
    cost = np.sum(w * r * r, axis=1)
    lam = np.full(K, cfg.lm_lambda0)
    done = ~np.isfinite(cost)
    conv = np.zeros(K, bool)
    iters = np.zeros(K, np.int64)
    with np.errstate(all="ignore"):
        for _ in range(max_iter):
            active = ~done
            if not active.any():
                break
            JwT = (J * w[..., None]).swapaxes(-1, -2)
            A = JwT @ J
            g = (JwT @ r[..., None])[..., 0]
            step = _damped_step(A, g, lam)
            trial = beta + step
            r2, J2 = prob.evaluate(trial)
            cost2 = np.sum(w * r2 * r2, axis=1)
            ok = active & (cost2 < cost)  # NaN compares False
            small_lam = lam <= cfg.lm_converge_lambda
            dp = (prob.c_last[:, None, :] @ step.reshape(K, m, 2))[:, 0]
            dpos = np.hypot(dp[:, 0], dp[:, 1])
            rel = (cost - cost2) / np.maximum(cost, _TINY)
            # convergence only on nearly undamped steps (a tiny step forced by damping is not)
            new_conv = (
                ok & small_lam & ((dpos < cfg.position_tolerance) | (rel < cfg.cost_tolerance))
            )
            rejected = active & ~ok
            if rejected.any():
                # a rejected nearly-undamped step with negligible predicted gain: at the minimum
                pred = np.sum(step * (2 * g - (A @ step[..., None])[..., 0]), axis=1)
                new_conv |= (
                    rejected & small_lam & (pred <= cfg.cost_tolerance * np.maximum(cost, _TINY))
                )
            if ok.all():
                beta, r, J, cost = trial, r2, J2, cost2
            elif ok.any():
                beta[ok], r[ok], J[ok], cost[ok] = trial[ok], r2[ok], J2[ok], cost2[ok]
            lam = np.where(
                active,
                np.where(ok, np.maximum(lam * cfg.lm_decrease, _LAMBDA_MIN), lam * cfg.lm_increase),
                lam,
            )
            iters += active
            conv |= new_conv
            done |= new_conv | (lam > cfg.lm_lambda_max)
    return LMResult(beta, cost, iters, conv, r, J)
