"""Process-noise-level IMM: a self-tuning constant-velocity filter on polar plots.

The engine under the default ``turning``, ``robust``, ``robust-adaptive``, ``huber`` and
``student-t`` methods (issue 16). An IMM (Blom & Bar-Shalom 1988) whose ``M`` models are
the same constant-velocity EKF (state ``[x, y, (z), vx, vy, (vz)]``, polar update with a
wrapped azimuth innovation) with different white-noise acceleration PSDs ``q_j``:

* **self-tuning ladder** (no target class): ``q = (1e-4, 1e-2, 1, 1e2, 1e4)`` m^2/s^3 with
  ``p_stay = 0.95`` -- eight decades of manoeuvrability, the model probabilities pick the
  level the innovations support, scan by scan;
* **target class** (``target = "ship"`` ...): two levels ``q = (a_steady^2 T, a_max^2 T)``
  (straight legs and the hardest manoeuvre of the class, :mod:`seatrack.models.targets`)
  with ``p_stay_j = exp(-T / tau_j)``, ``tau`` = the class's straight-leg and manoeuvre
  times.

The turn decision of a turning filter, or the adaptation of algorithm A, becomes a mode
probability; each level keeps its own state (a single state whose ``q`` is mixed by the
same probabilities was measured, and is no better than the best fixed ``q``).

Measurement models of the levels (the ``rule`` of a subclass), each with its density for
the model probabilities:

* ``gaussian`` -- the EKF update, Gaussian likelihood;
* ``contaminated`` -- the exact update under an ``epsilon``-contaminated Gaussian (spec
  ``robust.md``, Tukey-Huber: each channel -- range, azimuth, [elevation], [range rate] --
  is an outlier with prior probability ``epsilon`` and variance ``k_c r_c``): for every
  outlier pattern ``g in {0, 1}^m`` an EKF update with ``R_g``, weights ``w_g ∝ pi_g
  N(y; 0, H P H^T + R_g)`` (log space), the posterior collapsed to its mean and
  covariance, the likelihood ``sum_g pi_g N(...)``. An outlier is explained by the outlier
  component of *every* level, so it barely moves the model probabilities; a manoeuvre (a run
  of innovations too large even for the quiet level's outlier component) moves them to the
  agile level within a few scans;
* ``ramazanov`` -- algorithm R's robust variance per channel (``r_c <- y_c^2 / Delta_c -
  (H P H^T)_cc`` when ``J_c = y_c^2 / S_cc > Delta_c``), likelihood the contaminated one;
* ``huber`` -- Huber's IRLS update (:func:`seatrack.filters.robust_baselines.reweighted_update`
  with a :class:`~seatrack.filters.robust_baselines.HuberConfig`), likelihood the Student-t
  density of the whitened innovation components (see :class:`HuberLevels`);
* ``student-t`` -- the VB Student-t update (the same function with a
  :class:`~seatrack.filters.robust_baselines.StudentTConfig`), likelihood the Student-t
  density of each innovation component.

Every step is a handful of compiled batch calls: the IMM mixing kernel, one Kalman
prediction over ``(tracks, levels)``, the polar Jacobians of all levels, one (or, with
outliers, ``2^m``) Kalman updates over ``(tracks, levels[, patterns])`` and the compiled
combination.

References: Blom & Bar-Shalom, IEEE T-AC 33(8), 1988; Bar-Shalom, Li & Kirubarajan 2001,
sec. 11.6; Huber 1964 (least favourable distribution); Li & Jilkov 2005 (multiple-model
methods, survey part V: model-set design by levels of process noise).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray
from scipy.special import gammaln

from seatrack import kalman
from seatrack.config import param, redefault
from seatrack.filters.base import (
    CartesianState,
    ConfiguredFilter,
    Plots,
    TrackState,
    common_columns,
    finish_update,
    measurement_noise,
    predicted,
    speed_sigma_param,
    step_times,
    usable,
    wrap_angles,
)
from seatrack.filters.ekf import sensor_state
from seatrack.filters.imm import IMMState, combine, mix
from seatrack.filters.robust_baselines import (
    HuberConfig,
    StudentTConfig,
    reweighted_update,
)
from seatrack.kalman import cholesky_core, forward_core, matmul_core
from seatrack.models.measurement import polar_measurement
from seatrack.models.motion import cv_matrices
from seatrack.models.targets import TargetClass

FloatArray = NDArray[np.float64]

__all__ = [
    "LADDER",
    "LevelConfig",
    "OutlierConfig",
    "LevelIMMConfig",
    "ContaminatedConfig",
    "RamazanovConfig",
    "HuberLevelsConfig",
    "StudentTLevelsConfig",
    "level_noise",
    "outlier_patterns",
    "mixture_update",
    "contaminated_loglik",
    "student_t_logpdf",
    "LevelIMM",
    "ContaminatedLevels",
    "RamazanovLevels",
    "HuberLevels",
    "StudentTLevels",
]

_LOG_2PI = math.log(2.0 * math.pi)

#: the range a learnt channel outlier probability is kept in
_EPS_RANGE = (1e-3, 0.4)

#: the self-tuning ladder of process-noise PSDs, m^2/s^3 (no target class given)
LADDER = (1e-4, 1e-2, 1.0, 1e2, 1e4)


# ---------------------------------------------------------------------------
# Configuration
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class LevelConfig:
    """The process-noise levels of the IMM and the start of a track.

    ``accel_levels`` (set by a ``target`` class) take precedence over ``q_levels``; the
    persistence of level ``j`` is ``exp(-T / sojourn_times[j])`` when sojourn times are
    given (set by a target class), else ``p_stay`` for every level.
    """

    q_levels: tuple[float, ...] = param(
        LADDER, unit="m^2/s^3", doc="white-acceleration PSD of each level (self-tuning ladder)"
    )
    accel_levels: tuple[float, ...] = param(
        (), unit="m/s^2", doc="levels as accelerations, q = a^2 T (a target class sets them)"
    )
    p_stay: float = param(0.95, doc="persistence of every level per scan", min=0, max=1)
    sojourn_times: tuple[float, ...] = param(
        (), unit="s", doc="mean time in each level, p_stay = exp(-T/tau) (set by a target)"
    )
    initial_speed_sigma: float = speed_sigma_param(300.0)

    def __post_init__(self) -> None:
        levels = self.accel_levels or self.q_levels
        if not levels:
            raise ValueError("q_levels: at least one process-noise level is needed")
        for name in ("q_levels", "accel_levels", "sojourn_times"):
            vals = getattr(self, name)
            if any(not (isinstance(v, int | float) and math.isfinite(v) and v > 0) for v in vals):
                raise ValueError(f"{name}: every value must be a positive number, got {vals}")
        if self.sojourn_times and len(self.sojourn_times) != len(levels):
            raise ValueError(
                f"sojourn_times: one per level ({len(levels)}), got {len(self.sojourn_times)}"
            )
        if len(levels) > 1 and not self.p_stay < 1 and not self.sojourn_times:
            raise ValueError("p_stay must be < 1 with more than one level")

    @property
    def n_levels(self) -> int:
        return len(self.accel_levels or self.q_levels)

    @classmethod
    def for_target(cls, target: TargetClass) -> Any:
        """The preset of a target class: levels ``(a_steady, a_max)`` (``q = a^2 T``), sojourn
        times (straight legs, manoeuvres), initial speed std = the class's maximum speed."""
        return cls(
            accel_levels=(target.accel_steady, target.accel_max),
            sojourn_times=(target.straight_time, target.manoeuvre_time),
            initial_speed_sigma=target.speed_max,
        )


