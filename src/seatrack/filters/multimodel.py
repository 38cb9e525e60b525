"""Multiple-model tracking filter with range rate (JP H06-95138 B2; spec ``multimodel.md``).

``N`` hypotheses share one constant-velocity state ``x = [x, y, (z), vx, vy, (vz)]`` and one
covariance; hypothesis ``a`` adds a known constant input ``alpha_a`` (an acceleration
vector, m/s^2) over the scan (``x_k = Phi x_{k-1} + Gamma w + Gamma' alpha_a``,
``Gamma = Gamma' = [T^2/2 I; T I]``). Model reliabilities ``beta`` are Bayesian posterior
probabilities from the converted position *and* the measured range rate (the novelty
over Gholson & Moose 1977); the state uses one common gain, and the covariances include
the spread of the model means ("integrated" covariances).

Processing at scan k follows the spec's steps 1-11 exactly (compiled in
:mod:`seatrack.filters.multimodel_kernel`):

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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray

from seatrack.config import Checked
from seatrack.config import param
from seatrack.filters.base import CartesianState
from seatrack.filters.base import Plots
from seatrack.filters.base import SensorNoise
from seatrack.filters.base import TrackState
from seatrack.filters.base import common_columns
from seatrack.filters.base import conversion_param
from seatrack.filters.base import converted_positions
from seatrack.filters.base import finish_update
from seatrack.filters.base import predicted
from seatrack.filters.base import speed_sigma_param
from seatrack.filters.base import step_times
from seatrack.filters.imm import uniform_transition
from seatrack.filters.multimodel_kernel import step_kernel
from seatrack.geometry import G0
from seatrack.information import as_float64
from seatrack.models.targets import TargetClass

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
    "MultiModel",
    "MultiModelRangeRate",
    "MultiModelTrackConfig",
    "MultiModelRangeRateConfig",
]

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
        if self.transition is not None:
            return np.asarray(self.transition, dtype=float)
        return uniform_transition(len(self.alphas), self.p_stay)

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
    from seatrack.models.measurement import range_rate
    from seatrack.models.measurement import range_rate_jacobian

    xx = np.asarray(x, dtype=float)
    d = xx.shape[-1] // 2
    p = xx[..., :d] - (0.0 if sensor is None else np.asarray(sensor, float)[..., :d])
    v = xx[..., d:] - (0.0 if sensor_vel is None else np.asarray(sensor_vel, float)[..., :d])
    jp, jv = range_rate_jacobian(p, v)
    return range_rate(p, v), np.concatenate([jp, jv], -1)


# ---------------------------------------------------------------------------
# Filter object (thin shell)
# ---------------------------------------------------------------------------
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
        self.flags = (
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
        zz = as_float64(z)
        lead = zz.shape[:-1]
        d = self.d
        x = np.zeros(lead + (self.n,))
        x[..., :d] = zz
        if velocity is not None:
            x[..., d:] = as_float64(velocity)
        P = np.zeros(lead + (self.n, self.n))
        P[..., :d, :d] = as_float64(R)
        vs = np.broadcast_to(as_float64(velocity_std), lead + (d,))
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
        sp = np.zeros(d) if sensor is None else as_float64(sensor)[..., :d]
        sv = np.zeros(d) if sensor_vel is None else as_float64(sensor_vel)[..., :d]
        out = step_kernel(
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
            self.flags[0],
            self.flags[1],
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
        tt = as_float64(t)
        zz = as_float64(z)
        RR = as_float64(R)
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
        rr = None if range_rate is None else as_float64(range_rate)
        sp = None if sensor is None else as_float64(sensor)
        sv = None if sensor_vel is None else as_float64(sensor_vel)
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
# The filter contract: `seatrack track --method mm | mm-rangerate`
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class MultiModelTrackConfig(Checked):
    """Parameters of ``--method mm`` (position-only reliabilities, the prior art).

    The hypotheses are the embodiment's five: ``accel`` North, East, South, West and zero.
    """

    sigma_accel: float = param(
        3.0, key="sigma_accel_mps2", unit="m/s^2", doc="white acceleration std per axis", min=0
    )
    accel: float = param(
        10.0,
        key="accel_g",
        unit="g",
        doc="magnitude of the N/E/S/W hypotheses",
        min=0,
        max=1e4,  # 10,000 g: a larger value is a typo (its square would overflow)
    )
    p_stay: float = param(0.9, doc="diagonal of the hypothesis transition matrix", min=0, max=1)
    conversion: str = conversion_param()
    initial_speed_sigma: float = speed_sigma_param(300.0, aliases=("initial_velocity_std_mps",))
    integrated_covariance: bool = param(True, doc="spread-of-means terms (steps 8 and 11)")
    range_rate_likelihood: str = param(
        "independent",
        choices=("independent", "joint"),
        doc="range-rate likelihood: the spec's product, or the exact joint (mm-rangerate)",
    )

    @classmethod
    def for_target(cls, target: TargetClass) -> Any:
        """What the patent leaves open, from a target class: hypotheses at the class's typical
        manoeuvre acceleration, white acceleration a quarter of it (the residual of a
        turn's rotating acceleration between hypotheses), the class's maximum speed as the
        initial speed std."""
        return cls(
            accel=target.accel_typical,
            sigma_accel=0.25 * target.accel_typical,
            initial_speed_sigma=target.speed_max,
        )


@dataclass(frozen=True)
class MultiModelRangeRateConfig(MultiModelTrackConfig):
    """Parameters of ``--method mm-rangerate`` (reliabilities from position and range rate)."""

    sigma_accel: float = param(
        10.0, key="sigma_accel_mps2", unit="m/s^2", doc="white acceleration std per axis", min=0
    )


class MultiModel(CartesianState):
    """The multiple-model filter on the filter contract (``--method mm``).

    ``TrackState.x``/``P`` hold the integrated estimate: after :meth:`predict` the
    integrated prediction ``x(-)``, ``P(-)`` (steps 10-11), after :meth:`update` the
    filtered ``x(+)``, ``P(+)``. ``aux`` carries what the next scan starts from:
    ``x_post``, ``P_post``, ``t_post`` (the last filtered estimate and its time) and the
    reliabilities ``beta (B, N)``. Plots are converted to Cartesian positions
    (:func:`seatrack.filters.converted.convert_plots`) with the sensor noise. Every step is
    one call of the compiled scan kernel over the whole batch.
    """

    Config: type = MultiModelTrackConfig
    dims: ClassVar[tuple[int, ...]] = (2, 3)
    use_range_rate: ClassVar[bool] = False

    def __init__(
        self,
        config: MultiModelTrackConfig | None = None,
        sensor: SensorNoise | None = None,
        d: int = 2,
        range_rate: bool = False,
    ) -> None:
        self.config = config or self.Config()
        self.sensor = sensor or SensorNoise()
        self.d = d
        self.range_rate = bool(range_rate and self.use_range_rate)
        c = self.config
        alphas = tuple(tuple(a) for a in np.asarray(DEFAULT_ALPHAS) / (10 * G0) * c.accel)
        self.mm = MultiModelFilter(
            MultiModelConfig(
                alphas=alphas,
                p_stay=c.p_stay,
                sigma_w=c.sigma_accel,
                sigma_range_rate=self.sensor.sigma_range_rate,
                use_range_rate=self.range_rate,
                integrated_covariance=c.integrated_covariance,
                range_rate_likelihood=c.range_rate_likelihood,
            ),
            d=d,
        )

    def initiate(self, t: ArrayLike, x: ArrayLike, P: ArrayLike) -> TrackState:
        xx = np.asarray(x, dtype=float)
        PP = np.asarray(P, dtype=float)
        beta = np.broadcast_to(self.mm.config.prior_vector(), (xx.shape[0], len(self.mm.names)))
        st = TrackState.new(t, xx, PP)
        return st.replace(aux={"x_post": xx, "P_post": PP, "t_post": st.t, "beta": beta.copy()})

    def _scan(self, state: TrackState, z: FloatArray, R: FloatArray, rho: Any, plots: Any) -> Any:
        d = self.d
        a = state.aux
        sp = np.zeros(d) if plots is None else plots.sensor[:, :d]
        sv = np.zeros(d) if plots is None else plots.sensor_vel[:, :d]
        return step_kernel(
            a["x_post"], a["P_post"], a["beta"], state.t - a["t_post"], z, R, rho,
            self.mm.config.sigma_range_rate**2, sp, sv, self.mm.alphas, self.mm.pi, self.mm.Q,
            self.mm.flags[0], self.mm.flags[1],
        )  # fmt: skip

    def predict(self, state: TrackState, t: ArrayLike) -> TrackState:
        tt, _ = step_times(state, t)
        s = state.replace(t=tt)
        nan = np.full(self.d, np.nan)
        out = self._scan(s, nan, np.eye(self.d), np.nan, None)  # no plot: pure prediction
        return predicted(state, tt, out[3], out[4])

    def convert(self, plots: Plots) -> tuple[FloatArray, FloatArray]:
        """Converted positions ``(B, d)`` and covariances ``(B, d, d)`` of the plots."""
        return converted_positions(plots, self.sensor, self.config.conversion)

    def innovation(self, state: TrackState, plots: Plots) -> tuple[FloatArray, FloatArray]:
        z, R = self.convert(plots)
        d = self.d
        return z - state.x[:, :d], state.P[:, :d, :d] + R

    def update(self, state: TrackState, plots: Plots) -> TrackState:
        z, R = self.convert(plots)
        ok = np.asarray(np.isfinite(z).all(-1) & np.isfinite(R).all((-1, -2)), dtype=bool)
        z = np.where(ok[:, None], z, np.nan)
        R = np.where(ok[:, None, None], R, np.eye(self.d))
        rho = plots.range_rate if self.range_rate and plots.range_rate is not None else np.nan
        with np.errstate(all="ignore"):
            xo, Po, bo, _, _, ll, nis = self._scan(state, z, R, rho, plots)
        aux = {"x_post": xo, "P_post": Po, "t_post": state.t, "beta": bo}
        return finish_update(state, xo, Po, nis, ll, state.t, aux, ok)

    def columns(self, state: TrackState) -> dict[str, NDArray[Any]]:
        cols = common_columns(state.x, state.P, self.d)
        for a, name in enumerate(self.mm.names):
            cols[f"p_{name}"] = state.aux["beta"][:, a]
        return cols


class MultiModelRangeRate(MultiModel):
    """``--method mm-rangerate``: reliabilities from position and range rate (the patent)."""

    Config: type = MultiModelRangeRateConfig
    use_range_rate: ClassVar[bool] = True
    needs_range_rate: ClassVar[bool] = True
