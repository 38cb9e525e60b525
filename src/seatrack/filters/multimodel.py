"""Multiple-model tracking filter with range rate (JP H06-95138 B2; spec ``multimodel.md``).

``N`` hypotheses share one constant-velocity state ``x = [x, y, (z), vx, vy, (vz)]`` and one
covariance; hypothesis ``a`` adds a known constant input ``alpha_a`` (an acceleration
vector, m/s^2) over the scan (``x_k = Phi x_{k-1} + Gamma w + Gamma' alpha_a``,
``Gamma = Gamma' = [T^2/2 I; T I]``). Model reliabilities ``beta`` are Bayesian posterior
probabilities from the converted position *and* the measured range rate (the novelty
over Gholson & Moose 1977); the state uses one common gain, and the covariances include
the spread of the model means ("integrated" covariances).

Processing at scan k follows the spec's steps 1-11 exactly (see :func:`_step_core`):

1. ``x^a(-) = Phi x(+) + Gamma' alpha_a``; ``Pbar = Phi P(+) Phi^T + Gamma Q Gamma^T``.
2. ``S = H Pbar H^T + R``; ``f_a = N(Z; H x^a(-), S)``.
3. ``h^a = [(v - rho^a r / R) / R, r / R]``, ``s^a = h^a Pbar h^aT + sigma_rdot^2``,
   ``f^D_a = N(rho; rho^a, s^a)`` with ``rho^a = r . v / R`` at ``x^a(-)`` (relative to the
   sensor).
4. ``beta^-_a = sum_b pi_ab beta_b``; ``beta_a ∝ f_a f^D_a beta^-_a`` (log space,
   log-sum-exp).
5. ``K = Pbar H^T S^-1``.
6. ``u = sum_a beta_a alpha_a``; ``x~ = Phi x(+) + Gamma' u``; ``x(+) = x~ + K (Z - H x~)``.
7. ``P^a(+) = (I - K H) Pbar`` -- evaluated in Joseph form through :mod:`seatrack.kalman`
   (equal for the optimal gain, and stays PSD).
8. ``P(+) = P^a(+) + (I - KH) Gamma' C_beta Gamma'^T (I - KH)^T``,
   ``C_beta = sum_a beta_a (alpha_a - u)(alpha_a - u)^T`` (switch ``integrated_covariance``).
9. The next scan starts from the integrated ``P(+)``.
10. ``mu_a = sum_b pi_ab beta_b``; ``x(-) = Phi x(+) + Gamma' sum_a mu_a alpha_a``.
11. ``P(-) = Phi P(+) Phi^T + Gamma Q Gamma^T + Gamma' C_mu Gamma'^T`` (switch as 8).

Index convention of the outputs: steps 10-11 need the next scan interval, so the
integrated prediction made at scan ``k`` *for* scan ``k+1`` is returned with scan
``k+1`` (``x_pred[k+1]``, ``P_pred[k+1]``: the prediction for the time of plot ``k+1``,
before it is used). It is computed from exactly the quantities of steps 1 and 4 of that
scan (``mu = beta^-``), so nothing is computed twice.

[reading] choices, all parameters of :class:`MultiModelConfig`: the model set (default
the embodiment's five: 10 g North, East, South, West and zero), ``pi`` (default
diagonal ``p_stay = 0.9``, off-diagonal uniform), ``Q`` (``sigma_w^2 I``), ``sigma_rdot``,
priors (uniform), range rate positive when the range opens. A scan without a plot (NaN
position) is a pure prediction (``beta = beta^-``); a NaN range rate skips step 3 for
that scan. If every hypothesis' log-likelihood is ``-inf`` (innovations so large that
even the normalised innovation squared overflows) the reliabilities keep ``beta^-``
rather than becoming NaN.

Beyond the patent: ``range_rate_likelihood="joint"`` replaces the product ``f_a f^D_a``
(which treats the position and range-rate innovations as independent although both carry
the same prediction error) by their exact joint Gaussian likelihood.

All computations broadcast over leading (batch) dimensions: many tracks or Monte-Carlo
runs go through the same compiled kernel (``numba.guvectorize``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import guvectorize, njit
from numpy.typing import ArrayLike, NDArray

from seatrack.geometry import G0
from seatrack.kalman import cholesky_core, forward_core, update_core

FloatArray = NDArray[np.float64]

__all__ = [
    "DEFAULT_ALPHAS",
    "DEFAULT_NAMES",
    "MultiModelConfig",
    "MultiModelState",
    "MultiModelStep",
    "MultiModelResult",
    "MultiModelFilter",
    "range_rate_row",
    "track_plots_rangerate",
    "track_plots_position",
    "track_plots_imm",
]

_LOG_2PI = math.log(2.0 * math.pi)

#: the embodiment's five constant vectors (m/s^2, East North Up): 10 g North, East, South,
#: West and zero acceleration
DEFAULT_ALPHAS: tuple[tuple[float, float, float], ...] = (
    (0.0, 10 * G0, 0.0),
    (10 * G0, 0.0, 0.0),
    (0.0, -10 * G0, 0.0),
    (-10 * G0, 0.0, 0.0),
    (0.0, 0.0, 0.0),
)
DEFAULT_NAMES: tuple[str, ...] = ("north_10g", "east_10g", "south_10g", "west_10g", "cv")


# ---------------------------------------------------------------------------
# Configuration and results
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class MultiModelConfig:
    """Configuration of the multiple-model filter (spec "Not given in the original").

    Parameters
    ----------
    alphas : sequence of (d,) or (3,) vectors
        Constant input of each hypothesis, m/s^2 (East, North, Up). 3-vectors are cut to
        ``d = 2`` for 2-D tracking. Default: :data:`DEFAULT_ALPHAS`.
    names : sequence of str
        One name per hypothesis (used for the ``p_<name>`` output columns).
    p_stay : float
        Diagonal of ``pi`` when ``transition`` is not given; the rest of each column is
        spread uniformly.
    transition : (N, N) array, optional
        ``pi[a, b] = P(model a at k | model b at k-1)``; **columns** sum to one (spec
        convention; FilterPy's and :mod:`seatrack.filters.imm`'s matrix is its transpose).
    prior : (N,) array, optional
        Initial reliabilities ``beta_0`` (default uniform).
    sigma_w : float or (d,) sequence
        Standard deviation of the white acceleration ``w`` per axis, m/s^2
        (``Q = diag(sigma_w^2)``, piecewise constant over the scan). Default 10 m/s^2:
        the value chosen on the tuning seeds of ``benchmarks/multimodel.py`` for
        3-7 g turns at 1-4 s scans with the default 10 g hypotheses (with range rate a
        small ``sigma_w`` makes the range-rate likelihoods so sharp that a turn between
        the hypotheses is lost).
    sigma_range_rate : float
        Range-rate noise ``sigma_rdot``, m/s.
    use_range_rate : bool
        Step 3 on/off (off = position-only reliabilities, the prior art).
    range_rate_likelihood : {"independent", "joint"}
        ``"independent"`` (the spec): ``f_a f^D_a`` with ``s^a = h^a Pbar h^aT + sigma^2``,
        treating the position and range-rate innovations as independent although both
        contain the same prediction error. ``"joint"`` (beyond the patent): the exact
        joint Gaussian likelihood of ``(Z, rho)``, computed as ``f_a`` times the range-rate
        likelihood conditioned on the position innovation (mean shifted by
        ``c^T S^-1 (Z - H x^a)``, variance ``s^a - c^T S^-1 c``, ``c = H Pbar h^aT``).
    integrated_covariance : bool
        Spread-of-means terms of steps 8 and 11 on/off (off = per-model covariance).
    """

    alphas: Sequence[Sequence[float]] = DEFAULT_ALPHAS
    names: Sequence[str] = DEFAULT_NAMES
    p_stay: float = 0.9
    transition: Sequence[Sequence[float]] | None = None
    prior: Sequence[float] | None = None
    sigma_w: float | Sequence[float] = 10.0
    sigma_range_rate: float = 1.0
    use_range_rate: bool = True
    integrated_covariance: bool = True
    range_rate_likelihood: str = "independent"

    def __post_init__(self) -> None:
        N = len(self.alphas)
        if N < 1:
            raise ValueError("at least one hypothesis (alpha vector) is needed")
        if len(self.names) != N:
            raise ValueError(f"{len(self.names)} names for {N} hypotheses")
        if len({len(a) for a in self.alphas}) != 1:
            raise ValueError("all alpha vectors must have the same length")
        if not 0.0 <= self.p_stay <= 1.0:
            raise ValueError(f"p_stay must be in [0, 1], got {self.p_stay}")
        pi = self.transition_matrix()
        if pi.shape != (N, N) or np.any(pi < 0) or not np.allclose(pi.sum(axis=0), 1.0):
            raise ValueError(
                "transition must be N x N with non-negative columns summing to 1 "
                "(pi[a, b] = P(a at k | b at k-1))"
            )
        b0 = self.prior_vector()
        if b0.shape != (N,) or np.any(b0 < 0) or not math.isclose(b0.sum(), 1.0, rel_tol=1e-9):
            raise ValueError("prior must be N non-negative probabilities summing to 1")
        if self.range_rate_likelihood not in ("independent", "joint"):
            raise ValueError(
                f"range_rate_likelihood must be 'independent' or 'joint', "
                f"got {self.range_rate_likelihood!r}"
            )
        if np.any(np.asarray(self.sigma_w, dtype=float) < 0) or self.sigma_range_rate <= 0:
            raise ValueError("sigma_w must be >= 0 and sigma_range_rate > 0")

    @property
    def n_models(self) -> int:
        return len(self.alphas)

    def transition_matrix(self) -> FloatArray:
        """``pi`` (N, N), columns summing to one."""
        N = len(self.alphas)
        if self.transition is not None:
            return np.asarray(self.transition, dtype=float)
        if N == 1:
            return np.ones((1, 1))
        pi = np.full((N, N), (1.0 - self.p_stay) / (N - 1))
        np.fill_diagonal(pi, self.p_stay)
        return pi

    def prior_vector(self) -> FloatArray:
        N = len(self.alphas)
        return np.full(N, 1.0 / N) if self.prior is None else np.asarray(self.prior, dtype=float)

    def alpha_array(self, d: int) -> FloatArray:
        """Alphas as an (N, d) array (3-vectors cut to 2-D when ``d = 2``)."""
        a = np.asarray(self.alphas, dtype=float)
        if a.shape[1] < d:
            raise ValueError(f"alpha vectors have {a.shape[1]} components, need {d}")
        if a.shape[1] > d and np.any(a[:, d:] != 0):
            raise ValueError(f"alpha vectors have non-zero components beyond dimension {d}")
        return np.ascontiguousarray(a[:, :d])

    def process_noise(self, d: int) -> FloatArray:
        """``Q`` (d, d) of the white acceleration ``w``."""
        s = np.broadcast_to(np.asarray(self.sigma_w, dtype=float), (d,))
        return np.diag(s**2)


@dataclass(slots=True)
class MultiModelState:
    """Carried state (spec: "Carried from k-1"): integrated ``x(+)``, ``P(+)`` and ``beta``.

    Attributes
    ----------
    x : (..., n) ; P : (..., n, n) ; beta : (..., N)
    """

    x: FloatArray
    P: FloatArray
    beta: FloatArray


@dataclass(slots=True)
class MultiModelStep:
    """Outputs of one scan.

    Attributes
    ----------
    x, P : (..., n), (..., n, n)
        Smoothed (filtered) state ``x_k(+)`` and integrated covariance ``P_k(+)``.
    beta : (..., N)
        Reliabilities ``beta_k``.
    x_pred, P_pred : (..., n), (..., n, n)
        Integrated prediction ``x_k(-)``, ``P_k(-)`` for this scan's time, made from the
        previous scan (steps 10-11 of the previous scan).
    log_likelihood : (...)
        ``log sum_c f_c f^D_c beta^-_c`` (NaN without a plot).
    nis : (...)
        Position NIS of the plot against the integrated prediction,
        ``(Z - H x(-))^T (H P(-) H^T + R)^-1 (Z - H x(-))`` (NaN without a plot).
    """

    x: FloatArray
    P: FloatArray
    beta: FloatArray
    x_pred: FloatArray
    P_pred: FloatArray
    log_likelihood: FloatArray
    nis: FloatArray

    @property
    def state(self) -> MultiModelState:
        return MultiModelState(self.x, self.P, self.beta)


@dataclass(frozen=True, slots=True)
class MultiModelResult:
    """Outputs of a run over K scans (time axis just before the state axes).

    Attributes
    ----------
    t : (..., K) s
    x, P : (..., K, n), (..., K, n, n) -- ``x_k(+)``, ``P_k(+)``
    x_pred, P_pred : (..., K, n), (..., K, n, n) -- ``x_k(-)``, ``P_k(-)`` (NaN at k = 0)
    beta : (..., K, N)
    log_likelihood, nis : (..., K) (NaN at k = 0)
    names : model names
    """

    t: FloatArray
    x: FloatArray
    P: FloatArray
    x_pred: FloatArray
    P_pred: FloatArray
    beta: FloatArray
    log_likelihood: FloatArray
    nis: FloatArray
    names: tuple[str, ...]


# ---------------------------------------------------------------------------
# Compiled scan (steps 1-11 for one track)
# ---------------------------------------------------------------------------
@njit(cache=True)
def _maha(L, y):  # pragma: no cover - compiled
    """``y^T (L L^T)^-1 y`` by forward substitution."""
    w = np.empty(y.shape[0])
    forward_core(L, y, w)
    acc = 0.0
    for i in range(y.shape[0]):
        acc += w[i] * w[i]
    return acc


@njit(cache=True)
def _step_core(
    x, P, beta, T, Z, R, rho, srr2, spos, svel, alphas, pi, Q, use_rr, integ, xo, Po, bo, xp, Pp
):  # pragma: no cover - compiled
    """One scan of the spec's processing order; returns ``(log_likelihood, nis)``."""
    n = x.shape[0]
    d = n // 2
    N = alphas.shape[0]
    T2 = 0.5 * T * T
    gam = np.empty(n)  # Gamma = Gamma' = [T^2/2 I; T I] (diagonal blocks)
    for i in range(d):
        gam[i] = T2
        gam[i + d] = T
    # --- step 1: common part Phi x and Pbar = Phi P Phi^T + Gamma Q Gamma^T
    xc = np.empty(n)
    for i in range(d):
        xc[i] = x[i] + T * x[i + d]
        xc[i + d] = x[i + d]
    FP = np.empty((n, n))
    for j in range(n):
        for i in range(d):
            FP[i, j] = P[i, j] + T * P[i + d, j]
            FP[i + d, j] = P[i + d, j]
    Pb = np.empty((n, n))
    for i in range(n):
        for j in range(d):
            Pb[i, j] = FP[i, j] + T * FP[i, j + d]
            Pb[i, j + d] = FP[i, j + d]
    for i in range(n):
        for j in range(n):
            Pb[i, j] += gam[i] * gam[j] * Q[i % d, j % d]
    for i in range(n):
        for j in range(i + 1, n):
            v = 0.5 * (Pb[i, j] + Pb[j, i])
            Pb[i, j] = v
            Pb[j, i] = v
    # --- step 4 (prior part) and steps 10-11 of the previous scan: beta^- = pi beta = mu
    bm = np.empty(N)
    for a in range(N):
        s = 0.0
        for b in range(N):
            s += pi[a, b] * beta[b]
        bm[a] = s
    um = np.zeros(d)
    for a in range(N):
        for i in range(d):
            um[i] += bm[a] * alphas[a, i]
    Cm = np.zeros((d, d))
    for a in range(N):
        for i in range(d):
            for j in range(d):
                Cm[i, j] += bm[a] * (alphas[a, i] - um[i]) * (alphas[a, j] - um[j])
    for i in range(n):
        xp[i] = xc[i] + gam[i] * um[i % d]
        for j in range(n):
            Pp[i, j] = Pb[i, j] + integ * gam[i] * gam[j] * Cm[i % d, j % d]
    # --- no plot: pure prediction
    have_z = True
    for i in range(d):
        if not math.isfinite(Z[i]):
            have_z = False
    if not have_z:
        for a in range(N):
            bo[a] = bm[a]
        for i in range(n):
            xo[i] = xp[i]
            for j in range(n):
                Po[i, j] = Pp[i, j]
        return np.nan, np.nan
    # --- step 2: S = H Pbar H^T + R and the position log-likelihoods
    S = np.empty((d, d))
    for i in range(d):
        for j in range(d):
            S[i, j] = Pb[i, j] + 0.5 * (R[i, j] + R[j, i])
    L = np.empty((d, d))
    logdet = cholesky_core(S, L)
    if not math.isfinite(logdet):
        for i in range(n):
            xo[i] = np.nan
        return np.nan, np.nan
    lw = np.empty(N)
    y = np.empty(d)
    for a in range(N):
        for i in range(d):
            y[i] = Z[i] - xc[i] - T2 * alphas[a, i]
        lw[a] = -0.5 * (_maha(L, y) + logdet + d * _LOG_2PI)
    # --- step 3: range-rate log-likelihoods, h^a evaluated at x^a(-) relative to the sensor
    if use_rr != 0.0 and math.isfinite(rho):
        h = np.empty(n)
        c = np.empty(d)
        wc = np.empty(d)
        wy = np.empty(d)
        for a in range(N):
            Rh2 = 0.0
            pv = 0.0
            for i in range(d):
                p_i = xc[i] + T2 * alphas[a, i] - spos[i]
                v_i = xc[i + d] + T * alphas[a, i] - svel[i]
                Rh2 += p_i * p_i
                pv += p_i * v_i
            Rh = math.sqrt(Rh2)
            rhohat = pv / Rh
            for i in range(d):
                p_i = xc[i] + T2 * alphas[a, i] - spos[i]
                v_i = xc[i + d] + T * alphas[a, i] - svel[i]
                h[i] = (v_i - rhohat * p_i / Rh) / Rh
                h[i + d] = p_i / Rh
            s = srr2
            for i in range(n):
                hi = 0.0
                for j in range(n):
                    hi += Pb[i, j] * h[j]
                s += h[i] * hi
                if i < d:
                    c[i] = hi  # (H Pbar h^T)_i
            e = rho - rhohat
            if use_rr == 2.0:  # joint: condition the range rate on the position innovation
                for i in range(d):
                    y[i] = Z[i] - xc[i] - T2 * alphas[a, i]
                forward_core(L, c, wc)
                forward_core(L, y, wy)
                for i in range(d):
                    e -= wc[i] * wy[i]
                    s -= wc[i] * wc[i]
            lw[a] += -0.5 * (e * e / s + math.log(2.0 * math.pi * s))
    # --- step 4: reliabilities in log space (log-sum-exp)
    for a in range(N):
        lw[a] += math.log(bm[a]) if bm[a] > 0.0 else -np.inf
    mx = -np.inf
    for a in range(N):
        if lw[a] > mx:
            mx = lw[a]
    if mx > -np.inf and math.isfinite(mx):
        s = 0.0
        for a in range(N):
            s += math.exp(lw[a] - mx)
        lse = mx + math.log(s)
        for a in range(N):
            bo[a] = math.exp(lw[a] - lse)
    else:  # every likelihood is exactly zero even in log space: no information
        lse = -np.inf
        for a in range(N):
            bo[a] = bm[a]
    # --- steps 5 and 7: common gain and P^a(+) (Joseph form, seatrack.kalman core)
    H = np.zeros((d, n))
    for i in range(d):
        H[i, i] = 1.0
    yc = np.empty(d)
    for i in range(d):
        yc[i] = Z[i] - xc[i]
    So = np.empty((d, d))
    K = np.empty((n, d))
    update_core(xc, Pb, yc, H, R, xo, Po, So, K)  # xo = Phi x + K (Z - H Phi x)
    # --- step 6: x(+) = x~ + K (Z - H x~) = [Phi x + K (Z - H Phi x)] + (I - KH) Gamma' u
    u = np.zeros(d)
    for a in range(N):
        for i in range(d):
            u[i] += bo[a] * alphas[a, i]
    G = np.empty((n, d))  # (I - KH) Gamma'
    for i in range(n):
        for j in range(d):
            G[i, j] = (gam[i] if i % d == j else 0.0) - K[i, j] * T2
    for i in range(n):
        s = 0.0
        for j in range(d):
            s += G[i, j] * u[j]
        xo[i] += s
    # --- step 8: integrated covariance (spread of the model means)
    if integ != 0.0:
        C = np.zeros((d, d))
        for a in range(N):
            for i in range(d):
                for j in range(d):
                    C[i, j] += bo[a] * (alphas[a, i] - u[i]) * (alphas[a, j] - u[j])
        GC = np.empty((n, d))
        for i in range(n):
            for j in range(d):
                s = 0.0
                for k in range(d):
                    s += G[i, k] * C[k, j]
                GC[i, j] = s
        for i in range(n):
            for j in range(i, n):
                s = 0.0
                for k in range(d):
                    s += GC[i, k] * G[j, k]
                v = Po[i, j] + s
                Po[i, j] = v
                Po[j, i] = v
    # --- consistency statistic: plot against the integrated prediction
    for i in range(d):
        y[i] = Z[i] - xp[i]
        for j in range(d):
            S[i, j] = Pp[i, j] + 0.5 * (R[i, j] + R[j, i])
    nis = _maha(L, y) if math.isfinite(cholesky_core(S, L)) else np.nan
    return lse, nis