@dataclass(frozen=True)
class OutlierConfig:
    """The contaminated-Gaussian plot noise (spec ``robust.md``; Ramazanov's set-up
    ``k = (10, 25)``): each channel is an outlier with prior ``epsilon``, variance ``k r``."""

    outlier_probability: float = param(
        0.01, doc="prior probability that a plot channel is an outlier (0: Gaussian)", min=0,
        max=0.5,
    )  # fmt: skip
    outlier_memory: float = param(
        0.0, key="outlier_memory_scans",
        doc="learn each channel's outlier probability over about this many scans (0: fixed)",
        min=0,
    )  # fmt: skip
    outlier_scale_range: float = param(10.0, doc="outlier variance / nominal, range", min=1)
    outlier_scale_azimuth: float = param(25.0, doc="outlier variance / nominal, azimuth", min=1)
    outlier_scale_elevation: float = param(25.0, doc="outlier variance / nominal, elevation", min=1)
    outlier_scale_range_rate: float = param(
        10.0, doc="outlier variance / nominal, range rate", min=1
    )

    def scales(self, d: int, range_rate: bool) -> FloatArray:
        """Variance multipliers ``k`` of the channels: range, azimuth, [elevation], [rr]."""
        k = [self.outlier_scale_range, self.outlier_scale_azimuth]
        if d == 3:
            k.append(self.outlier_scale_elevation)
        if range_rate:
            k.append(self.outlier_scale_range_rate)
        return np.array(k)


