"""Baselines for the robust sonar tracker, on the interface of :mod:`seatrack.filters.robust`.

Spec ``docs/robust.md`` ("Paper's Monte-Carlo set-up" and "Beyond the paper"). All filters
run the full Cartesian state ``[x, y, vx, vy(, ax, ay)]`` (East, North) with the 2-D
range/bearing measurement :class:`seatrack.models.measurement.RangeBearing` and the
compiled :func:`seatrack.kalman.extended_update` (Joseph form), vectorised over a leading
batch axis. They share the motion model, the constant disturbance noise ``L0`` and the
initialisation of the robust filter (:class:`~seatrack.filters.robust.SonarModel`,
:func:`~seatrack.filters.robust.initial_state`) so that differences come from the update only.

* :func:`ekf_filter` -- the ordinary (non-robust) extended Kalman filter, the paper's anchor
  ``RMS_EKF(k)`` (Bar-Shalom, Li & Kirubarajan 2001, sec. 10.3).
* :func:`clairvoyant_filter` -- the paper's "optimal" filter: an EKF that knows which
  measurement components are anomalous (uses ``q1`` for them) and the true manoeuvre
  (a per-step disturbance intensity supplied by the caller).
* :func:`huber_filter` -- Huber M-estimation update by iteratively reweighted least squares
  on the whitened measurement residuals (Huber 1964; Boncelet & Dickinson 1983; Karlgaard &
  Schaub 2007, "Huber-based divided difference filtering", J. Guid. Control Dyn. 30(3)).
* :func:`student_t_filter` -- variational-Bayes Student-t measurement-noise filter
  (Piché, Särkkä & Hartikainen 2012, "Recursive outlier-robust filtering and smoothing for
  nonlinear systems using the multivariate Student-t distribution", IEEE MLSP; cf. Roth,
  Özkan & Gustafsson 2013 and the VB adaptive filter of Särkkä & Nummenmaa 2009). With
  ``per_component=True`` (default) range and bearing get independent scale variables
  (independent Student-t noises, the natural model for independent range/bearing outliers).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray
from scipy.special import erfc

from seatrack.config import is_positive_integer
from seatrack.config import is_positive_number
from seatrack.config import require
from seatrack.filters.robust import SonarModel
from seatrack.filters.robust import TrackEstimates
from seatrack.filters.robust import axis_noise
from seatrack.filters.robust import axis_transition
from seatrack.filters.robust import beam_to_cartesian_cov
from seatrack.filters.robust import check_track_inputs
from seatrack.filters.robust import initial_state
from seatrack.filters.robust import per_axis_to_flat
from seatrack.kalman import UpdateResult
from seatrack.kalman import extended_update
from seatrack.kalman import predict
from seatrack.models.measurement import RangeBearing

FloatArray = NDArray[np.float64]

__all__ = [
    "HuberConfig",
    "StudentTConfig",
    "ekf_filter",
    "clairvoyant_filter",
    "huber_filter",
    "student_t_filter",
    "plain_update",
    "reweighted_update",
    "huber_minimax_threshold",
    "minimax_threshold_table",
    "student_t_dof",
]

_ANGULAR = np.array([False, True])

#: update step: (x_pred, P_pred, z, hx, H, R) -> (UpdateResult, outlier flags (B, 2))
UpdateStep = Callable[
    [FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray],
    tuple[UpdateResult, NDArray[np.bool_]],
]


@dataclass(frozen=True)
class HuberConfig:
    """Huber M-estimation update.

    Parameters
    ----------
    c : float
        Huber threshold on the whitened residual (1.345: 95 % efficiency at the Gaussian).
    iterations : int
        IRLS iterations (the first uses the innovation itself).
    """

    c: float = 1.345
    iterations: int = 5
    #: the first weights come from the innovation itself (:func:`reweighted_update`)
    prior_first: ClassVar[bool] = True

    def __post_init__(self) -> None:
        require(self, ("c",), is_positive_number, "a positive number")
        require(self, ("iterations",), is_positive_integer, "a positive integer")

    def weights(
        self, e: FloatArray, H: FloatArray, P: FloatArray, r_nom: FloatArray
    ) -> tuple[FloatArray, NDArray[np.bool_]]:
        """Huber weights ``w = min(1, c / |u|)`` of the whitened residuals
        ``u = e / sqrt(r_nom)``, and the flags ``w < 1`` (``H``, ``P``: unused)."""
        u = np.abs(e) / np.sqrt(r_nom)
        w = np.minimum(1.0, self.c / np.maximum(u, 1e-300))
        return w, w < 1.0


@dataclass(frozen=True)
class StudentTConfig:
    """Variational-Bayes Student-t measurement update.

    Parameters
    ----------
    nu : float
        Degrees of freedom of the Student-t measurement noise (scale = the nominal R).
    iterations : int
        VB fixed-point iterations per update.
    per_component : bool
        Independent scale variables for range and bearing (else one for the vector, as in
        Piché et al. 2012).
    flag_threshold : float
        A component is reported as an outlier when its expected normalised squared residual
        ``E[e^2] / r`` exceeds this (chi-square 1 dof, 99 %).
    """

    nu: float = 3.0
    iterations: int = 5
    per_component: bool = True
    flag_threshold: float = 6.63
    #: the first weights come from the residual at the plain update (:func:`reweighted_update`)
    prior_first: ClassVar[bool] = False

    def __post_init__(self) -> None:
        require(self, ("nu",), is_positive_number, "a positive number")
        require(self, ("iterations",), is_positive_integer, "a positive integer")

    def weights(
        self, e: FloatArray, H: FloatArray, P: FloatArray, r_nom: FloatArray
    ) -> tuple[FloatArray, NDArray[np.bool_]]:
        """VB scale weights ``E[lambda] = (nu + m) / (nu + tr(R^-1 A))``, ``A = e e^T +
        H P H^T`` (``P`` the current posterior), per component or for the vector, and the
        flags ``E[e^2] / r > flag_threshold``."""
        hph = np.einsum("...ij,...jk,...ik->...i", H, P, H)
        a = (e**2 + hph) / r_nom
        if self.per_component:
            lam = (self.nu + 1.0) / (self.nu + a)
        else:
            lam = np.repeat(((self.nu + 2.0) / (self.nu + a.sum(-1)))[..., None], 2, -1)
        return lam, a > self.flag_threshold


#: a reweighting rule of :func:`reweighted_update`
Reweighting = HuberConfig | StudentTConfig


def _nominal_r(model: SonarModel) -> FloatArray:
    return np.array([model.sigma_range**2, model.sigma_bearing**2])


def _diag(v: FloatArray) -> FloatArray:
    """``(..., m)`` to diagonal ``(..., m, m)``."""
    return v[..., :, None] * np.eye(v.shape[-1])


def _run_ekf(
    t: ArrayLike,
    z: ArrayLike,
    sensor: ArrayLike,
    model: SonarModel,
    step: UpdateStep,
    r_diag: FloatArray | None = None,
    sigma_a: FloatArray | None = None,
) -> TrackEstimates:
    """Shared predict/update loop of the Cartesian baselines.

    ``r_diag`` (B, N, 2) per-plot measurement variances (default the nominal ones);
    ``sigma_a`` (B, N) per-step disturbance std for the interval ending at each plot
    (default ``model.sigma_a``).
    """
    tt, zz, ss = check_track_inputs(t, z, sensor)
    B, N, _ = zz.shape
    k = model.order
    meas = RangeBearing(n=2 * k)
    X, Pc, psi = initial_state(zz, ss[:, 0], model)
    x = np.swapaxes(X, -1, -2).reshape(B, 2 * k)
    P = beam_to_cartesian_cov(Pc, psi)
    xs = np.empty((B, N, 2 * k))
    Ps = np.empty((B, N, 2 * k, 2 * k))
    outl = np.zeros((B, N, 2), dtype=bool)
    xs[:, 0], Ps[:, 0] = x, P
    r_nom = np.broadcast_to(_nominal_r(model), (B, 2))
    for n in range(1, N):
        dt = tt[n] - tt[n - 1]
        F = per_axis_to_flat(axis_transition(dt, k))
        if sigma_a is None:
            Q = per_axis_to_flat(axis_noise(dt, model.sigma_a, k))
        else:
            Q = per_axis_to_flat(axis_noise(dt, 1.0, k)) * (sigma_a[:, n] ** 2)[:, None, None]
        x, P = predict(x, P, F, Q)
        zn = zz[:, n]
        valid = np.asarray(np.isfinite(zn).all(-1))
        zn = np.where(valid[:, None], zn, 0.0)
        hx = meas.h(x, ss[:, n])
        H = meas.jacobian(x, ss[:, n])
        R = _diag(r_nom if r_diag is None else r_diag[:, n])
        res, flags = step(x, P, zn, hx, H, R)
        x = np.where(valid[:, None], res.x, x)
        P = np.where(valid[:, None, None], res.P, P)
        outl[:, n] = flags & valid[:, None]
        xs[:, n], Ps[:, n] = x, P
    return TrackEstimates(xs, Ps, outl, np.zeros((B, N, 2), dtype=bool))


def plain_update(
    x: FloatArray,
    P: FloatArray,
    z: FloatArray,
    hx: FloatArray,
    H: FloatArray,
    R: FloatArray,
    check: bool = True,
) -> tuple[UpdateResult, NDArray[np.bool_]]:
    """The EKF update of :func:`ekf_filter` (flags: diagnostic only)."""
    res = extended_update(x, P, z, hx, H, R, _ANGULAR, check)
    # diagnostic flag only (the EKF does not act on it): per-component chi-square 1 dof 99 %
    flags = res.y**2 > 6.63 * np.diagonal(res.S, axis1=-2, axis2=-1)
    return res, flags


def ekf_filter(
    t: ArrayLike, z: ArrayLike, sensor: ArrayLike, model: SonarModel | None = None
) -> TrackEstimates:
    """Extended Kalman filter on range/bearing (non-robust anchor of the paper's ratios).

    Same arguments as :func:`seatrack.filters.robust.robust_filter`. ``outlier`` is a
    diagnostic only: the per-component normalised innovation exceeds 6.63 (chi-square 1 dof
    99 %); the EKF uses every plot as it is.
    """
    return _run_ekf(t, z, sensor, model or SonarModel(), plain_update)


def clairvoyant_filter(
    t: ArrayLike,
    z: ArrayLike,
    sensor: ArrayLike,
    outlier: ArrayLike,
    outlier_scale: ArrayLike,
    sigma_a: ArrayLike | None = None,
    model: SonarModel | None = None,
) -> TrackEstimates:
    """The paper's "optimal" filter: an EKF told the truth about the noise.

    Parameters
    ----------
    t, z, sensor : as :func:`ekf_filter`.
    outlier : (B, N, 2) or (N, 2) bool
        Which range / bearing components were drawn from the anomalous noise (the mask of
        :func:`seatrack.simulate.observe`); their variance is ``q1 = outlier_scale * q0``.
    outlier_scale : float or (2,)
        ``q1 / q0`` for [range, bearing] (paper: 10, 25).
    sigma_a : (B, N) or (N,), optional
        True manoeuvre intensity: disturbance std (see ``SonarModel.sigma_a``) of the
        interval ending at each plot; default the nominal ``model.sigma_a``.
    model : SonarModel

    Returns
    -------
    TrackEstimates whose ``outlier`` is the given mask (what the filter was told).
    """
    m = model or SonarModel()
    tt, zz, ss = check_track_inputs(t, z, sensor)
    B, N, _ = zz.shape
    mask = np.broadcast_to(np.asarray(outlier, dtype=bool), (B, N, 2))
    scale = np.broadcast_to(np.asarray(outlier_scale, dtype=float), (2,))
    r = _nominal_r(m) * np.where(mask, scale, 1.0)
    sa = None if sigma_a is None else np.broadcast_to(np.asarray(sigma_a, dtype=float), (B, N))

    def step(
        x: FloatArray, P: FloatArray, zn: FloatArray, hx: FloatArray, H: FloatArray, R: FloatArray
    ) -> tuple[UpdateResult, NDArray[np.bool_]]:
        return extended_update(x, P, zn, hx, H, R, _ANGULAR), np.zeros(x.shape[:-1] + (2,), bool)

    est = _run_ekf(tt, zz, ss, m, step, r_diag=r, sigma_a=sa)
    return TrackEstimates(est.x, est.P, mask.copy(), est.adapting)


def _reweighted_filter(
    t: ArrayLike, z: ArrayLike, sensor: ArrayLike, model: SonarModel | None, config: Reweighting
) -> TrackEstimates:
    """The EKF of :func:`_run_ekf` with :func:`reweighted_update` by ``config``."""
    m = model or SonarModel()
    return _run_ekf(t, z, sensor, m, partial(reweighted_update, r_nom=_nominal_r(m), config=config))


def huber_filter(
    t: ArrayLike,
    z: ArrayLike,
    sensor: ArrayLike,
    model: SonarModel | None = None,
    config: HuberConfig | None = None,
) -> TrackEstimates:
    """EKF with a Huber M-estimation measurement update (iteratively reweighted).

    With whitened residuals ``u_i = (z_i - h_i(x') - H_i (x_j - x')) / sqrt(r_i)`` at the
    current iterate ``x_j`` (``x_0 = x'``, so the first residual is the innovation), the
    weights are ``w_i = min(1, c / |u_i|)`` and the next iterate is the Kalman update with
    ``R_w = diag(r_i / w_i)`` -- the minimiser of the prior term plus ``sum_i w_i u_i^2``,
    i.e. one IRLS step of Huber's loss on the measurement residuals (Karlgaard & Schaub
    2007 reweight the prior residuals too; here the prior is taken as Gaussian). The
    covariance is the Joseph-form covariance of the last step. ``outlier`` flags the
    components with final weight < 1.
    """
    return _reweighted_filter(t, z, sensor, model, config or HuberConfig())


def student_t_filter(
    t: ArrayLike,
    z: ArrayLike,
    sensor: ArrayLike,
    model: SonarModel | None = None,
    config: StudentTConfig | None = None,
) -> TrackEstimates:
    """EKF with a variational-Bayes Student-t measurement update (Piché et al. 2012).

    Measurement noise ``v | lambda ~ N(0, R / lambda)``, ``lambda ~ Gamma(nu/2, nu/2)``.
    The mean-field VB fixed point alternates the Kalman update with ``R / E[lambda]`` and
    ``E[lambda] = (nu + m) / (nu + tr(R^-1 A))`` where ``A = E[e e^T] = e e^T + H P H^T`` is
    the expected squared residual at the posterior (``m`` = 1 per component when
    ``per_component``, else 2 for the vector). ``outlier`` flags the components whose
    expected normalised squared residual exceeds ``flag_threshold``.
    """
    return _reweighted_filter(t, z, sensor, model, config or StudentTConfig())


def reweighted_update(
    x: FloatArray,
    P: FloatArray,
    zn: FloatArray,
    hx: FloatArray,
    H: FloatArray,
    R: FloatArray,
    r_nom: FloatArray,
    config: Reweighting,
    check: bool = True,
    update: Callable[..., Any] = extended_update,
) -> tuple[UpdateResult, NDArray[np.bool_]]:
    """Iteratively reweighted EKF update (the Huber IRLS update of :func:`huber_filter` or
    the VB Student-t update of :func:`student_t_filter`, by the type of ``config``).

    ``config.iterations`` times: weights ``w`` and flags from the residuals ``e`` by
    ``config.weights`` (the innovation first when ``config.prior_first``, else the residual
    at the current estimate), then the update with ``R = diag(r_nom / w)``; returns the last
    update and the last weights' flags. ``update`` is the Kalman update used (signature and
    result fields ``x``, ``P``, ``y`` of :func:`seatrack.kalman.extended_update`)."""
    res = update(x, P, zn, hx, H, R, _ANGULAR, check)
    y = res.y  # innovation (bearing wrapped)
    flags = np.zeros(x.shape[:-1] + (2,), dtype=bool)
    for i in range(config.iterations):
        first = config.prior_first and i == 0
        e = y if first else y - np.einsum("...ij,...j->...i", H, res.x - x)
        w, flags = config.weights(e, H, res.P, r_nom)
        res = update(x, P, zn, hx, H, _diag(r_nom / w), _ANGULAR, check)
    return res, flags


def huber_minimax_threshold(eps: ArrayLike) -> FloatArray:
    """Huber's minimax threshold ``c`` for contamination ``eps`` (0 < eps < 1): the root of
    ``2 phi(c) / c - 2 Phi(-c) = eps / (1 - eps)`` (Huber 1964; ``eps`` 0.01 -> 1.945, 0.05
    -> 1.398, 0.1 -> 1.140, 0.2 -> 0.862), by bisection on ``c`` in (1e-3, 10)."""
    e = np.asarray(eps, dtype=float)
    target = e / (1.0 - e)
    lo, hi = np.full(e.shape, 1e-3), np.full(e.shape, 10.0)
    for _ in range(48):  # the left side decreases in c; 2^-48 of the bracket
        c = 0.5 * (lo + hi)
        f = 2.0 * np.exp(-0.5 * c * c) / (math.sqrt(2.0 * math.pi) * c) - erfc(c / math.sqrt(2))
        lo, hi = np.where(f > target, c, lo), np.where(f > target, hi, c)
    return 0.5 * (lo + hi)


@functools.cache
def _minimax_table() -> tuple[FloatArray, FloatArray]:
    """:func:`huber_minimax_threshold` tabulated on log ``eps`` from 1e-4 to 0.5 (2049
    points), made on first use (2.5 ms): the filters read it every scan, where the bisection
    cost 15-25 us per plot."""
    log_eps = np.linspace(math.log(1e-4), math.log(0.5), 2049)
    return log_eps, huber_minimax_threshold(np.exp(log_eps))


def minimax_threshold_table(eps: ArrayLike) -> FloatArray:
    """:func:`huber_minimax_threshold` by linear interpolation on log ``eps`` (within 2e-6
    of it for ``eps`` in [1e-4, 0.5]; ``eps`` is clipped to that range): what the filters use
    each scan."""
    e = np.clip(np.asarray(eps, dtype=float), 1e-4, 0.5)
    return np.interp(np.log(e), *_minimax_table())


def student_t_dof(eps: ArrayLike, least: float) -> FloatArray:
    """Degrees of freedom of a VB Student-t channel with outlier probability ``eps``:
    ``max(least, 4 c^2 - 2)``, ``c`` = Huber's minimax threshold
    (:func:`minimax_threshold_table`) -- the residual at
    which the Student-t weight ``(nu + 1) / (nu + u^2)`` falls to one half
    (``u^2 = nu + 2``) is the one at which Huber's minimax weight ``c / |u|`` does
    (``|u| = 2 c``): 25.7 at the learnt floor 1e-3, 3.2 at 10 %, ``least`` at 20 %."""
    c = minimax_threshold_table(eps)
    return np.maximum(least, 4.0 * c * c - 2.0)
