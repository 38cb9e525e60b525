"""Robust coordinated-turn tracker for AIS position reports of many vessels at once.

Per vessel, a coordinated-turn extended Kalman filter (state ``[x, y, vx, vy, w]``, x East,
y North in the vessel's local tangent plane, turn rate ``w`` clockwise positive,
:mod:`seatrack.models.motion`) runs over the vessel's reports in time order, followed by a
Rauch-Tung-Striebel (RTS) smoother over each track segment (Bar-Shalom, Li & Kirubarajan
2001: 5.4.2 gating, 8.6 smoothing, 11.7 CT model). Measurements: the position, then (when
both are reported) SOG and COG as a velocity measurement ``[|v|, atan2(vx, vy)]``
(:func:`sogcog_model`, COG innovation wrapped to ``(-pi, pi]``, own chi-square gate).

Measurement noise. The report covariance is estimated per vessel from the vessel's own
reports (:func:`position_noise`): ``R = sigma_pos^2 I + sigma_time^2 v v^T``, white position
noise plus the error of the logged time, which displaces a moving vessel's report along its
velocity ``v`` (the predicted one). On the real files the measured cross-track noise is
0.1-1 m, while the along-track error grows with speed (timestamp sigma ~0.5 s), so a fixed
isotropic sigma of several metres over-smooths slow and manoeuvring vessels.

Timestamp offsets. That along-track error is mostly not white: the logged time of a report is
off by whole seconds (interpolation residuals of the Danish files cluster at 0, +-0.5 and
+-1 s; ~20 % of the reports are one second off, ~2 % two) while the positions themselves are
precise. A refinement pass (:func:`_refine_pass`, ``refine``) estimates each report's offset
``d`` from the smoothed track (:func:`timestamp_offsets`, MAP with a prior estimated from the
file) and filters again with the offset in the measurement model, ``h(x) = [x - vx d,
y - vy d]`` (the report shows the position ``d`` seconds before its logged time; linear, the
state stays at the logged time), and the timestamp sigma re-estimated on the corrected
times. The same pass re-estimates the report noise without the outliers and chooses per
vessel between ``q_accel`` and a steadier ``q_accel_steady`` by the prediction
log-likelihood of the vessel's reports (steady ships gain from the stiffer model,
manoeuvring craft need the other).

Physical limits. After every update, and on the smoothed output, the state is projected
onto ``speed <= max_speed_kn`` and ``|w| <= min(max_turn_rate_dps, max_accel_mps2 /
speed)`` (:func:`_constrain`): without it a CT filter fed plausible reports can lock onto a
spurious fast spin.

Outliers. Three kinds (:data:`OUTLIER_KINDS`), each a report that is not used (the filter
predicts through it) and is flagged:

1. **implausible jump**: outside the chi-square gate (``NIS = y^T S^-1 y`` against the
   ``gate_probability`` quantile of chi-square with 2 dof) *and* physically implausible:
   the speed implied by the straight line from the last accepted report exceeds
   ``max_speed_kn``, or the acceleration implied by its distance from the prediction,
   ``2 (|y| - n_sigma sqrt(lambda_max(S))) / dt^2``, exceeds ``max_accel_mps2``.
   Intervals are lengthened by ``time_resolution_s`` (one-second timestamps can hide up
   to one second) and distances shortened by the noise allowance
   ``n_sigma sqrt(2) sigma_pos`` [reading], so only reports implausible under the most
   generous reading are flagged;
2. **stale position**: the exact position of the previous report repeated while the vessel
   moves (the reported SOG; without one, the vessel's last SOG within ``max_gap_s``; else
   the filter speed less ``n_sigma`` of its sigma: a glitch the filter followed must not
   make a vessel at rest look moving) far enough since
   the position was first reported to exceed the noise allowance -- the "frozen position"
   glitch of AIS feeds, whose catch-up report otherwise looks like a jump;
3. **implausible after gap**: after a gap longer than ``max_gap_s``, a report implying more
   than ``max_speed_kn`` from the last accepted one (e.g. two transmitters sharing an
   MMSI); it has no track estimate.

A report outside the gate that is plausible is a manoeuvre: the predicted covariance is
inflated by ``NIS / gate`` before the update (so the report sits on the gate), which lets
the track follow sharp turns and speed changes without a second model [reading]. The causal
decisions are then revisited with the future (``revisit_passes``): an outlier that is
plausible against its accepted neighbours on both sides is accepted, an accepted report
that is implausible against them is rejected (:func:`neighbour_plausibility`), and the
vessels concerned are filtered again.

Tracks are split (re-initialised) at intervals longer than ``max_gap_s`` and after
``reinit_after`` consecutive outliers (the track was lost, e.g. after a wrong first
report). A segment is initialised from one report: its position, and the velocity from
SOG/COG when both are given (else zero with a wide prior).

Scale: all vessels go through one compiled (Numba, ``nogil``) loop over reports sorted by
vessel and time; there is no Python work per report. The measurement updates are the
Joseph-form core of :mod:`seatrack.kalman` and the covariance prediction its compiled
``F P F^T + Q`` core; the CT propagation ``f(x)``, its Jacobian and ``Q`` are compiled
copies of :func:`seatrack.models.motion.ct_transition`,
:func:`~seatrack.models.motion.ct_jacobian` and :func:`~seatrack.models.motion.ct_noise`
(tested equal to them), and the RTS step is written out for 5x5 matrices (no BLAS calls).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2

from seatrack.geometry import KNOT_MPS, bearing, wrap_2pi
from seatrack.kalman import predict_core, update_core, wrap_angle

FloatArray = NDArray[np.float64]

__all__ = [
    "AisTrackerConfig",
    "TrackStates",
    "AisTracks",
    "track_vessels",
    "track_reports",
    "ct_step",
    "sogcog_model",
    "OUTLIER_KINDS",
    "neighbour_plausibility",
    "position_noise",
]

NX = 5  # [x, y, vx, vy, w]
_CHI2_1_MEDIAN = float(chi2.ppf(0.5, 1))  # 0.4549


@lru_cache(maxsize=64)
def _chi2_ppf(p: float, dof: int) -> float:
    """Chi-square quantile (cached: SciPy's costs ~0.3 ms a call)."""
    return float(chi2.ppf(p, dof))


@lru_cache(maxsize=64)
def _trim_scale(keep: float) -> float:
    """``E[X | X <= chi2_1(keep)]`` for ``X ~ chi2_1``: ``F_3(chi2_1(keep)) / keep``."""
    return float(chi2.cdf(chi2.ppf(keep, 1), 3) / keep) if keep < 1.0 else 1.0


#: fewest reports with an identifiable offset (speed x 1 s > 3 sigma_pos) for the prior
_MIN_OFFSET_REPORTS = 100
_LOG_2PI = math.log(2.0 * math.pi)  # 2-D Gaussian: -0.5 (d2 + log det S) - log(2 pi)


@dataclass(frozen=True)
class AisTrackerConfig:
    """Configuration of the AIS tracker (SI inside; knots/degrees only where named so).

    Parameters
    ----------
    sigma_pos_m : float
        1-sigma AIS position error per axis, m [reading: GNSS noise plus the 1e-4 deg
        quantisation of some feeds]. The generous value behind the noise allowance of the
        plausibility tests (outliers); the filter's measurement noise is this value only
        with ``estimate_noise=False`` (else it is the upper bound of the estimate).
    q_accel : float
        White-noise acceleration PSD of the CT model, m^2/s^3.
    q_turn : float
        Turn-rate random-walk PSD, rad^2/s^3.
    gate_probability : float
        Chi-square (2 dof) gate probability.
    max_speed_kn : float
        Largest plausible speed over ground, knots [reading].
    max_accel_mps2 : float
        Largest plausible acceleration (incl. centripetal), m/s^2 [reading].
    n_sigma : float
        Noise allowance (in sigmas) in the plausibility tests.
    time_resolution_s : float
        Timestamp resolution; implied rates use ``dt + time_resolution_s``.
    max_gap_s : float
        Longer intervals split the track.
    reinit_after : int
        Consecutive outliers after which the track is re-initialised at the last one.
    smooth : bool
        Run the RTS smoother (else output the forward filter).
    revisit_passes : int
        Passes revisiting the causal decisions with the two-sided neighbour test
        (:func:`neighbour_plausibility`, neighbours = the reports accepted so far): an
        outlier (kinds 1, 3) that is plausible on both sides is accepted and an accepted
        report that is implausible is rejected (kind 1); each report's decision is revised
        at most once. Each pass re-runs the filter on the vessels concerned; 0 = causal
        decisions only. Of adjacent accepted reports rejected together, only the one with the
        largest implausibility score (implied speed / ``max_speed_kn``, implied acceleration
        / ``max_accel_mps2``) is rejected in a pass.
    init_speed_std_mps : float
        Prior velocity sigma per axis when SOG/COG are not both known.
    init_sogcog_std_mps : float
        Prior velocity sigma per axis when the velocity comes from SOG/COG.
    init_turn_std_dps : float
        Prior turn-rate sigma, deg/s.
    use_sog_cog : bool
        Also update with the reported SOG and COG (velocity measurements, see
        :func:`sogcog_model`) after an accepted position, when both are known; only when
        the reported and the predicted speed
        exceed ``min_speed_kn`` (COG is noise, and the speed Jacobian singular, near rest).
        A SOG/COG pair outside the chi-square gate is not used (the position still is).
    use_sog_alone : bool
        Also use SOG when COG is missing (a 1-D speed update). Off by default: on the
        Danish files without COG it made the hold-out error worse (their SOG lags the
        positions during speed changes) [reading].
    sigma_sog_kn, sigma_cog_deg : float
        1-sigma of the reported SOG (kn) and COG (deg) [reading: 0.1 kn / 0.1 deg
        resolution plus GNSS velocity noise and the lag of its smoothing].
    min_speed_kn : float
        Speed below which SOG/COG are not used, kn.
    estimate_noise : bool
        Estimate each vessel's position measurement noise from its own reports
        (:func:`position_noise`): ``R = sigma_pos^2 I + sigma_time^2 v v^T`` (white position
        noise plus a timestamp error along the velocity). False: ``R = sigma_pos_m^2 I``.
    sigma_pos_min_m : float
        Floor of the estimated position sigma, m [reading: the 1e-6 deg rounding of the
        files is ~0.03 m; 0.1 m keeps R well conditioned].
    sigma_time_min_s, noise_max_time_s : float
        Floor and cap of the estimated timestamp sigma, s [reading: the floor is the
        rounding of 1-s timestamps, 1/sqrt(12) s; chosen over 0 on the every-5th hold-out
        withholding the 2nd of each 5 reports, not the 5th that the tests withhold].
    noise_max_dt_s : float
        Only residuals with both neighbour intervals at most this long (s) enter the
        estimate (longer chords see the vessel's manoeuvres, not the noise).
    noise_min_reports : int
        Fewest residuals for an estimate (else ``sigma_pos_m`` and the timestamp floor).
    noise_trim : float
        Fraction of the smallest cross-track residuals kept for the position sigma.
    noise_min_speed_mps : float
        Chord speed (m/s) from which a residual informs the timestamp sigma.
    max_time_offset_s : int
        Largest whole-second timestamp error estimated per report
        (:func:`timestamp_offsets`, in the refinement pass); 0 = no offsets.
    sigma_time_fine_s : float
        Timestamp sigma (s) left once whole-second offsets are modelled: the scoring noise of
        :func:`timestamp_offsets` and the floor of the re-estimated sigma [reading: the
        interpolation residuals of the Danish files cluster within +-0.1 s of whole
        seconds; 0.15 rather than 0.07 or 0.1 on the hold-outs withholding the 1st to 4th of
        each five reports -- not the 5th that the tests withhold -- where it lost the 95th
        percentile to interpolation least often (2 of 20 file-folds against 7)].
    q_accel_steady : float
        Second, steadier acceleration PSD (m^2/s^3) of the refinement pass: each vessel
        keeps the track (``q_accel`` or this) whose reports have the larger prediction
        log-likelihood; 0 = ``q_accel`` only. [reading: ``q_accel`` 0.1 and this 0.003
        were chosen on the every-5th hold-out withholding the 2nd of each 5 reports (0.1
        and 0.2 both beat 0.05 there), not the 5th that the tests withhold.]
    offset_passes : int
        Re-estimations of the offsets from the steady track.
    refine : bool
        Run the refinement pass (:func:`_refine_pass`: timestamp offsets, noise without the
        outliers, steady or manoeuvring process noise per vessel); False is 1.35-1.8
        times faster (benchmarks/ais.py, 1 M synthetic reports, two runs).
    steady_nis_ratio : float
        The ``q_accel`` track is tried only for vessels whose mean NIS on the steady track
        exceeds this ratio times its 2 dof [reading: on the real files every vessel whose
        ``q_accel`` track had the larger likelihood had a steady mean NIS of 3.4 or more].
    min_offset_share : float
        Smallest estimated share of reports with a non-zero offset for offsets to be used
        at all (below it, the winners are noise: :func:`timestamp_offsets`).
    max_turn_rate_dps : float
        Largest turn-rate magnitude of the state, deg/s (also at most ``max_accel_mps2 /
        speed``); the state is projected onto it, and the speed onto ``max_speed_kn``,
        after every update [reading: the largest AIS rate of turn, 708 deg/min].
    """

    sigma_pos_m: float = 5.0
    q_accel: float = 0.1
    q_turn: float = 2e-6
    gate_probability: float = 0.9999
    max_speed_kn: float = 50.0
    max_accel_mps2: float = 2.0
    n_sigma: float = 3.0
    time_resolution_s: float = 1.0
    max_gap_s: float = 600.0
    reinit_after: int = 3
    smooth: bool = True
    revisit_passes: int = 4
    init_speed_std_mps: float = 8.0
    init_sogcog_std_mps: float = 1.0
    init_turn_std_dps: float = 1.0
    use_sog_cog: bool = True
    use_sog_alone: bool = False
    sigma_sog_kn: float = 0.3
    sigma_cog_deg: float = 3.0
    min_speed_kn: float = 2.0
    estimate_noise: bool = True
    sigma_pos_min_m: float = 0.1
    noise_max_dt_s: float = 60.0
    noise_min_reports: int = 10
    noise_trim: float = 0.9
    noise_min_speed_mps: float = 1.0
    noise_max_time_s: float = 5.0
    sigma_time_min_s: float = 0.2887
    max_time_offset_s: int = 2
    sigma_time_fine_s: float = 0.15
    q_accel_steady: float = 0.003
    offset_passes: int = 1
    refine: bool = True
    steady_nis_ratio: float = 1.5
    min_offset_share: float = 0.05
    max_turn_rate_dps: float = 12.0

    def __post_init__(self) -> None:
        for name in ("sigma_pos_m", "q_accel", "q_turn", "max_speed_kn", "max_accel_mps2"):
            if not getattr(self, name) > 0:
                raise ValueError(f"AisTrackerConfig.{name} must be > 0, got {getattr(self, name)}")
        if not 0.0 < self.gate_probability < 1.0:
            raise ValueError(f"gate_probability must be in (0, 1), got {self.gate_probability}")
        if self.reinit_after < 1:
            raise ValueError(f"reinit_after must be >= 1, got {self.reinit_after}")
        if not 0.0 < self.sigma_pos_min_m <= self.sigma_pos_m:
            raise ValueError(
                f"need 0 < sigma_pos_min_m <= sigma_pos_m, got {self.sigma_pos_min_m}, "
                f"{self.sigma_pos_m}"
            )
        if not 0.0 <= self.sigma_time_min_s <= self.noise_max_time_s:
            raise ValueError(
                f"need 0 <= sigma_time_min_s <= noise_max_time_s, got {self.sigma_time_min_s}, "
                f"{self.noise_max_time_s}"
            )
        if not 0.0 < self.noise_trim <= 1.0:
            raise ValueError(f"noise_trim must be in (0, 1], got {self.noise_trim}")
        for name in ("sigma_time_fine_s", "steady_nis_ratio", "max_turn_rate_dps"):
            if not getattr(self, name) > 0:
                raise ValueError(f"AisTrackerConfig.{name} must be > 0, got {getattr(self, name)}")
        for name in ("max_time_offset_s", "offset_passes", "q_accel_steady"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"AisTrackerConfig.{name} must be >= 0, got {getattr(self, name)}")
        if not 0.0 <= self.min_offset_share < 1.0:
            raise ValueError(f"min_offset_share must be in [0, 1), got {self.min_offset_share}")

    @property
    def gate(self) -> float:
        """Chi-square (2 dof) threshold of the gate."""
        return _chi2_ppf(self.gate_probability, 2)


# ---------------------------------------------------------------------------
# Compiled coordinated-turn step (mirror of seatrack.models.motion, tested equal)
# ---------------------------------------------------------------------------
@njit(cache=True)
def _ct_f_F(x, dt, fx, F):  # pragma: no cover - compiled
    """CT propagation ``fx = f(x, dt)`` and Jacobian ``F`` (see ``motion.ct_transition``)."""
    vx, vy, w = x[2], x[3], x[4]
    wt = w * dt
    s, c = math.sin(wt), math.cos(wt)
    if abs(wt) < 1e-3:
        t2, t3, t4, t5 = dt * dt, dt**3, dt**4, dt**5
        a = dt - w * w * t3 / 6 + w**4 * t5 / 120
        b = w * t2 / 2 - w**3 * t4 / 24
        da = -w * t3 / 3 + w**3 * t5 / 30
        db = t2 / 2 - w * w * t4 / 8 + w**4 * dt**6 / 144
    else:
        a = s / w
        b = (1 - c) / w
        da = dt * c / w - s / (w * w)
        db = dt * s / w - (1 - c) / (w * w)
    fx[0] = x[0] + a * vx + b * vy
    fx[1] = x[1] - b * vx + a * vy
    fx[2] = c * vx + s * vy
    fx[3] = -s * vx + c * vy
    fx[4] = w
    for i in range(NX):
        for j in range(NX):
            F[i, j] = 1.0 if i == j else 0.0
    F[0, 2] = a
    F[0, 3] = b
    F[0, 4] = da * vx + db * vy
    F[1, 2] = -b
    F[1, 3] = a
    F[1, 4] = -db * vx + da * vy
    F[2, 2] = c
    F[2, 3] = s
    F[2, 4] = dt * (-s * vx + c * vy)
    F[3, 2] = -s
    F[3, 3] = c
    F[3, 4] = dt * (-c * vx - s * vy)


@njit(cache=True)
def _ct_Q(dt, q, q_w, Q):  # pragma: no cover - compiled
    """CT process noise (see ``motion.ct_noise``): CV white-noise acceleration + w walk."""
    for i in range(NX):
        for j in range(NX):
            Q[i, j] = 0.0
    Q[0, 0] = Q[1, 1] = q * dt**3 / 3
    Q[0, 2] = Q[2, 0] = Q[1, 3] = Q[3, 1] = q * dt**2 / 2
    Q[2, 2] = Q[3, 3] = q * dt
    Q[4, 4] = q_w * dt


@njit(cache=True)
def _update2(x, P, y, H, R, xo, Po, K):  # pragma: no cover - compiled
    """Joseph-form update of the 5-state with a 2-D measurement (``H`` 2x5, innovation
    ``y``, noise ``R``): the same update as :func:`seatrack.kalman.update_core` (tested
    equal), ordered for this size -- ``(I - K H) P = P - K (H P)`` and
    ``(I - K H) P (I - K H)^T = A - (A H^T) K^T`` with ``A = (I - K H) P`` -- about 300
    multiply-adds instead of 480. Returns the NIS (inf if ``S`` is not positive definite,
    the state and covariance then unchanged). The general core given the same ordering
    was measured no faster (0.26 s per 100k-report pass against 0.18 s here, and no change
    for the 4-state filters): the gain comes from the sizes being known when compiling."""
    n = NX
    hp = np.empty((2, n))  # H P
    for r in range(2):
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += H[r, k] * P[k, j]
            hp[r, j] = acc
    s00 = R[0, 0]
    s01 = 0.5 * (R[0, 1] + R[1, 0])
    s11 = R[1, 1]
    for k in range(n):
        s00 += hp[0, k] * H[0, k]
        s01 += 0.5 * (hp[0, k] * H[1, k] + hp[1, k] * H[0, k])
        s11 += hp[1, k] * H[1, k]
    det = s00 * s11 - s01 * s01
    if not (s00 > 0.0 and det > 0.0):
        for j in range(n):
            xo[j] = x[j]
            for jj in range(n):
                Po[j, jj] = P[j, jj]
        return np.inf
    i00, i01, i11 = s11 / det, -s01 / det, s00 / det
    for j in range(n):  # K = P H^T S^-1 = (H P)^T S^-1
        K[j, 0] = hp[0, j] * i00 + hp[1, j] * i01
        K[j, 1] = hp[0, j] * i01 + hp[1, j] * i11
        xo[j] = x[j] + K[j, 0] * y[0] + K[j, 1] * y[1]
    nis = y[0] * (i00 * y[0] + i01 * y[1]) + y[1] * (i01 * y[0] + i11 * y[1])
    ap = np.empty((n, n))  # (I - K H) P
    for i in range(n):
        for j in range(n):
            ap[i, j] = P[i, j] - K[i, 0] * hp[0, j] - K[i, 1] * hp[1, j]
    for i in range(n):
        a0 = 0.0  # ((I - K H) P H^T)[i]
        a1 = 0.0
        for k in range(n):
            a0 += ap[i, k] * H[0, k]
            a1 += ap[i, k] * H[1, k]
        kr0 = K[i, 0] * R[0, 0] + K[i, 1] * R[1, 0]  # (K R)[i]
        kr1 = K[i, 0] * R[0, 1] + K[i, 1] * R[1, 1]
        for j in range(i, n):
            v = ap[i, j] - (a0 - kr0) * K[j, 0] - (a1 - kr1) * K[j, 1]
            Po[i, j] = v
            Po[j, i] = v
    return nis


@njit(cache=True)
def _constrain(x, vmax, amax, w_max):  # pragma: no cover - compiled
    """Project an updated state onto the physically possible set: speed at most ``vmax``
    and turn rate at most ``min(w_max, amax / speed)`` in magnitude (a vessel cannot turn
    faster than its rudder allows nor with a centripetal acceleration above ``amax``).
    Without it a coordinated-turn EKF fed plausible reports can lock onto a spurious fast
    spin (seen on the real Norwegian file: 34 deg/s at 200 m/s) and never recover."""
    spd = math.sqrt(x[2] * x[2] + x[3] * x[3])
    if spd > vmax:
        x[2] *= vmax / spd
        x[3] *= vmax / spd
        spd = vmax
    lim = w_max
    if spd * lim > amax:
        lim = amax / spd
    if x[4] > lim:
        x[4] = lim
    elif x[4] < -lim:
        x[4] = -lim


@njit(cache=True)
def _constrain_rows(X, vmax, amax, w_max):  # pragma: no cover - compiled
    """:func:`_constrain` on every row of ``X`` with a state (smoothed output)."""
    for i in range(X.shape[0]):
        if X[i, 0] == X[i, 0]:
            _constrain(X[i], vmax, amax, w_max)


@njit(cache=True)
def _sogcog(x, h, H):  # pragma: no cover - compiled
    """Speed and course of the state's velocity and their Jacobian (rows: SOG, COG)."""
    vx, vy = x[2], x[3]
    s2 = vx * vx + vy * vy
    s = math.sqrt(s2)
    h[0] = s
    h[1] = math.atan2(vx, vy)
    for j in range(NX):
        H[0, j] = 0.0
        H[1, j] = 0.0
    if s > 0.0:
        H[0, 2] = vx / s
        H[0, 3] = vy / s
        H[1, 2] = vy / s2
        H[1, 3] = -vx / s2


def sogcog_model(x: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """SOG/COG measurement model ``h(x) = [|v|, atan2(vx, vy)]`` (m/s, rad clockwise from
    North) and its analytic Jacobian ``(2, 5)`` -- the compiled function the tracker uses."""
    xx = np.ascontiguousarray(x, dtype=np.float64)
    h, H = np.empty(2), np.empty((2, NX))
    _sogcog(xx, h, H)
    return h, H


def ct_step(x: ArrayLike, dt: float, q: float, q_turn: float) -> tuple[FloatArray, ...]:
    """Compiled CT ``(f(x), F, Q)`` for one state; exposed to test it against the models."""
    xx = np.asarray(x, dtype=np.float64)
    fx, F, Q = np.empty(NX), np.empty((NX, NX)), np.empty((NX, NX))
    _ct_f_F(xx, float(dt), fx, F)
    _ct_Q(float(dt), q, q_turn, Q)
    return fx, F, Q


@njit(cache=True)
def _derived(x, P, out_std):  # pragma: no cover - compiled
    """1-sigma of x, y, speed, course and turn rate from the state covariance (linearised)."""
    out_std[0] = math.sqrt(max(P[0, 0], 0.0))
    out_std[1] = math.sqrt(max(P[1, 1], 0.0))
    vx, vy = x[2], x[3]
    s2 = vx * vx + vy * vy
    if s2 > 1e-12:
        s = math.sqrt(s2)
        ux, uy = vx / s, vy / s
        out_std[2] = math.sqrt(
            max(ux * ux * P[2, 2] + 2 * ux * uy * P[2, 3] + uy * uy * P[3, 3], 0)
        )
        # course = atan2(vx, vy): d/dvx = vy/s^2, d/dvy = -vx/s^2
        gx, gy = vy / s2, -vx / s2
        out_std[3] = math.sqrt(
            max(gx * gx * P[2, 2] + 2 * gx * gy * P[2, 3] + gy * gy * P[3, 3], 0)
        )
    else:
        out_std[2] = math.sqrt(max(0.5 * (P[2, 2] + P[3, 3]), 0.0))
        out_std[3] = math.pi  # course undefined at rest
    out_std[4] = math.sqrt(max(P[4, 4], 0.0))


@njit(cache=True)
def _rts_step(xf, Pf, F, xp, Pp, xs_n, Ps_n, xs, Ps, A, L, X, D):  # pragma: no cover
    """One RTS step (BLK 8.6): ``C = Pf F^T Pp^-1``, ``xs = xf + C (xs_n - xp)``,
    ``Ps = Pf + C (Ps_n - Pp) C^T``; ``C^T`` solved from ``Pp C^T = F Pf`` by Cholesky.
    Small fixed-size loops (no BLAS calls: 5x5 matrices)."""
    n = NX
    for i in range(n):  # A = F Pf
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += F[i, k] * Pf[k, j]
            A[i, j] = acc
    for j in range(n):  # Pp = L L^T
        d = Pp[j, j]
        for k in range(j):
            d -= L[j, k] * L[j, k]
        d = math.sqrt(max(d, 1e-300))
        L[j, j] = d
        for i in range(j + 1, n):
            acc = Pp[i, j]
            for k in range(j):
                acc -= L[i, k] * L[j, k]
            L[i, j] = acc / d
    for c in range(n):  # X = Pp^-1 A  (X = C^T)
        for i in range(n):
            acc = A[i, c]
            for k in range(i):
                acc -= L[i, k] * X[k, c]
            X[i, c] = acc / L[i, i]
        for i in range(n - 1, -1, -1):
            acc = X[i, c]
            for k in range(i + 1, n):
                acc -= L[k, i] * X[k, c]
            X[i, c] = acc / L[i, i]
    for i in range(n):  # xs = xf + C (xs_n - xp),  C[i, k] = X[k, i]
        acc = xf[i]
        for k in range(n):
            acc += X[k, i] * (xs_n[k] - xp[k])
        xs[i] = acc
    for i in range(n):  # D = C (Ps_n - Pp)
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += X[k, i] * (Ps_n[k, j] - Pp[k, j])
            D[i, j] = acc
    for i in range(n):  # Ps = Pf + D C^T (symmetric)
        for j in range(i, n):
            acc = 0.0
            for k in range(n):
                acc += D[i, k] * X[k, j]
            v = 0.5 * (Pf[i, j] + Pf[j, i]) + acc
            Ps[i, j] = v
            Ps[j, i] = v


@njit(cache=True)
def _smooth_segment(k0, k1, xp, Pp, Fk, xf, Pf, xs, Ps, has, smooth):  # pragma: no cover
    """RTS smoother over the scratch rows ``k0..k1`` (inclusive) that have a state; the
    next row of row ``k`` is the next one with a state (BLK 8.6)."""
    kn = k1
    while kn >= k0 and not has[kn]:
        kn -= 1
    if kn < k0:
        return
    xs[kn] = xf[kn]
    Ps[kn] = Pf[kn]
    A = np.empty((NX, NX))
    L = np.zeros((NX, NX))
    X = np.empty((NX, NX))
    D = np.empty((NX, NX))
    for k in range(kn - 1, k0 - 1, -1):
        if not has[k]:
            continue
        if smooth:
            _rts_step(
                xf[k], Pf[k], Fk[kn], xp[kn], Pp[kn], xs[kn], Ps[kn], xs[k], Ps[k], A, L, X, D
            )
        else:
            xs[k] = xf[k]
            Ps[k] = Pf[k]
        kn = k


#: outlier kinds (``TrackStates.outlier_kind``); 0 = not an outlier
OUTLIER_KINDS = {1: "implausible jump", 2: "stale position", 3: "implausible after gap"}


@njit(cache=True)
def _close(
    k0, k1, a, xp, Pp, Fk, xf, Pf, xs, Ps, has, smooth, out_x, out_std, std
):  # pragma: no cover
    """Smooth scratch rows ``k0..k1`` (inclusive) of the vessel starting at row ``a``; write
    the state, the 1-sigma of :func:`_derived` and (last column) the x-y covariance."""
    if k1 < k0:
        return
    _smooth_segment(k0, k1, xp, Pp, Fk, xf, Pf, xs, Ps, has, smooth)
    for kk in range(k0, k1 + 1):
        if has[kk]:
            r = a + kk
            for j in range(NX):
                out_x[r, j] = xs[kk, j]
            _derived(xs[kk], Ps[kk], std)
            for j in range(NX):
                out_std[r, j] = std[j]
            out_std[r, NX] = Ps[kk, 0, 1]


@njit(cache=True)
def _init_at(
    k, z, v0, known, v_std, v_std_known, sig, toff, w_std, xp, Pp, Fk, xf, Pf
):  # pragma: no cover
    """Initialise a segment in scratch row ``k`` from one report: position ``z`` (moved on
    by ``v0 toff`` for a report stamped ``toff`` seconds late), velocity ``v0`` (from
    SOG/COG) if ``known`` else zero, with the matching prior sigmas; position covariance =
    the report's measurement noise ``sig = (sigma_pos, sigma_time)`` (m, s), see
    :func:`position_noise`."""
    vx = v0[0] if known else 0.0
    vy = v0[1] if known else 0.0
    sv = v_std_known if known else v_std
    for j in range(NX):
        xf[k, j] = 0.0
        for jj in range(NX):
            Pf[k, j, jj] = 0.0
            Fk[k, j, jj] = 1.0 if j == jj else 0.0
    xf[k, 0] = z[0] + vx * toff
    xf[k, 1] = z[1] + vy * toff
    xf[k, 2] = vx
    xf[k, 3] = vy
    # measurement covariance of the report (timestamp-jitter term along the velocity)
    st2 = sig[1] * sig[1]
    Pf[k, 0, 0] = sig[0] * sig[0] + st2 * vx * vx
    Pf[k, 1, 1] = sig[0] * sig[0] + st2 * vy * vy
    Pf[k, 0, 1] = Pf[k, 1, 0] = st2 * vx * vy
    Pf[k, 2, 2] = Pf[k, 3, 3] = sv * sv
    Pf[k, 4, 4] = w_std * w_std
    xp[k] = xf[k]
    Pp[k] = Pf[k]


@njit(cache=True, nogil=True)
def _track_kernel(
    starts,
    t,
    z,
    use,
    force,
    v0,
    v0_known,
    sog,
    cog,
    sig,
    toff,
    use_vel,
    use_sog_alone,
    sigma_sog,
    sigma_cog,
    vmin,
    sigma_pos,
    q,
    q_w,
    gate,
    vmax,
    amax,
    w_max,
    nsig,
    tres,
    max_gap,
    reinit_after,
    init_v_std,
    init_v_std_known,
    init_w_std,
    smooth,
    out_x,
    out_std,
    out_flag,
    out_seg,
    out_nis,
    out_ll,
):  # pragma: no cover - compiled
    n_vessels = starts.shape[0] - 1
    L = 1
    for v in range(n_vessels):
        L = max(L, starts[v + 1] - starts[v])
    xp = np.zeros((L, NX))
    Pp = np.zeros((L, NX, NX))
    Fk = np.zeros((L, NX, NX))
    xf = np.zeros((L, NX))
    Pf = np.zeros((L, NX, NX))
    xs = np.zeros((L, NX))
    Ps = np.zeros((L, NX, NX))
    has = np.zeros(L, dtype=np.bool_)
    fx = np.empty(NX)
    F = np.empty((NX, NX))
    Q = np.empty((NX, NX))
    H = np.zeros((2, NX))  # position rows; columns 2, 3 carry the offset
    H[0, 0] = 1.0
    H[1, 1] = 1.0
    R = np.zeros((2, 2))
    R[0, 0] = R[1, 1] = sigma_pos * sigma_pos
    y = np.empty(2)
    Ko = np.empty((NX, 2))
    xo = np.empty(NX)
    Po = np.empty((NX, NX))
    Pi = np.empty((NX, NX))
    std = np.empty(NX)
    h2 = np.empty(2)
    H2 = np.zeros((2, NX))
    R2 = np.zeros((2, 2))
    R2[0, 0] = sigma_sog * sigma_sog
    R2[1, 1] = sigma_cog * sigma_cog
    y2 = np.empty(2)
    K2 = np.empty((NX, 2))
    H1 = np.zeros((1, NX))
    R1 = np.zeros((1, 1))
    R1[0, 0] = sigma_sog * sigma_sog
    y1 = np.empty(1)
    S1 = np.empty((1, 1))
    K1 = np.empty((NX, 1))
    xv = np.empty(NX)
    Pv = np.empty((NX, NX))
    noise_dist = nsig * math.sqrt(2.0) * sigma_pos  # noise allowance on a distance
    seg_id = 0
    for v in range(n_vessels):
        a, b = starts[v], starts[v + 1]
        init = False
        k_first = 0
        t_state = 0.0
        last_t = 0.0  # last accepted report
        last_x = 0.0
        last_y = 0.0
        prev_t = np.nan  # previous used report (accepted or not)
        prev_x = 0.0
        prev_y = 0.0
        run_t = 0.0
        n_out = 0
        sog_t = -np.inf  # last reported SOG of the vessel and its time
        sog_last = 0.0
        for i in range(a, b):
            k = i - a
            if use[i] and sog[i] == sog[i]:
                sog_t = t[i]
                sog_last = sog[i]
            out_seg[i] = -1
            out_nis[i] = np.nan
            out_ll[i] = np.nan
            has[k] = False
            # ---- stale position: exact repeat of the previous report while moving
            # (run_t: when the repeated position was first reported)
            stale = False
            if use[i] and prev_t == prev_t and z[i, 0] == prev_x and z[i, 1] == prev_y:
                if init and t[i] > run_t:
                    kp = k - 1
                    while kp > 0 and not has[kp]:
                        kp -= 1
                    spd = 0.0
                    if sog[i] == sog[i]:  # the reported SOG (GNSS), when there is one
                        spd = sog[i]
                    elif t[i] - sog_t <= max_gap:  # else the vessel's last reported SOG
                        spd = sog_last
                    elif has[kp]:  # else the filter speed, if significantly above zero
                        sv = math.sqrt(0.5 * (Pf[kp, 2, 2] + Pf[kp, 3, 3]))
                        spd = math.sqrt(xf[kp, 2] ** 2 + xf[kp, 3] ** 2) - nsig * sv
                    stale = spd * (t[i] - run_t) > noise_dist
            elif use[i]:
                run_t = t[i]
            if use[i]:
                prev_t = t[i]
                prev_x = z[i, 0]
                prev_y = z[i, 1]
            # ---- a long gap: implausible jump across it, or a new segment
            if init and t[i] - t_state > max_gap and use[i]:
                dxl = z[i, 0] - last_x
                dyl = z[i, 1] - last_y
                v_impl = (math.sqrt(dxl * dxl + dyl * dyl) - noise_dist) / (t[i] - last_t + tres)
                if v_impl > vmax and n_out + 1 < reinit_after and force[i] != 1:
                    n_out += 1
                    out_flag[i] = 3
                    # the row gets no estimate (the track is not propagated over the gap)
                    continue
                _close(
                    k_first, k - 1, a, xp, Pp, Fk, xf, Pf, xs, Ps, has, smooth, out_x, out_std, std
                )
                init = False
            elif init and t[i] - t_state > max_gap:
                # withheld row after a long gap: end the segment, no estimate for the row
                _close(
                    k_first, k - 1, a, xp, Pp, Fk, xf, Pf, xs, Ps, has, smooth, out_x, out_std, std
                )
                init = False
                continue
            if not init:
                if not use[i]:
                    continue  # withheld before a track exists: no estimate
                seg_id += 1
                init = True
                k_first = k
                n_out = 0
                _init_at(
                    k,
                    z[i],
                    v0[i],
                    v0_known[i],
                    init_v_std,
                    init_v_std_known,
                    sig[i],
                    toff[i],
                    init_w_std,
                    xp,
                    Pp,
                    Fk,
                    xf,
                    Pf,
                )
                t_state = t[i]
                last_t = t[i]
                last_x = z[i, 0]
                last_y = z[i, 1]
                has[k] = True
                out_seg[i] = seg_id
                continue
            # ---- predict to t[i] from the previous scratch row (always the one before)
            dt = t[i] - t_state
            kp = k - 1
            while not has[kp]:
                kp -= 1
            _ct_f_F(xf[kp], dt, fx, F)
            _ct_Q(dt, q, q_w, Q)
            predict_core(xf[kp], Pf[kp], F, Q, xo, Po)
            xp[k] = fx
            Pp[k] = Po
            Fk[k] = F
            xf[k] = fx
            Pf[k] = Po
            has[k] = True
            out_seg[i] = seg_id
            t_state = t[i]
            if not use[i]:
                continue
            if force[i] == 2:
                out_flag[i] = 1  # rejected by the two-sided test of the first pass
                continue
            if stale and force[i] != 1:
                out_flag[i] = 2  # not counted towards re-initialisation
                continue
            # ---- gate (measurement noise of this report)
            # R = sigma_pos^2 I + sigma_time^2 v v^T: white position noise plus the
            # timestamp error tau, z = p(t + tau) ~ p(t) + v tau (v: predicted velocity)
            st2 = sig[i, 1] * sig[i, 1]
            R[0, 0] = sig[i, 0] * sig[i, 0] + st2 * fx[2] * fx[2]
            R[1, 1] = sig[i, 0] * sig[i, 0] + st2 * fx[3] * fx[3]
            R[0, 1] = R[1, 0] = st2 * fx[2] * fx[3]
            # a report stamped toff seconds late shows the position at t - toff:
            # h(x) = [x - vx toff, y - vy toff] (H linear; toff = 0 unless estimated)
            dl = toff[i]
            y[0] = z[i, 0] - (fx[0] - dl * fx[2])
            y[1] = z[i, 1] - (fx[1] - dl * fx[3])
            s00 = Po[0, 0] - 2.0 * dl * Po[0, 2] + dl * dl * Po[2, 2] + R[0, 0]
            s01 = Po[0, 1] - dl * (Po[0, 3] + Po[1, 2]) + dl * dl * Po[2, 3] + R[0, 1]
            s11 = Po[1, 1] - 2.0 * dl * Po[1, 3] + dl * dl * Po[3, 3] + R[1, 1]
            det = s00 * s11 - s01 * s01
            d2 = (s11 * y[0] * y[0] - 2 * s01 * y[0] * y[1] + s00 * y[1] * y[1]) / det
            out_nis[i] = d2
            out_ll[i] = -0.5 * (d2 + math.log(det)) - _LOG_2PI
            if d2 > gate:
                # plausibility: implied speed from the last accepted report and implied
                # acceleration from the distance to the prediction
                dxl = z[i, 0] - last_x
                dyl = z[i, 1] - last_y
                v_impl = (math.sqrt(dxl * dxl + dyl * dyl) - noise_dist) / (t[i] - last_t + tres)
                tr = 0.5 * (s00 + s11)
                lam = tr + math.sqrt(max(tr * tr - det, 0.0))
                dev = math.sqrt(y[0] * y[0] + y[1] * y[1]) - nsig * math.sqrt(lam)
                dte = t[i] - last_t + tres
                a_impl = 2.0 * dev / (dte * dte)
                if (v_impl > vmax or a_impl > amax) and force[i] != 1:
                    n_out += 1
                    if n_out >= reinit_after:
                        # track lost: close the segment before i, restart at i
                        _close(
                            k_first,
                            k - 1,
                            a,
                            xp,
                            Pp,
                            Fk,
                            xf,
                            Pf,
                            xs,
                            Ps,
                            has,
                            smooth,
                            out_x,
                            out_std,
                            std,
                        )
                        seg_id += 1
                        k_first = k
                        n_out = 0
                        _init_at(
                            k,
                            z[i],
                            v0[i],
                            v0_known[i],
                            init_v_std,
                            init_v_std_known,
                            sig[i],
                            toff[i],
                            init_w_std,
                            xp,
                            Pp,
                            Fk,
                            xf,
                            Pf,
                        )
                        last_t = t[i]
                        last_x = z[i, 0]
                        last_y = z[i, 1]
                        out_seg[i] = seg_id
                        continue
                    out_flag[i] = 1
                    continue
                # plausible manoeuvre: inflate the prediction so the report sits on the gate
                f = d2 / gate
                for j in range(NX):
                    for jj in range(NX):
                        Pi[j, jj] = Po[j, jj] * f
                Pp[k] = Pi
            else:
                for j in range(NX):
                    for jj in range(NX):
                        Pi[j, jj] = Po[j, jj]
            H[0, 2] = H[1, 3] = -dl
            _update2(fx, Pi, y, H, R, xo, Po, Ko)
            if use_vel and sog[i] == sog[i] and sog[i] > vmin:
                # velocity measurements: SOG (and COG), sequential update after the position
                _sogcog(xo, h2, H2)
                if h2[0] > vmin:
                    nis2 = np.inf
                    if cog[i] == cog[i]:
                        y2[0] = sog[i] - h2[0]
                        y2[1] = wrap_angle(cog[i] - h2[1])
                        nis2 = _update2(xo, Po, y2, H2, R2, xv, Pv, K2)
                    elif use_sog_alone:
                        y1[0] = sog[i] - h2[0]
                        for j in range(NX):
                            H1[0, j] = H2[0, j]
                        nis2, _ = update_core(xo, Po, y1, H1, R1, xv, Pv, S1, K1)
                    if nis2 <= gate:
                        for j in range(NX):
                            xo[j] = xv[j]
                            for jj in range(NX):
                                Po[j, jj] = Pv[j, jj]
            _constrain(xo, vmax, amax, w_max)
            n_out = 0
            xf[k] = xo
            Pf[k] = Po
            last_t = t[i]
            last_x = z[i, 0]
            last_y = z[i, 1]
        if init:
            _close(
                k_first, b - a - 1, a, xp, Pp, Fk, xf, Pf, xs, Ps, has, smooth, out_x, out_std, std
            )


# ---------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class TrackStates:
    """Per-row estimates in each vessel's local plane (same row order as the inputs).

    Attributes
    ----------
    state : ndarray (N, 5)
        Smoothed (or filtered) ``[x, y, vx, vy, w]`` (m, m/s, rad/s); NaN without estimate.
    std : ndarray (N, 5)
        1-sigma of x, y (m), speed (m/s), course (rad), turn rate (rad/s).
    outlier : ndarray of bool (N,)
        Report judged an outlier and not used.
    outlier_kind : ndarray of int8 (N,)
        0 = none, else a key of :data:`OUTLIER_KINDS` (1 outside the gate and implausible,
        2 stale position, 3 implausible jump across a long gap).
    segment : ndarray of int (N,)
        Track segment id (splits at gaps / re-initialisations); -1 without estimate.
    nis : ndarray (N,)
        NIS of the report against the prediction (NaN for first reports / unused rows).
    time_offset : ndarray (N,)
        Estimated timestamp error of the report (s, whole seconds, logged minus true time;
        :func:`timestamp_offsets`); 0 where not estimated.
    """

    state: FloatArray
    std: FloatArray
    outlier: NDArray[np.bool_]
    outlier_kind: NDArray[np.int8]
    segment: NDArray[np.int64]
    nis: FloatArray
    time_offset: FloatArray


@dataclass(frozen=True)
class _Rows:
    """The kernel's inputs, rows sorted by (vessel, time): vessel id, time (s), position
    (m), use, SOG/COG velocity (m/s, zero where unknown) and whether known, SOG (m/s),
    COG (rad), report noise ``(sigma_pos, sigma_time)``, decisions ``force``, offsets (s)."""

    vessel: NDArray[np.int64]
    t: FloatArray
    z: FloatArray
    use: NDArray[np.bool_]
    v0: FloatArray
    known: NDArray[np.bool_]
    sog: FloatArray
    cog: FloatArray
    sig: FloatArray
    force: NDArray[np.int8]
    toff: FloatArray

    def take(self, rows: NDArray[np.bool_], **new: NDArray) -> _Rows:
        """The rows ``rows`` (whole vessels), with fields replaced by ``new`` (full length)."""
        fields = {k: new.get(k, getattr(self, k))[rows] for k in self.__dataclass_fields__}
        return _Rows(**fields)


def track_vessels(
    vessel: ArrayLike,
    t: ArrayLike,
    xy: ArrayLike,
    config: AisTrackerConfig | None = None,
    use: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    sog: ArrayLike | None = None,
    cog: ArrayLike | None = None,
) -> TrackStates:
    """Track many vessels at once in local planes (the compiled core of the AIS tracker).

    Parameters
    ----------
    vessel : array of int (N,)
        Vessel id of each report (any order; rows are grouped and time-sorted inside,
        stably, so equal times keep their input order).
    t : array (N,)
        Times, s.
    xy : array (N, 2)
        Positions East, North (m) in the vessel's local plane.
    config : AisTrackerConfig
    use : array of bool (N,), optional
        False = do not use the report (hold-out): the row still gets the track estimate.
    v0 : array (N, 2), optional
        Velocity (East, North; m/s) from SOG/COG for initialisation; NaN where unknown.
    sog : array (N,), optional
        Reported speed over ground (m/s; NaN unknown): stale-position test and, with
        ``use_sog_cog``, a velocity measurement.
    cog : array (N,), optional
        Reported course over ground (rad, clockwise from the plane's North; NaN unknown).

    Returns
    -------
    TrackStates
        In the input row order.
    """
    cfg = config or AisTrackerConfig()
    vid = np.asarray(vessel, dtype=np.int64)
    tt = np.asarray(t, dtype=np.float64)
    z = np.asarray(xy, dtype=np.float64)
    n = tt.size
    if z.shape != (n, 2) or vid.shape != (n,):
        raise ValueError(f"vessel (N,), t (N,) and xy (N, 2) needed; got {vid.shape}, {z.shape}")
    if not (np.isfinite(tt).all() and np.isfinite(z).all()):
        raise ValueError("times and positions must be finite (reject bad rows first)")
    u = np.ones(n, dtype=bool) if use is None else np.asarray(use, dtype=bool)
    sg = np.full(n, np.nan) if sog is None else np.asarray(sog, dtype=np.float64)
    cg = np.full(n, np.nan) if cog is None else np.asarray(cog, dtype=np.float64)
    vv = np.full((n, 2), np.nan) if v0 is None else np.asarray(v0, dtype=np.float64)
    order = np.lexsort((tt, vid))
    ts, zs, us, vs_ = tt[order], z[order], u[order], vid[order]
    vo = np.ascontiguousarray(vv[order])
    known: NDArray[np.bool_] = np.asarray(np.isfinite(vo).all(axis=1))
    vo[~known] = 0.0
    sgs = sg[order]
    cgs = cg[order]
    force = np.zeros(n, dtype=np.int8)
    if cfg.estimate_noise:
        sig = position_noise(vs_, ts, zs, us, cfg)
    else:
        sig = np.zeros((n, 2))
        sig[:, 0] = cfg.sigma_pos_m
    toff = np.zeros(n)
    rows = _Rows(vs_, ts, zs, us, vo, known, sgs, cgs, sig, force, toff)
    out: tuple[NDArray, ...] = _run_kernel(rows, cfg)
    vmax = cfg.max_speed_kn * KNOT_MPS
    for _ in range(cfg.revisit_passes):
        # revisit the causal decisions with the future (two-sided neighbour test):
        # outliers plausible on both sides are accepted and accepted reports that are
        # implausible are rejected
        flag = out[2]
        accepted = us & (flag == 0)
        v_prev, v_next, a_chord = neighbour_plausibility(vs_, ts, zs, accepted, cfg)
        bad = (v_prev > vmax) | (v_next > vmax) | (a_chord > cfg.max_accel_mps2)
        free = force == 0  # a decision is revised at most once, so the loop ends
        acc = ((flag == 1) | (flag == 3)) & ~bad & free
        rej = accepted & bad & (out[3] >= 0) & free
        # of adjacent accepted reports that are implausible together (a glitch and the
        # report after it), reject only the worst one in this pass: the other is judged
        # again against its new neighbours in the next pass
        score = np.fmax(np.fmax(v_prev / vmax, v_next / vmax), a_chord / cfg.max_accel_mps2)
        ip, inn, has_p, has_n = _neighbours(vs_, accepted)
        beaten_prev = has_p & rej[ip] & (score[ip] >= score)
        beaten_next = has_n & rej[inn] & (score[inn] > score)
        rej &= ~(beaten_prev | beaten_next)
        force[acc] = 1
        force[rej] = 2
        new = acc | rej
        if not new.any():
            break
        redo = np.isin(vs_, np.unique(vs_[new]))
        _put(out, redo, _run_kernel(rows.take(redo), cfg))
    if cfg.refine and n:
        out, toff = _refine_pass(rows, out, cfg)
    # segment ids 1, 2, ... in order of (vessel, time)
    seg = out[3]
    has = seg >= 0
    ids, first, which = np.unique(seg[has], return_index=True, return_inverse=True)
    rank = np.empty(ids.size, dtype=np.int64)
    rank[np.argsort(first)] = np.arange(1, ids.size + 1)
    seg[has] = rank[which]
    inv = np.empty_like(order)
    inv[order] = np.arange(n)
    out_x, out_std, out_flag, out_seg, out_nis, _ = (a[inv] for a in out)
    return TrackStates(out_x, out_std[:, :NX], out_flag > 0, out_flag, out_seg, out_nis, toff[inv])


def _put(out: tuple[NDArray, ...], rows: NDArray[np.bool_], new: tuple[NDArray, ...]) -> None:
    """Write kernel outputs ``new`` of the rows ``rows`` into ``out``; their segment ids are
    moved past those of ``out`` so that ids stay unique."""
    seg = new[3]
    seg[:] = np.where(seg >= 0, seg + int(out[3].max(initial=0)) + 1, -1)
    for a_out, a_new in zip(out, new, strict=True):
        a_out[rows] = a_new


def _refine_pass(
    rows: _Rows, out: tuple[NDArray, ...], cfg: AisTrackerConfig
) -> tuple[tuple[NDArray, ...], FloatArray]:
    """Refinement pass: whole-second timestamp offsets, report noise without the outliers,
    and a per-vessel choice of process noise (rows sorted by (vessel, time); ``out`` = the
    kernel outputs of the passes before, whose outlier decisions are kept).

    1. Offsets of the accepted reports from the track ``out`` (:func:`timestamp_offsets`,
       smoothed residuals): a first estimate that seeds step 3.
    2. Report noise re-estimated from the accepted reports only (:func:`position_noise`;
       the first estimate also saw the outliers); for vessels with offsets on the corrected
       times, with the timestamp-sigma floor ``sigma_time_fine_s``.
    3. All vessels filtered with the steady acceleration PSD ``q_accel_steady`` and the
       offsets in the measurement model; the offsets estimated again from that track
       (leave-one-out residuals; the steady track follows single glitches less) -- this
       estimate decides whether the file shows offsets at all -- up to ``offset_passes``
       times, re-filtering the vessels whose offsets changed (noise re-estimated).
    4. All vessels filtered with ``q_accel`` and the same offsets; per vessel, the track
       (``q_accel`` or ``q_accel_steady``) whose reports have the larger prediction
       log-likelihood is kept (a two-model choice per vessel: steady ships vs manoeuvring
       craft).
    """
    vs, ts, zs, us, sig = rows.vessel, rows.t, rows.z, rows.use, rows.sig
    usable = us & (out[2] == 0) & (out[3] >= 0)
    # first estimate from the (manoeuvring, coarse-noise) track: the smoothed residual
    off = timestamp_offsets(
        zs, out[0], _pos_cov(out[1]), sig, np.zeros(ts.size), usable, cfg, leave_one_out=False
    )
    uv, inv_v = np.unique(vs, return_inverse=True)

    def per_vessel(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """Rows of the vessels with any row in ``mask``."""
        return (np.bincount(inv_v, mask, uv.size) > 0)[inv_v]

    def noise(off: FloatArray) -> FloatArray:
        """Report noise again, from the accepted reports only (the first estimate also
        saw the outliers) and, for vessels with offsets, on the corrected times."""
        moved = per_vessel(off != 0.0)
        if cfg.estimate_noise:
            fine = replace(cfg, sigma_time_min_s=cfg.sigma_time_fine_s)
            sig_f = position_noise(vs, ts - off, zs, usable, fine)
            sig_f[:, 1] = np.where(moved, np.minimum(sig_f[:, 1], sig[:, 1]), sig[:, 1])
        else:
            sig_f = sig.copy()
            sig_f[moved, 1] = cfg.sigma_time_fine_s
        return sig_f

    sig_f = noise(off)
    force_f = rows.force.copy()
    force_f[usable] = 1  # the outlier decisions of the passes before are kept
    force_f[us & (out[2] == 1)] = 2

    def run(sub: NDArray[np.bool_], c: AisTrackerConfig) -> tuple[NDArray, ...]:
        return _run_kernel(rows.take(sub, sig=sig_f, force=force_f, toff=off), c)

    steady = replace(cfg, q_accel=cfg.q_accel_steady or cfg.q_accel)
    alt = run(np.ones(ts.size, dtype=bool), steady)
    for _ in range(cfg.offset_passes):
        # offsets again from the steady track (it follows single glitches less; this
        # estimate, not the first, decides whether the file shows offsets at all)
        new = timestamp_offsets(zs, alt[0], _pos_cov(alt[1]), sig_f, off, usable, cfg)
        again = per_vessel(new != off)
        if not again.any():
            break
        off = new
        sig_f = noise(off)
        _put(alt, again, run(again, steady))
    # vessels the steady model fits badly (mean NIS above steady_nis_ratio x its 2 dof)
    # are filtered with q_accel too; per vessel the track whose reports have the larger
    # prediction log-likelihood is kept
    fin = np.isfinite(alt[4])
    n_fin = np.maximum(np.bincount(inv_v[fin], None, uv.size), 1)
    mean_nis = np.bincount(inv_v[fin], alt[4][fin], uv.size) / n_fin
    cand = (mean_nis > 2.0 * cfg.steady_nis_ratio)[inv_v]
    if cfg.q_accel_steady > 0 and cand.any():
        # the q_accel track: the passes before for vessels without offsets (same model
        # but for the noise estimate), else filtered again with the offsets
        hi = tuple(a.copy() for a in out)
        moved = per_vessel(off != 0.0)
        if (cand & moved).any():
            _put(hi, cand & moved, run(cand & moved, cfg))
        fin = cand & np.isfinite(hi[5]) & np.isfinite(alt[5])
        ll = np.bincount(inv_v[fin], hi[5][fin], uv.size)
        ll_alt = np.bincount(inv_v[fin], alt[5][fin], uv.size)
        take = cand & (ll > ll_alt)[inv_v]
        _put(alt, take, tuple(a[take] for a in hi))
    return alt, off


def _pos_cov(std: FloatArray) -> FloatArray:
    """Position covariance ``(N, 2, 2)`` from the kernel's std output (sigma x, sigma y in
    the first two columns, the x-y covariance in the last)."""
    c = np.empty((std.shape[0], 2, 2))
    c[:, 0, 0] = std[:, 0] ** 2
    c[:, 1, 1] = std[:, 1] ** 2
    c[:, 0, 1] = c[:, 1, 0] = std[:, NX]
    return c


@njit(cache=True, error_model="numpy")
def _offset_scores(r0, v, d_old, A, sp, st, st_fine, cand, loo, q):  # pragma: no cover
    """``q[i, k] = r_d^T C^-1 r_d`` of :func:`timestamp_offsets` for every row ``i`` and
    candidate offset ``cand[k]`` (2x2 algebra written out; NaN for a degenerate row)."""
    for i in range(r0.shape[0]):
        vx, vy = v[i, 0], v[i, 1]
        s2 = sp[i] * sp[i]
        ex = r0[i, 0]
        ey = r0[i, 1]
        c00 = s2 + st_fine * st_fine * vx * vx
        c01 = st_fine * st_fine * vx * vy
        c11 = s2 + st_fine * st_fine * vy * vy
        if loo:
            # R of the run, its inverse; X = I - A R^-1; B = X^-1; e = B r; M = B A
            t2 = st[i] * st[i]
            r00 = s2 + t2 * vx * vx
            r01 = t2 * vx * vy
            r11 = s2 + t2 * vy * vy
            dr = r00 * r11 - r01 * r01
            i00, i01, i11 = r11 / dr, -r01 / dr, r00 / dr
            a00, a01, a10, a11 = A[i, 0, 0], A[i, 0, 1], A[i, 1, 0], A[i, 1, 1]
            x00 = 1.0 - (a00 * i00 + a01 * i01)
            x01 = -(a00 * i01 + a01 * i11)
            x10 = -(a10 * i00 + a11 * i01)
            x11 = 1.0 - (a10 * i01 + a11 * i11)
            dx = x00 * x11 - x01 * x10
            b00, b01, b10, b11 = x11 / dx, -x01 / dx, -x10 / dx, x00 / dx
            rx = ex + vx * d_old[i]
            ry = ey + vy * d_old[i]
            ex = b00 * rx + b01 * ry - vx * d_old[i]
            ey = b10 * rx + b11 * ry - vy * d_old[i]
            m00 = b00 * a00 + b01 * a10
            m01 = 0.5 * ((b00 * a01 + b01 * a11) + (b10 * a00 + b11 * a10))
            m11 = b10 * a01 + b11 * a11
            c00 += m00
            c01 += m01
            c11 += m11
        dc = c00 * c11 - c01 * c01
        j00, j01, j11 = c11 / dc, -c01 / dc, c00 / dc
        # (e + v d)^T C^-1 (e + v d) = a + 2 b d + c d^2
        qa = j00 * ex * ex + 2.0 * j01 * ex * ey + j11 * ey * ey
        qb = j00 * ex * vx + j01 * (ex * vy + ey * vx) + j11 * ey * vy
        qc = j00 * vx * vx + 2.0 * j01 * vx * vy + j11 * vy * vy
        for k in range(cand.shape[0]):
            d = cand[k]
            q[i, k] = qa + 2.0 * qb * d + qc * d * d


def timestamp_offsets(
    xy: FloatArray,
    state: FloatArray,
    pos_cov: FloatArray,
    sig: FloatArray,
    used_offset: FloatArray,
    usable: NDArray[np.bool_],
    config: AisTrackerConfig,
    leave_one_out: bool = True,
) -> FloatArray:
    """Most probable whole-second timestamp error of each report, given a smoothed track.

    The logged time of an AIS report is often off by whole seconds (on the Danish files
    ~20 % of the reports by one second and ~2 % by two, against precise positions): a
    report stamped ``d`` seconds late shows the position at ``t - d``, ``p(t) - v d``.

    Each candidate ``d`` in ``-max_time_offset_s .. max_time_offset_s`` scores

    ``0.5 r_d^T C^-1 r_d - log pi_d``,  ``r_d = e + v (d - used_offset)``,
    ``C = M + sigma_pos^2 I + sigma_time_fine_s^2 v v^T``

    where ``e`` is the report's residual (under the offset ``used_offset`` of the run that
    made the track) and ``M`` its prediction covariance. With ``leave_one_out`` (default)
    these are against the track of all *other* reports -- the smoothed track has used the
    report, which pulls it towards a glitch. With ``A`` the smoothed position covariance,
    ``R`` the report's noise covariance in that run (``sig``, the velocity ``v``) and ``r``
    the smoothed residual, Gaussian conditioning (``A = M (M + R)^-1 R``) gives

    ``e = B r``,  ``M = B A``,  ``B = (I - A R^-1)^-1``

    (the velocity uncertainty over the offset is neglected). Without it, ``e = r`` and
    ``M = 0``: the smoothed residual, shrunk towards the track, scored as if the track
    were exact -- the refinement pass uses this only for its first estimate, from the
    coarse first track, whose large ``M`` would hide every offset.

    and the smallest score wins (MAP). The prior ``pi`` is estimated from the reports
    themselves (all vessels together): starting from ``pi_0 = 0.6``, it is re-estimated
    from the counts of the winning offsets (plus one each) over the reports on which the
    offset is identifiable (``|v| * 1 s > 3 sigma_pos``), three times. Slow vessels keep
    ``d = 0`` through the prior. If the estimated share of non-zero offsets is below
    ``min_offset_share`` the data show no whole-second offsets (noise alone makes a few
    winners) and all offsets are 0; so they are with fewer than 100 identifiable reports.

    Parameters
    ----------
    xy : (N, 2) reported positions (m); state : (N, >= 4) smoothed states at the logged
    times (m, m/s; NaN = none); pos_cov : (N, 2, 2) their position covariance (m^2);
    sig : (N, 2) report noise ``(sigma_pos m, sigma_time s)`` of that run
    (:func:`position_noise`); used_offset : (N,) offsets (s) of that run;
    usable : (N,) bool, reports to score (used by that run); leave_one_out : bool.

    Returns
    -------
    ndarray (N,)
        Offsets (s, whole numbers; 0 for reports not scored).
    """
    k_max = int(config.max_time_offset_s)
    out = np.zeros(xy.shape[0])
    ok = usable & np.isfinite(state[:, :4]).all(axis=1) & np.isfinite(pos_cov).all(axis=(1, 2))
    if k_max <= 0 or not ok.any():
        return out
    cand = np.arange(-k_max, k_max + 1, dtype=np.float64)
    v = state[ok, 2:4]
    sp = sig[ok, 0]
    d_old = used_offset[ok]
    r0 = xy[ok] - state[ok, :2]  # residual of d = 0: r_d = r0 + v d
    q = np.empty((v.shape[0], cand.size))
    _offset_scores(
        r0, v, d_old, pos_cov[ok], sp, sig[ok, 1], config.sigma_time_fine_s, cand, leave_one_out, q
    )
    q = np.where(np.isfinite(q), q, np.where(cand == 0, 0.0, np.inf))  # degenerate: d = 0
    speed2 = (v**2).sum(axis=1)
    sp2 = sp**2
    prior = np.where(cand == 0, 0.6, 0.4 / (cand.size - 1))
    ident = speed2 > 9.0 * sp2
    if np.count_nonzero(ident) < _MIN_OFFSET_REPORTS:
        return out  # too few reports on which an offset shows to estimate its prior
    best = np.zeros(q.shape[0], dtype=np.int64)
    for _ in range(3):
        best = np.argmin(0.5 * q - np.log(prior), axis=1)
        count = np.bincount(best[ident], minlength=cand.size) + 1.0
        prior = count / count.sum()
    if 1.0 - prior[k_max] < config.min_offset_share:
        return out  # too few offsets to tell from noise: the data show none
    out[ok] = cand[best]
    return out


def _run_kernel(
    rows: _Rows, cfg: AisTrackerConfig
) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]:
    """Run the compiled tracker over rows sorted by (vessel, time); returns the state, std,
    outlier kind, segment, NIS and the prediction log-likelihood of each row."""
    n = rows.t.size
    vs = rows.vessel
    starts = np.flatnonzero(np.r_[True, vs[1:] != vs[:-1], True]).astype(np.int64)
    if n == 0:
        starts = np.zeros(1, dtype=np.int64)
    out_x = np.full((n, NX), np.nan)
    out_std = np.full((n, NX + 1), np.nan)  # + the x-y covariance (last column)
    out_flag = np.zeros(n, dtype=np.int8)
    out_seg = np.full(n, -1, dtype=np.int64)
    out_nis = np.full(n, np.nan)
    out_ll = np.full(n, np.nan)
    c = np.ascontiguousarray
    _track_kernel(
        starts,
        c(rows.t),
        c(rows.z),
        c(rows.use),
        c(rows.force),
        c(rows.v0),
        c(rows.known),
        c(rows.sog),
        c(rows.cog),
        c(rows.sig),
        c(rows.toff),
        cfg.use_sog_cog,
        cfg.use_sog_alone,
        cfg.sigma_sog_kn * KNOT_MPS,
        math.radians(cfg.sigma_cog_deg),
        cfg.min_speed_kn * KNOT_MPS,
        cfg.sigma_pos_m,
        cfg.q_accel,
        cfg.q_turn,
        cfg.gate,
        cfg.max_speed_kn * KNOT_MPS,
        cfg.max_accel_mps2,
        math.radians(cfg.max_turn_rate_dps),
        cfg.n_sigma,
        cfg.time_resolution_s,
        cfg.max_gap_s,
        cfg.reinit_after,
        cfg.init_speed_std_mps,
        cfg.init_sogcog_std_mps,
        math.radians(cfg.init_turn_std_dps),
        cfg.smooth,
        out_x,
        out_std,
        out_flag,
        out_seg,
        out_nis,
        out_ll,
    )
    # the smoother can step outside the physical limits the filter keeps: project again
    _constrain_rows(
        out_x, cfg.max_speed_kn * KNOT_MPS, cfg.max_accel_mps2, math.radians(cfg.max_turn_rate_dps)
    )
    return out_x, out_std, out_flag, out_seg, out_nis, out_ll


def _neighbours(
    vessel: NDArray[np.int64], accepted: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.bool_], NDArray[np.bool_]]:
    """Nearest *other* accepted row of the same vessel before / after every row (rows sorted
    by (vessel, time)): indices ``prev``, ``next`` (0 where none) and their masks."""
    n = vessel.size
    pos = np.arange(n)
    acc_idx = np.where(accepted, pos, -1)
    # previous accepted strictly before: shift the running max by one
    prev = np.maximum.accumulate(np.r_[-1, acc_idx[:-1]]) if n else acc_idx
    nxt_src = np.where(accepted, pos, n)
    nxt = np.minimum.accumulate(np.r_[nxt_src[1:], n][::-1])[::-1] if n else nxt_src
    has_p = prev >= 0
    has_p[has_p] &= vessel[prev[has_p]] == vessel[has_p]
    has_n = nxt < n
    has_n[has_n] &= vessel[nxt[has_n]] == vessel[has_n]
    return np.where(has_p, prev, 0), np.where(has_n, nxt, 0), has_p, has_n


def position_noise(
    vessel: NDArray[np.int64],
    t: FloatArray,
    xy: FloatArray,
    use: NDArray[np.bool_],
    config: AisTrackerConfig,
) -> FloatArray:
    """Per-vessel measurement noise of the reported positions, estimated from the vessel's own
    reports: ``(sigma_pos, sigma_time)`` per row (m, s).

    Model: ``z = p(t + tau) + e ~ p(t) + v tau + e`` with white position noise ``e``
    (``sigma_pos`` per axis) and a timestamp error ``tau`` (``sigma_time``: the one-second
    resolution and the reception latency of the logged time), i.e. the report covariance
    ``R = sigma_pos^2 I + sigma_time^2 v v^T`` used by the tracker.

    Estimate: rows sorted by (vessel, time); for every used report ``i`` with used
    neighbours ``p``, ``n`` of the same vessel (both intervals positive and at most
    ``noise_max_dt_s``), the chord residual ``r = z_i - ((1 - w) z_p + w z_n)``,
    ``w = (t_i - t_p) / (t_n - t_p)``, is split into its components across and along the
    chord direction; the chord speed is ``s = |z_n - z_p| / (t_n - t_p)``. On a locally
    straight, uniform track each component has variance ``c sigma^2`` with
    ``c = 1 + w^2 + (1 - w)^2`` (white errors of the three reports), where ``sigma^2`` is
    ``sigma_pos^2`` across and ``sigma_pos^2 + sigma_time^2 s^2`` along. Robust scales
    per vessel:

    * ``sigma_pos^2``: trimmed mean of ``x = r_cross^2 / c`` over all rows (at rest the
      chord direction is arbitrary: East when the chord is zero), keeping the smallest
      fraction ``noise_trim`` and dividing by ``E[chi2_1 | below its noise_trim
      quantile]``; clipped to ``[sigma_pos_min_m, sigma_pos_m]``. (A trimmed mean rather
      than the median: on grid-rounded feeds most residuals of a slow vessel are exactly
      zero and the median would be zero while the grid steps are not.)
    * ``sigma_time^2``: ``median(r_along^2 / (c s^2)) / median(chi2_1)`` over rows with
      ``s >= noise_min_speed_mps``, less ``sigma_pos^2 median(1 / s^2)``, clipped to
      ``[sigma_time_min_s, noise_max_time_s]``. The median ignores up to half the
      residuals (timestamps off by whole seconds, glitches, manoeuvres).

    Vessels with fewer than ``noise_min_reports`` residuals (moving residuals for
    ``sigma_time``) get ``sigma_pos_m`` and ``sigma_time_min_s``. Withheld reports
    (``use`` False) are not used. Measured on the real files (North Sea, chord residuals
    at 1-3 s spacing): cross-track 0.1-0.6 m, along-track growing with speed
    (``sigma_time`` ~0.4-0.6 s), the along-track errors being mostly whole-second
    timestamp offsets of single reports.
    """
    n = t.size
    tau_floor = config.sigma_time_min_s
    out = np.empty((n, 2))
    out[:, 0] = config.sigma_pos_m
    out[:, 1] = tau_floor
    if n == 0:
        return out
    ip, inn, has_p, has_n = _neighbours(vessel, use)
    dtp = t - t[ip]
    dtn = t[inn] - t
    lim = config.noise_max_dt_s
    ok = use & has_p & has_n & (dtp > 0) & (dtn > 0) & (dtp <= lim) & (dtn <= lim)
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return out
    span = dtp[idx] + dtn[idx]
    w = dtp[idx] / span
    c = 1.0 + w**2 + (1.0 - w) ** 2
    chord = xy[inn[idx]] - xy[ip[idx]]
    r = xy[idx] - (xy[ip[idx]] + w[:, None] * chord)
    length = np.hypot(chord[:, 0], chord[:, 1])
    ux = np.where(length > 0, chord[:, 0] / np.where(length > 0, length, 1.0), 1.0)
    uy = np.where(length > 0, chord[:, 1] / np.where(length > 0, length, 1.0), 0.0)
    r_along = r[:, 0] * ux + r[:, 1] * uy
    r_cross = -r[:, 0] * uy + r[:, 1] * ux
    speed = length / span
    vid = vessel[idx]
    uv, inv = np.unique(vid, return_inverse=True)
    s_pos2 = _group_trimmed_mean(inv, uv.size, r_cross**2 / c, config.noise_trim)
    n_all = np.bincount(inv, minlength=uv.size)
    s_pos2 = np.where(n_all >= config.noise_min_reports, s_pos2, config.sigma_pos_m**2)
    s_pos = np.clip(np.sqrt(s_pos2), config.sigma_pos_min_m, config.sigma_pos_m)
    mv = speed >= config.noise_min_speed_mps
    sp2 = np.where(mv, speed, 1.0) ** 2
    g = np.where(mv, inv, uv.size)  # parked rows go to an extra group
    tau2 = _group_median(g, uv.size + 1, r_along**2 / (c * sp2))[:-1] / _CHI2_1_MEDIAN
    tau2 -= s_pos**2 * _group_median(g, uv.size + 1, 1.0 / sp2)[:-1]
    n_mv = np.bincount(g, minlength=uv.size + 1)[:-1]
    tau2 = np.where(n_mv >= config.noise_min_reports, tau2, 0.0)
    s_tau = np.clip(np.sqrt(np.maximum(tau2, 0.0)), tau_floor, config.noise_max_time_s)
    vi = np.minimum(np.searchsorted(uv, vessel), uv.size - 1)
    known = uv[vi] == vessel
    out[known, 0] = s_pos[vi[known]]
    out[known, 1] = s_tau[vi[known]]
    return out


def _group_trimmed_mean(
    group: NDArray[np.int64], n_groups: int, x: FloatArray, keep: float
) -> FloatArray:
    """Per-group variance estimate from chi-square(1)-distributed ``x = r^2 / var``: the mean
    of the smallest fraction ``keep`` of each group's values, divided by its expectation
    ``E[X | X <= chi2_1(keep)] = F_3(chi2_1(keep)) / keep`` (``x f_1(x) = f_3(x)``)."""
    order = np.lexsort((x, group))
    xs, gs = x[order], group[order]
    count = np.bincount(gs, minlength=n_groups)
    first = np.r_[0, np.cumsum(count)[:-1]]
    n_keep = np.maximum(np.ceil(keep * count).astype(np.int64), 1)
    rank = np.arange(xs.size) - first[gs]
    kept = rank < n_keep[gs]
    tot = np.bincount(gs[kept], weights=xs[kept], minlength=n_groups)
    scale = _trim_scale(keep)
    out = np.full(n_groups, np.nan)
    has = count > 0
    out[has] = tot[has] / n_keep[has] / scale
    return out


def _group_median(group: NDArray[np.int64], n_groups: int, x: FloatArray) -> FloatArray:
    """Median of ``x`` per group ``0..n_groups-1`` (NaN for empty groups), vectorised."""
    order = np.lexsort((x, group))
    xs, gs = x[order], group[order]
    count = np.bincount(gs, minlength=n_groups)
    first = np.r_[0, np.cumsum(count)[:-1]]
    out = np.full(n_groups, np.nan)
    has = count > 0
    lo = first[has] + (count[has] - 1) // 2
    hi = first[has] + count[has] // 2
    out[has] = 0.5 * (xs[lo] + xs[hi])
    return out


def neighbour_plausibility(
    vessel: NDArray[np.int64],
    t: FloatArray,
    xy: FloatArray,
    accepted: NDArray[np.bool_],
    config: AisTrackerConfig,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Two-sided physical plausibility of each report against its accepted neighbours.

    Rows must be sorted by (vessel, time). For every row, with ``p``/``n`` the nearest
    *other* accepted report of the same vessel before/after it (NaN results where none):

    * ``v_prev = (|z - z_p| - d0) / (t - t_p + tau)``, ``v_next`` likewise (m/s);
    * ``a_chord = 2 (e - d0) / ((t - t_p + tau)(t_n - t + tau))`` (m/s^2), where ``e`` is
      the distance from ``z`` to the straight line between ``z_p`` and ``z_n`` at time
      ``t``: the smallest constant acceleration that takes a vessel from the chord out to
      the report and back;

    with the noise allowance ``d0 = n_sigma sqrt(2) sigma_pos`` and the timestamp
    resolution ``tau`` (so that only reports implausible under the most generous reading
    of the timestamps and noise score high).
    """
    ip, inn, has_p, has_n = _neighbours(vessel, accepted)
    d0 = config.n_sigma * math.sqrt(2.0) * config.sigma_pos_m
    tau = config.time_resolution_s
    dtp = t - t[ip] + tau
    dtn = t[inn] - t + tau
    dtp = np.where(has_p, dtp, 1.0)
    dtn = np.where(has_n, dtn, 1.0)
    v_prev = np.where(has_p, (np.hypot(*(xy - xy[ip]).T) - d0) / dtp, np.nan)
    v_next = np.where(has_n, (np.hypot(*(xy[inn] - xy).T) - d0) / dtn, np.nan)
    span = t[inn] - t[ip]
    w = np.where(span > 0, (t - t[ip]) / np.where(span > 0, span, 1.0), 0.5)
    chord = xy[ip] + w[:, None] * (xy[inn] - xy[ip])
    e = np.hypot(*(xy - chord).T)
    a_chord = np.where(has_p & has_n, 2.0 * (e - d0) / (dtp * dtn), np.nan)
    return v_prev, v_next, a_chord


@dataclass(frozen=True)
class AisTracks:
    """Tracker output, one entry per row of the :class:`~seatrack.io.ais.AisReports`.

    SI units and radians (degrees/knots only when written out). Rows without an estimate
    (rejected rows, or withheld rows before a track starts) hold NaN.

    Attributes
    ----------
    x_m, y_m : local East, North (m) in the vessel's plane (origin ``lat0``, ``lon0``).
    lat, lon : smoothed WGS84 position (deg).
    course : course over ground (rad, clockwise from true North at the vessel, [0, 2pi)).
    speed : speed over ground (m/s).
    turn_rate : rad/s, clockwise (starboard) positive.
    std_x_m, std_y_m : 1-sigma East / North (m); ``std_pos_m`` = sqrt((var_x + var_y)/2).
    std_course, std_speed, std_turn_rate : 1-sigma (rad, m/s, rad/s).
    outlier : bool; outlier_kind : int (see :data:`OUTLIER_KINDS`); segment : int;
    nis : float.
    time_offset_s : estimated timestamp error of the report (s, whole seconds, logged minus
    true time; :func:`timestamp_offsets`), NaN for rows without an estimate.
    """

    x_m: FloatArray
    y_m: FloatArray
    lat: FloatArray
    lon: FloatArray
    lat0: FloatArray
    lon0: FloatArray
    course: FloatArray
    speed: FloatArray
    turn_rate: FloatArray
    std_x_m: FloatArray
    std_y_m: FloatArray
    std_pos_m: FloatArray
    std_course: FloatArray
    std_speed: FloatArray
    std_turn_rate: FloatArray
    outlier: NDArray[np.bool_]
    outlier_kind: NDArray[np.int8]
    segment: NDArray[np.int64]
    nis: FloatArray
    time_offset_s: FloatArray


def _north_angle(lat: FloatArray, lon: FloatArray, lat0: FloatArray, lon0: FloatArray) -> Any:
    """Bearing (rad) of true North at (lat, lon) in the tangent plane of (lat0, lon0).

    The geodetic North unit vector at the point, ``(-sin p cos l, -sin p sin l, cos p)``
    in ECEF, projected on the plane's East and North axes (the rows of the ENU rotation of
    :func:`seatrack.geometry.geodetic_to_enu` at the origin); the angle is the meridian
    convergence between the vessel and its frame origin (exact on the ellipsoid).
    """
    p, lam = np.radians(lat), np.radians(lon)
    p0, l0 = np.radians(lat0), np.radians(lon0)
    n = np.stack([-np.sin(p) * np.cos(lam), -np.sin(p) * np.sin(lam), np.cos(p)], -1)
    e0 = np.stack([-np.sin(l0), np.cos(l0), np.zeros_like(l0)], -1)
    n0 = np.stack([-np.sin(p0) * np.cos(l0), -np.sin(p0) * np.sin(l0), np.cos(p0)], -1)
    gam = bearing(np.sum(n * e0, -1), np.sum(n * n0, -1))
    return np.where(np.isfinite(gam), gam, 0.0)


def track_reports(
    reports: Any,
    config: AisTrackerConfig | None = None,
    use: ArrayLike | None = None,
) -> AisTracks:
    """Track every vessel of :class:`~seatrack.io.ais.AisReports` (rejected rows skipped).

    Positions go to one local plane per vessel (:func:`seatrack.io.ais.to_local`); the
    compiled tracker runs over all vessels at once (:func:`track_vessels`); positions come
    back to WGS84 (:func:`seatrack.io.ais.from_local`) and the course is referred to true
    North at the vessel (the plane's North differs by the meridian convergence).

    Parameters
    ----------
    reports : AisReports
    config : AisTrackerConfig
    use : array of bool (N,), optional
        False withholds a row from the filter (it still gets the track estimate at its
        time) -- for hold-out tests.
    """
    from seatrack.io.ais import from_local, to_local

    cfg = config or AisTrackerConfig()
    n = len(reports)
    frame = to_local(reports)
    ok = reports.valid
    idx = np.flatnonzero(ok)
    sog = reports.sog_kn[idx] * KNOT_MPS
    cog = np.radians(reports.cog_deg[idx])
    u = None if use is None else np.asarray(use, dtype=bool)[idx]
    # COG is referred to true North at the vessel; the plane's North differs by the
    # meridian convergence, so rotate it into the plane (also for the initial velocity)
    gam0 = _north_angle(reports.lat[idx], reports.lon[idx], frame.lat0[idx], frame.lon0[idx])
    cog_plane = cog + gam0
    v0 = np.stack([sog * np.sin(cog_plane), sog * np.cos(cog_plane)], axis=-1)
    st = track_vessels(
        reports.mmsi[idx],
        reports.t[idx],
        frame.enu[idx, :2],
        cfg,
        use=u,
        v0=v0,
        sog=sog,
        cog=cog_plane,
    )

    def full(a: NDArray, fill: Any = np.nan, dtype: Any = float) -> NDArray:
        out = np.full((n,) + a.shape[1:], fill, dtype=dtype)
        out[idx] = a
        return out

    state = full(st.state)
    std = full(st.std)
    lat, lon = from_local(state[:, 0], state[:, 1], frame.lat0, frame.lon0)
    gam = _north_angle(lat, lon, frame.lat0, frame.lon0)
    course_plane = bearing(state[:, 2], state[:, 3])
    course = np.where(np.isfinite(state[:, 2]), wrap_2pi(course_plane - gam), np.nan)
    speed = np.hypot(state[:, 2], state[:, 3])
    return AisTracks(
        x_m=state[:, 0],
        y_m=state[:, 1],
        lat=lat,
        lon=lon,
        lat0=frame.lat0,
        lon0=frame.lon0,
        course=course,
        speed=speed,
        turn_rate=state[:, 4],
        std_x_m=std[:, 0],
        std_y_m=std[:, 1],
        std_pos_m=np.sqrt(0.5 * (std[:, 0] ** 2 + std[:, 1] ** 2)),
        std_course=std[:, 3],
        std_speed=std[:, 2],
        std_turn_rate=std[:, 4],
        outlier=full(st.outlier, False, bool),
        outlier_kind=full(st.outlier_kind, 0, np.int8),
        segment=full(st.segment, -1, np.int64),
        nis=full(st.nis),
        time_offset_s=full(st.time_offset),
    )