@dataclass(frozen=True)
class LevelIMMConfig(OutlierConfig, LevelConfig):
    """Parameters of ``--method mm`` (levels, position only; a 1 % outlier prior keeps an
    occasional wild plot from throwing the ladder to its top level)."""

    use_range_rate: bool = param(False, doc="use the plots' range rate when they have one")


@dataclass(frozen=True)
class ContaminatedConfig(OutlierConfig, LevelConfig):
    """Parameters of ``--method robust-adaptive`` (levels + contaminated-Gaussian update,
    prior ``epsilon = 0.1`` per channel, learnt over about 30 scans: chosen on the tuning
    seeds of ``benchmarks/defaults.py`` among a fixed 0.1 and memories of 30 and 100)."""

    outlier_probability: float = redefault(OutlierConfig, "outlier_probability", 0.1)
    outlier_memory: float = redefault(OutlierConfig, "outlier_memory", 30.0)
    use_range_rate: bool = param(True, doc="use the plots' range rate when they have one")


@dataclass(frozen=True)
class RamazanovConfig(OutlierConfig, LevelConfig):
    """Parameters of ``--method robust`` (levels + algorithm R's robust variance; the
    contaminated likelihood of the level probabilities with ``epsilon = 0.1``)."""

    outlier_probability: float = param(
        0.1, doc="prior probability that a plot channel is an outlier", min=0, max=0.5,
        exclusive_min=True,
    )  # fmt: skip
    delta_range: float = param(3.84, doc="outlier threshold on J, range (chi2 1 dof)", min=0,
                               exclusive_min=True)  # fmt: skip
    delta_bearing: float = param(3.84, doc="outlier threshold on J, bearing", min=0,
                                 exclusive_min=True)  # fmt: skip


@dataclass(frozen=True)
class HuberLevelsConfig(LevelConfig):
    """Parameters of ``--method huber`` (levels + Huber IRLS update)."""

    c: float = param(1.345, doc="Huber threshold on the whitened residual", min=0,
                     exclusive_min=True)  # fmt: skip
    iterations: int = param(2, doc="IRLS iterations (2-5 agree within 3 % on the tuning seeds)",
                            min=1)  # fmt: skip
    level_nu: float = param(3.0, doc="Student-t degrees of freedom of the level likelihood",
                            min=0, exclusive_min=True)  # fmt: skip


@dataclass(frozen=True)
class StudentTLevelsConfig(LevelConfig):
    """Parameters of ``--method student-t`` (levels + VB Student-t update)."""

    nu: float = param(3.0, doc="Student-t degrees of freedom", min=0, exclusive_min=True)
    iterations: int = param(2, doc="VB iterations (2-5 agree within 2 % on the tuning seeds)",
                            min=1)  # fmt: skip
    flag_threshold: float = param(6.63, doc="outlier flag on E[e^2]/r (chi2 1 dof 99 %)", min=0)