@guvectorize(
    [
        "void(f8[:], f8[:,:], f8[:], f8, f8[:], f8[:,:], f8, f8, f8[:], f8[:], f8[:,:], f8[:,:],"
        " f8[:,:], f8, f8, f8[:], f8[:,:], f8[:], f8[:], f8[:,:], f8[:], f8[:])"
    ],
    "(n),(n,n),(N),(),(d),(d,d),(),(),(d),(d),(N,d),(N,N),(d,d),(),()"
    "->(n),(n,n),(N),(n),(n,n),(),()",
    nopython=True,
    cache=True,
)
def _step_kernel(
    x,
    P,
    beta,
    T,
    Z,
    R,
    rho,
    srr2,
    spos,
    svel,
    alphas,
    pi,
    Q,
    use_rr,
    integ,
    xo,
    Po,
    bo,
    xp,
    Pp,
    ll,
    nis,
):  # pragma: no cover - compiled
    a, b = _step_core(
        x, P, beta, T, Z, R, rho, srr2, spos, svel, alphas, pi, Q, use_rr, integ, xo, Po, bo, xp, Pp
    )
    ll[0] = a
    nis[0] = b


def range_rate_row(
    x: ArrayLike, sensor: ArrayLike | None = None, sensor_vel: ArrayLike | None = None
) -> tuple[Any, FloatArray]:
    """Predicted range rate and its row Jacobian ``h^a`` (spec step 3), pure NumPy.

    Parameters
    ----------
    x : (..., 2d) state ``[position, velocity]``.
    sensor, sensor_vel : (..., d), optional -- sensor position / velocity (default rest at 0).

    Returns
    -------
    rho : (...) m/s, positive opening
    h : (..., 2d) ``[(v - rho r / R)^T / R, r^T / R]``

    This mirrors the compiled step 3 (which the tests check against it and against a
    numerical Jacobian) and reuses :func:`seatrack.models.measurement.range_rate_jacobian`.
    """
    from seatrack.models.measurement import range_rate, range_rate_jacobian

    xx = np.asarray(x, dtype=float)
    d = xx.shape[-1] // 2
    p = xx[..., :d] - (0.0 if sensor is None else np.asarray(sensor, float)[..., :d])
    v = xx[..., d:] - (0.0 if sensor_vel is None else np.asarray(sensor_vel, float)[..., :d])
    jp, jv = range_rate_jacobian(p, v)
    return range_rate(p, v), np.concatenate([jp, jv], -1)


