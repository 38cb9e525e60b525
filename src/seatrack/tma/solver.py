"""Batch bearings-only target motion analysis: the iterative filter of DE 3446658.

Spec: ``specs/tma.md``. The target moves with constant velocity on one or more legs;
from all stored bearings ``B_Mi`` (times ``T_Mi``, observer positions ``(X_Ei, Y_Ei)``)
and optional support values the solver estimates ``beta = (X0, Y0, Vx0, Vy0, Vx1, Vy1,
...)``: position at the reference time ``t0`` (the first bearing) and one velocity per leg
(see :mod:`seatrack.tma.legs`).

Algorithm (spec "Algorithm", in standard form)
-----------------------------------------------
* Residuals ``delta_i = wrap(B_Mi - bearing(X_i - X_Ei, Y_i - Y_Ei))`` (wrapped at every
  difference), Jacobian rows ``J_i = bearing_jacobian(d_i) (x) c_i`` -- for one leg exactly
  the spec's ``[R_y/R^2, -R_x/R^2, T R_y/R^2, -T R_x/R^2]``; support rows from
  :mod:`seatrack.tma.support`.
* Weighted Gauss–Newton step ``(J^T W J)^-1 J^T W delta`` (``W = 1/sigma^2``; the patent's
  "filter coefficients" with ``W = I``), with Levenberg–Marquardt damping
  ``(J^T W J + lambda diag(J^T W J))``: a step is accepted only if the weighted cost
  decreases, so the iteration never diverges.
* Convergence (spec step 5): the position change at the *current* (last) measurement
  time ``||Delta p(T_M)|| = ||sum_j Delta V_j T'_Mj + Delta P0||`` below
  ``position_tolerance`` (accepted, nearly undamped step), or the relative cost change
  below ``cost_tolerance``.

Parametrisation: Cartesian ``beta`` throughout (as in the patent), both for the start
search and the final answer; the covariance is ``(J^T W J)^-1`` in that state.

Automatic start (no user guess): *two-range* starts -- the target at range ``r1`` on the
first bearing and at range ``r2`` on the last bearing, joined by a constant velocity, for
``r1, r2`` on a log-spaced grid (``start_ranges``) -- plus the pseudo-linear estimate
(bearing lines written as linear equations). All starts of all contacts are iterated
together as one numpy batch for ``start_iterations`` LM iterations on at most
``start_max_bearings`` evenly spaced bearings; the lowest-cost start is then refined on
all the data. Every numeric choice is a :class:`TMAConfig` field.

Observability (spec "Observability"): the solution is ``observable`` only if (a) the
geometry can fix the range scale -- the own-ship track deviates from a straight
constant-velocity line by more than ``min_observer_deviation`` (an own-ship leg change) or
at least one support value is given; (b) the column-equilibrated whitened Jacobian
``W^(1/2) J D^-1`` has condition number below ``max_condition`` (its smallest singular
value is reported too) and there are at least as many rows as states; and (c) the range
is determined to first order: ``sigma_range / range <= max_relative_range_sigma``.
Otherwise the range-dependent operator values are NaN (their 1-sigma too) and a warning
says why.

Performance: residuals and Jacobians are evaluated for a whole batch (contacts x starts x
bearings) in numpy; padded rows carry zero weight.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2, norm

from seatrack.geometry import bearing, wrap_pi
from seatrack.models.measurement import bearing_jacobian
from seatrack.tma.bounds import operator_values, position_crb
from seatrack.tma.legs import leg_starts, leg_time_matrix
from seatrack.tma.support import SupportRows, SupportValue, support_residuals, support_rows

FloatArray = NDArray[np.float64]

__all__ = [
    "Bearings",
    "TMAConfig",
    "LastEstimate",
    "TMASolution",
    "bearing_residuals",
    "solve",
    "solve_many",
]


# ---------------------------------------------------------------------------
# Inputs and configuration
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Bearings:
    """Bearings of one contact (SI units, radians).

    Parameters
    ----------
    t : (N,) s, strictly increasing.
    bearing : (N,) rad, true bearing clockwise from North (any wrap).
    observer : (N, 2) m, observer position (East, North) at each bearing.
    sigma : (N,) rad, optional per-bearing standard deviation (else the solver's ``sigma``).
    """

    t: FloatArray
    bearing: FloatArray
    observer: FloatArray
    sigma: FloatArray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).reshape(-1)
        b = np.asarray(self.bearing, dtype=float).reshape(-1)
        o = np.asarray(self.observer, dtype=float)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "bearing", b)
        if o.ndim != 2 or o.shape[1] < 2 or o.shape[0] != t.size:
            raise ValueError(f"observer must have shape (N, 2) with N = {t.size}, got {o.shape}")
        object.__setattr__(self, "observer", o[:, :2])
        if b.size != t.size:
            raise ValueError(f"{b.size} bearings for {t.size} times")
        if t.size < 2:
            raise ValueError(f"TMA needs at least 2 bearings, got {t.size}")
        for name, a in (("t", t), ("bearing", b), ("observer", o[:, :2])):
            bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(t.size, -1)), axis=1))
            if bad.size:
                raise ValueError(f"{name} is not finite at index {bad[0]}")
        dt = np.diff(t)
        if np.any(dt <= 0):
            i = int(np.flatnonzero(dt <= 0)[0]) + 1
            raise ValueError(
                f"times must be strictly increasing; index {i}: {t[i]:g} after {t[i - 1]:g}"
            )
        if self.sigma is not None:
            s = np.broadcast_to(np.asarray(self.sigma, dtype=float), t.shape).copy()
            if not np.all(np.isfinite(s) & (s > 0)):
                raise ValueError("bearing sigma must be finite and positive")
            object.__setattr__(self, "sigma", s)

    def __len__(self) -> int:
        return int(self.t.size)


@dataclass(frozen=True)
class TMAConfig:
    """Solver configuration (spec defaults; every [reading] choice is a field).

    Parameters
    ----------
    sigma : float
        Bearing standard deviation (rad) when the bearings carry none. Weights ``1/sigma^2``.
    max_iterations : int
        Iteration limit of the final refinement (accepted + rejected LM trials).
    position_tolerance : float
        Patent's convergence threshold on the position change at the last time, m.
    cost_tolerance : float
        Relative cost-change threshold (second convergence test).
    lm_lambda0, lm_increase, lm_decrease, lm_lambda_max : float
        Levenberg–Marquardt damping: start, factor after a rejected / accepted step, give-up
        limit. ``lm_converge_lambda`` is the largest damping at which the convergence tests
        may declare convergence (a tiny step forced by heavy damping is not convergence).
    support_residual : "linear" | "square"
        [reading] linear range/speed residuals (default) or the patent's squares.
    start_ranges : (min, max, count)
        Log-spaced range grid (m) for the two-range automatic start.
    start_iterations : int
        LM iterations applied to every start before the best is kept.
    start_max_bearings : int
        Bearings (evenly spaced, first and last included) used in the start search.
    start_pseudolinear : bool
        Add the pseudo-linear estimate as a start.
    min_observer_deviation : float
        Own-ship deviation (m) from a straight constant-velocity track that counts as an
        own-ship manoeuvre (smaller deviations are taken as navigation noise).
    max_condition : float
        Largest acceptable condition number of the column-equilibrated whitened Jacobian.
    max_relative_range_sigma : float
        Largest acceptable ``sigma_range / range`` at the last time. Near the unobservable
        limit (e.g. a straight own-ship track with navigation noise) the first-order
        covariance is not a meaningful description of a very non-Gaussian error, so such
        solutions are reported as not observable. ``inf`` disables the test.
    confidence : float
        Probability of the reported confidence values (two-sided) and ellipses.
    residual_test_probability : float
        A warning is given when the weighted cost exceeds this quantile of the chi-square
        distribution with ``N + M - n`` degrees of freedom (residuals too large for the
        stated sigmas: wrong sigma, outliers or a target manoeuvre not in the model).
    """

    sigma: float = math.radians(1.0)
    max_iterations: int = 50
    position_tolerance: float = 0.5
    cost_tolerance: float = 1e-10
    lm_lambda0: float = 1e-3
    lm_increase: float = 10.0
    lm_decrease: float = 0.1
    lm_lambda_max: float = 1e12
    lm_converge_lambda: float = 1e-2
    support_residual: str = "linear"
    start_ranges: tuple[float, float, int] = (500.0, 60_000.0, 7)
    start_iterations: int = 6
    start_max_bearings: int = 24
    start_pseudolinear: bool = True
    min_observer_deviation: float = 10.0
    max_condition: float = 1e7
    max_relative_range_sigma: float = 0.5
    residual_test_probability: float = 0.999
    confidence: float = 0.95

    def __post_init__(self) -> None:
        if self.support_residual not in ("linear", "square"):
            raise ValueError(
                f"support_residual must be 'linear' or 'square', got {self.support_residual!r}"
            )
        if not (self.sigma > 0 and np.isfinite(self.sigma)):
            raise ValueError(f"sigma must be a positive number of radians, got {self.sigma}")
        lo, hi, k = self.start_ranges
        if not (0 < lo < hi and k >= 1):
            raise ValueError(
                f"start_ranges must be (min > 0, max > min, count >= 1), got {self.start_ranges}"
            )
        if not 0 < self.confidence < 1:
            raise ValueError(f"confidence must be in (0, 1), got {self.confidence}")


# ---------------------------------------------------------------------------
# Pure residual / Jacobian
# ---------------------------------------------------------------------------
def bearing_residuals(
    beta: ArrayLike, C: ArrayLike, observer: ArrayLike, z: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Bearing residuals ``wrap(z - h(beta))`` and Jacobian ``dh/dbeta`` (spec step 2).

    Parameters
    ----------
    beta : (..., n) states ``(X0, Y0, Vx0, Vy0, ...)``.
    C : (..., N, n/2) coefficient rows ``(1, T'_i0, T'_i1, ...)`` (:func:`leg_time_matrix`).
    observer : (..., N, 2) observer positions, m.
    z : (..., N) measured bearings, rad.

    Returns
    -------
    r : (..., N) rad in ``(-pi, pi]``.
    J : (..., N, n) rad per state unit; one leg: ``[R_y, -R_x, T R_y, -T R_x] / R^2``.
    """
    b = np.asarray(beta, dtype=float)
    CC = np.asarray(C, dtype=float)
    B = b.reshape(b.shape[:-1] + (-1, 2))
    d = CC @ B - np.asarray(observer, dtype=float)
    r = wrap_pi(np.asarray(z, dtype=float) - bearing(d[..., 0], d[..., 1]))
    g = bearing_jacobian(d)
    J = np.empty(d.shape[:-1] + (b.shape[-1],))
    for k in range(CC.shape[-1]):  # columns (2k, 2k + 1) = T'_ik * d(bearing)/d(position)
        J[..., 2 * k : 2 * k + 2] = CC[..., k, None] * g
    return np.asarray(r, dtype=float), J


@dataclass
class _Problem:
    """Arrays of one (or a padded batch of) least-squares problem(s).

    Leading dimension ``K`` (batch) is optional; bearing arrays ``(K, N, ...)``, support
    arrays ``(K, M, ...)``; padded rows have zero weight.
    """

    C: FloatArray  # (K, N, m)
    obs: FloatArray  # (K, N, 2)
    z: FloatArray  # (K, N)
    wb: FloatArray  # (K, N)
    sk: NDArray[np.int64]  # (K, M)
    sA: FloatArray  # (K, M, m)
    soff: FloatArray  # (K, M, 2)
    sval: FloatArray  # (K, M)
    sw: FloatArray  # (K, M)
    square: bool
    c_last: FloatArray  # (K, m)

    @staticmethod
    def build(
        bearings: Bearings,
        support: Sequence[SupportValue],
        starts: FloatArray,
        config: TMAConfig,
        sigma: float | None = None,
        index: NDArray[np.int64] | None = None,
    ) -> _Problem:
        """Unbatched problem (no leading K) for one contact; ``index`` selects bearings."""
        sig = (
            bearings.sigma
            if bearings.sigma is not None
            else np.full(len(bearings), sigma or config.sigma)
        )
        t, z, obs = bearings.t, bearings.bearing, bearings.observer
        if index is not None:
            t, z, obs, sig = t[index], z[index], obs[index], sig[index]
        C = leg_time_matrix(t, starts)
        rows: SupportRows = support_rows(support, starts, config.support_residual == "square")
        return _Problem(
            C,
            np.asarray(obs, dtype=float),
            np.asarray(z, dtype=float),
            1.0 / sig**2,
            rows.kind,
            rows.A,
            rows.offset,
            rows.value,
            rows.weight,
            rows.square,
            leg_time_matrix(bearings.t[-1:], starts)[0],
        )

    @staticmethod
    def stack(problems: Sequence[_Problem]) -> _Problem:
        """Pad and stack unbatched problems of equal state size into a batch."""
        N = max(p.z.size for p in problems)
        M = max(p.sk.size for p in problems)

        def padb(a: NDArray[Any], n: int, zero: bool) -> NDArray[Any]:
            if a.shape[0] == n:
                return a
            if zero or a.shape[0] == 0:
                fill = np.zeros((n - a.shape[0],) + a.shape[1:], a.dtype)
            else:  # repeat the last real row (finite geometry), weight set to zero
                fill = np.repeat(a[-1:], n - a.shape[0], axis=0)
            return np.concatenate([a, fill], axis=0)

        return _Problem(
            np.stack([padb(p.C, N, False) for p in problems]),
            np.stack([padb(p.obs, N, False) for p in problems]),
            np.stack([padb(p.z, N, False) for p in problems]),
            np.stack([padb(p.wb, N, True) for p in problems]),
            np.stack([padb(p.sk, M, True) for p in problems]),
            np.stack([padb(p.sA, M, True) for p in problems]),
            np.stack([padb(p.soff, M, True) for p in problems]),
            np.stack([padb(p.sval, M, True) for p in problems]),
            np.stack([padb(p.sw, M, True) for p in problems]),
            problems[0].square,
            np.stack([p.c_last for p in problems]),
        )

    def repeat(self, k: int) -> _Problem:
        """Each batch entry repeated ``k`` times (for multi-start), batch ``K * k``."""

        def rep(a: NDArray[Any]) -> NDArray[Any]:
            return np.repeat(a, k, axis=0)

        return _Problem(
            rep(self.C), rep(self.obs), rep(self.z), rep(self.wb), rep(self.sk), rep(self.sA),
            rep(self.soff), rep(self.sval), rep(self.sw), self.square, rep(self.c_last),
        )  # fmt: skip

    @property
    def weights(self) -> FloatArray:
        return np.concatenate([self.wb, self.sw], axis=-1)

    def evaluate(self, beta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Stacked residuals ``(..., N + M)`` and Jacobian ``(..., N + M, n)``."""
        b = np.asarray(beta, dtype=float)
        r, J = bearing_residuals(b, self.C, self.obs, self.z)
        if self.sk.shape[-1] == 0:
            return r, J
        B = b.reshape(b.shape[:-1] + (-1, 2))
        rs, Js = support_residuals(B, self.sk, self.sA, self.soff, self.sval, self.square)
        return np.concatenate([r, rs], -1), np.concatenate([J, Js], -2)


# ---------------------------------------------------------------------------
# Levenberg–Marquardt, batched
# ---------------------------------------------------------------------------
@dataclass
class _LMResult:
    beta: FloatArray  # (K, n)
    cost: FloatArray  # (K,)
    iterations: NDArray[np.int64]
    converged: NDArray[np.bool_]
    r: FloatArray  # (K, R)
    J: FloatArray  # (K, R, n)


def _lm(prob: _Problem, beta0: FloatArray, cfg: TMAConfig, max_iter: int) -> _LMResult:
    """Damped Gauss–Newton on a batch; a step is taken only if the weighted cost decreases."""
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
    diag = np.arange(n)
    tiny = 1e-300
    with np.errstate(all="ignore"):
        for _ in range(max_iter):
            active = ~done
            if not active.any():
                break
            JwT = (J * w[..., None]).swapaxes(-1, -2)
            A = JwT @ J
            g = (JwT @ r[..., None])[..., 0]
            D = A[:, diag, diag]
            D = np.maximum(D, 1e-12 * D.max(axis=1, keepdims=True) + tiny)
            Ad = A.copy()
            Ad[:, diag, diag] += lam[:, None] * D
            try:
                step = np.linalg.solve(Ad, g[..., None])[..., 0]
            except np.linalg.LinAlgError:
                step = np.stack(
                    [np.linalg.lstsq(a, gg, rcond=None)[0] for a, gg in zip(Ad, g, strict=True)]
                )
            trial = beta + step
            r2, J2 = prob.evaluate(trial)
            cost2 = np.sum(w * r2 * r2, axis=1)
            ok = active & (cost2 < cost)  # NaN compares False
            small_lam = lam <= cfg.lm_converge_lambda
            dp = (prob.c_last[:, None, :] @ step.reshape(K, m, 2))[:, 0]
            dpos = np.hypot(dp[:, 0], dp[:, 1])
            rel = (cost - cost2) / np.maximum(cost, tiny)
            # convergence only on nearly undamped steps (a tiny step forced by damping is not)
            new_conv = (
                ok & small_lam & ((dpos < cfg.position_tolerance) | (rel < cfg.cost_tolerance))
            )
            rejected = active & ~ok
            if rejected.any():
                # a rejected nearly-undamped step with negligible predicted gain: at the minimum
                pred = np.sum(step * (2 * g - (A @ step[..., None])[..., 0]), axis=1)
                new_conv |= (
                    rejected & small_lam & (pred <= cfg.cost_tolerance * np.maximum(cost, tiny))
                )
            if ok.all():
                beta, r, J, cost = trial, r2, J2, cost2
                lam = np.maximum(lam * cfg.lm_decrease, 1e-12)
            else:
                if ok.any():
                    beta[ok], r[ok], J[ok], cost[ok] = trial[ok], r2[ok], J2[ok], cost2[ok]
                lam = np.where(
                    active,
                    np.where(ok, np.maximum(lam * cfg.lm_decrease, 1e-12), lam * cfg.lm_increase),
                    lam,
                )
            iters += active
            conv |= new_conv
            done |= new_conv | (lam > cfg.lm_lambda_max)
    return _LMResult(beta, cost, iters, conv, r, J)


# ---------------------------------------------------------------------------
# Automatic start
# ---------------------------------------------------------------------------
def _decimate(n: int, k: int) -> NDArray[np.int64] | None:
    if n <= k:
        return None
    return np.unique(np.round(np.linspace(0, n - 1, k)).astype(np.int64))


def _two_range_starts(bearings: Bearings, n: int, cfg: TMAConfig) -> FloatArray:
    """Starts with the target at range r1 on the first and r2 on the last bearing (S, n)."""
    lo, hi, k = cfg.start_ranges
    ranges = np.geomspace(lo, hi, int(k))
    r1, r2 = (a.ravel() for a in np.meshgrid(ranges, ranges, indexing="ij"))
    b0, b1 = bearings.bearing[0], bearings.bearing[-1]
    u0 = np.array([np.sin(b0), np.cos(b0)])
    u1 = np.array([np.sin(b1), np.cos(b1)])
    p0 = bearings.observer[0] + r1[:, None] * u0
    p1 = bearings.observer[-1] + r2[:, None] * u1
    v = (p1 - p0) / (bearings.t[-1] - bearings.t[0])
    return np.concatenate([p0] + [v] * ((n - 2) // 2), axis=1)


def _pseudolinear(prob: _Problem, n: int) -> FloatArray | None:
    """Pseudo-linear estimate: ``cos(B) (X - X_E) - sin(B) (Y - Y_E) = 0`` in least squares."""
    s, c = np.sin(prob.z), np.cos(prob.z)
    m = n // 2
    A = np.zeros((prob.z.size, n))
    A[:, 0::2] = c[:, None] * prob.C[:, :m]
    A[:, 1::2] = -s[:, None] * prob.C[:, :m]
    y = c * prob.obs[:, 0] - s * prob.obs[:, 1]
    sw = np.sqrt(prob.wb)
    sol, *_ = np.linalg.lstsq(A * sw[:, None], y * sw, rcond=None)
    return np.asarray(sol, dtype=float) if np.all(np.isfinite(sol)) else None


# ---------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class LastEstimate:
    """Operator picture at the last bearing time (spec "Output in operator terms").

    Values are NaN when the geometry is not observable, except the bearing (always
    observable). Angles in rad ``[0, 2 pi)``, clockwise from North.
    """

    time: float
    x: float
    y: float
    range: float
    bearing: float
    course: float
    speed: float
    sigma_x: float
    sigma_y: float
    sigma_range: float
    sigma_bearing: float
    sigma_course: float
    sigma_speed: float
    covariance: FloatArray  #: (6, 6) of (x, y, range, bearing, course, speed)
    confidence: float = 0.95

    @property
    def z_factor(self) -> float:
        """Two-sided Gaussian factor of ``confidence`` (1.96 for 95 %)."""
        return float(norm.ppf(0.5 + self.confidence / 2))

    @property
    def position_covariance(self) -> FloatArray:
        """Covariance (2, 2) of the position at ``time`` (m^2)."""
        return np.asarray(self.covariance[:2, :2])

    @property
    def halfwidths(self) -> dict[str, float]:
        """Half-widths of the two-sided ``confidence`` intervals (1.96 sigma for 95 %) of
        range (m), bearing (rad), course (rad) and speed (m/s)."""
        z = self.z_factor
        return {
            "range": z * self.sigma_range,
            "bearing": z * self.sigma_bearing,
            "course": z * self.sigma_course,
            "speed": z * self.sigma_speed,
        }


@dataclass(frozen=True)
class TMASolution:
    """Result of a TMA solve.

    Attributes
    ----------
    t0 : reference time (first bearing), s.
    starts : (L,) leg start times, s (``starts[0] = t0``).
    state : (2 + 2L,) ``(X0, Y0, Vx0, Vy0, Vx1, Vy1, ...)`` at ``t0`` (m, m/s). When not
        ``observable`` it is one point of a set of equally good solutions.
    covariance : (n, n) ``(J^T W J)^-1`` at the solution (same order as ``state``); not
        meaningful (possibly NaN or huge) when ``observable`` is False.
    iterations : LM iterations of the final refinement (accepted + rejected trials); the
        automatic start's batch iterations (``start_iterations`` per start) are not counted.
    converged : the convergence tests were met.
    cost : weighted least-squares cost ``sum w r^2``.
    residuals : (N,) bearing residuals, rad.
    residual_rms : RMS of the bearing residuals, rad.
    observable, condition_number, smallest_singular_value : see module docstring.
    observer_deviation : largest own-ship distance from its straight-line fit, m.
    last : :class:`LastEstimate` at the last bearing time.
    manoeuvres_detected : True if the leg start times were found from the data.
    warnings : human-readable warnings.
    """

    t0: float
    starts: FloatArray
    state: FloatArray
    covariance: FloatArray
    iterations: int
    converged: bool
    cost: float
    residuals: FloatArray
    residual_rms: float
    observable: bool
    condition_number: float
    smallest_singular_value: float
    observer_deviation: float
    last: LastEstimate
    n_bearings: int
    n_support: int
    manoeuvres_detected: bool = False
    warnings: tuple[str, ...] = field(default_factory=tuple)

    @property
    def manoeuvres(self) -> FloatArray:
        """Manoeuvre (leg change) times after ``t0``, s."""
        return np.asarray(self.starts[1:])

    @property
    def legs(self) -> list[tuple[float, float, float]]:
        """``(start_s, vx, vy)`` of each leg."""
        B = self.state.reshape(-1, 2)
        return [
            (float(s), float(B[1 + j, 0]), float(B[1 + j, 1])) for j, s in enumerate(self.starts)
        ]

    def position_at(self, t: ArrayLike) -> FloatArray:
        """Estimated target position ``(..., 2)`` at times ``t`` (s)."""
        return np.asarray(leg_time_matrix(t, self.starts) @ self.state.reshape(-1, 2))

    def position_covariance_at(self, t: float) -> FloatArray:
        """Covariance (2, 2) of the estimated position at time ``t`` (exact: linear map)."""
        return position_crb(self.covariance, self.starts, t)


# ---------------------------------------------------------------------------
# Finalisation: covariance, conditioning, observability, operator values
# ---------------------------------------------------------------------------
def observer_deviation(t: ArrayLike, observer: ArrayLike) -> float:
    """Largest distance (m) of the own-ship positions from their least-squares straight
    constant-velocity fit -- zero when the own ship has not manoeuvred."""
    tt = np.asarray(t, dtype=float)
    o = np.asarray(observer, dtype=float)[:, :2]
    dt = tt - tt.mean()
    do = o - o.mean(axis=0)
    v = (dt @ do) / max(float(dt @ dt), 1e-300)  # least-squares velocity
    e = do - dt[:, None] * v
    return float(np.sqrt(np.max(e[:, 0] ** 2 + e[:, 1] ** 2)))


@lru_cache(maxsize=256)
def _chi2_quantile(p: float, dof: int) -> float:
    return float(chi2.ppf(p, dof))


def _finalise(
    bearings: Bearings,
    support: Sequence[SupportValue],
    starts: FloatArray,
    beta: FloatArray,
    cost: float,
    r: FloatArray,
    J: FloatArray,
    w: FloatArray,
    iterations: int,
    converged: bool,
    cfg: TMAConfig,
    detected: bool,
) -> TMASolution:
    n = beta.size
    N = len(bearings)
    warnings: list[str] = []
    A = (J * w[:, None]).T @ J
    d = np.sqrt(np.maximum(np.diag(A), 1e-300))
    As = A / np.outer(d, d)
    ev = np.linalg.eigvalsh(0.5 * (As + As.T))
    smin = float(np.sqrt(max(ev[0], 0.0)))
    smax = float(np.sqrt(max(ev[-1], 0.0)))
    cond = smax / smin if smin > 0 else math.inf
    try:
        L = np.linalg.cholesky(As)
        Linv = np.linalg.inv(L)
        P = (Linv.T @ Linv) / np.outer(d, d)
        P = 0.5 * (P + P.T)
        pd = bool(np.all(np.isfinite(P)))
    except np.linalg.LinAlgError:
        P = np.full((n, n), np.nan)
        pd = False
    dev = observer_deviation(bearings.t, bearings.observer)
    geometry_ok = dev > cfg.min_observer_deviation or len(support) > 0
    if not geometry_ok:
        warnings.append(
            f"not observable: the own ship did not manoeuvre (largest deviation from a straight "
            f"track {dev:.2f} m) and no support values were given; range, course and speed "
            "are undetermined -- manoeuvre the own ship or add a range/speed/course support value"
        )
    rows_ok = r.size >= n and N + len(support) >= n
    if not rows_ok:
        warnings.append(f"not observable: {N + len(support)} measurements for {n} unknowns")
    cond_ok = pd and cond < cfg.max_condition
    if geometry_ok and rows_ok and not cond_ok:
        warnings.append(
            f"not observable: ill-conditioned geometry (condition number {cond:.3g} >= "
            f"{cfg.max_condition:.3g})"
        )
    if not converged:
        warnings.append("the iteration did not converge within the iteration limit")
    dof = N + len(support) - n
    if dof > 0 and cost > _chi2_quantile(cfg.residual_test_probability, dof):
        warnings.append(
            f"the residuals are larger than the measurement sigmas explain (cost {cost:.1f} > "
            f"{_chi2_quantile(cfg.residual_test_probability, dof):.1f}, the "
            f"{cfg.residual_test_probability:.1%} chi-square bound for {dof} degrees of freedom; "
            f"bearing residual RMS {math.degrees(float(np.sqrt(np.mean(r[:N] ** 2)))):.2f} deg): "
            "sigma too small, outliers or an unmodelled target manoeuvre -- the 1-sigma values "
            "are optimistic"
        )
    t_last = float(bearings.t[-1])
    vals, G = operator_values(beta, starts, t_last, bearings.observer[-1])
    cov6 = G @ P @ G.T if pd else np.full((6, 6), np.nan)
    sig = np.sqrt(np.maximum(np.diag(cov6), 0.0))
    rel = float(sig[2] / vals[2]) if vals[2] > 0 else math.inf
    precise = bool(rel <= cfg.max_relative_range_sigma)
    if geometry_ok and rows_ok and cond_ok and not precise:
        warnings.append(
            f"not observable: range 1-sigma is {rel:.0%} of the range (limit "
            f"{cfg.max_relative_range_sigma:.0%}); the geometry does not fix the range yet"
        )
    observable = geometry_ok and rows_ok and cond_ok and precise
    if not observable:
        keep = np.zeros(6, bool)
        keep[3] = True  # the bearing is measured directly
        vals = np.where(keep, vals, np.nan)
        bs = float(1.0 / np.sqrt(w[N - 1]))  # measurement sigma of the last bearing
        sig = np.full(6, np.nan)
        sig[3] = bs
        cov6 = np.full((6, 6), np.nan)
        cov6[3, 3] = bs**2
    v, e = [float(x) for x in vals], [float(x) for x in sig]
    last = LastEstimate(
        time=t_last, x=v[0], y=v[1], range=v[2], bearing=v[3], course=v[4], speed=v[5],
        sigma_x=e[0], sigma_y=e[1], sigma_range=e[2], sigma_bearing=e[3], sigma_course=e[4],
        sigma_speed=e[5], covariance=cov6, confidence=cfg.confidence,
    )  # fmt: skip
    rb = r[:N]
    return TMASolution(
        t0=float(bearings.t[0]),
        starts=np.asarray(starts, dtype=float),
        state=np.asarray(beta, dtype=float),
        covariance=P,
        iterations=int(iterations),
        converged=bool(converged),
        cost=float(cost),
        residuals=np.asarray(rb, dtype=float),
        residual_rms=float(np.sqrt(np.mean(rb**2))),
        observable=bool(observable),
        condition_number=float(cond),
        smallest_singular_value=smin,
        observer_deviation=dev,
        last=last,
        n_bearings=N,
        n_support=len(support),
        manoeuvres_detected=detected,
        warnings=tuple(warnings),
    )


# ---------------------------------------------------------------------------
# Public entry points
# ---------------------------------------------------------------------------
def _starts(bearings: Bearings, manoeuvres: Sequence[float] | None) -> FloatArray:
    """Leg start times; every leg must begin before the last bearing (a leg without
    bearings has an undetermined velocity -- spec: future manoeuvre limits are infinite)."""
    starts = leg_starts(float(bearings.t[0]), manoeuvres if manoeuvres is not None else ())
    if starts.size > 1 and starts[-1] >= bearings.t[-1]:
        raise ValueError(
            f"manoeuvre time {starts[-1]:g} s is not before the last bearing "
            f"({bearings.t[-1]:g} s); a leg needs bearings"
        )
    return starts


def _as_initial(initial: ArrayLike, n: int) -> FloatArray:
    b = np.asarray(initial, dtype=float).reshape(-1)
    if b.size == 4 and n > 4:  # one velocity for every leg
        b = np.concatenate([b[:2]] + [b[2:4]] * ((n - 2) // 2))
    if b.size != n:
        raise ValueError(f"initial state has {b.size} components; the model has {n}")
    if not np.all(np.isfinite(b)):
        raise ValueError("initial state must be finite")
    return b


def _auto_start(
    items: Sequence[tuple[Bearings, Sequence[SupportValue], FloatArray, Any]],
    cfg: TMAConfig,
    sigma: float | None,
) -> FloatArray:
    """Best start (K, n) per problem: all starts of all problems iterated as one batch."""
    n = 2 + 2 * items[0][2].size
    starts_list, probs = [], []
    for b, s, st, _ in items:
        idx = _decimate(len(b), cfg.start_max_bearings)
        p = _Problem.build(b, s, st, cfg, sigma, idx)
        S = _two_range_starts(b, n, cfg)
        if cfg.start_pseudolinear:
            ple = _pseudolinear(p, n)
            S = np.vstack([S, ple if ple is not None else S[:1]])
        starts_list.append(S)
        probs.append(p)
    n_s = starts_list[0].shape[0]
    batch = _Problem.stack(probs).repeat(n_s)
    res = _lm(batch, np.concatenate(starts_list), cfg, cfg.start_iterations)
    costs = np.where(np.isfinite(res.cost), res.cost, np.inf).reshape(len(items), n_s)
    best = np.argmin(costs, axis=1)
    return res.beta.reshape(len(items), n_s, n)[np.arange(len(items)), best]


def _solve_group(
    items: Sequence[tuple[Bearings, Sequence[SupportValue], FloatArray, FloatArray | None]],
    cfg: TMAConfig,
    sigma: float | None,
    detected: Sequence[bool] | None = None,
) -> list[TMASolution]:
    """Solve problems with equal state size together: (bearings, support, starts, initial)."""
    n = 2 + 2 * items[0][2].size
    full = [_Problem.build(b, s, st, cfg, sigma) for b, s, st, _ in items]
    beta0 = np.zeros((len(items), n))
    need = [i for i, it in enumerate(items) if it[3] is None]
    for i, it in enumerate(items):
        if it[3] is not None:
            beta0[i] = it[3]
    if need:
        beta0[need] = _auto_start([items[i] for i in need], cfg, sigma)
    stacked = _Problem.stack(full)
    res = _lm(stacked, beta0, cfg, cfg.max_iterations)
    out = []
    W = stacked.weights
    for i, (b, s, st, _) in enumerate(items):
        N, M = len(b), len(s)
        keep = np.r_[np.arange(N), stacked.z.shape[1] + np.arange(M)]
        out.append(
            _finalise(
                b,
                s,
                st,
                res.beta[i],
                float(res.cost[i]),
                res.r[i][keep],
                res.J[i][keep],
                W[i][keep],
                int(res.iterations[i]),
                bool(res.converged[i]),
                cfg,
                bool(detected[i]) if detected else False,
            )  # fmt: skip
        )
    return out


def solve(
    bearings: Bearings,
    support: Sequence[SupportValue] | None = None,
    manoeuvres: Sequence[float] | str | None = None,
    sigma: float | None = None,
    initial: ArrayLike | None = None,
    config: TMAConfig | None = None,
) -> TMASolution:
    """Solve the TMA problem of one contact (spec "Algorithm").

    Parameters
    ----------
    bearings : :class:`Bearings` (radians, seconds, metres).
    support : support values (:class:`~seatrack.tma.support.SupportValue`), any number.
    manoeuvres : leg start times after the first bearing (s); ``None`` = one leg;
        ``"auto"`` = detect leg changes from the bearing residuals
        (:func:`seatrack.tma.detect.detect_legs`).
    sigma : bearing standard deviation, rad (overrides ``config.sigma``; per-bearing
        ``bearings.sigma`` takes precedence).
    initial : optional start ``(X0, Y0, Vx, Vy[, Vx1, Vy1, ...])`` at the first bearing
        time; without it the automatic start is used.
    config : :class:`TMAConfig`.
    """
    cfg = config or TMAConfig()
    sup = list(support or [])
    if isinstance(manoeuvres, str):
        if manoeuvres != "auto":
            raise ValueError(
                f"manoeuvres must be a list of times, None or 'auto', got {manoeuvres!r}"
            )
        from seatrack.tma.detect import detect_legs

        return detect_legs(bearings, sup, sigma=sigma, config=cfg).solution
    starts = _starts(bearings, manoeuvres)
    n = 2 + 2 * starts.size
    init = None if initial is None else _as_initial(initial, n)
    return _solve_group([(bearings, sup, starts, init)], cfg, sigma)[0]


def solve_many(
    contacts: Mapping[str, Bearings],
    support: Mapping[str, Sequence[SupportValue]] | None = None,
    manoeuvres: Sequence[float] | str | Mapping[str, Sequence[float] | str | None] | None = None,
    sigma: float | None = None,
    initial: Mapping[str, ArrayLike] | None = None,
    config: TMAConfig | None = None,
) -> dict[str, TMASolution]:
    """Solve every contact in one call; contacts with equal state size are solved as one
    vectorised batch (starts and refinement), ``"auto"`` manoeuvres contact by contact.

    ``manoeuvres`` is one value for all contacts or a mapping contact -> value (same
    meaning as in :func:`solve`).
    """
    cfg = config or TMAConfig()
    sup = support or {}
    unknown = set(sup) - set(contacts)
    if unknown:
        raise ValueError(f"support values for unknown contact(s): {', '.join(sorted(unknown))}")
    out: dict[str, TMASolution] = {}
    groups: dict[
        int, list[tuple[str, tuple[Bearings, list[SupportValue], FloatArray, FloatArray | None]]]
    ] = {}
    for cid, b in contacts.items():
        man = manoeuvres.get(cid) if isinstance(manoeuvres, Mapping) else manoeuvres
        s = list(sup.get(cid, []))
        if isinstance(man, str):
            out[cid] = solve(b, s, man, sigma, None, cfg)
            continue
        try:
            starts = _starts(b, man)
        except ValueError as exc:
            raise ValueError(f"contact {cid}: {exc}") from None
        n = 2 + 2 * starts.size
        init = None if initial is None or cid not in initial else _as_initial(initial[cid], n)
        groups.setdefault(n, []).append((cid, (b, s, starts, init)))
    for items in groups.values():
        sols = _solve_group([it for _, it in items], cfg, sigma)
        for (cid, _), sol in zip(items, sols, strict=True):
            out[cid] = sol
    return {cid: out[cid] for cid in contacts}