# ---------------------------------------------------------------------------
# Pure functions
# ---------------------------------------------------------------------------
def level_noise(config: LevelConfig, dt: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Process-noise PSDs ``q (B, M)`` (m^2/s^3) and transition matrices ``(B, M, M)``
    (``[i, j] = P(level j | level i)``) for scan intervals ``dt (B,)`` (s)."""
    t = np.asarray(dt, dtype=float)
    if config.accel_levels:
        q = np.square(config.accel_levels)[None, :] * t[:, None]
    else:
        q = np.broadcast_to(np.asarray(config.q_levels, dtype=float), (t.size, config.n_levels))
    M = config.n_levels
    if config.sojourn_times:
        p = np.exp(-t[:, None] / np.asarray(config.sojourn_times)[None, :])
    else:
        p = np.full((t.size, M), config.p_stay)
    if M == 1:
        return q, np.ones((t.size, 1, 1))
    off = (1.0 - p) / (M - 1)
    eye = np.eye(M, dtype=bool)
    PI = np.where(eye[None], p[:, :, None], off[:, :, None])
    return q, PI


def outlier_patterns(scales: FloatArray, epsilon: float) -> tuple[FloatArray, FloatArray]:
    """Every outlier pattern ``g in {0,1}^m``: ``(C, m)`` 0/1 and the log priors ``(C,)``
    (``prod eps^g (1 - eps)^(1 - g)``)."""
    m = scales.size
    G = np.array(list(itertools.product((0.0, 1.0), repeat=m)))
    logp = G @ np.full(m, math.log(epsilon)) + (1 - G) @ np.full(m, math.log1p(-epsilon))
    return G, logp


@njit(cache=True)
def _mixture_core(P, y, H, r, G, logp, k, dx, Po, ll, pout):  # pragma: no cover - compiled
    """Update of ``N`` Gaussians ``(x_i, P_i)`` on innovations ``y_i`` under plot noise that
    is, per pattern ``g``, ``N(0, diag(r_i * k^G_g))`` with prior ``exp(logp_g)``.

    With ``u_g = S_g^-1 y`` and weights ``w_g ∝ pi_g N(y; 0, S_g)`` the collapsed posterior
    is exactly ``x + P H^T u``, ``P - P H^T W H P`` with ``u = sum w_g u_g`` and
    ``W = sum w_g (S_g^-1 - (u_g - u)(u_g - u)^T)`` -- every pattern costs an ``m x m``
    factorisation only. Writes the state correction ``dx``, ``Po``, the log-likelihood and
    the posterior outlier probability of each channel; a non-positive-definite ``S_g``
    gives NaN.
    """
    N, n = dx.shape
    m = y.shape[1]
    C = G.shape[0]
    PHt = np.empty((n, m))
    HPH = np.empty((m, m))
    S = np.empty((m, m))
    L = np.empty((m, m))
    Si = np.empty((C, m, m))
    u = np.empty((C, m))
    lw = np.empty(C)
    e = np.empty(m)
    ub = np.empty(m)
    W = np.empty((m, m))
    PW = np.empty((n, m))
    for i in range(N):
        matmul_core(P[i], H[i].T, PHt)
        matmul_core(H[i], PHt, HPH)
        bad = False
        for g in range(C):
            for a in range(m):
                for c in range(m):
                    S[a, c] = 0.5 * (HPH[a, c] + HPH[c, a])
                S[a, a] += r[i, a] * (k[a] if G[g, a] > 0.0 else 1.0)
            logdet = cholesky_core(S, L)
            if not logdet == logdet:
                bad = True
                break
            for col in range(m):  # S^-1 column by column
                for a in range(m):
                    e[a] = 1.0 if a == col else 0.0
                forward_core(L, e, ub)
                for a in range(m - 1, -1, -1):
                    v = ub[a]
                    for b in range(a + 1, m):
                        v -= L[b, a] * Si[g, b, col]
                    Si[g, a, col] = v / L[a, a]
            q = 0.0
            for a in range(m):
                v = 0.0
                for b in range(m):
                    v += Si[g, a, b] * y[i, b]
                u[g, a] = v
                q += y[i, a] * v
            lw[g] = logp[i, g] - 0.5 * (q + logdet + m * _LOG_2PI)
        if bad:
            ll[i] = np.nan
            for a in range(n):
                dx[i, a] = np.nan
            continue
        top = lw.max()
        tot = 0.0
        for g in range(C):
            tot += math.exp(lw[g] - top)
        lse = top + math.log(tot)
        ll[i] = lse
        for a in range(m):
            ub[a] = 0.0
            pout[i, a] = 0.0
            for c in range(m):
                W[a, c] = 0.0
        for g in range(C):
            w = math.exp(lw[g] - lse)
            for a in range(m):
                ub[a] += w * u[g, a]
                pout[i, a] += w * G[g, a]
                for c in range(m):
                    W[a, c] += w * (Si[g, a, c] - u[g, a] * u[g, c])
        for a in range(m):
            for c in range(m):
                W[a, c] += ub[a] * ub[c]
        for a in range(n):
            v = 0.0
            for c in range(m):
                v += PHt[a, c] * ub[c]
            dx[i, a] = v
        matmul_core(PHt, W, PW)
        for a in range(n):
            for b in range(a, n):
                v = P[i, a, b]
                for c in range(m):
                    v -= PW[a, c] * PHt[b, c]
                Po[i, a, b] = v
                Po[i, b, a] = v


#: the single pattern of Gaussian plot noise, per measurement size
_GAUSSIAN = {m: (np.zeros((1, m)), np.zeros(1), np.ones(m)) for m in range(1, 6)}


def _flat(a: FloatArray, lead: tuple[int, ...], tail: tuple[int, ...]) -> FloatArray:
    """``a`` broadcast to ``lead + tail`` as a contiguous ``(N,) + tail`` array."""
    if a.shape != lead + tail:
        a = np.broadcast_to(a, lead + tail)
    return np.ascontiguousarray(a).reshape((-1,) + tail)


def mixture_update(
    x: FloatArray,
    P: FloatArray,
    y: FloatArray,
    H: FloatArray,
    r: FloatArray,
    patterns: tuple[FloatArray, FloatArray, FloatArray] | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Exact update of Gaussians ``x (..., n)``, ``P (..., n, n)`` on innovations
    ``y (..., m)`` (angles already wrapped) with Jacobians ``H (..., m, n)`` under
    contaminated plot noise (``patterns`` = :func:`outlier_patterns` and the scales ``k``)
    or, without patterns, Gaussian noise ``diag(r)``; ``r (..., m)`` or ``(m,)``.

    Returns the collapsed posterior ``x``, ``P``, the log-likelihood ``(...)`` and the
    posterior outlier probability of each channel ``(..., m)`` (compiled
    :func:`_mixture_core`).
    """
    lead, n, m = x.shape[:-1], x.shape[-1], y.shape[-1]
    N = int(np.prod(lead))
    G, logp, k = patterns if patterns is not None else _GAUSSIAN[m]
    C = G.shape[0]
    dx = np.empty((N, n))
    Po = np.empty((N, n, n))
    ll = np.empty(N)
    pout = np.empty((N, m))
    _mixture_core(
        _flat(P, lead, (n, n)), _flat(y, lead, (m,)), _flat(H, lead, (m, n)),
        _flat(r, lead, (m,)), G, _flat(logp, lead, (C,)), k, dx, Po, ll, pout,
    )  # fmt: skip
    xo = x + dx.reshape(lead + (n,))
    return xo, Po.reshape(lead + (n, n)), ll.reshape(lead), pout.reshape(lead + (m,))


def contaminated_loglik(
    y: FloatArray, H: FloatArray, P: FloatArray, r: FloatArray, patterns: Any
) -> FloatArray:
    """``log sum_g pi_g N(y; 0, H P H^T + R_g)`` of innovations ``y (..., m)``."""
    return mixture_update(np.zeros(P.shape[:-1]), P, y, H, r, patterns)[2]


def _hph(H: FloatArray, P: FloatArray) -> FloatArray:
    return np.asarray(H @ P @ np.swapaxes(H, -1, -2))


# ---------------------------------------------------------------------------
# The filter on the contract
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class _Linearised:
    """Every level's prior and its linearised measurement, the input of a rule: states
    ``X (B, M, n)``, covariances ``P (B, M, n, n)``, the plots ``z (B, M, m)`` (each track's
    plot repeated for its levels), ``hx (B, M, m)``, Jacobians ``H (B, M, m, n)`` and the
    innovations ``y = z - hx (B, M, m)`` (angles wrapped)."""

    X: FloatArray
    P: FloatArray
    z: FloatArray
    hx: FloatArray
    H: FloatArray
    y: FloatArray


@dataclass(frozen=True)
class _Updated:
    """One rule's update of every level: states, covariances, log-likelihoods ``(B, M)``
    and a per-channel outlier score ``(B, M, m)`` in [0, 1]."""

    X: FloatArray
    P: FloatArray
    ll: FloatArray
    outlier: FloatArray


class LevelIMM(ConfiguredFilter, CartesianState):
    """IMM of constant-velocity EKFs with process-noise levels (Gaussian plots).

    ``TrackState.x``/``P``: the combined estimate ``[x, y, (z), vx, vy, (vz)]``; ``aux``:
    the level states ``X (B, M, n)``, ``PP (B, M, n, n)``, the level probabilities
    ``mu (B, M)`` (after :meth:`predict` the predicted ones), the PSDs of the last
    prediction ``q (B, M)`` and the channel outlier scores ``outlier (B, m)``.
    """

    Config: ClassVar[type] = LevelIMMConfig
    dims: ClassVar[tuple[int, ...]] = (2, 3)

    def _setup(self) -> None:
        d = self.d
        self.R = measurement_noise(self.sensor, d, self.range_rate)
        self.r = np.ascontiguousarray(np.diagonal(self.R))
        ang = np.zeros(self.r.size)
        ang[1] = 1.0  # azimuth
        if d == 3:
            ang[2] = 1.0  # elevation
        self.angular = ang
        self.M = self.config.n_levels
        self._valid = np.ones((self.M, 2 * d))
        eps = float(getattr(self.config, "outlier_probability", 0.0))
        self.patterns: tuple[FloatArray, FloatArray, FloatArray] | None = None
        if eps > 0:
            k = self.config.scales(d, self.range_rate)
            self.patterns = (*outlier_patterns(k, eps), k)
        self._rule_setup()

    def _rule_setup(self) -> None:
        """Constants of the update rule (subclasses)."""

    # -- contract ------------------------------------------------------------------
    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        xx = np.asarray(x, dtype=float)
        PP = np.asarray(P, dtype=float)
        B, M = xx.shape[0], self.M
        aux = {
            "X": np.repeat(xx[:, None], M, 1),
            "PP": np.repeat(PP[:, None], M, 1),
            "mu": np.full((B, M), 1.0 / M),
            "q": np.zeros((B, M)),
            "outlier": np.zeros((B, self.r.size)),
            "eps": np.full((B, self.r.size), getattr(self.config, "outlier_probability", 0.0)),
        }
        return TrackState.new(t, xx, PP, aux)

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        tt, dt = step_times(state, t)
        a = state.aux
        q, PI = level_noise(self.config, dt)
        n = state.x.shape[1]
        X0, P0, c = mix(IMMState(a["X"], a["PP"], a["mu"]), PI, self._valid)
        F, Q1 = cv_matrices(dt, 1.0, self.d)  # one cached pair when the scans are regular
        Q1 = Q1[:, None] if Q1.ndim == 3 else Q1
        F = F[:, None] if F.ndim == 3 else F
        X, PP = kalman.predict(X0, P0, F, q[:, :, None, None] * Q1)
        _, x, P, _ = combine(X, PP, c, np.zeros_like(c), np.arange(n))
        out = predicted(state, tt, x, P, {"X": X, "PP": PP, "mu": c, "q": q})
        still = dt <= 0  # predicting to the same time changes nothing
        return out.where(still, predicted(state, tt, state.x, state.P)) if still.any() else out

    def _measure(self, x: FloatArray, plots: Plots, reps: int) -> tuple[FloatArray, FloatArray]:
        """``h(x)`` and Jacobians of states ``x (B * reps, n)`` (``reps`` per plot)."""
        s = np.repeat(sensor_state(plots, self.d), reps, 0)
        return polar_measurement(x, s, self.d, self.range_rate)

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        hx, H = self._measure(state.x, plots, 1)
        y = wrap_angles(plots.polar(self.range_rate) - hx, self.angular)
        return y, kalman.symmetrize(_hph(H, state.P) + self.R)

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        a = state.aux
        B, M = len(state), self.M
        X, PP = a["X"], a["PP"]
        n = X.shape[-1]
        hx, H = self._measure(X.reshape(B * M, n), plots, M)
        hx, H = hx.reshape(B, M, -1), H.reshape(B, M, -1, n)
        z, ok = usable(plots.polar(self.range_rate), hx[:, 0])
        with np.errstate(all="ignore"):
            y, S = self.innovation(state, plots)
            res = self._rule(self._linearised(X, PP, z, hx, H), self._patterns(a["eps"]))
            ll = np.where(ok[:, None], res.ll, 0.0)
            mu, x, P, tot = combine(res.X, res.P, a["mu"], ll, np.arange(n))
            nis = kalman.mahalanobis(y, S)
        outl = np.einsum("bj,bjm->bm", mu, res.outlier)
        aux = {
            "X": res.X,
            "PP": res.P,
            "mu": mu,
            "outlier": outl,
            "eps": self._learn(a["eps"], outl),
        }
        aux |= self._after_update(state.replace(x=x, P=P, aux=aux))
        return finish_update(state, x, P, nis, tot, state.t, aux, ok)

    def _linearised(
        self, X: FloatArray, P: FloatArray, z: FloatArray, hx: FloatArray, H: FloatArray
    ) -> _Linearised:
        """The input of :meth:`_rule` from the plots ``z (B, m)`` of the tracks."""
        zz = np.broadcast_to(z[:, None], hx.shape)
        return _Linearised(X, P, zz, hx, H, wrap_angles(zz - hx, self.angular))

    def _patterns(self, eps: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray] | None:
        """The outlier patterns with each track's log priors ``(B, 1, C)`` from its channel
        outlier probabilities ``eps (B, m)``."""
        if self.patterns is None:
            return None
        G, _, k = self.patterns
        logp = np.log(eps) @ G.T + np.log1p(-eps) @ (1.0 - G).T
        return G, logp[:, None, :], k

    def _learn(self, eps: FloatArray, outlier: FloatArray) -> FloatArray:
        """The channel outlier probabilities after this scan: a running mean of the
        posterior outlier probabilities over ``outlier_memory_scans`` (fixed when 0)."""
        memory = float(getattr(self.config, "outlier_memory", 0.0))
        if self.patterns is None or memory <= 0:
            return eps
        return np.clip(eps + (outlier - eps) / memory, _EPS_RANGE[0], _EPS_RANGE[1])

    def _after_update(self, updated: TrackState) -> dict[str, Any]:
        """Extra ``aux`` entries from the updated batch (subclasses; rejected plots keep the
        prior's)."""
        return {}

    def _rule(self, lin: _Linearised, patterns: Any = None) -> _Updated:
        """The update of every level: exact under the contaminated noise (``patterns``:
        :meth:`_patterns`), else the Gaussian EKF update (:func:`mixture_update`)."""
        x, Pm, ll, p = mixture_update(lin.X, lin.P, lin.y, lin.H, self.r, patterns)
        return _Updated(x, Pm, ll, p)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        """Common columns, ``p_manoeuvre`` (probability of every level but the quietest),
        ``q_m2ps3`` (the probability-weighted PSD of the last prediction) and
        ``outlier_range`` / ``outlier_bearing`` (outlier score of the channel > 0.5)."""
        a = state.aux
        cols: dict[str, NDArray[Any]] = dict(common_columns(state.x, state.P, self.d))
        mu = a["mu"]
        cols["p_manoeuvre"] = 1.0 - mu[:, 0] if self.M > 1 else np.zeros(len(state))
        cols["q_m2ps3"] = np.einsum("bj,bj->b", mu, a["q"])
        o = a["outlier"]
        cols["outlier_range"] = (o[:, 0] > 0.5).astype(np.int64)
        cols["outlier_bearing"] = (o[:, 1] > 0.5).astype(np.int64)
        return cols


class ContaminatedLevels(LevelIMM):
    """``--method robust-adaptive``: level IMM with the exact contaminated-Gaussian update,
    ``epsilon = 0.1`` (``adapting`` = the probability of the agile levels > 0.5)."""

    Config: ClassVar[type] = ContaminatedConfig

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        cols = super().columns(state)
        cols["adapting"] = (cols["p_manoeuvre"] > 0.5).astype(np.int64)
        return cols


class RamazanovLevels(LevelIMM):
    """``--method robust``: level IMM whose levels update with algorithm R's robust
    variance (``r_c <- max(r_c, y_c^2 / Delta_c - (H P H^T)_cc)``); the level
    probabilities use the contaminated-Gaussian likelihood (the spec's noise model)."""

    Config: ClassVar[type] = RamazanovConfig
    dims: ClassVar[tuple[int, ...]] = (2,)

    def _rule(self, lin: _Linearised, patterns: Any = None) -> _Updated:
        c = self.config
        delta = np.array([c.delta_range, c.delta_bearing])
        y, H, P = lin.y, lin.H, lin.P
        hph = np.einsum("...ij,...jk,...ik->...i", H, P, H)
        out = y**2 / (hph + self.r) > delta
        r = np.where(out, y**2 / delta - hph, self.r)
        x, Pm, _, _ = mixture_update(lin.X, P, y, H, r)
        ll = contaminated_loglik(y, H, P, self.r, patterns)
        return _Updated(x, Pm, ll, out.astype(float))


def _whitened(
    y: FloatArray, H: FloatArray, P: FloatArray, r: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Innovation components over their predicted std ``y_c / sqrt((H P H^T)_cc + r_c)``,
    and the log of those stds summed (for the densities)."""
    s = np.diagonal(_hph(H, P), axis1=-2, axis2=-1) + r
    return y / np.sqrt(s), 0.5 * np.log(s).sum(-1)


@dataclass(frozen=True)
class _Result:
    """The fields of an update the reweighting of :mod:`robust_baselines` reads."""

    x: FloatArray
    P: FloatArray
    y: FloatArray


def _kernel_update(
    x: FloatArray,
    P: FloatArray,
    z: FloatArray,
    hx: FloatArray,
    H: FloatArray,
    R: FloatArray,
    angular: ArrayLike,
    check: bool = False,
) -> _Result:
    """:func:`seatrack.kalman.extended_update` with a diagonal ``R`` through the compiled
    :func:`mixture_update` (one call for every level of every track; non-positive-definite
    innovation covariances give NaN, rejected by the caller)."""
    y = wrap_angles(z - hx, np.asarray(angular, dtype=float))
    xo, Po, _, _ = mixture_update(x, P, y, H, np.diagonal(R, axis1=-2, axis2=-1))
    return _Result(xo, Po, y)


def student_t_logpdf(u: FloatArray, nu: float) -> FloatArray:
    """Log density of independent unit Student-t components ``u`` (summed over the last
    axis), ``nu`` degrees of freedom."""
    log_norm = float(gammaln((nu + 1) / 2) - gammaln(nu / 2) - 0.5 * math.log(nu * math.pi))
    return np.asarray((log_norm - 0.5 * (nu + 1) * np.log1p(u**2 / nu)).sum(-1))


class _RobustRule(LevelIMM):
    """Shared shell of the Huber / Student-t levels: a robust update of
    :mod:`seatrack.filters.robust_baselines` and a heavy-tailed density."""

    dims: ClassVar[tuple[int, ...]] = (2,)
    _cfg: HuberConfig | StudentTConfig

    def _density(self, u: FloatArray) -> FloatArray:
        raise NotImplementedError

    def _rule(self, lin: _Linearised, patterns: Any = None) -> _Updated:
        res, flags = reweighted_update(lin.X, lin.P, lin.z, lin.hx, lin.H, self.R, self.r,
                                       self._cfg, False, _kernel_update)  # fmt: skip
        u, logs = _whitened(lin.y, lin.H, lin.P, self.r)
        return _Updated(res.x, res.P, self._density(u) - logs, flags.astype(float))


class HuberLevels(_RobustRule):
    """``--method huber``: level IMM with Huber's IRLS update; level likelihood Student-t
    (``level_nu``), not Huber's least favourable density: its Laplace tails let a gross
    outlier vote ~7 nats for a level twice as wide (the IMM went agile, 20 m/s velocity
    errors at 20 % contamination); log tails give ~2. Tuning seeds of
    ``benchmarks/defaults.py``: 36.1 / 41.3 m -> 19.5 / 27.9 m on the contaminated sets,
    0-5 % on the clean ones."""

    Config: ClassVar[type] = HuberLevelsConfig

    def _rule_setup(self) -> None:
        c = self.config
        self._cfg = HuberConfig(c=c.c, iterations=c.iterations)

    def _density(self, u: FloatArray) -> FloatArray:
        return student_t_logpdf(u, self.config.level_nu)


class StudentTLevels(_RobustRule):
    """``--method student-t``: level IMM with the VB Student-t update; level likelihood
    the Student-t density of each whitened innovation component."""

    Config: ClassVar[type] = StudentTLevelsConfig

    def _rule_setup(self) -> None:
        c = self.config
        self._cfg = StudentTConfig(nu=c.nu, iterations=c.iterations,
                                   flag_threshold=c.flag_threshold)  # fmt: skip

    def _density(self, u: FloatArray) -> FloatArray:
        return student_t_logpdf(u, self.config.nu)