# ---------------------------------------------------------------------------
# Filter object (thin shell)
# ---------------------------------------------------------------------------
def _f(a: ArrayLike) -> FloatArray:
    return np.asarray(a, dtype=np.float64)


class MultiModelFilter:
    """The patent's multiple-model filter (spec ``multimodel.md``, steps 1-11).

    Parameters
    ----------
    config : MultiModelConfig
    d : int
        Spatial dimensions: 3 (default, state ``[x, y, z, vx, vy, vz]``) or 2.
    """

    def __init__(self, config: MultiModelConfig | None = None, d: int = 3) -> None:
        if d not in (2, 3):
            raise ValueError(f"d must be 2 or 3, got {d}")
        self.config = config or MultiModelConfig()
        self.d = d
        self.n = 2 * d
        self.alphas = self.config.alpha_array(d)
        self.pi = np.ascontiguousarray(self.config.transition_matrix())
        self.Q = self.config.process_noise(d)
        self.names = tuple(self.config.names)
        self._flags = (
            (2.0 if self.config.range_rate_likelihood == "joint" else 1.0)
            if self.config.use_range_rate
            else 0.0,
            1.0 if self.config.integrated_covariance else 0.0,
        )

    def initiate(
        self, z: ArrayLike, R: ArrayLike, velocity_std: ArrayLike, velocity: ArrayLike | None = None
    ) -> MultiModelState:
        """One-point initialisation from a converted plot.

        Position ``z`` with covariance ``R``; velocity ``velocity`` (default 0) with
        standard deviation ``velocity_std`` (m/s) per axis; reliabilities the prior.
        """
        zz = _f(z)
        lead = zz.shape[:-1]
        d = self.d
        x = np.zeros(lead + (self.n,))
        x[..., :d] = zz
        if velocity is not None:
            x[..., d:] = _f(velocity)
        P = np.zeros(lead + (self.n, self.n))
        P[..., :d, :d] = _f(R)
        vs = np.broadcast_to(_f(velocity_std), lead + (d,))
        idx = np.arange(d, self.n)
        P[..., idx, idx] = vs**2
        beta = np.broadcast_to(self.config.prior_vector(), lead + (self.config.n_models,)).copy()
        return MultiModelState(x, P, beta)

    def step(
        self,
        state: MultiModelState,
        dt: ArrayLike,
        z: ArrayLike,
        R: ArrayLike,
        range_rate: ArrayLike | None = None,
        sensor: ArrayLike | None = None,
        sensor_vel: ArrayLike | None = None,
    ) -> MultiModelStep:
        """Process one scan (steps 1-11).

        Parameters
        ----------
        state : MultiModelState at the previous scan.
        dt : (...) s -- scan interval ``T = t_k - t_{k-1}``.
        z : (..., d) m -- converted plot (NaN row: no plot).
        R : (..., d, d) m^2 -- its covariance.
        range_rate : (...) m/s, optional (NaN or None: not used this scan).
        sensor, sensor_vel : (..., d) -- sensor position / velocity at the plot.
        """
        d = self.d
        rho = np.nan if range_rate is None else range_rate
        sp = np.zeros(d) if sensor is None else _f(sensor)[..., :d]
        sv = np.zeros(d) if sensor_vel is None else _f(sensor_vel)[..., :d]
        out = _step_kernel(
            state.x,
            state.P,
            state.beta,
            dt,
            z,
            R,
            rho,
            self.config.sigma_range_rate**2,
            sp,
            sv,
            self.alphas,
            self.pi,
            self.Q,
            self._flags[0],
            self._flags[1],
        )
        return MultiModelStep(*out)

    def run(
        self,
        t: ArrayLike,
        z: ArrayLike,
        R: ArrayLike,
        range_rate: ArrayLike | None = None,
        sensor: ArrayLike | None = None,
        sensor_vel: ArrayLike | None = None,
        velocity_std: float = 300.0,
        initial: MultiModelState | None = None,
    ) -> MultiModelResult:
        """Run over K scans; batch over leading dimensions.

        Parameters
        ----------
        t : (..., K) s -- scan times (strictly increasing).
        z : (..., K, d) ; R : (..., K, d, d) -- converted plots.
        range_rate : (..., K), optional.
        sensor, sensor_vel : (..., K, d), optional.
        velocity_std : float -- initial velocity standard deviation (one-point start).
        initial : state at ``t[..., 0]``; default a one-point start on the first plot.
        """
        tt = _f(t)
        zz = _f(z)
        RR = _f(R)
        K = zz.shape[-2]
        if tt.shape[-1] != K:
            raise ValueError(f"t has {tt.shape[-1]} scans, z has {K}")
        dts = np.diff(tt, axis=-1)
        if np.any(dts <= 0):
            raise ValueError("scan times must be strictly increasing")
        lead = np.broadcast_shapes(zz.shape[:-2], RR.shape[:-3], tt.shape[:-1])
        zz = np.broadcast_to(zz, lead + zz.shape[-2:])
        RR = np.broadcast_to(RR, lead + RR.shape[-3:])
        st = initial or self.initiate(zz[..., 0, :], RR[..., 0, :, :], velocity_std)
        n, N = self.n, self.config.n_models
        xs = np.empty(lead + (K, n))
        Ps = np.empty(lead + (K, n, n))
        xps = np.full(lead + (K, n), np.nan)
        Pps = np.full(lead + (K, n, n), np.nan)
        bs = np.empty(lead + (K, N))
        lls = np.full(lead + (K,), np.nan)
        nis = np.full(lead + (K,), np.nan)
        xs[..., 0, :], Ps[..., 0, :, :], bs[..., 0, :] = st.x, st.P, st.beta
        rr = None if range_rate is None else _f(range_rate)
        sp = None if sensor is None else _f(sensor)
        sv = None if sensor_vel is None else _f(sensor_vel)
        for k in range(1, K):
            res = self.step(
                st,
                dts[..., k - 1],
                zz[..., k, :],
                RR[..., k, :, :],
                None if rr is None else rr[..., k],
                None if sp is None else sp[..., k, :],
                None if sv is None else sv[..., k, :],
            )
            xs[..., k, :], Ps[..., k, :, :], bs[..., k, :] = res.x, res.P, res.beta
            xps[..., k, :], Pps[..., k, :, :] = res.x_pred, res.P_pred
            lls[..., k], nis[..., k] = res.log_likelihood, res.nis
            st = res.state
        return MultiModelResult(
            np.broadcast_to(tt, lead + (K,)).copy(), xs, Ps, xps, Pps, bs, lls, nis, self.names
        )


