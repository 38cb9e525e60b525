"""TMA results: covariance, the observability verdict and the operator picture.

Covariance: ``P = (J^T W J)^-1`` at the solution, computed from the SVD of the whitened
Jacobian with columns scaled to unit norm (:func:`seatrack.information.covariance_from_jacobian`)
after an explicit rank test -- never by hoping LAPACK notices a singular matrix.

Observability verdict (spec "Observability"; scale-invariant -- no threshold depends on the
units of the state). A solution is ``observable`` only if

(a) the geometry can fix the range scale: the own-ship track deviates from a straight
    constant-velocity line by more than ``min_observer_deviation`` (an own-ship leg change;
    smaller deviations are navigation noise), or at least one support value is given;
(b) the whitened Jacobian with unit-norm columns has full rank: its smallest singular value
    exceeds ``rank_tolerance`` times its largest (``1e-10``; an exactly unobservable geometry
    sits at the rounding floor, ~1e-16);
(c) the range is determined to first order: ``sigma_range / range <= max_relative_range_sigma``
    at the last bearing time (0.5).

Operator numbers (position, range, course, speed and their sigmas) are given only when the
solution is observable *and* converged; otherwise they are NaN (``null`` in RESULT.json)
except the last bearing, which is measured directly, and a warning says why.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike
from numpy.typing import NDArray
from scipy.stats import chi2
from scipy.stats import norm

from seatrack.information import RankCheck
from seatrack.information import covariance_from_jacobian
from seatrack.tma.bounds import OPERATOR_NAMES
from seatrack.tma.bounds import operator_values
from seatrack.tma.bounds import position_crb
from seatrack.tma.config import TMAConfig
from seatrack.tma.legs import leg_time_matrix
from seatrack.tma.problem import Bearings
from seatrack.tma.support import SupportValue

FloatArray = NDArray[np.float64]

__all__ = ["Fit", "LastEstimate", "TMASolution", "finalise", "observer_deviation"]


@dataclass(frozen=True)
class LastEstimate:
    """Operator picture at the last bearing time (spec "Output in operator terms").

    Values are NaN when the solution is not observable or did not converge, except the
    bearing (always measured). Angles in rad ``[0, 2 pi)``, clockwise from North.
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
    covariance : (n, n) ``(J^T W J)^-1`` at the solution (same order as ``state``); all NaN
        when the Jacobian is rank-deficient.
    iterations : LM trials from the chosen start value to convergence: the trials spent on
        the start that was kept (automatic start search, leg-detection candidate) plus the
        final refinement on all bearings.
    iterations_total : LM trials over every start (and leg-detection candidate) tried.
    converged : the convergence tests were met.
    cost : weighted least-squares cost ``sum w r^2``.
    residuals : (N,) bearing residuals, rad.
    residual_rms : RMS of the bearing residuals, rad.
    observable : the verdict of the module docstring.
    condition_number, smallest_singular_value : of the whitened Jacobian with unit-norm
        columns (scale-invariant; the smallest is 0 when rank-deficient).
    observer_deviation : largest own-ship distance from its straight-line fit, m.
    last : :class:`LastEstimate` at the last bearing time.
    manoeuvres_detected : True if the leg start times were found from the data.
    warnings : human-readable warnings.
    tonals : tonal ids of the frequency measurements.
    base_frequency, sigma_base_frequency : (T,) Hz, base frequency ``f0`` of each tonal and
        its 1-sigma (0 for a given ``f0``; NaN when not determined).
    base_frequency_fixed : (T,) the base frequency was given, not estimated.
    support_residuals, frequency_residuals, bow_angle_residuals : residuals of the other
        measurement kinds (support unit, Hz, rad).
    nis : per measurement kind (``bearing``, ``support``, ``frequency``, ``atb``) the sum of
        the squared normalised residuals ``sum r^2 / sigma^2`` and the number of rows.
    determined : for ``x, y, range, bearing, course, speed`` at the last bearing time and
        ``f0:<tonal>`` of each estimated tonal: True when the data determine it (see
        :func:`determined_parameters`).
    leg_estimates : :class:`LastEstimate` at the last bearing of each leg.
    sound_speed : m/s, of the frequency model.
    """

    t0: float
    starts: FloatArray
    state: FloatArray
    covariance: FloatArray
    iterations: int
    iterations_total: int
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
    tonals: tuple[str, ...] = ()
    base_frequency: FloatArray = field(default_factory=lambda: np.zeros(0))
    sigma_base_frequency: FloatArray = field(default_factory=lambda: np.zeros(0))
    base_frequency_fixed: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, bool))
    support_residuals: FloatArray = field(default_factory=lambda: np.zeros(0))
    frequency_residuals: FloatArray = field(default_factory=lambda: np.zeros(0))
    bow_angle_residuals: FloatArray = field(default_factory=lambda: np.zeros(0))
    nis: dict[str, tuple[float, int]] = field(default_factory=dict)
    determined: dict[str, bool] = field(default_factory=dict)
    leg_estimates: tuple[LastEstimate, ...] = ()
    sound_speed: float = 1500.0

    @property
    def valid(self) -> bool:
        """Observable and converged: the operator numbers are given."""
        return self.observable and self.converged

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


@dataclass(frozen=True)
class Fit:
    """Outcome of the iteration for one problem, input of :func:`finalise`.

    ``r``, ``J``, ``w``: residuals, Jacobian and weights of the real (unpadded) rows at
    ``beta``: bearings first, then support values, frequencies, ATB. With frequencies ``J``
    has one more column per estimated base frequency (joint Jacobian,
    :meth:`~seatrack.tma.problem.Problem.augmented`) and ``f0`` holds every tonal's base
    frequency (Hz).
    """

    beta: FloatArray
    cost: float
    r: FloatArray
    J: FloatArray
    w: FloatArray
    iterations: int
    iterations_total: int
    converged: bool
    f0: FloatArray = field(default_factory=lambda: np.zeros(0))


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


def _verdict(
    dev: float, n_rows: int, n: int, n_support: int, chk: RankCheck, rel: float,
    converged: bool, cfg: TMAConfig,
) -> tuple[bool, list[str]]:  # fmt: skip
    """Observability (a)-(c) of the module docstring and the reasons, in order.

    ``n_support`` counts every measurement that is not a bearing (support values,
    frequencies, ATB); ``n`` the unknowns (state and estimated base frequencies)."""
    why: list[str] = []
    geometry_ok = dev > cfg.min_observer_deviation or n_support > 0
    if not geometry_ok:
        why.append(
            f"not observable: the own ship did not manoeuvre (largest deviation from a straight "
            f"track {dev:.2f} m) and no support values were given; range, course and speed "
            "are undetermined -- manoeuvre the own ship or add a range/speed/course support value"
        )
    if n_rows < n:
        why.append(f"not observable: {n_rows} measurements for {n} unknowns")
    elif geometry_ok and not chk.full_rank:
        why.append(
            f"not observable: singular geometry (rank {chk.rank} of {n}; smallest scaled "
            f"singular value {chk.smallest:.3g} <= {chk.tolerance:.3g} x largest)"
        )
    observable = geometry_ok and n_rows >= n and chk.full_rank
    if observable and not rel <= cfg.max_relative_range_sigma:
        why.append(
            f"not observable: range 1-sigma is {rel:.0%} of the range (limit "
            f"{cfg.max_relative_range_sigma:.0%}); the geometry does not fix the range yet"
        )
        observable = False
    if not converged:
        why.append(
            "the iteration did not converge within the iteration limit; no operator values "
            "are given"
        )
    return observable, why


def _residual_warning(fit: Fit, N: int, n_support: int, cfg: TMAConfig) -> list[str]:
    dof = N + n_support - fit.J.shape[1]
    if dof <= 0:
        return []
    q = _chi2_quantile(cfg.residual_test_probability, dof)
    if not fit.cost > q:
        return []
    rms = math.degrees(float(np.sqrt(np.mean(fit.r[:N] ** 2))))
    return [
        f"the residuals are larger than the measurement sigmas explain (cost {fit.cost:.1f} > "
        f"{q:.1f}, the {cfg.residual_test_probability:.1%} chi-square bound for {dof} degrees "
        f"of freedom; bearing residual RMS {rms:.2f} deg): sigma too small, outliers or an "
        "unmodelled target manoeuvre -- the 1-sigma values are optimistic"
    ]


def _last_estimate(
    vals: FloatArray, cov6: FloatArray, valid: bool, bearing_sigma: float, t: float, conf: float
) -> LastEstimate:
    sig = np.sqrt(np.maximum(np.diag(cov6), 0.0))
    if not valid:
        keep = np.zeros(6, bool)
        keep[3] = True  # the bearing is measured directly
        vals = np.where(keep, vals, np.nan)
        sig = np.where(keep, bearing_sigma, np.nan)
        cov6 = np.full((6, 6), np.nan)
        cov6[3, 3] = bearing_sigma**2
    v, e = [float(x) for x in vals], [float(x) for x in sig]
    return LastEstimate(
        time=t, x=v[0], y=v[1], range=v[2], bearing=v[3], course=v[4], speed=v[5],
        sigma_x=e[0], sigma_y=e[1], sigma_range=e[2], sigma_bearing=e[3], sigma_course=e[4],
        sigma_speed=e[5], covariance=cov6, confidence=conf,
    )  # fmt: skip


def determined_parameters(
    Jw: FloatArray, functionals: FloatArray, rtol: float, tol: float = 1e-6
) -> NDArray[np.bool_]:
    """Which linear functionals ``g @ theta`` of the parameters the data determine.

    ``g`` is determined when it is orthogonal to the null space of the whitened Jacobian
    ``Jw`` (columns scaled to unit norm, singular values at or below ``rtol`` times the
    largest taken as zero): ``|g_s . v| <= tol |g_s|`` for every null vector ``v``, with
    ``g_s`` the functional in scaled parameters. A full-rank Jacobian determines them all.
    """
    norms = np.sqrt(np.sum(Jw * Jw, axis=0))
    G = np.atleast_2d(functionals)
    zero = norms <= 0
    s = np.where(zero, 1.0, norms)
    Js = Jw / s
    _, sv, Vt = np.linalg.svd(Js, full_matrices=Js.shape[0] < Js.shape[1])
    sv = np.concatenate([sv, np.zeros(Vt.shape[0] - sv.size)])
    null = Vt[sv <= rtol * max(float(sv[0]), 1e-300)]
    Gs = G / s
    touches_zero = np.any(np.abs(G[:, zero]) > 0, axis=1)
    if not null.shape[0]:
        return np.asarray(~touches_zero)
    proj = np.abs(Gs @ null.T).max(axis=1)
    scale = np.sqrt(np.sum(Gs * Gs, axis=1))
    return np.asarray((proj <= tol * scale) & ~touches_zero)


def _nis(fit: Fit, sizes: dict[str, int]) -> dict[str, tuple[float, int]]:
    """Sum of squared normalised residuals and row count per measurement kind."""
    out, off = {}, 0
    for kind, m in sizes.items():
        if m:
            out[kind] = (float((fit.w[off : off + m] * fit.r[off : off + m] ** 2).sum()), m)
        off += m
    return out


def _leg_estimates(
    bearings: Bearings, starts: FloatArray, beta: FloatArray, P: FloatArray | None,
    valid: bool, conf: float, last: LastEstimate,
    at_last: tuple[FloatArray, FloatArray, FloatArray],
) -> tuple[LastEstimate, ...]:  # fmt: skip
    """Operator picture at the last bearing of every leg.

    ``at_last``: :func:`operator_values` and the covariance ``(6, 6)`` at the last bearing
    (the last leg's, computed once); ``last`` is the solution's picture there, which is
    the last leg's when valid (otherwise that one carries the measurement's bearing sigma,
    the leg's the covariance's)."""
    out = []
    n_b = len(bearings.t)
    for e in starts[1:]:  # the legs before the last end at the next start
        i = int(np.searchsorted(bearings.t, e, side="left")) - 1
        out.append(_leg_estimate(bearings, starts, beta, P, valid, conf, i, at_last))
    if valid:
        out.append(last)
    else:
        out.append(_leg_estimate(bearings, starts, beta, P, valid, conf, n_b - 1, at_last))
    return tuple(out)


def _leg_estimate(
    bearings: Bearings, starts: FloatArray, beta: FloatArray, P: FloatArray | None,
    valid: bool, conf: float, i: int, at_last: tuple[FloatArray, FloatArray, FloatArray],
) -> LastEstimate:  # fmt: skip
    """Operator picture at bearing ``i`` (see :func:`_leg_estimates`)."""
    t = float(bearings.t[i])
    if i == len(bearings.t) - 1:
        vals, _, cov6 = at_last
    else:
        vals, G = operator_values(beta, starts, t, bearings.observer[i])
        cov6 = G @ P @ G.T if P is not None else np.full((6, 6), np.nan)
    sb = float(np.sqrt(max(cov6[3, 3], 0.0))) if P is not None else math.nan
    return _last_estimate(vals, cov6, valid, sb, t, conf)


def finalise(
    bearings: Bearings,
    support: Sequence[SupportValue],
    starts: FloatArray,
    fit: Fit,
    cfg: TMAConfig,
    detected: bool = False,
) -> TMASolution:
    """Covariance, observability verdict, warnings and operator picture of one fit."""
    n = fit.beta.size
    na = fit.J.shape[1]  # state and estimated base frequencies
    N = len(bearings)
    M, F, A = len(support), bearings.n_frequencies, bearings.n_bow_angles
    Jw = np.sqrt(fit.w)[:, None] * fit.J
    P_full, chk = covariance_from_jacobian(Jw, cfg.rank_tolerance)
    t_last = float(bearings.t[-1])
    vals, G = operator_values(fit.beta, starts, t_last, bearings.observer[-1])
    if P_full is None:
        P = np.full((n, n), np.nan)
        cov6 = np.full((6, 6), np.nan)
        rel = math.inf
    else:
        P = P_full[:n, :n]
        cov6 = G @ P @ G.T
        rel = float(math.sqrt(max(cov6[2, 2], 0.0)) / vals[2]) if vals[2] > 0 else math.inf
    dev = observer_deviation(bearings.t, bearings.observer)
    extra = M + F + A
    observable, warnings = _verdict(dev, fit.r.size, na, extra, chk, rel, fit.converged, cfg)
    warnings += _residual_warning(fit, N, extra, cfg)
    bs = float(1.0 / np.sqrt(fit.w[N - 1]))  # measurement sigma of the last bearing
    valid = observable and fit.converged
    last = _last_estimate(vals, cov6, valid, bs, t_last, cfg.confidence)
    rb = fit.r[:N]
    tonals: tuple[str, ...] = ()
    f0 = sf0 = np.zeros(0)
    fixed = np.zeros(0, bool)
    names = list(OPERATOR_NAMES)
    if F:
        assert bearings.frequencies is not None
        fr = bearings.frequencies
        tonals = tuple(fr.tonals)
        fixed = np.array([k in fr.base_frequency for k in tonals])
        f0 = np.asarray(fit.f0, dtype=float)
        sf0 = np.zeros(len(tonals))
        est_cov = np.diag(P_full)[n:] if P_full is not None else np.full(na - n, np.nan)
        sf0[~fixed] = np.sqrt(np.maximum(est_cov, 0.0))
        names += [f"f0:{k}" for k in np.asarray(tonals)[~fixed]]
    if chk.full_rank and observable:  # every value is determined
        determined = dict.fromkeys(names, True)
    else:
        if chk.full_rank:
            det = np.ones(len(names), bool)
        else:  # the operator values' gradients, then one row per estimated base frequency
            funcs = np.concatenate(
                [np.concatenate([G, np.zeros((6, na - n))], axis=1), np.eye(na)[n:]]
            )
            det = determined_parameters(Jw, funcs, cfg.rank_tolerance)
        if not observable:  # bearings alone fix only the bearing; others follow the rank test
            geometry = dev > cfg.min_observer_deviation or extra > 0
            det = det & (np.arange(det.size) == 3) if not geometry or chk.full_rank else det
        determined = dict(zip(names, det.tolist(), strict=True))
    if F and not valid:  # a sigma only for a base frequency the data determine
        sf0[~fixed] = [
            np.sqrt(max(P_full[n + j, n + j], 0.0))
            if (P_full is not None and determined[names[6 + j]]) else np.nan
            for j in range(int((~fixed).sum()))
        ]  # fmt: skip
    sizes = {"bearing": N, "support": M, "frequency": F, "atb": A}
    return TMASolution(
        t0=float(bearings.t[0]), starts=np.asarray(starts, dtype=float),
        state=np.asarray(fit.beta, dtype=float), covariance=P, iterations=int(fit.iterations),
        iterations_total=int(fit.iterations_total), converged=bool(fit.converged),
        cost=float(fit.cost), residuals=np.asarray(rb, dtype=float),
        residual_rms=float(np.sqrt(np.mean(rb**2))), observable=bool(observable),
        condition_number=float(chk.condition), smallest_singular_value=float(chk.smallest),
        observer_deviation=dev, last=last, n_bearings=N, n_support=M,
        manoeuvres_detected=detected, warnings=tuple(warnings), tonals=tonals,
        base_frequency=f0, sigma_base_frequency=sf0, base_frequency_fixed=fixed,
        support_residuals=np.asarray(fit.r[N : N + M]),
        frequency_residuals=np.asarray(fit.r[N + M : N + M + F]),
        bow_angle_residuals=np.asarray(fit.r[N + M + F :]),
        nis=_nis(fit, sizes),
        determined=determined,
        leg_estimates=_leg_estimates(bearings, starts, fit.beta, None if P_full is None else P,
                                     valid, cfg.confidence, last, (vals, G, cov6)),
        sound_speed=cfg.sound_speed,
    )  # fmt: skip