# ---------------------------------------------------------------------------
# `seatrack track --method mm-rangerate | mm`
# ---------------------------------------------------------------------------
#: config keys of the plot runners and their defaults (SI except where the name says deg / g)
RUNNER_DEFAULTS: dict[str, Any] = {
    "sigma_range_m": 30.0,
    "sigma_azimuth_deg": 0.3,
    "sigma_elevation_deg": 0.3,
    "sigma_range_rate_mps": 1.0,
    "sigma_accel_mps2": 10.0,
    "accel_g": 10.0,
    "p_stay": 0.9,
    "conversion": "unbiased",
    "initial_velocity_std_mps": 300.0,
    "integrated_covariance": True,
}


#: ``mm`` (position-only reliabilities) defaults: as :data:`RUNNER_DEFAULTS` except the
#: white acceleration, for which the benchmark's tuning picks 1-3 m/s^2 (vs 10 with range rate)
MM_DEFAULTS: dict[str, Any] = {**RUNNER_DEFAULTS, "sigma_accel_mps2": 3.0}


def runner_config(
    config: Mapping[str, Any], defaults: Mapping[str, Any] = RUNNER_DEFAULTS
) -> dict[str, Any]:
    """Merge a user config with the defaults; unknown keys are an error (likely typos)."""
    unknown = sorted(set(config) - set(defaults))
    if unknown:
        raise ValueError(
            f"unknown config key(s) {', '.join(unknown)}; known: {', '.join(sorted(defaults))}"
        )
    return {**defaults, **config}


def converted_plots(plots: Any, cfg: Mapping[str, Any]) -> tuple[FloatArray, FloatArray, int]:
    """Converted positions ``(K, d)`` and covariances ``(K, d, d)`` of a PlotTrack."""
    from seatrack.filters.converted import convert_plots

    el = plots.elevation
    cm = convert_plots(
        plots.range,
        plots.azimuth,
        el,
        float(cfg["sigma_range_m"]),
        math.radians(float(cfg["sigma_azimuth_deg"])),
        None if el is None else math.radians(float(cfg["sigma_elevation_deg"])),
        sensor=plots.sensor,
        method=cfg["conversion"],
    )
    return cm.z, cm.R, 2 if el is None else 3


def _track(plots: Any, config: Mapping[str, Any], use_range_rate: bool) -> dict[str, FloatArray]:
    from seatrack.filters.ekf import output_columns

    cfg = runner_config(config, RUNNER_DEFAULTS if use_range_rate else MM_DEFAULTS)
    z, R, d = converted_plots(plots, cfg)
    g = float(cfg["accel_g"]) * G0
    alphas = tuple(tuple(a) for a in np.asarray(DEFAULT_ALPHAS) / (10 * G0) * g)
    mcfg = MultiModelConfig(
        alphas=alphas,
        p_stay=float(cfg["p_stay"]),
        sigma_w=float(cfg["sigma_accel_mps2"]),
        sigma_range_rate=float(cfg["sigma_range_rate_mps"]),
        use_range_rate=use_range_rate,
        integrated_covariance=bool(cfg["integrated_covariance"]),
    )
    rr = plots.range_rate if use_range_rate else None
    if use_range_rate and rr is None:
        raise ValueError(f"track {plots.track}: method mm-rangerate needs a range_rate_mps column")
    flt = MultiModelFilter(mcfg, d=d)
    res = flt.run(
        plots.t,
        z,
        R,
        rr,
        plots.sensor[:, :d],
        plots.sensor_vel[:, :d],
        velocity_std=float(cfg["initial_velocity_std_mps"]),
    )
    out = output_columns(res.x, res.P, d)
    for a, name in enumerate(flt.names):
        out[f"p_{name}"] = res.beta[:, a]
    return out


def track_plots_rangerate(plots: Any, config: Mapping[str, Any]) -> dict[str, FloatArray]:
    """``seatrack track --method mm-rangerate``: reliabilities from position and range rate.

    Config keys (defaults in :data:`RUNNER_DEFAULTS`): polar noise ``sigma_range_m``,
    ``sigma_azimuth_deg``, ``sigma_elevation_deg``, ``sigma_range_rate_mps``; white
    acceleration ``sigma_accel_mps2``; hypothesis magnitude ``accel_g`` (N/E/S/W and zero);
    ``p_stay``; ``conversion`` (``unbiased`` / ``linearized``);
    ``initial_velocity_std_mps``; ``integrated_covariance``. Output: the common columns
    plus ``p_<model>`` reliabilities.
    """
    return _track(plots, config, use_range_rate=True)


def track_plots_position(plots: Any, config: Mapping[str, Any]) -> dict[str, FloatArray]:
    """``seatrack track --method mm``: the same filter with position-only reliabilities.

    Config keys as :func:`track_plots_rangerate` (defaults :data:`MM_DEFAULTS`); a
    ``range_rate_mps`` column, if present, is ignored.
    """
    return _track(plots, config, use_range_rate=False)


#: config keys of the IMM runner (CV + coordinated turn on converted plots); the noise
#: defaults are those chosen on the tuning seeds of ``benchmarks/multimodel.py`` (2 s scans)
IMM_DEFAULTS: dict[str, Any] = {
    "sigma_range_m": 30.0,
    "sigma_azimuth_deg": 0.3,
    "sigma_elevation_deg": 0.3,
    "sigma_range_rate_mps": 1.0,
    "q_cv": 0.01,
    "q_ct": 100.0,
    "q_omega": 1e-3,
    "p_stay": 0.95,
    "conversion": "unbiased",
    "initial_velocity_std_mps": 300.0,
    "initial_turn_rate_std_dps": 5.0,
    "use_range_rate": False,
}


def imm_filter(cfg: Mapping[str, Any], d: int) -> Any:
    """The reference IMM: CV + coordinated turn (:class:`seatrack.filters.imm.IMM`).

    Measurements are the converted positions (linear update), or, with
    ``use_range_rate``, positions stacked with the range rate (extended update; the
    sensor state ``[position, velocity]`` is passed to the range-rate model).
    """
    from seatrack.filters.imm import IMM
    from seatrack.models.measurement import Position, RangeRate, Stacked
    from seatrack.models.motion import ConstantVelocity, CoordinatedTurn

    models: list[Any] = [
        ConstantVelocity(q=float(cfg["q_cv"]), d=d),
        CoordinatedTurn(q=float(cfg["q_ct"]), q_omega=float(cfg["q_omega"]), d=d),
    ]
    meas: list[Any] = []
    for m in models:
        n = m.ndim_state
        pos = tuple(range(d))
        if cfg["use_range_rate"]:
            meas.append(
                Stacked(
                    [Position(n=n, pos=pos), RangeRate(n=n, pos=pos, vel=tuple(range(d, 2 * d)))]
                )
            )
        else:
            meas.append(Position(n=n, pos=pos))
    p = float(cfg["p_stay"])
    return IMM(models, [[p, 1 - p], [1 - p, p]], meas)


def track_plots_imm(plots: Any, config: Mapping[str, Any]) -> dict[str, FloatArray]:
    """``seatrack track --method imm``: standard IMM (CV + coordinated turn) on converted plots.

    Config keys (defaults :data:`IMM_DEFAULTS`): polar noise as for ``mm``; ``q_cv``,
    ``q_ct`` (white-noise acceleration PSD, m^2/s^3), ``q_omega`` (turn-rate PSD,
    rad^2/s^3), ``p_stay`` (IMM transition diagonal), ``conversion``,
    ``initial_velocity_std_mps``, ``initial_turn_rate_std_dps``, ``use_range_rate``.
    Output: the common columns plus ``p_cv``, ``p_ct`` and ``turn_rate_dps`` (CT model).
    """
    from seatrack.filters.ekf import output_columns

    cfg = runner_config(config, IMM_DEFAULTS)
    z, R, d = converted_plots(plots, cfg)
    use_rr = bool(cfg["use_range_rate"])
    if use_rr and plots.range_rate is None:
        raise ValueError(f"track {plots.track}: use_range_rate needs a range_rate_mps column")
    imm = imm_filter(cfg, d)
    K = z.shape[0]
    x0 = np.zeros(2 * d)
    x0[:d] = z[0]
    P0 = np.zeros((2 * d, 2 * d))
    P0[:d, :d] = R[0]
    P0[d:, d:] = np.eye(d) * float(cfg["initial_velocity_std_mps"]) ** 2
    sw = math.radians(float(cfg["initial_turn_rate_std_dps"]))
    st = imm.initial_state(x0, P0, extra={"w": (0.0, sw**2)})
    xs = np.empty((K, 2 * d))
    Ps = np.empty((K, 2 * d, 2 * d))
    mus = np.empty((K, 2))
    w = np.empty(K)
    xs[0], Ps[0], mus[0], w[0] = x0, P0, st.mu, 0.0
    srr2 = float(cfg["sigma_range_rate_mps"]) ** 2
    for k in range(1, K):
        dt = float(plots.t[k] - plots.t[k - 1])
        if use_rr:
            # Position.h subtracts the sensor position given with the range-rate sensor state
            zk = np.append(z[k] - plots.sensor[k, :d], plots.range_rate[k])
            Rk = np.zeros((d + 1, d + 1))
            Rk[:d, :d] = R[k]
            Rk[d, d] = srr2
            sensor = np.concatenate([plots.sensor[k, :d], plots.sensor_vel[k, :d]])
            res = imm.step(st, zk, dt, Rk, sensor)
        else:
            res = imm.step(st, z[k], dt, R[k])
        st = res.state
        xs[k], Ps[k], mus[k] = res.x, res.P, st.mu
        w[k] = imm.model_state(st, 1)[0][-1]
    out = output_columns(xs, Ps, d)
    out["p_cv"] = mus[:, 0]
    out["p_ct"] = mus[:, 1]
    out["turn_rate_dps"] = np.degrees(w)
    return out
